"""Statically weighed vehicles (CSV): the reference of a COST 323 assessment.

Contract
--------
* :func:`read_reference` reads ``record, gvw_kN`` (or ``time, gvw_kN``: see below) and,
  for the axle criteria,
  ``axle_weights_kN`` with ``n_axles`` and ``axle_spacings_m`` (any of them may be absent
  or empty: without axle weights only the gross weight is assessed; without spacings the
  axles are grouped by the summary's measured spacings).  ``speed_m_s``, ``vehicle`` (the
  summary's vehicle number within the record) and ``lane`` are optional.  Given cells must
  be numbers (lists: numbers) and agree with ``n_axles``.  The layout rules are those of
  :mod:`bwim.io.csvtable`.
* ``time`` (ISO 8601, the site's local time as the summary's: a date and time or a time
  of day; a UTC offset is dropped, the time kept as written) says when the vehicle
  crossed.  A row whose ``record`` is empty (or a file without that column) is matched
  by it (:func:`bwim.accuracy.assess`: the events of a continuous recording are named
  by the trigger, ``FILE#k``, not known when the trucks are weighed); a row with a
  record is matched by the record and its time is not read.  A row needs a record or a
  time; a vehicle given by time takes no ``vehicle``, and one time (with its lane) is
  given once.
* Weights are converted from kN to N (:class:`~bwim.accuracy.ReferenceRow`); spacings
  stay in m, speeds in m/s.  A record (with its vehicle) named twice is refused.
"""

from __future__ import annotations

import os
from pathlib import Path

from bwim.accuracy import ReferenceRow
from bwim.errors import InputError
from bwim.io.csvtable import (
    CsvTable,
    axles_cells,
    integer_cell,
    number_cell,
    once,
    record_name,
    speed_cell,
    time_cell,
)

__all__ = ["read_reference"]

_KN = 1000.0
_COLUMNS = ("gvw_kN",)


def read_reference(path: str | os.PathLike) -> tuple[ReferenceRow, ...]:
    """The statically weighed vehicles of a reference CSV (weights in N)."""
    t = CsvTable(Path(path), _COLUMNS)
    if "record" not in t.names and "time" not in t.names:
        raise InputError(f"{t.path}: missing column record (or time: when each vehicle "
                         f"crossed) (found {', '.join(t.names)})")
    seen: dict = {}
    rows = []
    for k, row in t.rows:
        text = row.get("record", "")
        # a row with a record is matched by it: its time is not read
        when = None if text else time_cell(t, k, "time", row.get("time", ""))
        name = record_name(t, k, text) if text or when is None else ""
        vehicle = integer_cell(t, k, "vehicle", row.get("vehicle", ""), optional=True)
        if name:
            once(t, k, (name, vehicle), f"record {name!r}" + (
                "" if vehicle is None else f" vehicle {vehicle}"), seen)
        elif vehicle is not None:
            raise InputError(f"{t.where(k, 'vehicle')}: a vehicle number needs a record (a "
                             "vehicle given by its time has none)")
        ref = _reference_row(t, k, name, vehicle, row, when)
        if not name:
            key = ("", ref.time, ref.lane)
            if key in seen:
                raise InputError(f"{t.where(k, 'time')}: the vehicle at {ref.label} already "
                                 f"on line {seen[key]}")
            seen[key] = k
        rows.append(ref)
    return tuple(rows)


def _reference_row(t: CsvTable, k: int, name: str, vehicle: int | None,
                   row: dict[str, str], when) -> ReferenceRow:
    full = {c: row.get(c, "") for c in ("n_axles", "axle_weights_kN", "axle_spacings_m")}
    _, weights, spacings = axles_cells(t, k, {**row, **full}, optional=True)
    weights, spacings = weights or (), spacings or ()
    for column, values in (("axle_weights_kN", weights), ("axle_spacings_m", spacings)):
        if any(v <= 0.0 for v in values):
            raise InputError(f"{t.where(k, column)}: values must be positive")
    gvw = number_cell(t, k, "gvw_kN", row["gvw_kN"], optional=False)
    if gvw <= 0.0:
        raise InputError(f"{t.where(k, 'gvw_kN')}: must be positive")
    lane = integer_cell(t, k, "lane", row.get("lane", ""), optional=True)
    return ReferenceRow(record=name, gvw=gvw * _KN, axle_weights=tuple(w * _KN for w in weights),
                        axle_spacings=spacings, speed=speed_cell(t, k, row), vehicle=vehicle,
                        lane=lane, time=when)
