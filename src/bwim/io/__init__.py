"""File formats: logger text files, CSV and HDF5 records, HDF5 results.

Contract
--------
* Records (:mod:`bwim.io.records`): a logger's CSV (:func:`read_csv_record`,
  :func:`write_csv_record`) and bwim's HDF5 (:func:`write_record`, :func:`read_record`,
  :func:`write_records`, :func:`read_records`), exact round trips.
* Logger files (:mod:`bwim.io.logger`): a real installation's text files, one event each,
  read by :func:`read_logger` in a :class:`LoggerFormat` (columns, delimiter, header,
  sampling rate, scale, sensor kinds) into a Record with strict, line-naming checks.
* Summaries (:mod:`bwim.io.summary`): ``summary.csv``, one row per vehicle
  (:class:`~bwim.summary.SummaryRow`), one column list for every command
  (:func:`write_summary`, :func:`read_summary`); static references
  (:mod:`bwim.io.reference`, :func:`read_reference`) for the COST 323 assessment.
* Results (:mod:`bwim.io.results`): HDF5 for :class:`~bwim.ForceIdentification`,
  :class:`~bwim.StaticWeights` and :class:`~bwim.InfluenceLine`, exact round trips.
* Every writer is atomic (:mod:`bwim.io.atomic`): the output appears complete or not at
  all; an unwritable path is an :class:`~bwim.errors.InputError` naming it.

Layering: this package holds file formats only.  It sits below the site chain (detect,
wim, site, batch), which may use it, and below :mod:`bwim.scenario`, the composition root
that describes an installation and reads its records (:func:`bwim.scenario.load_record`).
It never imports those.
"""

from bwim.io._csv import open_regular
from bwim.io.atomic import atomic_open, atomic_output, check_writable
from bwim.io.clock import ClockSpec, name_timestamp
from bwim.io.logger import LoggerFormat, read_logger
from bwim.io.records import (
    read_csv_record,
    read_record,
    read_records,
    write_csv_record,
    write_record,
    write_records,
)
from bwim.io.reference import read_reference
from bwim.io.results import (
    read_identification,
    read_influence_line,
    read_static_weights,
    write_identification,
    write_influence_line,
    write_static_weights,
)
from bwim.io.summary import read_summary, write_summary
from bwim.io.toml_writer import to_toml

__all__ = [
    "ClockSpec",
    "LoggerFormat",
    "atomic_open",
    "atomic_output",
    "check_writable",
    "name_timestamp",
    "open_regular",
    "read_csv_record",
    "read_identification",
    "read_influence_line",
    "read_logger",
    "read_record",
    "read_records",
    "read_reference",
    "read_static_weights",
    "read_summary",
    "to_toml",
    "write_csv_record",
    "write_identification",
    "write_influence_line",
    "write_record",
    "write_records",
    "write_static_weights",
    "write_summary",
]
