"""No loss (issue 22 item 4): ``bwim weigh --resume`` on fewer records keeps every row
already written; every output file a command writes is refused (one line, exit 2,
nothing written) when it exists, unless ``--force``.  Data: a tiny realistic site
(:mod:`bwim.synthetic`, ``short-span-4-lane``) and the beam example; the expected
outcomes are the issue's (rows kept, files untouched), not the code's output."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from bwim.cli import main
from bwim.io.outputs import MANIFEST_NAME

from tests.cli_checks import one_line_error

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def day(small_site):
    return small_site


@pytest.fixture(scope="module")
def weighed(day, tmp_path_factory):
    """The day's four events weighed once (the folder is copied by the tests that change
    it)."""
    out = tmp_path_factory.mktemp("weighed") / "out"
    assert main(_weigh_argv(day, [day.traffic[0].parent], out)) == 0
    return out


def _weigh_argv(day, records, out, *more) -> list[str]:
    return ["weigh", str(day.scenario), *map(str, records), "--calibration-records",
            str(day.calibration[0].parent), "-o", str(out), *more]


def _rows(summary: Path) -> list[dict[str, str]]:
    with summary.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def _copy(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst)
    return dst


def test_resume_on_fewer_records_keeps_every_row(day, weighed, tmp_path, capsys):
    """Issue 22: ``--resume`` with one of the four events dropped the other rows (100 rows
    → 9).  Every row of the first run is still in the summary, unchanged, and the one
    record given again is skipped (done before)."""
    out = _copy(weighed, tmp_path / "out")
    before = _rows(out / "summary.csv")
    assert len(before) >= 4
    code = main(_weigh_argv(day, [day.traffic[-1]], out, "--resume"))
    printed = capsys.readouterr().out
    assert code == 0
    assert "(1 done before)" in printed
    after = _rows(out / "summary.csv")
    key = ("record", "vehicle", "gvw_kN", "axle_weights_kN", "status")
    assert sorted(tuple(r[k] for k in key) for r in after) == \
        sorted(tuple(r[k] for k in key) for r in before)


def test_resume_without_a_manifest_does_not_replace_a_summary(day, tmp_path, capsys):
    """A folder with a summary.csv but no manifest (another run's, or the manifest
    removed): nothing to resume, so ``--resume`` must not replace the summary."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.csv").write_text("record\nmine\n")
    code = main(_weigh_argv(day, [day.traffic[0]], out, "--resume"))
    one_line_error(code, capsys.readouterr().err, "summary.csv exists", "--force")
    assert (out / "summary.csv").read_text() == "record\nmine\n"
    assert not (out / MANIFEST_NAME).exists()


@pytest.mark.parametrize("name", ["calibration_runs.csv", "influence_lines.h5"])
@pytest.mark.parametrize("resume", [False, True])
def test_site_outputs_need_force(day, tmp_path, capsys, name, resume):
    """An existing calibration_runs.csv or influence_lines.h5 is not replaced without
    --force, also under --resume when the folder holds no batch to resume."""
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text("keep me")
    code = main(_weigh_argv(day, [day.traffic[0]], out, *(["--resume"] if resume else [])))
    one_line_error(code, capsys.readouterr().err, f"{name} exists", "--force")
    assert sorted(p.name for p in out.iterdir()) == [name]
    assert (out / name).read_text() == "keep me"


def test_site_outputs_replaced_with_force(day, weighed, tmp_path, capsys):
    out = _copy(weighed, tmp_path / "out")
    (out / "calibration_runs.csv").write_text("old")
    code = main(_weigh_argv(day, [day.traffic[0]], out, "--force"))
    assert code == 0, capsys.readouterr().err
    assert (out / "calibration_runs.csv").read_text().startswith("run,")
    # this site's gauges have their y: the runs' lateral position in metres, and says so
    assert "lateral (m)" in _rows(out / "calibration_runs.csv")[0]
    assert len(_rows(out / "summary.csv")) >= 1


@pytest.fixture(scope="module")
def beam(tmp_path_factory):
    d = tmp_path_factory.mktemp("beam")
    text = (ROOT / "examples" / "beam.toml").read_text(encoding="utf-8")
    scen = d / "beam.toml"
    scen.write_text(text.replace("approach = 50.0", "approach = 5.0"), encoding="utf-8")
    assert main(["simulate", str(scen), "-o", str(d / "a.h5")]) == 0
    return {"scen": scen, "a": d / "a.h5"}


@pytest.mark.parametrize(("argv", "existing"), [
    (["identify", "{scen}", "{a}", "-o", "{out}"], "a_forces.h5"),
    (["weigh", "{scen}", "{a}", "--calibration-records", "{a}", "-o", "{out}"],
     "a_static.h5"),
    (["weigh", "{scen}", "{a}", "--calibration-records", "{a}", "-o", "{out}"],
     "influence_line.h5"),
    (["demo", "--quick", "-o", "{out}"], "report.html"),
    (["demo", "--quick", "--out", "{out}"], "calibrated_bridge.toml"),
    (["reproduce", "5.1", "--quick", "-o", "{out}"], "5_1_convergence.png"),
])
def test_every_output_file_needs_force(beam, tmp_path, capsys, argv, existing):
    """Each command's output files, one at a time, existing: refused at once with one
    line naming it, the folder as it was (no other file written)."""
    out = tmp_path / "out"
    out.mkdir()
    (out / existing).write_text("keep me")
    values = {"scen": beam["scen"], "a": beam["a"], "out": out}
    code = main([a.format(**values) for a in argv])
    one_line_error(code, capsys.readouterr().err, f"{existing} exists", "--force")
    assert sorted(p.name for p in out.iterdir()) == [existing]
    assert (out / existing).read_text() == "keep me"


# --- progress on stderr when it is not a terminal (issue 21 item 5) -------------------------
def test_weigh_progress_lines_when_stderr_is_not_a_terminal(day, tmp_path, capsys,
                                                            monkeypatch):
    """stderr captured (not a terminal): plain lines with count, total and ETA (every
    item here: the period set to zero)."""
    from bwim.cli.common import Progress

    monkeypatch.setattr(Progress, "every", 0.0)
    code = main(_weigh_argv(day, [day.traffic[0].parent], tmp_path / "out"))
    err = capsys.readouterr().err
    assert code == 0, err
    n = len(day.traffic)
    lines = [ln for ln in err.splitlines() if ln.startswith("bwim: weighing: ")]
    assert [ln.split()[2] for ln in lines] == [f"{k}/{n}" for k in range(1, n + 1)], err
    assert all("ETA " in ln for ln in lines)
    assert lines[-1].endswith("ETA 0 s")


def test_calibration_progress_lines_when_stderr_is_not_a_terminal(capsys, monkeypatch):
    from bwim.cli.common import CalibrationProgress

    progress = CalibrationProgress()
    monkeypatch.setattr(progress, "every", 1e9)
    for stage, it in (("stiffness", 1), ("stiffness", 2), ("mass", 1)):
        progress(stage, it, 0.5 / it)
    progress.close()
    lines = capsys.readouterr().err.splitlines()
    assert [ln.split(": ")[2] for ln in lines] == ["stiffness", "mass"]
    assert "iteration 1, best 0.5" in lines[0]


def test_site_calibration_prints_short(day):
    """``print(site_calibration)`` was 25 kB (issue 21): one line naming what was
    learned."""
    from bwim.scenario import build_site_setup, load_record, load_scenario
    from bwim.site import calibrate_site

    sc = load_scenario(day.scenario)
    site = calibrate_site([load_record(p, sc) for p in day.calibration], build_site_setup(sc))
    text = str(site)
    assert text == repr(site) and "\n" not in text and len(text) < 200, text
    assert f"{site.n_used} of {len(day.calibration)} runs used" in text


def test_a_record_result_file_never_replaces_an_input(beam, tmp_path, capsys):
    """``weigh a.h5 a_static.h5 -o <their folder>``: a.h5's weights would be written over
    the record a_static.h5: refused, even with --force."""
    import shutil

    a = shutil.copy(beam["a"], tmp_path / "a.h5")
    other = shutil.copy(beam["a"], tmp_path / "a_static.h5")
    before = Path(other).read_bytes()
    code = main(["weigh", str(beam["scen"]), str(a), str(other), "--calibration-records",
                 str(a), "-o", str(tmp_path), "--force"])
    one_line_error(code, capsys.readouterr().err, "is the input", "a_static.h5")
    assert Path(other).read_bytes() == before


def test_a_resume_refuses_a_record_of_the_same_name_from_another_file(day, weighed,
                                                                      tmp_path, capsys):
    """A copy of one of the day's files, from another folder, given to --resume: the
    summary would hold two rows of one record (review of stop 33: both were weighed, and
    bwim report and accuracy then refused the summary). Refused, one line, nothing
    changed."""
    import shutil

    out = _copy(weighed, tmp_path / "out")
    before = (out / "summary.csv").read_text()
    moved = tmp_path / "moved"
    moved.mkdir()
    shutil.copy2(day.traffic[0], moved / day.traffic[0].name)
    code = main(_weigh_argv(day, [moved], out, "--resume"))
    one_line_error(code, capsys.readouterr().err, "already holds record",
                   day.traffic[0].name)
    assert (out / "summary.csv").read_text() == before


@pytest.mark.parametrize("entry", [
    {"source": "a.txt"},                                  # no rows
    {"source": "a.txt", "rows": 5},
    {"rows": []},                                         # no source
    "an entry",
    {"source": "a.txt", "rows": [{"vehicle": "1"}]},      # a row without its record
])
def test_a_damaged_manifest_is_one_line(day, weighed, tmp_path, capsys, entry):
    import json

    out = _copy(weighed, tmp_path / "out")
    data = json.loads((out / MANIFEST_NAME).read_text())
    data["entries"]["x"] = entry
    (out / MANIFEST_NAME).write_text(json.dumps(data))
    code = main(_weigh_argv(day, [day.traffic[0]], out, "--resume"))
    one_line_error(code, capsys.readouterr().err, "damaged manifest")
