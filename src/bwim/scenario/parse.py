"""Reading and writing scenario files: TOML in, :class:`~bwim.scenario.Scenario` out.

Contract
--------
* :func:`load_scenario` reads a TOML file into a :class:`~bwim.scenario.Scenario`;
  :func:`scenario_from_dict` does the same for an already parsed mapping and
  :func:`dump_scenario` writes a scenario back (``load → dump → load`` gives an equal
  scenario; comments are not kept).
* Validation is strict and every message is one line that starts with the file name
  (the forms are listed in :mod:`bwim.scenario`).
"""

from __future__ import annotations

import dataclasses
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import MISSING, fields
from pathlib import Path
from typing import Any

from bwim.atomic import atomic_open
from bwim.errors import InputError
from bwim.io import open_regular
from bwim.io.toml_writer import to_toml
from bwim.scenario.checks import (
    At,
    choice,
    integer,
    number_or_numbers,
    parse_table,
    show,
    string,
    tables,
)
from bwim.scenario.specs import (
    VEHICLE_TYPES,
    AxleDetectorSpec,
    BridgeSpec,
    CalibrateSpec,
    DriftSpec,
    IdentifySpec,
    LaneSpec,
    LinesSpec,
    LoggerSpec,
    RoadSpec,
    RunSpec,
    Scenario,
    SensorSpec,
    TriggerSpec,
    VehicleSpec,
)
from bwim.vehicles import NAMED_VEHICLES
from bwim.vehicles.types import Truck3D

__all__ = ["dump_scenario", "load_scenario", "read_toml", "scenario_from_dict",
           "scenario_to_dict"]

_SECTIONS = ("title", "bridge", "sensors", "logger", "axle_detectors", "lanes", "drift",
             "lines", "trigger", "vehicle", "road", "run",
             "identify", "calibrate")


def _parse_bridge(table: Any, src: str) -> BridgeSpec:
    at = At(src, "[bridge]")
    if not isinstance(table, dict):
        raise InputError(f"{src}: [bridge] must be a table, got {show(table)}")
    if "kind" not in table:
        raise InputError(f"{src}: [bridge] is missing the key 'kind' (\"plate\" or \"beam\")")
    kind = choice("plate", "beam")(table["kind"], At(src, "[bridge]", "kind"))
    spec = parse_table(BridgeSpec, table, at, kind=kind)
    if spec.zones is not None and spec.zone_map is not None:
        raise at.error("give zones or zone_map, not both")
    if spec.joints is not None and (spec.zones is not None or spec.zone_map is not None):
        raise at.error("joints make the zones: give joints, or zones / zone_map, not both")
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
    at = At(src, "[vehicle]")
    if not isinstance(table, dict):
        raise InputError(f"{src}: [vehicle] must be a table, got {show(table)}")
    if "name" not in table and "type" not in table and "axle_loads" in table:
        # a calibration truck known by its static axle loads and spacings only
        table = {"type": "moving_forces", **table}
    if ("name" in table) == ("type" in table):
        raise at.error("give either name (a named vehicle), type (with its parameters), or "
                       "axle_loads (static, N) with axle_spacings")
    if "name" in table:
        name = choice(*NAMED_VEHICLES)(table["name"], At(src, "[vehicle]", "name"))
        for key in table:
            if key != "name":
                raise InputError(f"{src}: unknown key {key!r} in [vehicle] with a name; "
                                 "allowed keys: name")
        return VehicleSpec(name=name)
    vtype = choice(*VEHICLE_TYPES)(table["type"], At(src, "[vehicle]", "type"))
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
        where = At(src, "[vehicle]", key)
        out[key] = (integer(value, where) if key == "n_tractor_axles"
                    else number_or_numbers(value, where))
    for key in required:
        if key not in out:
            raise InputError(f"{src}: [vehicle] type = {vtype!r} is missing the key {key!r}")
    return VehicleSpec(type=vtype, params=out)


def _parse_road(table: Any, src: str) -> RoadSpec:
    at = At(src, "[road]")
    spec = parse_table(RoadSpec, table, at)
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
    at = At(src, "[logger]")
    spec = parse_table(LoggerSpec, table, at)
    names = [c for c in spec.columns if c != "-"]
    if len(set(names)) != len(names):
        dup = next(c for c in names if names.count(c) > 1)
        raise at.error(f"columns: the name {dup!r} appears twice")
    if "time" not in names and spec.sampling_rate is None:
        raise at.error("needs a 'time' column or sampling_rate")
    if spec.sampling_rate is not None and not spec.sampling_rate > 0:
        raise at.error(f"sampling_rate must be positive, got {spec.sampling_rate:g}")
    return spec


def _parse_detectors(value: Any, src: str) -> tuple[AxleDetectorSpec, ...]:
    """``[axle_detectors]`` (one lane) or ``[[axle_detectors]]`` (one table per lane)."""
    single = isinstance(value, dict)
    specs = tables(AxleDetectorSpec, "axle_detectors")(value, At(src, "top level"))
    seen_channels: dict[str, int] = {}
    seen_lanes: dict[int, int] = {}
    for k, spec in enumerate(specs, start=1):
        at = At(src, "[axle_detectors]" if single else f"[[axle_detectors]] entry {k}")
        if len(spec.channels) != 2 or spec.channels[0] == spec.channels[1]:
            raise at.error("channels must name two different logger channels, in the order "
                           f"traffic meets them, got {list(spec.channels)}")
        if not spec.distance > 0:
            raise at.error(f"distance must be positive, got {spec.distance:g}")
        if spec.max_spacing is not None and not spec.max_spacing > 0:
            raise at.error(f"max_spacing must be positive, got {spec.max_spacing:g}")
        if spec.max_length is not None and not spec.max_length > 0:
            raise at.error(f"max_length must be positive, got {spec.max_length:g}")
        for ch in spec.channels:
            if ch in seen_channels:
                raise at.error(f"channel {ch!r} is already a detector of entry "
                               f"{seen_channels[ch]}")
            seen_channels[ch] = k
        lane = spec.lane if spec.lane is not None else k
        if lane in seen_lanes:
            raise at.error(f"lane {lane} already has detectors (entry {seen_lanes[lane]})")
        seen_lanes[lane] = k
    if sum(1 for sp in specs if sp.calibration) > 1:
        raise InputError(f"{src}: [[axle_detectors]]: calibration = true in more than one "
                         "entry; the calibration truck drives one lane")
    return specs


def _parse_lanes(value: Any, src: str) -> tuple[LaneSpec, ...]:
    specs = tables(LaneSpec, "lanes")(value, At(src, "top level"))
    seen: set[int] = set()
    for k, spec in enumerate(specs, start=1):
        if spec.number in seen:
            raise InputError(f"{src}: [[lanes]] entry {k}: lane {spec.number} appears twice")
        seen.add(spec.number)
    return specs


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
    top = At(src, "top level")
    kw: dict[str, Any] = {}
    if "bridge" in doc:
        kw["bridge"] = _parse_bridge(doc["bridge"], src)
    if "title" in doc:
        kw["title"] = string(doc["title"], At(src, "top level", "title"))
    if "sensors" in doc:
        kw["sensors"] = tables(SensorSpec, "sensors")(doc["sensors"], top)
    if "vehicle" in doc:
        kw["vehicle"] = _parse_vehicle(doc["vehicle"], src)
    if "road" in doc:
        kw["road"] = _parse_road(doc["road"], src)
    if "logger" in doc:
        kw["logger"] = _parse_logger(doc["logger"], src)
    if "axle_detectors" in doc:
        kw["axle_detectors"] = _parse_detectors(doc["axle_detectors"], src)
    if "lanes" in doc:
        kw["lanes"] = _parse_lanes(doc["lanes"], src)
    for name, cls in (("run", RunSpec), ("identify", IdentifySpec),
                      ("calibrate", CalibrateSpec), ("drift", DriftSpec),
                      ("lines", LinesSpec), ("trigger", TriggerSpec)):
        if name in doc:
            kw[name] = parse_table(cls, doc[name], At(src, f"[{name}]"))
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
    with open_regular(p) as f:  # a folder, a FIFO or a device is refused, not waited on
        try:
            data = f.read()
        except OSError as exc:
            raise InputError(f"{p}: cannot read: {(exc.strerror or str(exc)).lower()}"
                             ) from None
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
    if scenario.logger is not None:
        doc["logger"] = _spec_dict(scenario.logger)
        clock = scenario.logger.clock
        if clock is not None:
            doc["logger"]["clock"] = ("none" if clock.none else clock.pattern
                                      if clock.pattern and not (clock.column or clock.date)
                                      else {k: getattr(clock, k) for k in
                                            ("pattern", "column", "date", "format")
                                            if getattr(clock, k) is not None} or "name")
    for name in ("axle_detectors", "lanes"):
        if getattr(scenario, name):
            doc[name] = [_spec_dict(sp) for sp in getattr(scenario, name)]
    if scenario.vehicle is not None:
        v = scenario.vehicle
        doc["vehicle"] = {"name": v.name} if v.name is not None else {
            "type": v.type, **_plain(v.params)}
    for name in ("road", "run", "identify", "calibrate", "drift", "lines", "trigger"):
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
