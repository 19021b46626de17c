"""The day's table of gauge health (issue 22 item 1): ``bwim weigh`` writes
``gauge_health.csv`` beside summary.csv, per gauge how many vehicles it was left out of
and why, and its median gain ratio; refused without --force like the other outputs;
kept whole across --resume.

Data: the shared small realistic site (tests/conftest.py, ``small_site``: an FE plate
with vehicle dynamics, gauge noise, offsets and drift; calibrated by influence lines).
Its lane-1 truck's file is copied three times (the clock is in the name: one and two
seconds later) with one fault each, as a faulty logger channel writes it: s02 reversed,
s05 dead, s02 clipped at its resting reading.  The expected counts are the faults
injected, not the code's output.
"""

from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from bwim.batch.gauges import VehicleGauges, tally_gauges
from bwim.cli import main
from bwim.errors import InputError
from bwim.io.gauge_health import COLUMNS, write_gauge_health
from bwim.scenario import load_record, load_scenario
from bwim.site import weigh_event

GAUGES = [f"s{k:02d}" for k in range(1, 13)]


def _faulty(path: Path, out: Path, scenario, gauge: str, fault) -> Path:
    """``path`` with the column of ``gauge`` replaced by ``fault(column)``."""
    k = list(scenario.logger.columns).index(gauge)
    rows = [line.split() for line in path.read_text().splitlines()]
    values = fault(np.array([float(r[k]) for r in rows]))
    for r, v in zip(rows, values, strict=True):
        r[k] = f"{v:.3f}"
    out.write_text("\n".join("\t".join(r) for r in rows) + "\n")
    return out


def _later(name: str, seconds: int) -> str:
    """A traffic file name ``PL1_YYYY-MM-DD-HH-MM-SS-mmm.txt`` ``seconds`` later."""
    stem, ms = name[:-len("-611.txt")], name[-len("611.txt"):]
    return f"{stem[:-2]}{int(stem[-2:]) + seconds:02d}-{ms}"


@pytest.fixture(scope="module")
def day(small_site, tmp_path_factory):
    """A traffic folder: the site's four events, the lane-1 truck's with s02 reversed,
    and two copies of it, s05 dead and s02 clipped at its first reading."""
    scenario = load_scenario(small_site.scenario)
    truck = next(p for p in small_site.traffic if p.name == "PL1_2026-04-17-15-41-34-611.txt")
    folder = tmp_path_factory.mktemp("gauge_day") / "traffic"
    folder.mkdir()
    for p in small_site.traffic:
        if p != truck:
            shutil.copy(p, folder / p.name)
    _faulty(truck, folder / truck.name, scenario, "s02", lambda y: -y)
    _faulty(truck, folder / _later(truck.name, 1), scenario, "s05", np.zeros_like)
    _faulty(truck, folder / _later(truck.name, 2), scenario, "s02",
            lambda y: np.minimum(y, y[0]))
    return small_site, folder


def _table(path: Path) -> dict[str, dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as f:
        return {r["gauge"]: r for r in csv.DictReader(f)}


def _weigh(small_site, records: Path, out: Path, *extra: str) -> int:
    return main(["weigh", str(small_site.scenario), str(records), "--calibration-records",
                 str(small_site.calibration[0].parent), "-o", str(out), *extra])


def test_the_table_counts_each_fault(day, tmp_path):
    """Three trucks judged (the three copies; the site's other vehicles drive the other
    way, or share the span and are refused before their gauges are judged): s02 left out
    of two (reversed, clipped), s05 of one (flat), no other gauge of any.  The median gain
    ratios lie within 0.85 … 1.15 (a healthy gauge of the trucks weighed alone: the
    clean ratios' range, tests/unit/test_site_health.py), over 3 vehicles for a gauge
    never left out, 1 for s02 (only the truck with s05 dead weighed with it), 2 for s05."""
    small_site, folder = day
    out = tmp_path / "out"
    assert _weigh(small_site, folder, out) == 0
    table = _table(out / "gauge_health.csv")
    assert list(table) == GAUGES
    with (out / "gauge_health.csv").open(encoding="utf-8") as f:
        assert tuple(f.readline().strip().split(",")) == COLUMNS
    kinds = ("flat", "clipped", "silent", "reversed", "gain", "drift")
    for g, row in table.items():
        assert row["vehicles_judged"] == "3"
        expected = {"s02": {"reversed": 1, "clipped": 1}, "s05": {"flat": 1}}.get(g, {})
        assert {k: int(row[k]) for k in kinds if int(row[k])} == expected, (g, row)
        assert int(row["left_out"]) == sum(expected.values())
        assert int(row["n_ratios"]) == 3 - sum(expected.values())
        assert 0.85 < float(row["median_gain_ratio"]) < 1.15, (g, row)


def test_the_table_is_an_output_refused_without_force(day, tmp_path):
    """An existing gauge_health.csv (the only output there) is refused without --force,
    named, exit 2, nothing written; --force replaces it."""
    small_site, folder = day
    out = tmp_path / "out"
    out.mkdir()
    (out / "gauge_health.csv").write_text("another run's table\n")
    assert _weigh(small_site, folder, out) == 2
    assert (out / "gauge_health.csv").read_text() == "another run's table\n"
    assert not (out / "summary.csv").exists()
    assert _weigh(small_site, folder, out, "--force") == 0
    assert _table(out / "gauge_health.csv")["s05"]["flat"] == "1"


def test_a_resume_on_fewer_records_keeps_their_gauges(day, tmp_path):
    """A --resume given only the three clean files keeps the faulty trucks' counts (the
    manifest holds what each record's gauges did), as it keeps their summary rows."""
    small_site, folder = day
    out = tmp_path / "out"
    assert _weigh(small_site, folder, out) == 0
    first = (out / "gauge_health.csv").read_text()
    clean = [p for p in folder.iterdir() if not p.name.startswith("PL1_2026-04-17-15-41-3")]
    assert len(clean) == 3
    assert main(["weigh", str(small_site.scenario), *map(str, clean), "--calibration-records",
                 str(small_site.calibration[0].parent), "-o", str(out), "--resume"]) == 0
    assert (out / "gauge_health.csv").read_text() == first


def test_the_ratios_are_those_of_the_check(small_site):
    """Algebra: the ratio the table takes from the weighing a clean truck was weighed with
    (:func:`bwim.site.health.gain_ratios`) is the check's own (:func:`check_gauges`, its
    weighing without the drift factor: a factor common to all gauges changes only the
    weights of the line through the others, via the expected deviations) to 1e-3."""
    from bwim.scenario import build_site_setup
    from bwim.site import calibrate_site
    from bwim.site.health import check_gauges, gain_ratios

    scenario = load_scenario(small_site.scenario)
    calibration = calibrate_site([load_record(p, scenario) for p in small_site.calibration],
                                 build_site_setup(scenario))
    path = next(p for p in small_site.traffic if p.name.startswith("PL1_2026-04-17-15"))
    record = load_record(path, scenario)
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and v.drift_factor != 1.0
    ours = gain_ratios(v.weighing, calibration.lines)
    theirs = check_gauges(record, v.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine).ratios
    assert set(ours) == set(theirs) == set(GAUGES)
    for g in GAUGES:
        assert ours[g] == pytest.approx(theirs[g], abs=1e-3)


def test_tally_and_writer(tmp_path):
    """Algebra: counts by kind, the median of the ratios given, a gauge no vehicle
    weighed alone has no median (empty cell); a row without a column is refused."""
    vehicles = [VehicleGauges(faults={"a": "flat"}, ratios={"b": 1.0}),
                VehicleGauges(faults={"a": "drift", "b": "gain"}),
                VehicleGauges(ratios={"a": 0.9, "b": 1.2}),
                VehicleGauges.from_json(VehicleGauges(ratios={"b": 1.1}).to_json())]
    a, b = tally_gauges(["a", "b"], vehicles)
    assert (a.judged, a.left_out, a.kinds["flat"], a.kinds["drift"]) == (4, 2, 1, 1)
    assert (a.median_ratio, a.n_ratios) == (0.9, 1)
    assert (b.left_out, b.kinds["gain"], b.n_ratios) == (1, 1, 3)
    assert b.median_ratio == pytest.approx(1.1)
    (c,) = tally_gauges(["c"], [VehicleGauges(), VehicleGauges(ratios={})])
    assert math.isnan(c.median_ratio) and c.n_ratios == 0
    write_gauge_health(tmp_path / "t.csv", [c.as_row()])
    assert (tmp_path / "t.csv").read_text().splitlines()[1] == "c,2,0,0,0,0,0,0,0,,0"
    with pytest.raises(InputError, match="without n_ratios"):
        write_gauge_health(tmp_path / "u.csv", [{k: 0 for k in COLUMNS[:-1]}])
