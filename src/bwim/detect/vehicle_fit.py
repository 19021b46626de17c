"""A vehicle's axles at two detectors as one least-squares model, and its refinement.

Contract
--------
* :class:`Problem` holds one record's two detector channels for the fit: weighted by each
  detector's level (:attr:`~bwim.detect.response.DetectorResponse.level`: what the
  learned response missed of the calibration truck's axles, or the noise if more; all
  misfits of :mod:`bwim.detect.pursuit` and :mod:`bwim.detect.groups` are in these
  "level variances"), the columns of their **rest** (with gauges: the bending as the
  learned gauge combination reads it, an offset and a drift; without: none, readings and
  responses high-passed in space over :data:`~bwim.detect.response.HIGH_PASS` m of
  travel at the record's first speed estimate), and the responses ``K_d`` on their grids.
* Model of a vehicle's axles on its window (:func:`window`: :data:`REACH` m of travel
  before its first axle reaches detector 1 to REACH m after its last leaves detector 2,
  every ``step``-th sample: at least :data:`WINDOW_SAMPLES` per response width at half
  height)::

      y_d(t) = Σ_i A_id K_d(v (t − τ_i) − D_d) + rest_d(t) + e,   D_1 = 0, D_2 = D,

  ``τ_i`` the time axle ``i`` passes detector 1, ``v`` the speed, ``A_id`` its amplitude
  at each detector (free: an axle's dynamic force differs at the two instants it passes
  them).  :func:`solve` gives the amplitudes and rest by linear least squares, the
  residual, each axle's **removal cost** (the misfit's rise without it:
  ``A_i² / [(MᵀM)⁻¹]_ii`` summed over the detectors) and, on request, the
  variable-projection Jacobian of the residual in (τ, v) (Kaufman's approximation);
  residuals and costs are scaled to the misfit of all samples.  :func:`refine` is
  Levenberg–Marquardt on (τ, v) over that projection (at most :data:`MAX_LM`
  iterations, until the misfit falls by less than :data:`CONVERGED` of itself).
* An axle is **seen by both** detectors when ``|ln(A_2 / (ρ A_1))|`` (``ρ`` the learned
  gain ratio) is at most :data:`RATIO_SPREADS` times the spread the calibration runs
  showed, and at least :data:`MIN_RATIO_BOUND`.
* Times in s, distances in m, speeds in m/s; amplitudes in each detector's reading units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.linalg.lapack import dgesv as _gesv

from .response import HIGH_PASS, LearnedResponses, high_pass

__all__ = ["CONVERGED", "MAX_LM", "MIN_RATIO_BOUND", "RATIO_SPREADS", "REACH",
           "WINDOW_SAMPLES", "Problem", "Rows", "Solution", "VehicleFit", "make_problem", "refine",
           "relative", "ridged_normal", "solution", "solve", "window"]

#: A vehicle's fit looks this far beyond its first and last axle, m of travel.
REACH = 2.0
#: An axle's two amplitudes may differ from the gain ratio by this many learned spreads.
RATIO_SPREADS = 4.0
#: ... and at least by this factor (natural log: a factor 3).
MIN_RATIO_BOUND = float(np.log(3.0))
#: Samples per response width (at half height) a vehicle's fit keeps at least.
WINDOW_SAMPLES = 8
#: Levenberg–Marquardt iterations of a refinement, at most ...
MAX_LM = 15
#: ... which stops when the misfit falls by less than this share (or the times move by
#: less than 5 mm of travel).
CONVERGED = 3e-3


def ridged_normal(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Mᵀ, G)`` for both detectors' design matrices stacked, ``M`` (2, n, p): ``G =
    Mᵀ M`` with its diagonal raised by 1e-12 of its mean (a ridge far below the data's
    scale that keeps a rank-deficient fit solvable)."""
    Mt = M.transpose(0, 2, 1)
    G = Mt @ M
    p = G.shape[1]
    diag = G.reshape(2, -1)[:, ::p + 1]  # a view
    diag += 1e-12 * (diag.sum(axis=-1) / p + 1e-300)[:, None]
    return Mt, G


@dataclass(frozen=True, eq=False)
class Problem:
    """One record's two channels, weighted, their rest's columns and the responses (see
    the module contract); made by :func:`make_problem`."""

    t: np.ndarray
    y: np.ndarray  # (n_t, 2) weighted (level units); high-passed without gauges
    rest: tuple[np.ndarray, np.ndarray]  # per detector (n_t, k) weighted columns
    q_rest: tuple[np.ndarray, np.ndarray]  # their orthonormal bases (all samples)
    w: np.ndarray  # (2,) 1 / level
    ratio: float  # the second detector's gain over the first's
    bound: float  # largest |ln(A_2 / (ratio A_1))| of an axle
    spread: float  # learned spread of that log ratio
    shift: tuple[float, float]  # D_d
    grids: tuple  # per detector (u, K, dK/du), high-passed without gauges
    steps: tuple  # per detector K's differences between ordinates (0 after the last)
    fs: float
    step: int  # every step-th sample in a vehicle's window

    def atoms(self, taus: np.ndarray, v: float, rows: slice | np.ndarray = slice(None),
              slopes: bool = False, only: int | None = None,
              dt: np.ndarray | None = None):
        """Per detector the weighted columns K(v (t − τ_i) − D_d), (n_rows, n), K linear
        between its ordinates; with ``slopes`` also their slopes dK/du (of the linear
        pieces) at the same points; with ``only`` that detector's (None for the other).
        ``dt``: the rows' times less ``taus`` (n_rows, n), when already made."""
        if dt is None:
            dt = self.t[rows][:, None] - taus[None, :]
        out, der = [], []
        for c, (u, k, _) in enumerate(self.grids):
            if only is not None and c != only:
                out.append(None)
                der.append(None)
                continue
            du = u[1] - u[0]
            x = (v * dt - (self.shift[c] + u[0])) * (1.0 / du)
            np.clip(x, 0.0, u.size - 1.000001, out=x)  # the grids end in zeros
            j = x.astype(np.intp)
            x -= j
            step = self.steps[c][j]
            out.append((k[j] + x * step) * self.w[c])
            if slopes:
                der.append(step * (self.w[c] / du))
        return (out, der) if slopes else out

    @cached_property
    def stacked(self) -> tuple[np.ndarray, np.ndarray]:
        """The readings (2, n_t, 1) and the rest's columns (2, n_t, k), one detector after
        the other."""
        return np.array([self.y[:, c] for c in range(2)])[..., None], np.array(self.rest)

    @cached_property
    def _both(self):
        """Both detectors' grids as one (for :meth:`both_atoms`): offsets, scales and
        bounds of shape (2, 1, 1), K and its differences end to end, each's first index."""
        def col(values, dtype=float):
            return np.array(values, dtype=dtype)[:, None, None]

        u = [g[0] for g in self.grids]
        du = [ui[1] - ui[0] for ui in u]
        return (col([self.shift[c] + u[c][0] for c in range(2)]),
                col([1.0 / d for d in du]), col([ui.size - 1.000001 for ui in u]),
                np.concatenate([g[1] for g in self.grids]), np.concatenate(self.steps),
                col([0, u[0].size], np.intp), col(self.w),
                col([self.w[c] / du[c] for c in range(2)]))

    def both_atoms(self, v: float, dt: np.ndarray, slopes: bool = False,
                   out: np.ndarray | None = None):
        """:meth:`atoms` of both detectors as one array (2, n_rows, n), the same numbers,
        from the rows' times less the axles' ``dt`` (n_rows, n); with ``slopes`` also the
        slopes (2, n_rows, n).  ``out``: where to write the atoms (2, n_rows, n)."""
        off, inv_du, top, k, steps, first, w, w_du = self._both
        x = (v * dt - off) * inv_du
        np.maximum(x, 0.0, out=x)  # the grids end in zeros (np.clip: the same numbers)
        np.minimum(x, top, out=x)
        j = x.astype(np.intp)
        x -= j
        j += first
        step = steps[j]
        x *= step
        x += k[j]
        out = np.multiply(x, w, out=out)
        return (out, step * w_du) if slopes else (out, None)

    def log_ratio(self, amps: np.ndarray) -> np.ndarray:
        """``ln(A_2 / (ratio A_1))`` per axle (±inf where one detector sees nothing)."""
        a1 = np.maximum(amps[:, 0], 0.0)
        a2 = np.maximum(amps[:, 1], 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log(a2 / (self.ratio * a1))
        return np.where(np.isnan(r), np.inf, r)

    def seen_by_both(self, amps: np.ndarray) -> np.ndarray:
        return np.abs(self.log_ratio(amps)) <= self.bound


@dataclass(frozen=True, eq=False)
class VehicleFit:
    """A vehicle's fit on its window: times, speed, amplitudes (n, 2), misfit, each axle's
    removal cost (level variances)."""

    taus: np.ndarray
    v: float
    amps: np.ndarray
    chi: float
    gains: np.ndarray
    #: the least squares (with slopes) at these times and speed on the refinement's
    #: window (a later fit on the same window starts from it)
    solution: Solution | None = None


def make_problem(t: np.ndarray, y: np.ndarray, gauges: np.ndarray | None,
                 learned: LearnedResponses, v: float, *, fs: float | None = None,
                 bending: np.ndarray | None = None) -> Problem:
    """The :class:`Problem` of a record's times ``t``, detector channels ``y`` (n_t, 2)
    and ``gauges`` (n_t, n_gauges; None: high-pass) at the first speed estimate ``v``.
    ``fs`` (the sampling rate from the median step) and ``bending`` (n_t, 2: the gauges
    less their mean, combined with each response's weights) when already made."""
    if fs is None:
        fs = 1.0 / float(np.median(np.diff(t)))
    w = 1.0 / np.array([max(r.level, 1e-300) for r in learned.responses])
    spread = float(learned.amplitude_spread)
    bound = max(RATIO_SPREADS * spread, MIN_RATIO_BOUND)
    # a vehicle's fit samples every step-th reading: at least WINDOW_SAMPLES per response
    # width at half height (the response is smooth on that scale)
    width = min(r.fwhm for r in learned.responses) / v * fs
    step = max(1, int(width // WINDOW_SAMPLES))
    common = dict(t=t, w=w, ratio=float(learned.gain_ratio), bound=bound, spread=spread,
                  shift=(0.0, learned.distance), fs=fs, step=step)
    if learned.gauges and gauges is not None:
        if bending is None:
            g = gauges - gauges.mean(axis=0)
            bending = np.column_stack([g @ r.bending for r in learned.responses])
        tc = t - t.mean()
        tc = tc / max(float(np.ptp(tc)), 1e-300)
        rest = tuple(np.column_stack([bending[:, c], np.ones_like(tc), tc]) * w[c]
                     for c in range(2))
        grids = tuple(r.padded() for r in learned.responses)
        q = np.linalg.qr(np.array(rest))[0]  # both at once (each on its own: the same)
        return Problem(y=(y - y.mean(axis=0)) * w, rest=rest, q_rest=(q[0], q[1]), grids=grids,
                        steps=_steps(grids), **common)
    y_hp = high_pass(y, HIGH_PASS / v * fs) * w
    empty = np.zeros((t.size, 0))
    grids = tuple(r.high_passed() for r in learned.responses)
    return Problem(y=y_hp, rest=(empty, empty), q_rest=(empty, empty), grids=grids,
                    steps=_steps(grids), **common)


def _steps(grids) -> tuple:
    """Per grid K's differences between ordinates, 0 after the last (np.diff and
    np.append's numbers, by slices)."""
    return tuple(np.concatenate((k[1:] - k[:-1], [0.0])) for _, k, _ in grids)


def relative(amps: np.ndarray) -> np.ndarray:
    """Amplitudes over each detector's largest, (n, 2)."""
    top = amps.max(axis=0) if amps.size else np.zeros(2)
    return amps / np.where(top > 0, top, 1.0)


def window(pb: Problem, taus: np.ndarray, v: float) -> np.ndarray:
    """Samples from REACH m of travel before the first axle reaches detector 1 to REACH m
    after the last leaves detector 2."""
    lo = pb.t.searchsorted(taus.min() - REACH / v)
    hi = pb.t.searchsorted(taus.max() + (pb.shift[1] + REACH) / v, side="right")
    return np.arange(lo, hi, pb.step)


class Rows:
    """What every fit on one vehicle's window reads: the sampled rows' times, readings
    (2, n_rows, 1) and rest columns (2, n_rows, k), copied once per window."""

    def __init__(self, pb: Problem, rows: np.ndarray, index: slice | None = None):
        """``index``: a slice selecting the same rows (read through views rather than
        gathered by the index array: the same numbers, faster)."""
        y, rest = pb.stacked
        at = rows if index is None else index
        self.rows = rows
        self.t = pb.t[at]
        self.y = np.ascontiguousarray(y[:, at])  # C order: numpy's products then give
        self.rest = np.ascontiguousarray(rest[:, at])  # the numbers of one detector's


class Solution:
    """Both detectors' least-squares amplitudes and rest of the axles ``taus`` at speed
    ``v`` on a window's rows (see :func:`solve`), as one stack of two problems; the
    Jacobian on request."""

    def __init__(self, pb: Problem, taus: np.ndarray, v: float, w: Rows, slopes: bool):
        n = taus.size
        self.taus, self.v, self.w, self.slopes = taus, v, w, slopes
        self.dt = w.t[:, None] - taus[None, :]
        M = np.empty((2, w.t.size, n + w.rest.shape[2]))  # the atoms, then the rest
        M[:, :, n:] = w.rest
        self.dX = pb.both_atoms(v, self.dt, slopes, out=M[:, :, :n])[1]
        Mt, G = ridged_normal(M)
        try:
            Ginv = np.linalg.inv(G)
        except np.linalg.LinAlgError:
            Ginv = np.empty_like(G)
            for c in range(2):
                try:
                    Ginv[c] = np.linalg.inv(G[c])
                except np.linalg.LinAlgError:
                    Ginv[c] = np.linalg.pinv(G[c])
        coef = Ginv @ (Mt @ w.y)
        # every step-th sample: scaled to the misfit of all samples
        self.k, self.step = math.sqrt(pb.step), pb.step
        self.res = (w.y - M @ coef).reshape(-1) * self.k
        self.M, self.Mt, self.Ginv, self.a = M, Mt, Ginv, coef[:, :n, 0]

    # amplitudes and removal costs when read (a refinement's rejected trials never are)
    @cached_property
    def amps(self) -> np.ndarray:
        """The axles' amplitudes (n, 2)."""
        return self.a.T.copy()

    @cached_property
    def gains(self) -> np.ndarray:
        """Each axle's removal cost (level variances of all samples)."""
        # removing regressor i raises the misfit by coef_i² / [(MᵀM)⁻¹]_ii
        n = self.taus.size
        gains = self.a**2 / np.maximum(self.Ginv.diagonal(axis1=1, axis2=2)[:, :n], 1e-300)
        return (gains[0] + gains[1]) * self.step

    def jacobian(self) -> np.ndarray:
        """The variable-projection Jacobian (Kaufman) of the residual in (τ_1 … τ_n, v)."""
        n, v, dX = self.taus.size, self.v, self.dX
        D = np.empty((2, self.w.t.size, n + 1))
        D[:, :, :n] = -v * dX * self.a[:, None, :]  # ∂(X a)/∂τ_i
        D[:, :, n] = ((dX * self.dt) @ self.a[..., None])[..., 0]  # ∂(X a)/∂v
        J = self.M @ (self.Ginv @ (self.Mt @ D)) - D
        return J.reshape(-1, n + 1) * self.k


def solve(pb: Problem, taus: np.ndarray, v: float, rows: np.ndarray, slopes: bool):
    """Per detector the least-squares amplitudes and rest on ``rows`` (free in sign), the
    residual; with ``slopes`` the variable-projection Jacobian (Kaufman) of the residual
    with respect to (τ_1 … τ_n, v); each axle's removal cost.  Residual and costs are
    scaled by the window's sampling step (misfits of all samples)."""
    sol = Solution(pb, taus, v, rows if isinstance(rows, Rows) else Rows(pb, rows), slopes)
    return sol.res, (sol.jacobian() if slopes else None), sol.amps, sol.gains


def solution(pb: Problem, taus: np.ndarray, v: float, start: Solution | None = None
             ) -> Solution:
    """The least squares with slopes of the axles ``taus`` (ascending) at speed ``v`` on
    their window: ``start`` when it is that one (the same numbers, not made again)."""
    rows = window(pb, taus, v)
    if (start is not None and start.v == v and np.array_equal(start.taus, taus)
            and start.slopes and np.array_equal(start.w.rows, rows)):
        return start
    # the window is every step-th sample from its first: a slice selects the same rows
    index = slice(int(rows[0]), int(rows[-1]) + 1, pb.step) if rows.size else None
    return Solution(pb, taus, v, Rows(pb, rows, index), True)


def refine(pb: Problem, taus: np.ndarray, v: float, iterations: int = MAX_LM, *,
           start: Solution | None = None) -> VehicleFit:
    """The vehicle's axle times and speed by Levenberg–Marquardt on the variable
    projection (amplitudes and rest by least squares inside), on a fixed window.
    ``start``: the :class:`Solution` with slopes at these times and speed on their window
    when already made (the same numbers, not made again)."""
    taus = np.sort(np.asarray(taus, dtype=float))
    p = np.concatenate((taus, [v]))
    sol = solution(pb, taus, v, start)
    rows = sol.w
    r = sol.res
    cost = float(r @ r)
    lam = 1e-3
    scale = np.full(taus.size + 1, 1.0 / v)  # τ in s, v in m/s: metres
    for _ in range(iterations):
        Js = sol.jacobian() * scale  # sol: the last accepted (only it is read)
        A = Js.T @ Js
        g = Js.T @ r
        improved = False
        for _ in range(8):
            damped = A.copy()  # A + λ diag(diag(A) + 1e-12), by LAPACK's gesv directly
            diag = damped.reshape(-1)[::taus.size + 2]  # (numpy's solve: the same numbers)
            diag += lam * (diag + 1e-12)
            x, info = _gesv(damped, g)[2:]
            if info:
                raise np.linalg.LinAlgError("singular matrix")
            step = -x * scale
            trial = p + step
            tt, vv = np.sort(trial[:-1]), trial[-1]
            if vv <= 0:
                lam *= 10.0
                continue
            # a step that moves an axle off the window leaves its column zero at a
            # detector: the fit is degenerate, its misfit not finite, the step rejected
            with np.errstate(invalid="ignore", over="ignore"):
                trial_sol = Solution(pb, tt, vv, rows, True)
                c2 = float(trial_sol.res @ trial_sol.res)
            if np.isfinite(c2) and c2 < cost:
                rel = (cost - c2) / max(cost, 1e-300)
                sol = trial_sol
                p, r, cost = np.concatenate((tt, [vv])), sol.res, c2
                lam = max(lam / 3.0, 1e-7)
                improved = True
                break
            lam *= 10.0
        if not improved or rel < CONVERGED or np.abs(step[:-1]).max() * p[-1] < 5e-3:
            break
    # the last accepted solution's amplitudes and removal costs (made once, when read)
    return VehicleFit(taus=p[:-1], v=float(p[-1]), amps=sol.amps, chi=cost, gains=sol.gains,
                      solution=sol)
