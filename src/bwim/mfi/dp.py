"""Tikhonov-regularised force identification by dynamic programming, and its batch twin.

Contract
--------
Minimise over the initial forces ``f_0`` (the bridge starts at rest: ``X_0 = E f_0`` with
``E`` = :attr:`~bwim.mfi.statespace.MFIModel.x0_map`) and the unknowns ``r_0 … r_{N−2}``
(docs/theory.md §4; Dowling et al. (2012) eqs. (2) and (3))::

    J = Σ_k ‖W^{1/2} (d_k − Q_k X_k)‖² + λ Σ_k ‖r_k‖² [+ λ ‖f_0‖²],   X_{k+1} = H_k X_k + T r_k

In first order ``f_0`` is free (only force *changes* are penalised); in zeroth order
``r_k = f_{k+1}`` and ``f_0`` is penalised like every other force value.

* :func:`solve_dp` is Bellman's recursion (docs/theory.md §4): cost-to-go
  ``V_k(X) = Xᵀ R_k X + 2 s_kᵀ X + const`` backwards, then the optimal ``r_k = −K_k X_k −
  g_k`` forwards.  O(N) time and memory in the record length.  The gains do not depend on
  the data: :func:`dp_gains` computes them once and :func:`solve_with_gains` reuses them
  for further data vectors (GCV probes).
* :func:`sweep` runs the same recursion for many λ at once (the L-curve), in O(N) time
  and memory per λ, within the memory limit.
* :func:`solve_batch` stacks the whole problem as one dense least-squares system; it is
  O(N³) and exists to check the recursion (they agree to round-off).
* Everything is in the model's scaled units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.limits import check_memory, memory_limit
from bwim.mfi.statespace import MFIModel

__all__ = ["BLOCK_MIN_MODES", "DPGains", "Solution", "Sweep", "dp_gains", "solve_batch", "solve_dp",
           "solve_with_gains", "sweep", "sweep_bytes"]


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
    R = QWQ[N - 1]  # docs/theory.md §4: R_N = QᵀWQ
    for k in range(N - 2, -1, -1):
        H = Hs[k]  # Dowling et al. (2012) eq. (2): X_{k+1} = H_k X_k + T r_k
        Gk = np.linalg.inv(lam_eye + R[nz:, nz:])  # docs/theory.md §4: G_k = (λI + TᵀRT)⁻¹
        Kk = Gk @ (R[nz:] @ H)  # docs/theory.md §4: K_k = G_k Tᵀ R_{k+1} H_k
        Ak = A[k]
        Ak[:] = H
        Ak[nz:] -= Kk
        # docs/theory.md §4: R_k = QᵀWQ + H_kᵀ R_{k+1} (H_k − T K_k), symmetrised
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
    s = -QWd[N - 1]  # docs/theory.md §4: s_N = −QᵀW d_N
    for k in range(N - 2, -1, -1):
        g[k] = gains.G[k] @ s[nz:]  # docs/theory.md §4: g_k = G_k Tᵀ s_{k+1}
        s = gains.A[k].T @ s - QWd[k]  # docs/theory.md §4: s_k = −QᵀWd_k + (H − TK)ᵀ s_{k+1}
    X = np.zeros((N, model.n_x))
    E = model.x0_map
    X[0] = E @ (-gains.R0_ff_inv @ (E.T @ s))
    r = np.empty((N - 1, nf))
    Hs = model.H_all
    for k in range(N - 1):  # docs/theory.md §4, forward pass
        r[k] = -gains.K[k] @ X[k] - g[k]  # r_k = −K_k X_k − g_k
        X[k + 1] = Hs[k] @ X[k]  # Dowling et al. (2012) eq. (2)
        X[k + 1, nz:] += r[k]
    return _finish(model, X, r, d, W)


def _finish(model, X, r, d, W) -> Solution:
    # Dowling et al. (2012) eq. (3): the readings ε_k = Q X_k
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
    # docs/theory.md §4 (Tikhonov functional): J = Σ ‖W^{1/2}(d_k − Q X_k)‖² + λ Σ ‖r_k‖²
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
# All λ in one stacked pass (issue 15), chunked by the memory limit (issue 23)
# --------------------------------------------------------------------------------------

#: Share of the memory limit (:func:`bwim.limits.memory_limit`) that :func:`sweep` may
#: hold; the λ are split into as few chunks as fit in it.
SWEEP_MEMORY_SHARE = 0.5

#: Steps between two symmetrisations of the stacked cost-to-go Hessians in :func:`sweep`
#: (round-off leaves them a few ulp from symmetric per step; the closed-loop recursion
#: does not amplify it).
SYM_EVERY = 16


@dataclass(frozen=True, kw_only=True, eq=False)
class Sweep:
    """Solutions of one data vector for several λ (scaled units).

    Attributes
    ----------
    lam : ndarray (n_lam,)
    residual_norm, seminorm : ndarray (n_lam,)
        ρ = ‖W^{1/2}(d − Q X)‖ and η = ‖r‖ for each λ.
    X : ndarray (n_lam, N, n_x) or None
        The trajectories when asked for (``keep=True``); like ``r`` and ``forces``, a
        λ-first view of the pass's step-first arrays when all λ went in one chunk (index
        the λ wanted; copy it to let the others go).
    r : ndarray (n_lam, N − 1, n_f) or None
    forces : ndarray (n_lam, N, n_f) or None
        The scaled forces, when asked for (``keep=True`` or ``keep_forces=True``).
    """

    lam: np.ndarray
    residual_norm: np.ndarray
    seminorm: np.ndarray
    X: np.ndarray | None
    r: np.ndarray | None
    forces: np.ndarray | None = None


#: From this many modes the products with P go by its 2 × 2 blocks; below, one dense
#: product costs less than the blocks' six element-wise operations on strided views
#: (numpy's per-call and per-row overhead dominates these small arrays).
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
                 keep: bool, keep_forces: bool, block_min_modes: int):
    """One stacked pass for the λ in ``lams``.  The cost-to-go is carried in augmented
    form, ``V_k(X) = [X; 1]ᵀ R̃_k [X; 1]`` with ``R̃ = [[R, s], [sᵀ, c]]``, so that the
    Riccati step of docs/theory.md §4 updates ``R_k``, ``s_k`` and the constant together
    and one solve gives both ``K_k`` and ``g_k`` (``K̃ = [K, g]``, ``r_k = −K̃ [X_k; 1]``)."""
    N, nz, nf, nx = model.n_steps, model.n_z, model.n_f, model.n_x
    na = nx + 1
    L = lams.size
    c = model.f_carry
    pb = _PBlocks(model.P, L * na, block_min_modes)
    Qz = model.Qz
    WQz = W[:, None] * Qz
    QWd = model.qwd(W, d)
    # Q̃_k = [[QᵀWQ, −QᵀWd], [−dᵀWQ, dᵀWd]]: its modal block is constant, the columns
    # of [f; 1] change with the step
    qcol = np.empty((N, na, nf + 1))
    np.matmul(WQz.T, model.D, out=qcol[:, :nz, :nf])
    np.matmul(np.swapaxes(model.D * W[:, None], 1, 2), model.D, out=qcol[:, nz:nx, :nf])
    qcol[:, :nx, nf] = -QWd
    qcol[:, nx, :nf] = -QWd[:, nz:]
    qcol[:, nx, nf] = (d * d) @ W
    Qt = np.zeros((na, na))
    Qt[:nz, :nz] = Qz.T @ WQz
    Hf = np.empty((N, nx, nf))  # the force columns of H_k: [Γ_k; c I]
    Hf[:, :nz] = model.gamma
    Hf[:, nz:] = c * np.eye(nf)
    lam_eye = lams[:, None, None] * np.eye(nf)
    K = np.empty((N - 1, L, nf, na))  # −K̃_k
    R = np.empty((L, na, na))
    Qt[:, nz:] = qcol[N - 1]
    Qt[nz:, :] = qcol[N - 1].T
    R[:] = Qt
    RH = np.empty((L, na, na))
    Rn = np.empty((L, na, na))
    MK = np.empty((L, na, na))
    S = np.empty((L, nf, nf))
    for k in range(N - 2, -1, -1):
        # docs/theory.md §4 (Bellman): R̃ H̃_k with H̃ = [[P, Γ_k, 0], [0, c I, 0], [0, 0, 1]]
        pb.right(R[:, :, :nz], RH[:, :, :nz])
        np.matmul(R[:, :, :nx], Hf[k], out=RH[:, :, nz:nx])
        RH[:, :, nx] = R[:, :, nx]
        M = RH[:, nz:nx, :]  # T̃ᵀ R̃ H̃
        # G_k = (λ I + Tᵀ R T)⁻¹, [K_k, g_k] = G_k Tᵀ [R H, s]
        np.add(R[:, nz:nx, nz:nx], lam_eye, out=S)
        Kk = np.matmul(np.linalg.inv(S), M, out=K[k])
        np.negative(Kk, out=Kk)
        # R̃_k = Q̃_k + H̃ᵀ R̃ H̃ − M̃ᵀ G M̃
        pb.left_t(RH[:, :nz, :], Rn[:, :nz, :])
        np.matmul(Hf[k].T, RH[:, :nx, :], out=Rn[:, nz:nx, :])
        Rn[:, nx, :] = RH[:, nx, :]
        np.matmul(np.swapaxes(M, 1, 2), Kk, out=MK)
        Rn += MK
        Qt[:, nz:] = qcol[k]
        Qt[nz:, :] = qcol[k].T
        if k % SYM_EVERY == 0:
            np.add(Rn, np.swapaxes(Rn, 1, 2), out=R)
            R *= 0.5
            R += Qt
        else:
            np.add(Rn, Qt, out=R)
    # the initial forces minimise V_0 over X_0 = E f_0 (zeroth order penalises f_0 too)
    initial = lams if c == 0.0 else np.zeros(L)
    E = model.x0_map
    R0_inv = np.linalg.pinv(E.T @ R[:, :nx, :nx] @ E + initial[:, None, None] * np.eye(nf),
                            rcond=1e-12, hermitian=True)
    X = np.empty((N, L, na))
    X[:, :, nx] = 1.0
    X[0, :, :nx] = -(R0_inv @ (R[:, :nx, nx] @ E)[:, :, None])[:, :, 0] @ E.T
    r = np.empty((N - 1, L, nf))
    # docs/theory.md §4 forward pass: r_k = −K̃_k [X_k; 1] and Dowling et al. (2012)
    # eq. (2), X_{k+1} = H_k X_k + T r_k
    for k in range(N - 1):
        xk = X[k]
        rk = r[k]
        np.matmul(K[k], xk[:, :, None], out=rk[:, :, None])
        nxt = X[k + 1]
        pb.right(xk[:, :nz], nxt[:, :nz], transpose=True)
        nxt[:, :nz] += xk[:, nz:nx] @ model.gamma[k].T
        if c:
            np.add(xk[:, nz:nx], rk, out=nxt[:, nz:nx])
        else:
            nxt[:, nz:nx] = rk
    del K
    res = np.empty(L)
    for j in range(L):  # ρ = ‖W^{1/2}(d − Q X)‖ (Dowling et al. (2012) eq. (3)), per λ
        fit = X[:, j, :nz] @ Qz.T
        fit += np.matmul(model.D, X[:, j, nz:nx, None])[:, :, 0]
        fit -= d
        fit *= fit
        res[j] = np.sqrt(fit.sum(axis=0) @ W)
    eta = np.sqrt(np.einsum("klf,klf->l", r, r))
    # λ-first views of the step-first arrays, not copies: the caller takes the one λ it
    # needs (a copy of all of them cost as much as a tenth of the pass)
    Xk = X[:, :, :nx].transpose(1, 0, 2) if keep else None
    rk = r.transpose(1, 0, 2) if keep else None
    fk = X[:, :, nz:nx].transpose(1, 0, 2) if keep or keep_forces else None
    return res, eta, Xk, rk, fk


def sweep_bytes(model: MFIModel, n_lam: int, *, keep: bool = False,
                keep_forces: bool = False) -> float:
    """Bytes :func:`sweep` holds for ``n_lam`` λ in one chunk: the per-step model arrays
    it builds once, and per λ the feedback gains, the trajectory, the seminorm's
    increments and what is kept (counted as copies, which it is when the λ go in several
    chunks; one chunk hands out views, so this is an upper bound)."""
    N, nf, nx, ns = model.n_steps, model.n_f, model.n_x, model.n_s
    fixed = N * ((nx + 1) * (nf + 1) + nx * nf + nx + 2 * ns)
    per_lam = N * (nf * (nx + 1) + (nx + 1) + nf + (nx + nf if keep else 0)
                   + (nf if keep or keep_forces else 0))
    return 8.0 * (fixed + n_lam * per_lam)


def sweep(model: MFIModel, d: np.ndarray, lams, weights: np.ndarray | None = None, *,
          keep: bool = False, keep_forces: bool = False,
          block_min_modes: int = BLOCK_MIN_MODES) -> Sweep:
    """Solve for every λ in ``lams`` (scaled) in one stacked pass of the recursion.

    The Riccati recursion (in augmented form, with the data term), the forward pass and
    the norms run once over the time axis with the λ axis batched; products with the
    modal transition use its per-mode 2 × 2 blocks from ``block_min_modes`` modes
    (:data:`BLOCK_MIN_MODES`; dense below).  Time and memory are O(N n_λ) in the record
    length N; the λ are split into as few chunks as fit in :data:`SWEEP_MEMORY_SHARE` of
    the memory limit (:func:`sweep_bytes`; one λ that does not fit raises
    :class:`~bwim.errors.InputError`).  Same minimiser as :func:`solve_dp` (they agree to
    round-off)."""
    d, W = _check(model, d, weights)
    lams = np.atleast_1d(np.asarray(lams, dtype=float))
    if lams.ndim != 1 or lams.size == 0 or not np.all(np.isfinite(lams)) or np.any(lams <= 0):
        raise InputError("lams must be a non-empty 1-D array of positive numbers")
    opts = {"keep": keep, "keep_forces": keep_forces}
    check_memory(sweep_bytes(model, 1, **opts),
                 f"the force identification of a record of {model.n_steps} samples")
    one = sweep_bytes(model, 1, **opts) - sweep_bytes(model, 0, **opts)
    room = SWEEP_MEMORY_SHARE * memory_limit() - sweep_bytes(model, 0, **opts)
    step = max(1, int(room // one))
    parts = [_sweep_chunk(model, lams[i:i + step], d, W, keep, keep_forces, block_min_modes)
             for i in range(0, lams.size, step)]

    def joined(i):
        if parts[0][i] is None:
            return None
        return parts[0][i] if len(parts) == 1 else np.concatenate([p[i] for p in parts])

    return Sweep(lam=lams.copy(), residual_norm=joined(0), seminorm=joined(1), X=joined(2),
                 r=joined(3), forces=joined(4))
