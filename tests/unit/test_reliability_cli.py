"""Issue 14 on the command line: no input overwritten, no run replacing another's output,
batches that survive a bad record and an interruption, one-line errors (exit 2) for the
reported tracebacks, options that are refused rather than replaced, scenario data paths
that cannot read files elsewhere.  Reference: the issue's reproductions, each run here."""

from __future__ import annotations

import csv
import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bwim.cli import main
from bwim.io.outputs import LOCK_NAME, MANIFEST_NAME, OutputLock, refuse_input_overwrite

from tests.cli_checks import one_line_error

ROOT = Path(__file__).resolve().parents[2]
BEAM = ROOT / "examples" / "beam.toml"


def _scenario(folder: Path, name: str = "s.toml", subs: dict[str, str] | None = None) -> Path:
    """The beam example with a short approach (fast), text substituted."""
    text = BEAM.read_text(encoding="utf-8").replace("approach = 50.0", "approach = 5.0")
    for old, new in (subs or {}).items():
        assert old in text, old
        text = text.replace(old, new)
    p = folder / name
    p.write_text(text, encoding="utf-8")
    return p


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("rel")
    scen = _scenario(d)
    assert main(["simulate", str(scen), "-o", str(d / "a.h5")]) == 0
    assert main(["simulate", str(scen), "-o", str(d / "b.csv")]) == 0
    return {"dir": d, "scen": scen, "a": d / "a.h5", "b": d / "b.csv"}


def _tmp_files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if p.name.endswith(".tmp")]


# --- never overwrite an input; never an existing output without --force -------------------
def test_outputs_never_overwrite_inputs(files, tmp_path, capsys):
    b = tmp_path / "b.csv"
    b.write_bytes(files["b"].read_bytes())
    before = b.read_bytes()
    code, _, err = _run(["identify", files["scen"], b, "-o", b], capsys)
    one_line_error(code, err, "input")
    assert b.read_bytes() == before
    scen = _scenario(tmp_path)
    text = scen.read_text()
    code, _, err = _run(["calibrate", scen, files["a"], "-o", scen], capsys)
    one_line_error(code, err, "input")
    assert scen.read_text() == text
    with pytest.raises(Exception, match="input"):
        refuse_input_overwrite([tmp_path / "." / "s.toml"], [scen])


def test_existing_output_needs_force(files, tmp_path, capsys):
    out = tmp_path / "r.h5"
    out.write_text("precious")
    code, _, err = _run(["simulate", files["scen"], "-o", out], capsys)
    one_line_error(code, err, "--force")
    assert out.read_text() == "precious"
    code, _, err = _run(["simulate", files["scen"], "-o", out, "--force"], capsys)
    assert code == 0, err
    assert out.read_bytes()[:4] == b"\x89HDF"


# --- one run per output folder -------------------------------------------------------------
def test_output_folder_lock(files, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    with OutputLock(out):  # another run holds the folder
        code, _, err = _run(["identify", files["scen"], files["a"], "-o", out], capsys)
        one_line_error(code, err, LOCK_NAME)
        assert not (out / "summary.csv").exists()
    code, _, err = _run(["identify", files["scen"], files["a"], "-o", out], capsys)
    assert code == 0, err
    assert not (out / LOCK_NAME).exists()  # released at exit
    (out / LOCK_NAME).write_text("999999999\n")  # a killed run's lock is taken over
    code, _, err = _run(["identify", files["scen"], files["a"], "-o", out, "--force"], capsys)
    assert code == 0, err


# --- batches ------------------------------------------------------------------------------
def _summary(out):
    return list(csv.DictReader((out / "summary.csv").open()))


def test_bad_record_does_not_abort_the_batch_and_resume_retries_it(files, tmp_path, capsys):
    """A bad record is a failed row (exit 1); --resume skips the records done and retries
    the failed one, which, once repaired, is processed (the resume rule of bwim.batch)."""
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    out = tmp_path / "out"
    code, stdout, err = _run(["identify", files["scen"], files["a"], junk, files["b"], "-o",
                              out], capsys)
    assert code == 1, err
    assert "junk.h5 failed" in err and "not an HDF5 file" in err
    by = {r["record"]: r for r in _summary(out)}
    assert by["junk.h5"]["status"] == "failed" and by["junk.h5"]["reason"]
    assert by["a.h5"]["status"] == by["b.csv"]["status"] == "weighed"
    assert float(by["a.h5"]["gvw_kN"]) > 0
    assert (out / "a_forces.h5").exists() and (out / "b_forces.h5").exists()
    assert (out / MANIFEST_NAME).exists() and not _tmp_files(tmp_path)
    rows = _summary(out)
    # the resume skips the records done and keeps their results; the failed one is retried
    stamp = (out / "a_forces.h5").stat().st_mtime_ns
    code, stdout, err = _run(["identify", files["scen"], files["a"], junk, files["b"], "-o",
                              out, "--resume"], capsys)
    assert code == 1 and "2 done before" in stdout and "junk.h5 failed" in err, stdout
    assert (out / "a_forces.h5").stat().st_mtime_ns == stamp
    assert _summary(out) == rows
    junk.write_bytes(files["a"].read_bytes())  # repaired
    code, stdout, err = _run(["identify", files["scen"], files["a"], junk, files["b"], "-o",
                              out, "--resume"], capsys)
    assert code == 0 and "2 done before" in stdout, err
    by = {r["record"]: r for r in _summary(out)}
    assert by["junk.h5"]["status"] == "weighed" and (out / "junk_forces.h5").exists()
    # --force without --resume redoes everything
    code, stdout, _ = _run(["identify", files["scen"], files["a"], "-o", out, "--force"],
                           capsys)
    assert code == 0 and "done before" not in stdout
    assert (out / "a_forces.h5").stat().st_mtime_ns != stamp


def test_a_second_run_into_the_folder_resumes_or_is_refused(files, tmp_path, capsys):
    """Without --resume a second run would replace the first's summary: refused.  With
    --resume it adds its records and keeps the first's rows (a resume never drops a row);
    a batch of another scenario is refused even with --resume."""
    out = tmp_path / "out"
    code, _, err = _run(["identify", files["scen"], files["a"], "-o", out], capsys)
    assert code == 0, err
    first = (out / "summary.csv").read_text()
    code, _, err = _run(["identify", files["scen"], files["b"], "-o", out], capsys)
    one_line_error(code, err, "summary.csv")
    assert (out / "summary.csv").read_text() == first
    code, stdout, err = _run(["identify", files["scen"], files["b"], "-o", out, "--resume"],
                             capsys)
    assert code == 0, err
    assert [r["record"] for r in _summary(out)] == ["b.csv", "a.h5"]
    code, stdout, _ = _run(["identify", files["scen"], files["a"], "-o", out, "--resume"],
                           capsys)
    assert code == 0 and "1 done before" in stdout
    assert {r["record"] for r in _summary(out)} == {"a.h5", "b.csv"}
    other = _scenario(tmp_path)
    code, _, err = _run(["identify", other, files["a"], "-o", out, "--resume"], capsys)
    one_line_error(code, err, "another batch")


def test_interrupt_keeps_finished_records_and_leaves_no_tmp(files, tmp_path, capsys,
                                                            monkeypatch):
    from bwim.batch import events

    real = events.identify_item
    calls = []

    def one(job, item):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job, item)

    monkeypatch.setattr(events, "identify_item", one)
    out = tmp_path / "out"
    code, _, err = _run(["identify", files["scen"], files["a"], files["b"], "-o", out], capsys)
    assert code == 130 and "interrupted" in err
    assert (out / "a_forces.h5").exists() and not (out / "b_forces.h5").exists()
    assert not _tmp_files(tmp_path) and not (out / LOCK_NAME).exists()
    monkeypatch.setattr(events, "identify_item", real)
    code, stdout, _ = _run(["identify", files["scen"], files["a"], files["b"], "-o", out,
                            "--resume"], capsys)
    assert code == 0 and "1 done before" in stdout


def test_jobs_two_writes_what_jobs_one_writes(files, tmp_path, capsys):
    """The parallel path (this process and a loky worker, the bridge pickled once) against
    the serial one (reference: equivalence): the same summary byte for byte, the same
    manifest entries and the same forces in every result, a bad record among the good."""
    import json

    import numpy as np

    from bwim.io import read_identification

    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    c = tmp_path / "c.h5"
    c.write_bytes(files["a"].read_bytes())
    recs = [files["a"], junk, files["b"], c]
    outs = []
    for jobs in (1, 2):
        out = tmp_path / f"jobs{jobs}"
        code, _, err = _run(["identify", files["scen"], *recs, "-o", out, "--jobs", jobs],
                            capsys)
        assert code == 1 and "junk.h5 failed" in err, err
        outs.append(out)
    one, two = outs
    assert (one / "summary.csv").read_bytes() == (two / "summary.csv").read_bytes()
    entries = [json.loads((o / MANIFEST_NAME).read_text())["entries"] for o in outs]
    assert entries[0] == entries[1]
    for name in ("a_forces.h5", "b_forces.h5", "c_forces.h5"):
        x, y = read_identification(one / name), read_identification(two / name)
        np.testing.assert_array_equal(x.axle_forces, y.axle_forces)
        np.testing.assert_array_equal(x.axle_weights, y.axle_weights)


def test_sigterm_stops_the_worker_pool(files, tmp_path):
    """``identify --jobs 2`` under SIGTERM: the command exits and no worker survives."""
    psutil = pytest.importorskip("psutil")
    recs = tmp_path / "recs"
    recs.mkdir()
    for k in range(12):
        (recs / f"r{k:02d}.h5").write_bytes(files["a"].read_bytes())
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen([sys.executable, "-m", "bwim.cli", "identify", str(files["scen"]),
                             str(recs), "-o", str(tmp_path / "out"), "--jobs", "2"],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    me = psutil.Process(proc.pid)
    children: list = []
    deadline = time.time() + 60
    while time.time() < deadline and proc.poll() is None:
        children = me.children(recursive=True)
        if sum("python" in (c.name() or "") for c in children) >= 2:
            break
        time.sleep(0.2)
    assert proc.poll() is None, "finished before the test could interrupt it"
    time.sleep(1.0)
    children = me.children(recursive=True)
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("bwim identify ignored SIGTERM")
    _, alive = psutil.wait_procs(children, timeout=10)
    for p in alive:
        p.kill()
    assert not alive, alive
    assert proc.returncode == 130, proc.stderr.read()
    assert not _tmp_files(tmp_path) and not (tmp_path / "out" / LOCK_NAME).exists()


# --- tracebacks that became one line -------------------------------------------------------
def test_full_disk_when_writing_hdf5(files, tmp_path, capsys, monkeypatch):
    from bwim.io import records

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(records, "_put_record", full)
    out = tmp_path / "r.h5"
    code, _, err = _run(["simulate", files["scen"], "-o", out], capsys)
    one_line_error(code, err, "no space left")
    assert not out.exists() and not _tmp_files(tmp_path)


def test_record_name_not_utf8(files, tmp_path, capsys):
    raw = os.fsencode(tmp_path) + b"/rec\xff.h5"
    with open(raw, "wb") as f:
        f.write(files["a"].read_bytes())
    code, _, err = _run(["identify", files["scen"], os.fsdecode(raw), "-o",
                              tmp_path / "out"], capsys)
    assert code == 0, err
    assert "rec\ufffd.h5" in (tmp_path / "out" / "summary.csv").read_text(encoding="utf-8")
    bad = os.fsencode(tmp_path) + b"/gone\xfe.h5"
    code, _, err = _run(["identify", files["scen"], os.fsdecode(bad), "-o", tmp_path / "o2"],
                        capsys)
    assert code in (1, 2) and "Traceback" not in err


def test_reproduce_out_is_a_file_or_read_only(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    code, _, err = _run(["reproduce", "5.1", "--quick", "--out", f], capsys)
    one_line_error(code, err, "file")
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o500)
    try:
        if os.access(ro, os.W_OK):
            pytest.skip("permissions are not enforced for root")
        code, _, err = _run(["reproduce", "5.1", "--quick", "--out", ro / "sub"], capsys)
        one_line_error(code, err, "ro")
    finally:
        ro.chmod(0o700)


@pytest.mark.parametrize(("subs", "needle"), [
    ({"speed = 22.0 ": "speed = nan "}, "speed"),
    ({"sampling_rate = 500.0": "sampling_rate = 0.5"}, "sampling_rate"),
    ({"[run]\n": "[run]\nnoise = 1e300\n"}, "noise"),
    ({"[run]\n": "[identify]\nn_lam = 0\n\n[run]\n"}, "n_lam"),
    ({"[run]\n": "[identify]\nlam_range = [1e3, 1e-6]\n\n[run]\n"}, "lam_range"),
    ({"[run]\n": "[calibrate]\npopulation = 0\n\n[run]\n"}, "population"),
    ({"[run]\n": "[calibrate]\nn_jobs = -5\n\n[run]\n"}, "n_jobs"),
])
def test_scenario_values_refused(tmp_path, capsys, subs, needle):
    scen = _scenario(tmp_path, subs=subs)
    code, _, err = _run(["simulate", scen, "-o", tmp_path / "r.h5"], capsys)
    one_line_error(code, err, needle)
    assert "road" not in err


def test_jobs_minus_five_refused(files, tmp_path, capsys):
    for argv in (["identify", files["scen"], files["a"], "-o", tmp_path / "o", "--jobs", "-5"],
                 ["calibrate", files["scen"], files["a"], "-o", tmp_path / "m.toml",
                  "--jobs", "-5"]):
        code, _, err = _run(argv, capsys)
        one_line_error(code, err, "--jobs")


# --- security ---------------------------------------------------------------------------
def test_profile_outside_the_scenario_folder_is_refused(tmp_path, capsys):
    sub = tmp_path / "deep" / "er"
    sub.mkdir(parents=True)
    secret = tmp_path / "secret.csv"
    secret.write_text("root:x:0:0:root:/root:/bin/bash\n")
    road = '[road]\nprofile = "../../secret.csv"\n'
    scen = _scenario(sub, subs={'[road]\nroughness = "A"': road, "seed = 3\n": ""})
    code, _, err = _run(["simulate", scen, "-o", tmp_path / "r.h5"], capsys)
    one_line_error(code, err, "outside")
    scen = _scenario(sub, subs={'[road]\nroughness = "A"': '[road]\nprofile = "/etc/passwd"',
                                "seed = 3\n": ""})
    code, _, err = _run(["simulate", scen, "-o", tmp_path / "r.h5"], capsys)
    one_line_error(code, err, "outside")
    # a file inside the folder that is not a profile: its content is never echoed
    (sub / "p.csv").write_text("root:x:0:0:root:/root:/bin/bash\n1,2\n")
    scen = _scenario(sub, subs={'[road]\nroughness = "A"': '[road]\nprofile = "p.csv"',
                                "seed = 3\n": ""})
    code, _, err = _run(["simulate", scen, "-o", tmp_path / "r.h5"], capsys)
    one_line_error(code, err, "not a road profile")
    assert "bin/bash" not in err and "x:0:0" not in err


def test_weigh_refuses_to_write_into_its_records_folder(small_site, tmp_path, capsys):
    """``-o`` the records' own folder: its outputs would sit among the logger files and be
    read as records by the next ``bwim weigh`` of that folder (review of stop 32: a
    ``--resume`` then failed, another output folder gave 5 failed rows).  Exit 2, one
    line, the folder unchanged."""
    import shutil

    records = tmp_path / "traffic"
    shutil.copytree(small_site.out_dir / "traffic", records)
    before = sorted(p.name for p in records.iterdir())
    code, _, err = _run(["weigh", small_site.scenario, records, "--calibration-records",
                         small_site.out_dir / "calibration", "-o", records], capsys)
    one_line_error(code, err, "is the input folder")
    assert sorted(p.name for p in records.iterdir()) == before
