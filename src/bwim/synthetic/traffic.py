"""Trucks of the test day: the calibration truck and random heavy traffic.

Contract
--------
* :func:`calibration_truck` is a 5-axle, 40.0 t tractor–semitrailer (2-axle tractor,
  tri-axle trailer) with axle spacings exactly 3.8, 6.0, 1.3, 1.3 m: the parameters of
  :func:`bwim.vehicles.library.tractor_semitrailer` (same bodies, wheels, suspensions,
  tyres, inertias) with the fifth wheel 0.5 m ahead of the drive axle (3.3 m), the
  tractor's CG at 1.7 m and the trailer's CG placed so that the kingpin carries the same
  share of the trailer (28.3 %) as in the library truck.  Its static axle loads are
  whatever static equilibrium of that model gives.
* :func:`random_truck` draws one of :data:`TRUCK_KINDS`: ``rigid_2`` (2-axle rigid),
  ``rigid_3`` (steer + tandem), ``artic_2+2``, ``artic_2+3`` (tri-axle trailer),
  ``artic_3+2`` and ``artic_3+3`` (tractor with a tandem drive), with a gross mass drawn
  uniformly in :data:`GVW_RANGE` (t; 10–50 t over all kinds), axle spacings drawn in
  ranges typical of EU trucks (a group's axles 1.30–1.40 m apart, equal within a group)
  and per-wheel suspension and tyre values drawn uniformly within ±20 % of nominal values
  per axle role (unsprung mass ±10 %):

  =========  ==========  ============  ============  ===========================
  role       wheel (kg)  k_s (kN/m)    c_s (kN s/m)  k_t (MN/m)
  =========  ==========  ============  ============  ===========================
  steer      350         300           6             1.5 (single tyre)
  drive      550         500           10            3.0 (dual pair)
  trailer    400         400           8             2.0 (wide single)
  =========  ==========  ============  ============  ===========================

  Tyre damping 1 kN s/m per wheel (±20 %).  The ranges this gives (k_s 0.24–0.6 MN/m,
  single tyres 1.2–1.8 MN/m, duals 2.4–3.6 MN/m) lie within Cebon's (1999) ranges quoted
  in :mod:`bwim.vehicles.library`; the wide-single trailer tyres (1.6–2.4 MN/m) follow
  the library's assumed 2.0 MN/m.  Body masses follow from the gross mass less the
  unsprung masses; centres of gravity from a front-axle share (rigid trucks: 30–42 %
  two-axle, 25–35 % with a tandem) or a kingpin share (28–36 % of the trailer), the
  tractor CG at 40–48 % of the way to its drive axle (group centre) and the fifth wheel
  0.3–0.6 m ahead of it.  Inertias are uniform-box estimates ``m (a² + b²) / 12`` as in
  the library (body length about the axle length + 3 m, 2.5 m wide, 2.5–3 m high).
* Units: kg, m, N/m, N s/m; every draw comes from the ``rng`` passed in.
"""

from __future__ import annotations

import numpy as np

from bwim.errors import InputError
from bwim.vehicles.types import TractorSemitrailer, Truck3D

__all__ = ["GVW_RANGE", "TRUCK_KINDS", "TRUCK_MIX", "calibration_truck", "random_truck",
           "vehicle_mass"]

#: Truck kinds and their share of the traffic.
TRUCK_KINDS = ("rigid_2", "rigid_3", "artic_2+2", "artic_2+3", "artic_3+2", "artic_3+3")
TRUCK_MIX = (0.20, 0.15, 0.10, 0.35, 0.10, 0.10)

#: Gross mass range of each kind, t.
GVW_RANGE = {
    "rigid_2": (10.0, 18.0),
    "rigid_3": (15.0, 27.0),
    "artic_2+2": (18.0, 36.0),
    "artic_2+3": (22.0, 46.0),
    "artic_3+2": (24.0, 46.0),
    "artic_3+3": (28.0, 50.0),
}

#: Nominal per-wheel values by axle role: unsprung mass, suspension k and c, tyre k.
_ROLES = {
    "steer": (350.0, 300e3, 6e3, 1.5e6),
    "drive": (550.0, 500e3, 10e3, 3.0e6),
    "trailer": (400.0, 400e3, 8e3, 2.0e6),
}
_TYRE_DAMPING = 1e3
_HEIGHT = 2.5  # m, body height in the box estimate of inertia
_BODY_WIDTH = 2.5  # m
_TRACK = 2.0  # m


def vehicle_mass(vehicle: Truck3D | TractorSemitrailer) -> float:
    """Total mass, kg: bodies plus two wheels per axle."""
    wheels = 2.0 * float(np.sum(vehicle.wheel_mass))
    if isinstance(vehicle, TractorSemitrailer):
        return vehicle.tractor_mass + vehicle.trailer_mass + wheels
    return vehicle.body_mass + wheels


def calibration_truck() -> TractorSemitrailer:
    """The 5-axle, 40.0 t calibration truck (see the module docstring)."""
    spacings = np.array([3.8, 6.0, 1.3, 1.3])
    hitch = 3.3
    group = spacings[0] + spacings[1] + spacings[2]  # centre of the tri-axle
    kingpin = (10.81 - 8.6) / (10.81 - 3.0)  # the library truck's kingpin share
    return TractorSemitrailer(
        tractor_mass=6.5e3, tractor_pitch_inertia=19.5e3, tractor_roll_inertia=6.8e3,
        tractor_cg_offset=1.7,
        trailer_mass=29.3e3, trailer_pitch_inertia=450e3, trailer_roll_inertia=37.8e3,
        trailer_cg_offset=group - kingpin * (group - hitch),
        hitch_offset=hitch, n_tractor_axles=2,
        axle_spacings=spacings,
        wheel_mass=[350.0, 550.0, 400.0, 400.0, 400.0],
        suspension_stiffness=[300e3, 600e3, 400e3, 400e3, 400e3],
        suspension_damping=[6e3, 10e3, 8e3, 8e3, 8e3],
        tyre_stiffness=[1.75e6, 3.5e6, 2.0e6, 2.0e6, 2.0e6],
        tyre_damping=[1e3] * 5,
        track_width=_TRACK,
    )


def _spacings(kind: str, rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """Axle spacings and the number of tractor (or front-body) axles."""
    u = rng.uniform
    group = u(1.30, 1.40)
    if kind == "rigid_2":
        return np.array([u(3.8, 5.8)]), 2
    if kind == "rigid_3":
        return np.array([u(3.6, 4.6), group]), 3
    if kind == "artic_2+2":
        return np.array([u(3.5, 3.9), u(6.5, 8.0), group]), 2
    if kind == "artic_2+3":
        return np.array([u(3.5, 3.9), u(5.5, 7.0), group, group]), 2
    drive = u(1.30, 1.40)
    if kind == "artic_3+2":
        return np.array([u(3.0, 3.4), drive, u(5.5, 7.0), group]), 3
    return np.array([u(3.0, 3.4), drive, u(5.0, 6.5), group, group]), 3


def _suspensions(roles: list[str], rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Per-axle (per-wheel values) arrays, each role's values drawn once per vehicle."""
    drawn = {}
    for role in dict.fromkeys(roles):  # first-appearance order: draws do not depend on hashing
        m, ks, cs, kt = _ROLES[role]
        f = rng.uniform(0.8, 1.2, 4)
        drawn[role] = (m * rng.uniform(0.9, 1.1), ks * f[0], cs * f[1], kt * f[2],
                       _TYRE_DAMPING * f[3])
    keys = ("wheel_mass", "suspension_stiffness", "suspension_damping", "tyre_stiffness",
            "tyre_damping")
    return {k: np.array([drawn[r][i] for r in roles]) for i, k in enumerate(keys)}


def random_truck(kind: str, rng: np.random.Generator) -> Truck3D | TractorSemitrailer:
    """A random truck of ``kind`` (one of :data:`TRUCK_KINDS`; see the module docstring)."""
    if kind not in TRUCK_KINDS:
        raise InputError(f"unknown truck kind {kind!r}; expected one of {', '.join(TRUCK_KINDS)}")
    u = rng.uniform
    spacings, n_front = _spacings(kind, rng)
    offsets = np.concatenate([[0.0], np.cumsum(spacings)])
    n_axles = offsets.size
    gvw = u(*GVW_RANGE[kind]) * 1e3
    if kind.startswith("rigid"):
        wheels = _suspensions(["steer"] + ["drive"] * (n_axles - 1), rng)
        body = gvw - 2.0 * wheels["wheel_mass"].sum()
        rear = offsets[1:].mean()
        front_share = u(0.30, 0.42) if n_axles == 2 else u(0.25, 0.35)
        length = offsets[-1] + 3.0
        return Truck3D(
            body_mass=body, cg_offset=rear * (1.0 - front_share),
            pitch_inertia=body * (length**2 + _HEIGHT**2) / 12,
            roll_inertia=body * (_BODY_WIDTH**2 + _HEIGHT**2) / 12,
            axle_spacings=spacings, track_width=_TRACK, **wheels)
    wheels = _suspensions(["steer"] + ["drive"] * (n_front - 1)
                          + ["trailer"] * (n_axles - n_front), rng)
    tractor = (u(6.0, 7.0) if n_front == 2 else u(7.5, 8.5)) * 1e3
    trailer = gvw - tractor - 2.0 * wheels["wheel_mass"].sum()
    drive = offsets[1:n_front].mean()
    group = offsets[n_front:].mean()
    hitch = drive - u(0.3, 0.6)
    kingpin = u(0.28, 0.36)
    trailer_length = offsets[-1] - hitch + 3.0
    return TractorSemitrailer(
        tractor_mass=tractor, tractor_cg_offset=drive * u(0.40, 0.48),
        tractor_pitch_inertia=tractor * ((drive + 3.0) ** 2 + _HEIGHT**2) / 12,
        tractor_roll_inertia=tractor * (_BODY_WIDTH**2 + _HEIGHT**2) / 12,
        trailer_mass=trailer, trailer_cg_offset=group - kingpin * (group - hitch),
        trailer_pitch_inertia=trailer * (trailer_length**2 + 3.0**2) / 12,
        trailer_roll_inertia=trailer * (_BODY_WIDTH**2 + 3.0**2) / 12,
        hitch_offset=hitch, n_tractor_axles=n_front, axle_spacings=spacings,
        track_width=_TRACK, **wheels)
