"""Records on disk: a logger's CSV, and bwim's own HDF5.

Contract
--------
* CSV (what a logger writes): a header row with a time column (default ``time``, s) and
  one column per sensor named by the sensor's ``name``; one row per sample.  Sensor
  positions are not in the file: they come from the scenario (:func:`read_csv_record`
  takes the sensors).  Columns may come in any order; the record's channels follow the
  order of ``sensors``.  A missing sensor column, an unexpected column (unless
  ``allow_extra``), an empty cell, text that is not a number, a NaN or infinite sample,
  time that does not increase and an empty file each raise
  :class:`~bwim.errors.InputError` naming the file, the line and the column.
  :func:`write_csv_record` writes every number in its shortest exact form (``repr``), so
  that ``read_csv_record(write_csv_record(r))`` gives the same time and data bit for bit.
* The record's wall clock (:attr:`bwim.Record.clock`, the date and time at record time 0)
  is a comment line ``# clock = 2015-10-01T09:45:52.576000`` (ISO 8601) before the header
  when it is known: :func:`read_csv_record` reads it from any ``#`` line before the header
  of that form (a malformed one is refused, naming the line), and files without it (or
  older bwim's) read with ``clock = None``; other readers skip it as a comment.
* HDF5 (bwim's records, simulated or measured): :func:`write_record` /
  :func:`read_record` round-trip a :class:`~bwim.Record` exactly: time, data, sensors,
  passages, truths, the VBI convergence, the simulation settings and the clock (an ISO
  8601 attribute ``clock``; a file without it, as older bwim wrote, reads as None).
  :func:`write_records` / :func:`read_records` hold several records in one file
  (``records/0``, ``records/1``, …); ``read_records`` also reads a single-record file.
* Every writer is atomic (:mod:`bwim.io.atomic`): no half-written file, ever.

HDF5 layout of one record (a group, or the file root)::

    attrs [clock] (ISO 8601 text, if known)
    time (n_t,)  data (n_t, n_sensors)
    sensors/ x y kind name
    passages/ count; 0/ attrs speed lane delay [track_width]; axle_spacings
    truths/ count; 0/ wheel_forces axle_forces static_wheel_loads static_axle_loads
                      contact_lost
    convergence/ attrs method iterations change converged      (if present)
    settings/ attrs approach tail                               (if present)
"""

from __future__ import annotations

import csv
import io
import os
import re
from collections.abc import Iterator, Sequence
from datetime import datetime
from pathlib import Path

import h5py
import numpy as np

from bwim.errors import InputError
from bwim.io import _hdf5 as h5
from bwim.io._csv import check_time, decimal_resolution, open_regular, read_numeric_csv
from bwim.io.atomic import atomic_open
from bwim.records import Passage, Record, SimulationSettings, Truth, VBIConvergence
from bwim.sensors import Sensor

__all__ = [
    "read_csv_record",
    "read_record",
    "read_records",
    "write_csv_record",
    "write_record",
    "write_records",
]


# --- CSV ---------------------------------------------------------------------------------
_CLOCK_LINE = re.compile(r"#\s*clock\s*=\s*(.*?)\s*")


def _csv_clock(path: Path) -> datetime | None:
    """The ``# clock = ...`` line before a CSV record's header, if there is one (the file
    has been read once already: a regular file of bounded lines)."""
    with open_regular(path) as raw, io.TextIOWrapper(raw, encoding="utf-8-sig") as f:
        for k, line in enumerate(f, start=1):
            s = line.strip()
            if s and not s.startswith("#"):
                return None                          # the header: no clock line before it
            m = _CLOCK_LINE.fullmatch(s)
            if m:
                try:
                    return datetime.fromisoformat(m.group(1))
                except ValueError:
                    raise InputError(f"{path}: line {k}: {m.group(1)[:40]!r} is not an ISO "
                                     "8601 date and time (the record's clock)") from None
    return None


def read_csv_record(
    path: str | os.PathLike,
    sensors: Sequence[Sensor],
    passage: Passage | Sequence[Passage] | None = None,
    *,
    time_column: str = "time",
    allow_extra: bool = False,
    scale: float = 1.0,
    delimiter: str | None = None,
) -> Record:
    """A record from a logger's CSV file.

    Parameters
    ----------
    path : str or path
        The CSV file (see the module docstring).
    sensors : sequence of Sensor
        The channels to read, by name; their positions and kinds come from here.
    passage : Passage or sequence of Passage, optional
        The vehicle crossing(s) the record holds (speed, lane, axle layout, delay).
    time_column : str
        Name of the time column, s.
    allow_extra : bool
        Ignore columns that are neither time nor a sensor (default: an error).
    scale : float
        Factor applied to the readings (e.g. ``1e-6`` for a logger writing µε).
    delimiter : str, optional
        Field separator (default: ``,``, or ``;`` / tab if the header has no comma).

    Returns
    -------
    Record
    """
    p = Path(path)
    sensors = tuple(sensors)
    if not sensors:
        raise InputError(f"{p}: no sensors given to read")
    if not np.isfinite(scale) or scale == 0:
        raise InputError(f"scale must be a finite non-zero factor, got {scale!r}")
    wanted = [s.name for s in sensors]
    if len(set(wanted)) != len(wanted):
        dup = next(n for n in wanted if wanted.count(n) > 1)
        raise InputError(f"two sensors are named {dup!r}; CSV columns need distinct names")
    if time_column in wanted:
        raise InputError(f"a sensor is named like the time column {time_column!r}")
    names, values, lines = read_numeric_csv(p, delimiter=delimiter)
    if time_column not in names:
        raise InputError(f"{p}: no time column {time_column!r}; columns: {', '.join(names)}")
    missing = [n for n in wanted if n not in names]
    if missing:
        raise InputError(f"{p}: no column for sensor {missing[0]!r}"
                         + (f" (and {len(missing) - 1} more)" if len(missing) > 1 else "")
                         + f"; columns: {', '.join(names)}")
    extra = [n for n in names if n != time_column and n not in wanted]
    if extra and not allow_extra:
        raise InputError(f"{p}: column {extra[0]!r} is not a sensor of the scenario "
                         "(remove it, or allow extra columns)")
    t = values[:, names.index(time_column)]
    if t.size < 2:
        raise InputError(f"{p}: a record needs at least two samples, got {t.size}")
    # uniform sampling within 1 % of the step (plus how finely the file writes time):
    # dropped samples or a jittered clock would put every axle in the wrong place
    # (a clock on a coarse decimal grid is exact: the rounding allowance is capped at a
    # tenth of the step, so a dropped sample is never taken for rounding)
    step = float(np.median(np.diff(t)))
    check_time(t, lines, where=p, tolerance=0.01,
               resolution=min(decimal_resolution(t), 0.1 * abs(step)))
    data = values[:, [names.index(n) for n in wanted]] * scale
    if passage is None:
        passages: tuple[Passage, ...] = ()
    elif isinstance(passage, Passage):
        passages = (passage,)
    else:
        passages = tuple(passage)
    return Record(time=t, data=data, sensors=sensors, passages=passages, clock=_csv_clock(p))


def _csv_lines(values: np.ndarray) -> Iterator[str]:
    """One CSV line per row, each number in its shortest exact form."""
    for row in values.tolist():
        yield ",".join(map(repr, row)) + "\n"


def write_csv_record(
    record: Record, path: str | os.PathLike, *, time_column: str = "time"
) -> None:
    """Write a record's time and readings as CSV (header: time, then sensor names), after
    a ``# clock = ...`` line when the record's clock is known.

    Positions, passages and truths are not written (use :func:`write_record` for them).
    """
    names = [s.name for s in record.sensors]
    if time_column in names:
        raise InputError(f"a sensor is named like the time column {time_column!r}")
    buf = io.StringIO()
    if record.clock is not None:
        buf.write(f"# clock = {record.clock.isoformat()}\n")
    csv.writer(buf, lineterminator="\n").writerow([time_column, *names])
    with atomic_open(path, newline="") as f:
        f.write(buf.getvalue())
        for line in _csv_lines(np.column_stack([record.time, record.data])):
            f.write(line)


# --- HDF5 --------------------------------------------------------------------------------
def _put_truth(g: h5py.Group, truth: Truth) -> None:
    for name in ("wheel_forces", "axle_forces", "static_wheel_loads", "static_axle_loads"):
        g.create_dataset(name, data=np.asarray(getattr(truth, name), dtype=float))
    g.create_dataset("contact_lost", data=np.asarray(truth.contact_lost, dtype=bool))


def _get_truth(g: h5py.Group) -> Truth:
    return Truth(
        wheel_forces=h5.array(g, "wheel_forces"), axle_forces=h5.array(g, "axle_forces"),
        static_wheel_loads=h5.array(g, "static_wheel_loads"),
        static_axle_loads=h5.array(g, "static_axle_loads"),
        contact_lost=h5.array(g, "contact_lost").astype(bool),
    )


def _put_record(g: h5py.Group, record: Record) -> None:
    if not isinstance(record, Record):
        raise InputError(f"expected a bwim.Record, got {type(record).__name__}")
    if record.clock is not None:
        g.attrs["clock"] = record.clock.isoformat()
    g.create_dataset("time", data=record.time)
    g.create_dataset("data", data=record.data)
    h5.put_sensors(g, record.sensors)
    h5.put_list(g, "passages", record.passages, h5.put_passage)
    h5.put_list(g, "truths", record.truths, _put_truth)
    c = record.convergence
    if c is not None:
        cg = g.create_group("convergence")
        cg.attrs["method"] = c.method
        cg.attrs["iterations"] = int(c.iterations)
        cg.attrs["change"] = float(c.change)
        cg.attrs["converged"] = bool(c.converged)
    if record.settings is not None:
        sg = g.create_group("settings")
        sg.attrs["approach"] = float(record.settings.approach)
        sg.attrs["tail"] = float(record.settings.tail)


def _get_record(g: h5py.Group) -> Record:
    conv = None
    if "convergence" in g:
        cg = g["convergence"]
        conv = VBIConvergence(method=str(h5.attr(cg, "method")),
                              iterations=int(h5.attr(cg, "iterations")),
                              change=float(h5.attr(cg, "change")),
                              converged=bool(h5.attr(cg, "converged")))
    settings = None
    if "settings" in g:
        sg = g["settings"]
        settings = SimulationSettings(approach=float(h5.attr(sg, "approach")),
                                      tail=float(h5.attr(sg, "tail")))
    clock = g.attrs.get("clock")
    if clock is not None:
        if isinstance(clock, bytes):
            clock = clock.decode("utf-8")
        clock = datetime.fromisoformat(str(clock))  # ValueError: a damaged file
    return Record(
        time=h5.array(g, "time"), data=h5.array(g, "data"), sensors=h5.get_sensors(g),
        passages=h5.get_list(g, "passages", h5.get_passage),
        truths=h5.get_list(g, "truths", _get_truth), convergence=conv, settings=settings,
        clock=clock,
    )


def write_record(record: Record, path: str | os.PathLike) -> None:
    """Write one record to an HDF5 file (exact round trip with :func:`read_record`)."""
    if not isinstance(record, Record):
        raise InputError(f"expected a bwim.Record, got {type(record).__name__}")
    with h5.h5_writer(path, "record") as f:
        _put_record(f, record)


def write_records(records: Sequence[Record], path: str | os.PathLike) -> None:
    """Write several records to one HDF5 file (``records/0``, ``records/1``, …)."""
    records = list(records)
    if not records:
        raise InputError("no records to write")
    with h5.h5_writer(path, "records") as f:
        h5.put_list(f, "records", records, _put_record)


def read_record(path: str | os.PathLike) -> Record:
    """The record of an HDF5 file written by :func:`write_record` (or a one-record file
    of :func:`write_records`)."""
    records = read_records(path)
    if len(records) != 1:
        raise InputError(f"{path}: holds {len(records)} records; read them with read_records")
    return records[0]


def read_records(path: str | os.PathLike) -> tuple[Record, ...]:
    """All records of an HDF5 file of :func:`write_records` or :func:`write_record`."""
    with h5.h5_reader(path, "record", "records") as f:
        if f.attrs["bwim_format"] == "record":
            return (_get_record(f),)
        return h5.get_list(f, "records", _get_record)
