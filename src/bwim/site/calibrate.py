"""A site's calibration from the calibration truck's runs: detectors' responses, lines of
every gauge, and the drift models.

Contract
--------
* :func:`calibrate_site` (named steps: responses, detection, runs, lines, drift):

  1. **Responses** (``SiteSetup.detection`` ``"learned"`` or ``"auto"``): the calibration
     lane's detectors' responses are learned from the runs with the truck's known
     layout (:func:`bwim.detect.learn_responses`, which also checks the declared detector
     distance against the truck's spacings); the other lanes' pairs take the same shape
     with their own channels' sign, noise and gain ratio (measured on the runs: every
     detector also feels the calibration truck).  ``"auto"`` falls back to separate
     peaks, with a note, when the runs cannot teach a response.
  2. **Detection** of every vehicle in every lane of each run (:mod:`bwim.site.lanes`).
  3. **Runs**: a run is used when its lane holds exactly one vehicle whose axle count
     and spacings are the truck's (within :data:`SPACING_TOLERANCE`), none of whose
     gauges reads flat (dead or stuck; a gauge flat in half the runs or more is refused),
     and no other vehicle is on the span at the same time in any lane (then it is
     rejected with that reason: "another vehicle on the bridge: lane 3, −x, 5 axles"); a
     used run keeps its detected speed, arrival and lateral position with the truck's
     spacings.  A vehicle that crosses before or after the truck without sharing the
     span with it (also in the truck's lane: the truck is then the one vehicle of its
     layout) does not reject the run: the run is cut to the truck's own part of the
     record (:func:`bwim.site.isolate.own_part`; gauge activity no detected vehicle
     explains before or after the truck is cut off too), and every later step uses that
     part.
     Gauge activity that no detected vehicle explains next to the truck (a
     vehicle in a lane without detectors) rejects the run too, and so does a used run
     whose load's lateral centre moves across the deck while the truck crosses
     (:func:`load_centre_spread` more than :data:`LOAD_CENTRE_FACTOR` times the used
     runs' median and :data:`LOAD_CENTRE_MOVE` m more: such a vehicle on the span with
     the truck part of the time).  The span is the lines'
     support, so this takes passes: first the runs with no other vehicle in the record
     at all give provisional lines (one line per gauge whatever the lateral model: a
     lateral slope does not move the span, and its freedom lets a vehicle no detector
     saw draw it off the axles; one such run alone: its own lines' support; lines that
     cannot be fitted: the median of the runs' own supports when
     three runs or more give one, else refused;
     what each other pair reads of the span's bending, learned robustly from every run,
     is no vehicle: :mod:`bwim.site.bending`), then every run is judged with their
     support; when
     runs were rejected, the calibration lane's responses are learned again from the
     runs kept (another vehicle on the detectors smears the learned shapes) and every
     run is detected and judged again with them.  From the second pass on, what the
     other pairs read of the span's bending is known from the first pass's runs
     (:mod:`bwim.site.bending`): a trace of it is not another vehicle.
  4. **Lines** of every gauge from the used runs stacked (:func:`bwim.wim.calibrate_lines`:
     per-run scale factors, their trend, outlier runs rejected with a reason).
  5. **Drift**: the runs' factors over the time of day
     (:class:`~bwim.site.drift.TimeOfDayDrift`, with their dates) and, with a
     temperature channel (``DriftSetup.temperature``), against the runs' median temperatures
     (:class:`~bwim.site.drift.TemperatureDrift`).

  Without axle detectors the truck is found from the strain alone
  (:func:`bwim.detect.detect_known_truck`, then ``strain_passes`` of lines and
  re-detection): see :func:`calibrate_site`.
* **The declaration is checked against the data** (``SiteSetup.calibration_loads`` and
  ``calibration_spacings``, the ``[vehicle]`` of a scenario):

  - the loads before anything else: an axle under :data:`MIN_AXLE_LOAD` (5 kN), or a
    truck of :data:`MIN_TRUCK_AXLES` axles or more under :data:`MIN_TRUCK_WEIGHT`
    (10 t), is no calibration truck: the loads were given in kg (or kN), not N, and the
    message says so (a 40 t truck in kg reads 4.1 t);
  - the spacings after the runs are chosen (with axle detectors): a declared spacing
    that every used run's detected spacing differs from by more than
    :data:`SPACING_BIAS` on the same side (twice that with two used runs) is refused,
    with the detected mean (the
    runs' tolerance :data:`SPACING_TOLERANCE` accepts each run, but all of them
    disagreeing the same way is the declaration's error, not the detection's).
    Without axle detectors the truck is found with its declared spacings, which the
    strain then cannot contradict;
  - the loads' order after the lines: the lines are fitted to the
    used runs again with the declared loads in reverse order, and when those leave a
    relative residual under :data:`REVERSED_FIT` × the declared order's, the loads were
    declared last axle first and are refused with that hint (a line absorbs part of a
    wrong load distribution, but not all of it).  Loads within :data:`REVERSED_SAME` of
    their reverse (a symmetric truck) are not checked.  Without axle detectors the
    passages are found with the loads (:func:`bwim.detect.detect_known_truck`), which
    fits them to the declared order: there the truck is found again with the loads in
    reverse order, and the first lines of each order (before any re-detection pass)
    are compared by the same rule;
* **A gauge faulty in one run** (reversed, or its gain changed) would corrupt its line
  for the whole day: after the lines, each gauge's gain ratio ``⟨m, f⟩ / ⟨f, f⟩`` in
  each used run (its reading, less its mean offset from ``f``, against ``f``, the lines'
  reading of the truck's known loads at the run's passage and scale; a weighing's free
  loads would take up part of one gauge's change), over the median of the run's ratios
  (its own scale), is compared with the same gauge's median over the runs, where its reading stands
  :data:`RUN_GAUGE_SNR` times out of its noise.  A run whose ratio is negative or off by
  more than :data:`~bwim.site.health.GAIN_TOLERANCE` is left out with the gauge named,
  and the lines are fitted again without it.  With only two runs seeing the gauge, a
  disagreement cannot be attributed: InputError, asking for more runs.  After a run is
  left out (by this judge or the moving load's), the runs left are judged again, by both,
  until neither leaves one out: two runs left that disagree are refused as they are when
  given alone.
* **A gauge clipped or drifting in one run**, in the same pass: a run in which a gauge is
  held at a rail (:func:`bwim.site.health.check_gauges`' clipping test on the run and its
  passage) is left out naming the gauge; a run in which a gauge's baseline changes (its
  residual over the whole record, reading − offset − fitted static reading, has a
  least-squares line in time whose change from the first sample to the last is ``D``)
  by more than :data:`RUN_DRIFT` × its noise at rest beyond the same gauge's median
  ``D`` over the runs is left out as drifting.  With only two runs, ``D`` differing by
  more than twice that cannot be attributed: InputError, asking for more runs.
* Raises :class:`~bwim.errors.InputError` when fewer than two runs are usable, naming
  each run's reason, or when the declaration contradicts the data (above).
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import date
from types import MappingProxyType

import numpy as np

from bwim.detect import (
    Detection,
    DetectorResponse,
    LearnedResponses,
    detect_from_strain,
    detect_known_truck,
    learn_responses,
)
from bwim.detect.lateral import in_metres
from bwim.detect.presence import unexplained_activity, windows_overlap
from bwim.detect.response import band_pass, peak_polarity
from bwim.detect.result import FLAG_COUNT_MISMATCH, FLAG_MULTIPLE_PRESENCE, FLAG_TRUNCATED
from bwim.detect.signals import channel_data, robust_sigma
from bwim.errors import DATA_ERRORS, InputError
from bwim.records import Passage, Record
from bwim.site.bending import DetectorBending, learn_bending
from bwim.site.drift import TemperatureDrift, TimeOfDayDrift, seconds_of_day
from bwim.site.health import FLAT_NOISE, GAIN_TOLERANCE, check_gauges
from bwim.site.isolate import own_part
from bwim.site.lanes import EventDetection, LaneVehicle, detect_lanes
from bwim.site.setup import SiteSetup
from bwim.wim import MultiRunCalibration, Weighing, calibrate_lines
from bwim.wim.influence_line import read_channels
from bwim.wim.multirun import RunFit
from bwim.wim.weigh import weighing_model

__all__ = ["LOAD_CENTRE_FACTOR", "LOAD_CENTRE_MOVE", "LOAD_CENTRE_SHARE", "MIN_AXLE_LOAD",
           "MIN_TRUCK_AXLES", "MIN_TRUCK_WEIGHT", "REVERSED_FIT", "REVERSED_SAME",
           "RUN_DRIFT", "RUN_SCALE_RANGE", "SPACING_BIAS", "SPACING_TOLERANCE",
           "STRAIN_ONLY_PASSES", "SiteCalibration", "calibrate_site", "gauge_names",
           "load_centre_spread", "record_temperature", "temperature_channel"]

#: A calibration run whose detected axle spacings differ from the truck's by more than
#: this (m) is rejected: the detection, not the truck, is wrong.
SPACING_TOLERANCE = 0.3
#: A declared spacing that every used run's detected spacing differs from by more than
#: this (m), all on the same side, is refused: the detectors measure the truck's
#: spacings to a few centimetres (tests/unit/test_site_declaration.py states the spread).
#: With two used runs, by more than twice this: two runs fall on one side half the time,
#: and the detection's scatter reaches past it (77 used runs of 13 short-span-4-lane
#: days: the 6 m spacing read more than 0.05 m short in 15.6 % of runs, so both of two
#: runs in 2.4 %; more than 0.1 m off in 1.3 %; stop 37).
SPACING_BIAS = 0.05
#: The lines fitted with the declared loads in reverse order leave less than this fraction
#: of the declared order's relative residual: the loads were declared in reverse order
#: (tests/unit/test_site_load_order.py states the residuals of both orders).
REVERSED_FIT = 0.75
#: Loads within this relative difference of their reverse order are a symmetric truck:
#: the order is not checked.
REVERSED_SAME = 0.02
#: Gravity, m/s², for the loads' message in tonnes.
_G = 9.81
#: A calibration truck's axle is heavier than this, N (an empty car's axle is ≈ 5 kN).
MIN_AXLE_LOAD = 5e3
#: A calibration truck of MIN_TRUCK_AXLES axles or more weighs more than this, N (10 t:
#: an empty 5-axle articulated truck weighs about 14 t).
MIN_TRUCK_WEIGHT = 10e3 * _G
MIN_TRUCK_AXLES = 5
#: Least spread (natural log) of a transferred pair's amplitude ratio about its gain ratio.
TRANSFERRED_SPREAD = float(np.log(2.0))
#: Without axle detectors: passes of (lines from the runs, runs re-detected against them).
STRAIN_ONLY_PASSES = 2
#: A gauge is compared between calibration runs where its reading is this many times its
#: noise (RMS over the samples with an axle on the lines' support).  The ratio averages
#: the whole crossing: the clean runs of the test sites' far gauges (3 to 10 times their
#: noise) keep within ×1.13 of their median, the near ones' within ×1.11.
RUN_GAUGE_SNR = 3.0
#: A gauge's baseline change over a calibration run (its residual's least-squares line,
#: first sample to last) may differ from its median change over the runs by this many
#: times its noise at rest before the run is left out as drifting (the clean runs of the
#: test sites differ by a few times: tests/unit/test_site_run_faults.py states them).
RUN_DRIFT = 12.0


#: The load's lateral centre is followed over the samples whose summed strain exceeds
#: this share of its largest (the truck on the span, not its approach).
LOAD_CENTRE_SHARE = 0.3
#: A used run whose load's lateral centre spreads over more than this many times the used
#: runs' median spread ...
LOAD_CENTRE_FACTOR = 2.0
#: ... and by more than this (m) had another vehicle on the span that no detector saw.
LOAD_CENTRE_MOVE = 0.5


def gauge_names(record: Record) -> list[str]:
    """The record's structural channels (strain, deflection)."""
    return [s.name for s in record.sensors if s.kind.is_structural]


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteCalibration:
    """What :func:`calibrate_site` learned from the runs.

    Attributes
    ----------
    lines : MultiRunCalibration
        The lines, the runs' residuals, scale factors and rejections.
    detections : tuple of Detection
        What detection found in each run's calibration lane (same order as the records).
    reasons : tuple of str
        Why each run was left out ("" when it was used).
    fits : tuple of (RunFit or None)
        Each run against the lines (None for a run that detection left out).
    setup : SiteSetup
    responses : mapping of int to LearnedResponses
        The detector lanes' responses (empty: detection by separate peaks).
    bending : mapping of int to DetectorBending
        What each detector pair other than the calibration lane's reads of the span's
        bending, from the runs used (:mod:`bwim.site.bending`; empty without gauges).
    time_of_day : TimeOfDayDrift or None
        The runs' factors over the time of day.
    temperature : TemperatureDrift or None
        The runs' factors against their temperature (with a temperature channel).
    notes : tuple of str
        What was decided and why (a fallback, a distance offset).
    """

    lines: MultiRunCalibration
    detections: tuple[Detection, ...]
    reasons: tuple[str, ...]
    fits: tuple[RunFit | None, ...]
    setup: SiteSetup
    responses: Mapping[int, LearnedResponses] = field(default_factory=dict)
    bending: Mapping[int, DetectorBending] = field(default_factory=dict)
    time_of_day: TimeOfDayDrift | None = None
    temperature: TemperatureDrift | None = None
    notes: tuple[str, ...] = ()

    @property
    def n_used(self) -> int:
        return sum(1 for r in self.reasons if not r)

    @property
    def dates(self) -> tuple[date, ...]:
        """The calibration runs' dates (empty when their clock has no date)."""
        return () if self.time_of_day is None else self.time_of_day.dates

    def __repr__(self) -> str:
        return (f"SiteCalibration({self.n_used} of {len(self.reasons)} runs used, "
                f"{len(self.lines.channels)} channels, detection "
                f"{'learned' if self.responses else 'peaks'}, lanes "
                f"{[p.lane for p in self.setup.lanes]})")


def calibrate_site(records: Sequence[Record], setup: SiteSetup, *,
                   strain_passes: int = STRAIN_ONLY_PASSES) -> SiteCalibration:
    """Detect the calibration truck in every run and calibrate the lines of every gauge
    (see the module docstring).

    Parameters
    ----------
    records : sequence of Record
        Runs of the calibration truck (logger events), with clock time.
    setup : SiteSetup
    strain_passes : int
        Without axle detectors: passes of (lines from the runs, every run re-detected
        against them by :func:`bwim.detect.detect_from_strain` with the truck's spacings)
        after the first estimate (:func:`bwim.detect.detect_known_truck`, line unknown);
        more passes cost one strain-only detection per run each and reduce the speed
        error (measured by ``tests/validation/test_site_strain_only.py``).

    Returns
    -------
    SiteCalibration

    Raises
    ------
    InputError
        No records, or fewer than two usable runs (the reasons are in the message; when
        the calibration lane's pair saw no vehicle in half the runs or more while another
        pair saw one of about the truck's axle count in each of them, the message names
        that pair as the one to mark).
    """
    if records is None or len(records) == 0:
        raise InputError("records: give at least one calibration run")
    if not isinstance(setup, SiteSetup):
        raise InputError(f"setup must be a SiteSetup, got {type(setup).__name__}")
    bad = next((k for k, r in enumerate(records) if not isinstance(r, Record)), None)
    if bad is not None:
        raise InputError(f"records[{bad}] must be a bwim.Record, got "
                         f"{type(records[bad]).__name__}")
    _check_distinct(records)
    _check_loads(setup)
    if setup.lateral == "linear":
        _check_lateral_metres(records)
    if not setup.lanes:
        if int(strain_passes) < 0:
            raise InputError(f"strain_passes must be >= 0, got {strain_passes!r}")
        return _strain_only(records, setup, int(strain_passes))
    notes: list[str] = []
    responses = _responses(records, setup, notes)
    # pass 1, the span unknown: runs with no other vehicle anywhere in the record; what
    # the other pairs read of the span's bending from every run (robustly: a vehicle
    # crossing a pair now and then is an outlier), a trace of it not a vehicle
    everywhere = _bending(records, setup, ())
    events = [detect_lanes(rec, setup, responses=responses, gauges=gauge_names(rec),
                           bending=everywhere) for rec in records]
    flat = _flat_runs(records)
    reasons, passages, kept = _without(flat, *_truck_runs(events, setup, strict=True))
    span = _first_support(records, setup, reasons, passages, kept, events)
    if span is not None:
        # what the other pairs read of the span's bending, from these runs of the truck
        # alone: a trace of it is not another vehicle
        bending = _bending(records, setup, kept)
        # pass 2: with the lines' support, another vehicle counts when it is on the span
        # at the same time as the truck
        events = [detect_lanes(rec, setup, responses=responses, span=span,
                               gauges=gauge_names(rec), bending=bending) for rec in records]
        reasons, passages, kept = _without(flat, *_truck_runs(events, setup))
        # pass 3: the responses learned again from the runs of the truck alone (a run
        # with another vehicle on the detectors smears the learned shapes and every
        # speed found with them), and the runs detected again with them
        if 2 <= len(kept) < len(records) and responses:
            responses = _responses(_own_parts(records, events, setup, kept), setup, [],
                                   learn_from=kept) or responses
            events = [detect_lanes(rec, setup, responses=responses, span=span,
                                   gauges=gauge_names(rec), bending=bending)
                      for rec in records]
            reasons, passages, kept = _without(flat, *_truck_runs(events, setup))
        # from here on each run used is its truck's own part of the record: a vehicle
        # before or after it in the file is cut off
        records = _own_parts(records, events, setup, kept)
    lane_detections = [e.by_lane.get(setup.calibration_lane, Detection()) for e in events]
    cal = _site_calibration(records, setup, lane_detections, reasons, passages, kept,
                            events)
    # a run whose load moved across the deck (another vehicle shared the span), then a
    # run whose gauge disagrees with the same gauge in the others: out, the lines fitted
    # again (each run's reason is then the new fit's), and the runs left judged again by
    # both until neither leaves one out (two runs left that disagree are refused)
    judged = False
    while not judged:
        judged = True
        for judge in (_moving_load_runs, _faulty_gauge_runs):
            out = judge(records, setup, cal, passages, kept)
            if out:
                judged = False
                reasons = [out.get(k, why) for k, why in enumerate(reasons)]
                keep = [i for i, k in enumerate(kept) if k not in out]
                passages, kept = [passages[i] for i in keep], [kept[i] for i in keep]
                cal = _site_calibration(records, setup, lane_detections, reasons,
                                        passages, kept)
    _check_spacings(events, cal.reasons, setup)
    _check_scales(records, cal)
    _check_load_order(records, passages, kept, cal.lines, setup)
    return SiteCalibration(
        lines=cal.lines, detections=cal.detections, reasons=cal.reasons, fits=cal.fits,
        setup=setup, responses=MappingProxyType(dict(responses)),
        bending=MappingProxyType(_bending(records, setup, kept)),
        time_of_day=_time_of_day(records, cal),
        temperature=_temperature(records, cal, setup),
        notes=tuple([*notes, *_clock_note(records, cal)]))


def _faulty_gauge_runs(records: Sequence[Record], setup: SiteSetup, cal: _Lines,
                       passages: Sequence[Passage], kept: Sequence[int]) -> dict[int, str]:
    """Runs in which a gauge disagrees with the same gauge in the other runs: ``{run:
    reason}`` (see the module docstring).  Raises InputError when only two runs are
    compared and they disagree (which one is faulty cannot be told)."""
    lines = cal.lines
    names = [c.name for c in lines.channels]
    ratios: dict[int, np.ndarray] = {}
    trends: dict[int, np.ndarray] = {}
    faulty: dict[int, str] = {}
    for p, k in zip(passages, kept, strict=True):
        fit = cal.fits[k]
        if cal.reasons[k] or fit is None or not np.isfinite(fit.scale):
            continue
        try:
            model = weighing_model(records[k], p, lines, combine=setup.combine)
            w = model.weigh(scale=fit.scale)
            health = check_gauges(records[k], p, lines, combine=setup.combine)
        except DATA_ERRORS:
            continue
        if [c.name for c in w.channels] != names or w.measured.shape[0] == 0:
            continue
        clip = next((f for f in health.faults if f.kind == "clipped"), None)
        if clip is not None:  # a rail is the run's own: no other run is needed to see it
            faulty[k] = f"gauge {clip.gauge} clipped in this run ({clip.detail})"
        trends[k] = _baseline_change(records[k], w, lines) / np.maximum(
            lines.channel_noise, np.finfo(float).tiny)
        # each gauge's gain against the lines under the truck's known loads (a weighing's
        # free loads would take up part of one gauge's change: ×1.5 read as ×1.2), the
        # run's own scale taken out by the median over its gauges
        design = model.design
        known = np.array([setup.calibration_loads[list(g)].sum()
                          for g in model.event.groups.groups])
        pred = fit.scale * np.einsum("kgc,g->kc", design.groups, known)
        meas = model.readings - (model.readings - pred).mean(axis=0)
        m, f = meas[design.on], pred[design.on]
        power = (f * f).sum(axis=0)
        a = (m * f).sum(axis=0) / np.maximum(power, np.finfo(float).tiny)
        # the reading's own strength (a line two disagreeing runs cancel is near zero)
        snr = np.sqrt((m * m).sum(axis=0) / m.shape[0]) / np.maximum(
            lines.channel_noise, np.finfo(float).tiny)
        a = np.where(snr >= RUN_GAUGE_SNR, a, np.nan)
        mid = np.nanmedian(a) if np.isfinite(a).any() else np.nan
        ratios[k] = a / mid if np.isfinite(mid) and mid > 0 else a
    runs = list(ratios)
    if len(runs) < 2:
        return faulty
    table = np.array([ratios[k] for k in runs])
    for j, name in enumerate(names):
        col = table[:, j]
        seen = np.flatnonzero(np.isfinite(col))
        if seen.size < 2:
            continue
        if seen.size == 2:
            q = col[seen[0]] / col[seen[1]]
            if q <= 0 or abs(np.log(q)) > np.log(GAIN_TOLERANCE):
                raise InputError(
                    f"gauge {name} disagrees between the only two calibration runs that "
                    f"see it (runs {runs[seen[0]] + 1} and {runs[seen[1]] + 1}, gain ratio "
                    f"{q:.2f}): one of them has a faulty gauge, or another vehicle on the span "
                    "with its truck; give more runs")
            continue
        ref = float(np.median(col[seen]))
        for i in seen:
            q = col[i] / ref
            if q <= 0:
                faulty.setdefault(runs[i], f"gauge {name} reversed in this run (its "
                                  "response against the other runs' is negative)")
            elif abs(np.log(q)) > np.log(GAIN_TOLERANCE):
                faulty.setdefault(runs[i], f"gauge {name} at {q:.2f} × its gain in the other "
                                  "runs")
    _drifting_runs(names, runs, np.array([trends[k] for k in runs]), faulty)
    return faulty


def load_centre_spread(record: Record, lines: MultiRunCalibration,
                       offsets: np.ndarray) -> float:
    """How far the load's lateral centre moves while a vehicle crosses, m: the spread
    (90th less 10th percentile) of ``Σ y_j ε_j / Σ ε_j`` over the samples whose summed
    strain exceeds :data:`LOAD_CENTRE_SHARE` of its largest, ``ε_j`` each of the lines'
    channels less its ``offsets``, in the sign of its line (the sum of its ordinates: a
    gauge that reads a load negative, mounted or wired so or in hogging, counts by its
    size, not against the others), ``y_j`` its first sensor's ``y``; nan when a ``y`` is
    unknown or no sample qualifies."""
    ys = [c.sensors[0].y for c in lines.channels]
    if any(y is None for y in ys):
        return float("nan")
    sign = np.where(lines.line.ordinates.sum(axis=0) < 0, -1.0, 1.0)
    r = (read_channels(record, lines.channels) - np.asarray(offsets, dtype=float)) * sign
    total = r.sum(axis=1)
    if total.size == 0 or not total.max() > 0:
        return float("nan")
    on = total > LOAD_CENTRE_SHARE * total.max()
    if np.count_nonzero(on) < 3:
        return float("nan")
    centre = (r[on] @ np.asarray(ys, dtype=float)) / total[on]
    lo, hi = np.percentile(centre, [10.0, 90.0])
    return float(hi - lo)


def _moving_load_runs(records: Sequence[Record], setup: SiteSetup, cal: _Lines,
                      passages: Sequence[Passage], kept: Sequence[int]) -> dict[int, str]:
    """Used runs whose load's lateral centre moved across the deck while the truck
    crossed (:func:`load_centre_spread`) more than :data:`LOAD_CENTRE_FACTOR` times the
    used runs' median and by :data:`LOAD_CENTRE_MOVE` more: another vehicle, which no
    detector saw, shared the span with the truck part of the time (one truck alone loads
    the deck at one lateral position).  ``{run: reason}``; none with fewer than three
    used runs.  (``setup`` and ``passages`` unused: the signature of
    :func:`_faulty_gauge_runs`, the other judge of the used runs.)"""
    spread = {}
    for k in kept:
        fit = cal.fits[k]
        if cal.reasons[k] or fit is None:
            continue
        value = load_centre_spread(records[k], cal.lines, fit.offsets)
        if np.isfinite(value):
            spread[k] = value
    if len(spread) < 3:
        return {}
    ref = float(np.median(list(spread.values())))
    return {k: (f"another vehicle on the bridge: the load's lateral centre moved "
                f"{value:.2f} m while the truck crossed (the runs' median {ref:.2f} m)")
            for k, value in spread.items()
            if value > LOAD_CENTRE_FACTOR * ref and value > ref + LOAD_CENTRE_MOVE}


def _drifting_runs(names: Sequence[str], runs: Sequence[int], changes: np.ndarray,
                   faulty: dict[int, str]) -> None:
    """Adds to ``faulty`` the runs in which a gauge's baseline change (``changes``, shape
    (n_runs, n_gauges), in units of its noise at rest) differs from the same gauge's
    median over the runs by more than :data:`RUN_DRIFT`; with only two runs, a
    difference beyond twice that cannot be attributed: InputError."""
    for j, name in enumerate(names):
        col = changes[:, j]
        if col.size == 2:
            if abs(col[0] - col[1]) > 2 * RUN_DRIFT:
                raise InputError(
                    f"gauge {name}'s baseline changes by {col[0]:+.0f} and {col[1]:+.0f} × "
                    f"its noise in the only two calibration runs (runs {runs[0] + 1} and "
                    f"{runs[1] + 1}): one of them has a drifting gauge; give more runs")
            continue
        off = col - np.median(col)
        for i in np.flatnonzero(np.abs(off) > RUN_DRIFT):
            faulty.setdefault(runs[i], f"gauge {name} drifts in this run (its baseline "
                              f"changes {off[i]:+.0f} × its noise beyond its median change "
                              "in the other runs)")


def _baseline_change(record: Record, w: Weighing, lines: MultiRunCalibration) -> np.ndarray:
    """Each channel's residual over the whole record (reading − offset − fitted static
    reading, the latter 0 with no axle on the support): the change of its least-squares
    straight line in time from the first sample to the last, logger units."""
    r = read_channels(record, lines.channels) - w.offsets
    r[np.isin(record.time, w.time)] -= w.fitted
    t = record.time - record.time.mean()
    return (t @ r) / max(float(t @ t), np.finfo(float).tiny) * float(np.ptp(record.time))


def _flat_runs(records: Sequence[Record]) -> dict[int, str]:
    """Runs in which a gauge reads flat (dead or stuck: its sample-to-sample variation
    below :data:`bwim.site.health.FLAT_NOISE` of the run's median gauge's: every working
    gauge shows at least its noise), with the reason; a gauge flat in half the runs or
    more is refused (a dead gauge)."""
    names = gauge_names(records[0])
    if not names or any(gauge_names(r) != names for r in records):
        return {}
    noise = np.array([np.std(np.diff(r.channels(names).data, axis=0), axis=0)
                      for r in records]) / np.sqrt(2.0)  # (n_runs, n_gauges)
    typical = np.median(noise, axis=1)  # each run's median gauge
    flat = noise < FLAT_NOISE * typical[:, None]
    dead = [n for n, f in zip(names, flat.T, strict=True) if f.sum() * 2 >= len(records)]
    if dead and len(records) >= 2:
        raise InputError(f"gauge {dead[0]!r} reads flat (dead or stuck) in "
                         f"{int(flat[:, names.index(dead[0])].sum())} of {len(records)} "
                         "calibration runs: leave it out of the scenario's [[sensors]]")
    return {k: f"gauge {names[int(np.flatnonzero(row)[0])]!r} reads flat in this run "
               "(dead or stuck)" for k, row in enumerate(flat) if row.any()}


def _without(flat: Mapping[int, str], reasons: list[str], passages: list[Passage],
             kept: list[int]) -> tuple[list[str], list[Passage], list[int]]:
    """The runs of :func:`_truck_runs` less those with a flat gauge."""
    reasons = [r or flat.get(k, "") for k, r in enumerate(reasons)]
    keep = [i for i, k in enumerate(kept) if k not in flat]
    return reasons, [passages[i] for i in keep], [kept[i] for i in keep]


#: The used runs' scale factors span at most this ratio (largest over smallest): one truck
#: of the declared loads, whose strain-to-load ratio drifts ±15 % at most within a day
#: (the real site of docs/realistic_site.md: 0.86 … 1.13, a ratio 1.31), with its own
#: dynamics on top.  Beyond it the runs are not of one truck of those loads (e.g. traffic
#: given as calibration records).
RUN_SCALE_RANGE = 1.6


def _check_scales(records: Sequence[Record], cal: _Lines) -> None:
    scales = np.array([fit.scale for _, fit in _used(records, cal)])
    if scales.size < 2 or np.any(scales <= 0):
        return
    lo, hi = float(scales.min()), float(scales.max())
    if hi / lo > RUN_SCALE_RANGE:
        raise InputError(
            f"the used calibration runs' scale factors range from {lo:.2f} to {hi:.2f} "
            f"(×{hi / lo:.1f}; one truck drifts ×{RUN_SCALE_RANGE:g} at most): these are not "
            "runs of one truck of the declared loads (traffic given as calibration records?)")


# --- 0. the declaration -------------------------------------------------------------------
def _check_loads(setup: SiteSetup) -> None:
    """The declared loads are a truck's in N (see the module docstring)."""
    loads = setup.calibration_loads
    total, lightest = float(loads.sum()), float(loads.min())
    if lightest >= MIN_AXLE_LOAD and (loads.size < MIN_TRUCK_AXLES
                                      or total >= MIN_TRUCK_WEIGHT):
        return
    why = (f"an axle of {lightest / 1e3:.2f} kN (under {MIN_AXLE_LOAD / 1e3:g} kN)"
           if lightest < MIN_AXLE_LOAD else
           f"{loads.size} axles weighing {total / 1e3:.1f} kN ({total / _G / 1e3:.1f} t) in "
           f"all (under {MIN_TRUCK_WEIGHT / _G / 1e3:g} t)")
    raise InputError(f"the calibration truck's declared axle loads are implausible: {why}; "
                     "give the static axle loads in N, not kg or kN (1 kg weighs 9.81 N; "
                     "[vehicle] axle_loads)")


def _check_load_order(records: Sequence[Record], passages: Sequence[Passage],
                      kept: Sequence[int], lines: MultiRunCalibration,
                      setup: SiteSetup) -> None:
    """The declared loads against the same loads in reverse order, on the runs and
    passages the lines were fitted to (module docstring)."""
    loads = setup.calibration_loads
    if _symmetric(loads):
        return  # a truck of (nearly) symmetric loads: either order is the same truck
    try:
        other = calibrate_lines([records[k] for k in kept], passages, loads[::-1],
                                lateral=setup.lateral,
                                support_lobes=setup.support_lobes)
    except DATA_ERRORS:
        return  # the reverse order cannot even be fitted: the declared one stands
    _refuse_reversed(float(lines.line.residual), float(other.line.residual))


def _check_load_order_strain(records: Sequence[Record], setup: SiteSetup,
                             lines: MultiRunCalibration) -> None:
    """Without axle detectors: the truck found in the runs with the loads in reverse
    order, its lines against ``lines`` (the declared order's, from the truck found with
    the declared loads).  The passages found with one order are fitted to that order
    (its speed and arrival absorb part of the wrong distribution), so each order gets
    its own."""
    loads = setup.calibration_loads
    if _symmetric(loads):
        return
    reverse = loads[::-1]
    try:
        dets = detect_known_truck(records, reverse, setup.calibration_spacings,
                                  gauges=gauge_names(records[0]))
        _, passages, kept = _truck_runs([_as_event(d, setup) for d in dets], setup)
        other = calibrate_lines([records[k] for k in kept], passages, reverse,
                                lateral=setup.lateral,
                                support_lobes=setup.support_lobes)
    except DATA_ERRORS:
        return
    _refuse_reversed(float(lines.line.residual), float(other.line.residual))


def _symmetric(loads: np.ndarray) -> bool:
    return bool(np.allclose(loads, loads[::-1], rtol=REVERSED_SAME, atol=0.0))


def _refuse_reversed(declared: float, reversed_: float) -> None:
    if reversed_ < REVERSED_FIT * declared:
        raise InputError(
            f"the calibration runs fit markedly better with the declared axle loads in "
            f"reverse order (relative residual {reversed_:.3f} against {declared:.3f} as "
            "declared): give [vehicle] axle_loads from the first axle to the last, in the "
            "truck's direction of travel, as axle_spacings")


def _check_lateral_metres(records: Sequence[Record]) -> None:
    """Lines linear in the lateral position need that position in metres: every gauge
    with its ``y``, not all one (:func:`bwim.detect.lateral_position`).  A lateral index
    in gauge order (the other case) depends on each vehicle's wheels and loads as much as
    on where it drives: on basic-2-lane (gauges without ``y``), lines linear in it
    weighed lane-1 trucks driving within the runs' lateral range 12-42 % low, flagged
    ``lateral_extrapolated`` at most (review of stop 37)."""
    for k, rec in enumerate(records):
        if not in_metres([s for s in rec.sensors if s.kind.is_structural]):
            raise InputError(
                f"lateral = 'linear' needs every gauge's y (m, not all one), which "
                f"records[{k}]'s sensors do not give: a lateral index in gauge order is no "
                "position to make lines linear in; give the gauges' y or leave lateral "
                "unset")


def _check_distinct(records: Sequence[Record]) -> None:
    """Refuse a run given twice (the same readings, or the same clock): one run's lines
    would count as two (the least two runs then passed with one)."""
    seen: dict[object, int] = {}
    for k, rec in enumerate(records):
        keys = [hashlib.sha1(np.ascontiguousarray(rec.data).tobytes()).hexdigest()]
        start = rec.clock_at(rec.time[0]) if rec.clock is not None else None
        if start is not None:  # (events cut from one long file share its clock)
            keys.append(start)
        for key in keys:
            if key in seen:
                same = "readings" if isinstance(key, str) else f"clock ({key:%Y-%m-%d %H:%M:%S})"
                raise InputError(f"calibration runs {seen[key] + 1} and {k + 1} are the same "
                                 f"run (the same {same}): give each run once")
            seen[key] = k


def _check_spacings(events: Sequence[EventDetection], reasons: Sequence[str],
                    setup: SiteSetup) -> None:
    """The declared spacings against the used runs' detected ones (module docstring)."""
    lane = setup.calibration_lane or 1
    n = len(setup.calibration_spacings)
    # the truck of each used run: its lane's vehicle with the truck's axle count (another
    # vehicle may have crossed the lane before or after it)
    detected = np.array([
        trucks[0].vehicle.passage.axle_spacings
        for ev, why in zip(events, reasons, strict=True) if not why
        and (trucks := [w for w in ev.vehicles if w.pair == lane
                        and len(w.vehicle.passage.axle_spacings) == n])])
    if detected.ndim != 2 or detected.shape[0] < 2:
        return
    dev = detected - setup.calibration_spacings
    bias = SPACING_BIAS if dev.shape[0] >= 3 else 2.0 * SPACING_BIAS
    wrong = [i for i in range(dev.shape[1])
             if np.all(dev[:, i] > bias) or np.all(dev[:, i] < -bias)]
    if wrong:
        shown = "; ".join(f"spacing {i + 1} declared {setup.calibration_spacings[i]:.2f} m, "
                          f"detected {setup.calibration_spacings[i] + dev[:, i].mean():.2f} m"
                          for i in wrong)
        raise InputError(f"the calibration truck's declared axle spacings contradict all "
                         f"{dev.shape[0]} used runs: {shown} (every run more than "
                         f"{bias:g} m the same way); check [vehicle] axle_spacings")


# --- 1. responses --------------------------------------------------------------------------
def _responses(records: Sequence[Record], setup: SiteSetup, notes: list[str],
               learn_from: Sequence[int] | None = None) -> dict[int, LearnedResponses]:
    """The detectors' responses: the calibration lane's learned from the runs
    ``learn_from`` (default all), the other lanes' transferred with every run's readings."""
    if setup.detection == "peaks":
        return {}
    pair = setup.calibration_pair
    teach = records if learn_from is None else [records[k] for k in learn_from]
    try:
        learned = learn_responses(teach, pair.channels, pair.distance,
                                  setup.calibration_spacings,
                                  loads=setup.calibration_loads)
    except InputError as exc:
        if "another lane" in str(exc) and len(setup.lanes) > 1:
            raise InputError(f"lane {pair.lane}'s detectors ({', '.join(pair.channels)}), "
                             f"the calibration lane: {exc}; if the truck drove another "
                             "lane, mark that lane's pair (calibration = true in its "
                             "[[axle_detectors]] table)") from None
        if setup.detection == "learned" or "distance" in str(exc):
            raise
        notes.append(f"detection by separate peaks: the runs did not teach the detectors' "
                     f"responses ({' '.join(str(exc).split())})")
        return {}
    if abs(learned.distance_offset) > 0.01 * pair.distance:
        notes.append(f"the detectors' distance may be off by {learned.distance_offset:+.3f} m "
                     f"(the truck's spacings against the declared {pair.distance:g} m)")
    out = {pair.lane: learned}
    for other in setup.lanes:
        if other.lane != pair.lane:
            out[other.lane] = _transferred(learned, other.channels, other.distance, records)
    return out


def _transferred(learned: LearnedResponses, channels: tuple[str, str], distance: float,
                 records: Sequence[Record]) -> LearnedResponses:
    """The calibration lane's response shape for another pair of detectors: each
    channel's own sign, noise and (relative) gain from its band-passed readings in the
    runs, which feel every vehicle on the deck."""
    polarity, noise, size = [], [], []
    for ch in channels:
        y = np.concatenate([r.channels([ch]).data[:, 0] for r in records])
        fs = records[0].sampling_rate
        z = band_pass(y, fs)
        polarity.append(float(peak_polarity(z[:, None])[0]))
        noise.append(max(robust_sigma(np.diff(y)) / np.sqrt(2.0), 1e-300))
        size.append(float(np.percentile(np.abs(z), 99.5)))
    ref = learned.responses[0]
    rel_misfit = ref.misfit / max(ref.noise, 1e-300)
    resp = tuple(
        DetectorResponse(channel=ch, u=r.u, k=r.k * r.sign * pol, noise=n,
                         misfit=n * rel_misfit)
        for ch, r, pol, n in zip(channels, learned.responses, polarity, noise, strict=True))
    gain = np.array(size) / max(size[0], 1e-300)
    amps = np.column_stack([np.ones(1), np.full(1, gain[1])])
    # the pair's gain ratio from the readings' sizes (every vehicle of the runs: cruder
    # than the calibration lane's axle by axle, so its spread is at least a factor 2)
    return LearnedResponses(responses=resp, distance=distance,
                            amplitudes=amps, speeds=np.zeros(0), first_axle_times=np.zeros(0),
                            residuals=np.zeros(0), reasons=(), distance_offset=0.0, nit=0,
                            gain_ratio=float(gain[1]),
                            amplitude_spread=max(learned.amplitude_spread,
                                                 TRANSFERRED_SPREAD))


def _bending(records: Sequence[Record], setup: SiteSetup, kept: Sequence[int]
             ) -> dict[int, DetectorBending]:
    """Each other detector pair's reading of the span's bending, from the runs used (the
    truck alone: nothing crossed those pairs; all runs when fewer than two were used);
    none without gauges (:mod:`bwim.site.bending`)."""
    teach = [records[k] for k in kept] if len(kept) >= 2 else list(records)
    gauges = gauge_names(teach[0])
    if not gauges:
        return {}
    return {pair.lane: learn_bending(teach, pair.channels, gauges)
            for pair in setup.lanes if pair.lane != setup.calibration_lane}


# --- 3. runs -------------------------------------------------------------------------------
def _truck(ev: EventDetection, setup: SiteSetup, strict: bool = False) -> LaneVehicle | None:
    """The calibration truck of a run: the one vehicle of the calibration lane, or, when
    the lane holds more (not ``strict``), the one of them with the truck's axle count and
    spacings (within :data:`SPACING_TOLERANCE`) that never shares the span with another
    of them (a vehicle before or after it in the file); None otherwise."""
    lane = setup.calibration_lane or 1
    own = [v for v in ev.vehicles if v.pair == lane and v.lane == lane]
    if len(own) == 1:
        return own[0]
    if strict:
        return None
    like = [v for v in own if v.vehicle.n_axles == setup.calibration_loads.size
            and np.max(np.abs(v.vehicle.passage.axle_spacings - setup.calibration_spacings),
                       initial=0.0) <= SPACING_TOLERANCE]
    if len(like) != 1 or like[0].window is None:
        return None
    t = like[0]
    apart = all(w.window is not None and not windows_overlap(w.window, t.window)
                for w in own if w is not t)
    return t if apart else None


def _run_reason(ev: EventDetection, setup: SiteSetup, strict: bool = False) -> str:
    """Why a calibration run's detection cannot be used ("" if it can); ``strict``: any
    other vehicle in the record is one too many (the span is not known yet)."""
    lane = setup.calibration_lane or 1
    own = [v for v in ev.vehicles if v.pair == lane and v.lane == lane]
    if not own:
        det = ev.by_lane.get(lane)
        why = det.message if det is not None and det.message else ev.message or "no axles"
        return f"no vehicle detected ({why})"
    why = _truck_reason(ev, setup, own, strict)
    # a run refused whose truck the record cuts: that is why (its other flags, a second
    # vehicle or a wrong axle count, follow from the cut; a truck flagged so but whole
    # enough to pass the checks is used, as the lines' own fit judges it)
    if why and any(FLAG_TRUNCATED in v.vehicle.flags for v in own):
        return "the record starts or ends while the truck is on the bridge (truncated)"
    return why


def _truck_reason(ev: EventDetection, setup: SiteSetup, own: list[LaneVehicle],
                  strict: bool) -> str:
    """:func:`_run_reason` once the calibration lane holds a vehicle."""
    lane = setup.calibration_lane or 1
    truck = _truck(ev, setup, strict)
    if truck is None:
        return f"{len(own)} vehicles detected in lane {lane}, not one calibration truck"
    others = [v for v in ev.vehicles if v is not truck]
    busy = others if strict else [w for w in others if windows_overlap(w.window, truck.window)]
    if busy:
        shown = ", ".join(f"lane {w.lane}, {w.direction}, {w.vehicle.n_axles} axles"
                          for w in busy)
        return f"another vehicle on the bridge: {shown}"
    if FLAG_MULTIPLE_PRESENCE in truck.vehicle.flags and not truck.others:
        return "another vehicle on the bridge: gauge activity no axle detector saw"
    n = setup.calibration_loads.size
    p = truck.vehicle.passage
    if p.n_axles != n:
        return f"{p.n_axles} axles detected, the calibration truck has {n}"
    dev = np.max(np.abs(p.axle_spacings - setup.calibration_spacings), initial=0.0)
    if dev > SPACING_TOLERANCE:
        return (f"detected axle spacings differ from the truck's by {dev:.2f} m "
                f"(> {SPACING_TOLERANCE} m)")
    return ""


def _own_parts(records: Sequence[Record], events: Sequence[EventDetection],
               setup: SiteSetup, kept: Sequence[int]) -> list[Record]:
    """``records`` with each run of ``kept`` cut to its truck's own part
    (:func:`bwim.site.isolate.own_part`: the vehicles before or after it cut off, and
    the gauge activity before or after it that no detected vehicle explains, a vehicle
    no detector saw: :func:`bwim.detect.presence.unexplained_activity` on the gauges'
    sum; activity next to the truck has already refused the run)."""
    out = list(records)
    for k in kept:
        truck = _truck(events[k], setup)
        others = [w.window for w in events[k].vehicles if w is not truck]
        gauges = gauge_names(records[k])
        if gauges and truck.window is not None:
            windows = np.array([w for w in (truck.window, *others) if w is not None])
            total = channel_data(records[k], gauges).sum(axis=1)
            others += [(float(a), float(b)) for a, b in
                       unexplained_activity(records[k].time, total, windows)]
        out[k] = own_part(records[k], truck.window, others)
    return out


def _truck_elsewhere(events: Sequence[EventDetection], setup: SiteSetup) -> str:
    """When the calibration lane's detector pair saw no vehicle in half the runs or more
    while another pair saw one of about the truck's axle count (one axle more or less: a
    pair reading the truck with another pair's responses may merge a group) in each of
    them, and none of those runs shows one of the calibration pair's detectors silent or
    off in gain: the truck drove that pair's lane, what to mark ("" otherwise; the pair
    seeing most of those runs is named)."""
    lane = setup.calibration_lane or 1
    n_axles = setup.calibration_loads.size
    missing = [ev for ev in events if not any(v.pair == lane for v in ev.vehicles)]
    if not events or 2 * len(missing) < len(events):
        return ""
    # a detector of the pair silent or off in gain: the runs' reasons name it, no lane
    if any(det is not None and (FLAG_COUNT_MISMATCH in det.flags or det.fault)
           for det in (ev.by_lane.get(lane) for ev in missing)):
        return ""
    seen = [(sum(any(v.pair == p.lane and abs(v.vehicle.n_axles - n_axles) <= 1
                     for v in ev.vehicles) for ev in missing), p)
            for p in setup.lanes if p.lane != lane]
    count, pair = max(seen, key=lambda s: s[0], default=(0, None))
    if pair is None or count < len(missing):
        return ""
    return (f"lane {lane}'s detectors saw no vehicle in {len(missing)} of {len(events)} "
            f"runs, in each of which lane {pair.lane}'s ({', '.join(pair.channels)}) saw "
            f"one: if the truck drove lane {pair.lane}, mark that lane's pair "
            "(calibration = true in its [[axle_detectors]] table)")


def _truck_runs(events: Sequence[EventDetection], setup: SiteSetup, strict: bool = False):
    """Reasons and passages of the runs: the truck's layout is known exactly, so a usable
    run keeps its detected speed, arrival and lateral position with the truck's
    spacings."""
    reasons, passages, kept = [], [], []
    for k, ev in enumerate(events):
        reason = _run_reason(ev, setup, strict)
        reasons.append(reason)
        if not reason:
            p = _truck(ev, setup, strict).vehicle.passage
            passages.append(Passage(speed=p.speed, lane=p.lane, delay=p.delay,
                                    axle_spacings=setup.calibration_spacings,
                                    track_width=p.track_width))
            kept.append(k)
    return reasons, passages, kept


def _first_support(records: Sequence[Record], setup: SiteSetup, reasons: Sequence[str],
                   passages: Sequence[Passage], kept: Sequence[int],
                   events: Sequence[EventDetection]) -> tuple[float, float] | None:
    """The span by which pass 2 judges whether another vehicle shares the bridge with
    the truck: the support of provisional lines from the runs of pass 1 (the truck alone
    in the whole record, as far as the detectors tell).  When pass 1 kept one run, its
    own support (its lines alone, one per gauge: one run has one lateral position), so
    that runs whose other vehicle crossed before or after the truck are not all refused.
    When the provisional lines cannot be fitted (a vehicle no detector saw before or
    after the truck in one run: its strain draws the support off every other run's
    axles), the median of each run's own support if three runs or more give one (the
    majority's: two that disagree cannot tell which is right).  None otherwise."""
    if len(kept) == 1:
        return _own_support(records[kept[0]], passages[0], setup)
    if len(kept) < 2:
        return None
    # one line per gauge whatever ``setup.lateral``: the span is where the lines are
    # non-zero, which a lateral slope does not move; fitted to runs that may still hold a
    # vehicle no detector saw, that slope's freedom only lets it draw the span off
    plain = setup if setup.lateral is None else dataclasses.replace(setup, lateral=None)
    try:
        return _site_calibration(records, plain, [Detection()] * len(records), reasons,
                                 passages, kept, events).lines.support
    except DATA_ERRORS as exc:
        if len(kept) < 3:
            shown = ", ".join(str(k + 1) for k in kept)
            raise InputError(
                f"the first lines, from runs {shown} (the truck alone in the record, as "
                f"far as the detectors tell), cannot be fitted ({' '.join(str(exc).split())}):"
                " one of them may hold a vehicle no detector saw before or after the truck, "
                "which draws the lines' support off the other's axles; give more runs"
                ) from None
    supports = [s for k, p in zip(kept, passages, strict=True)
                if (s := _own_support(records[k], p, setup)) is not None]
    if len(supports) < 3:
        return None
    lo, hi = np.median(np.array(supports, dtype=float), axis=0)
    return float(lo), float(hi)


def _own_support(record: Record, passage: Passage, setup: SiteSetup
                 ) -> tuple[float, float] | None:
    """The support of one run's own lines (one per gauge), None when they cannot be
    fitted."""
    try:
        return calibrate_lines([record], [passage], setup.calibration_loads,
                               support_lobes=setup.support_lobes).support
    except DATA_ERRORS:
        return None


# --- 4. lines ------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True, eq=False)
class _Lines:
    lines: MultiRunCalibration
    detections: tuple[Detection, ...]
    reasons: tuple[str, ...]
    fits: tuple[RunFit | None, ...]


def _site_calibration(records, setup, detections, reasons, passages, kept,
                      events: Sequence[EventDetection] = ()) -> _Lines:
    if len(kept) < 2:
        shown = "; ".join(f"run {k + 1}: {r}" for k, r in enumerate(reasons) if r)
        hint = _truck_elsewhere(events, setup)
        raise InputError(f"only {len(kept)} usable calibration run(s) of {len(records)} "
                         "(the lines need at least two)" + (f": {shown}" if shown else "")
                         + (f"; {hint}" if hint else ""))
    lines = calibrate_lines([records[k] for k in kept], passages, setup.calibration_loads,
                            lateral=setup.lateral,
                            support_lobes=setup.support_lobes)
    reasons = list(reasons)
    fits: list[RunFit | None] = [None] * len(records)
    for run in lines.runs:
        fits[kept[run.index]] = run
        if run.rejected:
            reasons[kept[run.index]] = run.reason
    return _Lines(lines=lines, detections=tuple(detections), reasons=tuple(reasons),
                  fits=tuple(fits))


# --- 5. drift ------------------------------------------------------------------------------
def _used(records: Sequence[Record], cal: _Lines) -> list[tuple[Record, RunFit]]:
    return [(rec, fit) for rec, fit, why in zip(records, cal.fits, cal.reasons, strict=True)
            if fit is not None and not why and np.isfinite(fit.scale)]


def _clock_note(records: Sequence[Record], cal: _Lines) -> list[str]:
    """A note when runs used cannot be placed in the day (no time-of-day drift)."""
    used = _used(records, cal)
    if len(used) < 2 or all(rec.clock is not None or rec.time_of_day for rec, _ in used):
        return []
    return ["the calibration runs have no clock (none in their file names or columns, and "
            "their time columns are record times, starting within a minute of 0): the "
            "drift cannot follow the time of day, the runs' mean factor is used (give the "
            "clock: [logger] clock)"]


def _time_of_day(records: Sequence[Record], cal: _Lines) -> TimeOfDayDrift | None:
    used = _used(records, cal)
    if len(used) < 2:
        return None
    clocks = [rec.clock_at(rec.time[0]) for rec, _ in used]
    if all(c is not None for c in clocks):
        tod = [seconds_of_day(c) for c in clocks]
        dates = tuple(sorted({c.date() for c in clocks}))
    elif all(c is not None or rec.time_of_day for c, (rec, _) in zip(clocks, used,
                                                                     strict=True)):
        # some (or all) without a date: their time columns are the clock time of day
        tod = [seconds_of_day(c) if c is not None else rec.clock_seconds() % 86400.0
               for c, (rec, _) in zip(clocks, used, strict=True)]
        dates = ()
    else:  # a run without a clock and a record time: the runs cannot be placed in the day
        return None
    return TimeOfDayDrift.fit(tod, [fit.scale for _, fit in used], dates,
                              [float(rec.time[-1] - rec.time[0]) for rec, _ in used])


def temperature_channel(record: Record, setup: SiteSetup) -> str | None:
    """The record's temperature channel: the drift setup's, else its first channel of
    kind ``temperature``; None without one."""
    names = [s.name for s in record.sensors]
    if setup.drift.temperature is not None:
        return setup.drift.temperature if setup.drift.temperature in names else None
    return next((s.name for s in record.sensors if s.kind.value == "temperature"), None)


def record_temperature(record: Record, channel: str) -> float | None:
    """The record's temperature, °C: the median of the channel's finite samples (a probe's
    gaps are NaN); None when it has none."""
    values = record.channels([channel]).data[:, 0]
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else None


def _temperature(records: Sequence[Record], cal: _Lines, setup: SiteSetup
                 ) -> TemperatureDrift | None:
    used = _used(records, cal)
    channels = {temperature_channel(rec, setup) for rec, _ in used}
    if len(channels) != 1 or None in channels:
        return None
    channel = channels.pop()
    temps = [record_temperature(rec, channel) for rec, _ in used]
    known = [(t, fit.scale) for t, (_, fit) in zip(temps, used, strict=True) if t is not None]
    try:
        return TemperatureDrift.fit([t for t, _ in known], [f for _, f in known])
    except InputError:
        return None


# --- without axle detectors ----------------------------------------------------------------
def _strain_only(records: Sequence[Record], setup: SiteSetup, passes: int) -> SiteCalibration:
    """Calibration without axle detectors: the truck found from the strain (layout known),
    then ``passes`` of (lines, runs re-detected against them)."""
    gauges = gauge_names(records[0])
    dets = list(detect_known_truck(records, setup.calibration_loads,
                                   setup.calibration_spacings, gauges=gauges))
    events = [_as_event(d, setup) for d in dets]
    reasons, passages, kept = _truck_runs(events, setup)
    lines = None
    if len(kept) >= 2:  # the order of the loads, on the truck found with each order
        lines = calibrate_lines([records[k] for k in kept], passages,
                                setup.calibration_loads, lateral=setup.lateral,
                                support_lobes=setup.support_lobes)
        _check_load_order_strain(records, setup, lines)
    for _ in range(passes):
        if len(kept) < 2:
            break
        if lines is None:
            lines = calibrate_lines([records[k] for k in kept], passages,
                                    setup.calibration_loads, lateral=setup.lateral,
                                    support_lobes=setup.support_lobes)
        line = lines.line_at()
        lines = None
        dets = []
        for rec in records:
            try:
                det = detect_from_strain(rec, line, known_spacings=setup.calibration_spacings,
                                         gauges=gauge_names(rec))
            except InputError as exc:
                det = Detection(message=f"detection failed: {exc}", method="strain")
            dets.append(det)
        events = [_as_event(d, setup) for d in dets]
        reasons, passages, kept = _truck_runs(events, setup)
    cal = _site_calibration(records, setup, dets, reasons, passages, kept)
    return SiteCalibration(lines=cal.lines, detections=cal.detections, reasons=cal.reasons,
                           fits=cal.fits, setup=setup, time_of_day=_time_of_day(records, cal),
                           temperature=_temperature(records, cal, setup))


def _as_event(det: Detection, setup: SiteSetup) -> EventDetection:
    """A strain-only detection as the detection of the calibration lane."""
    from bwim.site.lanes import LaneVehicle

    lane = setup.calibration_lane or 1
    return EventDetection(
        vehicles=tuple(LaneVehicle(vehicle=v, lane=lane, direction="+x", pair=lane,
                                   window=v.window) for v in det.vehicles),
        by_lane={lane: det}, message=det.message)
