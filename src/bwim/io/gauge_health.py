"""``gauge_health.csv``: the day's health of each gauge, beside a batch's summary.

Contract
--------
* :data:`COLUMNS` is the file's header, in order: ``gauge``, ``vehicles_judged`` (the
  vehicles whose gauges were judged), ``left_out`` (the vehicles this gauge was left out
  of, flagged ``gauge_fault:NAME``), then that count by the fault's kind (``flat``,
  ``clipped``, ``silent``, ``reversed``, ``gain``, ``drift``: docs/flags.md), then
  ``median_gain_ratio`` (the median of its response over what the other gauges
  predict, over the vehicles weighed alone; empty when there is none) and ``n_ratios``
  (how many vehicles that median is of).  One line per gauge.
* :func:`write_gauge_health` writes rows (mappings from column to value; integers as
  they are, the ratio with 4 decimals) atomically (:mod:`bwim.io.atomic`), in the order
  given.  A row without a column is an :class:`~bwim.errors.InputError`.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable, Mapping

from bwim.errors import InputError
from bwim.io.atomic import atomic_open

__all__ = ["COLUMNS", "GAUGE_HEALTH_NAME", "write_gauge_health"]

#: The table's file name in a batch's output folder.
GAUGE_HEALTH_NAME = "gauge_health.csv"
#: The header of ``gauge_health.csv``.
COLUMNS = ("gauge", "vehicles_judged", "left_out", "flat", "clipped", "silent", "reversed",
           "gain", "drift", "median_gain_ratio", "n_ratios")


def _cell(value: object) -> str:
    if isinstance(value, float):
        return "" if not math.isfinite(value) else f"{value:.4f}"
    return str(value)


def write_gauge_health(path: str | os.PathLike, rows: Iterable[Mapping[str, object]]) -> None:
    """Write the table (see the module docstring)."""
    cells = []
    for row in rows:
        missing = [c for c in COLUMNS if c not in row]
        if missing:
            raise InputError(f"gauge health row without {', '.join(missing)}")
        cells.append([_cell(row[c]) for c in COLUMNS])
    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COLUMNS)
        w.writerows(cells)
