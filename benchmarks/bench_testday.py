"""Generation time of the simulated B-WIM test day (bwim.synthetic.make_test_day).

The full day (12 calibration runs, 100 traffic events, 0.25 m data mesh; target ≤ 2 min on
one core) and the small day of the tests (4 + 8 events, 0.5 m mesh; target ≤ 15 s).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from benchmarks._timing import print_table
from bwim.synthetic import make_test_day

CASES = {
    "full": ({}, 120.0),
    "small": ({"n_calibration": 4, "n_traffic": 8, "mesh": 0.5}, 15.0),
}


def run(cases=("small", "full")):
    rows = []
    for name in cases:
        kw, target = CASES[name]
        with tempfile.TemporaryDirectory() as tmp:
            t0, c0 = time.perf_counter(), time.process_time()
            day = make_test_day(Path(tmp) / "day", **kw)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            size = sum(p.stat().st_size for p in Path(tmp).rglob("*") if p.is_file())
        rows.append([name, len(day.events), f"{day.mesh:g}", f"{wall:.1f}", f"{cpu:.1f}",
                     f"{size / 2**20:.1f}",
                     f"< {target:g} s: " + ("met" if wall < target else "MISSED")])
    return rows


def main() -> None:
    # the full day's generation is timed by bench_site, which makes two of them
    print_table("Simulated test day: generation time",
                ["day", "events", "mesh (m)", "wall (s)", "cpu (s)", "MiB", "target"],
                run(cases=("small",)))


if __name__ == "__main__":
    main()
