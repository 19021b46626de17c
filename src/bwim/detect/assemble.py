"""From per-vehicle axle estimates to a :class:`~bwim.detect.result.Detection`.

Contract
--------
* A :class:`VehicleEstimate` is what a detecting method measured for one vehicle: the
  record time at which each axle passes the reference point ``x = position`` of the
  influence-line frame (s), the speed (m/s) and its diagnostics.
* :func:`assemble_detection` makes the passages (``delay = t_0 − position / speed``,
  spacings = time differences × speed), their time on the span and the flags that depend
  on it (``multiple_presence``, ``truncated``, ``unexplained_strain``), and each vehicle's
  lateral position (:func:`~bwim.detect.lateral.lateral_position`; ``Passage.lane`` is
  the lateral position, 0.0 when no gauge responded).  A vehicle is ``truncated`` when
  its time on the span reaches beyond the record, and the last one also when the gauges
  end the record away from where they started (:func:`ends_loaded`: the record was cut
  while a vehicle was on the bridge, whose axles beyond the cut no detector saw); when
  every vehicle's time on the span begins after the record's first :data:`END_SPAN` s
  and the gauges start at rest (:data:`STEADY_SHARE`), only an end on the side the
  crossing loaded the gauges counts (an end below a quiet start is the gauges' baseline
  drifting).
* :func:`section_readings` reads a record's section gauges once for every detection of
  one record (the pairs of a site, :func:`bwim.site.lanes.detect_lanes`): their readings
  (as :func:`~bwim.detect.signals.channel_data` gives them), their sum per sample, its
  noise (:func:`~bwim.detect.presence.signal_noise`) and the record's median time step;
  :func:`assemble_detection` given them (``section``) takes them instead of making them
  again, the same numbers.
* The quiet level of the gauges is taken outside every vehicle's time on the span (more
  than 50 ms from it) when the span is known and that leaves ≥ 10 % of the record, else
  from the first and last 10 % of the record.  Without a span, the lateral window of each
  vehicle runs between the midpoints of consecutive vehicles' axle times.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bwim.errors import InputError
from bwim.records import Passage, Record
from bwim.sensors import Sensor

from .lateral import lateral_positions
from .order_stats import end_excursion, outside_windows
from .presence import overlapping, signal_noise, span_windows, unexplained_activity
from .result import (
    FLAG_MULTIPLE_PRESENCE,
    FLAG_TRUNCATED,
    FLAG_UNEXPLAINED_STRAIN,
    Detection,
    VehicleDetection,
)
from .signals import channel_data, median

__all__ = ["END_SHARE", "END_SPAN", "STEADY_SHARE", "SectionReadings", "VehicleEstimate",
           "assemble_detection", "checked_section", "ends_loaded", "section_readings"]

#: Margin around a vehicle's time on the span, s, before samples count as quiet.
QUIET_MARGIN = 0.05
#: s of readings averaged at each end of a record (a free vibration's cycles average out).
END_SPAN = 0.05
#: A record whose gauges end further from where they started than this share of their
#: largest excursion ends (or starts) with a vehicle on the bridge.
END_SHARE = 0.15
#: A record starts at rest when its gauges' mean over the second :data:`END_SPAN` s lies
#: within this share of their largest excursion of the mean over the first: a vehicle on
#: the span moves about a metre in that time at road speed and changes them far more
#: (measured in stop 35: at most 0.027 on 150 lane-1 records of a bench day and the 12
#: light trucks the rule below had refused on four, 0.19-0.58 on the small test site's
#: lane-1 truck's record cut 0.3-0.9 s into it).
STEADY_SHARE = 0.05


def ends_loaded(time: np.ndarray, total: np.ndarray,
                quiet_start: bool = False, *, step: float | None = None) -> bool:
    """Whether the gauges' sum ``total`` ends the record (mean over its last
    :data:`END_SPAN` s) further than :data:`END_SHARE` of its largest excursion from where
    it started (mean over its first :data:`END_SPAN` s): a record cut while a vehicle is
    on the bridge, at its end or its start.  With ``quiet_start`` (no detected vehicle
    was on the span when the record started) and a start at rest (:data:`STEADY_SHARE`:
    a vehicle the detection missed, already past the detectors, would be moving) only
    an end on the excursion's side counts: a vehicle on the span loads the gauges the
    way the crossing did, so an end beyond a quiet start on the other side is the
    gauges' baseline moving (a drift over the record), not a load.  ``step``: the
    median time step, when already made."""
    t = np.asarray(time, dtype=float)
    y = np.ascontiguousarray(total, dtype=float)
    n = max(2, round(END_SPAN / (median(np.diff(t)) if step is None else step)))
    if y.size < 4 * n:
        return False
    # the first, last and second n values' means and the largest excursion from the
    # first mean (numpy's mean and argmax: bwim.detect.order_stats.end_excursion)
    start, end, middle, _, excursion = end_excursion(y, n)
    swing = abs(excursion)
    change = end - start
    steady = abs(middle - start) <= STEADY_SHARE * swing
    if quiet_start and steady and change * excursion < 0:
        return False
    return swing > 0 and abs(change) > END_SHARE * swing


@dataclass(frozen=True, kw_only=True, eq=False)
class SectionReadings:
    """A record's section gauges read once (:func:`section_readings`).

    Attributes
    ----------
    gauges : tuple of str
        The gauges' names, in order.
    readings : ndarray, shape (n_t, n_gauges)
        ``channel_data(record, gauges)`` (not to be changed).
    total : ndarray, shape (n_t,)
        ``readings.sum(axis=1)``.
    noise : float
        :func:`~bwim.detect.presence.signal_noise` of ``total``.
    step : float
        The record's median time step, s (:func:`~bwim.detect.signals.median` of
        ``numpy.diff(record.time)``).
    """

    gauges: tuple[str, ...]
    readings: np.ndarray
    total: np.ndarray
    noise: float
    step: float


def section_readings(record: Record, gauges: Sequence[str]) -> SectionReadings:
    """The section ``gauges`` of ``record`` read once (module docstring); InputError for
    a gauge the record does not have."""
    names = tuple(gauges)
    readings = channel_data(record, names)
    total = readings.sum(axis=1)
    return SectionReadings(gauges=names, readings=readings, total=total,
                           noise=signal_noise(total), step=median(np.diff(record.time)))


def checked_section(section: SectionReadings | None, record: Record, names: Sequence[str]
                    ) -> SectionReadings | None:
    """``section`` when it holds ``names`` of a record as long as ``record`` (else
    InputError); None without it."""
    if section is None:
        return None
    if not isinstance(section, SectionReadings):
        raise InputError(f"section must be SectionReadings, got {type(section).__name__}")
    if section.gauges != tuple(names) or section.readings.shape[0] != record.time.size:
        raise InputError(f"section: the readings of {list(section.gauges)} over "
                         f"{section.readings.shape[0]} samples, not of {list(names)} over "
                         f"{record.time.size}")
    return section


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleEstimate:
    """One vehicle as a detecting method measured it (see the module contract)."""

    times: np.ndarray
    speed: float
    confidence: float
    flags: tuple[str, ...] = ()
    amplitudes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    snr: float = float("nan")
    speed_spread: float = 0.0
    spacing_disagreement: float = float("nan")
    residual: float = float("nan")
    detector_times: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))


def _segments(extents: list[tuple[float, float]], t0: float, t1: float
              ) -> list[tuple[float, float]]:
    cuts = [0.5 * (extents[k][1] + extents[k + 1][0]) for k in range(len(extents) - 1)]
    edges = [t0, *cuts, t1]
    return [(edges[k], edges[k + 1]) for k in range(len(extents))]


def assemble_detection(
    record: Record,
    estimates: Sequence[VehicleEstimate],
    *,
    method: str,
    position: float = 0.0,
    span: tuple[float, float] | None = None,
    gauges: Sequence[Sensor] = (),
    lateral_threshold: float = 0.5,
    unexplained_fraction: float = 0.2,
    flags: Sequence[str] = (),
    notes: Sequence[str] = (),
    section: SectionReadings | None = None,
) -> Detection:
    """The Detection of ``estimates`` (in order of arrival) in ``record``; ``section``:
    the ``gauges`` of ``record`` already read (:func:`section_readings`)."""
    t = record.time
    est = sorted(estimates, key=lambda e: float(e.times[0]))
    passages = []
    for e in est:
        # the spacings as numpy's maximum(diff(times) * speed, 1e-6) makes them, one
        # Python float at a time (the same operations)
        times = np.asarray(e.times, dtype=float).tolist()
        speed = float(e.speed)
        spacings = [max((b - a) * speed, 1e-6) for a, b in itertools.pairwise(times)]
        passages.append(Passage(speed=e.speed, axle_spacings=spacings,
                                delay=float(times[0] - position / e.speed)))
    rec_flags = set(flags)
    notes = list(notes)
    veh_flags = [list(e.flags) for e in est]
    windows = None if span is None else span_windows(passages, span)
    if windows is not None:
        together = overlapping(windows)
        for k in np.flatnonzero(together):
            veh_flags[k].append(FLAG_MULTIPLE_PRESENCE)
        if together.any():
            ids = ", ".join(str(k + 1) for k in np.flatnonzero(together))
            notes.append(f"vehicles {ids} on the span at the same time")
        for k, (a, b) in enumerate(windows):
            if a < t[0] or b > t[-1]:
                veh_flags[k].append(FLAG_TRUNCATED)
                notes.append(f"vehicle {k + 1} is on the span {a:.3f}–{b:.3f} s, beyond "
                             f"the record ({t[0]:.3f}–{t[-1]:.3f} s)")
    quiet = None
    if windows is not None:
        outside, count = outside_windows(np.ascontiguousarray(t, dtype=float), windows,
                                         QUIET_MARGIN)
        if count >= 0.1 * t.size:
            quiet = outside
    if quiet is None:
        edge = max(1, t.size // 10)
        quiet = np.zeros(t.size, dtype=bool)
        quiet[:edge] = quiet[-edge:] = True
    if windows is not None:
        lat_windows = [tuple(w) for w in windows]
    else:
        lat_windows = _segments([(float(e.times[0]), float(e.times[-1])) for e in est],
                                float(t[0]), float(t[-1]))
    names = [s.name for s in gauges]
    section = checked_section(section, record, names) if names else None
    readings = (None if not names else channel_data(record, names) if section is None
                else section.readings)
    if windows is not None and names and len(est):
        total = readings.sum(axis=1) if section is None else section.total
        noise, step = (None, None) if section is None else (section.noise, section.step)
        extra = unexplained_activity(t, total, windows, margin=QUIET_MARGIN,
                                     fraction=unexplained_fraction, noise=noise, step=step)
        # no detected vehicle on the span at the start: every vehicle's time on the span
        # begins after the record's first END_SPAN s (ends_loaded also asks the gauges
        # to start at rest before only an end on the crossing's side counts as a load)
        if ends_loaded(t, total, quiet_start=bool(windows[:, 0].min() > t[0] + END_SPAN),
                       step=step):
            last = int(np.argmax(windows[:, 1]))
            if FLAG_TRUNCATED not in veh_flags[last]:
                veh_flags[last].append(FLAG_TRUNCATED)
            notes.append(f"the gauges end the record (at {t[-1]:.3f} s) away from where "
                         "they started: it ends (or starts) while a vehicle is on the bridge")
        if extra.size:
            rec_flags.add(FLAG_UNEXPLAINED_STRAIN)
            spans = ", ".join(f"{a:.3f}–{b:.3f} s" for a, b in extra)
            notes.append(f"strain activity at {spans} outside every detected vehicle's time "
                         "on the span (a vehicle the detection did not see?)")
    # every vehicle's lateral position with the one quiet mask: the gauges' quiet levels
    # taken once (lateral_position of each window, the same numbers)
    lats = (lateral_positions(record, lat_windows, quiet=quiet, gauges=names,
                              threshold=lateral_threshold, readings=readings)
            if names and est else None)
    vehicles = []
    for k, (e, p) in enumerate(zip(est, passages, strict=True)):
        if lats is not None:
            lateral, unit = lats[k].value, lats[k].unit
        else:
            lateral, unit = float("nan"), "gauge index"
        if np.isfinite(lateral):
            p = Passage(speed=p.speed, lane=lateral, axle_spacings=p.axle_spacings,
                        delay=p.delay)
        vflags = tuple(dict.fromkeys(veh_flags[k]))
        rec_flags.update(vflags)
        vehicles.append(VehicleDetection(
            passage=p, confidence=e.confidence, flags=vflags,
            axle_times=p.delay + p.axle_offsets / p.speed, axle_amplitudes=e.amplitudes,
            lateral=lateral, lateral_unit=unit,
            window=None if windows is None else (float(windows[k, 0]), float(windows[k, 1])),
            snr=e.snr, speed_spread=e.speed_spread,
            spacing_disagreement=e.spacing_disagreement, residual=e.residual,
            detector_times=e.detector_times))
    return Detection(vehicles=tuple(vehicles), flags=tuple(sorted(rec_flags)),
                     message="; ".join(notes), method=method)
