"""Closed form of a beam continuous over three spans (issue 20 item 5).  Calls no bwim.

Source: the three-moment equation (Clapeyron; Timoshenko & Young, "Theory of
Structures", 2nd ed., 1965, § 9.3): for spans l₁, l₂ meeting over support n,
``M_{n−1} l₁ + 2 M_n (l₁ + l₂) + M_{n+1} l₂ = −P c (l² − c²) / l`` for a point load P in
either span at distance c from that span's far support.  Checked in
``tests/unit/test_support_lobes.py`` against the tabulated three-equal-span coefficient
(0.175 PL at the middle of the loaded centre span) and the clamped-clamped limit (PL/8).
"""

from __future__ import annotations

import numpy as np


def centre_moment(x: np.ndarray, span: float, side: float) -> np.ndarray:
    """Mid-span moment of the centre span (supports at x = 0 and ``span``) of a beam
    continuous over end spans of length ``side`` (simply supported at −side and
    span + side), per unit load at ``x`` (m; zero off the beam)."""
    out = np.zeros(np.shape(x))
    a, L = side, span
    A = np.array([[2 * (a + L), L], [L, 2 * (a + L)]])
    for k, xi in enumerate(np.ravel(x)):
        if -a < xi < 0:  # left span, distance from its right support (B) 0 - xi
            d = xi + a  # from its left end
            rhs = np.array([-d * (a**2 - d**2) / a, 0.0])
            ss = 0.0
        elif 0 <= xi <= L:
            p, q = xi, L - xi
            rhs = np.array([-q * (L**2 - q**2) / L, -p * (L**2 - p**2) / L])
            ss = min(p, q) / 2
        elif L < xi < L + a:
            q = L + a - xi  # from the right end
            rhs = np.array([0.0, -q * (a**2 - q**2) / a])
            ss = 0.0
        else:
            continue
        mb, mc = np.linalg.solve(A, rhs)
        out.flat[k] = ss + (mb + mc) / 2
    return out
