"""Beam and girder elements, and the composite girder section.

Contract
--------
* A beam element of length L has DOF ``(w0, w_x0, w1, w_x1)``: Euler–Bernoulli bending
  with cubic Hermite interpolation, ``K = E I ∫ h'' h''ᵀ``, consistent mass
  ``M = μ ∫ h hᵀ`` (μ in kg/m).
* A girder element runs along a plate node line ``y = y_g`` and has 6 DOF, the plate's
  ``(w, w_x, w_y)`` at each end: Hermite bending on ``(w, w_x)`` and linear St-Venant
  torsion on the rotation about x, which is ``w_y`` (the paper's six-DOF beam element;
  docs/theory.md §1.2).
  Its stiffness is ``E_girder × (I k_bend + J / (2 (1 + ν_g)) k_tors)``: linear in the
  girder modulus, which is the calibrated parameter.  Rotary inertia is neglected.
* A girder's ``I`` is the second moment of area of the girder together with its share of
  slab, about the centroid of that composite section, in girder-modulus units (use
  :func:`composite_section`).  By default the slab's bending about its own mid-plane is
  taken out of ``I``, because the plate elements already carry it: plate plus girder then
  have exactly the composite section's stiffness.  The girder's soffit strain is
  ``ε_x = −z_b w_xx`` with ``z_b`` the distance from the composite centroid down to the
  bottom fibre of the girder.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_positive, require_range
from bwim.fe.plate import hermite_integrals

__all__ = [
    "CompositeSection",
    "Girder",
    "beam_unit_matrices",
    "composite_section",
    "girder_unit_matrices",
]


def beam_unit_matrices(length: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit bending stiffness (EI = 1) and mass (μ = 1) of a Hermite beam element."""
    h = hermite_integrals(length)
    return h.k22, h.m00


def girder_unit_matrices(
    length: float, inertia: float, torsion_constant: float, poisson: float
) -> tuple[np.ndarray, np.ndarray]:
    """Unit (E = 1, μ = 1) stiffness and mass of a 6-DOF girder element.

    DOF order ``(w0, w_x0, w_y0, w1, w_x1, w_y1)``.
    """
    kb, mb = beam_unit_matrices(length)
    bend = [0, 1, 3, 4]
    k = np.zeros((6, 6))
    m = np.zeros((6, 6))
    k[np.ix_(bend, bend)] = inertia * kb
    gj = torsion_constant / (2.0 * (1.0 + poisson))
    k[np.ix_([2, 5], [2, 5])] = gj / length * np.array([[1.0, -1.0], [-1.0, 1.0]])
    m[np.ix_(bend, bend)] = mb
    return k, m


@dataclass(frozen=True, kw_only=True)
class Girder:
    """A longitudinal girder under the deck along the node line ``y``.

    Parameters
    ----------
    y : float
        Transverse position of the girder's centre line, m from the right-hand edge.
    I : float
        Bending second moment of area used by the girder element, m⁴ (see
        :func:`composite_section`).
    z_bottom : float
        Distance from the composite centroid down to the girder's soffit, m (> 0); the
        girder's strain gauges read ``ε_x = −z_bottom w_xx``.
    E : float
        Girder modulus, Pa (the calibrated parameter ``E_girder``).
    mu : float
        Girder mass per unit length, kg/m, excluding the slab (the plate carries it).
    J : float
        St-Venant torsion constant, m⁴ (0 ignores the girder's torsion).
    poisson : float
        Poisson ratio of the girder material (shear modulus ``E / (2 (1 + ν))``).
    """

    y: float
    I: float
    z_bottom: float
    E: float
    mu: float
    J: float = 0.0
    poisson: float = 0.2

    def __post_init__(self) -> None:
        require_range("Girder.y", self.y, -np.inf, np.inf)
        require_positive("Girder.I", self.I)
        require_positive("Girder.z_bottom", self.z_bottom)
        require_positive("Girder.E", self.E)
        require_positive("Girder.mu", self.mu)
        if not np.isfinite(self.J) or self.J < 0.0:
            raise InputError(f"Girder.J must be >= 0, got {self.J:g}")
        require_range("Girder.poisson", self.poisson, -1.0, 0.5)


@dataclass(frozen=True, kw_only=True)
class CompositeSection:
    """Section properties of a girder acting compositely with its share of slab.

    All second moments are in girder-modulus units (slab transformed by the modular ratio).
    """

    I: float
    """I for the girder element (slab's own bending removed if ``exclude_slab_bending``)."""
    I_composite: float
    """Full second moment of the composite section about its centroid, m⁴."""
    z_bottom: float
    """Distance from the composite centroid down to the girder soffit, m."""
    area: float
    """Transformed area of the composite section, m²."""


def composite_section(
    *,
    girder_area: float,
    girder_inertia: float,
    girder_depth: float,
    girder_centroid_height: float | None = None,
    slab_width: float,
    slab_thickness: float,
    modular_ratio: float = 1.0,
    exclude_slab_bending: bool = True,
) -> CompositeSection:
    """Composite girder + slab section by the parallel-axis theorem.

    Parameters
    ----------
    girder_area, girder_inertia : float
        Area (m²) and second moment about its own centroid (m⁴) of the bare girder.
    girder_depth : float
        Depth of the girder below the slab soffit, m.
    girder_centroid_height : float, optional
        Height of the girder's centroid above its soffit (default: half its depth).
    slab_width, slab_thickness : float
        The slab's effective width and thickness acting with the girder, m.
    modular_ratio : float
        ``E_slab / E_girder``: the slab is transformed to girder units.
    exclude_slab_bending : bool
        Remove the slab's bending about its own mid-plane (``n b t³ / 12``) from ``I``
        because the plate elements already carry it (default True).

    Returns
    -------
    CompositeSection
    """
    A_g = require_positive("girder_area", girder_area)
    I_g = require_positive("girder_inertia", girder_inertia)
    d_g = require_positive("girder_depth", girder_depth)
    b = require_positive("slab_width", slab_width)
    t = require_positive("slab_thickness", slab_thickness)
    n = require_positive("modular_ratio", modular_ratio)
    c_g = d_g / 2 if girder_centroid_height is None else girder_centroid_height
    require_range("girder_centroid_height", c_g, 0.0, d_g)
    A_s = n * b * t
    c_s = d_g + t / 2
    A = A_g + A_s
    c = (A_g * c_g + A_s * c_s) / A
    I_slab_own = n * b * t**3 / 12
    I_comp = I_g + A_g * (c - c_g) ** 2 + I_slab_own + A_s * (c_s - c) ** 2
    I_elem = I_comp - I_slab_own if exclude_slab_bending else I_comp
    return CompositeSection(
        I=I_elem, I_composite=I_comp, z_bottom=c, area=A
    )
