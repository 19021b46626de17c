"""Reading a WIM summary and a static reference (CSV) for the COST 323 assessment.

Contract
--------
* Both files are comma-separated (a tab also works) with a header row; lists inside a cell
  are ``;``-separated (``"3.8;6.0;1.3;1.3"``).  Blank lines and lines starting with ``#``
  are skipped; a UTF-8 byte-order mark is ignored; extra columns are ignored.
* :func:`read_summary` reads what ``bwim weigh`` writes: ``record, n_axles, speed_m_s,
  axle_spacings_m, axle_weights_kN, gvw_kN, flags`` (``speed_m_s`` and ``flags`` may be
  absent).  A cell that is empty or ``nan`` means "unknown": a row without a gross weight
  is a record the system did not weigh.  A list with an unknown value is unknown as a
  whole.
* :func:`read_reference` reads statically weighed vehicles: ``record, gvw_kN`` and, for
  the axle criteria, ``axle_weights_kN`` with ``n_axles`` and ``axle_spacings_m`` (any of
  them may be absent or empty: without axle weights only the gross weight is assessed;
  without spacings the axles are grouped by the summary's measured spacings).
  ``speed_m_s`` is optional.  Given cells must be numbers (lists: numbers) and agree with
  ``n_axles``.
* Weights are converted from kN to N (:class:`~bwim.accuracy.SummaryRow`,
  :class:`~bwim.accuracy.ReferenceRow`); spacings stay in m, speeds in m/s.
* Every problem is an :class:`~bwim.errors.InputError` naming the file and, where it has
  one, the line and the column: no such file, an empty file, a missing column, a row
  with the wrong number of fields, a duplicate record name, text that is not a number,
  and no data rows.
"""

from __future__ import annotations

import csv
import math
import os
from pathlib import Path

from bwim.accuracy import ReferenceRow, SummaryRow
from bwim.errors import InputError

__all__ = ["read_reference", "read_summary"]

_KN = 1000.0
_SUMMARY_COLUMNS = ("record", "n_axles", "axle_spacings_m", "axle_weights_kN", "gvw_kN")
_REFERENCE_COLUMNS = ("record", "gvw_kN")


class _Table:
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

    def where(self, line: int, column: str) -> str:
        return f"{self.path}: line {line}, column {column}"


def _missing(text: str) -> bool:
    return text == "" or text.lower() == "nan"


def _number(t: _Table, line: int, column: str, text: str, *, optional: bool) -> float | None:
    if _missing(text):
        if optional:
            return None
        raise InputError(f"{t.where(line, column)}: empty cell")
    return _finite(t.where(line, column), text)


def _finite(where: str, text: str) -> float:
    """``float(text)``; raises :class:`InputError` (at ``where``) unless a finite number."""
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: {text!r} is not finite")
    return v


def _integer(t: _Table, line: int, column: str, text: str, *, optional: bool) -> int | None:
    v = _number(t, line, column, text, optional=optional)
    if v is None:
        return None
    if v != int(v) or v < 1:
        raise InputError(f"{t.where(line, column)}: {text!r} is not a positive integer")
    return int(v)


def _numbers(t: _Table, line: int, column: str, text: str, *, optional: bool
             ) -> tuple[float, ...] | None:
    """The values of a ';'-separated list; None if unknown (optional lists only)."""
    if text == "":
        return ()
    parts = [p.strip() for p in text.split(";")]
    if any(_missing(p) for p in parts):
        if optional:
            return None
        raise InputError(f"{t.where(line, column)}: {text!r} has an empty or NaN value")
    return tuple(_finite(t.where(line, column), p) for p in parts)


def _record(t: _Table, line: int, text: str, seen: dict[str, int]) -> str:
    if not text:
        raise InputError(f"{t.where(line, 'record')}: empty record name")
    if text in seen:
        raise InputError(f"{t.where(line, 'record')}: record {text!r} already on line "
                         f"{seen[text]}")
    seen[text] = line
    return text


def _axles(t: _Table, line: int, row: dict[str, str], *, optional: bool
           ) -> tuple[int | None, tuple[float, ...] | None, tuple[float, ...] | None]:
    """``n_axles`` and the axle weights (kN) and spacings (m) of a row, the list lengths
    checked against ``n_axles``; an optional row may leave any of them empty or unknown."""
    n_axles = _integer(t, line, "n_axles", row["n_axles"], optional=optional)
    weights = _numbers(t, line, "axle_weights_kN", row["axle_weights_kN"], optional=optional)
    spacings = _numbers(t, line, "axle_spacings_m", row["axle_spacings_m"], optional=optional)
    if n_axles is not None:
        for column, values, expected in (("axle_weights_kN", weights, n_axles),
                                         ("axle_spacings_m", spacings, n_axles - 1)):
            if (values or not optional) and len(values) != expected:
                raise InputError(f"{t.where(line, column)}: {len(values)} values for "
                                 f"n_axles = {n_axles}")
    return n_axles, weights, spacings


def _speed(t: _Table, line: int, row: dict[str, str]) -> float | None:
    """The optional ``speed_m_s`` column of a row, m/s (None if absent or empty)."""
    if "speed_m_s" not in row:
        return None
    return _number(t, line, "speed_m_s", row["speed_m_s"], optional=True)


def read_summary(path: str | os.PathLike) -> tuple[SummaryRow, ...]:
    """The rows of a ``summary.csv`` written by ``bwim weigh`` (weights in N)."""
    return _read(path, _SUMMARY_COLUMNS, _summary_row)


def read_reference(path: str | os.PathLike) -> tuple[ReferenceRow, ...]:
    """The statically weighed vehicles of a reference CSV (weights in N)."""
    return _read(path, _REFERENCE_COLUMNS, _reference_row)


def _read(path: str | os.PathLike, columns, parse_row) -> tuple:
    """``parse_row(table, line, record, row)`` of every row of the CSV at ``path``, the
    record names checked (non-empty, unique)."""
    t = _Table(Path(path), columns)
    seen: dict[str, int] = {}
    return tuple(parse_row(t, k, _record(t, k, row["record"], seen), row) for k, row in t.rows)


def _summary_row(t: _Table, k: int, name: str, row: dict[str, str]) -> SummaryRow:
    n_axles, weights, spacings = _axles(t, k, row, optional=True)
    gvw = _number(t, k, "gvw_kN", row["gvw_kN"], optional=True)
    speed = _speed(t, k, row)
    flags = tuple(f.strip() for f in row.get("flags", "").split(";") if f.strip())
    return SummaryRow(
        record=name, gvw=None if gvw is None else gvw * _KN,
        axle_weights=tuple(w * _KN for w in weights or ()),
        axle_spacings=spacings or (), n_axles=n_axles, speed=speed, flags=flags)


def _reference_row(t: _Table, k: int, name: str, row: dict[str, str]) -> ReferenceRow:
    full = {c: row.get(c, "") for c in ("n_axles", "axle_weights_kN", "axle_spacings_m")}
    _, weights, spacings = _axles(t, k, {**row, **full}, optional=True)
    weights, spacings = weights or (), spacings or ()
    for column, values in (("axle_weights_kN", weights), ("axle_spacings_m", spacings)):
        if any(v <= 0.0 for v in values):
            raise InputError(f"{t.where(k, column)}: values must be positive")
    gvw = _number(t, k, "gvw_kN", row["gvw_kN"], optional=False)
    if gvw <= 0.0:
        raise InputError(f"{t.where(k, 'gvw_kN')}: must be positive")
    return ReferenceRow(record=name, gvw=gvw * _KN, axle_weights=tuple(w * _KN for w in weights),
                        axle_spacings=spacings, speed=_speed(t, k, row))
