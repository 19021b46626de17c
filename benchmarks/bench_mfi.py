"""Moving force identification timing (issue 4).

A 1 s, 1 kHz record with 20 modes including a 30-point L-curve (target < 3 s), the growth
with record length, and the dynamic-programming solve against the dense stacked Tikhonov
solve of the same problem, both measured in this run.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

import bwim
from benchmarks._timing import print_table
from bwim import paper
from bwim.mfi import build_model, identify_forces, solve_batch, solve_dp
from bwim.mfi.statespace import ForceUnknowns, Order


def _record(duration: float, fs: float = 1000.0):
    """The paper truck on the paper bridge at the speed that makes the crossing last
    ``duration`` seconds (first axle on to last axle off)."""
    bridge = paper.slab_bridge()
    truck = paper.truck()
    speed = (bridge.length + truck.length) / duration
    rec = bwim.simulate(bridge, truck, speed=speed, lane=paper.LANE, sensors=paper.sensors(),
                        road=paper.road(1), sampling_rate=fs, approach=20.0)
    return bridge, rec


def _timed(fn, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run(durations=(0.5, 1.0, 2.0, 4.0), batch_durations=(0.05, 0.1, 0.2), repeat: int = 3):
    rows = []
    for dur in durations:
        bridge, rec = _record(dur)
        t_lc, ident = _timed(lambda b=bridge, r=rec: identify_forces(b, r, n_modes=20),
                             repeat)
        t_one, _ = _timed(lambda b=bridge, r=rec, lam=ident.lam: identify_forces(
            b, r, n_modes=20, lam=lam), repeat)
        note = "< 3 s: " + ("met" if t_lc < 3.0 else "MISSED") if dur == 1.0 else ""
        rows.append([f"{dur:g}", rec.time.size, f"{t_one:.3f}", f"{t_lc:.2f}", "", "", note])
    for dur in batch_durations:
        bridge, rec = _record(0.5)
        n = round(dur * 1000) + 1
        short = dataclasses.replace(rec, time=rec.time[:n], data=rec.data[:n], truths=())
        scale = np.abs(rec.data).max()
        model = build_model(bridge, bridge.modes(20), short, scale,
                            unknowns=ForceUnknowns.WHEEL, order=Order.FIRST)
        d = rec.data[:n] / scale
        t_dp, a = _timed(lambda m=model, d=d: solve_dp(m, d, 1.0), repeat)
        t_b, b = _timed(lambda m=model, d=d: solve_batch(m, d, 1.0), 1)
        assert np.allclose(a.X, b.X, atol=1e-8 * np.abs(b.X).max())
        rows.append([f"{dur:g}", n, f"{t_dp:.3f}", "", f"{t_b:.2f}", f"{t_b / t_dp:.0f}×", ""])
    return rows


def main() -> None:
    print_table(
        "MFI: paper truck and bridge, 18 channels, 20 modes, 1 kHz (wall time, s; "
        "rows with a batch time are the DP solve alone on a short record)",
        ["record (s)", "samples", "one λ (DP)", "30-pt L-curve", "batch dense", "DP speed-up",
         "target"],
        run(),
    )


if __name__ == "__main__":
    main()
