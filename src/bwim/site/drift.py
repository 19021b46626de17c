"""The drift of a bridge's strain-to-load ratio, corrected from one day to the next.

A slab's strain under a given truck drifts with its temperature by ±10 % or more within a
day, and differently the next day: a factor fixed on the calibration day cannot hold on
another.  Three sources of the factor, chosen in the scenario (``[drift] method``) and
reported per vehicle (``drift_method``):

Contract
--------
* ``"temperature"``: the logger has a temperature channel (``DriftSetup.temperature``).
  The calibration runs' scale factors are regressed on their temperature
  (:class:`TemperatureDrift`, least squares, a straight line); an event's factor is the
  line at its own temperature.  A record's temperature is the median of its channel's
  readings; a probe's gaps (empty or NaN fields, read as NaN) are left out, and a record
  with no reading at all is left out of the fit, or, for an event, falls back to the
  time of day flagged ``temperature_missing`` (``"auto"``) or is refused
  (``"temperature"``).  It holds on any day the factor follows the temperature.
  Temperatures beyond the runs' range by more than a quarter of it are flagged
  ``temperature_extrapolated``.
* ``"traffic"``: **self-calibration from the traffic itself** (:func:`traffic_drift`):
  the steering axle of the commonest articulated class (``reference_class``: an
  axle-group code, :mod:`bwim.classify`; default, among the classes of five or more
  axles weighed, the commonest) is a stable reference: its load hardly depends on the
  payload.  Its weighed value, divided by a nominal value, tracks the factor: a robust
  local-linear trend over the day's clock time (:class:`bwim.wim.ScaleTrend`, bandwidth
  by cross-validation among :data:`TRAFFIC_BANDWIDTHS`, after dropping ratios beyond
  :data:`OUTLIER` robust standard deviations of their local median, within
  :data:`LOCAL_WINDOW` in time: the day's drift is larger than their scatter), one
  trend per date; a vehicle before the date's first kept reference vehicle or after its
  last gets the trend's end value, flagged ``outside_calibration_time``.
  The nominal value is learned while the calibration holds: the mean reference steering
  axle (within the same outlier limit; a mean, as the trends are local means: a median
  would shift every factor by the loads' skew) of vehicles weighed on a calibration date
  inside the runs' span, with the runs' own trend; without such traffic,
  ``reference_load`` (N) from the scenario.  A date with fewer than ``min_reference``
  reference vehicles is too thin: its vehicles fall back to the next source, flagged
  ``drift_traffic_thin``.
* ``"time_of_day"``: the calibration runs' factors over the time of day
  (:class:`bwim.wim.ScaleTrend` over seconds since midnight; runs that straddle
  midnight, a night calibration, over seconds since :attr:`TimeOfDayDrift.origin`, the
  middle of the longest gap between their times of day, so that their span stays
  whole) applied at the event's time of day, on any date; on a date other than the
  calibration's, or outside the runs' span of the day, flagged
  ``outside_calibration_time`` (the last resort: the issue
  measured it leaves a real site at C(15)).  It needs clocks: runs without one whose
  time columns are record times (from 0: :data:`bwim.records.RECORD_TIME_SPAN`) give
  no time-of-day drift at all, and an event without one (:attr:`bwim.Record.time_of_day`
  false) keeps the mean factor, flagged ``no_clock``.  Runs some of which have only a
  clock time of day have no dates: vehicles on other dates are then not flagged.
* ``"trend"``: the runs' factors over absolute clock time (the calibration day only:
  constant, flagged, beyond its span); ``"none"``: the calibration's mean factor.
* ``"auto"`` (default): temperature when the logger has a temperature channel; else the
  traffic where it is thick enough and a nominal value is known; else the time of day.
* A factor multiplies the strains: weights are divided by it.  The traffic method works on
  the summary rows of a whole batch (:func:`traffic_drift` after weighing: it needs the
  day's traffic); the others per event.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import date, datetime

import numpy as np

from bwim.errors import InputError
from bwim.plausibility import Limits, quality_of, weight_flags
from bwim.records import day_origin, on_day_axis, seconds_of_day
from bwim.summary import SummaryRow
from bwim.wim.scale_trend import ScaleTrend

__all__ = ["DRIFT_METHODS", "LOCAL_WINDOW", "NEIGHBOURS", "DriftSetup", "TemperatureDrift",
           "TimeOfDayDrift", "TrafficDrift", "traffic_drift"]

#: Sources of the drift factor (see the module docstring).
DRIFT_METHODS = ("auto", "traffic", "temperature", "time_of_day", "trend", "none")
#: Reference ratios beyond this many robust standard deviations of a day's median are
#: left out of its trend (a misdetected axle, a wrong class).
OUTLIER = 4.0
#: s: the bandwidths the traffic method's trend is chosen among (cross-validated), half an
#: hour to four hours: a deck's temperature, and the factor with it, changes over hours,
#: while the reference vehicles are many and each scatters by its own dynamics.
TRAFFIC_BANDWIDTHS = tuple(h * 3600.0 for h in (0.5, 1.0, 1.5, 2.0, 3.0, 4.0))
#: s: a reference vehicle's ratio is an outlier against the median of the reference
#: vehicles within this time of it (the drift over it is small against their scatter) ...
LOCAL_WINDOW = 3600.0
#: ... or of this many nearest it in time, where fewer are within it.
NEIGHBOURS = 7


@dataclass(frozen=True, kw_only=True)
class DriftSetup:
    """How the drift is corrected (see the module docstring).

    Attributes
    ----------
    method : str
        :data:`DRIFT_METHODS`.
    temperature : str or None
        The logger channel of a temperature, °C.
    reference_class : str or None
        The traffic method's reference class (axle-group code), None: the commonest of
        five or more axles.
    reference_load : float or None
        Its steering axle's nominal static load, N, where no traffic is weighed while the
        calibration holds.
    min_reference : int
        The fewest reference vehicles in a date for the traffic method.
    """

    method: str = "auto"
    temperature: str | None = None
    reference_class: str | None = None
    reference_load: float | None = None
    min_reference: int = 20

    def __post_init__(self) -> None:
        if self.method not in DRIFT_METHODS:
            raise InputError(f"drift method must be one of {', '.join(DRIFT_METHODS)}, got "
                             f"{self.method!r}")
        if self.reference_load is not None and not (
                isinstance(self.reference_load, int | float)
                and math.isfinite(self.reference_load) and self.reference_load > 0):
            raise InputError(f"reference_load must be a positive load, N, got "
                             f"{self.reference_load!r}")
        if isinstance(self.min_reference, bool) or not isinstance(self.min_reference, int) \
                or self.min_reference < 3:
            raise InputError(f"min_reference must be an integer >= 3, got "
                             f"{self.min_reference!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class TimeOfDayDrift:
    """The calibration runs' factors over the time of day (see the module docstring).

    Attributes
    ----------
    trend : ScaleTrend
        Over the time of day on the drift's axis (:meth:`axis`: seconds since midnight,
        unless the runs straddle it).
    dates : tuple of date
        The calibration runs' dates (empty when their clock has no date).
    origin : float
        Where the axis's day starts, s since midnight: 0, or for runs that straddle
        midnight the middle of the longest gap between their times of day (an event
        in that gap takes the factor of the runs' nearer end).
    reach : float
        s: how long the last run's record lasts beyond its start (the runs are timed by
        their records' starts, a vehicle by its crossing: the last run's own truck
        crosses within it).
    """

    trend: ScaleTrend
    dates: tuple[date, ...]
    origin: float = 0.0
    reach: float = 0.0

    @classmethod
    def fit(cls, times_of_day: Sequence[float], factors: Sequence[float],
            dates: tuple[date, ...] = (), durations: Sequence[float] | None = None
            ) -> TimeOfDayDrift:
        """The trend of the runs' ``factors`` over their ``times_of_day`` (s since
        midnight: their records' starts), on an axis that keeps their span whole;
        ``durations`` (s) their records' lengths."""
        origin = day_origin(times_of_day)
        axis = [on_day_axis(t, origin) for t in times_of_day]
        reach = 0.0 if durations is None else float(durations[int(np.argmax(axis))])
        return cls(trend=ScaleTrend.fit(axis, factors), dates=dates, origin=origin,
                   reach=max(reach, 0.0))

    def axis(self, time_of_day: float) -> float:
        """A time of day (s since midnight) on the trend's axis: from :attr:`origin` to
        origin + 86400 s."""
        return on_day_axis(time_of_day, self.origin)

    def factor(self, when: datetime | float) -> tuple[float, bool]:
        """The factor at a clock (a datetime, or seconds of day) and whether that is
        outside the calibration: another date, or beyond the runs' span of the day."""
        if isinstance(when, datetime):
            tod = self.axis(seconds_of_day(when))
            other_day = bool(self.dates) and when.date() not in self.dates
        else:
            tod, other_day = self.axis(float(when)), False
        lo, hi = self.trend.span
        return float(self.trend(tod)), other_day or not lo <= tod <= hi + self.reach


@dataclass(frozen=True, kw_only=True, eq=False)
class TemperatureDrift:
    """The runs' factors as a straight line in temperature (see the module docstring).

    Attributes
    ----------
    intercept, slope : float
        ``factor = intercept + slope (T − reference)``, per °C.
    reference : float
        Mean run temperature, °C.
    span : (float, float)
        The runs' temperature range, °C.
    residual : float
        RMS of the runs' factors about the line.
    """

    intercept: float
    slope: float
    reference: float
    span: tuple[float, float]
    residual: float

    @classmethod
    def fit(cls, temperatures: Sequence[float], factors: Sequence[float]) -> TemperatureDrift:
        T = np.asarray(temperatures, dtype=float)
        f = np.asarray(factors, dtype=float)
        if T.size < 3 or not np.all(np.isfinite(T)) or np.ptp(T) <= 0:
            raise InputError("the temperature drift needs three runs or more at different "
                             "temperatures")
        ref = float(T.mean())
        slope, intercept = np.polyfit(T - ref, f, 1)
        res = f - (intercept + slope * (T - ref))
        return cls(intercept=float(intercept), slope=float(slope), reference=ref,
                   span=(float(T.min()), float(T.max())),
                   residual=float(np.sqrt(np.mean(res**2))))

    def factor(self, temperature: float) -> tuple[float, bool]:
        """The factor at ``temperature`` (°C) and whether it lies beyond the runs' range
        by more than a quarter of it."""
        lo, hi = self.span
        margin = 0.25 * (hi - lo)
        return (float(self.intercept + self.slope * (temperature - self.reference)),
                not lo - margin <= temperature <= hi + margin)


@dataclass(frozen=True, kw_only=True, eq=False)
class TrafficDrift:
    """The traffic method's fit (see :func:`traffic_drift`).

    Attributes
    ----------
    reference_class : str
    nominal : float
        The reference steering axle's nominal load, N.
    nominal_source : str
        ``"calibration day traffic"`` or ``"scenario"``.
    trends : dict
        Per date, the ScaleTrend of the reference ratios over seconds of day (None for a
        date too thin).
    counts : dict
        Per date, the reference vehicles used.
    """

    reference_class: str
    nominal: float
    nominal_source: str
    trends: dict
    counts: dict


def _keep(values: np.ndarray) -> np.ndarray:
    """Which values lie within :data:`OUTLIER` robust standard deviations of their median."""
    med = float(np.median(values))
    rsd = 1.4826 * float(np.median(np.abs(values - med))) or 1e-9
    return np.abs(values - med) <= OUTLIER * rsd


def _keep_about_trend(t: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Which of the day's ratios ``q`` at clock times ``t`` (s) lie within :data:`OUTLIER`
    robust standard deviations of their local median: of the ratios within
    :data:`LOCAL_WINDOW` of each in time, or of its :data:`NEIGHBOURS` nearest in time
    where fewer are that near (the day's drift moves the ratios by more than their
    scatter: against the day's one median, a busy morning would make a thinner
    afternoon's ratios outliers)."""
    order = np.argsort(t, kind="stable")
    ts, qs = t[order], q[order]
    n = ts.size
    lo = np.searchsorted(ts, ts - LOCAL_WINDOW, side="left")
    hi = np.searchsorted(ts, ts + LOCAL_WINDOW, side="right")
    local = np.empty(n)
    for i in range(n):
        a, b = int(lo[i]), int(hi[i])
        if b - a < min(NEIGHBOURS, n):  # thin here: the nearest in time instead
            near = np.argsort(np.abs(ts - ts[i]), kind="stable")[:NEIGHBOURS]
            local[i] = np.median(qs[near])
        else:
            local[i] = np.median(qs[a:b])
    keep = np.empty(n, dtype=bool)
    keep[order] = _keep(qs - local)
    return keep


def _steer(row: SummaryRow) -> float | None:
    """The row's steering axle load as weighed before any drift correction, N."""
    if not row.weighed or not row.axle_weights:
        return None
    return row.axle_weights[0] * (row.drift_factor or 1.0)


def _reference_class(rows: Sequence[SummaryRow]) -> str | None:
    counts = Counter(r.vehicle_class for r in rows
                     if r.weighed and r.vehicle_class and (r.n_axles or 0) >= 5)
    return counts.most_common(1)[0][0] if counts else None


def traffic_drift(rows: Sequence[SummaryRow], setup: DriftSetup, *,
                  calibration: TimeOfDayDrift | None = None,
                  calibration_span: tuple[float, float] | None = None) -> TrafficDrift | None:
    """Fit the traffic method on a batch's rows (see the module docstring); None when it
    cannot: no reference class, or no nominal value.

    ``calibration`` is the runs' time-of-day trend with their dates, and
    ``calibration_span`` their clock span (s, on its :meth:`~TimeOfDayDrift.axis`)
    within which a calibration date's traffic gives the nominal value."""
    cls = setup.reference_class or _reference_class(rows)
    if cls is None:
        return None
    refs = [(r, s) for r in rows if r.vehicle_class == cls and isinstance(r.time, datetime)
            and (s := _steer(r)) is not None]
    nominal, source = None, ""
    if calibration is not None and calibration.dates:
        lo, hi = calibration_span or calibration.trend.span
        base = [s / calibration.trend(t) for r, s in refs
                if r.time.date() in calibration.dates
                and lo <= (t := calibration.axis(seconds_of_day(r.time))) <= hi]
        if len(base) >= setup.min_reference:
            # the mean, as the trends are local means (a median would bias every factor
            # by the steering loads' skew), of the ratios within the outlier limit
            ratios = np.asarray(base)
            nominal = float(np.mean(ratios[_keep(ratios)]))
            source = "calibration day traffic"
    if nominal is None and setup.reference_load is not None:
        nominal, source = float(setup.reference_load), "scenario"
    if nominal is None:
        return None
    trends, counts = {}, {}
    by_date: dict[date, list[tuple[float, float]]] = {}
    for r, s in refs:
        by_date.setdefault(r.time.date(), []).append((seconds_of_day(r.time), s / nominal))
    for day, pts in by_date.items():
        t = np.array([p[0] for p in pts])
        q = np.array([p[1] for p in pts])
        keep = _keep_about_trend(t, q)
        counts[day] = int(keep.sum())
        trends[day] = (ScaleTrend.fit(t[keep], q[keep], candidates=TRAFFIC_BANDWIDTHS)
                       if counts[day] >= setup.min_reference
                       else None)
    return TrafficDrift(reference_class=cls, nominal=nominal, nominal_source=source,
                        trends=trends, counts=counts)


def corrected(row: SummaryRow, factor: float, method: str, flags: Sequence[str] = (),
              limits: Limits | None = None, drop: Sequence[str] = ()) -> SummaryRow:
    """The row with its weights divided by ``factor`` in place of the factor it had, its
    plausibility checked again on the new weights (a weight that becomes implausible is
    refused with the reason); ``drop`` are flags the new factor makes moot."""
    if not row.weighed:
        return dataclasses.replace(row, flags=tuple(dict.fromkeys([*row.flags, *flags])))
    scale = (row.drift_factor or 1.0) / factor
    axles = tuple(w * scale for w in row.axle_weights)
    groups = tuple(w * scale for w in row.group_weights)
    new_flags = list(dict.fromkeys([
        *[f for f in row.flags if f not in _WEIGHT_FLAGS and f not in drop], *flags,
        *weight_flags(np.array(axles), np.array(groups or axles), limits or Limits())]))
    quality = quality_of(new_flags)
    if quality == "reject":
        hard = ", ".join(f for f in new_flags if f in _WEIGHT_FLAGS)
        return dataclasses.replace(row, drift_factor=factor, drift_method=method,
                                   flags=tuple(new_flags)).refused(
            f"implausible weighing ({hard})")
    return dataclasses.replace(row, axle_weights=axles, group_weights=groups,
                               gvw=row.gvw * scale, flags=tuple(new_flags), quality=quality,
                               drift_factor=factor, drift_method=method)


#: The plausibility flags of the weights themselves (checked again after a correction).
_WEIGHT_FLAGS = ("negative_axle_weight", "negative_group_weight", "axle_weight_high",
                 "axle_weight_low", "gvw_high", "gvw_low")


def apply_traffic_drift(rows: Sequence[SummaryRow], fit: TrafficDrift) -> list[SummaryRow]:
    """Every weighed row of a date with a trend divided by the trend at its time; rows of
    a thin date keep their factor and are flagged ``drift_traffic_thin``."""
    out = []
    for r in rows:
        if not r.weighed or not isinstance(r.time, datetime):
            out.append(r)
            continue
        trend = fit.trends.get(r.time.date())
        if trend is None:
            out.append(corrected(r, r.drift_factor or 1.0, r.drift_method or "none",
                                 ("drift_traffic_thin",)))
            continue
        when = seconds_of_day(r.time)
        # beyond the first and last reference vehicle the trend holds its end value: not
        # measured there (flagged as a time outside the calibration's)
        inside = trend.covers(when)
        out.append(corrected(r, float(trend(when)), "traffic",
                             () if inside else ("outside_calibration_time",),
                             drop=("outside_calibration_time", "no_drift") if inside
                             else ("no_drift",)))
    return out
