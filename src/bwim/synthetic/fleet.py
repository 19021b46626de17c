"""Heavy traffic of a motorway-like road: vehicle classes, their loads, axles and tyres.

Contract
--------
* :data:`FLEET_KINDS` and :data:`FLEET_MIX` (share of the heavy traffic, assumed typical
  of a European motorway, where the 5-axle tractor–semitrailer ``artic_2+3`` is the most
  common class): 2-, 3- and 4-axle rigid trucks (``rigid_4``: twin steering axles and a
  tandem) and tractor–semitrailers ``artic_T+S`` (T tractor axles, S semitrailer axles;
  ``artic_3+4``: a low-loader).  Drawbar trailers and 8–9-axle combinations are not
  modelled (the vehicle models are a rigid truck and a tractor–semitrailer).
* Loading: a fraction ``u`` of the class's payload range, drawn from a mixture — 20 %
  empty (u in 0–0.1), 30 % part-loaded (0.1–0.8), 50 % full (0.8–1.05); gross mass
  ``empty + u (full − empty)`` with (empty, full) of :data:`GVW_RANGE` (t).
* **Axle loads follow from the vehicle's build, not from a target.**  A tractor's
  bobtail mass (7.0–8.0 t with two axles, 8.5–9.5 t with three) carries a share of
  0.60–0.68 (0.50–0.58) on its steering axle (forward-control European tractors: engine
  and cab over the front axle); the fifth wheel sits 0.2–0.5 m ahead of the drive axle
  (group centre); the semitrailer's kingpin carries 22–32 % of the semitrailer.  So the
  steering axle gets a small share of the payload through the kingpin
  (``kingpin load × lead / wheelbase``): for ``artic_2+3`` it comes out about 48 kN empty
  and 55 kN full with a spread of a few kN while the gross weight goes from 14.5 to 40 t
  — nearly independent of payload, as WIM data show: 5-axle semitrailers' steering axle
  averaged 49.4 kN both in the normal and in the overloaded state (Mathematical Problems
  in Engineering 2014, article 273693, Table 2, N = 948 and 97 trucks); static steer-axle
  loads of on-highway tractors are about 10,500–11,500 lb (46.7–51.2 kN) bobtail
  (trucknews.com, "Spring Loaded", on EPA-2004/2010 tractors).  The spread (CV ≈ 5 %) is
  this model's, not a published value.  Rigid trucks: the front axle's share of the
  gross weight falls with payload (two-axle: 0.55–0.65 empty, 0.36–0.42 full, near the
  7.1 t / 11.5 t axle limits of an 18 t truck).
* Axle spacings in ranges typical of EU vehicles (group axles 1.30–1.40 m apart, equal
  within a group); tyres: steering ``single``, drive and rigid rear axles ``dual``,
  semitrailer axles ``wide`` singles (70 % of semitrailers) or ``dual``.  Suspension and
  tyre values per axle role within ±20 % of nominal (unsprung mass ±10 %); tyre
  stiffness per wheel 1.5 MN/m (single), 2.0 MN/m (wide), 3.0 MN/m (dual pair).
* Units: kg, m, N; every draw from the ``rng`` passed in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.vehicles.types import TractorSemitrailer, Truck3D

__all__ = ["FLEET_KINDS", "FLEET_MIX", "GVW_RANGE", "TrafficVehicle", "draw_kind",
           "traffic_vehicle"]

FLEET_KINDS = ("rigid_2", "rigid_3", "rigid_4", "artic_2+2", "artic_2+3", "artic_3+2",
               "artic_3+3", "artic_3+4")
FLEET_MIX = (0.12, 0.07, 0.03, 0.04, 0.55, 0.05, 0.12, 0.02)

#: (empty, full) gross mass of each kind, t.
GVW_RANGE = {
    "rigid_2": (7.5, 18.0), "rigid_3": (11.0, 26.0), "rigid_4": (14.0, 32.0),
    "artic_2+2": (13.0, 36.0), "artic_2+3": (14.5, 40.0), "artic_3+2": (16.0, 40.0),
    "artic_3+3": (17.0, 44.0), "artic_3+4": (20.0, 48.0),
}

# nominal per-wheel values by role: unsprung mass kg, suspension k N/m and c N s/m
_ROLE = {"steer": (350.0, 300e3, 6e3), "drive": (550.0, 500e3, 10e3),
         "trailer": (400.0, 400e3, 8e3)}
_TYRE_K = {"single": 1.5e6, "wide": 2.0e6, "dual": 3.0e6}  # N/m per wheel
_TYRE_C = 1e3  # N s/m per wheel
_TRACK = 2.0  # m
_HEIGHT = 2.5  # m, body height for inertia estimates
_BODY_WIDTH = 2.5  # m


@dataclass(frozen=True, kw_only=True, eq=False)
class TrafficVehicle:
    """A drawn vehicle: its model, class, tyre type per axle and loading fraction."""

    kind: str
    vehicle: Truck3D | TractorSemitrailer
    tyres: tuple[str, ...]  #: one of bwim.synthetic.detector.TYRES per axle
    loading: float  #: fraction of the payload range (0 empty, 1 full)


def draw_kind(rng: np.random.Generator, *, min_axles: int = 2) -> str:
    """A kind drawn with :data:`FLEET_MIX`, among kinds with at least ``min_axles``."""
    kinds = [k for k in FLEET_KINDS if _n_axles(k) >= min_axles]
    if not kinds:
        raise InputError(f"no vehicle kind has {min_axles} axles or more")
    share = np.array([FLEET_MIX[FLEET_KINDS.index(k)] for k in kinds])
    return kinds[int(rng.choice(len(kinds), p=share / share.sum()))]


def _n_axles(kind: str) -> int:
    if kind.startswith("rigid"):
        return int(kind[-1])
    a, b = kind.split("_")[1].split("+")
    return int(a) + int(b)


def _loading(rng: np.random.Generator) -> float:
    r = rng.uniform()
    if r < 0.2:
        return float(rng.uniform(0.0, 0.1))
    if r < 0.5:
        return float(rng.uniform(0.1, 0.8))
    return float(rng.uniform(0.8, 1.05))


def _spacings(kind: str, rng: np.random.Generator) -> np.ndarray:
    u = rng.uniform
    group = u(1.30, 1.40)
    table = {
        "rigid_2": lambda: [u(3.8, 5.8)],
        "rigid_3": lambda: [u(3.6, 4.6), group],
        "rigid_4": lambda: [u(1.9, 2.1), u(3.0, 3.8), group],
        "artic_2+2": lambda: [u(3.5, 3.9), u(6.5, 8.0), group],
        "artic_2+3": lambda: [u(3.5, 3.9), u(5.5, 7.0), group, group],
        "artic_3+2": lambda: [u(3.0, 3.4), u(1.30, 1.40), u(5.5, 7.0), group],
        "artic_3+3": lambda: [u(3.0, 3.4), u(1.30, 1.40), u(5.0, 6.5), group, group],
        "artic_3+4": lambda: [u(3.0, 3.4), u(1.30, 1.40), u(4.5, 6.0), group, group, group],
    }
    return np.array(table[kind]())


def _axles(roles: list[str], tyres: list[str], rng: np.random.Generator) -> dict:
    """Per-axle (per-wheel values) arrays; each role's values drawn once per vehicle."""
    drawn = {}
    for role in dict.fromkeys(roles):  # first-appearance order: no hash-dependent draws
        m, ks, cs = _ROLE[role]
        f = rng.uniform(0.8, 1.2, 4)
        drawn[role] = (m * rng.uniform(0.9, 1.1), ks * f[0], cs * f[1], f[2], _TYRE_C * f[3])
    return {
        "wheel_mass": np.array([drawn[r][0] for r in roles]),
        "suspension_stiffness": np.array([drawn[r][1] for r in roles]),
        "suspension_damping": np.array([drawn[r][2] for r in roles]),
        "tyre_stiffness": np.array([_TYRE_K[t] * drawn[r][3]
                                    for r, t in zip(roles, tyres, strict=True)]),
        "tyre_damping": np.array([drawn[r][4] for r in roles]),
    }


def traffic_vehicle(kind: str, rng: np.random.Generator) -> TrafficVehicle:
    """A random vehicle of ``kind`` (one of :data:`FLEET_KINDS`; see the module)."""
    if kind not in FLEET_KINDS:
        raise InputError(f"unknown vehicle kind {kind!r}; expected one of "
                         f"{', '.join(FLEET_KINDS)}")
    u = rng.uniform
    spacings = _spacings(kind, rng)
    offsets = np.concatenate([[0.0], np.cumsum(spacings)])
    n = offsets.size
    loading = _loading(rng)
    empty, full = GVW_RANGE[kind]
    gvw = (empty + loading * (full - empty)) * 1e3  # kg
    if kind.startswith("rigid"):
        n_front = 2 if kind == "rigid_4" else 1
        roles = ["steer"] * n_front + ["drive"] * (n - n_front)
        tyres = ["single"] * n_front + ["dual"] * (n - n_front)
        axles = _axles(roles, tyres, rng)
        share = {"rigid_2": ((0.55, 0.65), (0.36, 0.42)),
                 "rigid_3": ((0.45, 0.55), (0.28, 0.33)),
                 "rigid_4": ((0.50, 0.58), (0.38, 0.44))}[kind]
        s_empty, s_full = u(*share[0]), u(*share[1])
        front = s_empty + (s_full - s_empty) * min(loading, 1.0)
        body = gvw - 2.0 * axles["wheel_mass"].sum()
        f_c, r_c = offsets[:n_front].mean(), offsets[n_front:].mean()
        on_front = front * gvw - 2.0 * axles["wheel_mass"][:n_front].sum()
        cg = r_c - (r_c - f_c) * on_front / body
        length = offsets[-1] + 3.0
        vehicle = Truck3D(
            body_mass=body, cg_offset=cg,
            pitch_inertia=body * (length**2 + _HEIGHT**2) / 12,
            roll_inertia=body * (_BODY_WIDTH**2 + _HEIGHT**2) / 12,
            axle_spacings=spacings, track_width=_TRACK, **axles)
        return TrafficVehicle(kind=kind, vehicle=vehicle, tyres=tuple(tyres), loading=loading)

    n_tractor = int(kind.split("_")[1].split("+")[0])
    roles = ["steer"] + ["drive"] * (n_tractor - 1) + ["trailer"] * (n - n_tractor)
    trailer_tyre = "wide" if u() < 0.7 else "dual"
    tyres = ["single"] + ["dual"] * (n_tractor - 1) + [trailer_tyre] * (n - n_tractor)
    axles = _axles(roles, tyres, rng)
    wm = axles["wheel_mass"]
    bobtail = (u(7.0, 8.0) if n_tractor == 2 else u(8.5, 9.5)) * 1e3
    steer_share = u(0.60, 0.68) if n_tractor == 2 else u(0.50, 0.58)
    tractor = bobtail - 2.0 * wm[:n_tractor].sum()
    drive = offsets[1:n_tractor].mean()
    cg_tractor = drive * (1.0 - (steer_share * bobtail - 2.0 * wm[0]) / tractor)
    hitch = drive - u(0.2, 0.5)
    kingpin = u(0.22, 0.32)
    trailer = gvw - bobtail - 2.0 * wm[n_tractor:].sum()
    if trailer < 3e3:  # cannot happen with GVW_RANGE; guards a bad table edit
        raise InputError(f"{kind}: semitrailer body mass {trailer:.0f} kg is too small")
    group = offsets[n_tractor:].mean()
    trailer_length = offsets[-1] - hitch + 3.0
    vehicle = TractorSemitrailer(
        tractor_mass=tractor, tractor_cg_offset=cg_tractor,
        tractor_pitch_inertia=tractor * ((drive + 3.0) ** 2 + _HEIGHT**2) / 12,
        tractor_roll_inertia=tractor * (_BODY_WIDTH**2 + _HEIGHT**2) / 12,
        trailer_mass=trailer, trailer_cg_offset=group - kingpin * (group - hitch),
        trailer_pitch_inertia=trailer * (trailer_length**2 + 3.0**2) / 12,
        trailer_roll_inertia=trailer * (_BODY_WIDTH**2 + 3.0**2) / 12,
        hitch_offset=hitch, n_tractor_axles=n_tractor, axle_spacings=spacings,
        track_width=_TRACK, **axles)
    return TrafficVehicle(kind=kind, vehicle=vehicle, tyres=tuple(tyres), loading=loading)
