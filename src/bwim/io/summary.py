"""``summary.csv``: one row per vehicle, the one column list both commands write.

Contract
--------
* :data:`COLUMNS` is the file's header, in order: the seven columns of the contract
  (``record, n_axles, speed_m_s, axle_spacings_m, axle_weights_kN, gvw_kN, flags``), then
  ``vehicle, time, lane, direction, class, group_weights_kN, lateral, lateral_unit,
  group_laterals, confidence, residual, quality, method, drift_factor, drift_method,
  lambda, status, reason``.  One :class:`~bwim.summary.SummaryRow` per line; units in the
  column names (weights kN, spacings m, speed m/s), ``lateral`` and ``group_laterals``
  (one per axle group) in ``lateral_unit``; lists ``;``-separated; ``time`` ISO 8601
  (``2015-10-01T09:45:52.576``, or ``09:45:52.576`` when only the clock time of day is
  known); empty cells are unknown.
* :func:`write_summary` writes rows atomically (:mod:`bwim.io.atomic`), in the order
  given.  :func:`read_summary` reads such a file back into rows (weights in N); it also
  reads summaries of earlier versions, which had only some of the columns (the five
  ``record, n_axles, axle_spacings_m, axle_weights_kN, gvw_kN`` are required; a row
  without ``status`` is weighed when it has a gross weight).  :func:`to_cells` /
  :func:`from_cells` turn one row into the file's text cells and back (exact for the
  numbers as written), e.g. for a batch's manifest.
* Errors are :class:`~bwim.errors.InputError` naming the file, line and column
  (:mod:`bwim.io.csvtable`); a row the constructor of SummaryRow refuses (a weight on a
  row that is not weighed) is refused naming its line.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable, Mapping
from datetime import datetime
from datetime import time as dtime
from pathlib import Path

from bwim.errors import InputError
from bwim.io.atomic import atomic_open
from bwim.io.csvtable import (
    CsvTable,
    axles_cells,
    integer_cell,
    number_cell,
    numbers_cell,
    once,
    record_name,
    speed_cell,
    time_cell,
)
from bwim.summary import SummaryRow

__all__ = ["COLUMNS", "CONTRACT_COLUMNS", "from_cells", "is_summary", "read_summary",
           "to_cells", "write_summary"]

#: The contract's first seven columns.
CONTRACT_COLUMNS = ("record", "n_axles", "speed_m_s", "axle_spacings_m", "axle_weights_kN",
                    "gvw_kN", "flags")
#: The header of ``summary.csv``.
COLUMNS = (*CONTRACT_COLUMNS, "vehicle", "time", "lane", "direction", "class",
           "group_weights_kN", "lateral", "lateral_unit", "group_laterals", "confidence",
           "residual", "quality", "method", "drift_factor", "drift_method", "lambda", "status",
           "reason")
_REQUIRED = ("record", "n_axles", "axle_spacings_m", "axle_weights_kN", "gvw_kN")
_KN = 1000.0


def _joined(values: Iterable[float], fmt: str, scale: float = 1.0) -> str:
    return ";".join(format(float(v) / scale, fmt) for v in values)


def _num(value: float | None, fmt: str, scale: float = 1.0) -> str:
    return "" if value is None else format(float(value) / scale, fmt)


def _time_text(value: datetime | dtime | None) -> str:
    if value is None:
        return ""
    return value.isoformat(timespec="milliseconds")


def to_cells(row: SummaryRow) -> dict[str, str]:
    """The text cells of one row, by column name (:data:`COLUMNS`)."""
    return {
        "record": row.record,
        "n_axles": "" if row.n_axles is None else str(row.n_axles),
        "speed_m_s": _num(row.speed, ".3f"),
        "axle_spacings_m": _joined(row.axle_spacings, ".3f"),
        "axle_weights_kN": _joined(row.axle_weights, ".2f", _KN),
        "gvw_kN": _num(row.gvw, ".2f", _KN),
        "flags": ";".join(row.flags),
        "vehicle": str(row.vehicle),
        "time": _time_text(row.time),
        "lane": "" if row.lane is None else str(row.lane),
        "direction": row.direction,
        "class": row.vehicle_class,
        "group_weights_kN": _joined(row.group_weights, ".2f", _KN),
        "lateral": _num(row.lateral, ".3f"),
        "lateral_unit": row.lateral_unit,
        "group_laterals": _joined(row.group_laterals, ".3f"),
        "confidence": _num(row.confidence, ".3f"),
        "residual": _num(row.residual, ".4g"),
        "quality": row.quality,
        "method": row.method,
        "drift_factor": _num(row.drift_factor, ".4f"),
        "drift_method": row.drift_method,
        "lambda": _num(row.lam, ".4g"),
        "status": row.status or "",
        "reason": row.reason,
    }


def from_cells(cells: Mapping[str, str], *, table: CsvTable | None = None,
               line: int = 0) -> SummaryRow:
    """A row from its text cells (absent columns are unknown); ``table`` and ``line``
    name the place in messages."""
    t = table if table is not None else CsvTable.of_cells(dict(cells))
    row = {c: cells.get(c, "") for c in COLUMNS}
    n_axles, weights, spacings = axles_cells(t, line, row, optional=True)
    gvw = number_cell(t, line, "gvw_kN", row["gvw_kN"], optional=True)
    groups = numbers_cell(t, line, "group_weights_kN", row["group_weights_kN"], optional=True)
    paths = numbers_cell(t, line, "group_laterals", row["group_laterals"], optional=True)
    vehicle = integer_cell(t, line, "vehicle", row["vehicle"], optional=True)
    lane = integer_cell(t, line, "lane", row["lane"], optional=True)

    def opt(column: str) -> float | None:
        return number_cell(t, line, column, row[column], optional=True)

    # the cells' own messages name the file, line and column: read them before the row
    when = time_cell(t, line, "time", row["time"])
    name, speed = record_name(t, line, row["record"]), speed_cell(t, line, row)
    numbers = {c: opt(c) for c in ("lateral", "confidence", "residual", "drift_factor",
                                   "lambda")}
    try:
        return SummaryRow(
            record=name, vehicle=vehicle or 1,
            status=row["status"] or None, time=when,
            lane=lane, direction=row["direction"], vehicle_class=row["class"],
            n_axles=n_axles, speed=speed, axle_spacings=spacings or (),
            axle_weights=tuple(w * _KN for w in weights or ()),
            gvw=None if gvw is None else gvw * _KN,
            group_weights=tuple(w * _KN for w in groups or ()),
            flags=tuple(f.strip() for f in row["flags"].split(";") if f.strip()),
            lateral=numbers["lateral"], lateral_unit=row["lateral_unit"],
            group_laterals=paths or (),
            confidence=numbers["confidence"], residual=numbers["residual"],
            quality=row["quality"], method=row["method"],
            drift_factor=numbers["drift_factor"], drift_method=row["drift_method"],
            lam=numbers["lambda"], reason=row["reason"])
    except InputError as exc:
        where = "" if table is None else f"{table.path}: line {line}: "
        raise InputError(f"{where}{exc}") from None


def read_summary(path: str | os.PathLike) -> tuple[SummaryRow, ...]:
    """The rows of a ``summary.csv`` (weights in N); see the module docstring."""
    t = CsvTable(Path(path), _REQUIRED)
    seen: dict = {}
    rows = []
    for k, cells in t.rows:
        row = from_cells(cells, table=t, line=k)
        once(t, k, row.key, f"record {row.record!r} vehicle {row.vehicle}", seen)
        rows.append(row)
    return tuple(rows)


def is_summary(path: str | os.PathLike) -> bool:
    """Whether the CSV file at ``path`` starts with a summary's contract columns."""
    try:
        with open(path, newline="", encoding="utf-8", errors="replace") as f:
            header = next(csv.reader(f), [])
    except OSError:
        return False
    return tuple(h.strip() for h in header[:len(CONTRACT_COLUMNS)]) == CONTRACT_COLUMNS


def write_summary(path: str | os.PathLike, rows: Iterable[SummaryRow]) -> None:
    """Write ``rows`` (in that order) as ``summary.csv`` at ``path``, atomically."""
    with atomic_open(path, newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        for row in rows:
            w.writerow(to_cells(row))
