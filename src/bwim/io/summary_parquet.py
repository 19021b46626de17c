"""``summary.parquet``: the summary's rows as a typed table (Apache Parquet, via pyarrow).

Contract
--------
* The same columns as ``summary.csv``, in the same order and with the same names
  (:data:`bwim.io.summary.COLUMNS`: units in the names, weights kN, spacings m, speed
  m/s), typed instead of text: numbers ``float64`` or ``int32``, the per-axle lists
  ``list<float64>``, ``flags`` ``list<string>``, ``time`` a ``timestamp[us]`` when every
  known time has a date (else ``time64[us]`` when every one is a time of day only, else
  ISO 8601 text), an unknown value null.  The file's metadata carries
  ``bwim.columns_version`` = :data:`VERSION` (version 2 added ``group_laterals``; a
  version-1 file reads with it empty).  Times keep their microseconds.
* :func:`write_summary_parquet` writes atomically (a temporary file in the same folder,
  then renamed): no half-written file.  :func:`read_summary_parquet` reads such a file
  back into :class:`~bwim.summary.SummaryRow` (weights in N; to round-off: they are
  stored in kN).
* pyarrow is an optional dependency (``pip install bwim[parquet]``); without it both
  functions raise :class:`~bwim.errors.InputError` saying so.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from datetime import datetime
from datetime import time as dtime
from typing import Any

from bwim.errors import InputError
from bwim.io.atomic import atomic_output
from bwim.io.csvtable import time_cell
from bwim.io.summary import COLUMNS
from bwim.summary import SummaryRow

__all__ = ["VERSION", "read_summary_parquet", "require_pyarrow", "write_summary_parquet"]

#: The column list's version stored in the file's metadata.
VERSION = "2"
_KN = 1000.0
_FLOAT = ("speed_m_s", "gvw_kN", "lateral", "confidence", "residual", "drift_factor",
          "lambda")
_INT = ("n_axles", "vehicle", "lane")
_LISTS = ("axle_spacings_m", "axle_weights_kN", "group_weights_kN", "group_laterals")
#: Columns a version-1 file lacks (read as not measured).
_SINCE_V2 = ("group_laterals",)
_TEXT = ("record", "direction", "class", "lateral_unit", "quality", "method",
         "drift_method", "status", "reason")


def require_pyarrow() -> Any:
    """pyarrow (with its parquet module), or an InputError saying how to install it."""
    try:
        import pyarrow
        import pyarrow.parquet  # the submodule, used as pyarrow.parquet
    except ImportError:
        raise InputError("Parquet needs pyarrow: pip install 'bwim[parquet]'") from None
    return pyarrow


def _columns(rows: list[SummaryRow]) -> dict[str, list]:
    return {
        "record": [r.record for r in rows],
        "n_axles": [r.n_axles for r in rows],
        "speed_m_s": [r.speed for r in rows],
        "axle_spacings_m": [[float(v) for v in r.axle_spacings] for r in rows],
        "axle_weights_kN": [[float(v) / _KN for v in r.axle_weights] for r in rows],
        "gvw_kN": [None if r.gvw is None else float(r.gvw) / _KN for r in rows],
        "flags": [list(r.flags) for r in rows],
        "vehicle": [r.vehicle for r in rows],
        "time": [r.time for r in rows],
        "lane": [r.lane for r in rows],
        "direction": [r.direction for r in rows],
        "class": [r.vehicle_class for r in rows],
        "group_weights_kN": [[float(v) / _KN for v in r.group_weights] for r in rows],
        "lateral": [r.lateral for r in rows],
        "lateral_unit": [r.lateral_unit for r in rows],
        "group_laterals": [[float(v) for v in r.group_laterals] for r in rows],
        "confidence": [r.confidence for r in rows],
        "residual": [r.residual for r in rows],
        "quality": [r.quality for r in rows],
        "method": [r.method for r in rows],
        "drift_factor": [r.drift_factor for r in rows],
        "drift_method": [r.drift_method for r in rows],
        "lambda": [r.lam for r in rows],
        "status": [r.status for r in rows],
        "reason": [r.reason for r in rows],
    }


def _time_type(pa: Any, times: list) -> Any:
    known = [t for t in times if t is not None]
    if all(isinstance(t, datetime) for t in known):
        return pa.timestamp("us")
    if all(isinstance(t, dtime) for t in known):
        return pa.time64("us")
    return pa.string()


def write_summary_parquet(path: str | os.PathLike, rows: Iterable[SummaryRow]) -> None:
    """Write ``rows`` to ``path`` as Parquet (see the module contract)."""
    pa = require_pyarrow()
    rows = list(rows)
    data = _columns(rows)
    types = {name: pa.float64() for name in _FLOAT}
    types.update({name: pa.int32() for name in _INT})
    types.update({name: pa.list_(pa.float64()) for name in _LISTS})
    types.update({name: pa.string() for name in _TEXT})
    types["flags"] = pa.list_(pa.string())
    types["time"] = _time_type(pa, data["time"])
    if types["time"] == pa.string():
        data["time"] = [None if t is None else t.isoformat(timespec="microseconds")
                        for t in data["time"]]
    schema = pa.schema([(name, types[name]) for name in COLUMNS],
                       metadata={"bwim.columns_version": VERSION})
    table = pa.table({name: pa.array(data[name], type=types[name]) for name in COLUMNS},
                     schema=schema)
    # the project's one atomic write (the usual file permissions, nothing left behind)
    with atomic_output(path) as tmp:
        try:
            pa.parquet.write_table(table, str(tmp))
        except OSError as exc:
            raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None


def read_summary_parquet(path: str | os.PathLike) -> tuple[SummaryRow, ...]:
    """The rows of a file :func:`write_summary_parquet` wrote, weights in N."""
    pa = require_pyarrow()
    try:
        table = pa.parquet.read_table(path)
    except (OSError, pa.ArrowInvalid) as exc:
        raise InputError(f"{path}: not a readable Parquet file ({exc})") from None
    missing = [c for c in COLUMNS if c not in table.column_names and c not in _SINCE_V2]
    if missing:
        raise InputError(f"{path}: not a bwim summary (no column {missing[0]!r})")
    cols = table.to_pydict()
    for c in _SINCE_V2:  # a version-1 file: not measured
        cols.setdefault(c, [[] for _ in range(table.num_rows)])
    rows = []
    for k in range(table.num_rows):
        time = cols["time"][k]
        if isinstance(time, str):
            try:
                time = time_cell(None, k, "time", time)
            except InputError as exc:
                raise InputError(f"{path}: row {k + 1}: {exc}") from None
        gvw = cols["gvw_kN"][k]
        rows.append(SummaryRow(
            record=cols["record"][k], vehicle=cols["vehicle"][k], status=cols["status"][k],
            time=time, lane=cols["lane"][k], direction=cols["direction"][k] or "",
            vehicle_class=cols["class"][k] or "", n_axles=cols["n_axles"][k],
            speed=cols["speed_m_s"][k], axle_spacings=tuple(cols["axle_spacings_m"][k]),
            axle_weights=tuple(v * _KN for v in cols["axle_weights_kN"][k]),
            gvw=None if gvw is None else gvw * _KN,
            group_weights=tuple(v * _KN for v in cols["group_weights_kN"][k]),
            flags=tuple(cols["flags"][k]), lateral=cols["lateral"][k],
            lateral_unit=cols["lateral_unit"][k] or "",
            group_laterals=tuple(cols["group_laterals"][k] or ()),
            confidence=cols["confidence"][k],
            residual=cols["residual"][k], quality=cols["quality"][k] or "",
            method=cols["method"][k] or "", drift_factor=cols["drift_factor"][k],
            drift_method=cols["drift_method"][k] or "", lam=cols["lambda"][k],
            reason=cols["reason"][k] or ""))
    return tuple(rows)
