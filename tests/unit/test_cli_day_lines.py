"""``bwim weigh``'s lines on the day-level steps (bwim.cli.batches): one per lane whose
spread (of lateral positions, of axle groups' positions) was measured and one per gauge
whose faults the vehicles around them did not share, with the numbers of the checks'
results (made here from rows: the checks themselves are tested in test_site_wander.py,
test_site_wheelpath.py and test_site_unconfirmed.py)."""

from __future__ import annotations

from datetime import datetime, timedelta

from bwim.cli.batches import _print_paths, _print_speeds, _print_unconfirmed, _print_wander
from bwim.site import (
    drop_speed_outliers,
    refuse_lateral_outliers,
    refuse_off_path,
    refuse_unconfirmed_faults,
)
from bwim.summary import SummaryRow

T0 = datetime(2026, 7, 20, 6, 0)


def _row(k: int, lateral: float, *faults: str, paths: tuple[float, ...] = ()
         ) -> SummaryRow:
    return SummaryRow(record=f"e{k:04d}.txt", lane=1, direction="+x", n_axles=2,
                      group_laterals=paths,
                      time=T0 + timedelta(minutes=k), axle_weights=(60e3, 90e3),
                      group_weights=(60e3, 90e3), gvw=150e3, lateral=lateral,
                      lateral_unit="m", flags=tuple(f"gauge_fault:{g}" for g in faults),
                      quality="warning" if faults else "ok", method="moses")


def test_the_day_lines(capsys):
    rows = [_row(k, 5.9 + 0.01 * (k % 7 - 3)) for k in range(60)]
    rows[20] = _row(20, 7.5)  # beside another vehicle
    rows[40] = _row(40, 5.9, "s12")  # a gauge loaded by another vehicle
    faults = refuse_unconfirmed_faults(rows)
    _print_unconfirmed(faults)
    _print_wander(refuse_lateral_outliers(faults.rows))
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("gauge s12: disagreed in 1 vehicle(s)")
    assert "unconfirmed_gauge_fault" in out[0]
    assert out[1].startswith("lane 1 +x: lateral position 5.90 m ± ")
    assert "over 59 vehicle(s); 1 refused beyond 3.5 σ" in out[1]
    assert len(out) == 2


def test_the_axle_groups_line(capsys):
    rows = [_row(k, 5.9, paths=(5.8 + 0.01 * (k % 7 - 3), 5.9)) for k in range(60)]
    rows[30] = _row(30, 6.5, paths=(7.1, 5.9))  # an axle of the next lane's vehicle
    _print_paths(refuse_off_path(rows))
    out = capsys.readouterr().out.splitlines()
    assert out == ["lane 1 +x: axle groups against their vehicle's others (m): first -0.10 ± "
                   "0.03, last +0.10 ± 0.03; 1 refused beyond 6 σ (an axle of a vehicle beside "
                   "it)"]


def test_the_speeds_line(capsys):
    rows = [SummaryRow(record=f"c{k:04d}.txt", lane=3, direction="-x", n_axles=2,
                       speed=22.0 + 0.1 * (k % 9 - 4), time=T0 + timedelta(minutes=k),
                       status="refused", reason="counted, not weighed") for k in range(60)]
    rows[30] = SummaryRow(record="c0030.txt", lane=3, direction="-x", n_axles=2, speed=7.0,
                          time=T0 + timedelta(minutes=30), status="refused",
                          reason="counted, not weighed")
    _print_speeds(drop_speed_outliers(rows))
    out = capsys.readouterr().out.splitlines()
    assert out == ["lane 3 -x: 1 vehicle(s) left out, at speeds far from the lane's traffic "
                   "around them (beyond 5 σ: traces of another vehicle)"]


def test_a_small_day_says_its_lateral_checks_did_not_run(capsys):
    rows = [_row(k, 5.9, *(("s12",) if k == 3 else ()), paths=(5.9, 5.9)) for k in range(10)]
    _print_unconfirmed(refuse_unconfirmed_faults(rows))
    _print_wander(refuse_lateral_outliers(rows))
    _print_paths(refuse_off_path(rows))
    _print_speeds(drop_speed_outliers(rows))
    assert capsys.readouterr().out.splitlines() == [
        "lane 1 +x: 10 vehicle(s) weighed, too few for the day's lateral checks (they need "
        "30): a vehicle beside one that no detector saw is not refused; weigh the whole day "
        "together"]
