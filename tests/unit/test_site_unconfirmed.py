"""A gauge fault the vehicles around it do not confirm (bwim.site.unconfirmed): the
vehicle is refused; a gauge that stays faulty keeps its vehicles' weights.

The rows are built here (the rule is counting over neighbours in time: its effect on the
realistic site, where every fault of a healthy gauge came from a truck in lane 4 that no
detector saw, is measured by benchmarks/bench_realsite.py)."""

from __future__ import annotations

from datetime import datetime, timedelta

import pytest

from bwim.errors import InputError
from bwim.site import finish_day, refuse_unconfirmed_faults
from bwim.site.unconfirmed import CONFIRM, FLAG_UNCONFIRMED, NEIGHBOURS
from bwim.summary import SummaryRow

T0 = datetime(2026, 7, 20, 6, 0)


def _row(k: int, *faults: str, weighed: bool = True, timed: bool = True) -> SummaryRow:
    flags = tuple(f"gauge_fault:{g}" for g in faults)
    time = T0 + timedelta(minutes=k) if timed else None
    if not weighed:
        return SummaryRow(record=f"e{k:04d}.txt", status="refused", flags=flags, time=time,
                          reason="too few healthy gauges")
    return SummaryRow(record=f"e{k:04d}.txt", lane=1, direction="+x", n_axles=2, time=time,
                      axle_weights=(60e3, 90e3), group_weights=(60e3, 90e3), gvw=150e3,
                      flags=flags, quality="warning" if flags else "ok", method="moses")


def test_a_sporadic_fault_refuses_its_vehicle():
    rows = [_row(k, *(("s12",) if k in (10, 70) else ())) for k in range(100)]
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 100 and check.counts == {"s12": 2}
    assert check.refused == (("e0010.txt", 1), ("e0070.txt", 1))
    assert check.unconfirmed == {"s12": 2}
    r = check.rows[10]
    assert r.status == "refused" and r.gvw is None and r.axle_weights == ()
    assert r.quality == "reject" and FLAG_UNCONFIRMED in r.flags
    assert "gauge_fault:s12" in r.flags and f"s12 in 1 of the {NEIGHBOURS}" in r.reason
    assert all(a is b for k, (a, b) in enumerate(zip(check.rows, rows, strict=True))
               if k not in (10, 70))


def test_a_gauge_that_fails_at_noon_keeps_every_vehicle_after_noon():
    # 100 vehicles a minute apart; s03 dead from the 60th on; s12 disagrees once after
    rows = [_row(k, *(("s03",) if k >= 60 else ()), *(("s12",) if k == 80 else ()))
            for k in range(100)]
    check = refuse_unconfirmed_faults(rows)
    # from the first faulty vehicle on, half the window centred on it (or more) is
    # faulty: confirmed; only the vehicle where s12 also disagreed is refused
    assert NEIGHBOURS // 2 >= CONFIRM * NEIGHBOURS
    assert check.refused == (("e0080.txt", 1),)
    kept = [r for r in check.rows[60:] if r.weighed]
    assert len(kept) == 39 and all("gauge_fault:s03" in r.flags for r in kept)


def test_the_order_is_the_clock_not_the_list(rng):
    # the noon failure listed in a shuffled order: the same rows refused
    rows = [_row(k, *(("s03",) if k >= 60 else ()), *(("s12",) if k == 80 else ()))
            for k in range(100)]
    shuffled = [rows[k] for k in rng.permutation(len(rows))]
    assert set(refuse_unconfirmed_faults(shuffled).refused) == {("e0080.txt", 1)}


def test_a_small_day_cannot_judge():
    rows = [_row(k) for k in range(NEIGHBOURS - 2)] + [_row(900, "s12")]
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 0 and check.refused == ()
    assert all(a is b for a, b in zip(check.rows, rows, strict=True))


def test_rows_not_weighed_are_left_alone_and_not_counted():
    rows = ([_row(k) for k in range(40)] + [_row(50 + k, "s01", weighed=False)
                                            for k in range(40)])
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 40 and check.counts == {}
    assert all(a is b for a, b in zip(check.rows, rows, strict=True))


def test_rows_without_a_clock_keep_their_place():
    rows = [_row(k, *(("s12",) if k == 5 else ()), timed=False) for k in range(40)]
    assert refuse_unconfirmed_faults(rows).refused == (("e0005.txt", 1),)


@pytest.mark.parametrize("kwargs, match", [
    ({"confirm": 0.0}, "confirm"), ({"confirm": 1.5}, "confirm"),
    ({"confirm": float("nan")}, "confirm"), ({"neighbours": 0}, "neighbours"),
    ({"neighbours": True}, "neighbours"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(InputError, match=match):
        refuse_unconfirmed_faults([_row(0)], **kwargs)


def test_finish_day_runs_it_first(small_site_calibrated):
    rows = [_row(k) for k in range(60)] + [_row(60, "s12")]
    day = finish_day(rows, small_site_calibrated[-1])
    assert day.faults.refused == (("e0060.txt", 1),)
    assert day.rows[-1].status == "refused" and FLAG_UNCONFIRMED in day.rows[-1].flags
    assert "FaultCheck(" in repr(day)
