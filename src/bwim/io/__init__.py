"""File formats: TOML scenarios and bridge models, CSV and HDF5 records, HDF5 results.

Contract
--------
* Scenarios (:mod:`bwim.io.scenario`): :func:`load_scenario` reads a TOML file into a
  frozen :class:`Scenario` with strict, one-line, file-and-key-naming errors;
  :func:`dump_scenario` writes one back.  The builders (:mod:`bwim.io.build`) make the
  bridge, sensors, vehicle, road and passage, :func:`simulate_scenario` runs the
  scenario's crossing and :func:`load_record` reads a CSV or HDF5 record for it.
* Bridge models (:mod:`bwim.io.bridgefile`): :func:`save_bridge` / :func:`load_bridge`
  round-trip any bridge (a calibrated one included) exactly, as TOML.
* Records (:mod:`bwim.io.records`): a logger's CSV (:func:`read_csv_record`,
  :func:`write_csv_record`) and bwim's HDF5 (:func:`write_record`, :func:`read_record`,
  :func:`write_records`, :func:`read_records`), exact round trips.
* Logger files (:mod:`bwim.io.logger`): a real installation's text files, one event each,
  read by :func:`read_logger` in a :class:`LoggerFormat` (columns, delimiter, header,
  sampling rate, scale, sensor kinds) into a Record with strict, line-naming checks.
* Results (:mod:`bwim.io.results`): HDF5 for :class:`~bwim.ForceIdentification`,
  :class:`~bwim.StaticWeights` and :class:`~bwim.InfluenceLine`, exact round trips.
* Every writer is atomic (:mod:`bwim.io.atomic`): the output appears complete or not at
  all; an unwritable path is an :class:`~bwim.errors.InputError` naming it.

This package is above the core: it imports the library, the library never imports it.
"""

from bwim.io.atomic import atomic_open, atomic_output, check_writable
from bwim.io.bridgefile import bridge_spec, load_bridge, save_bridge
from bwim.io.build import (
    build_bridge,
    build_logger_format,
    build_passage,
    build_road,
    build_sensors,
    build_site_setup,
    build_vehicle,
    load_record,
    simulate_scenario,
)
from bwim.io.logger import LoggerFormat, read_logger
from bwim.io.records import (
    read_csv_record,
    read_record,
    read_records,
    write_csv_record,
    write_record,
    write_records,
)
from bwim.io.results import (
    read_identification,
    read_influence_line,
    read_static_weights,
    write_identification,
    write_influence_line,
    write_static_weights,
)
from bwim.io.scenario import (
    VEHICLE_TYPES,
    BridgeSpec,
    CalibrateSpec,
    GirderSpec,
    IdentifySpec,
    RoadSpec,
    RunSpec,
    Scenario,
    SectionSpec,
    SensorSpec,
    VehicleSpec,
    dump_scenario,
    load_scenario,
    read_toml,
    scenario_from_dict,
    scenario_to_dict,
)
from bwim.io.toml_writer import to_toml

__all__ = [
    "VEHICLE_TYPES",
    "BridgeSpec",
    "CalibrateSpec",
    "GirderSpec",
    "IdentifySpec",
    "LoggerFormat",
    "RoadSpec",
    "RunSpec",
    "Scenario",
    "SectionSpec",
    "SensorSpec",
    "VehicleSpec",
    "atomic_open",
    "atomic_output",
    "bridge_spec",
    "build_bridge",
    "build_logger_format",
    "build_passage",
    "build_road",
    "build_sensors",
    "build_site_setup",
    "build_vehicle",
    "check_writable",
    "dump_scenario",
    "load_bridge",
    "load_record",
    "load_scenario",
    "read_csv_record",
    "read_identification",
    "read_influence_line",
    "read_logger",
    "read_record",
    "read_records",
    "read_static_weights",
    "read_toml",
    "save_bridge",
    "scenario_from_dict",
    "scenario_to_dict",
    "simulate_scenario",
    "to_toml",
    "write_csv_record",
    "write_identification",
    "write_influence_line",
    "write_record",
    "write_records",
    "write_static_weights",
]
