"""One-line errors and limits on the command line (issue 22 items 5-6, issue 21 item 5):
a reader that closes the pipe, a NUL byte in a path, a deeply nested TOML file, a full
disk while an output is written, unreadable calibration runs (their real reason), a
decimal comma, ``--version``, ``-o`` everywhere; non-regular files refused from their
``stat``, the memory limit on ``weigh``, logger files over the size limit, and pool
workers that die with their parent.  The expected outcomes are the issues' (one line,
exit 2, nothing written; no process left), not the code's output."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bwim.cli import COMMANDS, main
from bwim.synthetic import make_test_day

from tests.cli_checks import one_line_error

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    return make_test_day(tmp_path_factory.mktemp("limits") / "day", site="short-span-4-lane",
                         seed=4, n_calibration=6, n_traffic=2, n_calibration_day_traffic=0,
                         mesh=0.6)


def _weigh_argv(day, out, *, scenario=None, calibration=None, records=None) -> list[str]:
    return ["weigh", str(scenario or day.scenario),
            *map(str, records or [day.traffic[0].parent]),
            "--calibration-records", str(calibration or day.calibration[0].parent),
            "-o", str(out)]


def _tmp_files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if p.name.endswith(".tmp")]


# --- one-line errors -----------------------------------------------------------------------
_PROGRESS_EVERY_ITEM = ("import sys; from bwim.cli import common, main; "
                        "common.Progress.every = 0.0; sys.exit(main(sys.argv[1:]))")


@pytest.mark.parametrize("merged", [False, True])
def test_weigh_into_a_closed_pipe(day, tmp_path, merged):
    """``bwim weigh ... | head -1`` (and ``2>&1 | head -1``): the reader is gone before
    the first line; no traceback, the exit code is the command's own (0) and the summary
    is written whole.  Progress is printed for every record (its period set to zero) so
    that stderr is written to as well."""
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-c", _PROGRESS_EVERY_ITEM,
                             *_weigh_argv(day, out)], env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT if merged else subprocess.PIPE)
    proc.stdout.close()  # the reader goes away at once
    _, err = proc.communicate(timeout=120)
    err = (err or b"").decode()
    assert proc.returncode == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    if not merged:
        assert f"bwim: weighing: {len(day.traffic)}/{len(day.traffic)}" in err
    lines = (out / "summary.csv").read_text().splitlines()
    assert len(lines) >= 1 + len(day.traffic)


def test_nul_byte_in_paths(day, tmp_path, capsys):
    for argv in (["simulate", "sc\x00enario.toml"],
                 ["simulate", str(ROOT / "examples" / "beam.toml"), "-o",
                  str(tmp_path / "r\x00.h5")],
                 _weigh_argv(day, tmp_path / "o1", records=[str(tmp_path / "e\x00.txt")]),
                 _weigh_argv(day, tmp_path / "o\x002")):
        one_line_error(main(argv), capsys.readouterr().err)
    assert not list(tmp_path.iterdir())


def test_deeply_nested_toml(tmp_path, capsys):
    scenario = tmp_path / "deep.toml"
    scenario.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    code = main(["simulate", str(scenario), "-o", str(tmp_path / "r.h5")])
    one_line_error(code, capsys.readouterr().err, "nested too deeply")
    assert not (tmp_path / "r.h5").exists()


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc/self/fd")
@pytest.mark.parametrize("name", ["calibration_runs.csv", "influence_lines.h5", "summary.csv"])
def test_full_disk_while_an_output_is_written(day, tmp_path, capsys, monkeypatch, name):
    """The disk fills up while ``name`` is written (its flush to disk fails with ENOSPC):
    one line naming it, no half-written file, no temporary file left."""
    real = os.fsync

    def fsync(fd):
        if f".{name}." in os.readlink(f"/proc/self/fd/{fd}"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    out = tmp_path / "out"
    code = main(_weigh_argv(day, out))
    one_line_error(code, capsys.readouterr().err, name, "no space left on device")
    assert not (out / name).exists()
    assert not _tmp_files(tmp_path)


def test_unreadable_calibration_runs_give_their_reason(day, tmp_path, capsys):
    """A wrong ``[logger] columns`` list (one column short): every run is unreadable; the
    message gives the first file's own reason and how many failed, not "give at least
    one calibration run"."""
    text = day.scenario.read_text()
    assert '"-", "-",\n]' in text
    scenario = tmp_path / "site.toml"
    scenario.write_text(text.replace('"-", "-",\n]', '"-",\n]'))
    code = main(_weigh_argv(day, tmp_path / "out", scenario=scenario))
    err = capsys.readouterr().err
    one_line_error(code, err, f"{len(day.calibration)} file(s) unreadable",
                    day.calibration[0].name, "columns of the format")
    assert "give at least one calibration run" not in err


def test_decimal_comma_is_hinted(day, tmp_path, capsys):
    runs = tmp_path / "runs"
    runs.mkdir()
    for p in day.calibration:
        (runs / p.name).write_text(p.read_text().replace(".", ","))
    code = main(_weigh_argv(day, tmp_path / "out", calibration=runs))
    one_line_error(code, capsys.readouterr().err, 'decimal = ","')


def test_version(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"bwim {version('bwim')}"


@pytest.mark.parametrize("command", [c for c in COMMANDS])
def test_every_command_takes_o(command):
    """``-o``, ``--out`` and ``--output`` name the same output on every command."""
    from bwim.cli import build_parser

    parser = build_parser()
    needed = {"simulate": ["s.toml"], "calibrate": ["s.toml", "r.h5"],
              "identify": ["s.toml", "r.h5"], "weigh": ["s.toml", "r", "--influence", "i.h5"],
              "accuracy": ["x.csv", "--reference", "r.csv"], "report": ["x"],
              "demo": [], "reproduce": ["5.1"]}[command.name]
    seen = set()
    for flag in ("-o", "--out", "--output"):
        args = vars(parser.parse_args([command.name, *needed, flag, "target"]))
        seen.add(next(k for k, v in args.items() if v == "target"))
    assert len(seen) == 1


# --- limits --------------------------------------------------------------------------------
@pytest.mark.skipif(not hasattr(os, "mkfifo") or not hasattr(signal, "alarm"),
                    reason="needs FIFOs and SIGALRM")
@pytest.mark.parametrize("where", ["records", "calibration"])
def test_fifo_and_device_refused_at_once(day, tmp_path, capsys, where):
    """A FIFO (or /dev/null) given as a record: refused from its stat, exit 2, never
    opened (opening a FIFO for reading would wait for a writer: the alarm ends a hang)."""
    fifo = tmp_path / "event.txt"
    os.mkfifo(fifo)

    def hang(signum, frame):
        raise TimeoutError("the FIFO was opened for reading")

    old = signal.signal(signal.SIGALRM, hang)
    try:
        for path in (fifo, Path(os.devnull)):
            kw = {where: [path]} if where == "records" else {"calibration": path}
            signal.alarm(20)
            code = main(_weigh_argv(day, tmp_path / "out", **kw))
            signal.alarm(0)
            one_line_error(code, capsys.readouterr().err, str(path), "not a regular file")
            assert not (tmp_path / "out" / "summary.csv").exists()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_garbage_memory_limit_refused_first(day, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("BWIM_MEMORY_LIMIT", "lots")
    out = tmp_path / "out"
    code = main(_weigh_argv(day, out))
    one_line_error(code, capsys.readouterr().err, "BWIM_MEMORY_LIMIT: not a size: 'lots'")
    assert not out.exists()


def test_weigh_honours_the_memory_limit(day, tmp_path, capsys):
    """A limit too small for one logger file (a few MiB of values): refused, with the
    need and the limit in the message; nothing weighed."""
    code = main(["--memory-limit", "64K", *_weigh_argv(day, tmp_path / "out")])
    one_line_error(code, capsys.readouterr().err, "more than the limit of 64 KiB")
    assert not (tmp_path / "out" / "summary.csv").exists()


def test_logger_file_over_the_size_limit_refused_by_size(day, tmp_path, capsys):
    """A 300 MiB logger file (sparse: no disk used) is refused from its size, at once."""
    from bwim.io.logger import MAX_LOGGER_BYTES

    runs = tmp_path / "runs"
    runs.mkdir()
    big = runs / "huge.txt"
    with big.open("wb") as f:
        f.truncate(MAX_LOGGER_BYTES + 1)
    t0 = time.perf_counter()
    code = main(_weigh_argv(day, tmp_path / "out", calibration=runs))
    elapsed = time.perf_counter() - t0
    one_line_error(code, capsys.readouterr().err, "huge.txt",
                    f"more than max_bytes = {MAX_LOGGER_BYTES}, the logger file limit")
    assert elapsed < 5.0


_CHILD = """
import os, sys, time
from pathlib import Path
from bwim.batch import Processes, Task

def run(shared, item):
    (Path(sys.argv[1]) / f"{os.getpid()}.pid").write_text(str(item))
    time.sleep(120)
    return item

if __name__ == "__main__":
    for _ in Processes(2).map(Task(run=run), [1, 2, 3], None):
        pass
"""


def test_pool_workers_die_with_their_parent(tmp_path):
    """``kill -9`` of a process running a pool (Processes(2)): its worker is gone within
    a few seconds (issue 22: workers of ``identify --jobs 2`` alive 6 minutes later)."""
    psutil = pytest.importorskip("psutil")
    script = tmp_path / "child.py"
    script.write_text(_CHILD)
    proc = subprocess.Popen([sys.executable, str(script), str(tmp_path)], env=ENV)
    try:
        deadline = time.time() + 60
        while time.time() < deadline and len(list(tmp_path.glob("*.pid"))) < 2:
            time.sleep(0.1)
        pids = {int(p.stem) for p in tmp_path.glob("*.pid")}
        assert proc.pid in pids and len(pids) == 2, pids
        [worker] = pids - {proc.pid}
        proc.kill()
        proc.wait()
        deadline = time.time() + 5
        while time.time() < deadline:
            try:
                if psutil.Process(worker).status() == psutil.STATUS_ZOMBIE:
                    break
            except psutil.NoSuchProcess:
                break
            time.sleep(0.1)
        else:
            psutil.Process(worker).kill()
            pytest.fail("the pool's worker outlived its parent by 5 s")
    finally:
        if proc.poll() is None:
            proc.kill()


@pytest.mark.parametrize(("option", "value"), [("--gvw-limit", "-5"), ("--axle-limit", "nan")])
def test_a_negative_overload_limit_is_named_in_its_own_unit(tmp_path, capsys, option, value):
    """``bwim report --gvw-limit -5``: one line in kN, the option's unit (review of stop
    32: "got -5000.0", the value in N), exit 2, no report written."""
    summary = tmp_path / "summary.csv"
    summary.write_text("record,status,reason\ne1.txt,failed,unreadable\n", encoding="utf-8")
    out = tmp_path / "report.html"
    code = main(["report", str(summary), option, value, "-o", str(out)])
    one_line_error(code, capsys.readouterr().err, f"{option} must be a load in kN",
                   f"got {value}")
    assert not out.exists()
