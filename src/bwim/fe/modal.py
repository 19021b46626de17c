"""Lowest natural modes of a bridge model.

Contract
--------
* Solves ``K φ = ω² M φ`` (docs/theory.md §1.4) on the free DOF for the ``n`` lowest
  modes by shift-invert Lanczos (``scipy.sparse.linalg.eigsh`` with σ = 0), the inverse
  operator being the banded Cholesky factor of K.  Tiny systems use a dense solver.
* Shapes are mass-normalised (``Φᵀ M Φ = I``) and signed so that the largest deflection
  component of each mode is positive (the first such DOF where extrema tie to round-off,
  as on a symmetric deck), which makes results reproducible.
* Frequencies are returned in Hz, ascending; ``omega`` in rad/s.
* :func:`select_modes` is the truncation a simulation or an identification uses: every
  mode up to a cut-off frequency (default sampling_rate / 8), checked against the
  sampling rate (at least 2.5 × the highest frequency in use, :func:`check_sampling_rate`).
* :func:`scaled_modes` gives the modes after a uniform mass scaling ``M → c M`` (K fixed)
  without solving again: ``K φ = ω² c M φ`` has the eigenvectors of ``K φ = ω² M φ``
  with ``ω'² = ω² / c``, and mass normalisation ``φ'ᵀ (c M) φ' = 1`` gives
  ``φ' = c^(−½) φ``; the order and the signs (c > 0) are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bwim.errors import InputError, require_positive

if TYPE_CHECKING:
    from bwim.fe.bridge import Bridge

__all__ = ["Modes", "check_sampling_rate", "lowest_modes", "scaled_modes", "select_modes"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Modes:
    """Natural modes of a bridge model.

    Attributes
    ----------
    omega : ndarray, shape (n,)
        Circular frequencies, rad/s, ascending.
    shapes : ndarray, shape (n_free, n)
        Mass-normalised mode shapes on the model's free DOF.
    """

    omega: np.ndarray
    shapes: np.ndarray

    @cached_property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies, Hz, ascending (``omega / 2π``)."""
        return self.omega / (2 * np.pi)

    @property
    def n(self) -> int:
        return self.omega.size


def lowest_modes(
    n: int,
    stiffness_factor: np.ndarray,
    K: sp.spmatrix,
    M: sp.spmatrix,
    deflection_dofs: np.ndarray,
) -> Modes:
    """The ``n`` lowest modes.

    Parameters
    ----------
    n : int
        Number of modes.
    stiffness_factor : ndarray
        Lower banded Cholesky factor of K (``scipy.linalg.cholesky_banded(lower=True)``).
    K, M : sparse matrices, shape (n_free, n_free)
    deflection_dofs : ndarray of int
        Free-DOF indices of the deflections w, used to fix each mode's sign.
    """
    n_free = K.shape[0]
    if not (isinstance(n, (int, np.integer)) and 1 <= n <= n_free):
        raise InputError(f"number of modes must be an integer in [1, {n_free}], got {n!r}")
    if n_free <= 60 or n >= n_free // 2:
        vals, vecs = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, n - 1])
    else:
        def solve(v: np.ndarray) -> np.ndarray:
            return sla.cho_solve_banded((stiffness_factor, True), v, check_finite=False)

        op = spla.LinearOperator((n_free, n_free), matvec=solve, dtype=float)
        v0 = np.random.default_rng(0).standard_normal(n_free)
        vals, vecs = spla.eigsh(K, k=n, M=M, sigma=0.0, which="LM", OPinv=op, v0=v0)
    order = np.argsort(vals)
    vals = vals[order]
    vecs = vecs[:, order]
    # mass-normalise and fix the sign
    mnorm = np.sqrt(np.einsum("ij,ij->j", vecs, M @ vecs))
    vecs = vecs / mnorm
    w = vecs[deflection_dofs] if deflection_dofs.size else vecs
    # The first DOF whose |w| is within round-off of the largest: on a symmetric deck two
    # opposite extrema tie, and a plain argmax would pick either by the last bit.
    aw = np.abs(w)
    big = np.argmax(aw >= (1.0 - 1e-8) * aw.max(axis=0), axis=0)
    vecs = vecs * np.sign(w[big, np.arange(w.shape[1])])
    omega = np.sqrt(np.clip(vals, 0.0, None))
    return Modes(omega=omega, shapes=vecs)


def select_modes(
    bridge: Bridge, *, n_modes: int | None = None, max_frequency: float | None = None,
    sampling_rate: float,
) -> Modes:
    """The modes a simulation (or identification) uses.

    All modes up to ``max_frequency`` (default ``sampling_rate / 8``) unless ``n_modes``
    is given.  Raises :class:`InputError` if the sampling rate is below 2.5 × the highest
    frequency in use (Nyquist with a margin).
    """
    if n_modes is not None:
        modes = bridge.modes(n_modes)
    else:
        f_cut = sampling_rate / 8 if max_frequency is None else require_positive(
            "max_frequency", max_frequency)
        k = min(10, bridge.n_free - 1)
        while True:
            modes = bridge.modes(k)
            if modes.frequencies[-1] > f_cut or k >= bridge.n_free - 1:
                break
            k = min(2 * k, bridge.n_free - 1)
        n = max(int(np.searchsorted(modes.frequencies, f_cut, side="right")), 1)
        modes = bridge.modes(n)
    check_sampling_rate(modes, sampling_rate)
    return modes


def check_sampling_rate(modes: Modes, sampling_rate: float) -> None:
    """Raise :class:`InputError` if ``sampling_rate`` (Hz) is below 2.5 × the highest
    frequency of ``modes`` (Nyquist with a margin)."""
    f_max = modes.frequencies[-1]
    if sampling_rate < 2.5 * f_max:
        raise InputError(
            f"sampling_rate {sampling_rate:g} Hz is too low for the modes in use (highest "
            f"{f_max:.1f} Hz); use at least {2.5 * f_max:.0f} Hz or fewer modes"
        )


def scaled_modes(modes: Modes, mass_factor: float) -> Modes:
    """The modes of the same stiffness with every mass scaled by ``mass_factor`` (> 0):
    frequencies × ``mass_factor^(−½)``, mass-normalised shapes × ``mass_factor^(−½)``
    (see the module docstring)."""
    c = require_positive("mass_factor", mass_factor)
    s = 1.0 / np.sqrt(c)
    return Modes(omega=modes.omega * s, shapes=modes.shapes * s)
