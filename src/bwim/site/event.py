"""One event of a site: every vehicle detected, each weighed or refused with its reason.

Contract
--------
* :func:`weigh_event` finds every vehicle of the record in every lane
  (:func:`bwim.site.lanes.detect_lanes`; vehicles a pair found one after the other,
  never on the span together, each detected again on its own part of the record:
  :func:`bwim.site.isolate.detected_alone`) and decides, vehicle by vehicle:

  - a vehicle travelling the other way than the calibration truck is **counted, not
    weighed** (no lines were calibrated for that direction): refused with that reason;
  - a vehicle whose detection is not to be trusted is refused first, with its reason: a
    detector of its pair off in gain (``detector_fault``), a fitted speed outside the
    detection's range (``speed_out_of_range``), a record that cuts it (``truncated``),
    one axle (``single_axle``);
  - a vehicle that shares the span with another vehicle travelling its way (side by side
    or following) is refused (``multiple_presence``): one record cannot tell their weights
    apart with lines of one vehicle;
  - a vehicle longer than its pair's ``max_length`` that has no axle spacing with room
    for two vehicles following each other (:attr:`~bwim.site.lanes.LaneVehicle.joined`)
    is refused, and so is a part cut out of a longer one that its own part of the record
    did not confirm (:attr:`~bwim.site.lanes.LaneVehicle.cut`);
  - the day's drift at the vehicle (below) is read from the event's whole record;
  - for any other vehicle, the vehicles that cross before or after it without sharing
    the span (a truck following it in its lane, one that crossed the other way before
    it) are cut off the record it is judged and weighed on
    (:func:`bwim.site.isolate.own_part`);
  - its gauges are judged first (:func:`bwim.site.health.check_gauges`, also for a
    vehicle weighed by MFI, below): a dead, stuck, reversed or gain-changed
    gauge is left out and named (``gauge_fault:NAME``, quality ``warning``); too few
    healthy gauges refuse it, and so does a gauge that disagrees while a vehicle of the
    other direction is on the span;
  - a vehicle whose lateral position (in metres, from the gauges' y) lies more than
    :data:`LATERAL_REACH` from the calibration runs' mean is refused (unless one faulty
    gauge, left out, moved it), by the lines or by MFI: it is in another lane than the
    runs (a lane without detectors, seen by this lane's pair) or another vehicle beside
    it pulls the strain's centre away, and the weighing is not calibrated there (an
    unseen truck beside a weighed one is in its readings: MFI weighed such a pair +126 %,
    its relative residual lowered by the larger signal);
  - it is then weighed (:func:`bwim.wim.weigh`: gauges combined by generalised
    least squares, axle groups as groups); one with a vehicle of the other direction on
    the span at the same time is weighed and flagged ``multiple_presence`` (the fit's
    residual check still refuses a weighing the other vehicle spoils);
  - a weighing of quality ``"reject"`` (negative or absurd weights, a fit far worse than
    the calibration's, a truncated record) gives no weights, only its flags and reason.

  It never raises on a record it can read: every outcome is an :class:`EventWeighing`.
* **Drift**: each weighed vehicle's weights are divided by the strain-to-load factor of
  the setup's method (:mod:`bwim.site.drift`) at the vehicle's clock time: the
  calibration runs' temperature regression at the record's median temperature, the runs'
  trend over the time of day, their trend over absolute time, or 1.  The traffic method
  works on a whole batch's rows afterwards (:func:`bwim.site.correct_drift`); per event
  it starts from the time of day.
* With a calibrated FE model (``bridge``: a :class:`~bwim.site.SiteModel`, or a bare
  :class:`~bwim.fe.bridge.Bridge` whose readings are strains and whose frame is the
  detectors') the calibration lane's vehicle is weighed by moving force identification
  instead (:func:`bwim.identify_forces` with ``identify_options``; the readings as
  :meth:`~bwim.site.SiteModel.readings` gives them, the gauges the health check found
  faulty left out): the gauges then need positions (x, y) in the model's frame.  A model
  that is not accepted weighs nothing (each such vehicle is refused with its reason).  As
  with the lines, a vehicle with one of the other direction on the span is weighed and
  flagged ``multiple_presence``, and the residual check (the model's own limit,
  :meth:`~bwim.site.SiteModel.residual_limit`) refuses a weighing the other vehicle
  spoils.  Its row's quality is the identification's, made a warning by any flag.
* :class:`EventWeighing` keeps its first weighed vehicle (else the first in the
  calibration lane) as the event's own (``weighed``, ``gvw``, ``weighing``...), and
  every vehicle in ``vehicles``; :meth:`EventWeighing.to_summary_rows` gives one row each.
* Units: N, m, s; readings in the logger's units.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from datetime import time as dtime
from typing import Any

import numpy as np

from bwim.classify import axle_configuration
from bwim.detect import Detection, VehicleDetection, detect_from_strain
from bwim.detect.presence import windows_overlap
from bwim.detect.result import (
    FLAG_DETECTOR_FAULT,
    FLAG_MULTIPLE_PRESENCE,
    FLAG_SINGLE_AXLE,
    FLAG_SPEED_RANGE,
    FLAG_TRUNCATED,
)
from bwim.errors import DATA_ERRORS, InputError
from bwim.fe.bridge import Bridge
from bwim.mfi import ForceIdentification, identify_forces
from bwim.plausibility import HARD_FLAGS, quality_of
from bwim.records import Passage, Record
from bwim.site.calibrate import (
    SiteCalibration,
    gauge_names,
    record_temperature,
    temperature_channel,
)
from bwim.site.health import check_gauges
from bwim.site.isolate import detected_alone, own_part
from bwim.site.lanes import EventDetection, LaneVehicle, detect_lanes
from bwim.site.model import SiteModel
from bwim.site.wheelpath import gauge_line, group_laterals
from bwim.summary import SummaryRow
from bwim.wim import Weighing, weigh

__all__ = ["EventWeighing", "VehicleWeighing", "weigh_event"]

#: m: how far from the calibration runs' mean lateral position a vehicle weighed by the
#: lines may lie: the wander a lane leaves a truck (a 2.5 m wide truck in a 3.5 m lane
#: moves ± 0.5 m) and the detected position's own error (about as much).  Beyond it the
#: vehicle is in another lane than the runs, or the strain's centre is pulled by a
#: vehicle no detector saw.
LATERAL_REACH = 1.0


def _why(exc: BaseException) -> str:
    """An exception as one line (its type when it has no message)."""
    return " ".join(str(exc).split()) or type(exc).__name__


def _axle_weights(w: VehicleWeighing | EventWeighing) -> np.ndarray | None:
    """A weighed vehicle's static axle weights, N: MFI's when it identified the forces,
    else Moses'; None unless weighed."""
    if not w.weighed:
        return None
    if w.identification is not None:
        return w.identification.axle_weights
    return w.weighing.axle_weights


def _gvw(w: VehicleWeighing | EventWeighing) -> float | None:
    """A weighed vehicle's gross weight, N (as :func:`_axle_weights`)."""
    if not w.weighed:
        return None
    if w.identification is not None:
        return float(w.identification.gvw[0])
    return w.weighing.gvw


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleWeighing:
    """One vehicle of an event, weighed or not.

    Attributes
    ----------
    vehicle : VehicleDetection
    lane : int or None
    direction : str
    weighed : bool
        True when ``weighing`` (or ``identification``) holds weights that passed the
        plausibility checks.
    reason : str
        Why the vehicle was not weighed ("" when it was).
    weighing : Weighing or None
    identification : ForceIdentification or None
    flags : tuple of str
    drift_factor : float or None
    drift_method : str
    group_laterals : tuple of float
        Each axle group's lateral position, in the vehicle's lateral unit
        (:func:`bwim.site.wheelpath.group_laterals`); measured for a weighed vehicle,
        empty otherwise.
    """

    vehicle: VehicleDetection
    lane: int | None
    direction: str
    weighed: bool
    reason: str = ""
    weighing: Weighing | None = None
    identification: ForceIdentification | None = None
    flags: tuple[str, ...] = ()
    drift_factor: float | None = None
    drift_method: str = ""
    group_laterals: tuple[float, ...] = ()

    @property
    def axle_weights(self) -> np.ndarray | None:
        """Static axle weights, N (None unless weighed)."""
        return _axle_weights(self)

    @property
    def gvw(self) -> float | None:
        """Gross vehicle weight, N (None unless weighed)."""
        return _gvw(self)


@dataclass(frozen=True, kw_only=True, eq=False)
class EventWeighing:
    """The outcome of one event (:func:`weigh_event`); never raised, always returned.

    The event's own attributes are those of its principal vehicle (the first weighed,
    else the first of the calibration lane); ``vehicles`` holds them all.

    Attributes
    ----------
    weighed : bool
        True when the principal vehicle holds weights that passed the plausibility checks.
    reason : str
        Why it was not weighed ("" when it was).
    detection : Detection or None
        The principal vehicle's lane's detection; None when detection itself failed.
    weighing : Weighing or None
    flags : tuple of str
        Detection and weighing flags of the principal vehicle.
    identification : ForceIdentification or None
        When weighed by MFI with an FE model.
    clock : datetime or None
        The record's wall clock at record time 0 (:attr:`bwim.Record.clock`).
    clock_of_day : bool
        True when the record has no ``clock`` but its time axis is the clock time of day
        (a logger that writes it in the time column: the axis does not start at 0).
    drift_factor : float or None
    drift_method : str
    vehicles : tuple of VehicleWeighing
        Every vehicle found, in order of arrival.
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
    vehicles: tuple[VehicleWeighing, ...] = ()

    @property
    def method(self) -> str:
        """``"mfi"`` (identified with an FE model) or ``"moses"`` (influence lines)."""
        return "mfi" if self.identification is not None else "moses"

    @property
    def passage(self) -> Passage | None:
        """The principal vehicle's passage (None when no single vehicle was found)."""
        if self.detection is None or len(self.detection.vehicles) != 1:
            return None
        return self.detection.vehicles[0].passage

    @property
    def axle_weights(self) -> np.ndarray | None:
        """Static axle weights, N (None unless weighed)."""
        return _axle_weights(self)

    @property
    def gvw(self) -> float | None:
        """Gross vehicle weight, N (None unless weighed)."""
        return _gvw(self)

    def time_at(self, t: float) -> datetime | dtime | None:
        """Wall-clock time of record time ``t`` (s): a datetime with the record's clock, a
        time of day when the record's axis is one (past midnight: the next day's), else
        None."""
        if self.clock is not None:
            return self.clock + timedelta(seconds=float(t))
        if self.clock_of_day and t >= 0.0:
            return (datetime.min + timedelta(seconds=float(t) % 86400.0)).time()
        return None

    def to_summary_row(self, record: str) -> SummaryRow:
        """The summary row of this event's principal vehicle, named ``record``."""
        rows = self.to_summary_rows(record)
        principal = next((k for k, v in enumerate(self.vehicles) if v.weighed), 0)
        return rows[principal] if principal < len(rows) else rows[0]

    def to_summary_rows(self, record: str) -> tuple[SummaryRow, ...]:
        """One :class:`~bwim.summary.SummaryRow` per vehicle (at least one), named
        ``record``: a weighed vehicle with its weights, every other refused with its
        reason (no weight leaves without its plausibility checks)."""
        if not self.vehicles:
            return (SummaryRow(record=record, status="refused", flags=self.flags,
                               reason=self.reason or "no vehicle found"),)
        return tuple(self._row(record, k, v) for k, v in enumerate(self.vehicles))

    def _row(self, record: str, k: int, vw: VehicleWeighing) -> SummaryRow:
        v = vw.vehicle
        p = v.passage
        w, ident = vw.weighing, vw.identification
        lateral = float(v.lateral) if np.isfinite(v.lateral) else None
        if ident is not None:  # the vehicle's own flags (drift, gauges) count too
            residual, lam = ident.residual, ident.lam
            own = ident.vehicle_quality[0]
            quality = own if own != "ok" else quality_of(vw.flags)
        elif w is not None:  # the vehicle's flags (w's, the drift's) make its quality
            residual, lam = w.residual, None
            quality = w.quality if w.quality == "reject" else quality_of(vw.flags)
        else:
            residual, quality, lam = None, "", None
        return SummaryRow(
            record=record, vehicle=k + 1, status="weighed" if vw.weighed else "refused",
            time=self.time_at(p.delay + (p.axle_offsets[0] if p.n_axles else 0.0)),
            lane=vw.lane, direction=vw.direction, n_axles=p.n_axles, speed=p.speed,
            axle_spacings=tuple(p.axle_spacings),
            vehicle_class=axle_configuration(p.axle_spacings),
            axle_weights=tuple(vw.axle_weights) if vw.weighed else (),
            gvw=vw.gvw if vw.weighed else None,
            group_weights=tuple(w.group_weights) if vw.weighed and w is not None else (),
            flags=vw.flags, lateral=lateral,
            lateral_unit=v.lateral_unit if lateral is not None else "",
            group_laterals=vw.group_laterals if lateral is not None else (),
            confidence=v.confidence, residual=residual, quality=quality,
            method=("mfi" if ident is not None else "moses") if (w or ident) else "",
            drift_factor=vw.drift_factor, drift_method=vw.drift_method, lam=lam,
            reason="" if vw.weighed else vw.reason)


# --- weigh_event -------------------------------------------------------------------------
def weigh_event(record: Record, calibration: SiteCalibration, *,
                bridge: Bridge | SiteModel | None = None,
                identify_options: Mapping[str, Any] | None = None) -> EventWeighing:
    """Detect and weigh every vehicle of one event (see the module docstring).

    Raises InputError for arguments of the wrong kind; never raises for a record it can
    read: detection or weighing failures come back as an
    :class:`EventWeighing` with ``weighed=False`` and the reason.  The result carries the
    record's clock (:meth:`EventWeighing.time_at`, the summary's ``time``).
    """
    if not isinstance(record, Record):
        raise InputError(f"record must be a bwim.Record, got {type(record).__name__}")
    if not isinstance(calibration, SiteCalibration):
        raise InputError(f"calibration must be a SiteCalibration (bwim.calibrate_site), got "
                         f"{type(calibration).__name__}")
    if identify_options is not None and not isinstance(identify_options, Mapping):
        raise InputError(f"identify_options must be a mapping of identify_forces' options, "
                         f"got {type(identify_options).__name__}")
    base = {"clock": record.clock, "clock_of_day": record.time_of_day}
    setup = calibration.setup
    lines = calibration.lines
    span = lines.core_support or lines.support  # a lobe beyond the zeros may be cut
    # the record's gauges (its parts have its channels: the names of every part's)
    gauges = gauge_names(record)
    try:
        if setup.lanes:
            def detect(rec: Record) -> EventDetection:
                return detect_lanes(rec, setup, responses=calibration.responses, span=span,
                                    gauges=gauges, bending=calibration.bending)

            # vehicles one after the other, each detected again on its own part
            ev = detected_alone(record, detect(record), detect)
        else:
            det = detect_from_strain(record, lines.line_at(), span=span, gauges=gauges)
            ev = _single_lane(det, calibration)
    except DATA_ERRORS as exc:
        return EventWeighing(weighed=False, reason=f"detection failed: {_why(exc)}", **base)
    if not ev.vehicles:
        det = ev.by_lane.get(setup.calibration_lane or 1)
        flags = (det.flags if det is not None else ()) or ("no_axles",)
        said = [(lane, d.message) for lane, d in ev.by_lane.items() if d.message]
        if len(said) > 1:  # every lane's pair was searched: each says what it found
            why = "; ".join(f"lane {lane}: {m}" for lane, m in said)
        else:
            why = (det.message if det is not None and det.message else ev.message) or \
                "no axle found"
        return EventWeighing(weighed=False, reason=why, detection=det, flags=flags, **base)
    model = (None if bridge is None else bridge if isinstance(bridge, SiteModel)
             else SiteModel.of_bridge(bridge))
    outcomes = tuple(_vehicle(record, ev, k, calibration, model, identify_options or {},
                              gauges) for k in range(len(ev.vehicles)))
    principal = next((o for o in outcomes if o.weighed), None) or next(
        (o for o in outcomes if o.lane == setup.calibration_lane), outcomes[0])
    pv = ev.vehicles[outcomes.index(principal)]
    lane_det = ev.by_lane.get(pv.pair)
    det = Detection(vehicles=(principal.vehicle,), flags=lane_det.flags if lane_det else (),
                    message=lane_det.message if lane_det else "",
                    method=lane_det.method if lane_det else "")
    return EventWeighing(
        weighed=principal.weighed, reason=principal.reason, detection=det,
        weighing=principal.weighing, flags=principal.flags,
        identification=principal.identification, drift_factor=principal.drift_factor,
        drift_method=principal.drift_method, vehicles=outcomes, **base)


def _single_lane(det: Detection, calibration: SiteCalibration) -> EventDetection:
    """A strain-only detection as the calibration lane's."""
    lane = calibration.setup.calibration_lane or 1
    vehicles = tuple(LaneVehicle(vehicle=v, lane=lane, direction="+x", pair=lane,
                                 window=v.window) for v in det.vehicles)
    if len(vehicles) > 1:  # the strain alone cannot tell side-by-side from following
        vehicles = tuple(dataclasses.replace(v, others=(lane,)) for v in vehicles)
    return EventDetection(vehicles=vehicles, by_lane={lane: det}, message=det.message)


def _vehicle(record: Record, ev: EventDetection, k: int, calibration: SiteCalibration,
             model: SiteModel | None, options: Mapping[str, Any], gauges: list[str]
             ) -> VehicleWeighing:
    """One vehicle's decision and weighing (see the module docstring); ``gauges``: the
    record's (:func:`bwim.site.calibrate.gauge_names`)."""
    setup = calibration.setup
    lv = ev.vehicles[k]
    v = lv.vehicle
    flags = tuple(dict.fromkeys([*v.flags]))

    def refused(reason: str, **kw) -> VehicleWeighing:
        return VehicleWeighing(vehicle=v, lane=lv.lane, direction=lv.direction,
                               weighed=False, reason=reason, flags=kw.pop("flags", flags),
                               **kw)

    cal_direction = setup.calibration_pair.direction if setup.calibration_pair else "+x"
    if lv.direction != cal_direction:
        return refused(f"counted, not weighed: no lines for lane {lv.lane} ({lv.direction}): "
                       "the calibration truck drove the other way")
    # first what makes the detection itself untrustworthy (its windows on the span, and
    # with them the flags below, come from its speed and axles) ...
    if FLAG_DETECTOR_FAULT in flags:
        det = ev.by_lane.get(lv.pair)
        fault = det.fault if det is not None and det.fault else "one is faulty"
        return refused(f"a faulty axle detector: {fault}; the axles it still matches are "
                       "not the vehicle's layout")
    if FLAG_SPEED_RANGE in flags:
        return refused(f"its fitted speed {v.passage.speed:.1f} m/s lies outside the "
                       "detection's speed range: its axles are not a vehicle's to trust")
    if FLAG_TRUNCATED in flags:  # ... then a record that cuts a vehicle (makes others)
        return refused("the record starts or ends while the vehicle is on the bridge "
                       "(truncated): its weights cannot be whole")
    if FLAG_SINGLE_AXLE in flags:
        return refused("one axle found: not a whole vehicle (an isolated peak, or a "
                       "vehicle whose other axles were not found)")
    same_way = [w for j, w in enumerate(ev.vehicles) if j != k and w.direction == lv.direction
                and w.lane is not None and windows_overlap(w.window, lv.window)]
    if same_way:
        lanes = ", ".join(str(w.lane) for w in same_way)
        return refused(f"multiple presence: {1 + len(same_way)} vehicles travelling "
                       f"{lv.direction} on the bridge at once (lanes {lv.lane}, {lanes}), "
                       "not weighed as one")
    if FLAG_MULTIPLE_PRESENCE in flags and not lv.others:
        return refused("multiple presence: two vehicles on the bridge at once, not "
                       "weighed as one")
    if lv.joined:
        length = float(np.sum(v.passage.axle_spacings))
        return refused(f"{v.n_axles} axles over {length:.1f} m, longer than any vehicle the "
                       "site admits, with no gap between them that vehicles following each "
                       "other leave at its speed: a longer combination or vehicles too "
                       "close to tell apart, not weighed as one or in parts")
    if lv.cut:
        return refused("vehicles following each other detected as one and cut by their "
                       "length; this part was not found again on its own part of the "
                       "record, so its axles are not trusted: not weighed")
    if "axle_count_mismatch" in flags:
        return refused("the axle detectors disagree on the number of axles")
    # the day's drift at this vehicle from the event's whole record (its temperature is
    # the event's: a part of the record may miss the probe's readings) ...
    try:
        factor, method, drift_flags = _drift_factor(record, v.passage, calibration)
    except InputError as exc:
        return refused(f"drift correction failed: {_why(exc)}")
    # ... the rest on its own part: the vehicles that cross before or after it are cut off
    # (bwim.site.isolate)
    record = own_part(record, lv.window,
                      [w.window for j, w in enumerate(ev.vehicles) if j != k])
    mfi = model is not None and lv.lane == setup.calibration_lane
    if mfi and not model.accepted:
        return refused(f"the bridge model is not accepted: {model.reason}")
    try:
        health = check_gauges(record, v.passage, calibration.lines, combine=setup.combine,
                              alone=FLAG_MULTIPLE_PRESENCE not in flags)
    except DATA_ERRORS as exc:
        return refused(f"weighing failed: {_why(exc)}")
    if not health.usable:
        return refused(health.reason, flags=(*flags, *health.flags))
    # one faulty gauge moves the detected lateral position; its weighing leaves it out
    one_fault = len({f.gauge for f in health.faults}) == 1
    if not one_fault and v.lateral_unit == "m":  # MFI too: a vehicle beside it no
        centre = calibration.lines.lateral_center  # detector saw is in its readings
        y = float(v.passage.lane)
        if abs(y - centre) > LATERAL_REACH:
            return refused(f"its lateral position {y:.2f} m lies {abs(y - centre):.2f} m from "
                           f"the calibration runs' {centre:.2f} m: another lane than the "
                           "runs', or a vehicle beside it no detector saw; the weighing is "
                           "not calibrated there", flags=(*flags, *health.flags))
    if mfi:  # the gauges the lines found faulty are left out of the MFI too
        faulty = {f.gauge for f in health.faults}
        if method == "trend":  # the lines apply the runs' trend themselves; MFI here
            trend, when = calibration.lines.scale_trend, record.clock_seconds()
            factor = float(trend(when))
            drift_flags = (*drift_flags,
                           *(() if trend.covers(when) else ("outside_calibration_time",)))
        out = _weigh_mfi(record, lv, (*flags, *health.flags), model, options, factor,
                         method, drift_flags, faulty)
        if not out.weighed:
            return out
        return dataclasses.replace(out, group_laterals=_group_laterals(
            record, lv, calibration, faulty, gauges))
    try:
        scaling = {"scale_correction": method == "trend",
                   "scale": None if method == "trend" else factor}
        # the gauge check's last weighing had the healthy channels: its model, scaled
        w = health.mark(health.model.weigh(**scaling) if health.model is not None else
                        weigh(record, v.passage, health.lines, combine=setup.combine,
                              **scaling))
    except DATA_ERRORS as exc:
        return refused(f"weighing failed: {_why(exc)}")
    flags = tuple(dict.fromkeys([*flags, *w.flags, *drift_flags]))
    if method == "trend":
        factor = w.scale_factor
    common = {"vehicle": v, "lane": lv.lane, "direction": lv.direction, "weighing": w,
              "flags": flags, "drift_factor": factor, "drift_method": method}
    if w.quality == "reject":
        hard = ", ".join(f for f in w.flags if f in HARD_FLAGS)
        return VehicleWeighing(weighed=False, reason=f"implausible weighing ({hard})",
                               **common)
    return VehicleWeighing(weighed=True, group_laterals=_group_laterals(
        record, lv, calibration, {f.gauge for f in health.faults}, gauges), **common)


def _group_laterals(record: Record, lv: LaneVehicle, calibration: SiteCalibration,
                    faulty: set[str], gauges: list[str]) -> tuple[float, ...]:
    """A weighed vehicle's axle groups' lateral positions (empty when they cannot be
    measured: :func:`bwim.site.wheelpath.group_laterals`), without the faulty gauges
    (``gauges``: the record's)."""
    try:
        return group_laterals(record, lv.vehicle.passage,
                              gauge_line=gauge_line(calibration.lines), window=lv.window,
                              gauges=[g for g in gauges if g not in faulty])
    except DATA_ERRORS:
        return ()


def _drift_factor(record: Record, passage: Passage, calibration: SiteCalibration
                  ) -> tuple[float, str, tuple[str, ...]]:
    """The strain-to-load factor of the setup's method at this vehicle (see the module
    docstring): factor, method used, flags."""
    setup = calibration.setup
    method = setup.drift.method
    lines = calibration.lines
    if method == "none":
        return 1.0, "none", ()
    if lines.scale_trend is None:  # runs without clocks, or too few: no drift at all
        return 1.0, "", ("no_drift",)
    if method == "trend":
        return 1.0, "trend", ()
    gap: tuple[str, ...] = ()
    if method in ("temperature", "auto"):
        # the channel matters only with the runs' temperature regression
        channel = (temperature_channel(record, setup) if calibration.temperature is not None
                   else None)
        if calibration.temperature is not None and channel is not None:
            temperature = record_temperature(record, channel)
            if temperature is not None:
                f, beyond = calibration.temperature.factor(temperature)
                return f, "temperature", ("temperature_extrapolated",) if beyond else ()
            if method == "temperature":
                raise InputError(f"the temperature channel {channel!r} has no reading in "
                                 "this record")
            gap = ("temperature_missing",)
        if method == "temperature":
            raise InputError("the temperature method needs a temperature channel in the "
                             "runs and in the event ([drift] temperature)")
    tod = calibration.time_of_day
    if tod is None:  # the runs cannot be placed in the day: no drift to apply
        return 1.0, "", (*gap, "no_drift")
    if record.clock is None and not record.time_of_day:
        # no clock and a record time: the event cannot be placed in the day
        return 1.0, "", (*gap, "no_clock")
    when = record.clock_at(passage.delay)
    f, outside = tod.factor(when if when is not None
                            else record.clock_seconds(passage.delay))
    return f, "time_of_day", (*gap, *(("outside_calibration_time",) if outside else ()))


def _weigh_mfi(record: Record, lv: LaneVehicle, flags: tuple[str, ...], model: SiteModel,
               options: Mapping[str, Any], factor: float, method: str,
               drift_flags: tuple[str, ...], faulty: set[str]) -> VehicleWeighing:
    """The detected vehicle weighed by moving force identification with ``model``,
    without the ``faulty`` gauges."""
    vehicle = lv.vehicle

    def refused(reason: str) -> VehicleWeighing:
        return VehicleWeighing(vehicle=vehicle, lane=lv.lane, direction=lv.direction,
                               weighed=False, reason=reason, flags=flags)

    if vehicle.lateral_unit != "m" or not np.isfinite(vehicle.lateral):
        return refused("weighing by MFI needs the vehicle's lane in metres (gauge y positions)")
    if faulty:
        record = record.channels([s for s in record.sensors if s.name not in faulty])
    try:
        rec = model.readings(record, vehicle.passage, factor)
    except InputError as exc:
        return refused(_why(exc))
    try:
        ident = identify_forces(model.bridge, rec, **options)
    except DATA_ERRORS as exc:
        return refused(f"weighing by MFI failed: {_why(exc)}")
    if "max_residual" not in options:  # the model's own limit, for this vehicle's weight
        ident = dataclasses.replace(ident, residual_limit=model.residual_limit(
            rec, float(ident.gvw[0]) if np.isfinite(ident.gvw[0]) else None))
    flags = tuple(dict.fromkeys([*flags, *ident.vehicle_flags[0], *drift_flags]))
    common = {"vehicle": vehicle, "lane": lv.lane, "direction": lv.direction,
              "identification": ident, "flags": flags, "drift_factor": factor,
              "drift_method": method}
    if ident.vehicle_quality[0] == "reject":
        hard = ", ".join(f for f in ident.vehicle_flags[0] if f in HARD_FLAGS)
        return VehicleWeighing(weighed=False, reason=f"implausible weighing ({hard})",
                               **common)
    return VehicleWeighing(weighed=True, **common)
