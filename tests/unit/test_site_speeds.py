"""A counted vehicle at a speed its lane's traffic around it does not drive is left out
(bwim.site.speeds).

References: the median and the normal-scaled median absolute deviation are scipy's
(``scipy.stats.median_abs_deviation(scale="normal")``) over the neighbours chosen here
by hand (the ``NEIGHBOURS`` rows nearest in time).  The rows are built here (the rule is
algebra); its effect on the realistic site is measured by benchmarks/bench_realsite.py.
"""

from __future__ import annotations

from datetime import datetime, time, timedelta

import numpy as np
import pytest
from scipy import stats

from bwim.errors import InputError
from bwim.site import drop_speed_outliers, finish_day
from bwim.site.speeds import NEIGHBOURS, NO_VEHICLE, SPEED_Z
from bwim.summary import SummaryRow

T0 = datetime(2026, 7, 20, 6, 0)


def _row(k: int, speed: float, *, minutes: float | None = None, lane: int = 3,
         direction: str = "-x", weighed: bool = False, when=None) -> SummaryRow:
    t = when if when is not None else T0 + timedelta(minutes=k if minutes is None else minutes)
    common = {"record": f"e{k:04d}.txt", "lane": lane, "direction": direction, "n_axles": 2,
              "speed": speed, "time": t}
    if weighed:
        return SummaryRow(axle_weights=(60e3, 90e3), group_weights=(60e3, 90e3),
                          gvw=150e3, quality="ok", method="moses", **common)
    return SummaryRow(status="refused", reason="counted, not weighed", **common)


@pytest.fixture
def lane3(rng):
    """120 counted vehicles a minute apart at 22 m/s ± 1 (normal quantiles, none beyond
    2.7 σ), shuffled in time."""
    v = 22.0 + stats.norm.ppf((np.arange(120) + 0.5) / 120)
    return [_row(k, s) for k, s in enumerate(rng.permutation(v))]


def test_a_trace_is_left_out_and_the_traffic_kept(lane3):
    trace = _row(500, 7.0, minutes=60.5)  # the span's bending read as a walking-pace vehicle
    fast = _row(501, 36.0, minutes=80.5)  # another truck's axles paired a group apart
    rows = [*lane3, trace, fast]
    check = drop_speed_outliers(rows)
    assert check.dropped == (trace, fast)
    assert check.rows[:-2] == tuple(lane3)
    assert all(a is b for a, b in zip(check.rows, lane3, strict=False))


def test_a_record_whose_every_vehicle_was_a_trace_keeps_a_row_saying_so(lane3):
    """The trace's record held nothing else: it keeps one refused row, with no weights,
    no lane, the trace's flags and the reason, where the trace was (review of stop 37:
    `bwim weigh` of the 800 records of seed 31's bench day wrote 793 rows, the 7 records
    whose only vehicle read was a trace missing from summary.csv).  A record with
    another row keeps that row alone."""
    trace = SummaryRow(**{**_row(500, 7.0, minutes=60.5).__dict__,
                          "flags": ("truncated", "multiple_presence")})
    fast = _row(501, 36.0, minutes=80.5)
    other = SummaryRow(**{**_row(502, 22.0, minutes=80.5).__dict__, "record": fast.record,
                          "vehicle": 2})
    check = drop_speed_outliers([*lane3[:60], trace, *lane3[60:], fast, other])
    assert check.dropped == (trace, fast)
    assert [r.record for r in check.rows] == [r.record for r in
                                              (*lane3[:60], trace, *lane3[60:], other)]
    kept = check.rows[60]
    assert (kept.status, kept.reason, kept.gvw, kept.lane, kept.speed, kept.time) == (
        "refused", NO_VEHICLE, None, None, None, trace.time)
    assert kept.flags == ("truncated", "multiple_presence")
    assert check.rows[-1] is other


def test_a_weighed_truck_whose_only_other_vehicle_was_a_trace_is_alone(lane3):
    """The trace's record also holds a lane-1 truck, weighed and flagged
    ``multiple_presence`` because of it (review of stop 35: 14 of the 15 weighed rows so
    flagged on the four bench days had no second vehicle on the span): with the trace
    left out it has no other vehicle, so it loses the flag, and its quality follows its
    remaining flags.  A truck beside a trace and a counted vehicle of its own record
    keeps it, and so does a row weighed by MFI its quality."""
    trace = _row(500, 7.0, minutes=60.5)
    truck = SummaryRow(record=trace.record, vehicle=2, lane=1, direction="+x", n_axles=5,
                       speed=22.0, time=trace.time, axle_weights=(50e3,) * 5,
                       group_weights=(50e3, 50e3, 150e3), gvw=250e3, quality="warning",
                       method="moses", flags=("multiple_presence",))
    tired = SummaryRow(record=trace.record, vehicle=3, lane=1, direction="+x", n_axles=5,
                       speed=22.0, time=trace.time, axle_weights=(50e3,) * 5,
                       group_weights=(50e3, 50e3, 150e3), gvw=250e3, quality="warning",
                       method="moses", flags=("multiple_presence", "lateral_extrapolated"))
    check = drop_speed_outliers([*lane3, trace, truck])
    assert check.dropped == (trace,)
    alone = check.rows[-1]
    assert alone.flags == () and alone.quality == "ok" and alone.gvw == truck.gvw
    soft = drop_speed_outliers([*lane3, trace, tired]).rows[-1]
    assert soft.flags == ("lateral_extrapolated",) and soft.quality == "warning"
    beside = _row(502, 22.0, minutes=60.5)  # a counted vehicle of the same record
    beside = SummaryRow(**{**beside.__dict__, "record": trace.record, "vehicle": 3})
    kept = drop_speed_outliers([*lane3, trace, truck, beside]).rows
    assert kept[-2].flags == ("multiple_presence",)
    mfi = SummaryRow(**{**truck.__dict__, "method": "mfi"})
    assert drop_speed_outliers([*lane3, trace, mfi]).rows[-1].quality == "warning"


def test_the_statistic_is_the_neighbours_median_and_normal_scaled_mad(lane3):
    # a row just inside and one just outside the limit, judged on the 30 rows nearest
    # in time (computed here by hand)
    at = 60.5
    near = sorted(lane3, key=lambda r: abs((r.time - T0).total_seconds() / 60 - at))
    v = np.array([r.speed for r in near[:NEIGHBOURS]])
    m, s = np.median(v), stats.median_abs_deviation(v, scale="normal")
    inside = _row(600, m - (SPEED_Z - 0.1) * s, minutes=at)
    outside = _row(601, m - (SPEED_Z + 0.1) * s, minutes=at)
    assert drop_speed_outliers([*lane3, inside]).dropped == ()
    assert drop_speed_outliers([*lane3, outside]).dropped == (outside,)


def test_a_queue_slows_every_vehicle_and_none_is_left_out(lane3):
    # 40 vehicles at 6 m/s ± 0.3 for 40 minutes in the middle of the day: their
    # neighbours in time are slow too
    queue = [_row(700 + k, 6.0 + 0.3 * np.sin(k), minutes=200.25 + k) for k in range(40)]
    after = [_row(800 + k, 22.0 + np.cos(k), minutes=240.5 + k) for k in range(40)]
    rows = [*lane3, *queue, *after]
    assert drop_speed_outliers(rows).dropped == ()


def test_weighed_rows_thin_lanes_and_other_lanes_are_not_judged(lane3):
    weighed = _row(900, 7.0, minutes=30.5, weighed=True)
    other_dir = [_row(1000 + k, 22.0 + 0.1 * k, lane=3, direction="+x") for k in range(10)]
    slow_other = _row(1100, 5.0, lane=3, direction="+x", minutes=5.5)
    rows = [*lane3, weighed, *other_dir, slow_other]
    check = drop_speed_outliers(rows)
    assert check.dropped == ()
    # with a lower minimum the thin group is judged
    assert drop_speed_outliers(rows, min_vehicles=10).dropped == (slow_other,)


def test_clock_times_of_day_are_judged_apart_from_dates(lane3):
    # 20 rows with clock times of day only: too few to judge, whatever the dated rows
    of_day = [_row(1200 + k, 22.0 + 0.1 * (k % 5), when=time(8, k)) for k in range(20)]
    slow = _row(1300, 7.0, when=time(8, 10, 30))
    rows = [*lane3, *of_day, slow]
    assert drop_speed_outliers(rows).dropped == ()
    assert drop_speed_outliers(rows, min_vehicles=15).dropped == (slow,)


def test_failed_rows_and_rows_without_time_stay(lane3):
    no_time = SummaryRow(record="x.txt", lane=3, direction="-x", speed=7.0, status="refused",
                         reason="counted")
    failed = SummaryRow(record="y.txt", status="failed", reason="unreadable")
    rows = [*lane3, no_time, failed]
    assert drop_speed_outliers(rows).rows == tuple(rows)


@pytest.mark.parametrize("kwargs, match", [
    ({"limit": 0.0}, "limit"), ({"limit": float("inf")}, "limit"),
    ({"neighbours": 2}, "neighbours"), ({"min_vehicles": 2.5}, "min_vehicles"),
])
def test_bad_arguments(lane3, kwargs, match):
    with pytest.raises(InputError, match=match):
        drop_speed_outliers(lane3, **kwargs)


def test_finish_day_leaves_the_trace_out(lane3, small_site_calibrated):
    trace = _row(500, 7.0, minutes=60.5)
    day = finish_day([*lane3, trace], small_site_calibrated[-1])
    assert day.speeds.dropped == (trace,)
    assert len(day.rows) == len(lane3) + 1 and trace not in day.rows
    assert day.rows[-1].record == trace.record and day.rows[-1].reason == NO_VEHICLE
    assert "SpeedCheck(" in repr(day)
