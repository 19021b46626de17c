"""Choosing λ: the L-curve's corner (default) and generalised cross-validation.

Contract
--------
* :func:`lcurve` solves on a log grid of λ and returns the residual norms ρ(λ) and the
  seminorms η(λ) (scaled units); all λ of the grid go through one stacked pass of the
  recursion (:func:`bwim.mfi.dp.sweep`).
* The corner is the maximum curvature of ``(log ρ, log η)`` parametrised by ``log λ``
  (Hansen 1992; the paper uses Busby & Trujillo's definition, the same curvature; see
  docs/theory.md §4, L-curve), found on a cubic-spline interpolant of the two curves so
  that it is not tied to the grid.
* :func:`lcurve_search` finds it coarse-to-fine in two stacked passes: a coarse log grid
  over the whole range brackets the corner, then a fine grid within one (or ``window``)
  coarse spacing either side of it is solved on the record's model with the
  trajectories kept, and the answer is the fine λ nearest to the corner located on the
  fine grid: its trajectory is the identification, so no λ is solved twice.  The coarse
  pass may run on a cheaper model of the same record (:class:`CoarseProblem`: every m-th
  sample, on fewer modes, λ carried over in physical units), whose corner is then only
  an estimate: while the corner sits at an end of the fine grid, or the curvature there
  is above the interior's, the grid is extended there (at most :data:`MAX_EXTENSIONS`
  times).  Without a coarse problem the corner is located on the union of both grids.
  The chosen λ lies within half a fine spacing of the located corner.
* Half grid first (with a coarse problem and ``weigh``, the static weights per λ): every
  other λ of the fine grid is solved first, in one stacked pass, and searched the same
  way (extensions at twice the spacing, towards larger λ only: with the corner below it,
  its smallest λ is taken).  When the static weights of all its admissible λ (at least
  three) agree within :data:`FLAT_TOL` of the largest, where the corner falls among them
  cannot move the weights by more than that, and its answer stands.  Otherwise the
  other half is solved and the search runs on the full fine grid, reusing every λ
  solved: the answer is the full grid's (an L-curve with two corners within the window,
  whose weights differ, is searched at the full resolution).  The force histories are
  not held to that tolerance: another λ changes them more than the weights.
* Why not downwards: a coarse problem of fewer modes fits the record worse, and the
  corner lies where the penalty's misfit reaches the misfit floor, so its corner lies
  above the model's (far above when the record's fast crossing excites the modes it
  lacks), and an extension would cost a pass of its own.  Below the corner the data, not
  the penalty, fix the forces: the static weights stop depending on λ there when the
  readings are clean, and when they are noisy the half grid's weights disagree and the
  full grid is searched, extended downwards as before.  Towards larger λ the penalty
  smooths the forces and the weights move, so the grid is extended there.
* Admissible λ (``admissible=``, given by :func:`~bwim.mfi.identify_forces` for first
  order, whose λ → ∞ limit is constant forces: the static weights): tyre forces are
  compressive, so a λ whose identified forces turn tensile where the forces are weighed
  is not a candidate.  The corner is sought on the λ at and above the
  smallest λ from which every grid λ is admissible (the whole grid when all are; its
  largest λ when none is).  Without it, a nearly flat L-curve (the response below the
  gauge noise at every frequency but the quasi-static) can put the maximum curvature on
  a spurious kink at the small-λ end, where the forces are wild and tensile
  (``benchmarks/mfi_accuracy.py``, λ rules, measures both rules).
* :func:`gcv` minimises ``G(λ) = n ‖ỹ − ŷ‖² / (n − tr A_λ)²`` with the trace of the
  influence matrix estimated by Hutchinson's method (Rademacher probes with a fixed seed);
  each probe reuses the λ's DP gains.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from bwim.mfi.dp import Solution, dp_gains, solve_with_gains, sweep
from bwim.mfi.statespace import MFIModel

__all__ = ["CoarseProblem", "CornerSearch", "LCurve", "gcv", "lcurve", "lcurve_search"]


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


#: At most this many extensions of the fine grid when the corner sits at one of its ends
#: (:func:`lcurve_search` with a coarse problem).
MAX_EXTENSIONS = 4


#: With ``weigh`` (:func:`lcurve_search`), the half fine grid is the answer when the static
#: weights of all its admissible λ agree within this fraction of the largest weight.
FLAT_TOL = 1e-4


@dataclass(frozen=True, kw_only=True, eq=False)
class CoarseProblem:
    """A cheaper model of the same record on which :func:`lcurve_search` brackets the
    corner (e.g. every m-th sample, on the modes that rate allows).

    Attributes
    ----------
    model : MFIModel
    d : ndarray (N_c, n_s)
        Its scaled data.
    weights : ndarray (n_s,)
    admissible : callable or None
        ``admissible(forces) -> bool per λ`` on its scaled forces (n_λ, N_c, n_f).
    """

    model: MFIModel
    d: np.ndarray
    weights: np.ndarray
    admissible: object = None


@dataclass(frozen=True, kw_only=True, eq=False)
class CornerSearch:
    """The L-curve of :func:`lcurve_search` and the solution at its corner.

    Attributes
    ----------
    curve : LCurve
        The λ solved on the record's model, their norms and the corner.
    solution : Solution
        The trajectory at ``curve.corner_scaled`` (scaled units).
    """

    curve: LCurve
    solution: Solution


def _solution(sw, i: int) -> Solution:
    # copies: the sweep's arrays (all its λ) are freed once the search returns
    return Solution(X=np.ascontiguousarray(sw.X[i]), r=np.ascontiguousarray(sw.r[i]),
                    residual_norm=float(sw.residual_norm[i]),
                    seminorm=float(sw.seminorm[i]))


def _fine_grid(t0: float, half: float, t_min: float, t_max: float, n: int) -> np.ndarray:
    """``n`` log λ strictly inside ``half`` either side of ``t0`` (clipped to the range)."""
    lo, hi = max(t0 - half, t_min), min(t0 + half, t_max)
    return np.linspace(lo, hi, n + 2)[1:-1]


def lcurve_search(model: MFIModel, d, weights, lam_range: tuple[float, float], *,
                  n_coarse: int = 8, n_fine: int = 8, admissible=None,
                  coarse: CoarseProblem | None = None, window: int = 1, weigh=None,
                  flat_tol: float = FLAT_TOL) -> CornerSearch:
    """Coarse-to-fine L-curve in two stacked passes (module docstring).

    ``n_coarse`` log-spaced λ over ``lam_range`` (scaled) bracket the corner, on
    ``coarse`` when given (λ carried over in physical units) or on ``model``; then
    ``n_fine`` λ strictly within ``window`` coarse spacings either side of that corner are
    solved on ``model`` with their trajectories kept.  The corner is located on the fine grid
    (with ``coarse``) or on the union of both grids, and the chosen λ is the fine λ
    nearest to it: its trajectory is the answer, no further solve.  ``admissible(forces)
    -> bool per λ`` (scaled forces, (n_λ, N, n_f)) restricts the corner.  With
    ``coarse``, ``weigh(forces) -> (n_λ, n_axles)`` static weights (scaled) makes the
    search solve every other fine λ first and stop there when their weights agree within
    ``flat_tol`` of the largest (module docstring)."""
    keep_f = admissible is not None
    t_min, t_max = np.log(lam_range[0]), np.log(lam_range[1])
    t_c = np.linspace(t_min, t_max, n_coarse)
    if coarse is None:
        first = sweep(model, d, np.exp(t_c), weights, keep_forces=keep_f)
        ok_c = admissible(first.forces) if keep_f else None
    else:
        lam_c = [coarse.model.lam_scaled(model.lam_physical(v)) for v in np.exp(t_c)]
        c_ok = coarse.admissible
        first = sweep(coarse.model, coarse.d, lam_c, coarse.weights,
                      keep_forces=c_ok is not None)
        ok_c = c_ok(first.forces) if c_ok is not None else None
    _, t0 = _corner(t_c, first.residual_norm, first.seminorm, _lowest_admissible(t_c, ok_c))
    step = t_c[1] - t_c[0]
    t_f = _fine_grid(t0, window * step, t_min, t_max, n_fine)
    h = t_f[1] - t_f[0] if t_f.size > 1 else step
    if coarse is None and np.min(np.abs(t_f[:, None] - t_c[None, :])) < 1e-3 * h:
        t_f = t_f + 0.25 * h  # keep clear of the coarse nodes (the spline needs distinct points)
    solved = _Solved(model, d, weights, admissible, weigh)
    base = None if coarse is not None else (t_c, first.residual_norm, first.seminorm, ok_c)
    n_ext = max(2, n_fine // 2)
    if coarse is not None and weigh is not None and t_f.size >= 4:
        # every other λ of the fine grid first: when the static weights of all its
        # admissible λ agree within flat_tol, the corner's place within it cannot move them
        half = _fine_search(solved, t_f[1::2], 2 * h, max(2, n_ext // 2), (t_min, t_max),
                            extend=True, down=False)
        if solved.flat(half.grid, half.lo, flat_tol):
            return half.result(model, d, weights, solved)
    found = _fine_search(solved, t_f, h, n_ext, (t_min, t_max), extend=coarse is not None,
                         base=base)
    return found.result(model, d, weights, solved)


class _Solved:
    """The λ solved on the record's model, by log λ: one stacked pass per call of
    :meth:`solve` for the λ not solved yet; their norms, admissibility, static weights
    and trajectories."""

    def __init__(self, model, d, weights, admissible, weigh):
        self.model, self.d, self.weights = model, d, weights
        self.admissible, self.weigh = admissible, weigh
        self.t: list[float] = []
        self.rows: list[tuple] = []  # (ρ, η, admissible, static weights, sweep, index)

    def find(self, t: float) -> int:
        for i, v in enumerate(self.t):
            if abs(v - t) <= 1e-9 * max(1.0, abs(t)):
                return i
        return -1

    def solve(self, ts: np.ndarray) -> None:
        new = []
        for t in ts:
            if self.find(t) < 0 and all(abs(t - v) > 1e-9 * max(1.0, abs(t)) for v in new):
                new.append(float(t))
        if not new:
            return
        sw = sweep(self.model, self.d, np.exp(new), self.weights, keep=True)
        ok = self.admissible(sw.forces) if self.admissible is not None else None
        w = self.weigh(sw.forces) if self.weigh is not None else None
        for i, t in enumerate(new):
            self.t.append(t)
            self.rows.append((sw.residual_norm[i], sw.seminorm[i],
                              None if ok is None else bool(ok[i]),
                              None if w is None else w[i], sw, i))

    def arrays(self, ts: np.ndarray):
        rows = [self.rows[self.find(t)] for t in ts]
        ok = (np.array([r[2] for r in rows]) if self.admissible is not None else None)
        return (np.array([r[0] for r in rows]), np.array([r[1] for r in rows]), ok)

    def solution(self, t: float) -> Solution:
        row = self.rows[self.find(t)]
        return _solution(row[4], row[5])

    def flat(self, ts: np.ndarray, lo: float | None, tol: float) -> bool:
        """Whether the static weights of the λ ``ts`` at or above ``lo`` agree within
        ``tol`` of the largest (False with fewer than three of them: no evidence)."""
        use = ts >= (lo if lo is not None else -np.inf) - 1e-12
        if np.count_nonzero(use) < 3:
            return False
        w = np.array([self.rows[self.find(t)][3] for t in ts[use]])
        scale = np.abs(w).max()
        return bool(scale > 0 and np.all(w.max(axis=0) - w.min(axis=0) <= tol * scale))


@dataclass(frozen=True, kw_only=True, eq=False)
class _Found:
    """A fine search's grid (sorted, with the coarse nodes when they are on the model),
    its norms, admissibility, curvature, corner and spacing; ``grid``: its solved λ."""

    t: np.ndarray
    rho: np.ndarray
    eta: np.ndarray
    ok: np.ndarray | None
    lo: float | None
    kappa: np.ndarray
    t_best: float
    h: float
    grid: np.ndarray

    def result(self, model, d, weights, solved: _Solved) -> CornerSearch:
        """The answer: the solved fine λ nearest to the corner (among the admissible
        ones), or a solve at the corner when none is within half a spacing."""
        nodes = self.grid
        cand = nodes >= (self.lo if self.lo is not None else -np.inf) - 1e-12
        if not cand.any():
            cand[:] = True
        dist = np.where(cand, np.abs(nodes - self.t_best), np.inf)
        j = int(np.argmin(dist))
        t_best = self.t_best
        if dist[j] <= 0.5 * self.h * (1 + 1e-9):
            t_best = float(nodes[j])
            sol = solved.solution(t_best)
        else:  # the corner lies outside the fine grid: solve at it
            sol = _solution(sweep(model, d, [np.exp(t_best)], weights, keep=True), 0)
        curve = _curve(model, np.exp(self.t), self.rho, self.eta, self.kappa, t_best, self.ok)
        return CornerSearch(curve=curve, solution=sol)


def _fine_search(solved: _Solved, t_f: np.ndarray, h: float, n_ext: int, t_range, *,
                 extend: bool, base=None, down: bool = True) -> _Found:
    """Solve ``t_f`` (spacing ``h``) and locate the corner on it, with the coarse nodes
    ``base`` = (t, ρ, η, admissible) when they were solved on the model; with ``extend``,
    extend the grid by ``n_ext`` λ at an end while the corner sits there (module
    docstring), at its low end only with ``down`` (otherwise its smallest λ is the
    corner)."""
    t_min, t_max = t_range
    grids = [t_f]
    solved.solve(t_f)

    def located():
        g = np.sort(np.concatenate(grids))
        rho, eta, ok = solved.arrays(g)
        t = g
        if base is not None:
            t = np.concatenate([base[0], g])
            rho = np.concatenate([base[1], rho])
            eta = np.concatenate([base[2], eta])
            ok = np.concatenate([base[3], ok]) if ok is not None else None
        o = np.argsort(t)
        t, rho, eta = t[o], rho[o], eta[o]
        ok = ok[o] if ok is not None else None
        lo = _lowest_admissible(t, ok)
        kappa, t_best = _corner(t, rho, eta, lo)
        return _Found(t=t, rho=rho, eta=eta, ok=ok, lo=lo, kappa=kappa, t_best=t_best, h=h,
                      grid=g)

    f = located()
    if not extend:
        return f
    # the coarse model's corner is an estimate: while the corner sits at an end of the
    # fine grid, extend the grid there by n_ext λ at the same spacing
    for _ in range(MAX_EXTENSIONS):
        t, kappa, lo, t_best = f.t, f.kappa, f.lo, f.t_best
        # an end is open when the corner sits next to it or the curvature there is
        # above the interior's (the corner lies beyond it)
        inner = kappa[1:-1][t[1:-1] >= (lo if lo is not None else -np.inf) - 1e-12]
        top = inner.max() if inner.size else -np.inf
        low_open = (t_best <= t[1] + 1e-9 * h or kappa[0] > top) and \
            (lo is None or lo <= t[0]) and t[0] - h > t_min
        high_open = (t_best >= t[-2] - 1e-9 * h or kappa[-1] > top) and t[-1] + h < t_max
        if low_open and not down:
            # the corner lies below the grid: its smallest λ is the nearest (module
            # docstring, half grid first)
            return replace(f, t_best=float(f.grid.min()))
        if low_open:
            t_new = t[0] - h * np.arange(1, n_ext + 1)
        elif high_open:
            t_new = t[-1] + h * np.arange(1, n_ext + 1)
        else:
            break
        t_new = t_new[(t_new > t_min) & (t_new < t_max)]
        if not t_new.size:
            break
        solved.solve(t_new)
        grids.append(t_new)
        f = located()
    return f


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
