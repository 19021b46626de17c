"""The README runs as written (issue 21: a README command failed on a fresh clone).

* Its real-installation walk-through (section "A real installation": the indented
  commands and the Python block, in order) runs in a fresh folder with the environment's
  ``bin`` first on the PATH, as `. .venv/bin/activate` leaves it: each command exits 0
  and the files the next one reads exist.
* The Python example (section "In Python") and the command-line tour (section "On the
  command line") runs the same way, but for
  ``bwim reproduce`` (minutes: ``make reproduce`` runs it).
* Every ``bwim`` command line in the README parses with the command's own parser.
"""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from bwim.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _section(title: str) -> str:
    start = README.index(f"## {title}")
    end = README.find("\n## ", start + 1)
    return README[start:end if end >= 0 else None]


def _steps(text: str) -> list[tuple[str, str]]:
    """("sh", line) for each 4-space-indented command and ("python", code) for each
    python block, in the order they appear (toml blocks are not steps)."""
    steps = []
    fence = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
    pos = 0
    for m in fence.finditer(text):
        steps += [("sh", line[4:]) for line in text[pos:m.start()].splitlines()
                  if line.startswith("    ") and line.strip()]
        if m.group(1) == "python":
            steps.append(("python", m.group(2)))
        pos = m.end()
    steps += [("sh", line[4:]) for line in text[pos:].splitlines()
              if line.startswith("    ") and line.strip()]
    return steps


def test_the_walk_through_is_what_the_test_runs():
    """The parser finds the section's eight commands and its Python block."""
    steps = _steps(_section("A real installation"))
    assert [kind for kind, _ in steps] == ["sh"] * 8 + ["python"]
    assert steps[0][1].startswith("python examples/test_day/make_test_day.py")


def _run(steps: list[tuple[str, str]], folder: Path) -> None:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    (folder / "examples").symlink_to(ROOT / "examples")
    for kind, code in steps:
        if kind == "sh":
            argv = shlex.split(code.split("#")[0])
            if argv[0] == "python":
                argv[0] = sys.executable
            done = subprocess.run(argv, cwd=folder, env=env, capture_output=True,
                                  text=True, timeout=300)
        else:
            done = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env,
                                  capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, (code, done.stderr[-2000:])


def test_the_python_example_runs(tmp_path):
    """Section "In Python": simulate, calibrate from a poor guess, identify."""
    steps = _steps(_section("In Python"))
    assert [kind for kind, _ in steps] == ["python"]
    _run(steps, tmp_path)


def test_the_command_line_tour_runs(tmp_path):
    """The section's commands in order, but ``bwim reproduce`` (``make reproduce``)."""
    steps = [s for s in _steps(_section("On the command line"))
             if not s[1].startswith("bwim reproduce")]
    assert len(steps) == 7
    _run(steps, tmp_path)
    assert (tmp_path / "report.html").stat().st_size > 0


def test_the_real_installation_walk_through_runs(tmp_path):
    _run(_steps(_section("A real installation")), tmp_path)
    assert (tmp_path / "site-report.html").stat().st_size > 0
    summary = (tmp_path / "site-out" / "summary.csv").read_text().splitlines()
    assert len(summary) > 12 and any(",weighed," in line for line in summary)
    assert (tmp_path / "site-out" / "gauge_health.csv").read_text().startswith("gauge,")
    # the FE model from the same logger files, then MFI weighing with it
    assert "accepted = true" in (tmp_path / "site-model.toml").read_text()
    mfi = (tmp_path / "site-out-mfi" / "summary.csv").read_text().splitlines()
    assert any(",weighed," in line and ",mfi," in line for line in mfi)
    # the same traffic as one long file, assessed by time: the same reference vehicles
    # found and weighed as from the event files (the README's claim)
    from bwim.accuracy import assess
    from bwim.io import read_reference, read_summary

    files = assess(read_summary(tmp_path / "site-out" / "summary.csv"),
                   read_reference(tmp_path / "site-day" / "reference.csv"))
    long = assess(read_summary(tmp_path / "site-out-long" / "summary.csv"),
                  read_reference(tmp_path / "site-day" / "reference_by_time.csv"))
    assert long.n_vehicles == files.n_vehicles >= 1 and long.n_reference == files.n_reference
    assert len(long.missing) == len(files.missing) and long.unmatched == long.ambiguous == ()
    assert (tmp_path / "site-out-long" / "events.csv").read_text().count("\n") == 13


def _bwim_lines() -> list[str]:
    lines = []
    for line in README.splitlines():
        if not line.startswith("    "):  # commands are indented code
            continue
        text = line.strip()
        for prefix in ("bwim ", ".venv/bin/bwim ", "$(BIN)/bwim "):
            if text.startswith(prefix):
                lines.append(text[len(prefix):].split("#")[0].strip())
    return lines


@pytest.mark.parametrize("line", _bwim_lines())
def test_every_bwim_command_line_parses(line):
    parser = build_parser()
    try:
        parser.parse_args(shlex.split(line))
    except SystemExit as exc:  # argparse's way of refusing
        pytest.fail(f"bwim {line}: exit {exc.code}")
