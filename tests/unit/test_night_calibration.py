"""Calibration runs at night, across midnight (a review of stop 33: the bridge closed for
the test truck from 23:20 to 01:00).  Over seconds since midnight the runs were the two
ends of the day: noon lay "inside" their span, with a factor interpolated across the
whole day between them.  Now the trend's axis starts in the middle of the longest gap
between the runs' times of day (bwim.site.drift.TimeOfDayDrift.fit).

Reference: closed form. Runs every 20 minutes from 23:20 to 01:00 with factors falling
0.01 per run (a deck cooling at night): linear interpolation between runs, the nearer
end's factor beyond them, flagged outside the calibration.
"""

from datetime import date, datetime

import pytest

from bwim.site.drift import TimeOfDayDrift
from bwim.wim import ScaleTrend

H = 3600.0
TIMES = [23 * H + 20 * 60 + k * 1200.0 for k in range(6)]  # 23:20 ... 01:00 (+1 day)
FACTORS = [1.00, 0.99, 0.98, 0.97, 0.96, 0.95]
DATES = (date(2015, 10, 1), date(2015, 10, 2))


@pytest.fixture
def night():
    # the times of day as a clock gives them: 00:00-01:00 after midnight
    return TimeOfDayDrift.fit([t % 86400.0 for t in TIMES], FACTORS, DATES)


def test_the_span_stays_whole_across_midnight(night):
    """The runs' span is 23:20-01:00 (on the axis: 84000-90000 s); the origin is the
    middle of the longest gap, 01:00-23:20: 12:10."""
    assert night.origin == pytest.approx(12 * H + 600.0)
    assert night.trend.span == pytest.approx((84000.0, 90000.0))


@pytest.mark.parametrize(("clock", "factor", "outside"), [
    (datetime(2015, 10, 1, 23, 50), 0.985, False),   # halfway between 23:40 and 00:00
    (datetime(2015, 10, 2, 0, 10), 0.975, False),
    (datetime(2015, 10, 2, 0, 50), 0.955, False),
    (datetime(2015, 10, 1, 12, 0), 0.95, True),      # before 12:10: the end nearer, 01:00
    (datetime(2015, 10, 2, 12, 20), 1.00, True),     # after 12:10: 23:20
    (datetime(2015, 10, 5, 23, 50), 0.985, True),    # another date
])
def test_factors_inside_and_beyond_the_night(night, clock, factor, outside):
    f, beyond = night.factor(clock)
    assert f == pytest.approx(factor, abs=1e-3) and beyond == outside


def test_runs_within_one_day_keep_seconds_since_midnight():
    """Runs from 08:00 to 16:00: the axis is the clock's own (origin 0), as before."""
    day = TimeOfDayDrift.fit([8 * H, 12 * H, 16 * H], [1.0, 0.9, 1.0], ())
    assert day.origin == 0.0 and day.trend.span == (8 * H, 16 * H)
    direct = ScaleTrend.fit([8 * H, 12 * H, 16 * H], [1.0, 0.9, 1.0])
    for t in (7 * H, 10 * H, 13.5 * H, 20 * H):
        assert day.factor(t) == (float(direct(t)), not direct.covers(t))


def test_the_last_runs_own_crossing_is_within_the_calibration():
    """The runs are timed by their records' starts, a vehicle by its crossing: with the
    runs' record lengths given (here 2 s each), a time up to 2 s after the last run's
    start is inside the calibration, later outside (review of stop 37: the last run's own
    truck, weighed as traffic 0.4 s after its record's start, was flagged
    ``outside_calibration_time``).  The factors are the trend's either way."""
    day = TimeOfDayDrift.fit([8 * H, 12 * H, 16 * H], [1.0, 0.9, 1.0], (), [2.0] * 3)
    assert day.factor(16 * H + 0.4) == (1.0, False)
    assert day.factor(16 * H + 2.0) == (1.0, False)
    assert day.factor(16 * H + 2.5) == (1.0, True)
    assert day.factor(8 * H - 0.1)[1]
    night = TimeOfDayDrift.fit([t % 86400.0 for t in TIMES], FACTORS, DATES, [3.0] * 6)
    assert night.factor(1 * H + 2.0) == (pytest.approx(0.95), False)  # 01:00 + 2 s
    assert night.factor(1 * H + 4.0)[1]


def test_clock_times_sort_from_where_their_day_starts():
    """bwim.records.day_origin / clock_key (the report's period and flow per hour):
    23:50, 00:10 run in that order; dated clocks come first, by instant."""
    from datetime import time

    from bwim.records import clock_key, day_origin

    assert day_origin([8 * H, 12 * H, 16 * H]) == 0.0
    # 00:10 and 23:50: the longest gap 00:10-23:50, its middle 12:00
    assert day_origin([23 * H + 3000.0, 600.0]) == pytest.approx(12 * H)
    times = [time(0, 10), datetime(2015, 10, 2, 1, 0), time(23, 50),
             datetime(2015, 10, 1, 23, 0)]
    assert sorted(times, key=clock_key(times)) == [
        datetime(2015, 10, 1, 23, 0), datetime(2015, 10, 2, 1, 0), time(23, 50), time(0, 10)]
