"""bwim.site.isolate: the part of a record a vehicle has to itself.

References: the cut times are closed forms of the windows (halfway through each quiet
gap); the readings of a strain whose influence has compact support (a triangle of ±3 m
about the gauges) are exactly zero before a vehicle's first axle reaches x = -3 m, so the
part cut around the first of two vehicles holds exactly the first one's readings."""

from __future__ import annotations

import dataclasses
import datetime as dt

import numpy as np
import pytest

import bwim
from bwim.detect import VehicleDetection
from bwim.records import Passage
from bwim.site.isolate import detected_alone, own_part
from bwim.site.lanes import EventDetection, LaneVehicle

FS = 512.0
HALF_SPAN = 3.0


def _record(passages: list[Passage], *, duration: float = 4.0,
            clock: dt.datetime | None = None) -> bwim.Record:
    """Two gauges at x = 0 reading the sum over axles of a 10 kN-per-axle triangle."""
    t = np.arange(0.0, duration, 1.0 / FS)
    total = np.zeros_like(t)
    for p in passages:
        x = p.speed * (t[:, None] - p.delay) - p.axle_offsets[None, :]
        total += np.clip(1.0 - np.abs(x) / HALF_SPAN, 0.0, None).sum(axis=1) * 10e3
    data = np.column_stack([total, 0.5 * total])
    sensors = (bwim.Sensor(x=0.0, y=4.0, name="g1"), bwim.Sensor(x=0.0, y=5.0, name="g2"))
    return bwim.Record(time=t, data=data, sensors=sensors, clock=clock)


def _window(p: Passage) -> tuple[float, float]:
    """Record times at which the first axle enters and the last leaves x in (-3, 3)."""
    return (p.delay - HALF_SPAN / p.speed,
            p.delay + (p.axle_offsets[-1] + HALF_SPAN) / p.speed)


def test_the_cuts_are_halfway_through_the_quiet_gaps():
    rec = _record([])
    part = own_part(rec, (1.0, 2.0), [(0.2, 0.6), (0.0, 0.4), (2.5, 3.1), (3.0, 3.5)])
    # the latest window before ends at 0.6 s, the earliest after starts at 2.5 s
    assert part.time[0] == pytest.approx(0.8, abs=1.0 / FS)
    assert part.time[-1] == pytest.approx(2.25, abs=1.0 / FS)
    assert part.time[0] >= 0.8 and part.time[-1] <= 2.25
    # the time values are kept (not restarted at 0)
    k = int(np.searchsorted(rec.time, part.time[0]))
    np.testing.assert_array_equal(part.time, rec.time[k:k + part.time.size])
    np.testing.assert_array_equal(part.data, rec.data[k:k + part.time.size])


def test_nothing_to_cut_gives_the_record_itself():
    rec = _record([])
    assert own_part(rec, None, [(0.0, 0.5)]) is rec
    assert own_part(rec, (1.0, 2.0), []) is rec
    assert own_part(rec, (1.0, 2.0), [None]) is rec
    # a window that overlaps (a vehicle on the span with it) does not cut
    assert own_part(rec, (1.0, 2.0), [(1.5, 2.6), (0.4, 1.2)]) is rec


def test_a_following_vehicle_is_cut_off_exactly():
    clock = dt.datetime(2015, 10, 1, 9, 45, 52, 576000)
    first = Passage(speed=20.0, axle_spacings=[3.5, 6.0, 1.3, 1.3], delay=0.4)
    gap = 12.0 + 2.5 + 1.4  # m between the first's last axle and the second's first
    second = Passage(speed=20.0, axle_spacings=[4.0],
                     delay=first.delay + (first.axle_offsets[-1] + gap) / 20.0)
    both = _record([first, second], clock=clock)
    alone = _record([first], clock=clock)
    part = own_part(both, _window(first), [_window(second)])
    assert part.time[-1] < both.time[-1] - 0.5  # the second's time on the span is gone
    assert part.clock == clock
    # the second's readings are exactly zero in the part: it holds the first's alone
    k = int(np.searchsorted(both.time, part.time[0]))
    np.testing.assert_array_equal(part.data, alone.data[k:k + part.time.size])
    # and the first's own readings are whole: they are zero where the part ends
    assert np.all(part.data[-10:] == 0.0)
    assert np.any(part.data > 0.0)
    # cut around the second, the first is cut off as well (the gap's other half)
    rest = own_part(both, _window(second), [_window(first)])
    assert rest.time[0] == pytest.approx(part.time[-1], abs=1.5 / FS)


def _lane_vehicle(n_axles: int, window: tuple[float, float], *, pair: int = 1,
                  direction: str = "+x", others: tuple[int, ...] = ()) -> LaneVehicle:
    """A stand-in detection; with ``others`` flagged multiple presence as
    bwim.site.lanes.detect_lanes flags a vehicle on the span with those lanes'."""
    p = Passage(speed=20.0, axle_spacings=[1.5] * (n_axles - 1))
    flags = ("multiple_presence",) if others else ()
    return LaneVehicle(vehicle=VehicleDetection(passage=p, confidence=0.9, window=window,
                                                flags=flags),
                       lane=pair, direction=direction, pair=pair, window=window,
                       others=others)


def test_vehicles_one_after_the_other_are_detected_again_each_on_its_part():
    """Algebra of the replacement (the detection is a stand-in that records the parts it
    is given; the effect on real detections: tests/validation/test_realistic_lanes.py)."""
    rec = _record([])
    first, second = _lane_vehicle(5, (0.5, 1.2), others=(3,)), _lane_vehicle(2, (2.0, 2.5))
    other_way = _lane_vehicle(4, (0.8, 1.5), pair=3, direction="-x", others=(1,))
    event = EventDetection(vehicles=(first, other_way, second), by_lane={})
    seen = []

    def detect(part):
        seen.append((float(part.time[0]), float(part.time[-1])))
        if part.time[-1] < 1.9:  # the first's part: found again with 6 axles (and the
            # vehicle the other way, in another pair)
            return EventDetection(vehicles=(_lane_vehicle(6, (0.51, 1.2)),
                                            _lane_vehicle(4, (0.8, 1.5), pair=3)),
                                  by_lane={})
        return EventDetection(vehicles=(), by_lane={})  # the second's: nothing found

    out = detected_alone(rec, event, detect)
    # the first's part ends halfway between its end (1.2) and the second's start (2.0),
    # the vehicle the other way on the span with it does not cut; the second's starts
    # halfway between the latest end before it (1.5, the other way's) and 2.0
    assert seen == [pytest.approx((0.0, 1.6), abs=1.0 / FS),
                    pytest.approx((1.75, rec.time[-1]), abs=1.0 / FS)]
    assert [v.vehicle.n_axles for v in out.vehicles] == [6, 4, 2]
    assert out.vehicles[1] is other_way and out.vehicles[2] is second
    assert "5-axle vehicle detected again" in out.message
    # vehicles that share the span, or are in other pairs, are not detected again
    alone = EventDetection(vehicles=(first, other_way), by_lane={})
    assert detected_alone(rec, alone, detect).vehicles == alone.vehicles
    assert len(seen) == 2


def _presence(v: LaneVehicle) -> tuple[bool, tuple[int, ...]]:
    return "multiple_presence" in v.vehicle.flags, v.others


def test_multiple_presence_stays_the_events_after_a_replacement():
    """The replacement's multiple presence is read from the event's vehicles, not from
    its part's detection (stand-in detections; the reference is the windows' overlaps):
    (a) a vehicle the other way on the span with it that its part cuts off (and so does
    not find) stays its ``others``; (b) a vehicle its part's detection saw that the event
    does not hold (a trace the event's detection left out) is not; (c) a flag the part
    gave without another vehicle (gauge activity no detector saw) stays."""
    rec = _record([])
    first = _lane_vehicle(5, (0.5, 1.2), others=(3,))
    other_way = _lane_vehicle(5, (1.0, 1.9), pair=3, direction="-x", others=(1,))
    second = _lane_vehicle(2, (2.0, 2.5))
    event = EventDetection(vehicles=(first, other_way, second), by_lane={})

    def cut_off(part):  # (a) the first's part ends at 1.6 s, mid other_way: not found
        if part.time[-1] < 1.9:
            return EventDetection(vehicles=(_lane_vehicle(5, (0.5, 1.2)),), by_lane={})
        return EventDetection(vehicles=(), by_lane={})

    out = detected_alone(rec, event, cut_off)
    assert [_presence(v) for v in out.vehicles] == [(True, (3,)), (True, (1,)),
                                                    (False, ())]
    assert out.vehicles[1] is other_way

    alone = _lane_vehicle(4, (0.3, 0.9))
    late = _lane_vehicle(5, (1.8, 2.6), others=(3,))
    late_other = _lane_vehicle(4, (1.4, 2.2), pair=3, direction="-x", others=(1,))
    event = EventDetection(vehicles=(alone, late_other, late), by_lane={})

    def with_trace(part):  # (b) the first's part holds a trace of its own in lane 3
        if part.time[-1] < 1.8:
            return EventDetection(vehicles=(
                _lane_vehicle(4, (0.3, 0.9), others=(3,)),
                _lane_vehicle(2, (0.6, 1.0), pair=3, direction="-x", others=(1,))),
                by_lane={})
        return EventDetection(vehicles=(), by_lane={})

    out = detected_alone(rec, event, with_trace)
    assert [_presence(v) for v in out.vehicles] == [(False, ()), (True, (1,)), (True, (3,))]

    def unseen(part):  # (c) gauge activity beside it in its part: flagged, no others
        if part.time[-1] < 1.8:
            v = _lane_vehicle(4, (0.3, 0.9))
            flagged = dataclasses.replace(v.vehicle, flags=("multiple_presence",))
            return EventDetection(vehicles=(dataclasses.replace(v, vehicle=flagged),),
                                  by_lane={})
        return EventDetection(vehicles=(), by_lane={})

    out = detected_alone(rec, event, unseen)
    assert _presence(out.vehicles[0]) == (True, ())


def test_samples_are_the_replaced_record():
    """Record.samples (own_part's cut) is the record dataclasses.replace makes of the
    samples, field by field, without checking them again; fewer than two samples are
    refused as replace refuses them."""
    import dataclasses
    from datetime import datetime

    import numpy as np
    import pytest

    from bwim.errors import InputError
    from bwim.records import Passage, Record
    from bwim.sensors import Sensor

    rng = np.random.default_rng(1)
    rec = Record(time=np.arange(200) / 100.0, data=rng.normal(size=(200, 3)),
                 sensors=tuple(Sensor(x=1.0, y=float(k), name=f"g{k}") for k in range(3)),
                 passages=(Passage(speed=10.0, axle_spacings=[3.0]),),
                 clock=datetime(2026, 7, 1, 8, 0, 0))
    keep = (rec.time >= 0.37) & (rec.time <= 1.2)
    got = rec.samples(keep)
    ref = dataclasses.replace(rec, time=rec.time[keep], data=rec.data[keep], passages=(),
                              truths=())
    assert type(got) is Record
    for f in dataclasses.fields(Record):
        a, b = getattr(got, f.name), getattr(ref, f.name)
        assert (np.array_equal(a, b) and a.dtype == b.dtype and a.strides == b.strides
                if isinstance(a, np.ndarray) else a == b), f.name
    one = rec.time <= 0.0
    with pytest.raises(InputError, match="at least two"):
        rec.samples(one)
