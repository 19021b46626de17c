"""Scenario files: a bridge, its sensors, a vehicle, a road and run settings in TOML.

Contract
--------
* :func:`load_scenario` reads a TOML file into a :class:`Scenario`, a frozen dataclass of
  section specs (:class:`BridgeSpec`, :class:`SensorSpec`, :class:`VehicleSpec`,
  :class:`RoadSpec`, :class:`RunSpec`, :class:`IdentifySpec`, :class:`CalibrateSpec`) that
  mirror the file; :func:`scenario_from_dict` does the same for an already parsed mapping
  and :func:`dump_scenario` writes a scenario back (``load → dump → load`` gives an equal
  scenario; comments are not kept).  The builders in :mod:`bwim.io.build` turn specs into
  bwim objects.
* Validation is strict and every message is one line that starts with the file name:

  - malformed TOML: ``"scenario.toml: line L, column C: <reason>"``;
  - an unknown key: ``"scenario.toml: unknown key 'lenght' in [bridge]; allowed keys:
    ..."`` (the allowed keys depend on the bridge ``kind`` and the vehicle ``type``);
  - a missing key: ``"scenario.toml: [bridge] is missing the key 'length'"``;
  - a wrong type: ``"scenario.toml: [bridge] nx: expected an integer, got 12.5"``;
  - an unknown choice: ``"scenario.toml: [vehicle] name: unknown value 'lorry'; expected
    one of two_axle_truck, ..."``.

  Values the library itself rejects (a negative modulus, a sensor off the deck) are
  reported by the builders with the library's message prefixed by the file and section.
* Units are SI as everywhere in bwim (m, s, N, kg, Pa; strain m/m).  Integers are accepted
  where numbers are expected; booleans never are.
* Schema (keys in brackets are optional; see ``examples/*.toml`` for commented files):

  ``title``
      optional free text.
  ``[bridge]``
      (optional: weighing with influence lines needs no FE model)
      ``kind = "plate" | "beam"``, ``length``.  Plate: ``width``, ``thickness``, mesh
      ``nx``/``ny`` or explicit ``x_lines``/``y_lines`` (optionally ``x_through``/
      ``y_through``: coordinates the grid must pass through, such as girder lines),
      ``E`` or ``E_x``/``E_y``, ``mu`` (kg/m²), [``poisson`` = 0.2].  Beam: ``n_elements``
      or ``x_lines`` [``x_through``], ``E``, ``I``, ``mu`` (kg/m), [``z_bottom``].  Both:
      [``damping_ratio`` = 0.03], [``supports``: a preset name or a table of edges
      ``x0``, ``x_end``, ``y0``, ``y_end`` → ``"free" | "simple" | "clamped"``],
      [``zones`` = [nzx, nzy] (plate) or n (beam)] or [``zone_map``: a zone label per
      element, (nx, ny) nested list or (n_elements,) list, with optional ``n_zones``].
      Moduli and masses are a number or one value per zone.
  ``[[bridge.girders]]``
      ``y``, ``E``, ``mu`` (kg/m), [``J`` = 0], [``poisson`` = 0.2] and either ``I`` and
      ``z_bottom`` or a sub-table ``[bridge.girders.section]`` for
      :func:`bwim.fe.composite_section` (``girder_area``, ``girder_inertia``,
      ``girder_depth``, ``slab_width``, [``girder_centroid_height``],
      [``slab_thickness`` = the deck's], [``modular_ratio`` = deck E / girder E],
      [``exclude_slab_bending`` = true]).
  ``[[sensors]]``
      ``x``, [``y`` = 0], [``kind`` = "strain_x"], [``name``].  Any of ``x``, ``y``,
      ``kind`` may be a list: the entry is then a grid, expanded kind by kind, then x,
      then y.  ``name`` is a template with the fields ``{kind}``, ``{short}`` (``x``,
      ``y`` or ``w``), ``{x}``, ``{y}`` and ``{i}`` (index in the entry), for example
      ``"{short}{x:g}_{y:g}"``; without a name, bwim's default names are used.
      Without ``x`` (logger channels weighed with influence lines, no FE model):
      ``name`` is a list of channel names, one sensor each, with an optional list ``y``
      of transverse positions (m) used to give the lateral position in metres.
  ``[logger]``
      a logger's text export: ``columns`` names every column in order (``"-"`` skips
      one, ``"time"`` is the time in s); [``delimiter`` = auto: ``","``, ``";"``,
      ``"tab"``, ``"whitespace"``], [``header`` = auto], [``sampling_rate``: Hz, when there
      is no time column], [``scale`` = 1: logger units to strain, one number or one per
      channel], [``decimal`` = "."], [``skip_lines`` = 0].  Record files are then read
      with :func:`bwim.io.read_logger` whatever their extension.
  ``[axle_detectors]``
      ``channels`` = [first, second] (logger channels, in the order traffic meets them),
      ``distance`` (m), [``position`` = 0: the first detector's x in the influence-line
      frame], [``max_spacing``: the largest axle spacing within one vehicle, m].
  ``[vehicle]``
      ``axle_loads`` (static, N) with ``axle_spacings`` (m): a calibration truck known by
      its weights only (a :class:`bwim.MovingForces`); or
      ``name`` = a named vehicle (:data:`bwim.vehicles.NAMED_VEHICLES`), or ``type`` =
      ``"moving_forces" | "sprung_mass" | "half_car" | "truck3d" |
      "tractor_semitrailer"`` with that class's parameters (``truck3d`` also takes
      ``axle_loads`` in place of ``body_mass``/``cg_offset``, see
      :meth:`bwim.Truck3D.from_axle_loads`).
  ``[road]``
      ``flat = true``; or ``roughness`` (G_d(n₀) in m³/cycle or an ISO class letter) with
      [``length``], [``start``] (default: covering the whole run), [``seed`` = 0],
      [``dx``], [``track_correlation``], [``waviness``], [``band``]; or ``profile`` = a CSV
      file (columns ``x`` and ``elevation``, or ``x``, ``right``, ``left``; a relative
      path is taken from the scenario's folder).  [``smoothing``]: tyre-patch length, m.
      No ``[road]`` section: a flat road.
  ``[run]``
      ``speed``, [``lane``], [``sampling_rate`` = 1000], [``approach`` = 100],
      [``tail`` = 0], [``method`` = "coupled"], [``delay`` = 0], [``n_modes``],
      [``max_frequency``], [``full_system``], [``static_correction``], [``noise`` = 0:
      gauge noise, a fraction of the peak strain], [``seed`` = 0: the noise seed].
  ``[identify]``, ``[calibrate]``
      options of :func:`bwim.identify_forces` and ``bwim.calibrate`` (see the classes).
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from bwim.calibration import Method, Refine
from bwim.calibration.meshdefect import MAX_LEVELS
from bwim.dynamics import DEFAULT_APPROACH, DEFAULT_SAMPLING_RATE, VBIMethod
from bwim.errors import InputError
from bwim.fe import EdgeSupport, Supports
from bwim.io.atomic import atomic_open
from bwim.io.toml_writer import to_toml
from bwim.mfi import ForceUnknowns, Order
from bwim.sensors import SensorKind
from bwim.vehicles import NAMED_VEHICLES
from bwim.vehicles.types import HalfCar, MovingForces, SprungMass, TractorSemitrailer, Truck3D

# The public names are listed once, in bwim.io.__all__ (which re-exports them).

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


# --- where a value sits, for messages ---------------------------------------------------
@dataclass(frozen=True)
class _At:
    src: str
    section: str
    key: str | None = None

    def __str__(self) -> str:
        return f"{self.src}: {self.section}" + (f" {self.key}" if self.key else "")

    def error(self, message: str) -> InputError:
        return InputError(f"{self}: {message}")

    def expected(self, what: str, value: Any) -> InputError:
        return self.error(f"expected {what}, got {_show(value)}")


def _show(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        text = repr(value)
        return text if len(text) <= 40 else "a list"
    return repr(value)


# --- value checkers: (value, at) -> converted value ---------------------------------------
Check = Callable[[Any, _At], Any]


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _number(v: Any, at: _At) -> float:
    if not _is_number(v):
        raise at.expected("a number", v)
    if not math.isfinite(v):
        raise at.expected("a finite number", v)
    return float(v)


def _at_least(low: float, *, strict: bool, high: float | None = None) -> Check:
    """A finite number > low (``strict``) or >= low, and <= high if given."""
    def check(v: Any, at: _At) -> float:
        x = _number(v, at)
        if (x <= low if strict else x < low) or (high is not None and x > high):
            rng = f"{'>' if strict else '>='} {low:g}" + (
                f" and <= {high:g}" if high is not None else "")
            raise at.error(f"must be {rng}, got {_show(v)}")
        return x
    return check


_positive = _at_least(0.0, strict=True)
_non_negative = _at_least(0.0, strict=False)


def _int_from(low: int) -> Check:
    def check(v: Any, at: _At) -> int:
        n = _integer(v, at)
        if n < low:
            raise at.error(f"must be an integer >= {low}, got {_show(v)}")
        return n
    return check


def _int_or_pair_from(low: int) -> Check:
    def check(v: Any, at: _At) -> int | tuple[int, int]:
        out = _int_or_pair(v, at)
        if any(n < low for n in (out if isinstance(out, tuple) else (out,))):
            raise at.error(f"must be integers >= {low}, got {_show(v)}")
        return out
    return check


def _jobs(v: Any, at: _At) -> int:
    n = _integer(v, at)
    if n < 1 and n != -1:
        raise at.error(f"must be a positive integer or -1 (all cores), got {_show(v)}")
    return n


def _levels_or_auto(v: Any, at: _At) -> int | str:
    """``calibrate``'s ``mesh_correction``: 0 to MAX_LEVELS bisections, or "auto"."""
    if v == "auto":
        return v
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_LEVELS:
        raise at.error(f"must be an integer from 0 to {MAX_LEVELS} or \"auto\", got {_show(v)}")
    return v


def _increasing_pair(v: Any, at: _At) -> tuple[float, float]:
    lo, hi = _pair(v, at)
    if not 0.0 < lo < hi:
        raise at.error(f"must be [low, high] with 0 < low < high, got {_show(v)}")
    return lo, hi


def _integer(v: Any, at: _At) -> int:
    if not isinstance(v, int) or isinstance(v, bool):
        raise at.expected("an integer", v)
    return v


def _boolean(v: Any, at: _At) -> bool:
    if not isinstance(v, bool):
        raise at.expected("true or false", v)
    return v


def _string(v: Any, at: _At) -> str:
    if not isinstance(v, str):
        raise at.expected("a string", v)
    return v


def _numbers(v: Any, at: _At) -> tuple[float, ...]:
    if not isinstance(v, list) or not v or not all(_is_number(e) for e in v):
        raise at.expected("a non-empty list of numbers", v)
    return tuple(float(e) for e in v)


def _number_or_numbers(v: Any, at: _At) -> float | tuple[float, ...]:
    if isinstance(v, list):
        return _numbers(v, at)
    if not _is_number(v):
        raise at.expected("a number or a list of numbers", v)
    return float(v)


def _choice(*options: str) -> Check:
    def check(v: Any, at: _At) -> str:
        v = _string(v, at)
        if v not in options:
            raise at.error(f"unknown value {v!r}; expected one of {', '.join(options)}")
        return v
    return check


def _choices(*options: str) -> Check:
    one = _choice(*options)

    def check(v: Any, at: _At) -> str | tuple[str, ...]:
        if isinstance(v, list):
            if not v:
                raise at.expected("a non-empty list", v)
            return tuple(one(e, at) for e in v)
        return one(v, at)
    return check


def _strings(v: Any, at: _At) -> tuple[str, ...]:
    if not isinstance(v, list) or not v or not all(isinstance(e, str) for e in v):
        raise at.expected("a non-empty list of strings", v)
    return tuple(v)


def _int_or_ints(v: Any, at: _At) -> int | tuple[int, ...]:
    if isinstance(v, list):
        if not v or not all(isinstance(e, int) and not isinstance(e, bool) for e in v):
            raise at.expected("an integer or a list of integers", v)
        return tuple(v)
    return _integer(v, at)


def _int_grid(v: Any, at: _At) -> tuple:
    def ints(row: Any) -> bool:
        return isinstance(row, list) and bool(row) and all(
            isinstance(e, int) and not isinstance(e, bool) for e in row)

    if ints(v):
        return tuple(v)
    if isinstance(v, list) and v and all(ints(r) for r in v):
        if len({len(r) for r in v}) != 1:
            raise at.error("the rows of the zone map have different lengths")
        return tuple(tuple(r) for r in v)
    raise at.expected("a list of integers or a list of rows of integers", v)


def _pair(v: Any, at: _At) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2 or not all(_is_number(e) for e in v):
        raise at.expected("two numbers [low, high]", v)
    return float(v[0]), float(v[1])


def _int_or_pair(v: Any, at: _At) -> int | tuple[int, int]:
    if isinstance(v, list):
        if len(v) != 2 or not all(isinstance(e, int) and not isinstance(e, bool) for e in v):
            raise at.expected("an integer or two integers", v)
        return v[0], v[1]
    return _integer(v, at)


def _lam(v: Any, at: _At) -> float | str:
    if isinstance(v, str):
        return _choice("lcurve", "gcv")(v, at)
    if not _is_number(v):
        raise at.expected('"lcurve", "gcv" or a number', v)
    return float(v)


def _number_or_string(v: Any, at: _At) -> float | str:
    if isinstance(v, str):
        return v
    if not _is_number(v):
        raise at.expected("a number or a string", v)
    return float(v)


_EDGES = tuple(f.name for f in fields(Supports))


def _supports(v: Any, at: _At) -> str | Mapping[str, str]:
    if isinstance(v, str):
        return v
    if not isinstance(v, dict):
        raise at.expected("a preset name or a table of edges", v)
    sub = _At(at.src, f"[{at.section.strip('[]')}.supports]")
    for edge, value in v.items():
        if edge not in _EDGES:
            raise InputError(f"{at.src}: unknown key {edge!r} in {sub.section}; "
                             f"allowed keys: {', '.join(_EDGES)}")
        _choice(*EdgeSupport)(value, _At(at.src, sub.section, edge))
    return MappingProxyType(dict(v))


def _subtable(cls: type, name: str) -> Check:
    def check(v: Any, at: _At) -> Any:
        _, entry, n = at.section.rpartition(" entry ")
        owner = f" of entry {n}" if entry else ""
        return _parse(cls, v, _At(at.src, f"[{name}]{owner}"))
    return check


def _tables(cls: type, name: str) -> Check:
    def check(v: Any, at: _At) -> tuple:
        if isinstance(v, dict):
            v = [v]
        if not isinstance(v, list) or not all(isinstance(e, dict) for e in v):
            raise InputError(f"{at.src}: {name} must be an array of tables [[{name}]], "
                             f"got {_show(v)}")
        return tuple(_parse(cls, e, _At(at.src, f"[[{name}]] entry {i + 1}"))
                     for i, e in enumerate(v))
    return check


# --- fields -------------------------------------------------------------------------------
def _req(check: Check, kinds: tuple[str, ...] | None = None) -> Any:
    """A required key (only for ``kinds`` of bridge when given)."""
    meta = {"check": check, "kinds": kinds, "required": True}
    return field(metadata=meta) if kinds is None else field(default=None, metadata=meta)


def _opt(check: Check, default: Any = None, kinds: tuple[str, ...] | None = None) -> Any:
    """An optional key with its default."""
    return field(default=default, metadata={"check": check, "kinds": kinds, "required": False})


def _keys(cls: type, kind: str | None) -> list[str]:
    return [f.name for f in fields(cls) if "check" in f.metadata
            and (kind is None or f.metadata["kinds"] is None or kind in f.metadata["kinds"])]


def _parse(cls: type, table: Any, at: _At, *, kind: str | None = None,
           extra: Mapping[str, Any] | None = None) -> Any:
    """Check a table against the fields of ``cls`` and build it."""
    if not isinstance(table, dict):
        raise InputError(f"{at.src}: {at.section} must be a table, got {_show(table)}")
    allowed = _keys(cls, kind)
    for key in table:
        if key not in allowed:
            note = f" for kind = {kind!r}" if kind is not None and key in _keys(cls, None) \
                else ""
            raise InputError(f"{at.src}: unknown key {key!r} in {at.section}{note}; "
                             f"allowed keys: {', '.join(allowed)}")
    spec = {f.name: f for f in fields(cls)}
    kwargs = {k: spec[k].metadata["check"](v, _At(at.src, at.section, k))
              for k, v in table.items()}
    for name in allowed:
        if name not in kwargs and spec[name].metadata["required"]:
            raise InputError(f"{at.src}: {at.section} is missing the key {name!r}")
    return cls(**kwargs, **(extra or {}))


# --- section specs -----------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class SectionSpec:
    """A composite girder section (:func:`bwim.fe.composite_section`); m, m², m⁴."""

    girder_area: float = _req(_number)
    girder_inertia: float = _req(_number)
    girder_depth: float = _req(_number)
    slab_width: float = _req(_number)
    girder_centroid_height: float | None = _opt(_number)
    slab_thickness: float | None = _opt(_number)
    """Default: the deck's thickness."""
    modular_ratio: float | None = _opt(_number)
    """``E_slab / E_girder``; default: the deck's (single) E over the girder's E."""
    exclude_slab_bending: bool = _opt(_boolean, True)


_SECTION_TABLE = _subtable(SectionSpec, "bridge.girders.section")


@dataclass(frozen=True, kw_only=True)
class GirderSpec:
    """A girder (:class:`bwim.Girder`): give ``I`` and ``z_bottom`` or a ``section``."""

    y: float = _req(_number)
    E: float = _req(_number)
    mu: float = _req(_number)
    I: float | None = _opt(_number)
    z_bottom: float | None = _opt(_number)
    J: float = _opt(_number, 0.0)
    poisson: float = _opt(_number, 0.2)
    section: SectionSpec | None = _opt(_SECTION_TABLE)  # noqa: RUF009 (a field)


_GIRDER_TABLES = _tables(GirderSpec, "bridge.girders")


@dataclass(frozen=True, kw_only=True)
class BridgeSpec:
    """The ``[bridge]`` section (arguments of :meth:`bwim.Bridge.plate` / ``.beam``).

    Lengths in m, moduli in Pa, ``mu`` in kg/m² (plate) or kg/m (beam), ``I`` in m⁴.
    Per-zone values are tuples.
    """

    kind: str = _req(_choice("plate", "beam"))
    length: float = _req(_number)
    width: float | None = _req(_number, _PLATE)
    thickness: float | None = _req(_number, _PLATE)
    nx: int | None = _opt(_integer, None, _PLATE)
    ny: int | None = _opt(_integer, None, _PLATE)
    n_elements: int | None = _opt(_integer, None, _BEAM)
    x_lines: tuple[float, ...] | None = _opt(_numbers)
    y_lines: tuple[float, ...] | None = _opt(_numbers, None, _PLATE)
    x_through: tuple[float, ...] | None = _opt(_numbers)
    y_through: tuple[float, ...] | None = _opt(_numbers, None, _PLATE)
    E: float | tuple[float, ...] | None = _opt(_number_or_numbers)
    E_x: float | tuple[float, ...] | None = _opt(_number_or_numbers, None, _PLATE)
    E_y: float | tuple[float, ...] | None = _opt(_number_or_numbers, None, _PLATE)
    mu: float | tuple[float, ...] = _req(_number_or_numbers)
    I: float | None = _req(_number, _BEAM)
    z_bottom: float | None = _opt(_number, None, _BEAM)
    poisson: float = _opt(_number, 0.2, _PLATE)
    damping_ratio: float = _opt(_number, 0.03)
    supports: str | Mapping[str, str] | None = _opt(_supports)
    zones: int | tuple[int, ...] | None = _opt(_int_or_ints)
    zone_map: tuple | None = _opt(_int_grid)
    n_zones: int | None = _opt(_integer)
    girders: tuple[GirderSpec, ...] = _opt(_GIRDER_TABLES, (), _PLATE)




def _name_or_names(v: Any, at: _At) -> str | tuple[str, ...]:
    if isinstance(v, list):
        names = _strings(v, at)
        if any(not n.strip() for n in names):
            raise at.error("sensor names must not be empty")
        return names
    return _string(v, at)


#: Kinds of a ``[[sensors]]`` entry (axle detectors are declared in ``[axle_detectors]``).
_SENSOR_KINDS = tuple(k for k in SensorKind if k is not SensorKind.AXLE_DETECTOR)


@dataclass(frozen=True, kw_only=True)
class SensorSpec:
    """One ``[[sensors]]`` entry: a sensor, or a grid when ``x``, ``y`` or ``kind`` is a
    tuple (expanded kind by kind, then x, then y).  Positions in m; ``x`` (and ``y``) may
    be left out when no FE model is used (logger channels weighed with influence lines),
    and ``name`` may then be a list: one sensor per name."""

    x: float | tuple[float, ...] | None = _opt(_number_or_numbers)
    y: float | tuple[float, ...] | None = _opt(_number_or_numbers)
    kind: str | tuple[str, ...] = _opt(_choices(*_SENSOR_KINDS), SensorKind.STRAIN_X.value)
    name: str | tuple[str, ...] = _opt(_name_or_names, "")


_DELIMITERS = (",", ";", "tab", "whitespace", "\t", " ")


@dataclass(frozen=True, kw_only=True)
class LoggerSpec:
    """The ``[logger]`` section: how a logger's text export is laid out
    (:class:`bwim.io.LoggerFormat`).  ``columns`` names every column in order (``"-"``
    skips one; ``"time"`` is the time column, in s); the delimiter and a header row are
    detected unless given; ``sampling_rate`` (Hz) when there is no time column; ``scale``
    turns logger units into strain (one number or one per channel in column order)."""

    columns: tuple[str, ...] = _req(_strings)
    delimiter: str | None = _opt(_choice(*_DELIMITERS))
    header: bool | None = _opt(_boolean)
    sampling_rate: float | None = _opt(_number)
    scale: float | tuple[float, ...] = _opt(_number_or_numbers, 1.0)
    decimal: str = _opt(_choice(".", ","), ".")
    skip_lines: int = _opt(_integer, 0)


@dataclass(frozen=True, kw_only=True)
class AxleDetectorSpec:
    """The ``[axle_detectors]`` section: two logger channels that respond to each axle,
    named in the order traffic meets them, ``distance`` m apart; ``position`` is the first
    detector's x in the influence-line frame (default 0: lines are measured from it)."""

    channels: tuple[str, ...] = _req(_strings)
    distance: float = _req(_number)
    position: float = _opt(_number, 0.0)
    max_spacing: float | None = _opt(_number)


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

    flat: bool = _opt(_boolean, False)
    roughness: float | str | None = _opt(_number_or_string)
    """G_d(n₀), m³/cycle, or an ISO 8608 class letter."""
    length: float | None = _opt(_positive)
    start: float | None = _opt(_number)
    seed: int = _opt(_int_from(0), 0)
    dx: float | None = _opt(_positive)
    track_correlation: float | None = _opt(_number)
    waviness: float | None = _opt(_number)
    band: tuple[float, float] | None = _opt(_pair)
    profile: str | None = _opt(_string)
    """CSV file; relative paths are taken from the scenario's folder."""
    smoothing: float | None = _opt(_positive)
    """Tyre-patch moving-average length, m."""


@dataclass(frozen=True, kw_only=True)
class RunSpec:
    """The ``[run]`` section: a simulated crossing (see :func:`bwim.simulate`)."""

    speed: float = _req(_positive)
    lane: float | None = _opt(_number)
    sampling_rate: float = _opt(_positive, DEFAULT_SAMPLING_RATE)
    approach: float = _opt(_non_negative, DEFAULT_APPROACH)
    tail: float = _opt(_non_negative, 0.0)
    method: str = _opt(_choice(*VBIMethod), VBIMethod.COUPLED.value)
    delay: float = _opt(_non_negative, 0.0)
    n_modes: int | None = _opt(_int_from(1))
    max_frequency: float | None = _opt(_positive)
    full_system: bool = _opt(_boolean, False)
    static_correction: bool = _opt(_boolean, True)
    noise: float = _opt(_at_least(0.0, strict=False, high=1.0), 0.0)
    """Gauge noise: one σ on every channel, a fraction of the record's peak strain
    (:meth:`bwim.Record.with_noise`; the paper's per-channel model is not a scenario
    option)."""
    seed: int = _opt(_int_from(0), 0)
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

    n_modes: int | None = _opt(_int_from(1))
    lam: float | str | None = _opt(_lam)
    order: str | None = _opt(_choice(*Order))
    unknowns: str | None = _opt(_choice(*ForceUnknowns))
    central: float | None = _opt(_number)
    static_correction: bool | None = _opt(_boolean)
    lam_range: tuple[float, float] | None = _opt(_increasing_pair)
    n_lam: int | None = _opt(_int_from(2))

    def kwargs(self) -> dict[str, Any]:
        """The options that are set, as keyword arguments."""
        return _set_options(self)


@dataclass(frozen=True, kw_only=True)
class CalibrateSpec:
    """The ``[calibrate]`` section: options of ``bwim.calibrate`` (unset: its default)."""

    unknowns: tuple[str, ...] | None = _opt(_strings)
    seed: int | None = _opt(_integer)
    method: str | None = _opt(_choice(*Method))
    refine: str | None = _opt(_choice(*Refine))
    population: int | tuple[int, int] | None = _opt(_int_or_pair_from(2))
    elite_fraction: float | None = _opt(_number)
    convergences: int | None = _opt(_int_from(0))
    max_evals: int | tuple[int, int] | None = _opt(_int_or_pair_from(1))
    bounds: tuple[float, float] | None = _opt(_pair)
    substructure: bool | None = _opt(_boolean)
    weights: str | None = _opt(_choice("none", "noise", "peak", "model"))
    mesh_check: float | None = _opt(_at_least(0.0, strict=True, high=1.0))
    mesh_correction: int | str | None = _opt(_levels_or_auto)
    n_modes: int | None = _opt(_int_from(1))
    n_jobs: int | None = _opt(_jobs)

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
    axle_detectors: AxleDetectorSpec | None = None
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


# --- parsing -------------------------------------------------------------------------------
_SECTIONS = ("title", "bridge", "sensors", "logger", "axle_detectors", "vehicle", "road", "run",
             "identify", "calibrate")


def _parse_bridge(table: Any, src: str) -> BridgeSpec:
    at = _At(src, "[bridge]")
    if not isinstance(table, dict):
        raise InputError(f"{src}: [bridge] must be a table, got {_show(table)}")
    if "kind" not in table:
        raise InputError(f"{src}: [bridge] is missing the key 'kind' (\"plate\" or \"beam\")")
    kind = _choice("plate", "beam")(table["kind"], _At(src, "[bridge]", "kind"))
    spec = _parse(BridgeSpec, table, at, kind=kind)
    if spec.zones is not None and spec.zone_map is not None:
        raise at.error("give zones or zone_map, not both")
    if spec.n_zones is not None and spec.zone_map is None:
        raise at.error("n_zones needs a zone_map")
    if kind == "plate" and isinstance(spec.zones, int):
        raise at.error(f"zones for a plate must be [nzx, nzy], got {spec.zones}")
    if kind == "plate" and isinstance(spec.zones, tuple) and len(spec.zones) != 2:
        raise at.error(f"zones for a plate must be [nzx, nzy], got {list(spec.zones)}")
    if kind == "beam" and isinstance(spec.zones, tuple):
        raise at.error(f"zones for a beam must be an integer, got {list(spec.zones)}")
    if kind == "beam" and spec.E is None:
        raise InputError(f"{src}: [bridge] is missing the key 'E'")
    return spec


def _parse_vehicle(table: Any, src: str) -> VehicleSpec:
    at = _At(src, "[vehicle]")
    if not isinstance(table, dict):
        raise InputError(f"{src}: [vehicle] must be a table, got {_show(table)}")
    if "name" not in table and "type" not in table and "axle_loads" in table:
        # a calibration truck known by its static axle loads and spacings only
        table = {"type": "moving_forces", **table}
    if ("name" in table) == ("type" in table):
        raise at.error("give either name (a named vehicle), type (with its parameters), or "
                       "axle_loads (static, N) with axle_spacings")
    if "name" in table:
        name = _choice(*NAMED_VEHICLES)(table["name"], _At(src, "[vehicle]", "name"))
        for key in table:
            if key != "name":
                raise InputError(f"{src}: unknown key {key!r} in [vehicle] with a name; "
                                 "allowed keys: name")
        return VehicleSpec(name=name)
    vtype = _choice(*VEHICLE_TYPES)(table["type"], _At(src, "[vehicle]", "type"))
    cls = VEHICLE_TYPES[vtype]
    params = [f for f in fields(cls) if f.init]
    allowed = [f.name for f in params]
    required = [f.name for f in params if f.default is MISSING and f.default_factory is MISSING]
    if cls is Truck3D and "axle_loads" in table:
        allowed = ["axle_loads"] + [n for n in allowed if n not in ("body_mass", "cg_offset")]
        required = ["axle_loads"] + [n for n in required if n not in ("body_mass", "cg_offset")]
    out: dict[str, Any] = {}
    for key, value in table.items():
        if key == "type":
            continue
        if key not in allowed:
            raise InputError(f"{src}: unknown key {key!r} in [vehicle] for type = {vtype!r}; "
                             f"allowed keys: type, {', '.join(allowed)}")
        where = _At(src, "[vehicle]", key)
        out[key] = (_integer(value, where) if key == "n_tractor_axles"
                    else _number_or_numbers(value, where))
    for key in required:
        if key not in out:
            raise InputError(f"{src}: [vehicle] type = {vtype!r} is missing the key {key!r}")
    return VehicleSpec(type=vtype, params=out)


def _parse_road(table: Any, src: str) -> RoadSpec:
    at = _At(src, "[road]")
    spec = _parse(RoadSpec, table, at)
    iso = ("roughness", "length", "start", "dx", "track_correlation", "waviness", "band")
    given = [k for k in table if k != "smoothing"]
    if spec.flat:
        if len(given) > 1:
            other = next(k for k in given if k != "flat")
            raise at.error(f"a flat road takes no other keys, got {other!r}")
        return spec
    if spec.profile is not None:
        clash = [k for k in table if k in (*iso, "seed")]
        if clash:
            raise at.error(f"a CSV profile takes no ISO 8608 keys, got {clash[0]!r}")
        return spec
    if spec.roughness is None:
        raise at.error("needs roughness (ISO 8608), profile (a CSV file) or flat = true")
    return spec


def _parse_logger(table: Any, src: str) -> LoggerSpec:
    at = _At(src, "[logger]")
    spec = _parse(LoggerSpec, table, at)
    names = [c for c in spec.columns if c != "-"]
    if len(set(names)) != len(names):
        dup = next(c for c in names if names.count(c) > 1)
        raise at.error(f"columns: the name {dup!r} appears twice")
    if "time" not in names and spec.sampling_rate is None:
        raise at.error("needs a 'time' column or sampling_rate")
    if spec.sampling_rate is not None and not spec.sampling_rate > 0:
        raise at.error(f"sampling_rate must be positive, got {spec.sampling_rate:g}")
    return spec


def _parse_detectors(table: Any, src: str) -> AxleDetectorSpec:
    at = _At(src, "[axle_detectors]")
    spec = _parse(AxleDetectorSpec, table, at)
    if len(spec.channels) != 2 or spec.channels[0] == spec.channels[1]:
        raise at.error("channels must name two different logger channels, in the order "
                       f"traffic meets them, got {list(spec.channels)}")
    if not spec.distance > 0:
        raise at.error(f"distance must be positive, got {spec.distance:g}")
    if spec.max_spacing is not None and not spec.max_spacing > 0:
        raise at.error(f"max_spacing must be positive, got {spec.max_spacing:g}")
    return spec


def scenario_from_dict(
    doc: Mapping[str, Any],
    *,
    source: str | os.PathLike = "<scenario>",
    folder: str | os.PathLike | None = None,
) -> Scenario:
    """A :class:`Scenario` from a parsed TOML document.

    Parameters
    ----------
    doc : mapping
        The document as :func:`tomllib.loads` returns it.
    source : str or path
        Names the document in messages.
    folder : str or path, optional
        Folder for relative paths in the scenario (default: the current folder).

    Raises
    ------
    InputError
        Unknown, missing or mistyped keys (one line naming file, section and key).
    """
    src = str(source)
    if not isinstance(doc, Mapping):
        raise InputError(f"{src}: a scenario is a table of sections")
    for key in doc:
        if key not in _SECTIONS:
            raise InputError(f"{src}: unknown key {key!r} at the top level; allowed keys: "
                             f"{', '.join(_SECTIONS)}")
    top = _At(src, "top level")
    kw: dict[str, Any] = {}
    if "bridge" in doc:
        kw["bridge"] = _parse_bridge(doc["bridge"], src)
    if "title" in doc:
        kw["title"] = _string(doc["title"], _At(src, "top level", "title"))
    if "sensors" in doc:
        kw["sensors"] = _tables(SensorSpec, "sensors")(doc["sensors"], top)
    if "vehicle" in doc:
        kw["vehicle"] = _parse_vehicle(doc["vehicle"], src)
    if "road" in doc:
        kw["road"] = _parse_road(doc["road"], src)
    if "logger" in doc:
        kw["logger"] = _parse_logger(doc["logger"], src)
    if "axle_detectors" in doc:
        kw["axle_detectors"] = _parse_detectors(doc["axle_detectors"], src)
    for name, cls in (("run", RunSpec), ("identify", IdentifySpec),
                      ("calibrate", CalibrateSpec)):
        if name in doc:
            kw[name] = _parse(cls, doc[name], _At(src, f"[{name}]"))
    return Scenario(**kw, source=src, folder=None if folder is None else Path(folder))


_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")
_TOML_END = re.compile(r"\s*\(at end of document\)\s*$")


def read_toml(path: str | os.PathLike) -> dict[str, Any]:
    """Parse a TOML file; errors name the file, line and column.

    Raises
    ------
    InputError
        ``"<file>: line L, column C: <reason>"`` for malformed TOML; a missing or
        unreadable file.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {(exc.strerror or str(exc)).lower()}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc.msg if hasattr(exc, "msg") and hasattr(exc, "lineno") else exc)
        line, col = getattr(exc, "lineno", None), getattr(exc, "colno", None)
        m = _TOML_POSITION.search(message)
        if m:
            line, col = int(m.group(1)), int(m.group(2))
            message = message[:m.start()]
        elif _TOML_END.search(message):
            raise InputError(f"{p}: end of file: {_TOML_END.sub('', message)}") from None
        if line is not None:
            raise InputError(f"{p}: line {line}, column {col}: {message}") from None
        raise InputError(f"{p}: {message}") from None


def load_scenario(path: str | os.PathLike) -> Scenario:
    """Read a scenario TOML file (see the module docstring for the schema).

    Parameters
    ----------
    path : str or path
        The file; relative paths inside it are taken from its folder.

    Returns
    -------
    Scenario
    """
    p = Path(path)
    return scenario_from_dict(read_toml(p), source=p, folder=p.parent)


# --- writing -----------------------------------------------------------------------------
def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _spec_dict(value)
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _spec_dict(spec: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in fields(spec):
        if "check" not in f.metadata:
            continue
        value = getattr(spec, f.name)
        default = f.default if f.default is not MISSING else (
            f.default_factory() if f.default_factory is not MISSING else MISSING)
        if value is None or (default is not MISSING and value == default
                             and type(value) is type(default)):
            continue
        out[f.name] = _plain(value)
    return out


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The TOML document of a scenario (values at their defaults are left out)."""
    doc: dict[str, Any] = {}
    if scenario.title:
        doc["title"] = scenario.title
    if scenario.bridge is not None:
        bridge = _spec_dict(scenario.bridge)
        doc["bridge"] = {"kind": bridge.pop("kind"), **bridge}
    if scenario.sensors:
        doc["sensors"] = [_spec_dict(s) for s in scenario.sensors]
    for name in ("logger", "axle_detectors"):
        spec = getattr(scenario, name)
        if spec is not None:
            doc[name] = _spec_dict(spec)
    if scenario.vehicle is not None:
        v = scenario.vehicle
        doc["vehicle"] = {"name": v.name} if v.name is not None else {
            "type": v.type, **_plain(v.params)}
    for name in ("road", "run", "identify", "calibrate"):
        spec = getattr(scenario, name)
        if spec is not None:
            doc[name] = _spec_dict(spec)
    return doc


def dump_scenario(scenario: Scenario, path: str | os.PathLike, *, header: str = "") -> None:
    """Write a scenario as TOML (atomically; see :mod:`bwim.io.atomic`).

    Parameters
    ----------
    scenario : Scenario
    path : str or path
    header : str
        Comment lines written at the top of the file.

    Notes
    -----
    Paths inside the scenario (a road ``profile``) are written as given: a relative one
    stays relative to the folder of the file it is written to.
    """
    text = to_toml(scenario_to_dict(scenario), header=header)
    with atomic_open(path) as f:
        f.write(text)
