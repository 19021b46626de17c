"""Vehicle–bridge interaction timing: the paper crossing (issue 3).

The paper's truck on the paper's slab bridge over the paper's road, 100 m approach,
1 kHz: coupled (target < 0.5 s) and iterative (target < 3 s) on this 2-core machine, with
the full-FE variants beside them, and the time per simulated second (approach included).
"""

from __future__ import annotations

from benchmarks._timing import median_time, print_table
from bwim import paper
from bwim.dynamics import simulate

TARGETS = {("modal", "coupled"): 0.5, ("modal", "iterative"): 3.0}


def run(*, approach: float = paper.APPROACH, repeat: int = 3, full: bool = True):
    bridge, sensors, truck = paper.slab_bridge(), paper.sensors(), paper.truck()
    road = paper.road(1, approach=approach)
    simulated = (approach + bridge.length + truck.length) / paper.SPEED
    rows = []
    for system in ("modal", "full") if full else ("modal",):
        for method in ("coupled", "iterative"):
            def go(method=method, system=system):
                return simulate(bridge, truck, speed=paper.SPEED, lane=paper.LANE,
                                sensors=sensors, road=road, method=method, approach=approach,
                                full_system=system == "full")
            rec = go()
            t = median_time(go, repeat=repeat, min_time=0.0)
            target = TARGETS.get((system, method))
            rows.append([system, method, rec.convergence.iterations, f"{t:.3f}",
                         f"{t / simulated * 1e3:.1f}",
                         "—" if target is None else f"< {target:g} s: "
                         + ("met" if t < target else "MISSED")])
    return rows, simulated


def main() -> None:
    rows, simulated = run()
    print_table(
        f"VBI: paper crossing, 100 m approach, 1 kHz ({simulated:.3f} s simulated)",
        ["bridge", "method", "iterations", "wall time (s)", "ms per simulated s", "target"],
        rows,
    )


if __name__ == "__main__":
    main()
