"""Tikhonov-regularised force identification by dynamic programming, and its batch twin.

Contract
--------
Minimise over the initial forces ``f_0`` (the bridge starts at rest, ``z_0 = 0``) and the
unknowns ``r_0 … r_{N−2}``::

    J = Σ_k ‖W^{1/2} (d_k − Q_k X_k)‖² + λ Σ_k ‖r_k‖² [+ λ ‖f_0‖²],   X_{k+1} = H_k X_k + T r_k

In first order ``f_0`` is free (only force *changes* are penalised); in zeroth order
``r_k = f_{k+1}`` and ``f_0`` is penalised like every other force value.

* :func:`solve_dp` is Bellman's recursion (THEORY §4): cost-to-go
  ``V_k(X) = Xᵀ R_k X + 2 s_kᵀ X + const`` backwards, then the optimal ``r_k = −K_k X_k −
  g_k`` forwards.  O(N) time and memory in the record length.  The gains do not depend on
  the data: :func:`dp_gains` computes them once and :func:`solve_with_gains` reuses them
  for further data vectors (GCV probes).
* :func:`solve_batch` stacks the whole problem as one dense least-squares system; it is
  O(N³) and exists to check the recursion (they agree to round-off).
* Everything is in the model's scaled units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.mfi.statespace import MFIModel

__all__ = ["DPGains", "Solution", "dp_gains", "solve_batch", "solve_dp", "solve_with_gains"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Solution:
    """An identified trajectory in scaled units."""

    X: np.ndarray  # (N, n_x)
    r: np.ndarray  # (N − 1, n_f)
    residual_norm: float  # ‖W^{1/2}(d − Q X)‖
    seminorm: float  # ‖r‖

    @property
    def forces(self) -> np.ndarray:
        """Scaled forces, shape (N, n_f)."""
        return self.X[:, -self.r.shape[1]:]


@dataclass(frozen=True, kw_only=True, eq=False)
class DPGains:
    """Data-independent part of the recursion for one λ."""

    K: np.ndarray  # (N − 1, n_f, n_x)
    G: np.ndarray  # (N − 1, n_f, n_f)  (λ I + Tᵀ R T)⁻¹
    A: np.ndarray  # (N − 1, n_x, n_x)  H_k − T K_k
    R0_ff_inv: np.ndarray  # (n_f, n_f)
    lam: float


def _check(model: MFIModel, d: np.ndarray, weights: np.ndarray | None):
    d = np.asarray(d, dtype=float)
    if d.shape != (model.n_steps, model.n_s):
        raise InputError(f"data must have shape {(model.n_steps, model.n_s)}, got {d.shape}")
    w = np.ones(model.n_s) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (model.n_s,) or np.any(w < 0) or not np.all(np.isfinite(w)):
        raise InputError(f"weights must be {model.n_s} non-negative numbers")
    return d, w


def dp_gains(model: MFIModel, lam: float, weights: np.ndarray) -> DPGains:
    """Backward Riccati recursion for the gains (independent of the data)."""
    if not np.isfinite(lam) or lam <= 0:
        raise InputError(f"lam must be positive, got {lam!r}")
    N, nz, nf, nx = model.n_steps, model.n_z, model.n_f, model.n_x
    K = np.empty((N - 1, nf, nx))
    G = np.empty((N - 1, nf, nf))
    A = np.empty((N - 1, nx, nx))
    QWQ = model.qwq(weights)
    Hs = model.H_all
    lam_eye = lam * np.eye(nf)
    R = QWQ[N - 1]
    for k in range(N - 2, -1, -1):
        H = Hs[k]
        Gk = np.linalg.inv(lam_eye + R[nz:, nz:])
        Kk = Gk @ (R[nz:] @ H)
        Ak = A[k]
        Ak[:] = H
        Ak[nz:] -= Kk
        R = H.T @ (R @ Ak)
        R += R.T
        R *= 0.5
        R += QWQ[k]
        K[k], G[k] = Kk, Gk
    initial = lam if model.f_carry == 0.0 else 0.0  # zeroth order penalises f_0 too
    # pseudo-inverse: a force that never reaches the deck during the record is unobservable;
    # it gets the minimum-norm value 0, as in the batch least-squares solution
    R0_ff_inv = np.linalg.pinv(R[nz:, nz:] + initial * np.eye(nf), rcond=1e-12, hermitian=True)
    return DPGains(K=K, G=G, A=A, R0_ff_inv=R0_ff_inv, lam=lam)


def solve_with_gains(model: MFIModel, gains: DPGains, d: np.ndarray,
                     weights: np.ndarray) -> Solution:
    """The data-dependent passes of the recursion with precomputed ``gains`` (made by
    :func:`dp_gains` for the same ``weights``); ``d`` (N, n_s) and ``weights`` (n_s,) in
    scaled units, not checked (see :func:`solve_dp` for the checked entry point)."""
    W = weights
    N, nz, nf = model.n_steps, model.n_z, model.n_f
    QWd = model.qwd(W, d)
    # data-dependent backward pass: s_k and g_k
    g = np.empty((N - 1, nf))
    s = -QWd[N - 1]
    for k in range(N - 2, -1, -1):
        g[k] = gains.G[k] @ s[nz:]
        s = gains.A[k].T @ s - QWd[k]
    X = np.zeros((N, model.n_x))
    X[0, nz:] = -gains.R0_ff_inv @ s[nz:]
    r = np.empty((N - 1, nf))
    Hs = model.H_all
    for k in range(N - 1):
        r[k] = -gains.K[k] @ X[k] - g[k]
        X[k + 1] = Hs[k] @ X[k]
        X[k + 1, nz:] += r[k]
    return _finish(model, X, r, d, W)


def _finish(model, X, r, d, W) -> Solution:
    fit = X[:, : model.n_z] @ model.Qz.T + np.einsum("ksf,kf->ks", model.D, X[:, model.n_z:])
    res = np.sqrt(np.sum(W * (d - fit) ** 2))
    return Solution(X=X, r=r, residual_norm=float(res), seminorm=float(np.linalg.norm(r)))


def solve_dp(
    model: MFIModel, d: np.ndarray, lam: float, weights: np.ndarray | None = None,
    gains: DPGains | None = None,
) -> Solution:
    """Optimal trajectory by dynamic programming (scaled units)."""
    d, W = _check(model, d, weights)
    if gains is None:
        gains = dp_gains(model, lam, W)
    return solve_with_gains(model, gains, d, W)


def solve_batch(
    model: MFIModel, d: np.ndarray, lam: float, weights: np.ndarray | None = None
) -> Solution:
    """The same minimisation as one dense stacked least-squares problem (small cases)."""
    d, W = _check(model, d, weights)
    N, nz, nf, nx = model.n_steps, model.n_z, model.n_f, model.n_x
    n_u = nf + (N - 1) * nf
    Mk = np.zeros((nx, n_u))
    Mk[nz:, :nf] = np.eye(nf)
    rows, rhs = [], []
    sw = np.sqrt(W)[:, None]
    for k in range(N):
        rows.append(sw * (model.Q(k) @ Mk))
        rhs.append(sw[:, 0] * d[k])
        if k < N - 1:
            Mk = model.H(k) @ Mk
            Mk[nz:, nf + k * nf: nf + (k + 1) * nf] += np.eye(nf)
    first = 0 if model.f_carry == 0.0 else nf  # zeroth order penalises f_0 too
    reg = np.zeros((n_u - first, n_u))
    reg[:, first:] = np.sqrt(lam) * np.eye(n_u - first)
    A = np.vstack([*rows, reg])
    b = np.concatenate([*rhs, np.zeros(n_u - first)])
    u = np.linalg.lstsq(A, b, rcond=None)[0]
    r = u[nf:].reshape(N - 1, nf)
    X = np.zeros((N, nx))
    X[0, nz:] = u[:nf]
    for k in range(N - 1):
        X[k + 1] = model.H(k) @ X[k]
        X[k + 1, nz:] += r[k]
    return _finish(model, X, r, d, W)
