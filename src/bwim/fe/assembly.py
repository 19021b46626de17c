"""Assembly of K and M from per-element unit matrices and a parameter vector.

Contract
--------
* An :class:`ElementSet` is a group of elements of one type (plate, beam or girder) with
  ``n_parts`` unit stiffness matrices per element and one unit mass matrix.  The element
  stiffness is ``Σ_p c[p, e] U_p[e]`` and the mass ``m[e] M_1[e]``; the coefficients come
  from the bridge parameters, the unit matrices never change.
* An :class:`Assembler` numbers the free DOF (constrained DOF removed), precomputes where
  every element entry lands, and then builds, for any coefficients, K and M as
  LAPACK lower-banded arrays (``ab[i − j, j] = K[i, j]``, for
  ``scipy.linalg.cholesky_banded(lower=True)``) or as SciPy CSR matrices — one weighted
  ``bincount`` each, no re-integration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

__all__ = ["Assembler", "ElementSet"]


@dataclass(frozen=True, eq=False)
class ElementSet:
    """Elements of one type.

    Attributes
    ----------
    dofs : ndarray, shape (n_e, nd)
        Global DOF numbers of each element.
    stiffness_units : ndarray, shape (n_parts, n_shapes, nd, nd)
        Unit stiffness matrices per distinct element shape.
    mass_units : ndarray, shape (n_shapes, nd, nd)
    shape_id : ndarray, shape (n_e,)
        Which shape each element has.
    """

    dofs: np.ndarray
    stiffness_units: np.ndarray
    mass_units: np.ndarray
    shape_id: np.ndarray


@dataclass(frozen=True, eq=False)
class _Scatter:
    """Where one element set's entries go, for the banded and the full (CSR) layouts."""

    band_elem: np.ndarray
    band_target: np.ndarray
    band_k: np.ndarray  # (n_parts, n_band_entries) unit values
    band_m: np.ndarray
    full_elem: np.ndarray
    full_row: np.ndarray
    full_col: np.ndarray
    full_k: np.ndarray
    full_m: np.ndarray


@dataclass(frozen=True, eq=False)
class Assembler:
    """Builds K and M on the free DOF of a model.

    Parameters
    ----------
    n_dof : int
        Number of global DOF (free and constrained).
    fixed : ndarray of int
        Constrained global DOF.
    sets : tuple of ElementSet
    """

    n_dof: int
    fixed: np.ndarray
    sets: tuple[ElementSet, ...]
    free: np.ndarray = field(init=False)
    free_of: np.ndarray = field(init=False)
    bandwidth: int = field(init=False)
    _scatter: tuple[_Scatter, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        free_mask = np.ones(self.n_dof, dtype=bool)
        free_mask[np.asarray(self.fixed, dtype=int)] = False
        free = np.flatnonzero(free_mask)
        free_of = np.full(self.n_dof, -1, dtype=np.int64)
        free_of[free] = np.arange(free.size)
        object.__setattr__(self, "free", free)
        object.__setattr__(self, "free_of", free_of)
        bw = 0
        for s in self.sets:
            f = free_of[s.dofs]
            f_masked = np.where(f >= 0, f, np.iinfo(np.int64).max)
            lo = f_masked.min(axis=1)
            hi = f.max(axis=1)
            ok = hi >= 0
            if np.any(ok):
                bw = max(bw, int((hi[ok] - lo[ok]).max()))
        object.__setattr__(self, "bandwidth", bw)
        object.__setattr__(self, "_scatter", tuple(self._plan(s) for s in self.sets))

    @property
    def n_free(self) -> int:
        return self.free.size

    def element_free_dofs(self, i: int) -> np.ndarray:
        """Free-DOF numbers of element set ``i`` (−1 where constrained)."""
        return self.free_of[self.sets[i].dofs]

    def _plan(self, s: ElementSet) -> _Scatter:
        f = self.free_of[s.dofs]  # (n_e, nd)
        nd = f.shape[1]
        fi = f[:, :, None]
        fj = f[:, None, :]
        both = (fi >= 0) & (fj >= 0)
        e_idx = np.broadcast_to(np.arange(f.shape[0])[:, None, None], both.shape)
        r_idx = np.broadcast_to(np.arange(nd)[None, :, None], both.shape)
        c_idx = np.broadcast_to(np.arange(nd)[None, None, :], both.shape)
        rows = np.broadcast_to(fi, both.shape)
        cols = np.broadcast_to(fj, both.shape)
        sid = s.shape_id
        # full layout
        fe, fr, fc = e_idx[both], r_idx[both], c_idx[both]
        full_k = s.stiffness_units[:, sid[fe], fr, fc]
        full_m = s.mass_units[sid[fe], fr, fc]
        # lower band layout
        low = both & (rows >= cols)
        be, br, bc = e_idx[low], r_idx[low], c_idx[low]
        gi, gj = rows[low], cols[low]
        target = (gi - gj) * self.n_free + gj
        return _Scatter(
            band_elem=be,
            band_target=target,
            band_k=s.stiffness_units[:, sid[be], br, bc],
            band_m=s.mass_units[sid[be], br, bc],
            full_elem=fe,
            full_row=rows[both],
            full_col=cols[both],
            full_k=full_k,
            full_m=full_m,
        )

    # --- banded --------------------------------------------------------------------------
    def _band(self, weights: list[np.ndarray], targets: list[np.ndarray]) -> np.ndarray:
        n = self.n_free
        flat = np.bincount(
            np.concatenate(targets), weights=np.concatenate(weights),
            minlength=(self.bandwidth + 1) * n,
        )
        return flat.reshape(self.bandwidth + 1, n)

    def stiffness_banded(self, coefs: list[np.ndarray]) -> np.ndarray:
        """Lower-banded K for per-set coefficient arrays ``coefs[i]`` (n_parts, n_e)."""
        w = [np.einsum("pk,pk->k", c[:, sc.band_elem], sc.band_k)
             for c, sc in zip(coefs, self._scatter, strict=True)]
        return self._band(w, [sc.band_target for sc in self._scatter])

    def mass_banded(self, masses: list[np.ndarray]) -> np.ndarray:
        """Lower-banded M for per-set mass coefficients ``masses[i]`` (n_e,)."""
        w = [m[sc.band_elem] * sc.band_m for m, sc in zip(masses, self._scatter, strict=True)]
        return self._band(w, [sc.band_target for sc in self._scatter])

    # --- sparse --------------------------------------------------------------------------
    def _csr(self, weights: list[np.ndarray]) -> sp.csr_matrix:
        rows = np.concatenate([sc.full_row for sc in self._scatter])
        cols = np.concatenate([sc.full_col for sc in self._scatter])
        mat = sp.coo_matrix(
            (np.concatenate(weights), (rows, cols)), shape=(self.n_free, self.n_free)
        )
        return mat.tocsr()

    def stiffness_csr(self, coefs: list[np.ndarray]) -> sp.csr_matrix:
        w = [np.einsum("pk,pk->k", c[:, sc.full_elem], sc.full_k)
             for c, sc in zip(coefs, self._scatter, strict=True)]
        return self._csr(w)

    def mass_csr(self, masses: list[np.ndarray]) -> sp.csr_matrix:
        w = [m[sc.full_elem] * sc.full_m for m, sc in zip(masses, self._scatter, strict=True)]
        return self._csr(w)
