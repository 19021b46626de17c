"""A B-WIM installation's chain: detect each vehicle, calibrate lines from the calibration
truck's runs, weigh unknown traffic, and check every weight before it leaves.

Contract
--------
* :class:`SiteSetup` is what the installation knows: the axle-detector channels (in the
  order traffic meets them), their distance (m) and the first detector's position in the
  influence-line frame (m), and the calibration truck's static axle loads (N) and axle
  spacings (m).  Without detectors, vehicles are found from the strain alone
  (:func:`bwim.detect.detect_from_strain`) with the calibrated lines.
* :func:`calibrate_site` detects the calibration truck in each run (speed, arrival,
  lateral position; the truck's axle layout is known, so a run whose detected axle count
  or spacings disagree with it is rejected with its reason) and calibrates the lines of
  every gauge from the runs stacked (:func:`bwim.wim.calibrate_lines`: per-run scale
  factors and their trend over clock time, outlier runs rejected with a reason).
  Without detectors, the truck is found from the summed gauges with the line unknown
  (:func:`bwim.detect.detect_known_truck`: the known spacings fix the axles' time
  separations; one line shared by the runs), then the lines are calibrated and the runs
  re-detected against them (``strain_passes``).  The lines' frame origin is then the
  centroid of the summed gauges' influence line (near the instrumented section), not a
  detector; calibration and weighing share it.
* :func:`weigh_event` detects the vehicles of one event and weighs a single vehicle by
  :func:`bwim.wim.weigh` (gauges combined by generalised least squares, axle groups as
  groups).  It never raises on a record it can read: every outcome is an
  :class:`EventWeighing` whose ``weighed`` says whether weights were produced and whose
  ``reason`` says why not.  An event with several vehicles on the bridge is flagged
  ``multiple_presence`` and not weighed as one vehicle; a weighing of quality
  ``"reject"`` (negative or absurd weights, a fit far worse than the calibration's, a
  truncated record) gives no weights, only its flags.
* With a calibrated FE model (``weigh_event(..., bridge=...)``) the detected vehicle is
  weighed by moving force identification instead; the gauges then need positions and
  the readings strain units (the scenario's ``[logger] scale``).
* Units: N, m, s; readings in the logger's units (a scale factor is not needed for
  influence lines: the calibration truck fixes it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from datetime import time as dtime
from typing import Any

import numpy as np

from bwim.classify import axle_configuration
from bwim.detect import (
    Detection,
    VehicleDetection,
    detect_axles,
    detect_from_strain,
    detect_known_truck,
)
from bwim.errors import BwimError, InputError, require_finite, require_positive
from bwim.fe.bridge import Bridge
from bwim.mfi import ForceIdentification, identify_forces
from bwim.plausibility import HARD_FLAGS
from bwim.records import Passage, Record
from bwim.summary import SummaryRow
from bwim.wim import MultiRunCalibration, Weighing, calibrate_lines, weigh
from bwim.wim.multirun import RunFit

__all__ = ["EventWeighing", "SiteCalibration", "SiteSetup", "calibrate_site", "weigh_event"]

#: A calibration run whose detected axle spacings differ from the truck's by more than
#: this (m) is rejected: the detection, not the truck, is wrong.
SPACING_TOLERANCE = 0.3

#: Drift corrections of the strain-to-load ratio: the calibration runs' trend over clock
#: time, or none (the calibration's mean factor).
DRIFT_METHODS = ("trend", "none")

#: Without axle detectors: passes of (lines from the runs, runs re-detected against them).
STRAIN_ONLY_PASSES = 2

#: What one event's detection or weighing may raise without ending a batch: bwim's own
#: errors and the numerical failures of a degenerate record (a singular fit).
_EVENT_ERRORS = (BwimError, ArithmeticError, ValueError, np.linalg.LinAlgError)


def _why(exc: BaseException) -> str:
    """An exception as one line (its type when it has no message)."""
    return " ".join(str(exc).split()) or type(exc).__name__


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteSetup:
    """What a B-WIM installation knows (see the module docstring).

    Parameters
    ----------
    calibration_loads : sequence of float
        The calibration truck's static axle loads, N.
    calibration_spacings : sequence of float
        Its axle spacings, m.
    detectors : (str, str) or None
        Axle-detector channel names, in the order traffic meets them; None: detect from
        the strain alone.
    distance : float or None
        Distance between the detectors, m (required with detectors).
    position : float
        The first detector's x in the influence-line frame, m (default 0: lines are
        measured from it).
    max_spacing : float or None
        Largest axle spacing within one vehicle, m (default :mod:`bwim.detect`'s).
    combine : str
        How the gauges are combined (:func:`bwim.wim.weigh`): ``"auto"`` (default:
        generalised least squares inside the calibrated lateral range, the gauges' sum
        outside it), ``"gls"``, ``"blue"`` or ``"sum"``.
    lateral : str or None
        ``"linear"``: lines linear in the lateral position; None: one line per gauge.
    drift : str
        How the day's drift of the strain-to-load ratio is corrected (see
        :data:`DRIFT_METHODS`): ``"trend"`` (default: the calibration runs' scale factors
        over clock time, :class:`bwim.wim.multirun.ScaleTrend`) or ``"none"``.
    """

    calibration_loads: np.ndarray
    calibration_spacings: np.ndarray
    detectors: tuple[str, str] | None = None
    distance: float | None = None
    position: float = 0.0
    max_spacing: float | None = None
    combine: str = "auto"
    lateral: str | None = None
    drift: str = "trend"

    def __post_init__(self) -> None:
        loads = np.array(self.calibration_loads, dtype=float, ndmin=1)
        spacings = np.array(self.calibration_spacings, dtype=float, ndmin=1)
        if loads.ndim != 1 or not np.all(np.isfinite(loads)) or np.any(loads <= 0):
            raise InputError("calibration_loads must be positive axle loads, N")
        if spacings.ndim != 1 or spacings.size != loads.size - 1 or not np.all(
                np.isfinite(spacings)) or np.any(spacings <= 0):
            raise InputError(f"calibration_spacings must be {loads.size - 1} positive "
                             f"distances for {loads.size} axle loads, got {spacings.tolist()}")
        object.__setattr__(self, "calibration_loads", loads)
        object.__setattr__(self, "calibration_spacings", spacings)
        if self.detectors is not None:
            det = tuple(self.detectors)
            if len(det) != 2 or det[0] == det[1]:
                raise InputError(f"detectors must be two different channels, got {det}")
            object.__setattr__(self, "detectors", det)
            if self.distance is None:
                raise InputError("two axle detectors need their distance, m")
            object.__setattr__(self, "distance", require_positive("distance", self.distance))
        object.__setattr__(self, "position", require_finite("position", self.position))
        if self.max_spacing is not None:
            object.__setattr__(self, "max_spacing",
                               require_positive("max_spacing", self.max_spacing))
        if self.combine not in ("auto", "gls", "blue", "sum"):
            raise InputError(f"combine must be auto, gls, blue or sum, got {self.combine!r}")
        if self.lateral not in (None, "linear"):
            raise InputError(f"lateral must be None or 'linear', got {self.lateral!r}")
        if self.drift not in DRIFT_METHODS:
            raise InputError(f"drift must be one of {', '.join(DRIFT_METHODS)}, got "
                             f"{self.drift!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteCalibration:
    """Lines of every gauge from the calibration truck's runs (:func:`calibrate_site`).

    Attributes
    ----------
    lines : MultiRunCalibration
        The lines, the runs' residuals, scale factors and rejections.
    detections : tuple of Detection
        What detection found in each run (same order as the records).
    reasons : tuple of str
        Why each run was left out ("" when it was used): detection or calibration.
    fits : tuple of (RunFit or None)
        Each run against the lines (its scale factor and residual); None for a run
        that detection left out.
    setup : SiteSetup
    """

    lines: MultiRunCalibration
    detections: tuple[Detection, ...]
    reasons: tuple[str, ...]
    fits: tuple[RunFit | None, ...]
    setup: SiteSetup

    @property
    def n_used(self) -> int:
        return sum(1 for r in self.reasons if not r)


@dataclass(frozen=True, kw_only=True, eq=False)
class EventWeighing:
    """The outcome of one event (:func:`weigh_event`); never raised, always returned.

    Attributes
    ----------
    weighed : bool
        True when ``weighing`` holds weights that passed the plausibility checks.
    reason : str
        Why the event was not weighed ("" when it was).
    detection : Detection or None
        None when detection itself failed (``reason`` says why).
    weighing : Weighing or None
        The fit (also for a rejected weighing, for inspection); None if not attempted.
    flags : tuple of str
        Detection and weighing flags together.
    identification : ForceIdentification or None
        The moving force identification, when weighed by MFI with an FE model.
    clock : datetime or None
        The record's wall clock at record time 0 (:attr:`bwim.Record.clock`).
    clock_of_day : bool
        True when the record has no ``clock`` but its time axis is the clock time of day
        (a logger that writes it in the time column: the axis does not start at 0).
    drift_factor : float or None
        The strain-to-load factor the weights were divided by (None: not weighed).
    drift_method : str
        Where it came from (:data:`DRIFT_METHODS`), ``""`` when no correction was made.
    """

    weighed: bool
    reason: str = ""
    detection: Detection | None = None
    weighing: Weighing | None = None
    flags: tuple[str, ...] = field(default_factory=tuple)
    identification: ForceIdentification | None = None
    clock: datetime | None = None
    clock_of_day: bool = False
    drift_factor: float | None = None
    drift_method: str = ""

    @property
    def method(self) -> str:
        """``"mfi"`` (identified with an FE model) or ``"moses"`` (influence lines)."""
        return "mfi" if self.identification is not None else "moses"

    @property
    def passage(self) -> Passage | None:
        """The weighed vehicle's passage (None when no single vehicle was found)."""
        if self.detection is None or len(self.detection.vehicles) != 1:
            return None
        return self.detection.vehicles[0].passage

    @property
    def axle_weights(self) -> np.ndarray | None:
        """Static axle weights, N (None unless weighed)."""
        if not self.weighed:
            return None
        if self.identification is not None:
            return self.identification.axle_weights
        return self.weighing.axle_weights

    @property
    def gvw(self) -> float | None:
        """Gross vehicle weight, N (None unless weighed)."""
        if not self.weighed:
            return None
        if self.identification is not None:
            return float(self.identification.gvw[0])
        return self.weighing.gvw

    def time_at(self, t: float) -> datetime | dtime | None:
        """Wall-clock time of record time ``t`` (s): a datetime with the record's clock, a
        time of day when the record's axis is one, else None."""
        if self.clock is not None:
            return self.clock + timedelta(seconds=float(t))
        if self.clock_of_day and 0.0 <= t < 86400.0:
            return (datetime.min + timedelta(seconds=float(t))).time()
        return None

    def to_summary_row(self, record: str) -> SummaryRow:
        """The summary row of this event's vehicle (the first one when several were found;
        see :meth:`to_summary_rows`), named ``record``."""
        return self.to_summary_rows(record)[0]

    def to_summary_rows(self, record: str) -> tuple[SummaryRow, ...]:
        """One :class:`~bwim.summary.SummaryRow` per detected vehicle (at least one), named
        ``record``: the weighed vehicle with its weights, every other one refused with the
        event's reason (no weight leaves without its plausibility checks)."""
        vehicles = () if self.detection is None else self.detection.vehicles
        if not vehicles:
            return (SummaryRow(record=record, status="refused", flags=self.flags,
                               reason=self.reason or "no vehicle found"),)
        return tuple(self._row(record, k, v) for k, v in enumerate(vehicles))

    def _row(self, record: str, k: int, v: VehicleDetection) -> SummaryRow:
        p = v.passage
        weighed = self.weighed and k == 0
        w, ident = self.weighing, self.identification
        lateral = float(v.lateral) if np.isfinite(v.lateral) else None
        if ident is not None:
            residual, quality, lam = ident.residual, ident.vehicle_quality[0], ident.lam
        elif w is not None:
            residual, quality, lam = w.residual, w.quality, None
        else:
            residual, quality, lam = None, "", None
        return SummaryRow(
            record=record, vehicle=k + 1, status="weighed" if weighed else "refused",
            time=self.time_at(p.delay), n_axles=p.n_axles, speed=p.speed,
            axle_spacings=tuple(p.axle_spacings),
            vehicle_class=axle_configuration(p.axle_spacings),
            axle_weights=tuple(self.axle_weights) if weighed else (),
            gvw=self.gvw if weighed else None,
            group_weights=tuple(w.group_weights) if weighed and w is not None else (),
            flags=self.flags, lateral=lateral,
            lateral_unit=v.lateral_unit if lateral is not None else "",
            confidence=v.confidence, residual=residual if k == 0 else None,
            quality=quality if k == 0 else "", method=self.method if k == 0 else "",
            drift_factor=self.drift_factor if k == 0 else None,
            drift_method=self.drift_method if k == 0 else "",
            lam=lam if k == 0 else None, reason="" if weighed else self.reason)


def _gauges(record: Record) -> list[str]:
    return [s.name for s in record.sensors if s.kind.is_structural]


def _detect(record: Record, setup: SiteSetup, *, span, line=None,
            known_spacings=None) -> Detection:
    options = {} if setup.max_spacing is None else {"max_axle_spacing": setup.max_spacing}
    if setup.detectors is not None:
        return detect_axles(record, setup.detectors, setup.distance, position=setup.position,
                            span=span, gauges=_gauges(record), **options)
    if line is None:
        raise InputError("without axle detectors the calibration runs need an influence "
                         "line to detect the truck from the strain (give [axle_detectors])")
    return detect_from_strain(record, line, known_spacings=known_spacings, span=span,
                              gauges=_gauges(record), **options)


def _run_reason(det: Detection, setup: SiteSetup) -> str:
    """Why a calibration run's detection cannot be used ("" if it can)."""
    if not det.vehicles:
        return f"no vehicle detected ({det.message or 'no axles'})"
    if len(det.vehicles) > 1:
        return f"{len(det.vehicles)} vehicles detected, not one calibration truck"
    v = det.vehicles[0]
    if "multiple_presence" in v.flags or "multiple_presence" in det.flags:
        return "multiple presence"
    n = setup.calibration_loads.size
    if v.passage.n_axles != n:
        return f"{v.passage.n_axles} axles detected, the calibration truck has {n}"
    dev = np.max(np.abs(v.passage.axle_spacings - setup.calibration_spacings), initial=0.0)
    if dev > SPACING_TOLERANCE:
        return (f"detected axle spacings differ from the truck's by {dev:.2f} m "
                f"(> {SPACING_TOLERANCE} m)")
    return ""


def calibrate_site(records: Sequence[Record], setup: SiteSetup, *,
                   strain_passes: int = STRAIN_ONLY_PASSES) -> SiteCalibration:
    """Detect the calibration truck in every run and calibrate the lines of every gauge.

    Parameters
    ----------
    records : sequence of Record
        Runs of the calibration truck (logger events), with clock time.
    setup : SiteSetup
    strain_passes : int
        Without axle detectors: passes of (lines from the runs, every run re-detected
        against them by :func:`bwim.detect.detect_from_strain` with the truck's spacings)
        after the first estimate (:func:`bwim.detect.detect_known_truck`, line unknown).
        More passes cost one strain-only detection per run each and reduce the speed
        error (measured by ``tests/validation/test_site_strain_only.py``).

    Returns
    -------
    SiteCalibration

    Raises
    ------
    InputError
        No records, or fewer than two usable runs (the reasons are in the message).
    """
    if records is None or len(records) == 0:
        raise InputError("records: give at least one calibration run")
    if setup.detectors is None:
        if int(strain_passes) < 0:
            raise InputError(f"strain_passes must be >= 0, got {strain_passes!r}")
        return _calibrate_strain_only(records, setup, int(strain_passes))
    detections = [_detect(rec, setup, span=None) for rec in records]
    reasons, passages, kept = _truck_runs(records, detections, setup)
    return _site_calibration(records, setup, detections, reasons, passages, kept)


def _site_calibration(records, setup, detections, reasons, passages, kept) -> SiteCalibration:
    if len(kept) < 2:
        shown = "; ".join(f"run {k + 1}: {r}" for k, r in enumerate(reasons) if r)
        raise InputError(f"only {len(kept)} usable calibration run(s) of {len(records)}: "
                         f"{shown}")
    lines = calibrate_lines([records[k] for k in kept], passages, setup.calibration_loads,
                            lateral=setup.lateral)
    fits: list[RunFit | None] = [None] * len(records)
    for run in lines.runs:
        fits[kept[run.index]] = run
        if run.rejected:
            reasons[kept[run.index]] = run.reason
    return SiteCalibration(lines=lines, detections=tuple(detections), reasons=tuple(reasons),
                           fits=tuple(fits), setup=setup)


def _truck_runs(records, dets, setup):
    """Reasons and passages of the runs' detections: the truck's layout is known exactly,
    so a usable run keeps its detected speed, arrival and lateral position with the
    truck's measured spacings."""
    reasons, passages, kept = [], [], []
    for k, det in enumerate(dets):
        reason = _run_reason(det, setup)
        reasons.append(reason)
        if not reason:
            v = det.vehicles[0].passage
            passages.append(Passage(speed=v.speed, lane=v.lane, delay=v.delay,
                                    axle_spacings=setup.calibration_spacings,
                                    track_width=v.track_width))
            kept.append(k)
    return reasons, passages, kept


def _calibrate_strain_only(records: Sequence[Record], setup: SiteSetup,
                           passes: int) -> SiteCalibration:
    """Calibration without axle detectors (see the module docstring)."""
    dets = list(detect_known_truck(records, setup.calibration_loads,
                                   setup.calibration_spacings,
                                   gauges=_gauges(records[0])))
    reasons, passages, kept = _truck_runs(records, dets, setup)
    for _ in range(passes):
        if len(kept) < 2:
            break
        lines = calibrate_lines([records[k] for k in kept], passages,
                                setup.calibration_loads, lateral=setup.lateral)
        line = lines.line_at()
        again = []
        for rec in records:
            try:
                det = _detect(rec, setup, span=None, line=line,
                              known_spacings=setup.calibration_spacings)
            except InputError as exc:
                det = Detection(message=f"detection failed: {exc}", method="strain")
            again.append(det)
        dets = again
        reasons, passages, kept = _truck_runs(records, dets, setup)
    return _site_calibration(records, setup, dets, reasons, passages, kept)


def weigh_event(record: Record, calibration: SiteCalibration, *, bridge: Bridge | None = None,
                identify_options: Mapping[str, Any] | None = None) -> EventWeighing:
    """Detect and weigh the vehicle of one event (see the module docstring).

    With ``bridge`` (a calibrated FE model), the detected vehicle is weighed by moving
    force identification (:func:`bwim.identify_forces` with ``identify_options``) instead
    of Moses: the gauges then need their positions (x, y) in the model's frame, the first
    axle detector's ``position`` is its x on the bridge, and the readings are strain
    (``[logger] scale``); the calibration runs' scale trend corrects the day's drift of
    the strain-to-load ratio as it does for Moses.

    Never raises for a record it can read: detection or weighing failures come back as an
    :class:`EventWeighing` with ``weighed=False`` and the reason.  The result carries the
    record's clock (:meth:`EventWeighing.time_at`, the summary's ``time``).
    """
    ev = _weigh_event(record, calibration, bridge=bridge, identify_options=identify_options)
    t0 = float(record.time[0])
    return dataclasses.replace(ev, clock=record.clock,
                               clock_of_day=record.clock is None and 0.0 < t0 < 86400.0)


def _weigh_event(record: Record, calibration: SiteCalibration, *, bridge: Bridge | None,
                 identify_options: Mapping[str, Any] | None) -> EventWeighing:
    setup = calibration.setup
    lines = calibration.lines
    try:
        det = _detect(record, setup, span=lines.support, line=lines.line_at())
    except _EVENT_ERRORS as exc:
        return EventWeighing(weighed=False, reason=f"detection failed: {_why(exc)}")
    if not det.vehicles:
        return EventWeighing(weighed=False, reason=det.message or "no axle found",
                             detection=det, flags=det.flags or ("no_axles",))
    flags = tuple(dict.fromkeys([*det.flags, *(f for v in det.vehicles for f in v.flags)]))
    if len(det.vehicles) > 1 or "multiple_presence" in flags:
        return EventWeighing(weighed=False, detection=det, flags=flags,
                             reason=f"multiple presence: {len(det.vehicles)} vehicles "
                             "on the bridge, not weighed as one")
    vehicle = det.vehicles[0]
    if "axle_count_mismatch" in flags:
        return EventWeighing(weighed=False, detection=det, flags=flags,
                             reason="the axle detectors disagree on the number of axles")
    if bridge is not None:
        return _weigh_mfi(record, det, flags, calibration, bridge, identify_options or {})
    try:
        w = weigh(record, vehicle.passage, lines, combine=setup.combine,
                  scale_correction=setup.drift != "none")
    except _EVENT_ERRORS as exc:
        return EventWeighing(weighed=False, detection=det, flags=flags,
                             reason=f"weighing failed: {_why(exc)}")
    flags = tuple(dict.fromkeys([*flags, *w.flags]))
    drift = {"drift_factor": w.scale_factor, "drift_method": "trend" if (
        setup.drift == "trend" and lines.scale_trend is not None) else ""}
    if w.quality == "reject":
        hard = ", ".join(f for f in w.flags if f in HARD_FLAGS)
        return EventWeighing(weighed=False, detection=det, weighing=w, flags=flags,
                             reason=f"implausible weighing ({hard})", **drift)
    return EventWeighing(weighed=True, detection=det, weighing=w, flags=flags, **drift)


def _weigh_mfi(record: Record, det: Detection, flags: tuple[str, ...],
               calibration: SiteCalibration, bridge: Bridge,
               options: Mapping[str, Any]) -> EventWeighing:
    """The detected vehicle weighed by moving force identification with ``bridge``."""
    vehicle = det.vehicles[0]

    def refused(reason: str) -> EventWeighing:
        return EventWeighing(weighed=False, detection=det, flags=flags, reason=reason)

    gauges = [s for s in record.sensors if s.kind.is_structural]
    if any(s.x is None or s.y is None for s in gauges):
        return refused("weighing by MFI needs every gauge's position (x, y) in the scenario")
    if vehicle.lateral_unit != "m" or not np.isfinite(vehicle.lateral):
        return refused("weighing by MFI needs the vehicle's lane in metres (gauge y positions)")
    trend = calibration.lines.scale_trend if calibration.setup.drift != "none" else None
    factor = float(trend(record.clock_seconds())) if trend is not None else 1.0
    rec = record.channels(gauges)
    # the model's bridge is at rest before the first axle arrives: the logger's offsets
    # are the readings' mean until then (the pre-trigger)
    before = vehicle.passage.axle_x(rec.time)[:, 0] < 0.0
    if np.count_nonzero(before) < 8:
        return refused("weighing by MFI needs readings before the first axle reaches the "
                       "bridge (a pre-trigger) to zero the gauges")
    data = (rec.data - rec.data[before].mean(axis=0)) / factor
    rec = dataclasses.replace(rec, data=data, passages=(vehicle.passage,))
    try:
        ident = identify_forces(bridge, rec, **options)
    except _EVENT_ERRORS as exc:
        return refused(f"weighing by MFI failed: {_why(exc)}")
    extra = [] if trend is None or trend.covers(record.clock_seconds()) else [
        "outside_calibration_time"]
    flags = tuple(dict.fromkeys([*flags, *ident.vehicle_flags[0], *extra]))
    drift = {"drift_factor": factor, "drift_method": "" if trend is None else "trend"}
    if ident.vehicle_quality[0] == "reject":
        hard = ", ".join(f for f in ident.vehicle_flags[0] if f in HARD_FLAGS)
        return EventWeighing(weighed=False, detection=det, flags=flags, identification=ident,
                             reason=f"implausible weighing ({hard})", **drift)
    return EventWeighing(weighed=True, detection=det, flags=flags, identification=ident,
                         **drift)
