"""Calibration timing against floors measured in the same run (issue 15).

The paper's slab (12 × 8 elements), truck and road, 100 m approach, 1 kHz, started from
E_x × 0.8, E_y × 1.2, μ × 1.25 (§5.1).  Each objective and its floor are timed in
interleaved repeats (shared cores: the ratio of each repeat, then the median).

* **Static objective** (stiffness stage, E_x and E_y): one evaluation against the floor
  "banded Cholesky of the same K + the 18 sensor solves" (``scipy.linalg``).  Target
  ≤ 1.3×.
* **Dynamic objective** (one evaluation of the crossing re-simulated): the mass stage
  (μ only: K fixed, modes scaled) and a joint trial (E_x, E_y, μ: modes solved).  Target
  ≤ 25 ms.  Floors: one numpy pass of modal Newmark over the crossing's steps and modes
  (all modes per step, bench_vbi's floor) and one ``eigsh`` of the trial's modes.
* **§5.1 full settings** (``bwim reproduce 5.1``: CE 200/40, 3 convergences, 100 m
  approach, then the LM refinement and the MFI checks): wall time, target ≤ 15 s.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla

from benchmarks._timing import print_table
from bwim import paper
from bwim.calibration.problem import DynamicObjective, ParameterSpace, StaticObjective
from bwim.dynamics import simulate
from bwim.dynamics.crossing import prepare_crossing, run_crossing

TARGET_STATIC = 1.3  #: × the floor
TARGET_DYNAMIC = 0.025  #: s per evaluation
TARGET_51 = 15.0  #: s


def _interleaved(fns, *, repeat: int, number: int) -> list[list[float]]:
    """Wall time per call of each of ``fns`` in each repeat, the functions interleaved."""
    for f in fns:
        f()
    out = [[] for _ in fns]
    for _ in range(repeat):
        for k, f in enumerate(fns):
            t0 = time.perf_counter()
            for _ in range(number):
                f()
            out[k].append((time.perf_counter() - t0) / number)
    return out


def _modal_floor(omega, zeta, f, dt):
    """One pass of average-acceleration Newmark over uncoupled modes, numpy per step."""
    a0, a1, a2 = 4 / dt**2, 2 / dt, 4 / dt
    C, K = 2 * zeta * omega, omega**2
    keff = K + a1 * C + a0
    u = np.zeros(omega.size)
    v = np.zeros_like(u)
    a = f[0].copy()
    U = np.empty_like(f)
    U[0] = u
    for k in range(1, f.shape[0]):
        u_new = (f[k] + a0 * u + a2 * v + a + C * (a1 * u + v)) / keff
        a_new = a0 * (u_new - u) - a2 * v - a
        v = v + dt / 2 * (a + a_new)
        u, a = u_new, a_new
        U[k] = u
    return U


def _setup(approach: float = paper.APPROACH):
    truth = paper.slab_bridge()
    road = paper.road(1, approach=approach)
    rec = simulate(truth, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                   sensors=paper.sensors(), road=road, approach=approach)
    p = truth.params
    start = truth.with_params(E_x=p["E_x"] * 0.8, E_y=p["E_y"] * 1.2, mu=p["mu"] * 1.25)
    return truth, start, rec, road


def run_objectives(*, approach: float = paper.APPROACH, repeat: int = 7,
                   number: int = 200):
    _, start, rec, road = _setup(approach)
    rng = np.random.default_rng(0)
    rows = []

    # --- static ---------------------------------------------------------------------
    space = ParameterSpace(start, ("E_x", "E_y"))
    static = StaticObjective(space, [rec], paper.truck())
    thetas = [space.vector() * rng.uniform(0.8, 1.2, space.n) for _ in range(16)]
    it = iter(range(10**9))
    model = start.model
    ab = model.assembler.stiffness_banded(model.stiffness_coefficients(start.params))
    St = np.ascontiguousarray(start.sensor_matrix(paper.sensors()).T)

    def floor_static():
        c = sla.cholesky_banded(ab, lower=True, check_finite=False)
        return sla.cho_solve_banded((c, True), St, check_finite=False)

    t_obj, t_floor = _interleaved(
        [lambda: static(thetas[next(it) % 16]), floor_static], repeat=repeat, number=number)
    ratio = float(np.median(np.array(t_obj) / np.array(t_floor)))
    rows.append(["static (E_x, E_y)", f"{np.median(t_obj) * 1e3:.3f}",
                 f"Cholesky + 18 solves {np.median(t_floor) * 1e3:.3f}", f"{ratio:.2f}",
                 f"≤ {TARGET_STATIC}×: " + ("met" if ratio <= TARGET_STATIC else "MISSED")])

    # --- dynamic --------------------------------------------------------------------
    for names, label in ((("mu",), "dynamic, mass stage (μ)"),
                         (("E_x", "E_y", "mu"), "dynamic, joint (E_x, E_y, μ)")):
        space = ParameterSpace(start, names)
        dyn = DynamicObjective(space, [rec], paper.truck(), road, start, approach=approach)
        thetas = [space.vector() * rng.uniform(0.8, 1.2, space.n) for _ in range(8)]
        # the fast path (modes scaled from the previous trial) against a plain simulation
        dyn(thetas[1])
        prep = prepare_crossing(start, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                                sensors=paper.sensors(), road=road, approach=approach,
                                sampling_rate=rec.sampling_rate, tail=rec.settings.tail)
        ref = run_crossing(prep, space.bridge(thetas[0], start), n_modes=dyn.n_modes).data
        err = np.abs(dyn.predicted(thetas[0])[0] - ref).max() / np.abs(ref).max()
        assert err < 1e-12, f"objective and simulation differ by {err:.1e}"
        trial = space.bridge(thetas[0], start)
        modes = trial.modes(dyn.n_modes)
        n_t = round((approach + start.length + paper.truck().length) / paper.SPEED
                    * 1000) + 1
        f = np.random.default_rng(1).standard_normal((n_t, modes.n))
        zeta = start.rayleigh.ratio(modes.omega)
        k = iter(range(10**9))

        def eigsh_floor(trial=trial, dyn=dyn):
            fresh = trial.with_params()  # same parameters, no cached modes
            return fresh.modes(dyn.n_modes)

        t_obj, t_nm, t_eig = _interleaved(
            [lambda dyn=dyn, thetas=thetas, k=k: dyn(thetas[next(k) % 8]),
             lambda f=f, modes=modes, zeta=zeta: _modal_floor(modes.omega, zeta, f, 1e-3),
             eigsh_floor], repeat=repeat, number=3)
        t = float(np.median(t_obj))
        ratio = float(np.median(np.array(t_obj) / np.array(t_nm)))
        rows.append([label, f"{t * 1e3:.1f}",
                     f"numpy modal pass {np.median(t_nm) * 1e3:.1f}; eigsh "
                     f"{np.median(t_eig) * 1e3:.1f}", f"{ratio:.2f}",
                     f"≤ {TARGET_DYNAMIC * 1e3:g} ms: "
                     + ("met" if t <= TARGET_DYNAMIC else "MISSED")])
    return rows


def run_51():
    from bwim.paper.reproduce import case_5_1

    t0 = time.perf_counter()
    rep = case_5_1(quick=False)
    wall = time.perf_counter() - t0
    cal = rep.artefacts["calibration"]
    stages = "; ".join(f"{s.name}: {s.nfev} ev, {s.wall_time:.1f} s" for s in cal.stages)
    return [["§5.1 full (CE 200/40, 100 m)", f"{wall:.1f}", str(cal.nfev), stages,
             f"≤ {TARGET_51:g} s: " + ("met" if wall <= TARGET_51 else "MISSED")]]


def main(*, full_51: bool = True) -> None:
    print_table("Calibration objectives against floors (paper slab 12×8, 100 m approach, "
                "1 kHz; median wall time per evaluation, ms; ratio = median of interleaved "
                "repeats)", ["objective", "time (ms)", "floor (ms)", "ratio to floor",
                             "target"], run_objectives())
    if full_51:
        print_table("§5.1 at full settings (bwim reproduce 5.1)",
                    ["case", "wall time (s)", "evaluations", "stages", "target"], run_51())


if __name__ == "__main__":
    main()
