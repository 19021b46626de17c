"""The ``bwim`` command line.

Contract
--------
``main(argv=None) -> int`` parses arguments, calls the library and prints; it holds no
numerics.  Bad input ends with a one-line message on stderr and exit code 2, never a
traceback.

Subcommands available now:

``demo``
    The paper's 12 m × 8 m slab bridge: its lowest modes and the static strains under the
    calibration truck's axle loads.  (Simulation, calibration and force identification
    join the demo as those layers land; it never pretends to calibrate.)
``reproduce {5.1,5.2,5.3,5.4,compare,all}``
    The paper's experiments: tables with the paper's numbers beside ours, figures in
    ``--out`` (default ``bwim-out/reproduce``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bwim import paper
from bwim.conventions import MICROSTRAIN
from bwim.errors import BwimError, InputError
from bwim.loads import PointLoad

__all__ = ["main"]


def _demo(args: argparse.Namespace) -> int:
    bridge = paper.slab_bridge()
    if not 1 <= args.modes <= 50:
        raise InputError(f"--modes must be between 1 and 50, got {args.modes}")
    grid = bridge.model.grid
    print("bwim demo: the paper's slab bridge (Dowling, OBrien & González 2012, §5.1)")
    print(f"  {grid.length:g} m × {grid.width:g} m slab, {grid.nx} × {grid.ny} BFS elements, "
          f"{bridge.n_free} free DOF, E = {paper.SLAB_E / 1e9:g} GPa, "
          f"μ = {paper.SLAB_MU:g} kg/m², h = {paper.SLAB_THICKNESS:g} m (assumed)")
    modes = bridge.modes(args.modes)
    print(f"\nLowest {args.modes} natural frequencies (Hz):")
    print("  " + "  ".join(f"{f:7.2f}" for f in modes.frequencies))

    x2 = grid.length / 2  # rear (heavier) axle at mid-span
    x1 = x2 + paper.AXLE_SPACING
    half = paper.TRACK_WIDTH / 2
    loads = [
        PointLoad(x=x, y=paper.LANE + dy, P=p / 2)
        for x, p in ((x1, paper.AXLE_LOADS[0]), (x2, paper.AXLE_LOADS[1]))
        if x <= grid.length
        for dy in (-half, half)
    ]
    sensors = [s for s in paper.sensors() if s.kind.value == "strain_x"]
    strains = bridge.static(loads, sensors) / MICROSTRAIN
    print(f"\nStatic longitudinal soffit strain (µε), rear axle "
          f"({paper.AXLE_LOADS[1] / 1e3:g} kN) at mid-span, lane centre y = {paper.LANE:g} m:")
    xs = sorted({s.x for s in sensors})
    ys = sorted({s.y for s in sensors})
    table = np.array(strains).reshape(len(xs), len(ys))
    print("   y (m) " + "".join(f"{'x = ' + format(x, 'g') + ' m':>12}" for x in xs))
    for j, y in enumerate(ys):
        print(f"  {y:6.1f} " + "".join(f"{table[i, j]:12.2f}" for i in range(len(xs))))
    print("\nVehicle simulation, calibration and force identification are not built yet.")
    return 0


def _reproduce(args: argparse.Namespace) -> int:
    import time

    from bwim import reproduce
    from bwim.io.atomic import atomic_output, check_writable

    names = list(reproduce.CASES) if args.case == "all" else [args.case]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    check_writable(out / ".probe")
    t0 = time.perf_counter()
    for name in names:
        print(f"== reproducing {name}{' (quick)' if args.quick else ''} ==", flush=True)
        kwargs = {"quick": args.quick}
        if name != "compare":
            kwargs["n_jobs"] = args.jobs
        report = reproduce.CASES[name](**kwargs)
        print(report.render(), flush=True)
        if not args.no_figures:
            from bwim.plots.reproduce import report_figures

            for fig_name, fig in report_figures(report).items():
                target = out / f"{name.replace('.', '_')}_{fig_name}.png"
                with atomic_output(target) as tmp:
                    fig.savefig(tmp, format="png", dpi=110)
                print(f"  figure: {target}")
        print()
    print(f"total {time.perf_counter() - t0:.1f} s")
    return 0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="bwim",
        description="Calibrated, dynamic Bridge Weigh-in-Motion.",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    d = sub.add_parser("demo", help="the paper's slab bridge: modes and static strains")
    d.add_argument("--modes", type=int, default=6, help="number of modes to print (default 6)")
    d.set_defaults(run=_demo)
    r = sub.add_parser(
        "reproduce",
        help="the paper's experiments with its numbers side by side",
        description="Reproduce Dowling, OBrien & González (2012) §5: 5.1 identical "
        "elements, 5.2 noise, 5.3 sixteen zones, 5.4 beam-and-slab bridge, and a comparison "
        "of optimisers ('compare').  Full runs take minutes (5.3 the longest); --quick runs "
        "small versions.",
    )
    r.add_argument("case", choices=["5.1", "5.2", "5.3", "5.4", "compare", "all"])
    r.add_argument("--quick", action="store_true", help="small, fast versions")
    r.add_argument("--out", default="bwim-out/reproduce", help="folder for the figures")
    r.add_argument("--jobs", type=int, default=1, help="worker processes for populations")
    r.add_argument("--no-figures", action="store_true", help="tables only")
    r.set_defaults(run=_reproduce)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``bwim`` command; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args))
    except BwimError as exc:
        print(f"bwim: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
