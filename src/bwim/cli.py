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
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

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


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="bwim",
        description="Calibrated, dynamic Bridge Weigh-in-Motion.",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    d = sub.add_parser("demo", help="the paper's slab bridge: modes and static strains")
    d.add_argument("--modes", type=int, default=6, help="number of modes to print (default 6)")
    d.set_defaults(run=_demo)
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
