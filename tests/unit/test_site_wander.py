"""The lanes' lateral check (bwim.site.wander): a weighed vehicle whose lateral position is
an outlier of its lane's traffic is refused.

References: the median and the normal-scaled median absolute deviation are scipy's
(``scipy.stats.median_abs_deviation(scale="normal")``); the 3.5 limit on the modified
z-score is Iglewicz & Hoaglin (1993).  The rows are built here (the statistic is algebra:
the realistic site's use of it is measured in tests/validation/test_realistic_lanes.py and
benchmarks/bench_realsite.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from bwim.errors import InputError
from bwim.site import finish_day, refuse_lateral_outliers
from bwim.site.wander import (
    FLAG_LATERAL_OUTLIER,
    MIN_VEHICLES,
    OUTLIER_Z,
    SIGMA_FLOOR,
    lane_wander,
)
from bwim.summary import SummaryRow


def _row(k: int, lateral: float | None, *, lane: int = 1, direction: str = "+x",
         unit: str = "m", weighed: bool = True) -> SummaryRow:
    if weighed:
        return SummaryRow(record=f"e{k:04d}.txt", lane=lane, direction=direction,
                          n_axles=2, axle_weights=(60e3, 90e3), group_weights=(60e3, 90e3),
                          gvw=150e3, lateral=lateral, lateral_unit=unit if lateral is not None
                          else "", quality="ok", method="moses")
    return SummaryRow(record=f"e{k:04d}.txt", lane=lane, direction=direction,
                      status="refused", lateral=lateral,
                      lateral_unit=unit if lateral is not None else "",
                      reason="two vehicles")


@pytest.fixture
def lane1(rng):
    """A lane of 200 positions at the normal quantiles (none beyond 2.9 σ), shuffled."""
    return list(rng.permutation(5.9 + 0.15 * stats.norm.ppf((np.arange(200) + 0.5) / 200)))


def test_spread_is_the_median_and_normal_scaled_mad(lane1):
    rows = [_row(k, y) for k, y in enumerate(lane1)]
    (w,) = lane_wander(rows)
    assert (w.lane, w.direction, w.unit, w.n) == (1, "+x", "m", 200)
    assert w.median == pytest.approx(np.median(lane1), abs=1e-12)
    assert w.sigma == pytest.approx(stats.median_abs_deviation(lane1, scale="normal"),
                                    rel=1e-12)


def test_a_row_beyond_the_limit_is_refused_and_one_within_kept(lane1):
    rows = [_row(k, y) for k, y in enumerate(lane1)]
    (w,) = lane_wander(rows)
    inside = _row(900, w.median + (OUTLIER_Z - 0.3) * w.sigma)
    outside = _row(901, w.median - (OUTLIER_Z + 0.3) * w.sigma)
    # two rows added to 200 move the median and the MAD a little: the z-scores are those
    # of the rows as given, as the check measures them
    check = refuse_lateral_outliers([*rows, inside, outside])
    (w2,) = check.lanes
    assert abs(w2.z(inside.lateral)) < OUTLIER_Z < abs(w2.z(outside.lateral))
    assert check.refused == ((outside.record, 1),)
    kept, refused = check.rows[-2], check.rows[-1]
    assert kept is inside
    assert refused.status == "refused" and refused.gvw is None
    assert refused.axle_weights == () and refused.group_weights == ()
    assert refused.quality == "reject" and FLAG_LATERAL_OUTLIER in refused.flags
    assert "lane's traffic" in refused.reason and "no detector saw" in refused.reason
    # every other row is the same object, in order
    assert all(a is b for a, b in zip(check.rows[:-1], [*rows, inside], strict=True))


def test_each_lane_and_direction_has_its_own_spread(lane1, rng):
    lane3 = 10.6 + 0.2 * stats.norm.ppf((np.arange(120) + 0.5) / 120)
    rows = ([_row(k, y) for k, y in enumerate(lane1)]
            + [_row(500 + k, y, lane=3, direction="-x") for k, y in enumerate(lane3)])
    # a lane-1 vehicle at lane 3's centre is an outlier of lane 1 only
    stray = _row(999, float(np.median(lane3)))
    check = refuse_lateral_outliers([*rows, stray])
    assert [(w.lane, w.direction) for w in check.lanes] == [(1, "+x"), (3, "-x")]
    assert check.refused == ((stray.record, 1),)


def test_a_thin_lane_is_not_measured(lane1):
    rows = [_row(k, y) for k, y in enumerate(lane1[:MIN_VEHICLES - 1])]
    far = _row(999, 20.0)
    check = refuse_lateral_outliers([*rows, far])
    # 29 + 1 = MIN_VEHICLES rows: measured, and the far one refused
    assert check.refused == ((far.record, 1),)
    check = refuse_lateral_outliers([*rows[:-1], far])
    assert check.lanes == () and check.refused == ()
    assert check.rows[-1] is far


def test_unweighed_rows_and_rows_without_position_are_left_alone(lane1):
    rows = [_row(k, y) for k, y in enumerate(lane1)]
    refused_far = _row(900, 30.0, weighed=False)
    no_position = _row(901, None)
    index = _row(902, 12.0, unit="gauge index")  # another unit: its own (thin) group
    check = refuse_lateral_outliers([*rows, refused_far, no_position, index])
    assert check.refused == ()
    assert check.rows[-3] is refused_far and check.rows[-2] is no_position
    assert check.rows[-1] is index
    assert check.lanes[0].n == len(lane1)


def test_identical_positions_use_the_floor():
    rows = [_row(k, 6.0) for k in range(40)]
    near = _row(900, 6.0 + (OUTLIER_Z - 0.5) * SIGMA_FLOOR)
    far = _row(901, 6.0 + (OUTLIER_Z + 0.5) * SIGMA_FLOOR)
    check = refuse_lateral_outliers([*rows, near, far])
    assert check.lanes[0].sigma == SIGMA_FLOOR
    assert check.refused == ((far.record, 1),)


@pytest.mark.parametrize("kwargs, match", [
    ({"limit": 0.0}, "limit"), ({"limit": float("nan")}, "limit"),
    ({"min_vehicles": 2}, "min_vehicles"), ({"min_vehicles": 5.0}, "min_vehicles"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(InputError, match=match):
        refuse_lateral_outliers([_row(0, 5.0)], **kwargs)


def test_finish_day_checks_the_lanes_before_the_drift(lane1, small_site_calibrated):
    """The day-level steps: the outlier is refused and the drift step (not applied on these
    rows: no clock time) keeps every row in order."""
    rows = [_row(k, y) for k, y in enumerate(lane1)] + [_row(999, 9.0)]
    day = finish_day(rows, small_site_calibrated[-1])
    assert len(day.rows) == len(rows)
    assert day.rows[-1].status == "refused" and day.wander.refused == (("e0999.txt", 1),)
    assert [r.record for r in day.rows] == [r.record for r in rows]
    assert "DayResult(" in repr(day) and "1 refused" in repr(day)
