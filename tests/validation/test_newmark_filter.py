"""The average-acceleration rule as recursive filters (issue 15) against the stepping.

Reference: Newmark's step (β = 1/4, γ = 1/2) written out here in extended precision
(numpy.longdouble), independently of bwim.dynamics.newmark.  The filter path of
:func:`integrate` (uncoupled modes: per-mode lfilter; full matrices: the eigenbasis of the
two-step companion matrix) must agree with it as closely as the float64 stepping does; the
lightly damped low modes make both lose a few digits over thousands of steps.
"""

import numpy as np

from bwim.dynamics.newmark import Newmark, final_state, integrate


def _reference(M, C, K, f, dt, u0, v0):
    L = np.longdouble
    h = L(dt)
    M, C, K, f = (np.asarray(x, dtype=L) for x in (M, C, K, f))
    diag = M.ndim == 1

    def mul(A, x):
        return A * x if diag else A @ x

    def solve(A, b):
        return b / A if diag else np.linalg.solve(A.astype(float), b.astype(float)).astype(L)

    a0, a1, a2 = L(4) / (h * h), L(2) / h, L(4) / h
    keff = K + a1 * C + a0 * M
    u, v = np.asarray(u0, L), np.asarray(v0, L)
    a = solve(M, f[0] - mul(C, v) - mul(K, u))
    U = np.empty(f.shape, dtype=L)
    U[0] = u
    for k in range(1, f.shape[0]):
        rhs = f[k] + mul(M, a0 * u + a2 * v + a) + mul(C, a1 * u + v)
        un = rhs / keff if diag else np.linalg.solve(keff.astype(float), rhs.astype(float))
        an = a0 * (un - u) - a2 * v - a
        v = v + h / 2 * (a + an)
        u, a = un, an
        U[k] = u
    return U.astype(float)


def test_uncoupled_modes_filter_matches_stepping():
    rng = np.random.default_rng(0)
    n = 12
    w = np.geomspace(5.0, 3000.0, n)
    zeta = 0.02 + 0.5 * (w / 3000.0) ** 2
    M, C, K = np.ones(n), 2 * zeta * w, w**2
    f = rng.standard_normal((4000, n))
    f[:500] = 0.0  # at rest first: the leading steps are skipped
    res = integrate(M, C, K, f, Newmark(1e-3))
    ref = _reference(M, C, K, f, 1e-3, np.zeros(n), np.zeros(n))
    # measured 3.7e-11 (the float64 stepping 5e-11 on a similar case)
    assert np.abs(res.u - ref).max() < 2e-10 * np.abs(ref).max()
    assert np.all(res.u[:499] == 0.0)


def test_coupled_filter_matches_stepping():
    """A 3-DOF chain with non-proportional damping, starting from a displaced state."""
    rng = np.random.default_rng(1)
    M = np.diag([2.0, 1.0, 0.5])
    K = np.array([[300.0, -100.0, 0.0], [-100.0, 250.0, -150.0], [0.0, -150.0, 150.0]])
    C = np.array([[3.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.5]])
    f = rng.standard_normal((3000, 3))
    u0, v0 = np.array([0.01, -0.02, 0.03]), np.array([0.1, 0.0, -0.1])
    res = integrate(M, C, K, f, Newmark(1e-3), u0=u0, v0=v0)
    ref = _reference(M, C, K, f, 1e-3, u0, v0)
    # measured 3.1e-11; the float64 stepping 1.0e-12 (the eigenbasis, cond ~30, costs
    # about 1.5 digits)
    assert np.abs(res.u - ref).max() < 2e-10 * np.abs(ref).max()


def test_final_state_matches_stepping():
    """:func:`final_state` (the closed-form sum over the eigenbasis) against the last row
    of the extended-precision stepping, on the same 3-DOF chain as above."""
    rng = np.random.default_rng(2)
    M = np.diag([2.0, 1.0, 0.5])
    K = np.array([[300.0, -100.0, 0.0], [-100.0, 250.0, -150.0], [0.0, -150.0, 150.0]])
    C = np.array([[3.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.5]])
    f = np.cumsum(rng.standard_normal((3000, 3)), axis=0)
    u0, v0 = np.array([0.01, -0.02, 0.03]), np.array([0.1, 0.0, -0.1])
    fin = final_state(M, C, K, f, Newmark(1e-3), u0=u0, v0=v0)
    ref = _reference(M, C, K, f, 1e-3, u0, v0)
    # measured 1.07e-11, the same as integrate's own last row (1.07e-11)
    assert np.abs(fin.u - ref[-1]).max() < 5e-11 * np.abs(ref[-1]).max()
    full = integrate(M, C, K, f, Newmark(1e-3), u0=u0, v0=v0)
    # v and a against integrate's last row: measured 1e-14 and 7e-14
    for got, want in ((fin.v, full.v[-1]), (fin.a, full.a[-1])):
        assert np.abs(got - want).max() < 1e-12 * np.abs(want).max()
