"""Newmark-β on a single-DOF oscillator against its closed form.

References: damped free vibration u = e^{−ζωt}(u₀ cos ω_d t + (v₀ + ζωu₀)/ω_d sin ω_d t) and
the steady state plus transient of harmonic forcing (Chopra, *Dynamics of Structures*,
eqs. 2.2.4 and 3.2.1-3.2.4).  Average acceleration is second-order accurate.
"""

import numpy as np

from bwim.dynamics.newmark import Newmark, integrate

M, K, ZETA = 2.0, 800.0, 0.05
W = np.sqrt(K / M)
C = 2 * ZETA * W * M
WD = W * np.sqrt(1 - ZETA**2)


def _free(dt, diag=False):
    t = np.arange(0.0, 2.0, dt)
    f = np.zeros((t.size, 1))
    mats = (np.array([M]), np.array([C]), np.array([K])) if diag else (
        np.array([[M]]), np.array([[C]]), np.array([[K]]))
    r = integrate(*mats, f, Newmark(dt), u0=[0.01], v0=[0.3])
    exact = np.exp(-ZETA * W * t) * (0.01 * np.cos(WD * t)
                                     + (0.3 + ZETA * W * 0.01) / WD * np.sin(WD * t))
    return np.abs(r.u[:, 0] - exact).max() / np.abs(exact).max(), r


def test_free_vibration_matches_closed_form_second_order():
    errors = [_free(dt)[0] for dt in (0.01, 0.005, 0.0025)]
    assert errors[-1] < 2e-3
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(rates, 2.0, atol=0.05)


def test_diagonal_and_matrix_paths_agree():
    _, full = _free(0.005)
    _, diag = _free(0.005, diag=True)
    np.testing.assert_allclose(diag.u, full.u, atol=1e-14)
    np.testing.assert_allclose(diag.a, full.a, atol=1e-9)


def test_harmonic_forcing_matches_closed_form():
    p0, w_f = 50.0, 0.7 * W
    dt = 0.001
    t = np.arange(0.0, 3.0, dt)
    f = p0 * np.sin(w_f * t)[:, None]
    r = integrate(np.array([M]), np.array([C]), np.array([K]), f, Newmark(dt))
    # Chopra eq. 3.2.2-3.2.4: particular solution C sin + D cos plus the transient that
    # satisfies u(0) = u'(0) = 0
    ratio = w_f / W
    den = (1 - ratio**2) ** 2 + (2 * ZETA * ratio) ** 2
    cs = p0 / K * (1 - ratio**2) / den
    dc = p0 / K * (-2 * ZETA * ratio) / den
    A = -dc
    B = (-cs * w_f + ZETA * W * A) / WD
    exact = (np.exp(-ZETA * W * t) * (A * np.cos(WD * t) + B * np.sin(WD * t))
             + cs * np.sin(w_f * t) + dc * np.cos(w_f * t))
    assert np.abs(r.u[:, 0] - exact).max() < 2e-3 * np.abs(exact).max()
