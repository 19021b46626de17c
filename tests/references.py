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
