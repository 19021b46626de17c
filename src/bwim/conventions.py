"""Units, axes and signs used everywhere in bwim.

This module holds no code that computes anything; it is the contract that every other
module follows, and the few named constants that go with it.

Units
-----
SI throughout the API: metres, seconds, newtons, kilograms, pascals.  Strain is
dimensionless (m/m); plots and printed tables show microstrain (µε) and kilonewtons.
Mass of a plate is per unit area (kg/m², the paper's "mass per unit length of a 1 m wide
strip"); mass of a beam or girder is per unit length (kg/m).

Axes
----
* ``x`` runs along the bridge in the direction of travel, from the support the traffic
  meets first (x = 0) to the far support (x = length).
* ``y`` runs across the deck, measured from the right-hand edge (y = 0) as seen by a
  driver travelling in +x, to the left-hand edge (y = width).
* ``z`` is vertical; the vertical displacement ``w`` is positive **downward**.

Degrees of freedom
------------------
Plate nodes carry ``(w, w_x, w_y, w_xy)`` — the deflection and its derivatives
∂w/∂x, ∂w/∂y and ∂²w/∂x∂y (Bogner–Fox–Schmit).  Beam nodes carry ``(w, w_x)``.  Slopes are
derivatives of the downward deflection, not rotations with a right-hand-rule sign.

Signs
-----
* Wheel and point forces are positive pushing **down** (in the direction of +w).
* Strain is positive in tension and is read at the soffit (bottom face): for a plate
  ``ε_x = −(h/2) ∂²w/∂x²``, ``ε_y = −(h/2) ∂²w/∂y²``; for a beam or girder
  ``ε_x = −z_b ∂²w/∂x²`` with ``z_b`` the distance from the neutral axis to the soffit.
  A simply supported span under a downward load therefore shows positive (tensile) strain
  at mid-span.
* Road elevation is positive **up** (a bump raises the wheel).

Time
----
In a vehicle crossing record, time 0 is the instant the first axle reaches x = 0.

Randomness
----------
Only through an explicit ``seed`` or ``rng`` argument (``numpy.random.default_rng``): the
same seed gives the same numbers.  No module keeps global random state.
"""

from __future__ import annotations

__all__ = ["GRAVITY", "KILONEWTON", "MICROSTRAIN"]

#: Standard gravity, m/s² (used to turn masses into static loads).
GRAVITY = 9.81

#: Strain per microstrain: ``strain / MICROSTRAIN`` is in µε.
MICROSTRAIN = 1e-6

#: Newtons per kilonewton: ``force / KILONEWTON`` is in kN.
KILONEWTON = 1e3
