"""Wrong declarations and data loss on the realistic site (issue 22): refused with the
reason, never a silent wrong weight; nothing lost.

Data: the realistic simulated day of ``bench_faults`` (``short-span-4-lane``, seed 41,
never used while developing; 12 calibration runs, 80 traffic events; cached under
``BWIM_BENCH_CACHE``).  Every case runs ``bwim weigh`` (``bwim report`` and ``bwim demo``
for ``report.html``) in-process, as a user would:

* **declarations** (the scenario's ``[vehicle]`` edited the way the mistake would edit
  it): as declared (the control), axle loads in kg instead of N, spacings each 0.2 m
  long, each 0.2 m short, the traffic folder given as ``--calibration-records``, loads in
  reverse order, a 3-axle truck declared for the 5-axle one (its first two spacings, the
  last three loads as one).  Expected: the control weighed, every mistake refused.
* **data loss**: ``bwim weigh --resume`` given half the records of the first run (every
  row of the first run must be kept, unchanged), and each output of a command
  (``summary.csv``, ``calibration_runs.csv``, ``influence_lines.h5``,
  ``gauge_health.csv`` of ``weigh``; ``report.html`` of ``report`` and ``demo``)
  already in the output folder: refused without ``--force``, the file unchanged.

Printed per case: the expected and the actual outcome (refused with its reason, or
weighed with the weights' median error against ``truth.csv``) and the **silent wrong
weights**: a weight written with empty flags and more than 10 % from the true GVW (the
issue's measure; target 0).  The traffic vehicles are matched to the truth by record,
lane and direction (a record with two vehicles in one lane and direction is skipped).
"""

from __future__ import annotations

import contextlib
import csv
import io
import re
import shutil
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from benchmarks.bench_faults import site_day
from bwim.cli import main as bwim

#: A weight this far from the truth (relative), written with empty flags, is silent and wrong.
SILENT = 0.10
#: The outputs of ``bwim weigh`` on a site that an existing file of must stop.
WEIGH_OUTPUTS = ("summary.csv", "calibration_runs.csv", "influence_lines.h5",
                 "gauge_health.csv")
#: A file's content that no command writes.
PRECIOUS = b"an earlier result: keep me\n"


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """One case: what was expected and what happened.

    Attributes
    ----------
    case : str
    expected : str
        ``"refused"``, ``"weighed"`` or ``"kept"`` (the earlier output left whole).
    actual : str
        What happened, one line (the reason of a refusal; the weights' error).
    as_expected : bool
    silent : int
        Silent wrong weights written (see the module docstring).
    """

    case: str
    expected: str
    actual: str
    as_expected: bool
    silent: int = 0

    def row(self, width: int = 90) -> list[object]:
        text = self.actual if len(self.actual) <= width else self.actual[:width - 1] + "…"
        return [self.case, self.expected, text, "yes" if self.as_expected else "NO",
                f"{self.silent} (0)"]


def _run(args: Sequence[str]) -> tuple[int, str]:
    """``bwim ARGS`` in this process: its exit code and its last line on stderr."""
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = bwim([str(a) for a in args])
    lines = err.getvalue().strip().splitlines()
    return code, (lines[-1].removeprefix("bwim: error: ") if lines else "")


def _vehicle(text: str, key: str, values: Sequence[float]) -> str:
    """The scenario's ``key = [...]`` line replaced by ``values``."""
    new, n = re.subn(rf"^{key} = \[.*\]$",
                     f"{key} = [" + ", ".join(f"{v:.6g}" for v in values) + "]", text,
                     flags=re.MULTILINE)
    if n != 1:
        raise ValueError(f"{key} is not once in the scenario")
    return new


def _declared(text: str, key: str) -> np.ndarray:
    match = re.search(rf"^{key} = \[(.*)\]$", text, flags=re.MULTILINE)
    return np.array([float(v) for v in match.group(1).split(",")])


def _truth(day: Path) -> dict[tuple[str, str, str], float | None]:
    """True GVW (kN) by (record, lane, direction); None when two vehicles share them."""
    out: dict[tuple[str, str, str], float | None] = {}
    with open(day / "truth.csv", newline="") as f:
        for r in csv.DictReader(f):
            key = (r["record"], r["lane"], r["direction"])
            out[key] = None if key in out else float(r["gvw_kN"])
    return out


def _rows(summary: Path) -> list[dict[str, str]]:
    with open(summary, newline="") as f:
        return list(csv.DictReader(f))


def weighed(summary: Path, truth: dict) -> tuple[int, int, float]:
    """Weights written in ``summary``: how many, how many silent and wrong, and their
    median relative error against the truth (nan when none is matched)."""
    errors, silent, n = [], 0, 0
    for r in _rows(summary):
        if not r["gvw_kN"]:
            continue
        n += 1
        true = truth.get((r["record"], r["lane"], r["direction"]))
        if true is None:
            continue
        err = float(r["gvw_kN"]) / true - 1.0
        errors.append(err)
        silent += (not r["flags"]) and abs(err) > SILENT
    return n, silent, float(np.median(errors)) if errors else float("nan")


def declaration_cases(day: Path, work: Path, names: Sequence[str] | None = None
                      ) -> list[Outcome]:
    """The declaration cases (module docstring) on the day in folder ``day``, written
    under ``work``; ``names`` picks some (default all)."""
    text = (day / "scenario.toml").read_text()
    loads, spacings = _declared(text, "axle_loads"), _declared(text, "axle_spacings")
    cases = {
        "as declared (control)": ("weighed", text, "calibration"),
        "axle loads in kg, not N": ("refused", _vehicle(text, "axle_loads", loads / 9.81),
                                    "calibration"),
        "spacings each 0.2 m long": ("refused", _vehicle(text, "axle_spacings",
                                                         spacings + 0.2), "calibration"),
        "spacings each 0.2 m short": ("refused", _vehicle(text, "axle_spacings",
                                                          spacings - 0.2), "calibration"),
        "traffic as calibration records": ("refused", text, "traffic"),
        "loads in reverse order": ("refused", _vehicle(text, "axle_loads", loads[::-1]),
                                   "calibration"),
        "3-axle truck declared for the 5-axle": ("refused", _vehicle(_vehicle(
            text, "axle_loads", [*loads[:2], loads[2:].sum()]), "axle_spacings",
            spacings[:2]), "calibration"),
    }
    truth = _truth(day)
    out = []
    for k, (name, (expected, scenario, runs)) in enumerate(cases.items()):
        if names is not None and name not in names:
            continue
        folder = work / f"declaration-{k}"
        folder.mkdir(parents=True)
        (folder / "site.toml").write_text(scenario)
        code, err = _run(["weigh", folder / "site.toml", day / "traffic",
                          "--calibration-records", day / runs, "-o", folder / "out"])
        summary = folder / "out" / "summary.csv"
        if code == 2 or not summary.exists():
            out.append(Outcome(case=name, expected=expected, actual=f"refused: {err}",
                               as_expected=expected == "refused"))
            continue
        n, silent, median = weighed(summary, truth)
        out.append(Outcome(case=name, expected=expected,
                           actual=f"weighed: {n} weights, median error {median:+.1%}",
                           as_expected=expected == "weighed", silent=silent))
    return out


def data_loss_cases(day: Path, work: Path, *, demo: bool = True) -> list[Outcome]:
    """The data-loss cases (module docstring) on the day in folder ``day``, written under
    ``work``; ``demo``: also ``bwim demo`` over an existing ``report.html``."""
    scenario, runs = day / "scenario.toml", day / "calibration"
    records = sorted((day / "traffic").iterdir())
    out = []
    # --resume given half the records: every row of the first run kept, unchanged
    first = work / "resume"
    code, err = _run(["weigh", scenario, *records, "--calibration-records", runs,
                      "-o", first])
    before = _rows(first / "summary.csv")
    code, err = _run(["weigh", scenario, *records[::2], "--calibration-records", runs,
                      "-o", first, "--resume"])
    after = _rows(first / "summary.csv")
    kept = sum(r in after for r in before)
    out.append(Outcome(case=f"weigh --resume on {len(records[::2])} of {len(records)} records",
                       expected="kept", actual=f"{kept} of {len(before)} earlier rows kept "
                       f"(exit {code})", as_expected=kept == len(before)))
    # an output of a command already there: refused without --force, left whole
    commands = {name: ["weigh", scenario, records[0], "--calibration-records", runs, "-o"]
                for name in WEIGH_OUTPUTS}
    commands["report.html"] = ["report", first / "summary.csv", "-o"]
    if demo:
        commands["report.html (demo)"] = ["demo", "--quick", "--out"]
    for k, (name, args) in enumerate(commands.items()):
        folder = work / f"existing-{k}"
        folder.mkdir()
        target = folder / name.split()[0]
        target.write_bytes(PRECIOUS)
        code, err = _run([*args, target if args[0] == "report" else folder])
        err = err.replace(str(folder) + "/", "")
        whole = target.read_bytes() == PRECIOUS
        out.append(Outcome(case=f"existing {name} without --force", expected="refused",
                           actual=(f"refused: {err}" if code == 2 else f"exit {code}")
                           + ("" if whole else "; the file was replaced"),
                           as_expected=code == 2 and whole))
    return out


def run(day: Path, names: Sequence[str] | None = None, *, loss: bool = True,
        demo: bool = True) -> list[Outcome]:
    """Every case (``names``: some declaration cases; ``loss``: the data-loss cases) in a
    temporary folder."""
    with tempfile.TemporaryDirectory(prefix="bwim-declarations-") as tmp:
        work = Path(tmp)
        out = declaration_cases(day, work, names)
        if loss:
            out += data_loss_cases(day, work, demo=demo)
        shutil.rmtree(work, ignore_errors=True)
    return out


def main() -> None:
    t0 = time.perf_counter()
    out = run(site_day())
    silent = sum(o.silent for o in out)
    print_table(f"Wrong declarations and data loss on the realistic site (seed 41, bwim weigh "
                f"as a user runs it; {sum(o.as_expected for o in out)} of {len(out)} cases "
                f"as expected, {silent} silent wrong weights; "
                f"{time.perf_counter() - t0:.0f} s)",
                ["case", "expected", "actual", "as expected",
                 "silent wrong weights > 10 % (target)"], [o.row() for o in out])


if __name__ == "__main__":
    main()
