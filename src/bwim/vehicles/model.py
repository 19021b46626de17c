"""Linear vehicle models in a common form, and the builder that assembles them.

Contract
--------
Every vehicle becomes a :class:`VehicleModel`: ``n_v`` DOF ``y`` (vertical displacements
and small rotations, measured from static equilibrium, **downward positive** like the
deck's w) and ``n_c`` contact points (wheels).  With the ground under contact c displaced
downward by ``g_c`` (deck deflection minus road elevation), the tyre compression is
``Δ = Eᵀ y − g`` and

    M ÿ + C ẏ + K y = E (K_t g + C_t ġ)                      (vehicle)
    F_c = F_static,c + k_t,c Δ_c + c_t,c Δ̇_c                 (contact force, down)

where ``K`` and ``C`` already include the tyre springs and dampers (``E K_t Eᵀ``).
A :class:`~bwim.vehicles.MovingForces` has ``n_v = 0``: its contact forces are the static
ones.

Contacts are ordered axle by axle, the right wheel (smaller y) first; each has an offset
``s`` behind the first axle and a lateral offset ``e`` from the vehicle centre line
(positive to the left, i.e. towards larger y).

The builder (:func:`assemble`) takes rigid bodies with bounce, pitch and roll, wheel
masses, suspensions, tyres and linear constraints (an articulation), and solves static
equilibrium for the wheel loads — also when the axle layout is statically indeterminate
(docs/theory.md §2.1).
A point at ``(s, e)`` on a body moves down by ``z + (s_cg − s) θ + e φ`` (pitch θ positive
nose-down, roll φ positive left side down).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from bwim.conventions import GRAVITY
from bwim.errors import InputError, NumericalError

__all__ = ["BodySpec", "VehicleModel", "WheelSpec", "assemble"]


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleModel:
    """A linear vehicle in the common form (see module docstring).

    Attributes
    ----------
    mass, damping, stiffness : ndarray, shape (n_v, n_v)
    contact : ndarray, shape (n_v, n_c)
        ``E``: contact-point displacements are ``Eᵀ y``.
    tyre_stiffness, tyre_damping : ndarray, shape (n_c,)
    static_forces : ndarray, shape (n_c,)
        Static wheel loads, N.
    contact_offset : ndarray, shape (n_c,)
        Distance behind the first axle, m.
    contact_lateral : ndarray, shape (n_c,)
        Offset from the centre line, m (+ left).
    contact_axle : ndarray of int, shape (n_c,)
    axle_offsets : ndarray, shape (n_axles,)
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    contact: np.ndarray
    tyre_stiffness: np.ndarray
    tyre_damping: np.ndarray
    static_forces: np.ndarray
    contact_offset: np.ndarray
    contact_lateral: np.ndarray
    contact_axle: np.ndarray
    axle_offsets: np.ndarray

    @property
    def n_dof(self) -> int:
        return self.mass.shape[0]

    @property
    def n_contacts(self) -> int:
        return self.static_forces.size

    @property
    def n_axles(self) -> int:
        return self.axle_offsets.size

    @property
    def static_axle_loads(self) -> np.ndarray:
        return np.bincount(self.contact_axle, self.static_forces, minlength=self.n_axles)

    def frequencies(self) -> np.ndarray:
        """Natural frequencies on a rigid road, Hz (undamped)."""
        if self.n_dof == 0:
            return np.zeros(0)
        w2 = sla.eigh(self.stiffness, self.mass, eigvals_only=True)
        return np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)


@dataclass(frozen=True, kw_only=True)
class BodySpec:
    """A rigid body: ``pitch_inertia``/``roll_inertia`` None removes that DOF."""

    mass: float
    cg_offset: float = 0.0  #: CG distance behind the first axle, m
    pitch_inertia: float | None = None  #: kg m² about the transverse axis
    roll_inertia: float | None = None  #: kg m² about the longitudinal axis


@dataclass(frozen=True, kw_only=True)
class WheelSpec:
    """A wheel (or a whole axle's wheel set in 2-D models) and what holds it.

    With ``mass > 0`` the wheel has its own DOF, hung from the body by the suspension
    (``suspension_*``) and resting on the ground through the tyre (``tyre_*``).  With
    ``mass == 0`` the body point rests on the ground directly through the tyre spring.
    Several contact points may share one wheel DOF (``share`` > 0: same wheel as the
    previous spec), each with its own part of the tyre.
    """

    body: int
    offset: float  #: s, m behind the first axle
    lateral: float = 0.0  #: e, m (+ left)
    axle: int = 0
    mass: float = 0.0
    suspension_stiffness: float = 0.0
    suspension_damping: float = 0.0
    tyre_stiffness: float
    tyre_damping: float = 0.0
    share_previous: bool = False  #: a second contact of the previous spec's wheel DOF


def assemble(
    bodies: Sequence[BodySpec],
    wheels: Sequence[WheelSpec],
    *,
    constraints: Sequence[tuple[tuple[int, float, float], tuple[int, float, float]]] = (),
    roll_links: Sequence[tuple[int, int]] = (),
) -> VehicleModel:
    """Assemble M, C, K, contacts and static loads of a vehicle.

    Parameters
    ----------
    bodies, wheels
        Rigid bodies and wheels (see :class:`BodySpec`, :class:`WheelSpec`).
    constraints
        Pairs of body points ``((body_a, s, e), (body_b, s, e))`` that move together
        vertically (a hitch).
    roll_links
        Pairs of bodies whose roll angles are equal (a roll-stiff fifth wheel).
    """
    # --- generalised coordinates before constraints --------------------------------------
    dof_of: list[dict[str, int]] = []
    n = 0
    masses: list[float] = []
    for b in bodies:
        d = {"z": n}
        masses.append(b.mass)
        n += 1
        if b.pitch_inertia is not None:
            d["pitch"] = n
            masses.append(b.pitch_inertia)
            n += 1
        if b.roll_inertia is not None:
            d["roll"] = n
            masses.append(b.roll_inertia)
            n += 1
        dof_of.append(d)
    wheel_dof: list[int | None] = []
    for w in wheels:
        if w.share_previous:
            wheel_dof.append(wheel_dof[-1])
        elif w.mass > 0:
            wheel_dof.append(n)
            masses.append(w.mass)
            n += 1
        else:
            wheel_dof.append(None)
    M = np.diag(masses)
    K = np.zeros((n, n))
    C = np.zeros((n, n))

    def point(body: int, s: float, e: float) -> np.ndarray:
        row = np.zeros(n)
        d, b = dof_of[body], bodies[body]
        row[d["z"]] = 1.0
        if "pitch" in d:
            row[d["pitch"]] = b.cg_offset - s
        if "roll" in d:
            row[d["roll"]] = e
        return row

    G = np.zeros(n)  # generalised gravity (downward)
    for b, d in zip(bodies, dof_of, strict=True):
        G[d["z"]] += b.mass * GRAVITY
    contact_rows = []
    for w, wd in zip(wheels, wheel_dof, strict=True):
        body_pt = point(w.body, w.offset, w.lateral)
        if wd is None:
            contact_rows.append(body_pt)
            continue
        if not w.share_previous:
            G[wd] += w.mass * GRAVITY
            rel = body_pt.copy()
            rel[wd] -= 1.0
            K += w.suspension_stiffness * np.outer(rel, rel)
            C += w.suspension_damping * np.outer(rel, rel)
        row = np.zeros(n)
        row[wd] = 1.0
        contact_rows.append(row)
    E = np.stack(contact_rows, axis=1)
    kt = np.array([w.tyre_stiffness for w in wheels], dtype=float)
    ct = np.array([w.tyre_damping for w in wheels], dtype=float)
    K += E @ np.diag(kt) @ E.T
    C += E @ np.diag(ct) @ E.T

    # --- constraints (articulation) --------------------------------------------------------
    rows = [point(a[0], a[1], a[2]) - point(b[0], b[1], b[2]) for a, b in constraints]
    for a, b in roll_links:
        r = np.zeros(n)
        r[dof_of[a]["roll"]] = 1.0
        r[dof_of[b]["roll"]] = -1.0
        rows.append(r)
    if rows:
        T = sla.null_space(np.stack(rows))
        M, C, K = T.T @ M @ T, T.T @ C @ T, T.T @ K @ T
        E, G = T.T @ E, T.T @ G
    try:
        y_static = np.linalg.solve(K, G)
    except np.linalg.LinAlgError:
        raise NumericalError("the vehicle has no static equilibrium (a free mechanism)") from None
    static = kt * (E.T @ y_static)
    if np.any(static <= 0):
        raise InputError(
            f"the vehicle's static wheel loads are not all positive: {np.round(static, 1)} N; "
            "check its centre of gravity against its axles"
        )
    axles = np.array([w.axle for w in wheels])
    n_axles = axles.max() + 1
    offsets = np.zeros(n_axles)
    for w in wheels:
        offsets[w.axle] = w.offset
    return VehicleModel(
        mass=M, damping=C, stiffness=K, contact=E, tyre_stiffness=kt, tyre_damping=ct,
        static_forces=static,
        contact_offset=np.array([w.offset for w in wheels]),
        contact_lateral=np.array([w.lateral for w in wheels]),
        contact_axle=axles, axle_offsets=offsets,
    )
