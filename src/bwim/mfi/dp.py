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

__all__ = ["BLOCK_MIN_MODES", "DPGains", "Solution", "Sweep", "dp_gains", "solve_batch", "solve_dp",
           "solve_with_gains", "sweep"]


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
    E = model.x0_map
    R0_ff_inv = np.linalg.pinv(E.T @ R @ E + initial * np.eye(nf), rcond=1e-12, hermitian=True)
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
    E = model.x0_map
    X[0] = E @ (-gains.R0_ff_inv @ (E.T @ s))
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
    Mk[:, :nf] = model.x0_map
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
    X[0] = model.x0_map @ u[:nf]
    for k in range(N - 1):
        X[k + 1] = model.H(k) @ X[k]
        X[k + 1, nz:] += r[k]
    return _finish(model, X, r, d, W)


# --------------------------------------------------------------------------------------
# All λ in one stacked pass (issue 15)
# --------------------------------------------------------------------------------------

#: Bytes of stored feedback (K, g and the trajectories) per chunk of λ in :func:`sweep`.
SWEEP_CHUNK_BYTES = 48 * 2**20


@dataclass(frozen=True, kw_only=True, eq=False)
class Sweep:
    """Solutions of one data vector for several λ (scaled units).

    Attributes
    ----------
    lam : ndarray (n_lam,)
    residual_norm, seminorm : ndarray (n_lam,)
        ρ = ‖W^{1/2}(d − Q X)‖ and η = ‖r‖ for each λ.
    X : ndarray (n_lam, N, n_x) or None
        The trajectories when asked for (``keep=True``).
    r : ndarray (n_lam, N − 1, n_f) or None
    """

    lam: np.ndarray
    residual_norm: np.ndarray
    seminorm: np.ndarray
    X: np.ndarray | None
    r: np.ndarray | None


#: From this many modes the products with P go by its 2 × 2 blocks; below, one dense
#: product costs less than the blocks' six element-wise operations (numpy's per-call
#: overhead dominates small arrays).  Measured crossover (one BLAS thread, 1–2.5 s
#: records): 20 modes 0.42 s dense against 0.59 s by blocks, 36 modes 2.9 against 3.1 s,
#: 40 about equal, 45 modes 4.7 against 4.2 s.
BLOCK_MIN_MODES = 40


class _PBlocks:
    """Products with the modal transition ``P = [[diag a, diag b], [diag c, diag d]]`` (one
    2 × 2 block per mode, states ordered [q; q̇]) by scaling rows/columns; a dense
    product when P has another structure."""

    def __init__(self, P: np.ndarray, rows: int, min_modes: int = BLOCK_MIN_MODES):
        nz = P.shape[0]
        self.P, self.m = P, nz // 2
        m = self.m
        self.blocks = None
        if nz % 2 == 0 and m >= min_modes:
            blocks = [np.diag(P[i:i + m, j:j + m]).copy() for i in (0, m) for j in (0, m)]
            rebuilt = np.block([[np.diag(blocks[0]), np.diag(blocks[1])],
                                [np.diag(blocks[2]), np.diag(blocks[3])]])
            if np.array_equal(rebuilt, P):
                self.blocks = blocks
        self._tmp = np.empty(rows * m)

    def right(self, Y: np.ndarray, out: np.ndarray, transpose: bool = False) -> np.ndarray:
        """out = Y @ P (or Y @ Pᵀ) for Y (..., n_z)."""
        if self.blocks is None:
            return np.matmul(Y, self.P.T if transpose else self.P, out=out)
        a, b, c, d = self.blocks
        if transpose:
            b, c = c, b
        m = self.m
        y1, y2 = Y[..., :m], Y[..., m:]
        t = self._tmp[: y1.size].reshape(y1.shape)
        np.multiply(y1, a, out=out[..., :m])
        np.multiply(y2, c, out=t)
        out[..., :m] += t
        np.multiply(y1, b, out=out[..., m:])
        np.multiply(y2, d, out=t)
        out[..., m:] += t
        return out

    def left_t(self, Y: np.ndarray, out: np.ndarray) -> np.ndarray:
        """out = Pᵀ @ Y for Y (L, n_z, n)."""
        if self.blocks is None:
            return np.matmul(self.P.T, Y, out=out)
        a, b, c, d = (v[:, None] for v in self.blocks)
        m = self.m
        y1, y2 = Y[:, :m], Y[:, m:]
        t = self._tmp[: y1.size].reshape(y1.shape)
        np.multiply(y1, a, out=out[:, :m])
        np.multiply(y2, c, out=t)
        out[:, :m] += t
        np.multiply(y1, b, out=out[:, m:])
        np.multiply(y2, d, out=t)
        out[:, m:] += t
        return out


def _sweep_chunk(model: MFIModel, lams: np.ndarray, d: np.ndarray, W: np.ndarray,
                 keep: bool, block_min_modes: int):
    N, nz, nf, nx = model.n_steps, model.n_z, model.n_f, model.n_x
    L = lams.size
    c = model.f_carry
    pb = _PBlocks(model.P, L * nx, block_min_modes)
    gam = model.gamma
    gamT = np.ascontiguousarray(gam.transpose(0, 2, 1))
    Qz = model.Qz
    WQz = W[:, None] * Qz
    qzz = Qz.T @ WQz
    cross = np.einsum("sz,ksf->kzf", WQz, model.D)  # (N, nz, nf)
    crossT = np.ascontiguousarray(cross.transpose(0, 2, 1))
    qff = np.einsum("ksf,s,ksg->kfg", model.D, W, model.D)
    QWd = model.qwd(W, d)
    lam_eye = lams[:, None, None] * np.eye(nf)
    K = np.empty((N - 1, L, nf, nx))
    g = np.empty((N - 1, L, nf))
    R = np.empty((L, nx, nx))
    R[:, :nz, :nz] = qzz
    R[:, :nz, nz:] = cross[N - 1]
    R[:, nz:, :nz] = crossT[N - 1]
    R[:, nz:, nz:] = qff[N - 1]
    s = np.broadcast_to(-QWd[N - 1], (L, nx)).copy()
    RH = np.empty((L, nx, nx))
    Rn = np.empty((L, nx, nx))
    MK = np.empty((L, nx, nx))
    sn = np.empty((L, nx))
    for k in range(N - 2, -1, -1):
        # R H with H = [[P, Γ], [0, c I]]
        pb.right(R[:, :, :nz], RH[:, :, :nz])
        np.matmul(R[:, :, :nz], gam[k], out=RH[:, :, nz:])
        if c:
            RH[:, :, nz:] += R[:, :, nz:]
        M = RH[:, nz:, :]  # Tᵀ R H
        Gk = np.linalg.inv(lam_eye + R[:, nz:, nz:])
        Kk = np.matmul(Gk, M, out=K[k])
        sf = s[:, nz:]
        np.matmul(Gk, sf[:, :, None], out=g[k][:, :, None])
        # R_k = Hᵀ R H − Mᵀ G M + QᵀWQ, symmetrised
        pb.left_t(RH[:, :nz, :], Rn[:, :nz, :])
        np.matmul(gamT[k], RH[:, :nz, :], out=Rn[:, nz:, :])
        if c:
            Rn[:, nz:, :] += M
        np.matmul(np.swapaxes(M, 1, 2), Kk, out=MK)
        Rn -= MK
        np.add(Rn, np.swapaxes(Rn, 1, 2), out=R)
        R *= 0.5
        R[:, :nz, :nz] += qzz
        R[:, :nz, nz:] += cross[k]
        R[:, nz:, :nz] += crossT[k]
        R[:, nz:, nz:] += qff[k]
        # s_k = Aᵀ s − QᵀW d with A = H − T K
        sz = s[:, :nz]
        pb.right(sz, sn[:, :nz])
        np.matmul(sz, gam[k], out=sn[:, nz:])
        if c:
            sn[:, nz:] += sf
        sn -= (sf[:, None, :] @ Kk)[:, 0, :]
        sn -= QWd[k]
        s, sn = sn, s
    initial = lams if c == 0.0 else np.zeros(L)  # zeroth order penalises f_0 too
    E = model.x0_map
    R0_inv = np.linalg.pinv(E.T @ R @ E + initial[:, None, None] * np.eye(nf),
                            rcond=1e-12, hermitian=True)
    X = np.empty((N, L, nx))
    X[0] = -(R0_inv @ (s @ E)[:, :, None])[:, :, 0] @ E.T
    r = np.empty((N - 1, L, nf))
    for k in range(N - 1):
        xk = X[k]
        rk = r[k]
        np.matmul(K[k], xk[:, :, None], out=rk[:, :, None])
        rk += g[k]
        np.negative(rk, out=rk)
        nxt = X[k + 1]
        pb.right(xk[:, :nz], nxt[:, :nz], transpose=True)
        nxt[:, :nz] += xk[:, nz:] @ gamT[k]
        if c:
            np.add(xk[:, nz:], rk, out=nxt[:, nz:])
        else:
            nxt[:, nz:] = rk
    fit = X[:, :, :nz] @ Qz.T + np.einsum("ksf,klf->kls", model.D, X[:, :, nz:])
    res = np.sqrt(np.einsum("kls,s->l", (d[:, None, :] - fit) ** 2, W))
    eta = np.sqrt(np.einsum("klf,klf->l", r, r))
    if keep:
        return res, eta, X.transpose(1, 0, 2).copy(), r.transpose(1, 0, 2).copy()
    return res, eta, None, None


def sweep(model: MFIModel, d: np.ndarray, lams, weights: np.ndarray | None = None, *,
          keep: bool = False, block_min_modes: int = BLOCK_MIN_MODES) -> Sweep:
    """Solve for every λ in ``lams`` (scaled) in one stacked pass of the recursion.

    The Riccati recursion, the data pass and the forward pass run once over the time axis
    with the λ axis batched; products with the modal transition use its per-mode 2 × 2
    blocks from ``block_min_modes`` modes (:data:`BLOCK_MIN_MODES`; dense below), and
    ``Q_kᵀ W Q_k`` is assembled per step from its constant modal block and the small
    static-correction blocks.  Memory is O(N n_λ n_f n_x), bounded by splitting
    λ into chunks of :data:`SWEEP_CHUNK_BYTES`.  Same minimiser as :func:`solve_dp`
    (they agree to round-off)."""
    d, W = _check(model, d, weights)
    lams = np.atleast_1d(np.asarray(lams, dtype=float))
    if lams.ndim != 1 or lams.size == 0 or not np.all(np.isfinite(lams)) or np.any(lams <= 0):
        raise InputError("lams must be a non-empty 1-D array of positive numbers")
    per_lam = 8 * model.n_steps * (model.n_f * model.n_x + model.n_f
                                   + (model.n_x + model.n_f if keep else 0)
                                   + 2 * model.n_x + 2 * model.n_s)
    step = max(1, int(SWEEP_CHUNK_BYTES // per_lam))
    parts = [_sweep_chunk(model, lams[i:i + step], d, W, keep, block_min_modes)
             for i in range(0, lams.size, step)]
    return Sweep(
        lam=lams.copy(), residual_norm=np.concatenate([p[0] for p in parts]),
        seminorm=np.concatenate([p[1] for p in parts]),
        X=np.concatenate([p[2] for p in parts]) if keep else None,
        r=np.concatenate([p[3] for p in parts]) if keep else None,
    )
