"""The calibration runs table (``calibration_runs.csv`` of ``bwim weigh``) read back.

Contract
--------
* ``bwim weigh`` writes one row per calibration run: ``run`` (file name),
  ``speed (m/s)``, ``lateral`` (the run's lateral covariate, in the unit of the summary's
  ``lateral_unit``), ``scale`` (the run's strain-to-load factor relative to the fitted
  lines, dimensionless, 1 = the lines), ``residual`` (relative residual of the run's fit)
  and ``status`` (``used`` or why the run was left out).  An optional ``time`` column
  (ISO 8601 date-time, or a clock time of day) dates each run.
* :func:`is_runs_table` tells such a file by its header (``run`` first, ``scale`` and
  ``residual`` among the columns); :func:`read_calibration_runs` reads it into
  :class:`CalibrationRuns`.  Empty cells are unknown (None).  A cell that is not a
  number, or a time that is not ISO 8601, is an :class:`~bwim.errors.InputError` naming
  the file, line and column.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from datetime import datetime
from datetime import time as dtime
from pathlib import Path

from bwim.errors import InputError
from bwim.io.csvtable import time_cell

__all__ = ["CalibrationRun", "CalibrationRuns", "is_runs_table", "read_calibration_runs"]

_REQUIRED = ("run", "scale", "residual")


@dataclass(frozen=True, kw_only=True)
class CalibrationRun:
    """One calibration run: its name, speed (m/s), lateral covariate, scale factor,
    relative residual, status (``"used"`` or the reason it was left out) and time."""

    name: str
    speed: float | None = None
    lateral: float | None = None
    scale: float | None = None
    residual: float | None = None
    status: str = "used"
    time: datetime | dtime | None = None

    @property
    def used(self) -> bool:
        """Whether the run went into the influence lines."""
        return self.status == "used"


@dataclass(frozen=True, kw_only=True)
class CalibrationRuns:
    """The runs of one site calibration, in the file's order."""

    name: str
    runs: tuple[CalibrationRun, ...]

    @property
    def n_used(self) -> int:
        """Runs that went into the influence lines."""
        return sum(r.used for r in self.runs)


def _header(path: Path) -> list[str]:
    try:
        with open(path, newline="", encoding="utf-8", errors="replace") as f:
            return [h.strip() for h in next(csv.reader(f), [])]
    except OSError:
        return []


def is_runs_table(path: str | os.PathLike) -> bool:
    """Whether the CSV file at ``path`` is a calibration runs table (see the module
    docstring)."""
    header = _header(Path(path))
    return bool(header) and header[0] == "run" and all(c in header for c in _REQUIRED)


def _column(header: list[str], *names: str) -> int | None:
    for name in names:
        if name in header:
            return header.index(name)
    return None


def read_calibration_runs(path: str | os.PathLike) -> CalibrationRuns:
    """The runs of a ``calibration_runs.csv`` (see the module docstring)."""
    p = Path(path)
    try:
        with open(p, newline="", encoding="utf-8") as f:
            lines = [r for r in csv.reader(f)]
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: cannot read: {exc}") from None
    header = [h.strip() for h in (lines[0] if lines else [])]
    missing = [c for c in _REQUIRED if c not in header]
    if missing:
        raise InputError(f"{p}: not a calibration runs table (no column "
                         f"{', '.join(missing)})")
    cols = {"speed": _column(header, "speed (m/s)", "speed_m_s"),
            "lateral": _column(header, "lateral (m)", "lateral (gauge index)", "lateral"),
            "scale": _column(header, "scale"),
            "residual": _column(header, "residual"), "status": _column(header, "status"),
            "time": _column(header, "time")}

    def cell(row: list[str], key: str) -> str:
        k = cols[key]
        return row[k].strip() if k is not None and k < len(row) else ""

    def number(row: list[str], key: str, line: int) -> float | None:
        text = cell(row, key)
        if not text:
            return None
        try:
            v = float(text)
        except ValueError:
            raise InputError(f"{p}: line {line}: column {key}: {text!r} is not a "
                             "number") from None
        return v if math.isfinite(v) else None

    def when(row: list[str], line: int) -> datetime | dtime | None:
        text = cell(row, "time")
        if not text:
            return None
        try:
            return time_cell(None, line, "time", text)
        except InputError:
            raise InputError(f"{p}: line {line}: column time: {text!r} is not an ISO 8601 "
                             "time") from None

    runs = []
    for line, row in enumerate(lines[1:], start=2):
        if not row or not row[0].strip():
            continue
        runs.append(CalibrationRun(
            name=row[0].strip(), speed=number(row, "speed", line),
            lateral=number(row, "lateral", line), scale=number(row, "scale", line),
            residual=number(row, "residual", line), status=cell(row, "status") or "used",
            time=when(row, line)))
    return CalibrationRuns(name=p.name, runs=tuple(runs))
