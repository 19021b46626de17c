"""A gauge fault the day does not confirm (bwim.site.unconfirmed): the vehicle is refused;
a gauge faulty in most of the day's vehicles keeps their weights.

The rows are built here (the rule is counting: its effect on the realistic site, where
every healthy-gauge fault came from a truck in lane 4 that no detector saw, is measured
by benchmarks/bench_realsite.py)."""

from __future__ import annotations

import pytest

from bwim.errors import InputError
from bwim.site import finish_day, refuse_unconfirmed_faults
from bwim.site.unconfirmed import CONFIRM, FLAG_UNCONFIRMED, MIN_VEHICLES


def _row(k: int, *faults: str, weighed: bool = True):
    from bwim.summary import SummaryRow

    flags = tuple(f"gauge_fault:{g}" for g in faults)
    if not weighed:
        return SummaryRow(record=f"e{k:04d}.txt", status="refused", flags=flags,
                          reason="too few healthy gauges")
    return SummaryRow(record=f"e{k:04d}.txt", lane=1, direction="+x", n_axles=2,
                      axle_weights=(60e3, 90e3), group_weights=(60e3, 90e3), gvw=150e3,
                      flags=flags, quality="warning" if flags else "ok", method="moses")


def test_a_sporadic_fault_refuses_its_vehicles():
    rows = [_row(k) for k in range(99)] + [_row(99, "s12")]
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 100 and check.counts == {"s12": 1}
    assert check.confirmed == () and check.refused == (("e0099.txt", 1),)
    r = check.rows[-1]
    assert r.status == "refused" and r.gvw is None and r.axle_weights == ()
    assert r.quality == "reject" and FLAG_UNCONFIRMED in r.flags
    assert "gauge_fault:s12" in r.flags and "s12 in 1 of 100" in r.reason
    assert all(a is b for a, b in zip(check.rows[:-1], rows[:-1], strict=True))


def test_a_gauge_faulty_in_most_vehicles_keeps_their_weights():
    n = 100
    k_faulty = int(CONFIRM * n)  # exactly the share, the last row included: confirmed
    rows = ([_row(k, "s03") for k in range(k_faulty - 1)]
            + [_row(k) for k in range(k_faulty - 1, n - 1)] + [_row(n - 1, "s03", "s12")])
    check = refuse_unconfirmed_faults(rows)
    assert check.counts == {"s03": k_faulty, "s12": 1} and check.confirmed == ("s03",)
    # s03 confirmed everywhere; the vehicle that also lost s12 (1 of 100) is refused
    assert check.refused == ((f"e{n - 1:04d}.txt", 1),)
    assert sum(r.weighed for r in check.rows) == n - 1
    # one fewer and s03 is not confirmed: all its vehicles are refused
    check = refuse_unconfirmed_faults([*rows[1:], _row(999)])
    assert check.confirmed == () and len(check.refused) == k_faulty - 1


def test_a_small_day_cannot_judge():
    rows = [_row(k) for k in range(MIN_VEHICLES - 2)] + [_row(900, "s12")]
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 0 and check.refused == ()
    assert all(a is b for a, b in zip(check.rows, rows, strict=True))


def test_rows_not_weighed_are_left_alone_and_not_counted():
    rows = ([_row(k) for k in range(40)] + [_row(50 + k, "s01", weighed=False)
                                            for k in range(40)])
    check = refuse_unconfirmed_faults(rows)
    assert check.n_weighed == 40 and check.counts == {}
    assert all(a is b for a, b in zip(check.rows, rows, strict=True))


@pytest.mark.parametrize("kwargs, match", [
    ({"confirm": 0.0}, "confirm"), ({"confirm": 1.5}, "confirm"),
    ({"confirm": float("nan")}, "confirm"), ({"min_vehicles": 0}, "min_vehicles"),
    ({"min_vehicles": True}, "min_vehicles"),
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
