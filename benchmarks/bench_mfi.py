"""Moving force identification timing (issues 4 and 15).

A 1 s, 1 kHz record with 20 modes including the L-curve (coarse-to-fine, 16 λ), the growth
with record length, and the dynamic-programming solve against the dense stacked Tikhonov
solve of the same problem, both measured in this run.  The floor (issue 15) is one sparse
Tikhonov solve of the same problem at the chosen λ (the KKT system of the stacked
least-squares problem with the states as unknowns, factorised by SuperLU), measured in the
same run: target ``identify_forces`` ≤ 1.5× the floor and ≤ 0.5 s.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import bwim
from benchmarks._timing import median_time, print_table
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
        note = "≤ 0.5 s: " + ("met" if t_lc <= 0.5 else "MISSED") if dur == 1.0 else ""
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


def sparse_tikhonov(model, d, lam, W):
    """The floor: the same minimisation as one sparse KKT solve (states X_k and unknowns
    r_k as variables, the transitions as equality constraints); returns the states."""
    N, nz, nf, nx = model.n_steps, model.n_z, model.n_f, model.n_x
    nX, nr = N * nx, (N - 1) * nf
    hess_x = sp.bsr_matrix((model.qwq(W), np.arange(N), np.arange(N + 1)),
                           shape=(nX, nX))
    reg = np.full(nr, lam)
    blocks = [hess_x, sp.diags(reg)]
    hess = sp.block_diag(blocks, format="csr")
    if model.f_carry == 0.0:  # zeroth order penalises f_0 too
        hess = hess + sp.csr_matrix((np.full(nf, lam), (nz + np.arange(nf),
                                                        nz + np.arange(nf))),
                                    shape=hess.shape)
    # constraints: X_{k+1} − H_k X_k − T r_k = 0 (k < N − 1), z_0 = 0
    H = model.H_all[:-1]
    k = np.arange(N - 1)
    rows_h = (k[:, None, None] * nx + np.arange(nx)[None, :, None]).repeat(nx, 2)
    cols_h = (k[:, None, None] * nx + np.arange(nx)[None, None, :]).repeat(nx, 1)
    ri = (k[:, None] * nx + nz + np.arange(nf)[None, :]).ravel()
    rc = nX + (k[:, None] * nf + np.arange(nf)[None, :]).ravel()
    eye_r = np.arange((N - 1) * nx)
    rows = np.concatenate([rows_h.ravel(), eye_r, ri, (N - 1) * nx + np.arange(nz)])
    cols = np.concatenate([cols_h.ravel(), eye_r + nx, rc, np.arange(nz)])
    vals = np.concatenate([-H.ravel(), np.ones(eye_r.size), -np.ones(ri.size),
                           np.ones(nz)])
    n_con = (N - 1) * nx + nz
    C = sp.csr_matrix((vals, (rows, cols)), shape=(n_con, nX + nr))
    kkt = sp.bmat([[hess, C.T], [C, None]], format="csc")
    rhs = np.concatenate([model.qwd(W, d).ravel(), np.zeros(nr + n_con)])
    sol = spla.spsolve(kkt, rhs)
    return sol[:nX].reshape(N, nx)


def run_floor(duration: float = 1.0, repeat: int = 3, n_modes: int | None = 20,
              noise: float = 0.0):
    """identify_forces (L-curve and fixed λ) against the sparse floor at the chosen λ, with
    ``n_modes`` modes (None: the order chosen from the record, the default) on the record
    with ``noise`` gauge noise (fraction of the peak strain)."""
    bridge, rec = _record(duration)
    if noise:
        rec = rec.with_noise(noise, seed=1)
    ident = identify_forces(bridge, rec, n_modes=n_modes)
    t_lc = median_time(lambda: identify_forces(bridge, rec, n_modes=n_modes), repeat=repeat,
                       min_time=0.0)
    t_one = median_time(lambda: identify_forces(bridge, rec, n_modes=ident.n_modes,
                                                lam=ident.lam),
                        repeat=repeat, min_time=0.0)
    scale = float(np.abs(rec.data).max())
    model = build_model(bridge, bridge.modes(ident.n_modes), rec, scale,
                        unknowns=ident.unknowns, order=ident.order)
    d, W = rec.data / scale, np.ones(rec.data.shape[1])
    X = sparse_tikhonov(model, d, ident.lam_scaled, W)
    ref = solve_dp(model, d, ident.lam_scaled, W).X
    assert np.allclose(X, ref, atol=1e-6 * np.abs(ref).max()), "floor and DP disagree"
    t_floor = median_time(lambda: sparse_tikhonov(model, d, ident.lam_scaled, W),
                          repeat=repeat, min_time=0.0)
    verdict = ("ratio ≤ 1.5: " + ("met" if t_lc <= 1.5 * t_floor else "MISSED")
               + "; ≤ 0.5 s: " + ("met" if t_lc <= 0.5 else "MISSED"))
    how = f"{n_modes} (given)" if n_modes else f"{ident.n_modes} (from the record)"
    return [f"{duration:g}", f"{noise:.0%}", how, rec.time.size, ident.lcurve.lam.size,
            f"{t_lc:.3f}", f"{t_one:.3f}", f"{t_floor:.3f}", f"{t_lc / t_floor:.2f}", verdict]


def main() -> None:
    print_table(
        "MFI against its floor: identify_forces (L-curve) / one sparse Tikhonov solve at "
        "the chosen λ (wall time, s)",
        ["record (s)", "noise", "modes", "samples", "λ solved", "L-curve", "fixed λ", "floor",
         "ratio", "target"],
        [run_floor(), run_floor(n_modes=None), run_floor(n_modes=None, noise=0.02)],
    )
    print_table(
        "MFI: paper truck and bridge, 18 channels, 20 modes, 1 kHz (wall time, s; "
        "rows with a batch time are the DP solve alone on a short record)",
        ["record (s)", "samples", "one λ (DP)", "16-λ L-curve", "batch dense", "DP speed-up",
         "target"],
        run(),
    )


if __name__ == "__main__":
    main()
