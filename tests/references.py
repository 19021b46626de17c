"""Closed-form reference solutions used by the validation tests.

Each function states its source.  None of them calls bwim.
"""

from __future__ import annotations

import numpy as np


def orthotropic_rigidities(E_x, E_y, h, nu):
    """D_x, D_y and Huber's H = D_1 + 2 D_xy = sqrt(D_x D_y) (Timoshenko &
    Woinowsky-Krieger, *Theory of Plates and Shells*, 2nd ed., §86, eq. (f) with Huber's
    approximation)."""
    Dx = E_x * h**3 / (12 * (1 - nu**2))
    Dy = E_y * h**3 / (12 * (1 - nu**2))
    return Dx, Dy, np.sqrt(Dx * Dy)


def navier_point_load(a, b, Dx, Dy, H, h, x0, y0, x, y, n_terms=1000):
    """Navier double series for an orthotropic plate simply supported on four edges under a
    unit point load at (x0, y0): deflection w and soffit strains ε_x = −(h/2) w_xx,
    ε_y = −(h/2) w_yy at (x, y).

    Source: Timoshenko & Woinowsky-Krieger (1959) §86–87 (orthotropic plate equation
    D_x w_xxxx + 2H w_xxyy + D_y w_yyyy = q) with the point-load Fourier coefficients
    q_mn = 4 P / (a b) sin(mπx0/a) sin(nπy0/b) of §29.
    """
    m = np.arange(1, n_terms + 1)[:, None]
    n = np.arange(1, n_terms + 1)[None, :]
    den = np.pi**4 * (Dx * (m / a) ** 4 + 2 * H * (m / a) ** 2 * (n / b) ** 2 + Dy * (n / b) ** 4)
    W = 4 / (a * b) * np.sin(m * np.pi * x0 / a) * np.sin(n * np.pi * y0 / b) / den
    sxy = np.sin(m * np.pi * x / a) * np.sin(n * np.pi * y / b)
    w = np.sum(W * sxy)
    ex = h / 2 * np.sum(W * (m * np.pi / a) ** 2 * sxy)
    ey = h / 2 * np.sum(W * (n * np.pi / b) ** 2 * sxy)
    return w, ex, ey


def navier_frequencies(a, b, Dx, Dy, H, mu, k=6, n_terms=20):
    """Lowest k natural frequencies (Hz) of an orthotropic plate simply supported on four
    edges: ω_mn = π² sqrt((D_x (m/a)⁴ + 2H (m/a)²(n/b)² + D_y (n/b)⁴) / μ)
    (Leissa, *Vibration of Plates*, NASA SP-160 (1969), §11.1, eq. 11.6)."""
    m = np.arange(1, n_terms + 1)[:, None]
    n = np.arange(1, n_terms + 1)[None, :]
    w = np.pi**2 * np.sqrt(
        (Dx * (m / a) ** 4 + 2 * H * (m / a) ** 2 * (n / b) ** 2 + Dy * (n / b) ** 4) / mu
    )
    return np.sort(w.ravel())[:k] / (2 * np.pi)


def beam_frequencies(L, EI, m, k):
    """Simply supported Euler–Bernoulli beam: f_n = n² π / (2 L²) sqrt(EI / m)
    (Clough & Penzien, *Dynamics of Structures*, eq. 18-12)."""
    n = np.arange(1, k + 1)
    return n**2 * np.pi / (2 * L**2) * np.sqrt(EI / m)


def beam_midspan_point_load(L, EI, P):
    """Simply supported beam, central point load: deflection P L³ / (48 EI) and
    mid-span moment P L / 4 (Roark's Formulas for Stress and Strain, Table 8.1 case 1e)."""
    return P * L**3 / (48 * EI), P * L / 4


def moving_force_mode(P, A, omega, Omega, t):
    """Undamped modal response to a constant force P crossing at constant speed, from rest:
    q̈ + ω² q = P A sin(Ω t)  ⇒  q = P A / (ω² − Ω²) (sin Ωt − (Ω/ω) sin ωt)
    (Frýba, *Vibration of Solids and Structures under Moving Loads*, 3rd ed. 1999, §1.3,
    eq. 1.30, written per mode).  Valid while the force is on the span."""
    return P * A / (omega**2 - Omega**2) * (np.sin(Omega * t) - Omega / omega * np.sin(omega * t))


def fryba_beam(P, v, L, EI, m, x, t, n_terms=200, z_bottom=1.0):
    """Deflection and soffit strain at x of a simply supported Euler–Bernoulli beam under a
    constant force P moving at speed v (undamped), by Frýba's modal series (§1.3):
    mass-normalised modes sqrt(2/(m L)) sin(jπx/L), ω_j = (jπ/L)² sqrt(EI/m),
    Ω_j = jπv/L.  Returns (w, ε) arrays shaped like t."""
    t = np.asarray(t, dtype=float)[:, None]
    j = np.arange(1, n_terms + 1)[None, :]
    amp = np.sqrt(2.0 / (m * L))
    omega = (j * np.pi / L) ** 2 * np.sqrt(EI / m)
    q = moving_force_mode(P, amp, omega, j * np.pi * v / L, t)
    shape = amp * np.sin(j * np.pi * x / L)
    w = (q * shape).sum(axis=1)
    eps = z_bottom * (q * shape * (j * np.pi / L) ** 2).sum(axis=1)
    return w, eps


def moving_force_plate(P, v, y0, a, b, Dx, Dy, H, h, mu, x, y, t, n_terms=60):
    """Deflection and soffit strain ε_x at (x, y) of an orthotropic plate simply supported
    on four edges under a constant force P moving along y = y0 at speed v (undamped):
    Navier modes sqrt(4/(μab)) sin(mπx/a) sin(nπy/b) (Leissa 1969 §11.1) each driven as
    in :func:`moving_force_mode` with Ω_m = mπv/a."""
    t = np.asarray(t, dtype=float)[:, None, None]
    m = np.arange(1, n_terms + 1)[None, :, None]
    n = np.arange(1, n_terms + 1)[None, None, :]
    amp = np.sqrt(4.0 / (mu * a * b))
    omega = np.pi**2 * np.sqrt(
        (Dx * (m / a) ** 4 + 2 * H * (m / a) ** 2 * (n / b) ** 2 + Dy * (n / b) ** 4) / mu)
    q = moving_force_mode(P, amp * np.sin(n * np.pi * y0 / b), omega, m * np.pi * v / a, t)
    shape = amp * np.sin(m * np.pi * x / a) * np.sin(n * np.pi * y / b)
    w = (q * shape).sum(axis=(1, 2))
    eps = h / 2 * (q * shape * (m * np.pi / a) ** 2).sum(axis=(1, 2))
    return w, eps


def sprung_mass_on_beam(*, L, EI, m, mass, k, c, v, zeta, t, n_modes=6, road=None, rtol=1e-8):
    """A sprung mass crossing a simply supported beam: the coupled equations of Biggs
    (*Introduction to Structural Dynamics*, 1964, §8.5; the benchmark of Yang & Yau, J. Eng.
    Mech. 123(11), 1997) with analytic sine modes, integrated by SciPy's DOP853 at tight
    tolerance — independent of bwim's FE model and Newmark integrator.

    Displacements down positive from static equilibrium; the ground under the wheel moves
    down by g = w(vt) − r(vt) and the contact force on the beam is
    F = m g_n + k (y − g) + c (ẏ − ġ), ġ = ẇ + v w' − v r'.
    ``zeta(omega)`` gives modal damping; ``road`` is (r, r') callables or None.
    The mass starts at rest in static equilibrium on the road at x = 0.

    Returns mid-span deflection and contact force at the times ``t`` (on the span).
    """
    from scipy.integrate import solve_ivp

    j = np.arange(1, n_modes + 1)
    amp = np.sqrt(2.0 / (m * L))
    om = (j * np.pi / L) ** 2 * np.sqrt(EI / m)
    ze = zeta(om)
    r, rp = road if road is not None else (lambda x: 0.0 * x, lambda x: 0.0 * x)
    g_n = 9.81

    def phi(x):
        return amp * np.sin(j * np.pi * x / L), amp * j * np.pi / L * np.cos(j * np.pi * x / L)

    def contact(tt, z):
        q, qd, y, yd = z[:n_modes], z[n_modes:2 * n_modes], z[-2], z[-1]
        x = v * tt
        ph, php = phi(x)
        g = ph @ q - r(x)
        gd = ph @ qd + v * (php @ q) - v * rp(x)
        return mass * g_n + k * (y - g) + c * (yd - gd), ph, k * (y - g) + c * (yd - gd)

    def rhs(tt, z):
        F, ph, spring = contact(tt, z)
        q, qd = z[:n_modes], z[n_modes:2 * n_modes]
        qdd = ph * F - 2 * ze * om * qd - om**2 * q
        return np.concatenate([qd, qdd, [z[-1], -spring / mass]])

    z0 = np.zeros(2 * n_modes + 2)
    z0[-2] = -r(0.0)
    sol = solve_ivp(rhs, (0.0, float(t[-1])), z0, method="DOP853", t_eval=t, rtol=rtol,
                    atol=1e-6 * rtol)
    mid = amp * np.sin(j * np.pi / 2)
    w_mid = mid @ sol.y[:n_modes]
    F = np.array([contact(tt, sol.y[:, i])[0] for i, tt in enumerate(sol.t)])
    return w_mid, F


def levy_ss_free_first_frequency(a, b, D, mu, nu):
    """First natural frequency (Hz) of an isotropic plate simply supported on x = 0, a
    and free on y = ±b/2 (the beam-like mode m = 1, symmetric in y), by Lévy's exact
    solution (Leissa, *Vibration of Plates*, NASA SP-160 (1969), §4.3): with
    w = Y(y) sin(kx), k = π/a, λ⁴ = μω²/D, Y = A cosh(r₁y) + B cosh(r₂y),
    r₁,₂² = k² ± λ², the free-edge conditions M_y = Y'' − νk²Y = 0 and
    V_y = Y''' − (2 − ν)k²Y' = 0 at y = b/2 give a 2 × 2 determinant whose root λ < k
    is found by bisection (scipy.optimize.brentq)."""
    from scipy.optimize import brentq

    k, c = np.pi / a, b / 2

    def det(lam):
        r1, r2 = np.sqrt(k**2 + lam**2), np.sqrt(k**2 - lam**2)
        m1, m2 = (r1**2 - nu * k**2) * np.cosh(r1 * c), (r2**2 - nu * k**2) * np.cosh(r2 * c)
        v1 = r1 * (r1**2 - (2 - nu) * k**2) * np.sinh(r1 * c)
        v2 = r2 * (r2**2 - (2 - nu) * k**2) * np.sinh(r2 * c)
        return m1 * v2 - m2 * v1

    lam = brentq(det, 0.5 * k, k * (1 - 1e-12))
    return lam**2 * np.sqrt(D / mu) / (2 * np.pi)
