"""Newmark-β time integration of linear systems ``M ü + C u̇ + K u = f(t)``.

Contract
--------
* :class:`Newmark` holds β, γ and the step Δt and gives the standard coefficients
  ``a0 … a5`` (Bathe's notation) and the history terms built from them; nothing else in
  bwim spells a Newmark coefficient out.  The default (β = 1/4, γ = 1/2) is the
  average-acceleration rule: unconditionally stable, second-order accurate, no numerical
  damping.
* :func:`integrate` advances a time-invariant system over a whole load history with a
  precomputed step operator ``[u; v; a]ₖ₊₁ = A [u; v; a]ₖ + B fₖ₊₁``: one small matrix
  product per step.  Diagonal systems (modal coordinates) may pass 1-D arrays for M, C, K
  and are advanced for all modes at once.
* The same step (:meth:`Newmark.effective`, :meth:`Newmark.history`,
  :meth:`Newmark.update`) is used by the time-varying vehicle–bridge solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_positive

__all__ = ["Newmark", "NewmarkResult", "integrate"]


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
        a = (f[0] - C * v - K * u) / M if a0 is None else np.asarray(a0, dtype=float).copy()
        keff = scheme.effective(M, C, K)
        U[0], V[0], A[0] = u, v, a
        for k in range(1, n_t):
            u_new = (f[k] + scheme.history(M, C, u, v, a)) / keff
            v, a = scheme.update(u_new, u, v, a)
            u = u_new
            U[k], V[k], A[k] = u, v, a
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
    for k in range(1, n_t):
        z = Tz @ z + forced[:, k]
        Z[k] = z
    return NewmarkResult(u=Z[:, :n], v=Z[:, n:2 * n], a=Z[:, 2 * n:])
