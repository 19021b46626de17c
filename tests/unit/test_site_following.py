"""Vehicles following each other that the axle detectors saw as one (issue 21: two trucks
came out as one 10-axle vehicle of 627 kN): axles spread over more than the longest
vehicle allowed on European roads are cut into vehicles where a spacing leaves room for
two vehicles following each other at their speed, else left whole (and refused by
bwim.site.event).  Reference: the axle layouts the test builds (closed form: positions,
times, and the room ``MIN_OVERHANGS + MIN_HEADWAY × speed``)."""

import numpy as np
import pytest

from bwim.detect import VehicleDetection
from bwim.errors import InputError
from bwim.records import Passage
from bwim.site.lanes import MAX_WHEELBASE, MIN_HEADWAY, MIN_OVERHANGS, split_long, too_long

ARTIC = [3.6, 6.0, 1.31, 1.31]  # a 5-axle articulated truck, 12.22 m
RIGID = [5.4]                   # a 2-axle rigid truck
#: m/s: queueing traffic, where 5.5-8 m between two trucks' axles leaves room for their
#: bodies and a 0.5 s gap (2.4 + 0.5 × 5 = 4.9 m)
SLOW = 5.0


def _vehicle(spacings, speed=SLOW, delay=1.0):
    s = np.asarray(spacings, dtype=float)
    offsets = np.concatenate([[0.0], np.cumsum(s)])
    times = delay + offsets / speed
    return VehicleDetection(
        passage=Passage(speed=speed, lane=5.9, axle_spacings=s, delay=delay),
        confidence=0.9, axle_times=times, axle_amplitudes=np.linspace(0.5, 1.0, s.size + 1),
        lateral=5.9, window=(0.5, 3.0), detector_times=np.column_stack([times, times + 0.1]))


@pytest.mark.parametrize(("front", "gap", "rear"), [
    (ARTIC, 8.0, ARTIC),   # the 10 axles
    (ARTIC, 5.5, RIGID),   # 7 axles: 12.22 + 5.5 + 5.4 = 23.1 m
    (RIGID, 7.0, ARTIC),
])
def test_following_trucks_are_cut_where_they_part(front, gap, rear):
    whole = _vehicle([*front, gap, *rear])
    parts = split_long(whole)
    assert [p.n_axles for p in parts] == [len(front) + 1, len(rear) + 1]
    assert np.allclose(parts[0].passage.axle_spacings, front)
    assert np.allclose(parts[1].passage.axle_spacings, rear)
    # the rear truck's first axle passes x = 0 when the whole's axle len(front) + 1 did
    k = len(front) + 1
    assert parts[1].passage.delay == pytest.approx(whole.axle_times[k])
    assert np.allclose(parts[1].axle_times, whole.axle_times[k:])
    assert np.allclose(parts[1].detector_times, whole.detector_times[k:])
    for p in parts:
        assert "multiple_presence" in p.flags and p.window == whole.window
        assert p.passage.speed == whole.passage.speed


def test_a_long_vehicle_within_the_limit_stays_one():
    """A road train of 18.5 m between its first and last axles is one vehicle."""
    v = _vehicle([3.2, 1.35, 6.4, 1.31, 6.24])
    assert float(np.sum(v.passage.axle_spacings)) < MAX_WHEELBASE
    assert split_long(v) == [v]


def test_three_following_vehicles_give_three():
    parts = split_long(_vehicle([*ARTIC, 7.0, *ARTIC, 6.0, *RIGID]))
    assert [p.n_axles for p in parts] == [5, 5, 2]


@pytest.mark.parametrize(("front", "gap", "rear"), [
    (ARTIC, 8.0, ARTIC), (ARTIC, 5.5, RIGID), (RIGID, 7.0, ARTIC)])
def test_at_speed_no_spacing_leaves_room_for_two_vehicles(front, gap, rear):
    """The same layouts at 22 m/s: two vehicles need 2.4 + 0.5 × 22 = 13.4 m between
    their axles, more than any spacing here: a longer combination or vehicles too close
    to tell apart, left whole (not weighed: bwim.site.event)."""
    whole = _vehicle([*front, gap, *rear], speed=22.0)
    assert split_long(whole) == [whole] and too_long(whole)


@pytest.mark.parametrize("speed", [10.0, 15.0, 22.0, 30.0])
def test_the_room_for_two_vehicles_is_the_overhangs_and_the_headway(speed):
    """Closed form: a spacing just above ``MIN_OVERHANGS + MIN_HEADWAY × speed`` cuts,
    just below it does not (at speeds where the artic's own 6 m spacing leaves no room:
    below 7.2 m/s it would, and the cut could fall inside a vehicle)."""
    room = MIN_OVERHANGS + MIN_HEADWAY * speed
    assert [p.n_axles for p in split_long(_vehicle([*ARTIC, room + 0.01, *ARTIC],
                                                   speed=speed))] == [5, 5]
    below = _vehicle([*ARTIC, room - 0.01, *ARTIC], speed=speed)
    assert split_long(below) == [below]


def test_a_european_modular_system_combination():
    """A truck, dolly and semi-trailer of 22.5 m between first and last axle (4.5, 1.35,
    5.0, 1.3, 7.7, 1.31, 1.31 m): longer than the standard limit and, at 22 m/s, with no
    room for two vehicles: left whole and too long; where such combinations run
    (``max_length`` 25.25 m) one vehicle, not too long."""
    ems = _vehicle([4.5, 1.35, 5.0, 1.3, 7.7, 1.31, 1.31], speed=22.0)
    assert split_long(ems) == [ems] and too_long(ems)
    assert split_long(ems, max_length=25.25) == [ems] and not too_long(ems, 25.25)
    with pytest.raises(InputError, match="max_length"):
        split_long(ems, max_length=0.0)


@pytest.mark.parametrize(("front", "gap", "rear"), [
    (ARTIC, 8.0, ARTIC),   # 8 m between them: never on the 6 m span together
    (ARTIC, 5.5, RIGID),   # 5.5 m: both on it while the gap crosses it
    (RIGID, 7.0, ARTIC),
])
def test_given_the_span_each_part_has_its_own_window(front, gap, rear):
    """Closed form: a vehicle whose first axle passes x = 0 at ``delay`` with its last
    axle ``length`` behind is on the span (−3, 3) m from ``delay − 3/v`` to
    ``delay + (3 + length)/v``; the parts are multiple presence only when those overlap
    (the gap between them shorter than the span)."""
    speed, delay, span = SLOW, 1.0, (-3.0, 3.0)
    whole = _vehicle([*front, gap, *rear], speed=speed, delay=delay)
    parts = split_long(whole, span)
    rear_delay = delay + (sum(front) + gap) / speed
    expected = [(delay - 3.0 / speed, delay + (3.0 + sum(front)) / speed),
                (rear_delay - 3.0 / speed, rear_delay + (3.0 + sum(rear)) / speed)]
    for p, w in zip(parts, expected, strict=True):
        assert p.window == pytest.approx(w, abs=1e-12)
        assert ("multiple_presence" in p.flags) == (gap < span[1] - span[0])


def test_a_cut_part_is_replaced_only_by_its_own_detection():
    """The parts of a long vehicle one after the other, marked ``cut`` as
    bwim.site.lanes.detect_lanes marks them, go to bwim.site.isolate.detected_alone: a
    part found again once on its own part of the record is replaced by that detection
    (no longer ``cut``); a part not found stays ``cut`` (bwim.site.event refuses it:
    tests/validation/test_realistic_lanes.py).  The detection is a stand-in."""
    import bwim
    from bwim.site.isolate import detected_alone
    from bwim.site.lanes import EventDetection, LaneVehicle

    parts = split_long(_vehicle([*ARTIC, 8.0, *ARTIC]), (-3.0, 3.0))
    lanes = tuple(LaneVehicle(vehicle=p, lane=1, direction="+x", pair=1, window=p.window,
                              cut=True) for p in parts)
    t = np.arange(0.0, 10.0, 1.0 / 512.0)
    rec = bwim.Record(time=t, data=np.zeros((t.size, 1)),
                      sensors=(bwim.Sensor(x=0.0, y=4.0, name="g1"),))
    first = parts[0].window

    def detect(part):  # finds the first part's vehicle (5 axles), nothing else
        if part.time[0] <= first[0] and part.time[-1] >= first[1]:
            v = VehicleDetection(passage=_vehicle(ARTIC).passage, confidence=0.9,
                                 window=first)
            return EventDetection(vehicles=(LaneVehicle(vehicle=v, lane=1, direction="+x",
                                                        pair=1, window=first),), by_lane={})
        return EventDetection(vehicles=(), by_lane={})

    out = detected_alone(rec, EventDetection(vehicles=lanes, by_lane={}), detect)
    assert not out.vehicles[0].cut and out.vehicles[0].vehicle.n_axles == 5
    assert out.vehicles[1] is lanes[1] and out.vehicles[1].cut
