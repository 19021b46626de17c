"""Axle errors of ``identify_forces`` (L-curve λ) on the paper crossing: clean, 5 % noise,
first and zeroth order, longitudinal strains only, with the model order used and the wall
time of each identification.  Run it with a given ``PYTHONPATH``
to compare two versions of bwim (issue 15: the coarse-to-fine λ search must not change
the accuracy).

Second table (:func:`lambda_rules`): the L-curve against GCV on eight crossings of four
vehicles (data from the 24 × 16 slab, the 12 × 8 model; noise-free, 2 % and 5 % gauge
noise), largest force RMS error and largest |weight error|.  Before the corner was
restricted to λ with compressive forces (``LCurve.admissible``), five of the eight 5 %
rows had RMS errors of 78–253 % and weights off by up to 24 %."""

from __future__ import annotations

import time

import numpy as np

import bwim
from bwim import paper
from bwim.mfi import force_errors, identify_forces


def lambda_rules(noises=(0.0, 0.02, 0.05)) -> None:
    from bwim.vehicles import three_axle_truck, tractor_semitrailer, two_axle_truck

    fine, model = paper.slab_bridge(nx=24, ny=16), paper.slab_bridge()
    cases = [(paper.truck, 20.0, 2.0, 1), (three_axle_truck, 17.0, 6.0, 4),
             (three_axle_truck, 14.0, 2.0, 11), (three_axle_truck, 23.0, 6.0, 12),
             (tractor_semitrailer, 18.0, 2.0, 13), (tractor_semitrailer, 25.0, 6.0, 14),
             (two_axle_truck, 12.0, 6.0, 15), (two_axle_truck, 20.0, 6.0, 16)]
    print(f"\n{'vehicle':>20} {'m/s':>4} {'lane':>4} {'noise':>5} {'modes':>5} "
          f"{'L-curve RMS/w %':>16} {'GCV RMS/w %':>12}")
    for make, v, lane, seed in cases:
        rec = bwim.simulate(fine, make(), speed=v, lane=lane, sensors=paper.sensors(),
                            road=paper.road(seed))
        for noise in noises:
            r = rec if noise == 0 else rec.with_noise(noise, seed=7)
            out, modes = [], 0
            for lam in ("lcurve", "gcv"):
                ident = identify_forces(model, r, lam=lam)
                e = force_errors(ident, r.truth)
                out.append(f"{100 * e.rms_error.max():.1f}/"
                           f"{100 * np.abs(e.weight_error).max():.1f}")
                modes = modes or getattr(ident, "n_modes", 0)  # the L-curve's order
            print(f"{make.__name__:>20} {v:4g} {lane:4g} {noise:5.0%} "
                  f"{modes:5d} {out[0]:>16} {out[1]:>12}")


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
    lambda_rules()
