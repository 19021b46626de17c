"""The ``bwim`` subcommands end to end (called as ``main([...])``) on small scenarios, the
bad-input contract (exit 2, one line on stderr naming the problem, no traceback, no
partial output) and the dask local-cluster path of ``identify``.  Accuracy references:
the simulated vehicles' static loads, the scenario's true parameters, and Lévy's exact
first frequency of the slab (tests/references.py)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from bwim.cli import main
from bwim.io import read_identification, read_record, read_static_weights
from bwim.scenario import load_bridge

from tests.references import levy_ss_free_first_frequency

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "paper_slab.toml"


def _scenario(folder: Path, filename: str, subs: dict[str, str] | None = None) -> Path:
    """A copy of the paper slab example with a 10 m approach and text substituted."""
    text = EXAMPLE.read_text(encoding="utf-8").replace(
        "approach = 100.0", "approach = 10.0")
    for old, new in (subs or {}).items():
        assert old in text, old
        text = text.replace(old, new)
    path = folder / filename
    path.write_text(text, encoding="utf-8")
    return path


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Scenarios and simulated records: calibration truck (true bridge), a start model
    20 % off in E, and a 3-axle truck at 15 m/s (HDF5 and CSV)."""
    d = tmp_path_factory.mktemp("cli")
    cal = _scenario(d, "cal.toml")
    start = _scenario(d, "start.toml", {"E = 35e9": "E = 30e9"})
    three = _scenario(d, "three.toml", {'"two_axle_truck"': '"three_axle_truck"',
                                        "speed = 20.0": "speed = 15.0"})
    assert main(["simulate", str(cal), "-o", str(d / "cal.h5")]) == 0
    assert main(["simulate", str(three), "-o", str(d / "truck.h5")]) == 0
    assert main(["simulate", str(three), "-o", str(d / "truck.csv")]) == 0
    return {"dir": d, "cal": cal, "start": start, "three": three, "cal_h5": d / "cal.h5",
            "truck_h5": d / "truck.h5", "truck_csv": d / "truck.csv"}


def test_help_names_every_subcommand(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for cmd in ("simulate", "calibrate", "identify", "weigh", "report", "demo", "reproduce"):
        assert cmd in out


def test_simulate_writes_h5_and_csv(files, capsys):
    rec = read_record(files["truck_h5"])
    assert rec.passage.n_axles == 3 and rec.passage.speed == 15.0
    with open(files["truck_csv"], newline="") as f:
        header = next(csv.reader(f))
    assert header[0] == "time" and len(header) == 1 + len(rec.sensors)
    # a saved model replaces the scenario's bridge
    code, out, _ = _run(["simulate", files["cal"], "--bridge", files["cal"], "-o",
                         files["dir"] / "again.h5"], capsys)
    assert code == 0 and "record:" in out
    np.testing.assert_allclose(read_record(files["dir"] / "again.h5").data,
                               read_record(files["cal_h5"]).data)


def test_calibrate_then_identify_across_invocations(files, capsys):
    """calibrate (LM, noise-free record of the true bridge) returns the scenario's E and
    μ; identify weighs the 3-axle truck against the simulated static axle loads (the
    reference): measured axle errors 0.9 / 1.5 / 0.5 %, GVW 1.0 %, from both files."""
    d = files["dir"]
    model = d / "model.toml"
    code, out, err = _run(["calibrate", files["start"], files["cal_h5"], "-o", model,
                           "--method", "lm", "--seed", "0"], capsys)
    assert code == 0, err
    assert "E_x" in out and "identifiability" in out and "evaluations" in out
    bridge = load_bridge(model)
    assert bridge.params["E_x"][0] == pytest.approx(35e9, rel=1e-3)
    assert bridge.params["mu"][0] == pytest.approx(1560.0, rel=1e-3)

    res = d / "identify"
    code, out, err = _run(["identify", files["three"], files["truck_h5"], files["truck_csv"],
                           "--bridge", model, "-o", res, "--jobs", "2"], capsys)
    assert code == 0, err
    assert "['" not in out  # the axle weights as "58.3, 109.5", as weigh prints them
    with open(res / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["record"] for r in rows] == ["truck.h5", "truck.csv"]
    for r in rows:  # each row's weights printed as the summary has them, to 0.1 kN
        shown = ", ".join(f"{float(w):.1f}" for w in r["axle_weights_kN"].split(";"))
        assert shown in out, (shown, out)
    truth = read_record(files["truck_h5"]).truth
    for r in rows:
        assert r["status"] == "weighed" and r["method"] == "mfi" and r["class"] == "12"
        weights = np.array([float(w) for w in r["axle_weights_kN"].split(";")]) * 1e3
        np.testing.assert_allclose(weights, truth.static_axle_loads, rtol=0.025)
        assert float(r["gvw_kN"]) * 1e3 == pytest.approx(truth.gvw, rel=0.02)
        assert float(r["lambda"]) > 0
    ident = read_identification(res / "truck_forces.h5")
    assert ident.axle_forces.shape[1] == 3 and (res / "truck_2_forces.h5").exists()


def test_calibrate_mesh_correction_option(files, capsys):
    """--mesh-correction reaches calibrate and its report is printed; a bad value is one
    line and exit 2 (the accuracy is tests/validation/test_mesh_correction.py's)."""
    d = files["dir"]
    code, out, err = _run(["calibrate", files["start"], files["cal_h5"], "-o",
                           d / "corrected.toml", "--method", "lm", "--mesh-correction", "1"],
                          capsys)
    assert code == 0, err
    assert "mesh defect correction by the 24x16 model" in out and ", mesh pass 1" in out
    grid = load_bridge(d / "corrected.toml").model.grid  # the model the parameters fit
    assert (grid.nx, grid.ny) == (24, 16)
    for bad in ("7", "fine"):
        code, out, err = _run(["calibrate", files["start"], files["cal_h5"], "-o",
                               d / "bad.toml", "--mesh-correction", bad], capsys)
        assert code == 2 and len(err.strip().splitlines()) == 1
        assert "mesh_correction" in err and not (d / "bad.toml").exists()


def test_identify_on_a_dask_local_cluster(files, capsys):
    """The dask path weighs as the local one: GVW against the simulated static GVW
    (measured 1.0 %, as in the local run)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        summary = files["dir"] / "dask" / "summary.csv"
        summary.parent.mkdir()
        code, _out, err = _run(["identify", files["three"], files["truck_h5"], "-o", summary,
                               "--scheduler", cluster.scheduler_address], capsys)
    assert code == 0, err
    with open(summary, newline="") as f:
        [row] = list(csv.DictReader(f))
    truth = read_record(files["truck_h5"]).truth
    assert row["record"] == "truck.h5"
    assert float(row["gvw_kN"]) * 1e3 == pytest.approx(truth.gvw, rel=0.02)
    assert (summary.parent / "truck_forces.h5").exists()


def test_weigh_calibrates_and_reuses_the_influence_line(files, capsys):
    """Moses with an influence line calibrated from the 2-axle calibration record weighs
    the 3-axle truck against its simulated static loads: measured GVW −1.4 %, axles
    −5.9 / −5.7 / +6.1 % (static B-WIM splits a tandem-like group poorly); bounds ≈ 1.7×."""
    d = files["dir"]
    code, _out, err = _run(["weigh", files["cal"], files["truck_h5"], "--calibration-records",
                           files["cal_h5"], "-o", d / "weigh"], capsys)
    assert code == 0, err
    il = d / "weigh" / "influence_line.h5"
    w = read_static_weights(d / "weigh" / "truck_static.h5")
    assert il.exists() and w.n_axles == 3
    truth = read_record(files["truck_h5"]).truth
    assert w.gvw == pytest.approx(truth.gvw, rel=0.025)
    np.testing.assert_allclose(w.axle_weights, truth.static_axle_loads, rtol=0.1)
    code, _out, err = _run(["weigh", files["cal"], files["truck_h5"], "--influence", il,
                           "-o", d / "weigh2"], capsys)
    assert code == 0, err
    assert read_static_weights(d / "weigh2" / "truck_static.h5").gvw == pytest.approx(w.gvw)


def test_report_of_result_folders(files, capsys):
    d = files["dir"]
    assert main(["weigh", str(files["cal"]), str(files["truck_h5"]), "--calibration-records",
                 str(files["cal_h5"]), "-o", str(d / "rw")]) == 0
    capsys.readouterr()
    page = d / "report.html"
    code, _out, err = _run(["report", d / "rw", files["cal"], files["cal_h5"], "-o", page,
                           "--title", "Test report"], capsys)
    assert code == 0, err
    text = page.read_text(encoding="utf-8")
    assert "<title>Test report</title>" in text
    assert text.count("data:image/png;base64,") >= 3
    assert "Moses static axle weights" in text and "summary.csv" in text


# --- bad input ------------------------------------------------------------------------------
def _bad(tmp_path, capsys, argv, *needles, output=None):
    before = set(tmp_path.rglob("*"))
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    assert code == 2
    err = out.err
    assert err.startswith("bwim: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for n in needles:
        assert n in err, err
    created = [p for p in set(tmp_path.rglob("*")) - before if p.is_file()]
    assert created == [], created
    if output is not None:
        assert not Path(output).exists()
    return err


def _csv_copy(src: Path, dst: Path, edit) -> Path:
    with open(src, newline="") as f:
        rows = list(csv.reader(f))
    edit(rows)
    with open(dst, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return dst


def test_bad_toml_files(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[bridge\nkind = 'plate'\n")
    _bad(tmp_path, capsys, ["simulate", bad, "-o", tmp_path / "r.h5"], "bad.toml",
         output=tmp_path / "r.h5")
    unknown = _scenario(tmp_path, "unknown.toml", {"poisson = 0.2": "poisson = 0.2\nstiffnes = 3"})
    _bad(tmp_path, capsys, ["simulate", unknown, "-o", tmp_path / "r.h5"], "stiffnes")
    off = _scenario(tmp_path, "off.toml", {"x = [3.0, 6.0, 9.0]": "x = [3.0, 6.0, 19.0]"})
    _bad(tmp_path, capsys, ["simulate", off, "-o", tmp_path / "r.h5"], "19")
    negative = _scenario(tmp_path, "neg.toml", {"E = 35e9": "E = -35e9"})
    _bad(tmp_path, capsys, ["simulate", negative, "-o", tmp_path / "r.h5"], "E")
    vehicle = _scenario(tmp_path, "veh.toml", {'"two_axle_truck"': '"flying_truck"'})
    _bad(tmp_path, capsys, ["simulate", vehicle, "-o", tmp_path / "r.h5"], "flying_truck")


def test_bad_csv_records(files, tmp_path, capsys):
    src, scen = files["truck_csv"], files["three"]
    out = tmp_path / "out.csv"

    def drop(rows):
        for r in rows:
            del r[-1]

    def extra(rows):
        rows[0].append("spare")
        for r in rows[1:]:
            r.append("0")

    def nan(rows):
        rows[5][3] = "nan"

    def backwards(rows):
        rows[5][0], rows[6][0] = rows[6][0], rows[5][0]

    for name, edit, needle in (("missing", drop, "y9_6"), ("extra", extra, "spare"),
                               ("nan", nan, "nan"), ("time", backwards, "time")):
        bad = _csv_copy(src, tmp_path / f"{name}.csv", edit)
        # each bad record is its own batch into the same summary: --force replaces it
        code = main(["identify", str(scen), str(bad), "-o", str(out), "--force"])
        err = capsys.readouterr().err
        # a bad record is a failed record (exit 1, issue 14): a summary row with its reason
        assert code == 1 and err.startswith(f"bwim: {bad.name} failed: "), err
        assert needle.lower() in err.lower(), err
        rows = list(csv.DictReader(out.open()))
        row = next(r for r in rows if r["record"] == bad.name)
        assert row["status"] == "failed" and needle.lower() in row["reason"].lower()
        assert not (tmp_path / f"{name}_forces.h5").exists()


def test_unwritable_output_paths(files, tmp_path, capsys):
    missing = tmp_path / "no" / "such" / "r.h5"
    _bad(tmp_path, capsys, ["simulate", files["cal"], "-o", missing], str(missing.parent),
         output=missing)
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    try:
        import os

        if os.access(locked, os.W_OK):  # running as root: permissions do not bind
            target = tmp_path / "dir.h5"
            target.mkdir()
            _bad(tmp_path, capsys, ["simulate", files["cal"], "-o", target], "folder")
        else:
            _bad(tmp_path, capsys, ["simulate", files["cal"], "-o", locked / "r.h5"],
                 "permission")
    finally:
        locked.chmod(0o700)
    _bad(tmp_path, capsys, ["simulate", files["cal"], "-o", tmp_path / "r.txt"], ".txt")
    _bad(tmp_path, capsys, ["report", files["cal_h5"], "-o", tmp_path / "nope" / "r.html"],
         "nope")


def test_bad_record_and_model_files(files, tmp_path, capsys):
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    # a bad record in a batch is a failed record: exit 1, its reason in the summary
    code = main([str(a) for a in ["identify", files["three"], junk, "-o", tmp_path / "s.csv"]])
    err = capsys.readouterr().err
    assert code == 1 and "junk.h5" in err and "not an HDF5 file" in err, err
    (tmp_path / "s.csv").unlink()
    (tmp_path / "manifest.json").unlink()
    _bad(tmp_path, capsys, ["calibrate", files["cal"], tmp_path / "gone.h5", "-o",
                            tmp_path / "m.toml"], "gone.h5", output=tmp_path / "m.toml")
    _bad(tmp_path, capsys, ["identify", files["three"], files["truck_h5"], "--bridge",
                            tmp_path / "gone.toml", "-o", tmp_path / "s.csv"], "gone.toml")


def test_demo_quick_runs_the_whole_chain(tmp_path, capsys, monkeypatch):
    """The command prints the demo report's transcript as the report echoes it.  The
    slab's first frequency is Lévy's exact value for a plate simply supported on two
    edges and free on the others (references.levy_ss_free_first_frequency; measured
    agreement 4e-6, bound 1e-5), which lies between the Euler–Bernoulli beam
    (D = E h³/12) and the plate strip (D = E h³/(12 (1 − ν²))).  The noise-free demo
    calibration returns the true E_x, E_y, μ (measured within 2.5e-5 relative)."""
    from bwim import paper
    from bwim.paper import demo

    reports, run_demo = [], demo.run_demo

    def spy(**kw):
        reports.append(run_demo(**kw))
        return reports[-1]

    monkeypatch.setattr(demo, "run_demo", spy)
    code, out, err = _run(["demo", "--quick", "--out", tmp_path / "demo", "--modes", "2"],
                          capsys)
    assert code == 0, err
    [report] = reports
    assert out.startswith(report.render() + "\n\nfiles in ")
    assert [t.header[0] for t in report.tables] == ["parameter", "method"]
    h, e, mu = paper.SLAB_THICKNESS, paper.SLAB_E, paper.SLAB_MU
    nu = paper.SLAB_POISSON
    beam = np.pi / (2 * paper.SLAB_LENGTH**2) * np.sqrt(e * h**3 / 12 / mu)
    levy = levy_ss_free_first_frequency(paper.SLAB_LENGTH, paper.SLAB_WIDTH,
                                        e * h**3 / (12 * (1 - nu**2)), mu, nu)
    assert beam < levy < beam / np.sqrt(1 - nu**2)
    assert report.frequencies.size == 2
    assert report.frequencies[0] == pytest.approx(levy, rel=1e-5)
    for needle in ("natural frequencies", "calibrated", "MFI, calibrated model",
                   "Moses, calibrated IL", "truth (static)"):
        assert needle in out
    page = (tmp_path / "demo" / "report.html").read_text(encoding="utf-8")
    assert page.count("data:image/png;base64,") >= 5
    # the report's calibration table: the paper's two stages beside the refined answer
    [cal_section] = [s for s in report.sections() if s.title.startswith("Calibration")]
    table = cal_section.tables[0]
    two = table.header.index("two stages")
    for row, key in zip(table.rows, ("E_x", "E_y", "mu"), strict=True):
        assert float(row[two]) == pytest.approx(report.calibration.two_stage[key][0],
                                                rel=1e-4)
    assert "two-stage error (%)" in page
    calibrated = load_bridge(tmp_path / "demo" / "calibrated_bridge.toml").params
    true = paper.slab_bridge().params
    for k in ("E_x", "E_y", "mu"):
        assert calibrated[k][0] == pytest.approx(true[k][0], rel=5e-5), k
    assert list((tmp_path / "demo").glob("*.png"))


def test_calibrate_mass_option(files, capsys):
    """--mass reaches calibrate: "free" on a record without a free vibration after the
    truck leaves (the scenario records no tail) keeps the stages' mass and says why, and,
    the fit being required, the calibration failed: exit 1 with one line on stderr, the
    model written for inspection (as for a site model that fails its self-check,
    docs/cli.md); "dynamic" prints no mass line; an unknown choice is exit 2 (the
    accuracy of the free-vibration mass is tests/validation/test_free_vibration_mass.py's).
    """
    d = files["dir"]
    code, out, err = _run(["calibrate", files["start"], files["cal_h5"], "-o",
                           d / "free.toml", "--method", "lm", "--mass", "free"], capsys)
    assert code == 1, err
    assert "mass: the stages' (the free-vibration fit failed" in out
    # stderr: the progress lines, then the one line of the failure
    lines = [x for x in err.strip().splitlines() if not x.startswith("bwim: calibrating:")]
    assert len(lines) == 1 and lines[0].startswith("bwim: the calibration did not succeed")
    assert "no free vibration after exit" in lines[0]
    assert (d / "free.toml").exists()
    code, out, err = _run(["calibrate", files["start"], files["cal_h5"], "-o",
                           d / "dynamic.toml", "--method", "lm", "--mass", "dynamic"], capsys)
    assert code == 0 and "free vibration" not in out and "mass:" not in out, out
    with pytest.raises(SystemExit) as exc:
        main(["calibrate", str(files["start"]), str(files["cal_h5"]), "--mass", "heavy"])
    assert exc.value.code == 2


@pytest.mark.parametrize(("keys", "named"), [
    ('mass = "free"', "[calibrate] mass"),
    ('method = "lm"\nseed = 3', "[calibrate] method, seed"),
])
def test_calibrate_refuses_the_scenario_keys_it_would_ignore_for_logger_files(
        small_site, tmp_path, capsys, keys, named):
    """``[calibrate]`` keys in a scenario with ``[logger]`` other than
    ``mesh_correction`` (the only one the site's road-free fit reads; it takes the mass
    from the free vibration itself) are refused like ``--mass``, not silently ignored:
    exit 2, one line naming the keys and the scenario, no model written."""
    text = Path(small_site.scenario).read_text(encoding="utf-8")
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(text + f"\n[calibrate]\n{keys}\n", encoding="utf-8")
    out = tmp_path / "model.toml"
    code = main(["calibrate", str(scenario), str(small_site.out_dir / "calibration"),
                 "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert named in err[0] and str(scenario) in err[0]
    assert not out.exists()
