"""Generation time of the simulated test data (bwim.synthetic.make_test_day), per site.

* ``basic-2-lane``: the small day of the tests (4 + 8 events, 0.5 m mesh) and the full day
  (12 + 100 events, 0.25 m mesh): the baseline of this run.
* ``short-span-4-lane``: the small site of the tests (4 calibration runs, 12 + 4 traffic
  events, 0.5 m mesh; target: well under a minute, < 30 s) and the full default preset
  (12 runs, 700 traffic events on the traffic date, 450 on the calibration date, 0.25 m
  mesh): its cost per event against the basic full day's in the same run (target ≤ 3×:
  it has more sensors, both directions and more vehicles per event).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from benchmarks._timing import print_table
from bwim.synthetic import make_test_day

CASES = {
    "basic small": ("basic-2-lane", {"n_calibration": 4, "n_traffic": 8, "mesh": 0.5}),
    "basic full": ("basic-2-lane", {}),
    "short-span small": ("short-span-4-lane", {"n_calibration": 4, "n_traffic": 12,
                                               "n_calibration_day_traffic": 4, "mesh": 0.5}),
    "short-span full": ("short-span-4-lane", {}),
}


def _time(site: str, kw: dict):
    with tempfile.TemporaryDirectory() as tmp:
        t0, c0 = time.perf_counter(), time.process_time()
        day = make_test_day(Path(tmp) / "day", site=site, **kw)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        size = sum(p.stat().st_size for p in Path(tmp).rglob("*") if p.is_file())
    return day, wall, cpu, size


def run(cases=tuple(CASES)):
    measured = {}
    for name in cases:
        site, kw = CASES[name]
        day, wall, cpu, size = _time(site, kw)
        measured[name] = (len(day.events), day.mesh, wall, cpu, size)
    rows = []
    for name, (n, mesh, wall, cpu, size) in measured.items():
        per = wall / n
        target = ""
        if name == "short-span small":
            target = "< 30 s: " + ("met" if wall < 30.0 else "MISSED")
        elif name == "short-span full" and "basic full" in measured:
            base = measured["basic full"][2] / measured["basic full"][0]
            target = f"{per / base:.2f}x basic <= 3x: " + ("met" if per <= 3 * base
                                                          else "MISSED")
        rows.append([name, n, f"{mesh:g}", f"{wall:.1f}", f"{cpu:.1f}", f"{per:.3f}",
                     f"{size / 2**20:.1f}", target])
    return rows


def main() -> None:
    print_table("Simulated test data: generation time per site",
                ["case", "events", "mesh (m)", "wall (s)", "cpu (s)", "s / event", "MiB",
                 "target"], run())


if __name__ == "__main__":
    main()
