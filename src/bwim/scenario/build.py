"""Builders: bwim objects from a :class:`~bwim.scenario.Scenario`.

Contract
--------
* :func:`build_bridge`, :func:`build_sensors`, :func:`build_vehicle`, :func:`build_road`
  and :func:`build_passage` turn the scenario's section specs into a
  :class:`~bwim.Bridge`, a list of :class:`~bwim.Sensor`, a vehicle, a
  :class:`~bwim.RoadProfile` and a :class:`~bwim.Passage`;
  :func:`simulate_scenario` runs the scenario's crossing (with its noise, if any).
* The bridge is built by :meth:`bwim.Bridge.plate` / :meth:`bwim.Bridge.beam` with the
  same arguments a Python user would pass, so a scenario that states the paper's slab gives
  a bridge equal to :func:`bwim.paper.slab_bridge` (same parameters, same matrices).
* Errors the library raises keep their message, prefixed by the file and the section:
  ``"scenario.toml: [bridge]: E_x must be positive, got -3.5e+10"``.  A sensor off the
  deck, a sensor name used twice and a bad name template are reported here with the
  ``[[sensors]]`` entry they come from.
* :func:`load_record` reads a record by its extension: a logger's CSV with the
  scenario's sensors (and passage, when the scenario has ``[run]`` and ``[vehicle]``), or
  bwim's HDF5; :func:`record_reader` gives a reader of many files of one scenario (its
  sensors and logger format built once), the same records.
* A missing section that a builder needs is an :class:`~bwim.errors.InputError`
  (``"scenario.toml: no [vehicle] section"``); a missing ``[road]`` means a flat road.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from bwim.dynamics import DEFAULT_APPROACH, simulate
from bwim.errors import InputError, require_positive
from bwim.fe.bridge import Bridge
from bwim.fe.girder import Girder, composite_section
from bwim.fe.joints import with_joints
from bwim.fe.mesh import grid_lines
from bwim.io._csv import read_numeric_csv
from bwim.io.clock import ClockSpec
from bwim.io.logger import LoggerFormat, read_logger
from bwim.io.records import read_csv_record, read_record
from bwim.records import Passage, Record, SimulationSettings
from bwim.road import RoadProfile
from bwim.scenario.specs import VEHICLE_TYPES, BridgeSpec, GirderSpec, Scenario
from bwim.sensors import Sensor, SensorKind
from bwim.site import DetectorLane, DriftSetup, Lane, SiteSetup
from bwim.stream.settings import TriggerSettings
from bwim.vehicles import Vehicle, named
from bwim.vehicles.types import Truck3D

# The public names are listed once, in bwim.scenario.__all__ (which re-exports them).


@contextlib.contextmanager
def _context(prefix: str) -> Iterator[None]:
    """Prefix the message of any InputError raised inside the block."""
    try:
        yield
    except InputError as exc:
        raise InputError(f"{prefix}: {exc}") from None


def _values(v):
    return list(v) if isinstance(v, tuple) else v


def _lines(lines, through, size, n, axis: str, n_name: str):
    if through is None:
        return None if lines is None else list(lines)
    if lines is not None:
        raise InputError(f"give {axis}_lines or {axis}_through, not both")
    if n is None:
        raise InputError(f"{axis}_through needs {n_name}")
    return grid_lines(size, n, through=list(through), name=n_name)


def _girder(g: GirderSpec, spec: BridgeSpec, src: str, k: int) -> Girder:
    with _context(f"{src}: [[bridge.girders]] entry {k + 1}"):
        if g.section is None:
            if g.I is None or g.z_bottom is None:
                raise InputError("give I and z_bottom, or a [bridge.girders.section] table")
            return Girder(y=g.y, I=g.I, z_bottom=g.z_bottom, E=g.E, mu=g.mu, J=g.J,
                          poisson=g.poisson)
        if g.I is not None or g.z_bottom is not None:
            raise InputError("give I and z_bottom or a section table, not both")
        s = g.section
        ratio = s.modular_ratio
        if ratio is None:
            slab_e = spec.E if spec.E is not None else (
                spec.E_x if spec.E_x == spec.E_y else None)
            if not isinstance(slab_e, float):
                raise InputError("the section needs modular_ratio: the deck has no single "
                                 "modulus E")
            ratio = slab_e / require_positive("Girder.E", g.E)
        sec = composite_section(
            girder_area=s.girder_area, girder_inertia=s.girder_inertia,
            girder_depth=s.girder_depth, girder_centroid_height=s.girder_centroid_height,
            slab_width=s.slab_width,
            slab_thickness=spec.thickness if s.slab_thickness is None else s.slab_thickness,
            modular_ratio=ratio, exclude_slab_bending=s.exclude_slab_bending,
        )
        return Girder(y=g.y, I=sec.I, z_bottom=sec.z_bottom, E=g.E, mu=g.mu, J=g.J,
                      poisson=g.poisson)


def _with_zone_map(base: Bridge, spec: BridgeSpec, E_x, E_y) -> Bridge:
    """``base`` with the explicit zone labels of ``spec.zone_map`` and its parameters."""
    grid = base.model.grid
    zmap = np.array(spec.zone_map, dtype=int)
    shape = (grid.nx, grid.ny) if base.is_plate else (grid.nx,)
    if zmap.shape != shape:
        what = "(nx, ny)" if base.is_plate else "(n_elements,)"
        raise InputError(f"zone_map must have shape {what} = {shape}, got {zmap.shape}")
    n_zones = int(zmap.max()) + 1 if spec.n_zones is None else spec.n_zones
    if zmap.min() < 0 or zmap.max() >= n_zones:
        raise InputError(f"zone_map labels must lie in [0, {n_zones - 1}], got "
                         f"{int(zmap.min())} … {int(zmap.max())}")
    model = dataclasses.replace(base.model, zone_of_element=zmap.ravel(), n_zones=n_zones)
    return Bridge(model=model, E_x=E_x, E_y=E_y, mu=_values(spec.mu),
                  E_girder=base.E_girder, mu_girder=base.mu_girder,
                  damping_ratio=spec.damping_ratio)


def _plate(spec: BridgeSpec, src: str) -> Bridge:
    girders = tuple(_girder(g, spec, src, k) for k, g in enumerate(spec.girders))
    with _context(f"{src}: [bridge]"):
        length = require_positive("length", spec.length)
        width = require_positive("width", spec.width)
        geometry = dict(
            length=length, width=width, nx=spec.nx, ny=spec.ny, thickness=spec.thickness,
            x_lines=_lines(spec.x_lines, spec.x_through, length, spec.nx, "x", "nx"),
            y_lines=_lines(spec.y_lines, spec.y_through, width, spec.ny, "y", "ny"),
            poisson=spec.poisson, damping_ratio=spec.damping_ratio,
            supports=spec.supports if spec.supports is not None else "ss-free",
            girders=girders,
        )
        if spec.joints is not None:  # the deck, then a zone per joint (bwim.fe.joints)
            return with_joints(Bridge.plate(**geometry, E=_values(spec.E), E_x=_values(
                spec.E_x), E_y=_values(spec.E_y), mu=_values(spec.mu)), spec.joints)
        if spec.zone_map is None:
            return Bridge.plate(
                **geometry, E=_values(spec.E), E_x=_values(spec.E_x), E_y=_values(spec.E_y),
                mu=_values(spec.mu), zones=(1, 1) if spec.zones is None else spec.zones,
            )
        if spec.E is not None and (spec.E_x is not None or spec.E_y is not None):
            raise InputError("give either E or E_x/E_y, not both")
        E_x, E_y = (spec.E, spec.E) if spec.E is not None else (spec.E_x, spec.E_y)
        if E_x is None or E_y is None:
            raise InputError("a plate needs E, or both E_x and E_y")
        base = Bridge.plate(**geometry, E=1.0, mu=1.0)
        return _with_zone_map(base, spec, _values(E_x), _values(E_y))


def _beam(spec: BridgeSpec, src: str) -> Bridge:
    with _context(f"{src}: [bridge]"):
        length = require_positive("length", spec.length)
        geometry = dict(
            length=length, n_elements=spec.n_elements, I=spec.I, z_bottom=spec.z_bottom,
            x_lines=_lines(spec.x_lines, spec.x_through, length, spec.n_elements, "x",
                           "n_elements"),
            damping_ratio=spec.damping_ratio,
            supports=spec.supports if spec.supports is not None else "ss",
        )
        if spec.zone_map is None:
            return Bridge.beam(**geometry, E=_values(spec.E), mu=_values(spec.mu),
                               zones=1 if spec.zones is None else spec.zones)
        base = Bridge.beam(**geometry, E=1.0, mu=1.0)
        return _with_zone_map(base, spec, _values(spec.E), None)


def build_bridge(scenario: Scenario) -> Bridge:
    """The scenario's bridge (:meth:`bwim.Bridge.plate` or :meth:`bwim.Bridge.beam`).

    Raises
    ------
    InputError
        The library's message prefixed by the file and ``[bridge]`` (or the girder entry).
    """
    spec = scenario.require("bridge")
    if spec.kind == "plate":
        return _plate(spec, scenario.source)
    return _beam(spec, scenario.source)


_SHORT = {"strain_x": "x", "strain_y": "y", "deflection": "w"}


def _as_tuple(v) -> tuple:
    return v if isinstance(v, tuple) else (v,)


def _sensor_grid(entry) -> list[tuple]:
    """(kind, x, y) of an entry's sensors, expanded kind by kind, then x, then y."""
    return [(kind, x, y) for kind in _as_tuple(entry.kind) for x in _as_tuple(entry.x)
            for y in _as_tuple(entry.y)]


def _entry_names(entry, grid: list[tuple], at: str) -> list[str]:
    if isinstance(entry.name, tuple):
        if entry.x is None and entry.y is None:
            return list(entry.name)
        if len(entry.name) != len(grid):
            raise InputError(f"{at}: {len(entry.name)} names for {len(grid)} sensors")
        return list(entry.name)
    names = []
    for i, (kind, x, y) in enumerate(grid):
        try:
            names.append(entry.name.format(kind=kind, short=_SHORT.get(kind, kind), x=x, y=y, i=i))
        except (KeyError, IndexError, ValueError, AttributeError, TypeError) as exc:
            raise InputError(f"{at} name: bad template {entry.name!r} ({exc}); fields are "
                             "kind, short, x, y, i") from None
    return names


def build_sensors(scenario: Scenario) -> list[Sensor]:
    """The scenario's sensors in file order (grids expanded kind, then x, then y).

    An entry without ``x`` (a logger channel weighed with influence lines) gives sensors
    without a position, one per name of its ``name`` list.  Positions are checked against
    the deck when the scenario has a ``[bridge]``.

    Raises
    ------
    InputError
        A sensor off the deck, ``strain_y`` on a beam, a bad name template, a sensor
        without a position or a name, or two sensors with the same name (they would
        share a CSV column).
    """
    src = scenario.source
    b = scenario.bridge
    plate = b is None or b.kind == "plate"
    tol = 0.0 if b is None else 1e-9 * max(b.length, b.width or 0.0)
    out: list[Sensor] = []
    seen: dict[str, int] = {}
    for k, entry in enumerate(scenario.sensors):
        at = f"{src}: [[sensors]] entry {k + 1}"
        if entry.x is None and entry.y is not None and isinstance(entry.name, tuple) \
                and isinstance(entry.y, tuple) and len(entry.y) != len(entry.name):
            raise InputError(f"{at}: {len(entry.name)} names for {len(entry.y)} y positions")
        if entry.x is None and isinstance(entry.name, tuple):
            ys = entry.y if isinstance(entry.y, tuple) else (entry.y,) * len(entry.name)
            kinds = _as_tuple(entry.kind)
            if len(kinds) != 1:
                raise InputError(f"{at}: sensors without a position take one kind")
            grid = [(kinds[0], None, y) for y in ys]
        else:
            grid = _sensor_grid(entry)
        names = _entry_names(entry, grid, at)
        for (kind, x, y), name in zip(grid, names, strict=True):
            with _context(at):
                sensor = Sensor(x=x, y=y, kind=kind, name=name)
            if b is not None and b.kind != "plate" and kind == "strain_y":
                raise InputError(f"{at}: sensor {sensor.name!r}: strain_y is not "
                                 "available on a beam")
            if b is not None and sensor.x is not None:
                off_x = not -tol <= sensor.x <= b.length + tol
                off_y = plate and not -tol <= sensor.y <= b.width + tol
                if off_x or off_y:
                    size = f"{b.length:g} m" + (f" × {b.width:g} m" if plate else "")
                    where = f"x = {sensor.x:g} m" + (f", y = {sensor.y:g} m" if plate else "")
                    raise InputError(f"{at}: sensor {sensor.name!r} at {where} is off "
                                     f"the deck ({size})")
            if sensor.name in seen:
                raise InputError(f"{at}: sensor name {sensor.name!r} is already used "
                                 f"by entry {seen[sensor.name]}")
            seen[sensor.name] = k + 1
            out.append(sensor)
    return out


def _clock_spec(scenario: Scenario) -> ClockSpec | None:
    table = scenario.logger.clock
    if table is None:
        return None
    with _context(f"{scenario.source}: [logger] clock"):
        if table.none:
            return ClockSpec(from_name=False)
        return ClockSpec(pattern=table.pattern, column=table.column,
                         date_column=table.date, format=table.format)


def build_logger_format(scenario: Scenario) -> LoggerFormat:
    """The :class:`~bwim.io.LoggerFormat` of the scenario's ``[logger]`` section.

    Gauges take their kinds from ``[[sensors]]``; the ``[[axle_detectors]]`` channels are
    axle detectors; the ``clock`` columns are the clock's.  Every named column must be one
    of them.
    """
    return _logger_format(scenario, build_sensors(scenario))


def _logger_format(scenario: Scenario, sensors: list[Sensor]) -> LoggerFormat:
    """:func:`build_logger_format` with the scenario's sensors already built."""
    spec = scenario.require("logger")
    src = f"{scenario.source}: [logger]"
    kinds: dict[str, SensorKind] = {s.name: s.kind for s in sensors}
    for det in scenario.axle_detectors:
        for name in det.channels:
            if name in kinds:
                raise InputError(f"{scenario.source}: [axle_detectors] channel {name!r} is "
                                 "also a [[sensors]] gauge")
            kinds[name] = SensorKind.AXLE_DETECTOR
    clock = _clock_spec(scenario)
    clock_columns = {c for c in ((clock.column, clock.date_column) if clock else ())
                     if c is not None and c != "time"}
    channels = [c for c in spec.columns if c not in ("-", "time") and c not in clock_columns]
    for name in clock_columns:
        if name not in spec.columns:
            raise InputError(f"{src} clock: no column {name!r} in columns")
    for name in channels:
        if name not in kinds:
            raise InputError(f"{src} columns: {name!r} is neither a [[sensors]] name nor an "
                             "[axle_detectors] channel (use \"-\" to skip a column)")
    for name in kinds:
        if name not in channels:
            what = ("[axle_detectors] channel" if kinds[name] is SensorKind.AXLE_DETECTOR
                    else "sensor")
            raise InputError(f"{src} columns: no column for the {what} {name!r}")
    delimiter = {"tab": "\t", "\\t": "\t", "whitespace": " "}.get(spec.delimiter or "",
                                                                  spec.delimiter)
    with _context(src):
        return LoggerFormat(columns=spec.columns, delimiter=delimiter, header=spec.header,
                            sampling_rate=spec.sampling_rate, scale=spec.scale,
                            decimal=spec.decimal, kinds=kinds, skip_lines=spec.skip_lines,
                            clock=clock)


def build_site_setup(scenario: Scenario) -> SiteSetup:
    """What the installation knows (:class:`bwim.site.SiteSetup`): the
    ``[[axle_detectors]]`` lanes, the ``[[lanes]]``, the ``[drift]`` choice and the
    ``[vehicle]`` calibration truck's static axle loads and spacings."""
    truck = build_vehicle(scenario)
    lanes = []
    for k, det in enumerate(scenario.axle_detectors, start=1):
        with _context(f"{scenario.source}: [axle_detectors]"):
            lanes.append(DetectorLane(channels=det.channels, distance=det.distance,
                                      lane=det.lane if det.lane is not None else k,
                                      direction=det.direction, position=det.position,
                                      y=det.y, max_spacing=det.max_spacing,
                                      **({} if det.max_length is None
                                         else {"max_length": det.max_length})))
    cal = next((ln.lane for ln, det in zip(lanes, scenario.axle_detectors, strict=True)
                if det.calibration), None)
    traffic = [Lane(number=ln.number, y=ln.y, direction=ln.direction)
               for ln in scenario.lanes]
    drift = DriftSetup()
    if scenario.drift is not None:
        d = scenario.drift
        with _context(f"{scenario.source}: [drift]"):
            drift = DriftSetup(method=d.method, temperature=d.temperature,
                               reference_class=d.reference_class,
                               reference_load=None if d.reference_kN is None
                               else d.reference_kN * 1e3,
                               **({} if d.min_reference is None
                                  else {"min_reference": d.min_reference}))
        if d.temperature is not None:
            names = {s.name: s.kind for s in build_sensors(scenario)}
            if names.get(d.temperature) is not SensorKind.TEMPERATURE:
                raise InputError(f"{scenario.source}: [drift] temperature: no temperature "
                                 f"channel {d.temperature!r} in [[sensors]] (kind = "
                                 "\"temperature\")")
    with _context(f"{scenario.source}: [axle_detectors]"):
        return SiteSetup(calibration_loads=truck.static_axle_loads,
                         calibration_spacings=truck.axle_spacings, lanes=tuple(lanes),
                         traffic_lanes=tuple(traffic), calibration_lane=cal, drift=drift,
                         support_lobes=scenario.lines is not None
                         and scenario.lines.support_lobes)


def build_trigger(scenario: Scenario) -> TriggerSettings:
    """The trigger of ``bwim weigh --continuous`` (:class:`bwim.stream.TriggerSettings`):
    the ``[trigger]`` section's keys, the defaults for those left out (and without one)."""
    spec = scenario.trigger
    given = {} if spec is None else {
        f.name: getattr(spec, f.name) for f in dataclasses.fields(spec)
        if getattr(spec, f.name) is not None}
    with _context(f"{scenario.source}: [trigger]"):
        settings = TriggerSettings(**given)
    if settings.channels is not None and scenario.logger is not None:
        known = set(build_logger_format(scenario).channels)
        unknown = [c for c in settings.channels if c not in known]
        if unknown:
            raise InputError(f"{scenario.source}: [trigger] channels: no logger channel "
                             f"{unknown[0]!r} in [logger] columns")
    return settings


def build_vehicle(scenario: Scenario) -> Vehicle:
    """The scenario's vehicle: a named one or a :mod:`bwim.vehicles` class instance."""
    spec = scenario.require("vehicle")
    with _context(f"{scenario.source}: [vehicle]"):
        if spec.name is not None:
            return named(spec.name)
        cls = VEHICLE_TYPES[spec.type]
        params = {k: _values(v) for k, v in spec.params.items()}
        if cls is Truck3D and "axle_loads" in params:
            return Truck3D.from_axle_loads(**params)
        return cls(**params)


def _road_extent(scenario: Scenario) -> tuple[float, float]:
    """Default (start, end) of a random road: the whole run with a 5 m margin."""
    run = scenario.run
    approach = DEFAULT_APPROACH if run is None else run.approach
    run_out = 0.0 if run is None else run.speed * run.tail
    vehicle = 0.0 if scenario.vehicle is None else build_vehicle(scenario).length
    margin = 5.0 + (scenario.road.smoothing or 0.0)
    return (-(approach + vehicle + margin),
            scenario.require("bridge").length + vehicle + run_out + margin)


def _data_path(scenario: Scenario, name: str, key: str) -> Path:
    """A data file named in the scenario: relative to the scenario's folder, and inside it
    (a scenario must not make bwim read files elsewhere, e.g. ``../../etc/passwd``)."""
    folder = (scenario.folder or Path()).resolve()
    path = (folder / name).resolve()
    if not path.is_relative_to(folder):
        raise InputError(f"{scenario.source}: {key} {name!r} is outside the scenario's "
                         f"folder {folder}; data files must lie in it or below it")
    return path


def _read_profile(path: Path) -> RoadProfile:
    # messages never quote the file's content (it may be any file the user can read)
    try:
        names, values, _ = read_numeric_csv(path)
    except InputError as exc:
        if str(exc).endswith("no such file") or "cannot read" in str(exc):
            raise
        raise InputError(f"{path}: not a road profile (a CSV file with the header "
                         "x, elevation or x, right, left and rows of numbers)") from None
    if names == ["x", "elevation"]:
        elevation = values[:, 1]
    elif names == ["x", "right", "left"]:
        elevation = values[:, 1:]
    else:
        raise InputError(f"{path}: a road profile has the columns x, elevation or x, right, "
                         f"left; got {len(names)} other column(s)")
    with _context(f"{path}"):
        return RoadProfile(x=values[:, 0], elevation=elevation)


def build_road(scenario: Scenario) -> RoadProfile:
    """The scenario's road profile (flat without a ``[road]`` section).

    A random road without ``start``/``length`` covers the whole run: from the approach
    behind the vehicle's last axle to its exit plus ``tail`` seconds, with 5 m to spare.
    """
    spec = scenario.road
    if spec is None or spec.flat:
        return RoadProfile.flat()
    src = scenario.source
    if spec.profile is not None:
        road = _read_profile(_data_path(scenario, spec.profile, "[road] profile"))
    else:
        start, length = spec.start, spec.length
        if start is None or length is None:
            lo, hi = _road_extent(scenario)
            start = lo if start is None else start
            length = hi - start if length is None else length
        options = {k: getattr(spec, k) for k in ("dx", "track_correlation", "waviness", "band")
                   if getattr(spec, k) is not None}
        with _context(f"{src}: [road]"):
            road = RoadProfile.iso8608(spec.roughness, length=length, start=start,
                                       seed=spec.seed, **options)
    if spec.smoothing is not None:
        with _context(f"{src}: [road] smoothing"):
            road = road.smoothed(spec.smoothing)
    return road


def build_passage(scenario: Scenario, vehicle: Vehicle | None = None) -> Passage:
    """The passage a B-WIM system sees: the ``[run]`` speed, lane and delay and the
    vehicle's axle layout (of ``vehicle``, default the scenario's)."""
    run = scenario.require("run")
    vehicle = build_vehicle(scenario) if vehicle is None else vehicle
    lane = run.lane
    if lane is None:
        if scenario.bridge is None or scenario.bridge.kind == "plate":
            raise InputError(f"{scenario.source}: [run] needs lane on a plate bridge")
        lane = 0.0
    with _context(f"{scenario.source}: [run]"):
        return vehicle.passage(run.speed, lane, run.delay)


def simulate_scenario(scenario: Scenario, *, bridge: Bridge | None = None) -> Record:
    """Simulate the scenario's crossing (:func:`bwim.simulate`), with its ``[run]`` noise.

    Parameters
    ----------
    scenario : Scenario
    bridge : Bridge, optional
        Use this bridge (for example a calibrated one) instead of the scenario's.

    Returns
    -------
    Record
    """
    run = scenario.require("run")
    scenario.require("sensors")
    bridge = build_bridge(scenario) if bridge is None else bridge
    sensors = build_sensors(scenario)
    vehicle = build_vehicle(scenario)
    road = build_road(scenario)
    with _context(scenario.source):
        record = simulate(bridge, vehicle, sensors=sensors, road=road, **run.simulate_kwargs())
        if run.noise:
            record = record.with_noise(run.noise, seed=run.seed)
    return record


_CSV_SUFFIXES = (".csv", ".txt")
_HDF5_SUFFIXES = (".h5", ".hdf5", ".hdf")


def load_record(
    path: str | os.PathLike,
    scenario: Scenario | None = None,
    *,
    time_column: str = "time",
    allow_extra: bool = False,
    scale: float = 1.0,
) -> Record:
    """A record from a CSV file (sensors from ``scenario``) or a bwim HDF5 file.

    Parameters
    ----------
    path : str or path
        ``.h5``/``.hdf5``/``.hdf``: a record written by :func:`bwim.io.write_record`; with
        a scenario that has a ``[logger]`` section, any other file is a logger export read
        by :func:`bwim.io.read_logger`; otherwise ``.csv``/``.txt`` is bwim's CSV layout,
        read with :func:`bwim.io.read_csv_record`.
    scenario : Scenario, optional
        Needed for CSV: its ``[[sensors]]`` name the columns, and its ``[run]`` and
        ``[vehicle]`` (when present) give the passage.  A record without simulation
        settings (every CSV, and HDF5 records of measurements) takes the ``[run]``'s
        approach, with the tail the record has after the last axle leaves the bridge.
    time_column, allow_extra, scale
        As for :func:`bwim.io.read_csv_record` (CSV only).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in _HDF5_SUFFIXES:
        return _with_run_settings(read_record(p), scenario)
    if scenario is not None and scenario.logger is not None:
        # a logger's export, any extension: the [logger] section says how it is laid out
        return record_reader(scenario)(p)
    if suffix not in _CSV_SUFFIXES:
        raise InputError(f"{p}: unknown record format {p.suffix!r}; use .csv or .h5")
    if scenario is None:
        raise InputError(f"{p}: a CSV record needs a scenario for its sensor positions")
    scenario.require("sensors")
    sensors = build_sensors(scenario)
    passage = (build_passage(scenario) if scenario.run is not None
               and scenario.vehicle is not None else None)
    record = read_csv_record(p, sensors, passage, time_column=time_column,
                             allow_extra=allow_extra, scale=scale)
    return _with_run_settings(record, scenario)


@dataclasses.dataclass(frozen=True, eq=False)
class RecordReader:
    """:func:`load_record` for many files of one scenario, its sensors and logger format
    built once (:func:`record_reader`): ``reader(path)`` is ``load_record(path,
    scenario)``, the same record.  Picklable (a batch's ``read``, sent to worker
    processes: it is built again there from the scenario)."""

    scenario: Scenario
    sensors: tuple[Sensor, ...]
    fmt: LoggerFormat | None  # None: the scenario has no [logger] section

    def __reduce__(self):  # built again where it is unpickled (a format holds mappings)
        return record_reader, (self.scenario,)

    def __call__(self, path: str | os.PathLike) -> Record:
        p = Path(path)
        if self.fmt is None or p.suffix.lower() in _HDF5_SUFFIXES:
            return load_record(p, self.scenario)
        # their y (and x) travel with the readings; a gauge held at a rail is judged by
        # the site chain, which leaves it out of the vehicle it fails in and names it
        # (bwim.site.health), not by the reader, which would fail the whole record
        return _with_run_settings(
            read_logger(p, self.fmt, sensors=self.sensors or None, clip_run=None),
            self.scenario)


def record_reader(scenario: Scenario) -> RecordReader:
    """A :class:`RecordReader` of ``scenario``: its logger files read without building
    its sensors and format again for each (InputError for a bad ``[logger]`` section or
    bad sensors, at once)."""
    if scenario.logger is None:
        return RecordReader(scenario=scenario, sensors=(), fmt=None)
    sensors = build_sensors(scenario)
    return RecordReader(scenario=scenario, sensors=tuple(sensors),
                        fmt=_logger_format(scenario, sensors))


def _with_run_settings(record: Record, scenario: Scenario | None) -> Record:
    """The record with the scenario's ``[run]`` approach as its simulation settings, if it
    has none (see :func:`load_record`)."""
    if (record.settings is not None or scenario is None or scenario.run is None
            or scenario.bridge is None or not record.passages):
        return record
    settings = SimulationSettings(approach=scenario.run.approach,
                                  tail=record.time_after_exit(scenario.bridge.length))
    return dataclasses.replace(record, settings=settings)
