"""Cubic Hermite functions and the Bogner–Fox–Schmit orthotropic plate element.

Contract
--------
* 1-D cubic Hermite functions on an element of length ``L``, local ``s = x / L`` in
  [0, 1], in the order ``(value at 0, slope at 0, value at 1, slope at 1)``; derivatives
  are with respect to the physical coordinate (1/m, 1/m²).
* The BFS element (16 DOF) is the tensor product of the Hermite functions in x and y:
  local DOF ``4 a + b`` is ``h_a(x) h_b(y)``, see :meth:`bwim.fe.mesh.Grid.element_dofs`.
* Stiffness of an orthotropic Kirchhoff plate with Huber's torsion (docs/theory.md §1.1)::

      K_e = D_x K_xx + D_y K_yy + sqrt(D_x D_y) K_xy,    M_e = μ M_1

  with ``D_x = E_x h³ / (12 (1 − ν²))`` etc.  The three *unit matrices* depend only on
  the element size and ν, so K is rebuilt for new moduli without re-integration.
* All integrals are products of 1-D integrals of polynomials of degree ≤ 6, which 4-point
  Gauss–Legendre quadrature integrates exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "HermiteIntegrals",
    "bfs_shape",
    "bfs_unit_matrices",
    "flexural_rigidity",
    "hermite",
    "hermite_integrals",
]

_GAUSS_S, _GAUSS_W = np.polynomial.legendre.leggauss(4)
_GAUSS_S = 0.5 * (_GAUSS_S + 1.0)  # to [0, 1]
_GAUSS_W = 0.5 * _GAUSS_W


def hermite(s: np.ndarray, length: float | np.ndarray) -> tuple[np.ndarray, ...]:
    """Cubic Hermite functions and their x-derivatives at local coordinates ``s``.

    Parameters
    ----------
    s : array_like, shape (n,)
        Local coordinates in [0, 1].
    length : float or array_like, shape (n,)
        Element length(s), m.

    Returns
    -------
    h, dh, d2h : ndarray, each shape (n, 4)
        Values, first and second derivatives with respect to x.
    """
    s = np.atleast_1d(np.asarray(s, dtype=float))
    L = np.broadcast_to(np.asarray(length, dtype=float), s.shape)
    s2, s3 = s * s, s * s * s
    one = np.ones_like(s)
    h = np.stack([1 - 3 * s2 + 2 * s3, L * (s - 2 * s2 + s3), 3 * s2 - 2 * s3, L * (s3 - s2)], 1)
    dh = np.stack(
        [(6 * s2 - 6 * s) / L, one - 4 * s + 3 * s2, (6 * s - 6 * s2) / L, 3 * s2 - 2 * s], 1
    )
    d2h = np.stack(
        [(12 * s - 6) / L**2, (6 * s - 4) / L, (6 - 12 * s) / L**2, (6 * s - 2) / L], 1
    )
    return h, dh, d2h


@dataclass(frozen=True)
class HermiteIntegrals:
    """Exact 1-D integrals over an element of length L (each a 4 × 4 array).

    ``m00 = ∫ h hᵀ``, ``k11 = ∫ h' h'ᵀ``, ``k22 = ∫ h'' h''ᵀ``, ``k20 = ∫ h'' hᵀ``.
    """

    m00: np.ndarray
    k11: np.ndarray
    k22: np.ndarray
    k20: np.ndarray


def hermite_integrals(length: float) -> HermiteIntegrals:
    """1-D Hermite integrals by 4-point Gauss–Legendre quadrature (exact)."""
    h, dh, d2h = hermite(_GAUSS_S, length)
    w = _GAUSS_W * length
    return HermiteIntegrals(
        m00=np.einsum("q,qi,qj->ij", w, h, h),
        k11=np.einsum("q,qi,qj->ij", w, dh, dh),
        k22=np.einsum("q,qi,qj->ij", w, d2h, d2h),
        k20=np.einsum("q,qi,qj->ij", w, d2h, h),
    )


def flexural_rigidity(modulus: np.ndarray | float, thickness: float, poisson: float):
    """Plate flexural rigidity ``E h³ / (12 (1 − ν²))`` (N·m)."""
    return np.asarray(modulus) * thickness**3 / (12.0 * (1.0 - poisson**2))


def bfs_unit_matrices(a: float, b: float, poisson: float) -> tuple[np.ndarray, ...]:
    """Unit stiffness and mass matrices of an ``a × b`` BFS element.

    Returns
    -------
    k_xx, k_yy, k_xy, m_1 : ndarray, each shape (16, 16)
        ``K_e = D_x k_xx + D_y k_yy + sqrt(D_x D_y) k_xy`` and ``M_e = μ m_1``.
        ``k_xy`` holds the Poisson coupling ``D_1 = ν sqrt(D_x D_y)`` and the Huber twist
        rigidity ``D_xy = (1 − ν) sqrt(D_x D_y) / 2`` (energy term ``4 D_xy w_xy²``).
    """
    X = hermite_integrals(a)
    Y = hermite_integrals(b)
    k_xx = np.kron(X.k22, Y.m00)
    k_yy = np.kron(X.m00, Y.k22)
    coupling = np.kron(X.k20, Y.k20.T)  # ∫ N_i,xx N_j,yy dA
    k_xy = poisson * (coupling + coupling.T) + 2.0 * (1.0 - poisson) * np.kron(X.k11, Y.k11)
    m_1 = np.kron(X.m00, Y.m00)
    return k_xx, k_yy, k_xy, m_1


def bfs_shape(
    xi: np.ndarray, eta: np.ndarray, a: np.ndarray | float, b: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """BFS shape functions and curvature rows at local points.

    Returns
    -------
    n, n_xx, n_yy : ndarray, each shape (n_points, 16)
        ``w = n @ u_e``, ``w_xx = n_xx @ u_e``, ``w_yy = n_yy @ u_e``.
    """
    hx, _, d2hx = hermite(xi, a)
    hy, _, d2hy = hermite(eta, b)
    n = np.einsum("pa,pb->pab", hx, hy).reshape(-1, 16)
    n_xx = np.einsum("pa,pb->pab", d2hx, hy).reshape(-1, 16)
    n_yy = np.einsum("pa,pb->pab", hx, d2hy).reshape(-1, 16)
    return n, n_xx, n_yy
