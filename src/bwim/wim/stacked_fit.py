"""The stacked least squares of multi-run influence lines: the lines and the runs' scale
factors by alternating least squares, as an iterative solver with a visible shape.

Contract
--------
* Model (docs/theory.md §14): the reading of channel ``g`` in run ``r`` at sample ``k`` is
  ``ε_rg(t_k) = s_r Σ_i W_i I_g(x_rik; y_r) + c_rg + e_rgk`` with
  ``I_g(x; y) = I0_g(x) + dy_r I1_g(x)`` (``dy_r = y_r − ȳ``; ``I1`` only with the lateral
  model), ``I0``/``I1`` piecewise linear on a :class:`~bwim.wim.support.Grid`, zero at its
  ends.  Units: ordinates in reading per newton (``I1`` also per unit of lateral
  covariate), loads N, positions m, factors dimensionless.
* :func:`run_data` reduces one run to its centred normal-equation pieces (the offsets
  ``c_rg`` eliminated exactly by centring each run's rows, Frisch–Waugh–Lovell); every
  later step works on these small matrices, never on the samples.
* :class:`AlternatingLines` solves the bilinear problem in (lines, factors):
  ``setup`` solves the lines with every factor 1; each ``step`` is one pair of
  half-steps, the factors given the lines (one quadratic ``a_r s_r² − 2 b_r s_r`` per run,
  channels alike, subject to ``mean(s) = 1`` and, with the lateral model,
  ``Σ_r s_r dy_r = 0``: closed form by Lagrange multipliers) then the lines given the
  factors (one linear least-squares problem with the second-difference smoothing
  ``penalty`` scaled by the mean diagonal of its normal matrix), and returns the largest
  change of a factor; ``run`` steps until that change is below ``tol`` or ``max_iter``
  steps are done; ``finalize`` returns the :class:`LinesFit`.  Each half-step minimises
  the misfit over its block, so it never rises.  The second constraint removes a
  near-degeneracy: a factor linear in ``y`` is, to first order, a lateral line
  ``I1 ∝ I0``; it is given to the line.
* :func:`run_residual`, :func:`run_scale`, :func:`relative_residual` and
  :func:`run_misfit` judge one run against given lines.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from bwim.errors import NumericalError
from bwim.wim.influence_line import hat_design
from bwim.wim.support import Grid

__all__ = ["AlternatingLines", "LinesFit", "RunData", "RunResidual", "relative_residual",
           "run_data", "run_misfit", "run_residual", "run_scale"]


@dataclass(frozen=True, kw_only=True, eq=False)
class RunData:
    """One run's centred normal-equation pieces on a grid (offsets eliminated).

    Attributes
    ----------
    n_t : int
        Samples.
    gbar : ndarray, shape (m,)
        Mean row of the design ``G`` (m = n − 1 interior ordinates).
    ebar : ndarray, shape (n_c,)
        Mean reading of each channel.
    N : ndarray, shape (m, m)
        Centred ``GᵀG``.
    R : ndarray, shape (m, n_c)
        Centred ``Gᵀε``.
    EE : ndarray, shape (n_c, n_c)
        Centred ``εᵀε``.
    on : bool
        Whether any axle is on the support.
    """

    n_t: int
    gbar: np.ndarray
    ebar: np.ndarray
    N: np.ndarray
    R: np.ndarray
    EE: np.ndarray
    on: bool


def run_data(E: np.ndarray, P: np.ndarray, loads: np.ndarray, grid: Grid) -> RunData:
    """:class:`RunData` of a run with readings ``E`` (n_t, n_c), axle positions ``P``
    (n_t, n_axles), m, and static axle ``loads`` (n_axles,), N, on ``grid``."""
    G = hat_design(P, loads, grid.x0, grid.h, grid.n)
    n_t = E.shape[0]
    gbar = np.asarray(G.sum(axis=0)).ravel() / n_t
    ebar = E.mean(axis=0)
    Ec = E - ebar
    N = (G.T @ G).toarray() - n_t * np.outer(gbar, gbar)
    R = np.asarray(G.T @ E) - n_t * np.outer(gbar, ebar)
    return RunData(n_t=n_t, gbar=gbar, ebar=ebar, N=N, R=R, EE=Ec.T @ Ec, on=G.nnz > 0)


@dataclass(frozen=True, kw_only=True, eq=False)
class LinesFit:
    """What :class:`AlternatingLines` found.

    Attributes
    ----------
    theta0 : ndarray, shape (m, n_c)
        ``I0``'s interior ordinates.
    theta1 : ndarray, shape (m, n_c) or None
        ``I1``'s (None without the lateral model).
    scales : ndarray, shape (n_runs,)
        The runs' factors (all 1 without per-run factors).
    nit : int
        Alternating iterations (1 without per-run factors: one solve).
    nfev : int
        Linear least-squares solves of the lines.
    success : bool
        Whether the factors converged (always True without per-run factors).
    message : str
    """

    theta0: np.ndarray
    theta1: np.ndarray | None
    scales: np.ndarray
    nit: int
    nfev: int
    success: bool
    message: str

    def lines_at(self, dy: float) -> np.ndarray:
        """Interior ordinates ``I0 + dy I1`` (m, n_c) at ``dy = y − ȳ``."""
        return self.theta0 if self.theta1 is None else self.theta0 + dy * self.theta1


class AlternatingLines:
    """Alternating least squares of lines and factors (module docstring), in the shape of
    an iterative solver: ``setup``, ``step``, ``run``, ``finalize``.

        solver = AlternatingLines(data, dy, lateral=True, per_run_scale=True,
                                  penalty=P)
        fit = solver.solve(tol=1e-7, max_iter=200)     # setup, run, finalize

    Parameters
    ----------
    data : sequence of RunData
        The runs, on one grid.
    dy : ndarray, shape (n_runs,)
        Each run's lateral covariate less the centre ȳ.
    lateral : bool
        Fit ``I1`` too.
    per_run_scale : bool
        Fit the factors (else they stay 1 and one solve of the lines is the answer).
    penalty : ndarray, shape (m, m), or None
        The smoothing term (:func:`~bwim.wim.influence_line.smoothing_penalty`).
    """

    def __init__(self, data: Sequence[RunData], dy: np.ndarray, *, lateral: bool,
                 per_run_scale: bool, penalty: np.ndarray | None) -> None:
        self.data = list(data)
        self.dy = dy
        self.lateral = lateral
        self.per_run_scale = per_run_scale
        self.penalty = penalty

    def setup(self, *, tol: float, max_iter: int) -> None:
        """Start from factors 1 and the lines they give."""
        self.tol, self.max_iter = tol, max_iter
        self.scales = np.ones(len(self.data))
        self.nit = self.nfev = 0
        self.change = np.inf
        self._solve_lines()

    def step(self) -> float:
        """One iteration: the factors given the lines, then the lines given the factors;
        the largest change of a factor."""
        ab = np.array([_scale_terms(d, self._lines_at(y))
                       for d, y in zip(self.data, self.dy, strict=True)])
        if not np.all(ab[:, 0] > 0):
            raise NumericalError("a run of the fit has no axle on the lines' support")
        new = _factor_step(ab[:, 0], ab[:, 1], self.dy if self.lateral else None)
        if not np.all(new > 0):
            bad = int(np.flatnonzero(~(new > 0))[0])
            raise NumericalError(
                f"run {bad} of the fit gets a non-positive scale factor: its readings do "
                "not follow the lines (wrong passage or loads?)")
        self.change = float(np.max(np.abs(new - self.scales)))
        self.scales = new
        self._solve_lines()
        self.nit += 1
        return self.change

    @property
    def converged(self) -> bool:
        """The last step changed no factor by ``tol`` or more."""
        return self.change < self.tol

    def run(self) -> None:
        """Step until converged or ``max_iter`` steps are done (no step without per-run
        factors)."""
        if not self.per_run_scale:
            return
        while not self.converged and self.nit < self.max_iter:
            self.step()

    def finalize(self) -> LinesFit:
        """The lines, the factors and why the iteration stopped."""
        if not self.per_run_scale:
            nit, success = 1, True
            message = "one linear least-squares solve (no per-run factors)"
        elif self.converged:
            nit, success = self.nit, True
            message = f"factors converged (largest change {self.change:.1e} < {self.tol:g})"
        else:
            nit, success = self.nit, False
            message = (f"factors not converged after {self.max_iter} iterations (largest "
                       f"change {self.change:.1e})")
        return LinesFit(theta0=self.theta0, theta1=self.theta1, scales=self.scales, nit=nit,
                        nfev=self.nfev, success=success, message=message)

    def solve(self, *, tol: float, max_iter: int) -> LinesFit:
        """``setup``, ``run``, ``finalize``."""
        self.setup(tol=tol, max_iter=max_iter)
        self.run()
        return self.finalize()

    def _lines_at(self, dy: float) -> np.ndarray:
        return self.theta0 if self.theta1 is None else self.theta0 + dy * self.theta1

    def _solve_lines(self) -> None:
        """The lines given the factors (one penalised linear least-squares solve)."""
        data, s, dy, penalty = self.data, self.scales, self.dy, self.penalty
        m = data[0].N.shape[0]
        A0 = sum(si**2 * d.N for si, d in zip(s, data, strict=True))
        b0 = sum(si * d.R for si, d in zip(s, data, strict=True))
        if not self.lateral:
            K, b = A0.copy(), b0
            if penalty is not None:
                K += float(np.mean(np.diag(A0))) * penalty
        else:
            A1 = sum(si**2 * y * d.N for si, y, d in zip(s, dy, data, strict=True))
            A2 = sum(si**2 * y**2 * d.N for si, y, d in zip(s, dy, data, strict=True))
            b1 = sum(si * y * d.R for si, y, d in zip(s, dy, data, strict=True))
            K = np.block([[A0, A1], [A1, A2]])
            if penalty is not None:
                K[:m, :m] += float(np.mean(np.diag(A0))) * penalty
                K[m:, m:] += float(np.mean(np.diag(A2))) * penalty
            b = np.vstack([b0, b1])
        try:
            theta = scipy.linalg.solve(K, b, assume_a="pos")
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
            raise NumericalError(
                f"the influence-line ordinates are not determined by the runs ({K.shape[0]} "
                "unknowns per channel): use a larger spacing or smoothing > 0") from None
        self.nfev += 1
        if not self.lateral:
            self.theta0, self.theta1 = theta, None
        else:
            self.theta0, self.theta1 = theta[:m], theta[m:]


def _scale_terms(d: RunData, T: np.ndarray) -> tuple[float, float]:
    """``a = ‖G T‖²`` and ``b = ⟨G T, ε⟩`` (centred, channels alike) of a run: its misfit
    is ``a s² − 2 b s + const``."""
    if not d.on:
        return 0.0, 0.0
    return float(np.sum(T * (d.N @ T))), float(np.sum(T * d.R))


def _factor_step(a: np.ndarray, b: np.ndarray, dy: np.ndarray | None) -> np.ndarray:
    """Factors minimising ``Σ_r a_r s_r² − 2 b_r s_r`` subject to ``mean(s) = 1`` and, with
    the lateral model, ``Σ_r s_r dy_r = 0`` (Lagrange multipliers, closed form)."""
    C = np.ones((1, a.size)) if dy is None else np.vstack([np.ones(a.size), dy])
    target = np.zeros(C.shape[0])
    target[0] = a.size
    Ci = C / a  # C A⁻¹
    lam = np.linalg.solve(Ci @ C.T, Ci @ b - target)
    return (b - C.T @ lam) / a


def run_scale(d: RunData, T: np.ndarray) -> float:
    """The factor that fits a run best to the interior ordinates ``T`` (m, n_c), channels
    alike (nan if no axle is on the support)."""
    a, b = _scale_terms(d, T)
    return b / a if a > 0 else float("nan")


@dataclass(frozen=True, kw_only=True, eq=False)
class RunResidual:
    """A run's residual against given lines and factor.

    Attributes
    ----------
    cross : ndarray, shape (n_c, n_c)
        Residual cross-product matrix over the run's samples (reading units²; its trace
        is the residual sum of squares).
    offsets : ndarray, shape (n_c,)
        Fitted baseline offset of each channel.
    """

    cross: np.ndarray
    offsets: np.ndarray


def run_residual(d: RunData, T: np.ndarray, s: float) -> RunResidual:
    """The residual of a run against interior ordinates ``T`` (m, n_c) and factor ``s``."""
    NT = d.N @ T
    cross = T.T @ d.R
    res = d.EE - s * (cross + cross.T) + s**2 * (T.T @ NT)
    return RunResidual(cross=res, offsets=d.ebar - s * (d.gbar @ T))


def relative_residual(cross: np.ndarray, d: RunData) -> float:
    """‖residual‖ / ‖ε − c‖ over the run's samples and channels (nan if the run's
    centred readings are zero)."""
    den = float(np.trace(d.EE))
    return float(np.sqrt(max(float(np.trace(cross)), 0.0) / den)) if den > 0 else float("nan")


def run_misfit(cross: np.ndarray, var: np.ndarray, n_t: int) -> float:
    """RMS over samples and channels of a run's residual (``cross``, over ``n_t``
    samples) in units of each channel's ``sqrt(var)``."""
    return float(np.sqrt(max(float(np.sum(np.diag(cross) / var)), 0.0) / (n_t * var.size)))
