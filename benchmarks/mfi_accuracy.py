"""Axle errors of ``identify_forces`` (L-curve λ) on the paper crossing: clean, 5 % noise,
first and zeroth order, longitudinal strains only, with the model order used and the wall
time of each identification.  Run it with a given ``PYTHONPATH``
to compare two versions of bwim (issue 15: the coarse-to-fine λ search must not change
the accuracy)."""

from __future__ import annotations

import time

import numpy as np

import bwim
from bwim import paper
from bwim.mfi import force_errors, identify_forces


def main() -> None:
    bridge = paper.slab_bridge()
    rec = bwim.simulate(bridge, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                        sensors=paper.sensors(), road=paper.road(1))
    noisy = rec.with_noise(0.05, seed=7)
    low = rec.with_noise(0.01, seed=7)
    long = rec.channels([s for s in rec.sensors if s.kind.value == "strain_x"])
    cases = [("clean", rec, "first"), ("1 % noise", low, "first"), ("5 % noise", noisy, "first"),
             ("5 % noise", noisy, "zeroth"), ("strain_x only", long, "first")]
    print(f"{'case':>14} {'order':>6} {'modes':>5} {'n_lam':>5} {'lam (phys)':>11} "
          f"{'weight err %':>16} {'RMS err %':>14} {'GVW %':>6} {'time s':>6}")
    for name, r, order in cases:
        t0 = time.perf_counter()
        ident = identify_forces(bridge, r, order=order)
        elapsed = time.perf_counter() - t0
        e = force_errors(ident, rec.truth)
        w = " ".join(f"{v:+.3f}" for v in 100 * e.weight_error)
        rms = " ".join(f"{v:.3f}" for v in 100 * e.rms_error)
        n_modes = getattr(ident, "n_modes", 0)  # 0: a bwim before the field existed
        print(f"{name:>14} {order:>6} {n_modes:5d} {ident.lcurve.lam.size:5d} "
              f"{ident.lam:11.4e} {w:>16} {rms:>14} {100 * e.gvw_error:+6.3f} "
              f"{elapsed:6.2f}")


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    main()
