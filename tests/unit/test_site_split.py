"""A vehicle split across two records (bwim.site.split; a review finding of issue 21: a
pre-cut logger file that ends between a truck and its trailer weighed the truck alone).

References: closed forms of the axle layouts the tests build (a row's last axle passes
the detectors ``sum(spacings) / speed`` after its first; two vehicles following each
other need ``MIN_OVERHANGS + MIN_HEADWAY × speed`` between their axles, the rule
bwim.site.lanes.split_long cuts a record's own vehicles by), and, end to end, the
simulated small site's lane-1 truck (tests/conftest.py: FE plate with vehicle dynamics,
gauge noise, offsets and drift) written twice with clocks set from its true first-axle
time, speed and spacings (reference.csv), a chosen gap apart.
"""

from __future__ import annotations

import csv
import shutil
from datetime import datetime, timedelta
from datetime import time as dtime

import pytest

from bwim.cli import main
from bwim.io.summary import read_summary
from bwim.site import finish_day
from bwim.site.lanes import MIN_HEADWAY, MIN_OVERHANGS
from bwim.site.split import FLAG_SPLIT, refuse_split_vehicles
from bwim.summary import SummaryRow

T0 = datetime(2026, 4, 17, 15, 41, 34, 611000)
TRUCK = (3.6, 1.3, 6.0, 1.31)   # a 5-axle articulated truck, 12.21 m of axles
TRAILER = (4.5,)                # a drawbar trailer's two axles


def _row(record, t, spacings=TRUCK, speed=22.0, *, vehicle=1, lane=1, direction="+x",
         weighed=True):
    n = len(spacings) + 1
    w = dict(status="weighed", axle_weights=(50e3,) * n, gvw=50e3 * n) if weighed else \
        dict(status="refused", reason="counted, not weighed")
    return SummaryRow(record=record, vehicle=vehicle, time=t, lane=lane,
                      direction=direction, n_axles=n, speed=speed,
                      axle_spacings=tuple(spacings), **w)


def _after(front: SummaryRow, gap: float, speed: float) -> datetime:
    """The clock at which a vehicle at ``speed`` whose first axle is ``gap`` m behind
    ``front``'s last axle passes the detectors (both at one speed)."""
    return front.time + timedelta(seconds=(sum(front.axle_spacings) + gap) / speed)


@pytest.mark.parametrize("speed", [8.0, 15.0, 22.0, 30.0])
def test_a_gap_shorter_than_two_vehicles_need_is_one_vehicle(speed):
    """Closed form: 5 cm inside ``2.4 m + 0.5 s × speed`` is one vehicle (both parts
    refused), 5 cm beyond it two (both kept)."""
    room = MIN_OVERHANGS + MIN_HEADWAY * speed
    front = _row("a.txt", T0, speed=speed)
    for gap, split in ((room - 0.05, True), (room + 0.05, False)):
        rear = _row("b.txt", _after(front, gap, speed), TRAILER, speed)
        check = refuse_split_vehicles([front, rear])
        assert check.judged == 1
        assert [FLAG_SPLIT in r.flags for r in check.rows] == [split, split], gap
        assert [r.weighed for r in check.rows] == [not split, not split]
        if split:
            assert check.pairs[0][:2] == (("a.txt", 1), ("b.txt", 1))
            assert check.pairs[0][2] == pytest.approx(gap, abs=1e-4)
            assert check.refused == (("a.txt", 1), ("b.txt", 1))


def test_the_refused_parts_name_each_other_and_lose_their_weights():
    front = _row("a.txt", T0)
    rear = _row("b.txt", _after(front, 4.0, 22.0), TRAILER)
    a, b = refuse_split_vehicles([front, rear]).rows
    assert a.status == b.status == "refused" and a.quality == b.quality == "reject"
    assert a.gvw is None and a.axle_weights == () and b.gvw is None
    assert "b.txt vehicle 1, 4.0 m from it" in a.reason
    assert "a.txt vehicle 1, 4.0 m from it" in b.reason
    assert a.reason.startswith("one vehicle across two records")


def test_overlapping_records_holding_the_same_axles_are_one_vehicle():
    """A second file that starts before the first ended and holds the same truck: the
    rear row's first axle passes before the front row's last (negative gap)."""
    front = _row("a.txt", T0)
    again = _row("b.txt", T0 + timedelta(seconds=0.002))
    check = refuse_split_vehicles([front, again])
    assert check.pairs[0][2] < 0 and check.refused == (("a.txt", 1), ("b.txt", 1))


def test_a_records_own_vehicles_other_lanes_and_directions_are_not_paired():
    """Vehicles of one record were told apart by its detection; a vehicle of another
    lane or direction is no part of this one; the check leaves all of these alone."""
    front = _row("a.txt", T0)
    close = _after(front, 1.0, 22.0)
    for rear in (_row("a.txt", close, TRAILER, vehicle=2),
                 _row("b.txt", close, TRAILER, lane=2),
                 _row("b.txt", close, TRAILER, direction="-x")):
        check = refuse_split_vehicles([front, rear])
        assert check.rows == (front, rear) and not check.pairs


def test_only_consecutive_vehicles_are_judged():
    """Three vehicles of one lane in three records, the middle one well apart from both:
    no pair; the first and third are not compared past it."""
    a = _row("a.txt", T0)
    b = _row("b.txt", _after(a, 40.0, 22.0))
    c = _row("c.txt", _after(b, 40.0, 22.0))
    check = refuse_split_vehicles([c, a, b])  # input order is not time order
    assert check.judged == 2 and not check.pairs and check.rows == (c, a, b)


def test_a_counted_part_is_flagged_and_keeps_its_status():
    front = _row("a.txt", T0, weighed=False)
    rear = _row("b.txt", _after(front, 3.0, 22.0), TRAILER)
    a, b = refuse_split_vehicles([front, rear]).rows
    assert a.status == "refused" and a.reason == "counted, not weighed"
    assert FLAG_SPLIT in a.flags and FLAG_SPLIT in b.flags and not b.weighed


def test_rows_without_a_clock_or_of_another_clock_kind_are_not_judged():
    """No clock: nothing to place the rows by. A clock time of day and a datetime are two
    clocks (rows of the two kinds are judged apart)."""
    front = _row("a.txt", None)
    rear = _row("b.txt", None, TRAILER)
    assert refuse_split_vehicles([front, rear]).judged == 0
    tod = dtime(15, 41, 34, 611000)
    front = _row("a.txt", tod)
    rear = _row("b.txt", _after(_row("x", T0), 3.0, 22.0), TRAILER)
    assert refuse_split_vehicles([front, rear]).judged == 0
    close = (T0 + timedelta(seconds=(sum(TRUCK) + 3.0) / 22.0)).time()
    check = refuse_split_vehicles([front, _row("b.txt", close, TRAILER)])
    assert check.judged == 1 and len(check.pairs) == 1


def test_failed_rows_pass_through():
    failed = SummaryRow(record="b.txt", status="failed", reason="unreadable")
    front = _row("a.txt", T0)
    assert refuse_split_vehicles([front, failed]).rows == (front, failed)


# -- end to end: bwim weigh on logger files whose clocks are in their names ------------


def _name(clock: datetime) -> str:
    return f"PL1_{clock:%Y-%m-%d-%H-%M-%S}-{clock.microsecond // 1000:03d}.txt"


@pytest.mark.parametrize("gap", [5.0, 25.0])
def test_bwim_weigh_refuses_a_truck_whose_axles_go_on_in_the_next_file(
        small_site, tmp_path, gap):
    """The lane-1 truck's file, and the same file again with a clock ``gap`` m of travel
    after its last axle (from the truth: first-axle time, speed, spacings): 5 m, a
    drawbar trailer's distance, is one vehicle across two files (room at its 25 m/s:
    about 15 m), and neither part is weighed; 25 m is a truck following another, both
    weighed. Only the two files are weighed, so the day-level lateral checks do not run
    (fewer than 30 vehicles) and nothing else refuses them."""
    with open(small_site.reference, newline="") as f:
        ref = next(r for r in csv.DictReader(f) if r["lane"] == "1")
    speed = float(ref["speed_m_s"])
    length = sum(float(s) for s in ref["axle_spacings_m"].split(";"))
    src = small_site.out_dir / "traffic" / ref["record"]
    clock = datetime.strptime(ref["record"][4:-4], "%Y-%m-%d-%H-%M-%S-%f")
    later = clock + timedelta(seconds=round((length + gap) / speed, 3))
    folder = tmp_path / "traffic"
    folder.mkdir()
    shutil.copy(src, folder / src.name)
    shutil.copy(src, folder / _name(later))
    out = tmp_path / "out"
    assert main(["weigh", str(small_site.scenario), str(folder), "--calibration-records",
                 str(small_site.calibration[0].parent), "-o", str(out)]) == 0
    rows = [r for r in read_summary(out / "summary.csv") if r.lane == 1]
    assert len(rows) == 2
    split = gap < MIN_OVERHANGS + MIN_HEADWAY * speed
    assert [FLAG_SPLIT in r.flags for r in rows] == [split, split]
    assert [r.weighed for r in rows] == [not split, not split]


def test_finish_day_runs_the_check(small_site_calibrated):
    """finish_day refuses the parts (DayResult.split) among the day's other rows."""
    site = small_site_calibrated[3]
    front = _row("a.txt", T0)
    rear = _row("b.txt", _after(front, 4.0, 22.0), TRAILER)
    alone = _row("c.txt", T0 + timedelta(minutes=5))
    day = finish_day([front, alone, rear], site)
    assert day.split.refused == (("a.txt", 1), ("b.txt", 1))
    assert [r.weighed for r in day.rows] == [False, True, False]
    assert "SplitCheck(" in repr(day)


def test_parts_measured_at_two_speeds_are_judged_at_their_mean():
    """Front part at 20 m/s, rear at 24 (the contract: v = the mean, 22 m/s; room 13.4 m).
    The gap is the time between the front's last axle and the rear's first times v:
    0.605 s gives 13.31 m (one vehicle), 0.615 s 13.53 m (two); judged at the front's
    speed alone both would be one vehicle (12.1 m, 12.3 m against 12.4 m)."""
    front = _row("a.txt", T0, speed=20.0)
    last = T0 + timedelta(seconds=sum(TRUCK) / 20.0)
    for dt, split in ((0.605, True), (0.615, False)):
        rear = _row("b.txt", last + timedelta(seconds=dt), TRAILER, speed=24.0)
        assert bool(refuse_split_vehicles([front, rear]).pairs) == split, dt


@pytest.fixture
def summer_time_zone(monkeypatch):
    """The process in a time zone whose clocks change (Europe/Ljubljana: 2024-03-31 02:00
    → 03:00); the zone restored after."""
    import time

    monkeypatch.setenv("TZ", "Europe/Ljubljana")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def test_the_clocks_are_the_sites_whatever_the_machines_zone(summer_time_zone):
    """Clocks are naive site time: a truck at 02:59:59.5 and its trailer in the next
    file at 03:00:00.2 are 0.7 s apart whatever zone bwim runs in (read as the machine's
    local time, naive clocks were an hour apart on the night the clocks change)."""
    front = _row("a.txt", datetime(2024, 3, 31, 2, 59, 59, 500000), TRUCK, 20.0)
    rear = _row("b.txt", datetime(2024, 3, 31, 3, 0, 0, 200000), TRAILER, 20.0)
    # gap: (0.7 s - 12.21 m / 20 m/s) × 20 m/s = 1.79 m
    check = refuse_split_vehicles([front, rear])
    assert len(check.pairs) == 1 and check.pairs[0][2] == pytest.approx(1.79, abs=1e-6)
