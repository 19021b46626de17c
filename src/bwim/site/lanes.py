"""Vehicles in every lane of an event: each detector pair's detection, put together.

Contract
--------
* :func:`detect_lanes` runs the axle detection of every detector lane of the setup on a
  record (:func:`bwim.detect.detect_axles`, with that lane's learned responses when
  there are: :mod:`bwim.detect.pursuit`) and returns an :class:`EventDetection`: every
  vehicle found, in order of arrival, as a :class:`LaneVehicle` with its lane number and
  direction.
* Frames.  The lines' frame is the calibration truck's: it travels +x there, whichever
  way the bridge's own x runs (a calibration lane declared ``"-x"`` included).  A lane
  that travels like the calibration lane has its passages in that frame (its first
  detector at its ``position``).  A lane that travels the other way: its passages are in
  the mirrored frame ``x' = −x`` (axle i at ``x' = v (t − delay) − a_i``, the first
  detector at ``x' = −position``), where the span is ``(−x_end, −x_start)``; their
  windows on the span are clock times, comparable across lanes.
* A lane pair's detectors also feel vehicles of other lanes, weakly: a single axle found
  by a pair other than the calibration lane's, or a vehicle whose lateral position (m)
  lies clearly in a lane of the other direction (beyond three quarters of the way from
  the pair's ``y`` to that lane's centre) while a pair of that direction saw a vehicle
  at the same time (and the trace has its speed and reads its axles, or fits the pair's
  learned response poorly), is a trace of that vehicle and is left to its lane's
  detectors (reads its axles: as many, each spacing within :data:`ECHO_SPACING` in one
  order or the other); otherwise it is a vehicle of its own, whose lateral position
  another vehicle on the span pulled aside.  A vehicle that
  two pairs of one direction both report
  (its windows on the span overlap) is kept once, from the pair of its own lane (the
  one whose ``y`` is nearer the vehicle's lateral position in metres, else the one that
  saw it with the higher confidence).  A vehicle whose lateral position (m) lies nearer
  another lane of its direction (``SiteSetup.lane_of``) is given that lane's number;
  the vehicles of a pair whose own lane has no known centre line (no ``y``, no traffic
  lane of its number) keep the pair's number.
* **The span's bending read as a vehicle**: with ``bending`` (what each pair other than
  the calibration lane's reads of the span's bending, learned from the calibration runs:
  :mod:`bwim.site.bending`), a vehicle whose pair's largest reading over its time on the
  span (without ``span``: over the whole record) is mostly that bending
  (:meth:`~bwim.site.bending.DetectorBending.is_trace`) is a trace of a vehicle in
  another lane (its humps paired across the two detectors in the
  wrong order read as a slow vehicle) and is left out, with a note.  A light vehicle
  that crosses the pair while a heavy one bends the span more than its own axles read
  is left out with it.
* **Following vehicles**: a detected vehicle whose axles spread over more than its
  pair's ``max_length`` (:data:`~bwim.site.setup.MAX_WHEELBASE` by default, the longest
  standard vehicle on European roads) is vehicles following each other: it is cut
  between axle groups where two plausible vehicles part, at a spacing with room for two
  bodies and a time gap between them (:data:`MIN_OVERHANGS` + :data:`MIN_HEADWAY` ×
  speed; :func:`split_long`, again while a part is too long).  Without such a spacing
  it is a longer combination than the site admits or vehicles too close to tell apart:
  :attr:`LaneVehicle.joined`, weighed neither as one nor in parts.  Each part's window is its
  own time on the span: parts on the span together are each other's multiple presence
  (refused, never weighed as one); parts one after the other are detected again each on
  its own part of the record (:mod:`bwim.site.isolate`), whose detection replaces it.
  Until then a part is :attr:`LaneVehicle.cut` (its axles were read beside the other's)
  and is not weighed.
* **Multiple presence**: vehicles whose windows on the span overlap are each flagged
  ``multiple_presence``; :attr:`LaneVehicle.others` names the lanes of the others.  A
  vehicle no detector saw (a lane without detectors) shows as gauge activity outside
  every detected vehicle's window (:func:`bwim.detect.presence.unexplained_activity` on
  the gauges' sum); such activity that begins or ends within a quarter of a vehicle's
  window length of that window continues into it, so that vehicle is flagged
  ``multiple_presence`` too, with no lane in ``others``.
* Never raises for a record it can read: a lane whose detection fails contributes its
  reason to ``message`` and no vehicle.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bwim.classify import DEFAULT_GROUP_SPACING
from bwim.detect import Detection, LearnedResponses, VehicleDetection, detect_axles
from bwim.detect.assemble import SectionReadings, section_readings
from bwim.detect.presence import span_windows, unexplained_activity, windows_overlap
from bwim.detect.result import FLAG_MULTIPLE_PRESENCE
from bwim.detect.signals import channel_data
from bwim.errors import DATA_ERRORS, require_positive
from bwim.records import Passage, Record
from bwim.site.bending import DetectorBending
from bwim.site.setup import MAX_WHEELBASE, DetectorLane, SiteSetup

__all__ = ["ECHO_SPACING", "MAX_WHEELBASE", "MIN_HEADWAY", "MIN_OVERHANGS", "EventDetection",
           "LaneVehicle", "detect_lanes", "is_echo", "reads_axles_of", "split_long", "too_long"]


@dataclass(frozen=True, kw_only=True, eq=False)
class LaneVehicle:
    """One vehicle of an event, with its lane.

    Attributes
    ----------
    vehicle : VehicleDetection
        Passage in its lane's frame (see the module docstring), lateral position, flags.
    lane : int or None
        Its lane's number.
    direction : str
        ``"+x"`` or ``"-x"``.
    pair : int
        The detector lane whose detectors found it.
    window : (float, float) or None
        Record times it enters and leaves the span.
    others : tuple of int
        The lanes of the other vehicles on the span at the same time.
    cut : bool
        Cut from a longer detection by its length (:func:`split_long`): its axles and
        lateral position were read beside another vehicle's.  Not to be weighed until
        its own part of the record confirms it (:func:`bwim.site.isolate.detected_alone`
        replaces it by that detection).
    joined : bool
        Its axles spread over more than its pair's longest vehicle and no spacing between
        them leaves room for two vehicles following each other (:func:`split_long`): a
        longer combination than the site admits, or vehicles too close to tell apart.
        Not to be weighed, neither as one nor in parts.
    """

    vehicle: VehicleDetection
    lane: int | None
    direction: str
    pair: int
    window: tuple[float, float] | None
    others: tuple[int, ...] = ()
    cut: bool = False
    joined: bool = False


@dataclass(frozen=True, kw_only=True, eq=False)
class EventDetection:
    """Every vehicle of an event (see the module docstring).

    Attributes
    ----------
    vehicles : tuple of LaneVehicle
        In order of arrival on the span.
    by_lane : mapping of int to Detection
        Each detector lane's own detection.
    message : str
        Notes: why a lane found nothing or failed.
    """

    vehicles: tuple[LaneVehicle, ...]
    by_lane: Mapping[int, Detection]
    message: str = ""

    @property
    def flags(self) -> tuple[str, ...]:
        return tuple(sorted({f for d in self.by_lane.values() for f in d.flags}
                            | {f for v in self.vehicles for f in v.vehicle.flags}))


def _frame(pair: DetectorLane, span: tuple[float, float] | None, setup: SiteSetup
           ) -> tuple[float, tuple[float, float] | None]:
    """Position and span of a lane's detection in its own frame: the lines' frame (the
    calibration truck's: it travels +x there, whichever way the bridge's x runs) for a
    lane that travels like the calibration lane, mirrored for one that travels the other
    way."""
    pos = float(pair.position or 0.0)
    cal = setup.calibration_pair
    if cal is None or pair.direction == cal.direction:
        return pos, span
    return -pos, None if span is None else (-span[1], -span[0])


def detect_lanes(record: Record, setup: SiteSetup, *,
                 responses: Mapping[int, LearnedResponses] | None = None,
                 span: tuple[float, float] | None = None, gauges: Sequence[str] = (),
                 lanes: Sequence[int] | None = None,
                 bending: Mapping[int, DetectorBending] | None = None) -> EventDetection:
    """Every vehicle of ``record`` in every detector lane (see the module docstring).

    ``responses`` by lane number (learned detection where given, peaks elsewhere);
    ``span`` the lines' support in their frame; ``gauges`` the strain channels that give
    the lateral position; ``lanes`` limits the detection to these detector lanes;
    ``bending`` by lane number, what those pairs read of the span's bending
    (:mod:`bwim.site.bending`)."""
    bending = bending or {}
    responses = responses or {}
    by_lane: dict[int, Detection] = {}
    seen: list[tuple[DetectorLane, VehicleDetection]] = []
    cut: list[VehicleDetection] = []  # the parts of vehicles cut by their length
    joined: list[VehicleDetection] = []  # too long, and no room to cut them
    found: list[LaneVehicle] = []
    notes: list[str] = []
    # the section gauges read once for every pair (a record without one of them: each
    # pair's detection names it, as without)
    try:
        section = section_readings(record, gauges) if gauges else None
    except DATA_ERRORS:
        section = None
    for pair in setup.lanes:
        if lanes is not None and pair.lane not in lanes:
            continue
        position, lane_span = _frame(pair, span, setup)
        options = {} if pair.max_spacing is None else {"max_axle_spacing": pair.max_spacing}
        try:
            det = detect_axles(record, pair.channels, pair.distance, position=position,
                               span=lane_span, gauges=list(gauges),
                               responses=responses.get(pair.lane), section=section,
                               **options)
        except DATA_ERRORS as exc:
            notes.append(f"lane {pair.lane}: detection failed: {' '.join(str(exc).split())}")
            by_lane[pair.lane] = Detection(message=str(exc), method="")
            continue
        by_lane[pair.lane] = det
        if not det.vehicles and det.message and pair.lane == setup.calibration_lane:
            notes.append(f"lane {pair.lane}: {det.message}")
        for v in det.vehicles:
            parts = split_long(v, lane_span, max_length=pair.max_length)
            if len(parts) > 1:
                length = float(np.sum(v.passage.axle_spacings))
                notes.append(f"lane {pair.lane}: {v.n_axles} axles over {length:.1f} m, "
                             f"longer than any vehicle ({pair.max_length:g} m): "
                             f"{len(parts)} vehicles following each other")
                cut.extend(parts)
            for w in parts:
                if too_long(w, pair.max_length):
                    notes.append(
                        f"lane {pair.lane}: {w.n_axles} axles over "
                        f"{float(np.sum(w.passage.axle_spacings)):.1f} m, longer than any "
                        f"vehicle ({pair.max_length:g} m) with no gap between them that "
                        "vehicles following each other leave at its speed: a longer "
                        "combination or vehicles too close to tell apart")
                    joined.append(w)
            seen.extend((pair, w) for w in parts)
    for pair, v in seen:
        lane = pair.lane
        # the trace is judged over the vehicle's time on the span; without a span, over
        # the whole record (a vehicle crossing the pair anywhere in it keeps it)
        trace_window = v.window if span is not None else (float(record.time[0]),
                                                          float(record.time[-1]))
        if pair.lane in bending and bending[pair.lane].is_trace(record, trace_window):
            notes.append(f"lane {pair.lane}: a {v.n_axles}-axle trace of the span's bending "
                         "(a vehicle in another lane), not a vehicle of its own")
            continue
        if is_echo(v, pair, setup, seen):
            notes.append(f"lane {pair.lane}: a {v.n_axles}-axle trace of a vehicle in a "
                         "lane the other way, left to that lane's detectors")
            continue
        if (v.lateral_unit == "m" and np.isfinite(v.lateral)
                and pair.lane in setup.centres(pair.direction)):
            # nearer another lane's centre than its own; without its own, it stays
            lane = setup.lane_of(v.lateral, pair.direction) or lane
        found.append(LaneVehicle(vehicle=v, lane=lane, direction=pair.direction,
                                 pair=pair.lane, window=v.window,
                                 cut=any(v is w for w in cut),
                                 joined=any(v is w for w in joined)))
    vehicles = _deduplicated(found, setup)
    vehicles = _presence(vehicles)
    vehicles = _unseen_neighbours(record, vehicles, gauges, notes, section)
    return EventDetection(vehicles=tuple(vehicles), by_lane=by_lane, message="; ".join(notes))


#: s: the shortest time gap, bumper to bumper, of a vehicle following another at speed
#: that :func:`split_long` takes for two vehicles (the detection's own limit between
#: vehicles, :data:`bwim.detect.options.DEFAULT_MAX_AXLE_SPACING`, is this gap at 80 km/h).
MIN_HEADWAY = 0.5
#: m: the least body beyond the axles between two vehicles following each other: a cab's
#: front overhang (about 1.4 m) and a rear overhang of at least 1 m.
MIN_OVERHANGS = 2.4


def _axles_of(values: np.ndarray, axles: slice) -> np.ndarray:
    """The rows of per-axle ``values`` (first axis) of ``axles``; empty stays empty."""
    return values[axles] if len(values) else values


def split_long(v: VehicleDetection, span: tuple[float, float] | None = None, *,
               max_length: float = MAX_WHEELBASE) -> list[VehicleDetection]:
    """``v`` as the vehicles it holds: one when its axles span at most ``max_length``
    (m), else cut, each part cut again.  A cut lies only where the axle spacing leaves
    room for two vehicles following each other at ``v``'s speed: at least
    :data:`MIN_OVERHANGS` + :data:`MIN_HEADWAY` × speed.  The cut is the longest such
    spacing that leaves two vehicles of two axles or more, lies between axle groups
    (spacings of :data:`bwim.classify.DEFAULT_GROUP_SPACING` or more) with a single axle
    leading the rear vehicle, and leaves both within the limit; failing that, without
    the limit; failing that, the longest such spacing.  Without one, ``v`` stays whole
    although longer than ``max_length``: a longer combination than the limit allows, or
    vehicles too close to tell apart (:func:`too_long` says so; :func:`detect_lanes`
    marks it :attr:`LaneVehicle.joined`, not weighed).

    Each part keeps the whole's flags and lateral position.  ``span`` (m, the lines'
    support in the pair's frame, as :func:`detect_axles` takes it): each part's window is
    its own time on the span, and the parts are flagged ``multiple_presence`` only when
    those windows overlap (vehicles one after the other are not on the span together).
    Without it the parts keep the whole's window and are both flagged.  A part's axles
    and lateral position were read beside the other's: :func:`detect_lanes` marks it
    :attr:`LaneVehicle.cut`, not weighed until its own part of the record confirms it."""
    max_length = require_positive("max_length", max_length)
    spacings = np.asarray(v.passage.axle_spacings, dtype=float)
    if spacings.size < 2 or float(spacings.sum()) <= max_length:
        return [v]
    offsets = np.concatenate([[0.0], np.cumsum(spacings)])
    n = spacings.size
    # room for the bodies and the time gap of two vehicles following each other
    room = MIN_OVERHANGS + MIN_HEADWAY * float(v.passage.speed)

    def cuts(within: bool) -> list[int]:
        # both sides vehicles of two axles or more, the cut between axle groups, the
        # rear side led by a single (steering) axle; ``within``: both sides not too long
        return [k for k in range(1, n - 1)
                if spacings[k] >= max(DEFAULT_GROUP_SPACING, room)
                and spacings[k + 1] >= DEFAULT_GROUP_SPACING
                and (not within or (offsets[k] <= max_length
                                    and offsets[-1] - offsets[k + 1] <= max_length))]

    apart = [k for k in range(n) if spacings[k] >= room]
    if not apart:
        return [v]
    cut = max(cuts(True) or cuts(False) or apart, key=lambda k: spacings[k])
    p = v.passage
    halves = [(axles, Passage(speed=p.speed, lane=p.lane,
                              axle_spacings=spacings[axles][:-1] if axles.stop is not None
                              else spacings[axles.start:],
                              delay=p.delay + offsets[axles.start] / p.speed,
                              track_width=p.track_width))
              for axles in (slice(0, cut + 1), slice(cut + 1, None))]
    windows = ([v.window] * 2 if span is None else
               [tuple(float(x) for x in w) for w in span_windows([q for _, q in halves], span)])
    together = span is None or windows_overlap(*windows)
    flags = (v.flags if not together or FLAG_MULTIPLE_PRESENCE in v.flags
             else (*v.flags, FLAG_MULTIPLE_PRESENCE))
    parts = [dataclasses.replace(
        v, passage=passage, flags=flags, window=window,
        axle_times=_axles_of(v.axle_times, axles),
        axle_amplitudes=_axles_of(v.axle_amplitudes, axles),
        detector_times=_axles_of(v.detector_times, axles))
        for (axles, passage), window in zip(halves, windows, strict=True)]
    return [w for part in parts for w in split_long(part, span, max_length=max_length)]


def too_long(v: VehicleDetection, max_length: float = MAX_WHEELBASE) -> bool:
    """Whether ``v``'s axles spread over more than ``max_length`` (m): what
    :func:`split_long` leaves whole when no spacing has room for two vehicles."""
    return float(np.sum(v.passage.axle_spacings)) > max_length


#: Relative speed difference within which two pairs' vehicles may be one vehicle.
_SAME_SPEED = 0.03
#: Below this detection confidence a trace fits the pair's learned response too poorly
#: to be a vehicle of its own (an echo's axles reach the pair's detectors in the wrong
#: order, and fit only in part).
_ECHO_CONFIDENCE = 0.9
#: m: a trace read with that confidence is the other way's vehicle's echo only if it reads
#: that vehicle's axles: as many, each spacing within this of that vehicle's (in either
#: order); otherwise it is a vehicle of its own whose lateral position the other pulled
#: across (about 2.5 times the detection's 95th-percentile spacing error on the realistic
#: site, 0.15-0.16 m).  No confident echo with another axle count was met: on the four
#: ``bench_realsite`` days every echo whose axle count differed from its vehicle's had a
#: confidence below :data:`_ECHO_CONFIDENCE`, and the three confident traces with
#: another count at a vehicle's speed were real lane-3 trucks (read with 4 of their 5
#: axles) beside a lane-1 vehicle (stop 36).
ECHO_SPACING = 0.4


def is_echo(v: VehicleDetection, pair: DetectorLane, setup: SiteSetup,
          seen: Sequence[tuple[DetectorLane, VehicleDetection]]) -> bool:
    """Whether a vehicle a pair reports is a trace of a vehicle the other way: a single
    axle found by a pair other than the calibration lane's, or a vehicle whose lateral
    position (m) lies clearly in a lane of the other direction (beyond three quarters of
    the way from the pair's y to that lane's centre) while a pair of that direction saw
    a vehicle there at the same time, and the trace either has that vehicle's speed
    (within :data:`_SAME_SPEED`) and reads its axles (:func:`reads_axles_of`) or fits
    the pair's response poorly (confidence below :data:`_ECHO_CONFIDENCE`).  Otherwise
    the trace is a vehicle of its own whose lateral position another vehicle on the span
    pulled aside (a confident trace with fewer axles than the other vehicle, at its
    speed, is such a vehicle: a 2-axle lorry the other way beside the calibration
    truck)."""
    if v.n_axles < 2 and pair.lane != setup.calibration_lane:
        return True
    if pair.y is None or v.lateral_unit != "m" or not np.isfinite(v.lateral):
        return False
    nearest = setup.lane_of(v.lateral)
    if nearest is None or setup.direction_of(nearest) == pair.direction:
        return False
    centre = setup.centres()[nearest][0]
    if abs(v.lateral - pair.y) <= 0.75 * abs(centre - pair.y):
        return False
    return any(other.direction != pair.direction and windows_overlap(v.window, w.window)
               and (v.confidence < _ECHO_CONFIDENCE
                    or (abs(abs(w.passage.speed) - abs(v.passage.speed))
                        <= _SAME_SPEED * abs(v.passage.speed)
                        and reads_axles_of(v, w)))
               for other, w in seen)


def reads_axles_of(v: VehicleDetection, w: VehicleDetection) -> bool:
    """Whether ``v`` reads ``w``'s axles: as many, each spacing within
    :data:`ECHO_SPACING` of ``w``'s in one order or the other (an echo may read the axles
    the other way round)."""
    a, b = v.passage.axle_spacings, w.passage.axle_spacings
    if a.size != b.size:
        return False
    return a.size == 0 or bool(np.abs(a - b).max() <= ECHO_SPACING
                               or np.abs(a - b[::-1]).max() <= ECHO_SPACING)


def _deduplicated(found: list[LaneVehicle], setup: SiteSetup) -> list[LaneVehicle]:
    """One vehicle seen by two pairs of its direction kept once, from its own lane's."""
    pairs = {p.lane: p for p in setup.lanes}
    keep = [True] * len(found)
    for i, a in enumerate(found):
        for j in range(i + 1, len(found)):
            b = found[j]
            if not (keep[i] and keep[j]) or a.pair == b.pair or a.direction != b.direction:
                continue
            if not windows_overlap(a.window, b.window):
                continue
            drop = j if _own_pair_score(a, pairs) >= _own_pair_score(b, pairs) else i
            keep[drop] = False
    return [v for v, k in zip(found, keep, strict=True) if k]


def _own_pair_score(v: LaneVehicle, pairs: Mapping[int, DetectorLane]) -> float:
    """Higher for the pair a vehicle belongs to: lateral position near the pair's ``y``,
    else the detection's confidence."""
    y = pairs[v.pair].y
    if y is not None and v.vehicle.lateral_unit == "m" and np.isfinite(v.vehicle.lateral):
        return -abs(v.vehicle.lateral - y)
    return v.vehicle.confidence - 10.0


#: Unexplained activity this close to a window (in window lengths) continues into it.
_ABUTS = 0.25


def _unseen_neighbours(record: Record, vehicles: list[LaneVehicle], gauges: Sequence[str],
                       notes: list[str], section: SectionReadings | None
                       ) -> list[LaneVehicle]:
    """Vehicles next to gauge activity no detected vehicle explains, flagged
    ``multiple_presence`` (see the module docstring); ``section``: the gauges already
    read."""
    windows = [v.window for v in vehicles if v.window is not None]
    if not gauges or not windows:
        return vehicles
    if section is None:
        extra = unexplained_activity(record.time, channel_data(record, gauges).sum(axis=1),
                                     np.asarray(windows, dtype=float))
    else:
        extra = unexplained_activity(record.time, section.total,
                                     np.asarray(windows, dtype=float), noise=section.noise,
                                     step=section.step)
    if not extra.size:
        return vehicles
    out = []
    for v in vehicles:
        if v.window is None:
            out.append(v)
            continue
        a, b = v.window
        reach = _ABUTS * (b - a)
        if any(s - b < reach and a - e < reach for s, e in extra):
            veh = v.vehicle
            if FLAG_MULTIPLE_PRESENCE not in veh.flags:
                veh = dataclasses.replace(veh, flags=(*veh.flags, FLAG_MULTIPLE_PRESENCE))
            notes.append(f"lane {v.lane}: gauge activity no detector saw continues into the "
                         f"vehicle's time on the span ({a:.3f}–{b:.3f} s): another vehicle")
            v = dataclasses.replace(v, vehicle=veh)
        out.append(v)
    return out


def _presence(vehicles: list[LaneVehicle]) -> list[LaneVehicle]:
    out = []
    for i, v in enumerate(vehicles):
        others = tuple(w.lane if w.lane is not None else w.pair
                       for j, w in enumerate(vehicles) if j != i and windows_overlap(v.window,
                                                                              w.window))
        veh = v.vehicle
        if others and FLAG_MULTIPLE_PRESENCE not in veh.flags:
            veh = dataclasses.replace(veh, flags=(*veh.flags, FLAG_MULTIPLE_PRESENCE))
        same = veh is v.vehicle and others == v.others  # nothing to change: v itself
        out.append(v if same else dataclasses.replace(v, vehicle=veh, others=others))
    return sorted(out, key=lambda w: (w.window or (np.inf,))[0])
