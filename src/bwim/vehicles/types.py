"""The vehicle models: moving forces, sprung mass, half car, 3-D truck, tractor–semitrailer.

Contract
--------
Each class is a frozen description of a vehicle with a ``model()`` method returning the
common linear :class:`~bwim.vehicles.model.VehicleModel`, and ``passage(speed, lane)``
returning the :class:`~bwim.records.Passage` a B-WIM system would see.  Per-axle
parameters are arrays of length n_axles (a scalar is broadcast); in the 3-D models they
are values **per wheel** (each axle has two wheels).  Units: kg, kg m², N/m, N s/m, m.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from bwim.conventions import GRAVITY
from bwim.errors import InputError, require_finite, require_positive
from bwim.records import AxleLayout, Passage
from bwim.vehicles.model import BodySpec, VehicleModel, WheelSpec, assemble

__all__ = ["HalfCar", "MovingForces", "SprungAxles", "SprungAxles3D", "SprungMass",
           "TractorSemitrailer", "Truck3D", "Vehicle"]


def _per_axle(name: str, value, n: int, *, positive: bool = True, allow_zero=False):
    arr = np.array(value, dtype=float, ndmin=1)
    if arr.size == 1:
        arr = np.full(n, arr.item())
    if arr.shape != (n,):
        raise InputError(f"{name} must be a scalar or have one value per axle ({n}), "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite, got {arr.tolist()}")
    if positive and (np.any(arr < 0) if allow_zero else np.any(arr <= 0)):
        bad = arr[(arr < 0) if allow_zero else (arr <= 0)][0]
        word = "non-negative" if allow_zero else "positive"
        raise InputError(f"{name} must be {word}, got {bad:g}")
    return arr


def _spacings(value) -> np.ndarray:
    sp = np.array(value, dtype=float, ndmin=1) if np.size(value) else np.zeros(0)
    if not np.all(np.isfinite(sp)) or np.any(sp <= 0):
        raise InputError(f"axle_spacings must be positive distances, got {sp.tolist()}")
    return sp


class Vehicle(AxleLayout, ABC):
    """The base of every vehicle model: what simulation, calibration and weighing use
    (``model()``, ``passage()``, the axle layout); the subclasses are frozen dataclasses."""

    axle_spacings: np.ndarray
    track_width: float | None

    @property
    def length(self) -> float:
        """Distance from the first to the last axle, m."""
        return float(self.axle_spacings.sum())

    @property
    def static_axle_loads(self) -> np.ndarray:
        return self.model().static_axle_loads

    def passage(self, speed: float, lane: float = 0.0, delay: float = 0.0) -> Passage:
        return Passage(speed=speed, lane=lane, axle_spacings=self.axle_spacings,
                       track_width=self.track_width, delay=delay)

    @abstractmethod
    def model(self) -> VehicleModel:
        """The vehicle in the common linear form."""


@dataclass(frozen=True, kw_only=True, eq=False)
class MovingForces(Vehicle):
    """Constant axle loads at fixed spacings (no vehicle dynamics).

    ``track_width`` None: one force per axle on the lane centre line (1-D bridges);
    otherwise two wheels per axle, each carrying half the axle load.
    """

    axle_loads: np.ndarray
    axle_spacings: np.ndarray = field(default_factory=lambda: np.zeros(0))
    track_width: float | None = None

    def __post_init__(self) -> None:
        sp = _spacings(self.axle_spacings)
        object.__setattr__(self, "axle_spacings", sp)
        object.__setattr__(self, "axle_loads", _per_axle("axle_loads", self.axle_loads,
                                                         sp.size + 1))
        if self.track_width is not None:
            object.__setattr__(self, "track_width",
                               require_positive("track_width", self.track_width))

    def model(self) -> VehicleModel:
        n_w = 1 if self.track_width is None else 2
        axle = np.repeat(np.arange(self.n_axles), n_w)
        lateral = (np.zeros(axle.size) if n_w == 1
                   else np.tile([-self.track_width / 2, self.track_width / 2], self.n_axles))
        z0 = np.zeros((0, axle.size))
        return VehicleModel(
            mass=np.zeros((0, 0)), damping=np.zeros((0, 0)), stiffness=np.zeros((0, 0)),
            contact=z0, tyre_stiffness=np.zeros(axle.size), tyre_damping=np.zeros(axle.size),
            static_forces=self.axle_loads[axle] / n_w, contact_offset=self.axle_offsets[axle],
            contact_lateral=lateral, contact_axle=axle, axle_offsets=self.axle_offsets,
        )


@dataclass(frozen=True, kw_only=True, eq=False)
class SprungMass(Vehicle):
    """A single sprung mass (quarter car): body ``mass`` on ``stiffness``/``damping``.

    Without ``unsprung_mass`` the spring–damper rests on the road (Biggs' sprung mass);
    with it, the spring–damper is the suspension and the wheel rests on a tyre
    (``tyre_stiffness``, ``tyre_damping``).  One contact on the lane centre line.
    """

    mass: float
    stiffness: float
    damping: float = 0.0
    unsprung_mass: float = 0.0
    tyre_stiffness: float | None = None
    tyre_damping: float = 0.0
    axle_spacings: np.ndarray = field(default_factory=lambda: np.zeros(0), init=False)
    track_width: float | None = field(default=None, init=False)

    def __post_init__(self) -> None:
        require_positive("mass", self.mass)
        require_positive("stiffness", self.stiffness)
        if require_finite("damping", self.damping) < 0:
            raise InputError(f"damping must be >= 0, got {self.damping:g}")
        if self.unsprung_mass:
            require_positive("unsprung_mass", self.unsprung_mass)
            if self.tyre_stiffness is None:
                raise InputError("a sprung mass with an unsprung mass needs tyre_stiffness")
            require_positive("tyre_stiffness", self.tyre_stiffness)

    def model(self) -> VehicleModel:
        body = BodySpec(mass=self.mass)
        if not self.unsprung_mass:
            wheel = WheelSpec(body=0, offset=0.0, tyre_stiffness=self.stiffness,
                              tyre_damping=self.damping)
        else:
            wheel = WheelSpec(body=0, offset=0.0, mass=self.unsprung_mass,
                              suspension_stiffness=self.stiffness,
                              suspension_damping=self.damping,
                              tyre_stiffness=self.tyre_stiffness, tyre_damping=self.tyre_damping)
        return assemble([body], [wheel])


def _axle_wheels(
    n_axles, offsets, track_width, body, wheel_mass, ks, cs, kt, ct, two_d: bool
) -> list[WheelSpec]:
    wheels = []
    for i in range(n_axles):
        if two_d:
            if track_width is None:
                wheels.append(WheelSpec(body=body, offset=offsets[i], axle=i, mass=wheel_mass[i],
                                        suspension_stiffness=ks[i], suspension_damping=cs[i],
                                        tyre_stiffness=kt[i], tyre_damping=ct[i]))
            else:  # one wheel DOF per axle, the tyre split over two contact points
                for k, e in enumerate((-track_width / 2, track_width / 2)):
                    wheels.append(WheelSpec(
                        body=body, offset=offsets[i], lateral=e, axle=i, mass=wheel_mass[i],
                        suspension_stiffness=ks[i], suspension_damping=cs[i],
                        tyre_stiffness=kt[i] / 2, tyre_damping=ct[i] / 2, share_previous=k == 1))
        else:
            for e in (-track_width / 2, track_width / 2):
                wheels.append(WheelSpec(body=body, offset=offsets[i], lateral=e, axle=i,
                                        mass=wheel_mass[i], suspension_stiffness=ks[i],
                                        suspension_damping=cs[i], tyre_stiffness=kt[i],
                                        tyre_damping=ct[i]))
    return wheels


@dataclass(frozen=True, kw_only=True, eq=False)
class SprungAxles(Vehicle):
    """The base of the vehicles whose axles hang from rigid bodies: the axle layout and
    the per-axle wheel mass, suspension and tyre (arrays of length n_axles, a scalar
    broadcast; the subclasses say whether a value is per wheel or per axle).

    ``track_width`` None (the default here): one contact per axle on the centre line.
    """

    axle_spacings: np.ndarray
    wheel_mass: np.ndarray
    suspension_stiffness: np.ndarray
    suspension_damping: np.ndarray
    tyre_stiffness: np.ndarray
    tyre_damping: np.ndarray = 0.0
    track_width: float | None = None

    def _wheels(self, body: int, *, two_d: bool) -> list[WheelSpec]:
        """The wheels of every axle, hung from ``body`` (per-axle parameter arrays)."""
        return _axle_wheels(self.n_axles, self.axle_offsets, self.track_width, body,
                            self.wheel_mass, self.suspension_stiffness,
                            self.suspension_damping, self.tyre_stiffness, self.tyre_damping,
                            two_d=two_d)


@dataclass(frozen=True, kw_only=True, eq=False)
class HalfCar(SprungAxles):
    """A 2-D vehicle: body bounce and pitch, one wheel mass per axle (values per axle).

    ``cg_offset`` is the body's centre of gravity behind the first axle, m.  With a
    ``track_width`` each axle's tyre force is shared by two wheels at ±track/2 (for plate
    bridges); otherwise one contact per axle on the centre line.
    """

    body_mass: float
    pitch_inertia: float
    cg_offset: float

    def __post_init__(self) -> None:
        _validate_body(self, roll=False)

    def model(self) -> VehicleModel:
        body = BodySpec(mass=self.body_mass, cg_offset=self.cg_offset,
                        pitch_inertia=self.pitch_inertia)
        return assemble([body], self._wheels(0, two_d=True))


@dataclass(frozen=True, kw_only=True, eq=False)
class SprungAxles3D(SprungAxles):
    """The 3-D vehicles' axles: each a rigid bar with a wheel mass at each end, the wheels
    ``track_width`` apart (values **per wheel**, one per axle)."""

    track_width: float = 2.0


@dataclass(frozen=True, kw_only=True, eq=False)
class Truck3D(SprungAxles3D):
    """The paper's 3-D rigid truck: body bounce, pitch and roll; axles as in
    :class:`SprungAxles3D` (values per wheel).

    DOF: 3 + 2 × n_axles.  ``cg_offset`` is the body CG behind the first axle, m.
    """

    body_mass: float
    pitch_inertia: float
    roll_inertia: float
    cg_offset: float

    def __post_init__(self) -> None:
        _validate_body(self, roll=True)

    @classmethod
    def from_axle_loads(
        cls, *, axle_loads, axle_spacings, wheel_mass, **kw
    ) -> Truck3D:
        """A two-axle truck whose body mass and CG give the stated static axle loads.

        ``wheel_mass`` is per wheel; the body carries the rest of each axle load, and its
        CG follows from the lever rule (statically determinate for two axles).
        """
        loads = np.array(axle_loads, dtype=float)
        sp = _spacings(axle_spacings)
        if loads.shape != (2,) or sp.shape != (1,):
            raise InputError("from_axle_loads needs exactly two axle loads and one spacing")
        wm = _per_axle("wheel_mass", wheel_mass, 2)
        body_share = loads - 2 * wm * GRAVITY
        if np.any(body_share <= 0):
            raise InputError("wheel masses exceed the axle loads")
        body_mass = body_share.sum() / GRAVITY
        cg = sp[0] * body_share[1] / body_share.sum()
        return cls(body_mass=body_mass, axle_spacings=sp, cg_offset=cg, wheel_mass=wm, **kw)

    def model(self) -> VehicleModel:
        body = BodySpec(mass=self.body_mass, cg_offset=self.cg_offset,
                        pitch_inertia=self.pitch_inertia, roll_inertia=self.roll_inertia)
        return assemble([body], self._wheels(0, two_d=False))


@dataclass(frozen=True, kw_only=True, eq=False)
class TractorSemitrailer(SprungAxles3D):
    """An articulated 3-D vehicle: a tractor and a semitrailer, each a rigid body with
    bounce, pitch and roll, joined at the fifth wheel (a hitch that transmits vertical
    force and, being roll-stiff, roll).  Axles as in :class:`SprungAxles3D` (values per
    wheel).

    Axles ``0 … n_tractor_axles − 1`` belong to the tractor, the rest to the trailer.
    ``hitch_offset`` is the fifth wheel's distance behind the first axle; CG offsets are
    measured behind the first axle too.
    """

    tractor_mass: float
    tractor_pitch_inertia: float
    tractor_roll_inertia: float
    tractor_cg_offset: float
    trailer_mass: float
    trailer_pitch_inertia: float
    trailer_roll_inertia: float
    trailer_cg_offset: float
    hitch_offset: float
    n_tractor_axles: int

    def __post_init__(self) -> None:
        sp = _spacings(self.axle_spacings)
        object.__setattr__(self, "axle_spacings", sp)
        for name in ("tractor_mass", "tractor_pitch_inertia", "tractor_roll_inertia",
                     "trailer_mass", "trailer_pitch_inertia", "trailer_roll_inertia"):
            require_positive(name, getattr(self, name))
        if not 1 <= self.n_tractor_axles < sp.size + 1:
            raise InputError(f"n_tractor_axles must be in [1, {sp.size}], "
                             f"got {self.n_tractor_axles}")
        _validate_axles(self)

    def model(self) -> VehicleModel:
        tractor = BodySpec(mass=self.tractor_mass, cg_offset=self.tractor_cg_offset,
                           pitch_inertia=self.tractor_pitch_inertia,
                           roll_inertia=self.tractor_roll_inertia)
        trailer = BodySpec(mass=self.trailer_mass, cg_offset=self.trailer_cg_offset,
                           pitch_inertia=self.trailer_pitch_inertia,
                           roll_inertia=self.trailer_roll_inertia)
        wheels = []
        for body, axles in ((0, range(self.n_tractor_axles)),
                            (1, range(self.n_tractor_axles, self.n_axles))):
            wheels += [w for w in self._wheels(body, two_d=False) if w.axle in axles]
        hitch = ((0, self.hitch_offset, 0.0), (1, self.hitch_offset, 0.0))
        return assemble([tractor, trailer], wheels, constraints=[hitch], roll_links=[(0, 1)])


def _validate_axles(v) -> None:
    n = v.n_axles
    for name in ("wheel_mass", "suspension_stiffness", "suspension_damping",
                 "tyre_stiffness", "tyre_damping"):
        allow_zero = name in ("suspension_damping", "tyre_damping")
        object.__setattr__(v, name, _per_axle(name, getattr(v, name), n, allow_zero=allow_zero))
    if v.track_width is not None:
        object.__setattr__(v, "track_width", require_positive("track_width", v.track_width))


def _validate_body(v, *, roll: bool) -> None:
    object.__setattr__(v, "axle_spacings", _spacings(v.axle_spacings))
    require_positive("body_mass", v.body_mass)
    require_positive("pitch_inertia", v.pitch_inertia)
    if roll:
        require_positive("roll_inertia", v.roll_inertia)
    require_finite("cg_offset", v.cg_offset)
    _validate_axles(v)
