"""``bwim weigh``'s lines on the day-level steps (bwim.cli.batches): one per lane whose
spread was measured and one per gauge whose faults the vehicles around them did not
share, with the numbers of the checks' results (made here from rows: the checks
themselves are tested in test_site_wander.py and test_site_unconfirmed.py)."""

from __future__ import annotations

from datetime import datetime, timedelta

from bwim.cli.batches import _print_unconfirmed, _print_wander
from bwim.site import refuse_lateral_outliers, refuse_unconfirmed_faults
from bwim.summary import SummaryRow

T0 = datetime(2026, 7, 20, 6, 0)


def _row(k: int, lateral: float, *faults: str) -> SummaryRow:
    return SummaryRow(record=f"e{k:04d}.txt", lane=1, direction="+x", n_axles=2,
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


def test_nothing_to_say_on_a_small_day(capsys):
    rows = [_row(k, 5.9, *(("s12",) if k == 3 else ())) for k in range(10)]
    _print_unconfirmed(refuse_unconfirmed_faults(rows))
    _print_wander(refuse_lateral_outliers(rows))
    assert capsys.readouterr().out == ""
