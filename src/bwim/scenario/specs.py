"""The scenario's section specs: frozen dataclasses that mirror the TOML file.

Contract
--------
* One dataclass per section (:class:`BridgeSpec`, :class:`SensorSpec`,
  :class:`LoggerSpec`, :class:`AxleDetectorSpec`, :class:`VehicleSpec`, :class:`RoadSpec`,
  :class:`RunSpec`, :class:`IdentifySpec`, :class:`CalibrateSpec`) and :class:`Scenario`
  holding them.  Each field declares its check (:mod:`bwim.scenario.checks`), so the
  parser (:mod:`bwim.scenario.parse`) validates a table against the dataclass itself.
* Units are SI as everywhere in bwim (m, s, N, kg, Pa; strain m/m).  The schema is in
  :mod:`bwim.scenario`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from bwim.calibration import MassSource, Method, Refine
from bwim.calibration.meshdefect import MAX_LEVELS
from bwim.dynamics import DEFAULT_APPROACH, DEFAULT_SAMPLING_RATE, VBIMethod
from bwim.errors import InputError
from bwim.fe import EdgeSupport, Supports
from bwim.mfi import ForceUnknowns, Order
from bwim.scenario.checks import (
    At,
    at_least,
    boolean,
    choice,
    choices,
    increasing_pair,
    int_from,
    int_grid,
    int_or_ints,
    int_or_pair_from,
    integer,
    is_number,
    jobs,
    non_negative,
    number,
    number_or_numbers,
    number_or_string,
    numbers,
    opt,
    pair,
    positive,
    req,
    show,
    string,
    strings,
    subtable,
    tables,
)
from bwim.scenario.checks import number as finite_number  # LaneSpec has a field "number"
from bwim.sensors import SensorKind
from bwim.vehicles import NAMED_VEHICLES
from bwim.vehicles.types import HalfCar, MovingForces, SprungMass, TractorSemitrailer, Truck3D

__all__ = ["DIRECTIONS", "VEHICLE_TYPES", "AxleDetectorSpec", "BridgeSpec", "CalibrateSpec",
           "ClockTable", "DriftSpec", "GirderSpec", "IdentifySpec", "LaneSpec", "LinesSpec",
           "LoggerSpec", "RoadSpec", "RunSpec", "Scenario", "SectionSpec", "SensorSpec",
           "TriggerSpec", "VehicleSpec"]

#: Vehicle classes by their scenario ``type``.
VEHICLE_TYPES: Mapping[str, type] = MappingProxyType({
    "moving_forces": MovingForces,
    "sprung_mass": SprungMass,
    "half_car": HalfCar,
    "truck3d": Truck3D,
    "tractor_semitrailer": TractorSemitrailer,
})

_PLATE = ("plate",)
_BEAM = ("beam",)


_EDGES = tuple(f.name for f in fields(Supports))


def _supports(v: Any, at: At) -> str | Mapping[str, str]:
    if isinstance(v, str):
        return v
    if not isinstance(v, dict):
        raise at.expected("a preset name or a table of edges", v)
    sub = At(at.src, f"[{at.section.strip('[]')}.supports]")
    for edge, value in v.items():
        if edge not in _EDGES:
            raise InputError(f"{at.src}: unknown key {edge!r} in {sub.section}; "
                             f"allowed keys: {', '.join(_EDGES)}")
        choice(*EdgeSupport)(value, At(at.src, sub.section, edge))
    return MappingProxyType(dict(v))



def _levels_or_auto(v: Any, at: At) -> int | str:
    """``calibrate``'s ``mesh_correction``: 0 to MAX_LEVELS bisections, or "auto"."""
    if v == "auto":
        return v
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_LEVELS:
        raise at.error(f"must be an integer from 0 to {MAX_LEVELS} or \"auto\", got {show(v)}")
    return v



def _lam(v: Any, at: At) -> float | str:
    if isinstance(v, str):
        return choice("lcurve", "gcv")(v, at)
    if not is_number(v):
        raise at.expected('"lcurve", "gcv" or a number', v)
    return float(v)



@dataclass(frozen=True, kw_only=True)
class SectionSpec:
    """A composite girder section (:func:`bwim.fe.composite_section`); m, m², m⁴."""

    girder_area: float = req(number)
    girder_inertia: float = req(number)
    girder_depth: float = req(number)
    slab_width: float = req(number)
    girder_centroid_height: float | None = opt(number)
    slab_thickness: float | None = opt(number)
    """Default: the deck's thickness."""
    modular_ratio: float | None = opt(number)
    """``E_slab / E_girder``; default: the deck's (single) E over the girder's E."""
    exclude_slab_bending: bool = opt(boolean, True)


_SECTION_TABLE = subtable(SectionSpec, "bridge.girders.section")


@dataclass(frozen=True, kw_only=True)
class GirderSpec:
    """A girder (:class:`bwim.Girder`): give ``I`` and ``z_bottom`` or a ``section``."""

    y: float = req(number)
    E: float = req(number)
    mu: float = req(number)
    I: float | None = opt(number)
    z_bottom: float | None = opt(number)
    J: float = opt(number, 0.0)
    poisson: float = opt(number, 0.2)
    section: SectionSpec | None = opt(_SECTION_TABLE)  # noqa: RUF009 (a field)


_GIRDER_TABLES = tables(GirderSpec, "bridge.girders")


@dataclass(frozen=True, kw_only=True)
class BridgeSpec:
    """The ``[bridge]`` section (arguments of :meth:`bwim.Bridge.plate` / ``.beam``).

    Lengths in m, moduli in Pa, ``mu`` in kg/m² (plate) or kg/m (beam), ``I`` in m⁴.
    Per-zone values are tuples.
    """

    kind: str = req(choice("plate", "beam"))
    length: float = req(number)
    width: float | None = req(number, _PLATE)
    thickness: float | None = req(number, _PLATE)
    nx: int | None = opt(integer, None, _PLATE)
    ny: int | None = opt(integer, None, _PLATE)
    n_elements: int | None = opt(integer, None, _BEAM)
    x_lines: tuple[float, ...] | None = opt(numbers)
    y_lines: tuple[float, ...] | None = opt(numbers, None, _PLATE)
    x_through: tuple[float, ...] | None = opt(numbers)
    y_through: tuple[float, ...] | None = opt(numbers, None, _PLATE)
    E: float | tuple[float, ...] | None = opt(number_or_numbers)
    E_x: float | tuple[float, ...] | None = opt(number_or_numbers, None, _PLATE)
    E_y: float | tuple[float, ...] | None = opt(number_or_numbers, None, _PLATE)
    mu: float | tuple[float, ...] = req(number_or_numbers)
    I: float | None = req(number, _BEAM)
    z_bottom: float | None = opt(number, None, _BEAM)
    poisson: float = opt(number, 0.2, _PLATE)
    damping_ratio: float = opt(number, 0.03)
    supports: str | Mapping[str, str] | None = opt(_supports)
    zones: int | tuple[int, ...] | None = opt(int_or_ints)
    zone_map: tuple | None = opt(int_grid)
    n_zones: int | None = opt(integer)
    joints: tuple[float, ...] | None = opt(numbers, None, _PLATE)
    girders: tuple[GirderSpec, ...] = opt(_GIRDER_TABLES, (), _PLATE)




def _name_or_names(v: Any, at: At) -> str | tuple[str, ...]:
    if isinstance(v, list):
        names = strings(v, at)
        if any(not n.strip() for n in names):
            raise at.error("sensor names must not be empty")
        return names
    return string(v, at)


#: Kinds of a ``[[sensors]]`` entry (axle detectors are declared in ``[axle_detectors]``).
_SENSOR_KINDS = tuple(k for k in SensorKind if k is not SensorKind.AXLE_DETECTOR)


@dataclass(frozen=True, kw_only=True)
class SensorSpec:
    """One ``[[sensors]]`` entry: a sensor, or a grid when ``x``, ``y`` or ``kind`` is a
    tuple (expanded kind by kind, then x, then y).  Positions in m; ``x`` (and ``y``) may
    be left out when no FE model is used (logger channels weighed with influence lines),
    and ``name`` may then be a list: one sensor per name."""

    x: float | tuple[float, ...] | None = opt(number_or_numbers)
    y: float | tuple[float, ...] | None = opt(number_or_numbers)
    kind: str | tuple[str, ...] = opt(choices(*_SENSOR_KINDS), SensorKind.STRAIN_X.value)
    name: str | tuple[str, ...] = opt(_name_or_names, "")


_DELIMITERS = (",", ";", "tab", "whitespace", "\t", " ")


@dataclass(frozen=True, kw_only=True)
class ClockTable:
    """``[logger] clock``: a strptime ``pattern`` of the file name, or a clock ``column``
    (with its ``date`` column and ``format``), or ``none`` (no clock): the arguments of
    :class:`bwim.io.ClockSpec`."""

    pattern: str | None = None
    column: str | None = None
    date: str | None = None
    format: str | None = None
    none: bool = False


def _clock(v: Any, at: At) -> ClockTable:
    if isinstance(v, str):
        if v == "none":
            return ClockTable(none=True)
        if v == "name":
            return ClockTable()
        return ClockTable(pattern=v)
    if not isinstance(v, dict):
        raise at.expected('a file-name pattern, "name", "none" or a table {column, date, '
                          'format}', v)
    for key in v:
        if key not in ("column", "date", "format", "pattern"):
            raise at.error(f"unknown key {key!r}; allowed keys: column, date, format, "
                           "pattern")
    vals = {k: string(x, At(at.src, at.section, f"clock.{k}")) for k, x in v.items()}
    return ClockTable(**vals)


@dataclass(frozen=True, kw_only=True)
class LoggerSpec:
    """The ``[logger]`` section: how a logger's text export is laid out
    (:class:`bwim.io.LoggerFormat`).  ``columns`` names every column in order (``"-"``
    skips one; ``"time"`` is the time column, in s); the delimiter and a header row are
    detected unless given; ``sampling_rate`` (Hz) when there is no time column; ``scale``
    turns logger units into strain (one number or one per channel in column order)."""

    columns: tuple[str, ...] = req(strings)
    delimiter: str | None = opt(choice(*_DELIMITERS))
    header: bool | None = opt(boolean)
    sampling_rate: float | None = opt(number)
    scale: float | tuple[float, ...] = opt(number_or_numbers, 1.0)
    decimal: str = opt(choice(".", ","), ".")
    skip_lines: int = opt(integer, 0)
    clock: ClockTable | None = opt(_clock)  # noqa: RUF009 (a field)
    """Where each file's clock comes from (:class:`bwim.io.ClockSpec`): default, a
    timestamp in the file name in a common form."""


#: Travel directions in the bridge frame: +x (the frame's own) or −x.
DIRECTIONS = ("+x", "-x")


@dataclass(frozen=True, kw_only=True)
class AxleDetectorSpec:
    """One ``[[axle_detectors]]`` table (a lane's pair; the single ``[axle_detectors]``
    table of one lane stays valid): two logger channels that respond to each axle, named
    in the order that lane's traffic meets them, ``distance`` m apart; ``lane`` (its
    number), ``direction`` ("+x" or "-x"), ``y`` the detectors' lateral position (m);
    ``position`` is the first detector's x in the lines' frame (default: 0 for the lane
    the calibration truck drives, whose first detector the lines are measured from;
    ``distance`` for a −x lane whose pair is the same one mirrored); ``calibration`` marks
    the lane of the calibration truck (default: the first table); ``max_spacing`` the
    largest axle spacing within one vehicle and ``max_length`` the longest vehicle's spread
    from its first to its last axle (m; default 18.75, 25.25 where European Modular
    System combinations run)."""

    channels: tuple[str, ...] = req(strings)
    distance: float = req(number)
    position: float | None = opt(number)
    max_spacing: float | None = opt(number)
    max_length: float | None = opt(number)
    lane: int | None = opt(int_from(1))
    direction: str = opt(choice(*DIRECTIONS), "+x")
    y: float | None = opt(number)
    calibration: bool | None = opt(boolean)


@dataclass(frozen=True, kw_only=True)
class LaneSpec:
    """One ``[[lanes]]`` table: a traffic lane (with or without axle detectors), so that a
    vehicle found by the gauges' lateral position can be given its lane: ``number``, the
    centre line's ``y`` (m) and the ``direction``."""

    number: int = req(int_from(1))
    y: float = req(finite_number)  # not ``number``: the field above shadows it here
    direction: str = opt(choice(*DIRECTIONS), "+x")


@dataclass(frozen=True, kw_only=True)
class DriftSpec:
    """The ``[drift]`` section: how the drift of the strain-to-load ratio is corrected
    (:mod:`bwim.site.drift`): ``method``; ``temperature``, the logger channel of a
    temperature (°C) when the logger has one; for the traffic method the reference
    ``reference_class`` (an axle-group code such as ``"113"``, default: the commonest
    articulated class) and, where no traffic was weighed while the calibration holds, its
    steering axle's nominal load ``reference_kN``; ``min_reference``, the fewest reference
    vehicles a date needs for the traffic method (default 20)."""

    method: str = opt(choice("auto", "traffic", "temperature", "time_of_day", "trend",
                             "none"), "auto")
    temperature: str | None = opt(string)
    reference_class: str | None = opt(string)
    reference_kN: float | None = opt(at_least(1.0, strict=True))
    min_reference: int | None = opt(int_from(3))


@dataclass(frozen=True, kw_only=True)
class TriggerSpec:
    """The ``[trigger]`` section: how ``bwim weigh --continuous`` cuts a long recording
    into events (:class:`bwim.stream.TriggerSettings`, docs/streams.md; a key left out
    keeps its default): the thresholds ``on`` and ``off`` (noise σ), ``pre``, ``post``,
    ``min_duration``, ``merge_gap``, ``max_duration``, ``baseline`` and ``frame`` (s),
    ``noise`` (σ of the summed channels, their units; estimated when left out) and
    ``channels`` (the channels summed; default every strain and deflection channel)."""

    on: float | None = opt(at_least(0.0, strict=True))
    off: float | None = opt(at_least(0.0, strict=True))
    pre: float | None = opt(at_least(0.0, strict=False))
    post: float | None = opt(at_least(0.0, strict=False))
    min_duration: float | None = opt(at_least(0.0, strict=False))
    merge_gap: float | None = opt(at_least(0.0, strict=False))
    max_duration: float | None = opt(at_least(0.0, strict=True))
    baseline: float | None = opt(at_least(0.0, strict=True))
    frame: float | None = opt(at_least(0.0, strict=True))
    noise: float | None = opt(at_least(0.0, strict=True))
    channels: tuple[str, ...] | None = opt(strings)


@dataclass(frozen=True, kw_only=True)
class LinesSpec:
    """The ``[lines]`` section: how the site's influence lines are found from the
    calibration runs (:class:`bwim.site.SiteSetup`): ``support_lobes`` keeps a lobe of the
    lines beyond their first zeros (a slab continuous over its supports, or abutments
    that carry moment; a record may end on the lobe), off by default."""

    support_lobes: bool = opt(boolean, False)


@dataclass(frozen=True, kw_only=True)
class VehicleSpec:
    """The ``[vehicle]`` section: a named vehicle, or a ``type`` and its parameters
    (numbers, or lists of numbers per axle, in the class's SI units)."""

    name: str | None = None
    type: str | None = None
    params: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self) -> None:
        if (self.name is None) == (self.type is None):
            raise InputError("a vehicle spec needs either a name or a type")
        if self.name is not None and self.name not in NAMED_VEHICLES:
            raise InputError(f"unknown vehicle {self.name!r}; expected one of "
                             f"{', '.join(NAMED_VEHICLES)}")
        if self.type is not None and self.type not in VEHICLE_TYPES:
            raise InputError(f"unknown vehicle type {self.type!r}; expected one of "
                             f"{', '.join(VEHICLE_TYPES)}")
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))


@dataclass(frozen=True, kw_only=True)
class RoadSpec:
    """The ``[road]`` section: flat, ISO 8608 (``roughness``) or a CSV ``profile``."""

    flat: bool = opt(boolean, False)
    roughness: float | str | None = opt(number_or_string)
    """G_d(n₀), m³/cycle, or an ISO 8608 class letter."""
    length: float | None = opt(positive)
    start: float | None = opt(number)
    seed: int = opt(int_from(0), 0)
    dx: float | None = opt(positive)
    track_correlation: float | None = opt(number)
    waviness: float | None = opt(number)
    band: tuple[float, float] | None = opt(pair)
    profile: str | None = opt(string)
    """CSV file; relative paths are taken from the scenario's folder."""
    smoothing: float | None = opt(positive)
    """Tyre-patch moving-average length, m."""


@dataclass(frozen=True, kw_only=True)
class RunSpec:
    """The ``[run]`` section: a simulated crossing (see :func:`bwim.simulate`)."""

    speed: float = req(positive)
    lane: float | None = opt(number)
    sampling_rate: float = opt(positive, DEFAULT_SAMPLING_RATE)
    approach: float = opt(non_negative, DEFAULT_APPROACH)
    tail: float = opt(non_negative, 0.0)
    method: str = opt(choice(*VBIMethod), VBIMethod.COUPLED.value)
    delay: float = opt(non_negative, 0.0)
    n_modes: int | None = opt(int_from(1))
    max_frequency: float | None = opt(positive)
    full_system: bool = opt(boolean, False)
    static_correction: bool = opt(boolean, True)
    noise: float = opt(at_least(0.0, strict=False, high=1.0), 0.0)
    """Gauge noise: one σ on every channel, a fraction of the record's peak strain
    (:meth:`bwim.Record.with_noise`; the paper's per-channel model is not a scenario
    option)."""
    seed: int = opt(int_from(0), 0)
    """Seed of the noise."""

    def simulate_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`bwim.simulate` (everything but the objects)."""
        kw: dict[str, Any] = {
            "speed": self.speed, "sampling_rate": self.sampling_rate,
            "approach": self.approach, "tail": self.tail, "method": self.method,
            "delay": self.delay, "full_system": self.full_system,
            "static_correction": self.static_correction,
        }
        for name in ("lane", "n_modes", "max_frequency"):
            if getattr(self, name) is not None:
                kw[name] = getattr(self, name)
        return kw


def _set_options(spec: Any) -> dict[str, Any]:
    return {f.name: getattr(spec, f.name) for f in fields(spec)
            if getattr(spec, f.name) is not None}


@dataclass(frozen=True, kw_only=True)
class IdentifySpec:
    """The ``[identify]`` section: options of :func:`bwim.identify_forces` (unset: the
    library's default)."""

    n_modes: int | None = opt(int_from(1))
    lam: float | str | None = opt(_lam)
    order: str | None = opt(choice(*Order))
    unknowns: str | None = opt(choice(*ForceUnknowns))
    central: float | None = opt(number)
    static_correction: bool | None = opt(boolean)
    lam_range: tuple[float, float] | None = opt(increasing_pair)
    n_lam: int | None = opt(int_from(2))

    def kwargs(self) -> dict[str, Any]:
        """The options that are set, as keyword arguments."""
        return _set_options(self)


@dataclass(frozen=True, kw_only=True)
class CalibrateSpec:
    """The ``[calibrate]`` section: options of ``bwim.calibrate`` (unset: its default)."""

    unknowns: tuple[str, ...] | None = opt(strings)
    seed: int | None = opt(integer)
    method: str | None = opt(choice(*Method))
    refine: str | None = opt(choice(*Refine))
    population: int | tuple[int, int] | None = opt(int_or_pair_from(2))
    elite_fraction: float | None = opt(number)
    convergences: int | None = opt(int_from(0))
    max_evals: int | tuple[int, int] | None = opt(int_or_pair_from(1))
    bounds: tuple[float, float] | None = opt(pair)
    substructure: bool | None = opt(boolean)
    weights: str | None = opt(choice("none", "noise", "peak", "model"))
    mesh_check: float | None = opt(at_least(0.0, strict=True, high=1.0))
    mesh_correction: int | str | None = opt(_levels_or_auto)
    mass: str | None = opt(choice(*MassSource))
    n_modes: int | None = opt(int_from(1))
    n_jobs: int | None = opt(jobs)

    def kwargs(self) -> dict[str, Any]:
        """The options that are set, as keyword arguments."""
        return _set_options(self)


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """A parsed scenario file (see the module docstring for the schema).

    ``source`` names the file in messages and ``folder`` resolves relative paths; neither
    takes part in equality.
    """

    bridge: BridgeSpec | None = None
    sensors: tuple[SensorSpec, ...] = ()
    logger: LoggerSpec | None = None
    axle_detectors: tuple[AxleDetectorSpec, ...] = ()
    lanes: tuple[LaneSpec, ...] = ()
    drift: DriftSpec | None = None
    lines: LinesSpec | None = None
    trigger: TriggerSpec | None = None
    vehicle: VehicleSpec | None = None
    road: RoadSpec | None = None
    run: RunSpec | None = None
    identify: IdentifySpec | None = None
    calibrate: CalibrateSpec | None = None
    title: str = ""
    source: str = field(default="<scenario>", compare=False)
    folder: Path | None = field(default=None, compare=False)

    def require(self, section: str) -> Any:
        """The spec of ``section`` or an :class:`InputError` saying the file lacks it."""
        value = getattr(self, section)
        if value is None or value == ():
            header = "[[sensors]]" if section == "sensors" else f"[{section}]"
            raise InputError(f"{self.source}: no {header} section")
        return value

