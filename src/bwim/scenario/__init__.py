"""Scenarios: a bridge, its sensors, a logger, a vehicle, a road and run settings in TOML,
and the builders that turn them into bwim objects (the composition root).

Contract
--------
* :func:`load_scenario` reads a TOML file into a :class:`Scenario`, a frozen dataclass of
  section specs (:class:`BridgeSpec`, :class:`SensorSpec`, :class:`VehicleSpec`,
  :class:`RoadSpec`, :class:`RunSpec`, :class:`IdentifySpec`, :class:`CalibrateSpec`) that
  mirror the file (:mod:`bwim.scenario.specs`, checked by :mod:`bwim.scenario.checks`);
  :func:`scenario_from_dict` does the same for an already parsed mapping and
  :func:`dump_scenario` writes a scenario back (``load → dump → load`` gives an equal
  scenario; comments are not kept) (:mod:`bwim.scenario.parse`).  The builders
  (:mod:`bwim.scenario.build`) turn specs into bwim objects: bridge, sensors, vehicle,
  road, passage, the site's setup, the logger format, records (:func:`load_record`) and
  the scenario's simulated crossing (:func:`simulate_scenario`).
* Layering: this package is the composition root of the command line and of scripts.
  It imports the library and :mod:`bwim.io` (file formats); nothing below it imports it.
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
      Plate: or [``joints``: the y of each longitudinal joint, m; the column of elements
      holding it is a zone of its own (:mod:`bwim.fe.joints`)].
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
  ``[axle_detectors]`` or ``[[axle_detectors]]`` (one table per lane with detectors)
      ``channels`` = [first, second] (logger channels, in the order traffic meets them),
      ``distance`` (m), [``lane``: its number, default the table's place],
      [``direction`` = "+x": "-x" for traffic the other way], [``y``: the pair's (the
      lane's centre line's) transverse position, m], [``calibration``: true in the
      calibration truck's lane's table, default the first], [``position`` = 0: the first
      detector's x in the influence-line frame], [``max_spacing``: the largest axle
      spacing within one vehicle, m], [``max_length`` = 18.75: the longest vehicle's
      spread from first to last axle, m; 25.25 where European Modular System
      combinations run].
  ``[[lanes]]``
      a traffic lane (with or without detectors) by its centre line: ``number``, ``y``
      (m), [``direction`` = "+x"]; a vehicle whose lateral position (m) lies nearer it
      than its own pair's lane is given its number (:mod:`bwim.site.lanes`).  A lane
      with detectors must travel as its ``[[axle_detectors]]`` table says.
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
  ``[drift]``
      how the strain-to-load ratio's drift is corrected (:mod:`bwim.site.drift`):
      [``method`` = "auto": "traffic", "temperature", "time_of_day", "trend", "none"],
      [``temperature``: a temperature channel of ``[[sensors]]``], for the traffic method
      [``reference_class``: an axle-group code, default the commonest articulated
      class], [``reference_kN``: its steering axle's nominal load, where no traffic is
      weighed while the calibration holds], [``min_reference`` = 20: the fewest
      reference vehicles a date needs, else the time of day, flagged
      ``drift_traffic_thin``].
  ``[lines]``
      [``support_lobes`` = false]: the lines keep a lobe beyond their first zeros (a
      slab continuous over its supports).
  ``[trigger]``
      how ``bwim weigh --continuous`` cuts long recordings into events
      (:class:`bwim.stream.TriggerSettings`, docs/streams.md): [``on`` = 6], [``off`` =
      3] (noise σ), [``pre`` = 0.5], [``post`` = 0.5], [``min_duration`` = 0.1],
      [``merge_gap`` = 1], [``max_duration`` = 60], [``baseline`` = 10], [``frame`` =
      0.25] (s), [``noise``: σ of the summed channels], [``channels``: those summed].
"""


from bwim.scenario.bridgefile import bridge_spec, load_bridge, save_bridge
from bwim.scenario.build import (
    RecordReader,
    build_bridge,
    build_logger_format,
    build_passage,
    build_road,
    build_sensors,
    build_site_setup,
    build_trigger,
    build_vehicle,
    load_record,
    record_reader,
    simulate_scenario,
)
from bwim.scenario.parse import (
    dump_scenario,
    load_scenario,
    read_toml,
    scenario_from_dict,
    scenario_to_dict,
)
from bwim.scenario.sitemodel import load_model, load_site_model, save_site_model
from bwim.scenario.specs import (
    VEHICLE_TYPES,
    AxleDetectorSpec,
    BridgeSpec,
    CalibrateSpec,
    GirderSpec,
    IdentifySpec,
    LoggerSpec,
    RoadSpec,
    RunSpec,
    Scenario,
    SectionSpec,
    SensorSpec,
    VehicleSpec,
)

__all__ = [
    "VEHICLE_TYPES",
    "AxleDetectorSpec",
    "BridgeSpec",
    "CalibrateSpec",
    "GirderSpec",
    "IdentifySpec",
    "LoggerSpec",
    "RecordReader",
    "RoadSpec",
    "RunSpec",
    "Scenario",
    "SectionSpec",
    "SensorSpec",
    "VehicleSpec",
    "bridge_spec",
    "build_bridge",
    "build_logger_format",
    "build_passage",
    "build_road",
    "build_sensors",
    "build_site_setup",
    "build_trigger",
    "build_vehicle",
    "dump_scenario",
    "load_bridge",
    "load_model",
    "load_record",
    "load_scenario",
    "load_site_model",
    "read_toml",
    "record_reader",
    "save_bridge",
    "save_site_model",
    "scenario_from_dict",
    "scenario_to_dict",
    "simulate_scenario",
]
