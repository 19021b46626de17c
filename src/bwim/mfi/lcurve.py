"""Choosing λ: the L-curve's corner (default) and generalised cross-validation.

Contract
--------
* :func:`lcurve` solves on a log grid of λ and returns the residual norms ρ(λ) and the
  seminorms η(λ) (scaled units); all λ of the grid go through one stacked pass of the
  recursion (:func:`bwim.mfi.dp.sweep`).  :func:`lcurve_search` is coarse-to-fine: a coarse
  grid over the whole range, then a fine grid within one coarse spacing of its corner,
  the corner being located again on the union of both grids.  The corner is the maximum curvature of
  ``(log ρ, log η)`` parametrised by ``log λ`` (Hansen 1992; the paper uses Busby &
  Trujillo's definition, the same curvature), found on a cubic-spline interpolant of the
  two curves so that it is not tied to the grid.
* Admissible λ (``admissible=``, given by :func:`~bwim.mfi.identify_forces` for first
  order, whose λ → ∞ limit is constant forces: the static weights): tyre forces are
  compressive, so a λ whose identified forces turn tensile where the forces are weighed
  is not a candidate.  The corner is sought on the λ at and above the
  smallest λ from which every grid λ is admissible (the whole grid when all are; its
  largest λ when none is).  Without it, a nearly flat L-curve (the response below the
  gauge noise at every frequency but the quasi-static) puts the maximum curvature on a
  spurious kink at the small-λ end: measured force RMS errors of 80–250 % and weights off
  by up to 24 % at 5 % gauge noise (``benchmarks/mfi_accuracy.py``, λ rules).
* :func:`gcv` minimises ``G(λ) = n ‖ỹ − ŷ‖² / (n − tr A_λ)²`` with the trace of the
  influence matrix estimated by Hutchinson's method (Rademacher probes with a fixed seed);
  each probe reuses the λ's DP gains.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from bwim.mfi.dp import dp_gains, solve_with_gains, sweep
from bwim.mfi.statespace import MFIModel

__all__ = ["LCurve", "gcv", "lcurve", "lcurve_search"]


@dataclass(frozen=True, kw_only=True, eq=False)
class LCurve:
    """The L-curve of one identification.

    Attributes
    ----------
    lam : ndarray (n,)
        λ grid in physical units.
    lam_scaled : ndarray (n,)
    residual_norm, seminorm : ndarray (n,)
        ρ and η at each λ (scaled units).
    curvature : ndarray (n,)
        Curvature of (log ρ, log η) at each grid λ.
    corner : float
        The chosen λ (physical units); ``corner_scaled`` in scaled units.
    admissible : ndarray of bool (n,) or None
        Which grid λ give admissible forces (see module docstring), when checked.
    """

    lam: np.ndarray
    lam_scaled: np.ndarray
    residual_norm: np.ndarray
    seminorm: np.ndarray
    curvature: np.ndarray
    corner: float
    corner_scaled: float
    admissible: np.ndarray | None = None

    def plot(self, ax=None):
        """The curve and its corner (:func:`bwim.plots.mfi.plot_lcurve`); returns the
        figure."""
        from bwim.plots.mfi import plot_lcurve

        return plot_lcurve(self, ax=ax)


def _curvature(t, a, b):
    sa, sb = CubicSpline(t, a), CubicSpline(t, b)
    da, db = sa(t, 1), sb(t, 1)
    d2a, d2b = sa(t, 2), sb(t, 2)
    return (da * d2b - d2a * db) / np.maximum((da**2 + db**2) ** 1.5, 1e-300), sa, sb


def _corner(t, rho, eta, lo: float | None = None):
    """Curvature at the grid points and the log λ of maximum spline curvature (interior,
    at or above ``lo``; the largest grid λ when nothing interior is)."""
    a = np.log(np.maximum(rho, 1e-300))
    b = np.log(np.maximum(eta, 1e-300))
    kappa, sa, sb = _curvature(t, a, b)
    start = t[1] if lo is None else max(t[1], lo)
    if start >= t[-2]:
        return kappa, t[-1]
    # maximise the spline curvature between grid points (interior only)
    fine = np.linspace(start, t[-2], 40 * t.size)
    da, db, d2a, d2b = sa(fine, 1), sb(fine, 1), sa(fine, 2), sb(fine, 2)
    kf = (da * d2b - d2a * db) / np.maximum((da**2 + db**2) ** 1.5, 1e-300)
    return kappa, fine[int(np.argmax(kf))]


def _lowest_admissible(t: np.ndarray, ok: np.ndarray | None) -> float | None:
    """The smallest grid log λ from which every larger grid λ is admissible (None: no
    check; +inf: not even the largest is)."""
    if ok is None:
        return None
    bad = np.flatnonzero(~ok)
    if bad.size == 0:
        return float(t[0])
    return float(t[bad[-1] + 1]) if bad[-1] + 1 < t.size else float("inf")


def _curve(model, lam_s, rho, eta, kappa, t_best, admissible=None) -> LCurve:
    corner_scaled = float(np.exp(t_best))
    return LCurve(
        lam=np.array([model.lam_physical(v) for v in lam_s]),
        lam_scaled=lam_s.copy(), residual_norm=rho, seminorm=eta, curvature=kappa,
        corner=model.lam_physical(corner_scaled), corner_scaled=corner_scaled,
        admissible=admissible,
    )


def lcurve(model: MFIModel, d, weights, lam_grid_scaled: np.ndarray) -> LCurve:
    """Solve on the grid and locate the corner (maximum positive curvature)."""
    lam_grid_scaled = np.asarray(lam_grid_scaled, dtype=float)
    sw = sweep(model, d, lam_grid_scaled, weights)
    rho, eta = sw.residual_norm, sw.seminorm
    kappa, t_best = _corner(np.log(lam_grid_scaled), rho, eta)
    return _curve(model, lam_grid_scaled, rho, eta, kappa, t_best)


def lcurve_search(model: MFIModel, d, weights, lam_range: tuple[float, float], *,
                  n_coarse: int = 8, n_fine: int = 8, admissible=None) -> LCurve:
    """Coarse-to-fine L-curve: ``n_coarse`` log-spaced λ over ``lam_range`` (scaled),
    then ``n_fine`` more strictly within one coarse spacing either side of the coarse
    corner; the corner is located on the union of both grids.  ``admissible(X) -> bool
    per λ`` (X: the sweep's trajectories, (n_λ, N, n_x)) restricts the corner (module
    docstring)."""
    keep = admissible is not None
    coarse = np.geomspace(lam_range[0], lam_range[1], n_coarse)
    first = sweep(model, d, coarse, weights, keep=keep)
    t_c = np.log(coarse)
    ok_c = admissible(first.X) if keep else None
    _, t0 = _corner(t_c, first.residual_norm, first.seminorm,
                    _lowest_admissible(t_c, ok_c))
    step = t_c[1] - t_c[0]
    lo, hi = max(t0 - step, t_c[0]), min(t0 + step, t_c[-1])
    t_f = np.linspace(lo, hi, n_fine + 2)[1:-1]
    h = (hi - lo) / (n_fine + 1)
    if n_fine and np.min(np.abs(t_f[:, None] - t_c[None, :])) < 1e-3 * h:
        t_f += 0.25 * h  # keep clear of the coarse nodes (the spline needs distinct points)
    rho_f = eta_f = np.empty(0)
    ok_f = np.empty(0, dtype=bool)
    if t_f.size:
        second = sweep(model, d, np.exp(t_f), weights, keep=keep)
        rho_f, eta_f = second.residual_norm, second.seminorm
        if keep:
            ok_f = admissible(second.X)
    t = np.concatenate([t_c, t_f])
    order = np.argsort(t)
    t = t[order]
    rho = np.concatenate([first.residual_norm, rho_f])[order]
    eta = np.concatenate([first.seminorm, eta_f])[order]
    ok = np.concatenate([ok_c, ok_f])[order] if keep else None
    kappa, t_best = _corner(t, rho, eta, _lowest_admissible(t, ok))
    return _curve(model, np.exp(t), rho, eta, kappa, t_best, ok)


def gcv(model: MFIModel, d, weights, bounds_scaled: tuple[float, float], *, probes: int = 8,
        seed: int = 0) -> float:
    """λ (scaled) minimising generalised cross-validation."""
    rng = np.random.default_rng(seed)
    Z = rng.choice([-1.0, 1.0], size=(probes, *d.shape))
    sw = np.sqrt(weights)
    n = d.size

    def fitted(sol):
        nz = model.n_z
        return sol.X[:, :nz] @ model.Qz.T + np.einsum("ksf,kf->ks", model.D, sol.X[:, nz:])

    def score(log_lam: float) -> float:
        gains = dp_gains(model, float(np.exp(log_lam)), weights)
        sol = solve_with_gains(model, gains, d, weights)
        trace = 0.0
        for z in Z:
            # A maps weighted data ỹ = W^{1/2} d to W^{1/2} Q X̂: probe with d = W^{-1/2} z
            dz = np.divide(z, sw, out=np.zeros_like(z), where=sw > 0)
            trace += np.sum(z * sw * fitted(solve_with_gains(model, gains, dz, weights)))
        trace /= probes
        return n * sol.residual_norm**2 / max(n - trace, 1e-12) ** 2

    lo, hi = np.log(bounds_scaled[0]), np.log(bounds_scaled[1])
    grid = np.linspace(lo, hi, 9)
    vals = [score(g) for g in grid]
    i = int(np.argmin(vals))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = minimize_scalar(score, bounds=(a, b), method="bounded", options={"xatol": 0.05})
    return float(np.exp(res.x))
