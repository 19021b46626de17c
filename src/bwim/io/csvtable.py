"""Small CSV tables of weights: the parser shared by summaries and references.

Contract
--------
* :class:`CsvTable` reads a comma-separated file (a tab also works) with a header row;
  lists inside a cell are ``;``-separated (``"3.8;6.0;1.3;1.3"``).  Blank lines and lines
  starting with ``#`` are skipped; a UTF-8 byte-order mark is ignored; extra columns are
  ignored by the readers.
* The cell helpers (:func:`number_cell`, :func:`integer_cell`, :func:`numbers_cell`,
  :func:`axles_cells`, :func:`speed_cell`, :func:`record_name`, :func:`time_cell`) turn
  text into numbers (and ISO 8601 times: the site's local time, an offset dropped):
  a cell that is empty or ``nan`` means "unknown" where the caller allows it; a list with
  an unknown value is unknown as a whole.
* Every problem is an :class:`~bwim.errors.InputError` naming the file and, where it has
  one, the line and the column: no such file, an empty file, a missing column, a row
  with the wrong number of fields, a duplicate record name, text that is not a number,
  and no data rows.
"""

from __future__ import annotations

import csv
import math
import re
from datetime import datetime
from datetime import time as dtime
from pathlib import Path

from bwim.errors import InputError

_DATE = re.compile(r"\d{4}-\d{2}-\d{2}|\d{8}")  # a cell's leading date

__all__ = ["CsvTable", "axles_cells", "finite", "integer_cell", "missing", "number_cell",
           "numbers_cell", "once", "record_name", "speed_cell", "time_cell"]


class CsvTable:
    """Header and rows of a small CSV file, with the file's line numbers."""

    def __init__(self, path: Path, required: tuple[str, ...]) -> None:
        self.path = path
        try:
            with open(path, encoding="utf-8-sig", newline="") as f:
                lines = f.read().splitlines()
        except FileNotFoundError:
            raise InputError(f"{path}: no such file") from None
        except UnicodeDecodeError as exc:
            raise InputError(f"{path}: not UTF-8 text (byte {exc.start})") from None
        except OSError as exc:
            raise InputError(f"{path}: cannot read: {(exc.strerror or str(exc)).lower()}"
                             ) from None
        content = [(k, line) for k, line in enumerate(lines, start=1)
                   if line.strip() and not line.lstrip().startswith("#")]
        if not content:
            raise InputError(f"{path}: the file is empty")
        head_no, head = content[0]
        if "," in head:
            sep = ","
        elif "\t" in head:
            sep = "\t"
        elif ";" in head:
            raise InputError(f"{path}: line {head_no}: fields must be separated by commas "
                             f"(';' separates the values of a list)")
        else:
            sep = ","
        self.names = [n.strip() for n in next(csv.reader([head], delimiter=sep))]
        seen = set()
        for n in self.names:
            if n in seen:
                raise InputError(f"{path}: line {head_no}: duplicate column {n!r}")
            seen.add(n)
        absent = [c for c in required if c not in self.names]
        if absent:
            raise InputError(f"{path}: missing column(s) {', '.join(absent)} "
                             f"(found {', '.join(self.names)})")
        self.rows: list[tuple[int, dict[str, str]]] = []
        for k, line in content[1:]:
            fields = next(csv.reader([line], delimiter=sep))
            if len(fields) != len(self.names):
                raise InputError(f"{path}: line {k}: {len(fields)} fields, expected "
                                 f"{len(self.names)}")
            self.rows.append((k, {n: v.strip() for n, v in zip(self.names, fields,
                                                               strict=True)}))
        if not self.rows:
            raise InputError(f"{path}: no data rows")

    @classmethod
    def of_cells(cls, cells: dict[str, str], name: str = "summary row") -> CsvTable:
        """A one-row table of ``cells`` already split (e.g. from a manifest); messages
        name it ``name``."""
        t = cls.__new__(cls)
        t.path = Path(name)
        t.names = list(cells)
        t.rows = [(0, dict(cells))]
        return t

    def where(self, line: int, column: str) -> str:
        return f"{self.path}: line {line}, column {column}"


def missing(text: str) -> bool:
    return text == "" or text.lower() == "nan"


def number_cell(t: CsvTable, line: int, column: str, text: str, *, optional: bool) -> float | None:
    if missing(text):
        if optional:
            return None
        raise InputError(f"{t.where(line, column)}: empty cell")
    return finite(t.where(line, column), text)


def finite(where: str, text: str) -> float:
    """``float(text)``; raises :class:`InputError` (at ``where``) unless a finite number."""
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: {text!r} is not finite")
    return v


def integer_cell(t: CsvTable, line: int, column: str, text: str, *, optional: bool) -> int | None:
    v = number_cell(t, line, column, text, optional=optional)
    if v is None:
        return None
    if v != int(v) or v < 1:
        raise InputError(f"{t.where(line, column)}: {text!r} is not a positive integer")
    return int(v)


def numbers_cell(t: CsvTable, line: int, column: str, text: str, *, optional: bool
             ) -> tuple[float, ...] | None:
    """The values of a ';'-separated list; None if unknown (optional lists only)."""
    if text == "":
        return ()
    parts = [p.strip() for p in text.split(";")]
    if any(missing(p) for p in parts):
        if optional:
            return None
        raise InputError(f"{t.where(line, column)}: {text!r} has an empty or NaN value")
    return tuple(finite(t.where(line, column), p) for p in parts)


def record_name(t: CsvTable, line: int, text: str) -> str:
    """The ``record`` cell: a non-empty name."""
    if not text:
        raise InputError(f"{t.where(line, 'record')}: empty record name")
    return text


def once(t: CsvTable, line: int, key: object, label: str, seen: dict) -> None:
    """Refuse a second row of the same ``key`` (``label`` names it in the message)."""
    if key in seen:
        raise InputError(f"{t.where(line, 'record')}: {label} already on line {seen[key]}")
    seen[key] = line


def axles_cells(t: CsvTable, line: int, row: dict[str, str], *, optional: bool
           ) -> tuple[int | None, tuple[float, ...] | None, tuple[float, ...] | None]:
    """``n_axles`` and the axle weights (kN) and spacings (m) of a row, the list lengths
    checked against ``n_axles``; an optional row may leave any of them empty or unknown."""
    n_axles = integer_cell(t, line, "n_axles", row["n_axles"], optional=optional)
    weights = numbers_cell(t, line, "axle_weights_kN", row["axle_weights_kN"], optional=optional)
    spacings = numbers_cell(t, line, "axle_spacings_m", row["axle_spacings_m"], optional=optional)
    if n_axles is not None:
        for column, values, expected in (("axle_weights_kN", weights, n_axles),
                                         ("axle_spacings_m", spacings, n_axles - 1)):
            if (values or not optional) and len(values) != expected:
                raise InputError(f"{t.where(line, column)}: {len(values)} values for "
                                 f"n_axles = {n_axles}")
    return n_axles, weights, spacings


def speed_cell(t: CsvTable, line: int, row: dict[str, str]) -> float | None:
    """The optional ``speed_m_s`` column of a row, m/s (None if absent or empty)."""
    if "speed_m_s" not in row:
        return None
    return number_cell(t, line, "speed_m_s", row["speed_m_s"], optional=True)


def time_cell(t: CsvTable | None, line: int, column: str, text: str
              ) -> datetime | dtime | None:
    """An ISO 8601 cell: a date and time (``2015-10-01T09:45:52.576``) or a time of day
    (``09:45:52.576``), naive: the site's local time as written (a UTC offset is dropped,
    as the loggers' clocks are read); None when empty.  ``t`` None: the message names the
    column alone."""
    if not text:
        return None
    where = column if t is None else t.where(line, column)
    try:
        # a date leads (YYYY-MM-DD, YYYYMMDD): not the '-' of a time's UTC offset
        value = (datetime.fromisoformat(text) if ("T" in text or _DATE.match(text))
                 else dtime.fromisoformat(text))
    except ValueError:
        raise InputError(f"{where}: {text!r} is not an ISO 8601 time") from None
    return value.replace(tzinfo=None)  # the local time as written, as the clocks are read
