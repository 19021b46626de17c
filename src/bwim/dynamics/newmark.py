"""Newmark-β time integration of linear systems ``M ü + C u̇ + K u = f(t)``.

Contract
--------
* :class:`Newmark` holds β, γ and the step Δt and gives the standard coefficients
  ``a0 … a5`` (Bathe's notation) and the history terms built from them; nothing else in
  bwim spells a Newmark coefficient out.  The default (β = 1/4, γ = 1/2) is the
  average-acceleration rule (docs/theory.md §2.3): unconditionally stable, second-order
  accurate, no numerical damping.
* :func:`integrate` advances a time-invariant system over a whole load history with a
  precomputed step operator ``[u; v; a]ₖ₊₁ = A [u; v; a]ₖ + B fₖ₊₁``: one small matrix
  product per step.  Diagonal systems (modal coordinates) may pass 1-D arrays for M, C, K
  and are advanced for all modes at once.
* :func:`final_state` gives the last row of :func:`integrate` (u, v, a at the last step)
  without the history: for average acceleration a weighted sum of the loads in the
  eigenbasis of the two-step recursion (equal to the stepping up to round-off).
* The same step (:meth:`Newmark.effective`, :meth:`Newmark.history`,
  :meth:`Newmark.update`) is used by the time-varying vehicle–bridge solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_positive

__all__ = ["FinalState", "Newmark", "NewmarkResult", "final_state", "integrate"]


@dataclass(frozen=True)
class Newmark:
    """Newmark-β coefficients for a time step ``dt``."""

    dt: float
    beta: float = 0.25
    gamma: float = 0.5

    def __post_init__(self) -> None:
        require_positive("dt", self.dt)
        if not (0.0 < self.beta <= 0.5 and 0.5 <= self.gamma <= 1.0):
            raise InputError(f"Newmark needs 0 < beta <= 0.5 and 0.5 <= gamma <= 1, "
                             f"got beta={self.beta}, gamma={self.gamma}")

    @property
    def a0(self) -> float:
        """Coefficient of M in the effective stiffness (and of u in M's history)."""
        return 1.0 / (self.beta * self.dt**2)

    @property
    def a1(self) -> float:
        """Coefficient of C in the effective stiffness (and of u in C's history)."""
        return self.gamma / (self.beta * self.dt)

    @property
    def a2(self) -> float:
        """Coefficient of v in M's history."""
        return 1.0 / (self.beta * self.dt)

    @property
    def a3(self) -> float:
        """Coefficient of a in M's history."""
        return 0.5 / self.beta - 1.0

    @property
    def a4(self) -> float:
        """Coefficient of v in C's history."""
        return self.gamma / self.beta - 1.0

    @property
    def a5(self) -> float:
        """Coefficient of a in C's history."""
        return self.dt * (0.5 * self.gamma / self.beta - 1.0)

    @property
    def is_average_acceleration(self) -> bool:
        """β = 1/4, γ = 1/2 (the default rule)."""
        return self.beta == 0.25 and self.gamma == 0.5

    def effective(self, M, C, K):
        """Effective stiffness ``K + a1 C + a0 M``."""
        return K + self.a1 * C + self.a0 * M

    def mass_history(self, u, v, a):
        """``a0 u + a2 v + a3 a``: what multiplies M in the known part of the load."""
        return self.a0 * u + self.a2 * v + self.a3 * a

    def damping_history(self, u, v, a):
        """``a1 u + a4 v + a5 a``: what multiplies C in the known part of the load."""
        return self.a1 * u + self.a4 * v + self.a5 * a

    def history(self, M, C, u, v, a):
        """The known part of the effective load: ``M(·) + C(·)`` of the last state.

        Works for full matrices (vectors u, v, a) and for diagonal 1-D arrays.
        """
        mu = self.mass_history(u, v, a)
        cu = self.damping_history(u, v, a)
        if np.ndim(M) == 1:
            return M * mu + C * cu
        return M @ mu + C @ cu

    def update(self, u_new, u, v, a):
        """Velocity and acceleration at the new step from the new displacement."""
        a_new = self.a0 * (u_new - u) - self.a2 * v - self.a3 * a
        v_new = v + self.dt * ((1.0 - self.gamma) * a + self.gamma * a_new)
        return v_new, a_new


@dataclass(frozen=True, kw_only=True, eq=False)
class NewmarkResult:
    """Displacements, velocities and accelerations, each shape (n_t, n)."""

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray


def integrate(
    M: np.ndarray,
    C: np.ndarray,
    K: np.ndarray,
    f: np.ndarray,
    scheme: Newmark,
    u0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
    a0: np.ndarray | None = None,
) -> NewmarkResult:
    """Integrate ``M ü + C u̇ + K u = f`` from ``u0``, ``v0`` over ``f`` (n_t, n).

    ``f[0]`` is the load at the initial time; it sets the initial acceleration unless
    ``a0`` is given (continuing a run whose loads changed at that instant).  The result has
    the same n_t rows.  1-D M, C, K mean a diagonal (uncoupled) system.
    """
    f = np.asarray(f, dtype=float)
    if f.ndim != 2:
        raise InputError("f must have shape (n_t, n)")
    n_t, n = f.shape
    diag = np.ndim(M) == 1
    u = np.zeros(n) if u0 is None else np.asarray(u0, dtype=float).copy()
    v = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).copy()
    U = np.empty((n_t, n))
    V = np.empty((n_t, n))
    A = np.empty((n_t, n))
    if diag:
        M, C, K = (np.broadcast_to(np.asarray(x, dtype=float), (n,)) for x in (M, C, K))
        a = (f[0] - C * v - K * u) / M if a0 is None else np.asarray(a0, dtype=float).copy()
        start = 0
        if not (u.any() or v.any() or a.any()):
            # at rest under no load until the first load: nothing moves (exact zeros)
            loaded = np.flatnonzero(f.any(axis=1))
            start = max(int(loaded[0]) - 1, 0) if loaded.size else n_t - 1
            U[:start], V[:start], A[:start] = 0.0, 0.0, 0.0
        keff = scheme.effective(M, C, K)
        U[start], V[start], A[start] = u, v, a
        # two steps by the stepping rule, then (average acceleration) the same recursion
        # as a linear filter of the loads (:func:`_filter_modes`)
        explicit = n_t if not scheme.is_average_acceleration else min(start + 3, n_t)
        for k in range(start + 1, explicit):
            u_new = (f[k] + scheme.history(M, C, u, v, a)) / keff
            v, a = scheme.update(u_new, u, v, a)
            u = u_new
            U[k], V[k], A[k] = u, v, a
        if explicit < n_t:
            _filter_modes(M, C, K, f, scheme.dt, explicit, (U, V, A))
        return NewmarkResult(u=U, v=V, a=A)
    a = np.linalg.solve(M, f[0] - C @ v - K @ u) if a0 is None else np.asarray(a0, float).copy()
    # step operator: z_{k+1} = Tz z_k + Tf f_{k+1}, z = [u; v; a]
    kinv = np.linalg.inv(scheme.effective(M, C, K))
    g, dt = scheme.gamma, scheme.dt
    I = np.eye(n)
    hu = kinv @ (scheme.a0 * M + scheme.a1 * C)
    hv = kinv @ (scheme.a2 * M + scheme.a4 * C)
    ha = kinv @ (scheme.a3 * M + scheme.a5 * C)
    au = scheme.a0 * (hu - I)
    av = scheme.a0 * hv - scheme.a2 * I
    aa = scheme.a0 * ha - scheme.a3 * I
    Tz = np.block([
        [hu, hv, ha],
        [dt * g * au, I + dt * g * av, dt * ((1 - g) * I + g * aa)],
        [au, av, aa],
    ])
    Tf = np.vstack([kinv, dt * g * scheme.a0 * kinv, scheme.a0 * kinv])
    Z = np.empty((n_t, 3 * n))
    Z[0] = np.concatenate([u, v, a])
    forced = Tf @ f.T  # (3n, n_t)
    z = Z[0]
    explicit = min(3, n_t) if scheme.is_average_acceleration else n_t
    for k in range(1, explicit):
        z = Tz @ z + forced[:, k]
        Z[k] = z
    res = NewmarkResult(u=Z[:, :n], v=Z[:, n:2 * n], a=Z[:, 2 * n:])
    if explicit < n_t and not _filter_coupled(M, C, K, f, scheme.dt, explicit,
                                              (res.u, res.v, res.a)):
        for k in range(explicit, n_t):  # an eigenbasis too ill-conditioned: keep stepping
            z = Tz @ z + forced[:, k]
            Z[k] = z
    return res


def _filter_modes(M, C, K, f, dt, k0, out) -> None:
    """Continue the average-acceleration recursion of uncoupled modes from step ``k0`` as
    a linear recursive filter of the loads (scipy.signal.lfilter), filling ``out`` =
    (U, V, A) in place from row ``k0`` (rows ``k0 − 2`` and ``k0 − 1`` must be filled).

    Eliminating v and a from the Newmark relations (β = 1/4, γ = 1/2) and the equations of
    motion at three consecutive steps gives, per mode, with h = Δt and D(z) =
    (m + h c/2 + h² k/4) z² + (h² k/2 − 2 m) z + (m − h c/2 + h² k/4)::

        U = (h²/4)(z + 1)² F / D,   V = (h/2)(z² − 1) F / D,   A = (z − 1)² F / D

    (the trapezoid rule links them: (z − 1) U = (h/2)(z + 1) V, (z − 1) V = (h/2)(z + 1) A).
    The filters' initial conditions come from the two previous steps (lfiltic).  Equal
    to the stepping up to round-off.
    """
    from scipy import signal  # here, not at import: scipy.signal is slow to import

    h = dt
    nums = (h * h / 4 * np.array([1.0, 2.0, 1.0]), h / 2 * np.array([1.0, 0.0, -1.0]),
            np.array([1.0, -2.0, 1.0]))
    x_past = f[k0 - 1::-1][:2] if k0 >= 2 else None
    for m in range(f.shape[1]):
        den = np.array([M[m] + h * C[m] / 2 + h * h * K[m] / 4, h * h * K[m] / 2 - 2 * M[m],
                        M[m] - h * C[m] / 2 + h * h * K[m] / 4])
        x = f[k0:, m]
        for b, Y in zip(nums, out, strict=True):
            zi = signal.lfiltic(b, den, Y[k0 - 1::-1, m][:2], x_past[:, m])
            Y[k0:, m] = signal.lfilter(b, den, x, zi=zi)[0]


#: Largest condition number of the eigenvector basis :func:`_filter_coupled` accepts.
MAX_EIGENBASIS_CONDITION = 1e6


def _companion(M, C, K, h):
    """Eigen-decomposition of the average-acceleration two-step recursion (see
    :func:`_filter_coupled`): ``(lam, V, V⁻¹, V⁻¹ B)``, or None when the eigenbasis is
    ill-conditioned (near-defective companion matrix)."""
    n = M.shape[0]
    Ke = M + h / 2 * C + h * h / 4 * K
    Ki = np.linalg.inv(Ke)
    A = np.zeros((2 * n, 2 * n))
    A[:n, :n] = -Ki @ (h * h / 2 * K - 2 * M)
    A[:n, n:] = -Ki @ (M - h / 2 * C + h * h / 4 * K)
    A[n:, :n] = np.eye(n)
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) > MAX_EIGENBASIS_CONDITION:
        return None
    Vi = np.linalg.inv(V)
    return lam, V, Vi, Vi[:, :n] @ Ki


def _forcings(f, h, k0):
    """The right-hand sides ``N`` of u, v and a from step ``k0`` on (see
    :func:`_filter_coupled`)."""
    fk1, fk, fkm1 = f[k0:], f[k0 - 1:-1], f[k0 - 2:-2]
    return h * h / 4 * (fk1 + 2 * fk + fkm1), h / 2 * (fk1 - fkm1), fk1 - 2 * fk + fkm1


def _filter_coupled(M, C, K, f, dt, k0, out) -> bool:
    """The coupled (full-matrix) twin of :func:`_filter_modes`: continue the
    average-acceleration recursion from step ``k0`` as first-order complex filters.

    With ``K_e = M + h C/2 + h² K/4``, ``D₁ = h² K/2 − 2 M``, ``D₂ = M − h C/2 + h² K/4``,
    each of u, v, a obeys ``K_e y_{k+1} + D₁ y_k + D₂ y_{k−1} = N_{k+1}`` with
    ``N = (h²/4)(f_{k+1} + 2 f_k + f_{k−1})``, ``(h/2)(f_{k+1} − f_{k−1})`` and
    ``f_{k+1} − 2 f_k + f_{k−1}`` respectively.  In companion form ``w = [y_k; y_{k−1}]``,
    ``w_{k+1} = A w_k + B N_{k+1}``; in A's eigenbasis every coordinate is a first-order
    recursion (lfilter).  Returns False (and leaves ``out`` alone) when the eigenbasis
    is ill-conditioned (near-defective A)."""
    from scipy import signal  # here, not at import: scipy.signal is slow to import

    n = M.shape[0]
    eig = _companion(M, C, K, dt)
    if eig is None:
        return False
    lam, V, Vi, ViB = eig
    # u, v and a side by side: (n_t − k0, 2n, 3) forcings in the eigenbasis
    e = np.stack([N @ ViB.T for N in _forcings(f, dt, k0)], axis=2)
    xi0 = Vi @ np.stack([np.concatenate([Y[k0 - 1], Y[k0 - 2]]) for Y in out], axis=1)
    xi = np.empty_like(e)
    for j in range(2 * n):
        xi[:, j] = signal.lfilter([1.0], [1.0, -lam[j]], e[:, j], axis=0,
                                  zi=lam[j] * xi0[j][None, :])[0]
    for i, Y in enumerate(out):
        Y[k0:] = (xi[:, :, i] @ V[:n].T).real
    return True


@dataclass(frozen=True, kw_only=True)
class FinalState:
    """Displacement, velocity and acceleration at one step, each shape (n,)."""

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray


def final_state(
    M: np.ndarray,
    C: np.ndarray,
    K: np.ndarray,
    f: np.ndarray,
    scheme: Newmark,
    u0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
    a0: np.ndarray | None = None,
) -> FinalState:
    """The last row of :func:`integrate` with the same arguments (full M, C, K), without
    the history.

    For average acceleration, after the two stepped rows the recursion of
    :func:`_filter_coupled` is summed in closed form: in the companion eigenbasis
    ``ξ_last = λ^(n_t−k0) ξ₀ + Σ_k λ^(n_t−1−k) V⁻¹B N_k``, one weighted sum of the loads
    (equal to the stepping up to round-off).  Other schemes, or an ill-conditioned
    eigenbasis, step through :func:`integrate`.
    """
    f = np.asarray(f, dtype=float)
    if f.ndim != 2 or np.ndim(M) != 2:
        raise InputError("final_state needs full M, C, K and f of shape (n_t, n)")
    n_t, n = f.shape
    k0 = 3
    eig = (_companion(M, C, K, scheme.dt)
           if scheme.is_average_acceleration and n_t > k0 else None)
    if eig is None or not np.all(eig[0]):  # (a zero eigenvalue has no logarithm)
        res = integrate(M, C, K, f, scheme, u0=u0, v0=v0, a0=a0)
        return FinalState(u=res.u[-1], v=res.v[-1], a=res.a[-1])
    lam, V, Vi, ViB = eig
    head = integrate(M, C, K, f[:k0], scheme, u0=u0, v0=v0, a0=a0)
    xi0 = Vi @ np.stack([np.concatenate([Y[k0 - 1], Y[k0 - 2]])
                         for Y in (head.u, head.v, head.a)], axis=1)  # (2n, 3)
    N = np.concatenate(_forcings(f, scheme.dt, k0), axis=1)[::-1]  # (n_t − k0, 3n)
    S = (_powers(lam, N.shape[0]) @ N).reshape(2 * n, 3, n)  # Σ_k λ_j^p N_k, u, v, a
    xi = lam[:, None] ** (n_t - k0) * xi0 + np.einsum("jm,jim->ji", ViB, S)
    y = (V[:n] @ xi).real  # (n, 3)
    return FinalState(u=y[:, 0], v=y[:, 1], a=y[:, 2])


def _powers(lam: np.ndarray, n: int, block: int = 64) -> np.ndarray:
    """``lam[:, None] ** arange(n)`` as products ``λ^(block·b) λ^r`` of two short tables
    (a complex power per element costs far more than a product)."""
    nb = -(-n // block)
    log = np.log(lam.astype(complex))[:, None]
    outer = np.exp(log * (block * np.arange(nb)))[:, :, None]
    inner = np.exp(log * np.arange(block))[:, None, :]
    return (outer * inner).reshape(lam.size, nb * block)[:, :n]
