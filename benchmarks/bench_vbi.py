"""Vehicle–bridge interaction timing: the paper crossing (issues 3 and 15).

The paper's truck on the paper's slab bridge over the paper's road, 100 m approach,
1 kHz: coupled (target < 0.5 s) and iterative (target < 3 s) on this 2-core machine, with
the full-FE variants beside them, and the time per simulated second (approach included).

Floors (issue 15), measured in the same run on the same number of steps and modes: one
pass of the modal Newmark stepping in numpy (all modes per step, the pre-issue-15 loop)
and the same pass as ``scipy.signal.lfilter`` recursions.  Targets: iterative ≤ 1.5× the
numpy modal floor; coupled ≥ 3× faster than before issue 15 (``BEFORE_COUPLED`` s,
measured on this machine with the same benchmark).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from benchmarks._timing import median_time, print_table
from bwim import paper
from bwim.dynamics import simulate
from bwim.fe.modal import select_modes

#: Coupled paper crossing before issue 15 (commit 5265d80): median wall time on this
#: machine measured interleaved with the current code by
#: ``python -m benchmarks.compare_coupled`` (58–63 ms per round; the 116–128 ms first
#: reported was a loaded machine, and a lone first round still shows it).
BEFORE_COUPLED = 0.061

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


def _modal_floor(M, C, K, f, dt):
    """One pass of average-acceleration Newmark over uncoupled modes, numpy per step."""
    a0, a1, a2 = 4 / dt**2, 2 / dt, 4 / dt
    keff = K + a1 * C + a0 * M
    u = np.zeros(M.size)
    v = np.zeros(M.size)
    a = f[0] / M
    U = np.empty_like(f)
    U[0] = u
    for k in range(1, f.shape[0]):
        u_new = (f[k] + M * (a0 * u + a2 * v + a) + C * (a1 * u + v)) / keff
        a_new = a0 * (u_new - u) - a2 * v - a
        v = v + dt / 2 * (a + a_new)
        u, a = u_new, a_new
        U[k] = u
    return U


def _lfilter_floor(M, C, K, f, dt):
    h = dt
    out = np.empty_like(f)
    for m in range(M.size):
        den = [M[m] + h * C[m] / 2 + h * h * K[m] / 4, h * h * K[m] / 2 - 2 * M[m],
               M[m] - h * C[m] / 2 + h * h * K[m] / 4]
        out[:, m] = signal.lfilter(h * h / 4 * np.array([1.0, 2.0, 1.0]), den, f[:, m])
    return out


def run_floor(*, approach: float = paper.APPROACH, repeat: int = 5):
    """Modal crossings against the floors (see module docstring)."""
    bridge, sensors, truck = paper.slab_bridge(), paper.sensors(), paper.truck()
    road = paper.road(1, approach=approach)
    fs = 1000.0
    modes = select_modes(bridge, sampling_rate=fs)
    n_t = round((approach + bridge.length + truck.length) / paper.SPEED * fs) + 1
    M, C, K = np.ones(modes.n), 2 * bridge.rayleigh.ratio(modes.omega) * modes.omega, \
        modes.omega**2
    f = np.random.default_rng(0).standard_normal((n_t, modes.n))
    f[0] = 0.0  # from rest under no load, as a crossing starts (the filters' zero past)
    assert np.allclose(_lfilter_floor(M, C, K, f, 1 / fs), _modal_floor(M, C, K, f, 1 / fs),
                       rtol=0, atol=1e-9 * np.abs(_modal_floor(M, C, K, f, 1 / fs)).max())
    t_np = median_time(lambda: _modal_floor(M, C, K, f, 1 / fs), repeat=repeat,
                       min_time=0.0)
    t_lf = median_time(lambda: _lfilter_floor(M, C, K, f, 1 / fs), repeat=repeat,
                       min_time=0.0)
    rows = []
    for method in ("iterative", "coupled"):
        def go(method=method):
            return simulate(bridge, truck, speed=paper.SPEED, lane=paper.LANE,
                            sensors=sensors, road=road, method=method, approach=approach)
        t = median_time(go, repeat=repeat, min_time=0.0)
        if method == "iterative":
            target = "≤ 1.5× numpy floor: " + ("met" if t <= 1.5 * t_np else "MISSED")
        else:
            target = (f"≥ 3× faster than {BEFORE_COUPLED:g} s: "
                      + ("met" if 3 * t <= BEFORE_COUPLED else "MISSED")
                      + f" ({BEFORE_COUPLED / t:.1f}×)")
        rows.append([method, f"{t:.3f}", f"{t_np:.3f}", f"{t_lf:.4f}", f"{t / t_np:.2f}",
                     target])
    return rows, n_t, modes.n


def main() -> None:
    floor_rows, n_t, n_m = run_floor()
    print_table(
        f"VBI against the modal floor ({n_t} steps, {n_m} modes; wall time, s)",
        ["method", "crossing", "numpy modal floor", "lfilter floor", "ratio to numpy floor",
         "target"],
        floor_rows,
    )
    rows, simulated = run()
    print_table(
        f"VBI: paper crossing, 100 m approach, 1 kHz ({simulated:.3f} s simulated)",
        ["bridge", "method", "iterations", "wall time (s)", "ms per simulated s", "target"],
        rows,
    )


if __name__ == "__main__":
    main()
