"""Logger text files of a real installation: one event per file, read into a Record.

Contract
--------
* A :class:`LoggerFormat` says what the columns of a logger file are: ``columns`` names
  each column in file order; ``"-"`` skips a column (its content is never parsed, so it
  may hold text such as a status); ``"time"`` (at most once) is the time column, s; the
  columns that ``clock`` names (:class:`~bwim.io.clock.ClockSpec`: a clock column, a date
  column) hold the wall-clock time as text or numbers.  Every other name is a channel, in
  that order, with a :class:`~bwim.SensorKind` from ``kinds`` (default ``strain_x``; axle
  detectors are ``axle_detector``).
* :func:`read_logger` returns a :class:`~bwim.Record` with ``passages = ()``: ``time`` is
  the time column **as written** (s, not shifted: a clock time of day stays one; written
  more coarsely than :data:`COARSE_TIME` of its step and rounded unevenly, the uniform
  clock it was rounded from, by least squares), or ``k / sampling_rate`` (k = 0, 1, ...)
  without a time column; ``data`` (n_t, n_channels) is the file's numbers times ``scale``
  (logger units to strain; the default 1.0 keeps the file's units, which is right for data
  already in strain and for influence-line weighing, which works on uncalibrated units);
  ``sensors`` are one :class:`~bwim.Sensor` per channel, the caller's (by name) when given,
  else ``Sensor(name=..., kind=...)`` without a position; ``clock`` is the wall-clock date
  and time at record time 0 (:func:`bwim.io.clock.logger_clock`): by default from a
  timestamp in the file name (``2015-10-01-09-45-52-576``, ``20151001_094552``, ISO 8601),
  None when the name has none; ``LoggerFormat.clock`` sets a name pattern, a clock column
  or a date and time column pair instead (see :mod:`bwim.io.clock`).
* Text layout.  Any file extension.  UTF-8, a byte-order mark ignored; LF, CRLF or CR line
  endings; blank lines and lines whose first non-blank character is ``#`` are skipped
  anywhere (no comment after data on a line); ``skip_lines`` raw lines are dropped first
  (a logger's preamble).  The delimiter is ``,``, ``;``, tab or whitespace (``" "``: any
  run of spaces and tabs); auto-detected as the first of ``;``, tab, ``,``, whitespace
  that splits the first content line into ``len(columns)`` fields.  The header (one row
  of names, at most) is auto-detected: a first content row that holds the columns' own
  names (numbers or not), or none of whose channel and time fields is a number (a row of
  NaN excepted: data, refused as such), is a header, one with numbers is data, a mix is
  refused.  A header
  must have ``len(columns)`` fields; its names need not equal ``columns``.  A trailing
  delimiter is allowed: one empty field past the last column is dropped.  A field may be
  enclosed in double quotes (no delimiter or quote inside).  Numbers are decimal ASCII
  (``1``, ``-2.5``, ``.5``, ``3e-06``); with ``decimal=","`` the decimal mark is a comma,
  which needs a ``;``, tab or whitespace delimiter (auto-detection then never picks
  ``,``), and a ``.`` between digits is refused (a thousands separator: ``1.234``).
  Every number is read to the nearest double, exactly as ``float`` reads it.
* Refused with an :class:`~bwim.errors.InputError` whose one-line message starts with the
  file and names the line (and column) where there is one: a missing, unreadable, non-UTF-8
  or empty file; a path that is not a regular file (a folder, a FIFO, a device: refused at
  once, never read); a file larger than ``max_bytes`` (refused before reading); a data
  array (estimated from the file's size and the length of its first lines, before it is
  allocated) over the memory limit (:func:`bwim.limits.check_memory`,
  ``BWIM_MEMORY_LIMIT``); a line longer than the format allows or a field longer than
  ``max_field`` characters; a row with a missing or extra field; an empty field, text that
  is not a number (a number written with a decimal comma while ``decimal`` is ``"."``:
  the message hints ``decimal = ","``), NaN or an infinite sample in a channel or the time
  column (except that an empty or NaN field of a ``temperature`` channel is a gap, read
  as NaN: a temperature probe that drops out does not lose the record); fewer than
  ``min_samples`` or more than ``max_samples`` rows; time that goes back or repeats, a
  dropped sample (a step over 1.5 x the median step) or jitter (a step
  off the median by more than ``time_tolerance`` of it, plus one unit of the file's last
  written time decimal, or less when the steps show less rounding: 100 Hz written to 2
  decimals steps exactly 0.01 s); a time column that disagrees with ``sampling_rate``; a clipped
  channel (see :func:`read_logger`); a clock that cannot be read (see
  :mod:`bwim.io.clock`).  A problem of the text (lines, fields, numbers, the row count) is
  reported at the first line that has one, before the checks of the whole record (time,
  clipping, clock).
* Streaming, bounded memory. The file is read once, in chunks of at most :data:`CHUNK`
  characters (whole lines), each parsed at once (split into rows and fields and its plain
  decimals read in one compiled pass over its bytes: :mod:`bwim.io.field_kernels`; the
  few other numbers, such as ``1e-06``, one by one as the line-by-line path reads them; a
  chunk with anything unusual is re-read line by line, which gives the same numbers or the
  precise message) into the record's data array, sized from the estimate and scaled in
  place: the reader holds the data array, the time column (and a few arrays of its length
  while it is checked) and one chunk's text and work arrays, whatever the file's length;
  the memory estimate checked against the limit counts all of these.
"""

from __future__ import annotations

import io
import math
import os
import re
from bisect import bisect_right
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TextIO

import numpy as np

from bwim.errors import InputError, parse_enum, require_positive
from bwim.io._csv import check_time, open_regular, rounding
from bwim.io.clock import ClockRow, ClockSpec, logger_clock
from bwim.io.field_kernels import GAP, ChunkRows, Scan, scan_rows
from bwim.io.field_kernels import SKIP as SKIP_SLOT
from bwim.io.field_kernels import TIME as TIME_SLOT
from bwim.limits import check_memory
from bwim.records import Record
from bwim.sensors import Sensor, SensorKind

__all__ = ["CHUNK", "DELIMITERS", "MAX_LOGGER_BYTES", "LoggerFormat", "read_logger"]

DELIMITERS = (";", "\t", ",", " ")
"""Delimiters in the order auto-detection tries them (``" "``: any run of whitespace)."""

SKIP = "-"
TIME = "time"
MiB = 2**20
#: A time column written more coarsely than this share of its step (600 Hz to 4 decimals:
#: 0.06) is taken for a uniform clock rounded: the record's times are the least-squares
#: line through it (its median step would be a rounded step, up to 2 % off the rate).
COARSE_TIME = 1e-3
#: Logger files larger than this (bytes) are refused from their size, before reading.
MAX_LOGGER_BYTES = 256 * MiB

CHUNK = 2**16
"""Characters of text parsed at once (whole lines are added to finish the last one)."""

#: Bytes of work memory per character of a chunk while it is parsed (its bytes, its rows'
#: numbers and line numbers, the list of fields that are not plain decimals: at most 30
#: for ASCII text, see bwim.io.field_kernels), for the memory estimate.
_WORK_PER_CHAR = 32
#: Arrays of the time column's length alive besides the data while the record is checked
#: (time steps, their median, masks), for the memory estimate; a mask of the data's shape
#: (finite samples, clipping) is counted too.
_TIME_TEMPORARIES = 4

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_GROUPED = re.compile(r"\d\.\d", re.ASCII)  #: a '.' between digits (decimal comma files)
_NON_FINITE = {"nan": "NaN", "inf": "infinite", "infinity": "infinite"}


def _delim_name(d: str) -> str:
    return {"\t": "tab", " ": "whitespace"}.get(d, repr(d))


@dataclass(frozen=True, kw_only=True)
class LoggerFormat:
    """The layout of a logger's text files (see the module docstring).

    Parameters
    ----------
    columns : sequence of str
        One name per column, in file order: ``"time"`` (at most once), ``"-"`` (skipped),
        a column of ``clock``, or a channel name (unique).
    delimiter : str, optional
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (any run of spaces/tabs); None: detected.
    header : bool, optional
        Whether the first content row names the columns; None: detected.
    sampling_rate : float, optional
        Samples per second, Hz: required without a time column; with one, the file's rate
        must agree with it.
    scale : float, sequence of float or mapping
        Factor from logger units to the record's units (strain, m): one number for every
        channel, one per channel in channel order, or ``{channel: factor}`` (channels not
        named keep 1.0).  Finite and non-zero.  Default 1.0: the file's units.
    decimal : str
        Decimal mark, ``"."`` (default) or ``","`` (then the delimiter is not ``,``).
    kinds : mapping of str to SensorKind or str
        Sensor kind of channels by name (default ``strain_x``).
    skip_lines : int
        Raw lines to drop at the start of the file (a logger's preamble), >= 0.
    clock : ClockSpec, optional
        Where the files' wall-clock time is (:mod:`bwim.io.clock`); None: a timestamp in
        the file name in a common form, if there is one.  Its ``column`` and
        ``date_column`` (other than ``"time"``) must be columns of ``columns``.
    """

    columns: tuple[str, ...]
    delimiter: str | None = None
    header: bool | None = None
    sampling_rate: float | None = None
    scale: float | tuple[float, ...] | Mapping[str, float] = 1.0
    decimal: str = "."
    kinds: Mapping[str, SensorKind] = field(default_factory=dict)
    skip_lines: int = 0
    clock: ClockSpec | None = None
    _channels: tuple[str, ...] = field(default=(), init=False, repr=False, compare=False)
    _sensors: tuple[Sensor, ...] = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        cols = self.columns
        if isinstance(cols, str) or not isinstance(cols, Sequence) or not cols:
            raise InputError(f"LoggerFormat.columns must be a non-empty list of names, "
                             f"got {cols!r}")
        for j, c in enumerate(cols):
            if not isinstance(c, str) or not c.strip() or c != c.strip():
                raise InputError(f"LoggerFormat.columns[{j}] must be a non-empty name without "
                                 f"surrounding spaces, got {c!r}")
            if c != SKIP and c in cols[:j]:
                raise InputError(f"LoggerFormat.columns: {c!r} appears twice")
        cols = tuple(cols)
        object.__setattr__(self, "columns", cols)
        if self.clock is not None:
            if not isinstance(self.clock, ClockSpec):
                raise InputError(f"LoggerFormat.clock must be a bwim.io.clock.ClockSpec or "
                                 f"None, got {type(self.clock).__name__}")
            for c in self.clock.columns:
                if c not in cols:
                    raise InputError(f"LoggerFormat.clock: the column {c!r} is not one of "
                                     f"the columns {list(cols)}")
            if self.clock.column == TIME and TIME not in cols:
                raise InputError("LoggerFormat.clock: column 'time' (the time of day) needs "
                                 "a 'time' column")
        other = (SKIP, TIME, *self.clock_columns)
        object.__setattr__(self, "_channels", tuple(c for c in cols if c not in other))
        channels = self.channels
        if not channels:
            raise InputError(f"LoggerFormat.columns names no channel (only 'time', '-' and "
                             f"clock columns): {list(cols)}")
        if self.delimiter is not None and self.delimiter not in DELIMITERS:
            raise InputError(f"LoggerFormat.delimiter must be one of ',', ';', tab or ' ' "
                             f"(whitespace), or None to detect it; got {self.delimiter!r}")
        if self.header not in (None, True, False):
            raise InputError(f"LoggerFormat.header must be true, false or None (detect), "
                             f"got {self.header!r}")
        if self.decimal not in (".", ","):
            raise InputError(f"LoggerFormat.decimal must be '.' or ',', got {self.decimal!r}")
        if self.decimal == "," and self.delimiter == ",":
            raise InputError("LoggerFormat: decimal ',' needs a delimiter other than ','")
        if self.sampling_rate is not None:
            object.__setattr__(self, "sampling_rate",
                               require_positive("LoggerFormat.sampling_rate",
                                                self.sampling_rate))
        elif not self.has_time:
            raise InputError("LoggerFormat: without a 'time' column the sampling_rate is "
                             "needed")
        if (isinstance(self.skip_lines, bool) or not isinstance(self.skip_lines, int)
                or self.skip_lines < 0):
            raise InputError(f"LoggerFormat.skip_lines must be an integer >= 0, got "
                             f"{self.skip_lines!r}")
        object.__setattr__(self, "scale", self._check_scale(self.scale, channels))
        if not isinstance(self.kinds, Mapping):
            raise InputError(f"LoggerFormat.kinds must map channel names to sensor kinds, "
                             f"got {self.kinds!r}")
        kinds = {}
        for name, kind in self.kinds.items():
            if name not in channels:
                raise InputError(f"LoggerFormat.kinds: {name!r} is not a channel of the "
                                 f"columns {list(channels)}")
            try:
                kinds[name] = parse_enum(SensorKind, kind, "sensor kind")
            except InputError as exc:
                raise InputError(f"LoggerFormat.kinds[{name!r}]: {exc}") from None
        object.__setattr__(self, "kinds", MappingProxyType(kinds))
        object.__setattr__(self, "_sensors", tuple(Sensor(name=c, kind=self.kind_of(c))
                                                   for c in channels))

    @staticmethod
    def _check_scale(scale, channels):
        def factor(what, v):
            if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                    or not math.isfinite(v) or v == 0:
                raise InputError(f"LoggerFormat.scale{what} must be a finite non-zero "
                                 f"number, got {v!r}")
            return float(v)

        if isinstance(scale, Mapping):
            unknown = [k for k in scale if k not in channels]
            if unknown:
                raise InputError(f"LoggerFormat.scale: {unknown[0]!r} is not a channel of "
                                 f"the columns {list(channels)}")
            return MappingProxyType({k: factor(f"[{k!r}]", v) for k, v in scale.items()})
        if isinstance(scale, np.ndarray) and scale.ndim == 1:
            scale = scale.tolist()
        if isinstance(scale, Sequence) and not isinstance(scale, str):
            if len(scale) != len(channels):
                raise InputError(f"LoggerFormat.scale has {len(scale)} factors for "
                                 f"{len(channels)} channels {list(channels)}")
            return tuple(factor(f"[{j}]", v) for j, v in enumerate(scale))
        return factor("", scale)

    @property
    def clock_columns(self) -> tuple[str, ...]:
        """The columns the clock reads (other than ``"time"``), in ``clock``'s order."""
        return () if self.clock is None else self.clock.columns

    @property
    def channels(self) -> tuple[str, ...]:
        """The channel names (columns other than ``"time"``, ``"-"`` and the clock's), in
        file order."""
        return self._channels

    @property
    def has_time(self) -> bool:
        """Whether the files have a time column."""
        return TIME in self.columns

    @property
    def scales(self) -> np.ndarray:
        """Scale factor of each channel, shape (n_channels,)."""
        s = self.scale
        if isinstance(s, Mapping):
            return np.array([s.get(c, 1.0) for c in self.channels])
        return np.broadcast_to(np.asarray(s, dtype=float), (len(self.channels),)).copy()

    def kind_of(self, channel: str) -> SensorKind:
        """The sensor kind of a channel (``strain_x`` unless ``kinds`` says otherwise)."""
        return self.kinds.get(channel, SensorKind.STRAIN_X)


# --- reading -----------------------------------------------------------------------------

def _channel_sensors(fmt: LoggerFormat, sensors: Sequence[Sensor] | None) -> tuple[Sensor, ...]:
    given: dict[str, Sensor] = {}
    for k, s in enumerate(() if sensors is None else sensors):
        if not isinstance(s, Sensor):
            raise InputError(f"sensors[{k}] must be a bwim.Sensor, got {type(s).__name__}")
        if s.name in given:
            raise InputError(f"sensors: two sensors are named {s.name!r}")
        if s.name not in fmt.channels:
            raise InputError(f"sensors: {s.name!r} is not a channel of the logger columns "
                             f"{list(fmt.channels)}")
        if s.name in fmt.kinds and fmt.kinds[s.name] is not s.kind:
            raise InputError(f"sensors: {s.name!r} is a {s.kind.value} sensor but the logger "
                             f"format says {fmt.kinds[s.name].value}")
        given[s.name] = s
    if not given:
        return fmt._sensors                         # immutable: shared by its records
    return tuple(given.get(c) or Sensor(name=c, kind=fmt.kind_of(c)) for c in fmt.channels)


def _limit(name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
    return value


def _split(text: str, delim: str, n: int) -> list[str]:
    fields = text.split() if delim == " " else text.split(delim)
    if len(fields) == n + 1 and not fields[-1].strip():
        fields.pop()                                # a trailing delimiter
    return fields


def _clean(field_: str) -> str:
    s = field_.strip()
    if len(s) >= 2 and s[0] == '"' and s[-1] == '"':
        s = s[1:-1].strip()
    return s


def _detect_delimiter(text: str, n: int, decimal: str, where: Path, line: int) -> str:
    candidates = [d for d in DELIMITERS if not (decimal == "," and d == ",")]
    for d in candidates:
        if len(_split(text, d, n)) == n:
            return d
    names = ", ".join(_delim_name(d) for d in candidates)
    raise InputError(f"{where}: line {line}: no delimiter ({names}) splits it into the "
                     f"{n} columns of the format")


def _point(s: str, comma: bool) -> str:
    """A field with a decimal comma as Python reads it; with a comma as the mark, a '.'
    between digits may be a thousands separator ('1.234' is 1234 there, not 1.234), so
    the field is left unreadable."""
    if not comma:
        return s
    return "?" if _GROUPED.search(s) else s.replace(",", ".")


def _is_number(s: str, decimal: str) -> bool:
    return _NUMBER.fullmatch(_point(s, decimal == ",")) is not None


def _is_gap(s: str) -> bool:
    """An empty or NaN field: a gap, in a column that may have gaps."""
    return not s or s.lower().lstrip("+-") == "nan"


def _bad_field(s: str, decimal: str) -> str:
    if not s:
        return "empty field"
    kind = _NON_FINITE.get(s.lower().lstrip("+-"))
    if kind:
        return f"{kind} sample"
    shown = s if len(s) <= 20 else s[:20] + "..."
    if decimal == "." and "," in s and _NUMBER.fullmatch(s.replace(",", ".")):
        return f'{shown!r} is not a number (a decimal comma? set decimal = ",")'
    if decimal == "," and _GROUPED.search(s):
        return f"{shown!r} is not a number (a '.' with decimal = ',': a thousands separator?)"
    return f"{shown!r} is not a number"


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and length of each run of True in a boolean vector."""
    edges = np.diff(np.concatenate([[0], mask.view(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    return starts, np.flatnonzero(edges == -1) - starts


def _check_clipping(values: np.ndarray, names: Sequence[str], kinds: Sequence[SensorKind],
                    lines, where: Path, run: int) -> None:
    highs, lows = values.max(axis=0), values.min(axis=0)
    # a channel can only be clipped where at least `run` samples sit at its extreme
    at_high = (values == highs).sum(axis=0) >= run
    at_low = (values == lows).sum(axis=0) >= run
    for j, (name, kind) in enumerate(zip(names, kinds, strict=True)):
        if kind is SensorKind.AXLE_DETECTOR or not (at_high[j] or at_low[j]):
            continue
        col = values[:, j]
        for label, extreme in (("maximum", highs[j]), ("minimum", lows[j])):
            if col[0] == extreme or col[-1] == extreme:
                continue                    # the channel's resting value, not a saturation
            starts, lengths = _runs(col == extreme)
            long = np.flatnonzero(lengths >= run)
            if long.size:
                k = int(starts[long[0]])
                raise InputError(
                    f"{where}: channel {name!r} sits at its {label} {extreme:g} for "
                    f"{int(lengths[long[0]])} consecutive samples from line {lines[k]} "
                    f"(clipped: logger saturation?; clip_run = {run})")


def read_logger(
    path: str | os.PathLike,
    fmt: LoggerFormat,
    *,
    sensors: Sequence[Sensor] | None = None,
    max_bytes: int = MAX_LOGGER_BYTES,
    max_samples: int = 1_000_000,
    max_field: int = 64,
    min_samples: int = 2,
    clip_run: int | None = 10,
    time_tolerance: float = 0.01,
    vectorised: bool = True,
) -> Record:
    """A record from one logger text file.

    Parameters
    ----------
    path : str or path
        The logger file (any extension; a regular file).
    fmt : LoggerFormat
        Its layout.
    sensors : sequence of Sensor, optional
        Sensors of (some of) the channels, by name: they give the channels' positions and
        kinds.  Each must name a channel; a kind that contradicts ``fmt.kinds`` is refused.
        Channels without one get ``Sensor(name=channel, kind=fmt.kind_of(channel))``.
    max_bytes : int
        Larger files are refused before reading, from their size (default
        :data:`MAX_LOGGER_BYTES`, 256 MiB; a longer recording is split into files
        first).
    max_samples : int
        More data rows are refused (default 1 000 000: 33 min at 512 Hz).
    max_field : int
        Longer fields (characters, header included) are refused; a line may hold
        ``(max_field + 1) × (len(columns) + 1)`` characters, and at least 4096.
    min_samples : int
        Fewer data rows are refused (at least 2).
    clip_run : int or None
        A strain or deflection channel that sits exactly at its own maximum (or minimum)
        for ``clip_run`` or more consecutive samples is refused as clipped (logger
        saturation), unless the channel starts or ends at that value (its resting level
        without traffic, e.g. a quantised one-sided signal).
        Axle-detector channels are not checked (a saturated pulse still marks its axle).
        None: no check (the site chain's reader, :func:`bwim.scenario.record_reader`: its
        gauge check leaves a clipped gauge out of the vehicle it fails in and names it).
    time_tolerance : float
        Allowed relative deviation of each time step from the median step (default 1 %),
        on top of one unit of the last time decimal the file writes; also the allowed
        relative difference between a clock column's and the record's durations.
    vectorised : bool
        Parse each chunk at once (default).  False parses every line one by one, the
        reference path that gives the messages: the same record or message, slower (for
        checks and benchmarks).

    Returns
    -------
    Record
        ``time`` as in the file (s), ``data`` scaled, one sensor per channel,
        ``passages = ()``, ``clock`` from the file name or its clock columns (or None).

    Raises
    ------
    InputError
        Any problem of the file or the arguments (see the module docstring).
    """
    if not isinstance(fmt, LoggerFormat):
        raise InputError(f"fmt must be a bwim.io.logger.LoggerFormat, got {type(fmt).__name__}")
    max_bytes = _limit("max_bytes", max_bytes, 1)
    max_samples = _limit("max_samples", max_samples, 2)
    max_field = _limit("max_field", max_field, 1)
    min_samples = _limit("min_samples", min_samples, 2)
    if clip_run is not None:
        clip_run = _limit("clip_run", clip_run, 2)
    if isinstance(time_tolerance, bool) or not isinstance(time_tolerance, (int, float)) \
            or not 0 <= time_tolerance < 0.5:
        raise InputError(f"time_tolerance must lie in [0, 0.5), got {time_tolerance!r}")
    if not isinstance(vectorised, bool):
        raise InputError(f"vectorised must be true or false, got {vectorised!r}")
    channel_sensors = _channel_sensors(fmt, sensors)
    p = Path(path)
    with open_regular(p) as raw:
        size = os.fstat(raw.fileno()).st_size
        if size > max_bytes:
            raise InputError(f"{p}: {size} bytes is more than max_bytes = {max_bytes}, the "
                             "logger file limit (split the recording into shorter files)")
        try:
            with io.TextIOWrapper(raw, encoding="utf-8-sig", newline=None) as f:
                parser = _Parser(f, p, fmt, size=size, max_bytes=max_bytes,
                                 max_samples=max_samples, max_field=max_field,
                                 vectorised=vectorised,
                                 gaps={s.name for s in channel_sensors
                                       if s.kind is SensorKind.TEMPERATURE})
                parser.run()
        except UnicodeDecodeError:
            raise InputError(f"{p}: not UTF-8 text") from None
        except OSError as exc:
            raise InputError(f"{p}: cannot read: {(exc.strerror or str(exc)).lower()}"
                             ) from None
    rows = parser.rows
    n_t = rows.n
    if n_t < min_samples:
        raise InputError(f"{p}: {n_t} data row{'s' if n_t != 1 else ''}; a record needs at "
                         f"least {min_samples} samples")
    values, time = rows.finish()
    lines = rows.lines
    resolution = 10.0 ** -parser.decimals if parser.decimals else 0.0
    if time is None:
        time = np.arange(n_t) / fmt.sampling_rate
    else:
        h = check_time(time, lines, where=p, tolerance=float(time_tolerance),
                       resolution=resolution)
        if resolution > COARSE_TIME * h and np.ptp(np.diff(time)) > 1e-9 * h:
            # times written coarsely and rounded unevenly: the uniform clock they
            # were rounded from (least squares), whose step is the rate's (the median of
            # the rounded steps is one of them: up to 2 % off)
            k = np.arange(n_t, dtype=float)
            h = float(np.polyfit(k, time, 1)[0])
            time = (time.mean() - h * k.mean()) + h * k
        fs = fmt.sampling_rate
        off = 0.0 if fs is None else abs(h - 1.0 / fs) - time_tolerance * h
        if off > 0.0 and off > rounding(time, resolution):  # (only then: its cost)
            raise InputError(f"{p}: the time column steps {h:g} s ({1.0 / h:g} Hz) but "
                             f"sampling_rate is {fs:g} Hz")
    if clip_run is not None:
        _check_clipping(values, fmt.channels, [s.kind for s in channel_sensors], lines, p,
                        clip_run)
    scales = fmt.scales
    if np.any(scales != 1.0):
        values *= scales
        bad = np.argwhere(np.isinf(values))
        if bad.size:
            k, j = bad[0]
            raise InputError(f"{p}: line {lines[k]}, column {fmt.channels[j]!r}: the scaled "
                             "sample overflows")
    first = ClockRow(line=lines[0], time=float(time[0]), fields=parser.clock_first)
    last = ClockRow(line=lines[n_t - 1], time=float(time[-1]), fields=parser.clock_last)
    clock = logger_clock(fmt.clock, p, first, last, decimal=fmt.decimal,
                         tolerance=float(time_tolerance))
    return Record(time=time, data=values, sensors=channel_sensors, clock=clock)


# --- the data rows: a growing array and their line numbers --------------------------------

class _LineNumbers:
    """File line number of each data row, kept as runs of consecutive lines."""

    def __init__(self) -> None:
        self.rows: list[int] = []                   # first row of each run
        self.first: list[int] = []                  # its line

    def add(self, row: int, lines: np.ndarray) -> None:
        """Rows ``row, row + 1, ...`` are on ``lines`` (ascending)."""
        if lines.size == 0:
            return
        if int(lines[-1]) - int(lines[0]) == lines.size - 1:
            breaks = [0]                            # consecutive lines (they ascend)
        else:
            breaks = [0, *(np.flatnonzero(np.diff(lines) != 1) + 1).tolist()]
        for b in breaks:
            r, line = row + b, int(lines[b])
            if self.rows and line - self.first[-1] == r - self.rows[-1]:
                continue                            # continues the last run
            self.rows.append(r)
            self.first.append(line)

    def __getitem__(self, k) -> int:
        k = int(k)
        i = bisect_right(self.rows, k) - 1
        return self.first[i] + (k - self.rows[i])


class _Rows:
    """The data array (rows × channels) and the time column, grown in place."""

    def __init__(self, where: Path, n_channels: int, has_time: bool, *, size: int,
                 max_samples: int) -> None:
        self.where, self.n_channels, self.has_time = where, n_channels, has_time
        self.size, self.max_samples = size, max_samples
        self.values: np.ndarray | None = None
        self.time: np.ndarray | None = None
        self.n = 0
        self.lines = _LineNumbers()

    @property
    def capacity(self) -> int:
        return 0 if self.values is None else self.values.shape[0]

    def reserve(self, extra: int, chars_read: int) -> None:
        """Room for ``extra`` more rows; the first time, for the whole file as estimated
        from its size and the characters read so far."""
        need = self.n + extra
        if need <= self.capacity:
            return
        if self.values is None:
            estimate = need * self.size / max(chars_read, 1) * 1.02 + 16
        else:
            estimate = max(self.capacity * 1.25 + 1024,
                           need * self.size / max(chars_read, 1) * 1.02)
        rows = int(min(max(estimate, need), self.max_samples))
        columns = self.n_channels + self.has_time
        # the values, and the larger of one chunk's work (while reading) and a mask of the
        # values' shape with the time checks' arrays (after reading)
        extra = max(_WORK_PER_CHAR * CHUNK, rows * (columns + 8.0 * _TIME_TEMPORARIES))
        check_memory(rows * columns * 8.0 + extra,
                     f"{self.where}: reading about {rows} rows of {columns} numbers")
        if self.values is None:
            self.values = np.empty((rows, self.n_channels))
            self.time = np.empty(rows) if self.has_time else None
        else:
            self.values.resize((rows, self.n_channels), refcheck=False)
            if self.time is not None:
                self.time.resize(rows, refcheck=False)

    def add(self, values: np.ndarray, time: np.ndarray | None, lines: np.ndarray) -> None:
        r = values.shape[0]
        if r == 0:
            return
        self.values[self.n:self.n + r] = values
        if self.time is not None:
            self.time[self.n:self.n + r] = time
        self.lines.add(self.n, lines)
        self.n += r

    def finish(self) -> tuple[np.ndarray, np.ndarray | None]:
        """The data array and the time column, trimmed to the rows read."""
        self.values.resize((self.n, self.n_channels), refcheck=False)
        if self.time is not None:
            self.time.resize(self.n, refcheck=False)
        return self.values, self.time


# --- the parser ------------------------------------------------------------------------------


class _Parser:
    """Reads a logger file's rows into :class:`_Rows` (see the module docstring)."""

    def __init__(self, f: TextIO, p: Path, fmt: LoggerFormat, *, size: int, max_bytes: int,
                 max_samples: int, max_field: int, vectorised: bool = True,
                 gaps: set[str] | frozenset[str] = frozenset()) -> None:
        self.f, self.p, self.fmt = f, p, fmt
        self.vectorised, self.size = vectorised, size
        self.max_bytes, self.max_samples, self.max_field = max_bytes, max_samples, max_field
        cols = fmt.columns
        self.n = n = len(cols)
        self.max_line = max(4096, (max_field + 1) * (n + 1))
        channels = set(fmt.channels)
        self.keep = [j for j, c in enumerate(cols) if c in channels]
        self.t_col = cols.index(TIME) if fmt.has_time else None
        self.numeric = self.keep if self.t_col is None else [self.t_col, *self.keep]
        # columns whose empty or NaN fields read as NaN (a temperature sensor's gaps)
        self.gaps = {j for j, c in enumerate(cols) if c in gaps}
        # each column's place for the compiled scan (bwim.io.field_kernels)
        slot = dict(zip(self.keep, range(len(self.keep)), strict=True))
        if self.t_col is not None:
            slot[self.t_col] = TIME_SLOT
        self.slots = np.array([slot.get(j, SKIP_SLOT) for j in range(n)], dtype=np.int64)
        self.gap_flags = np.array([GAP if j in self.gaps else 0 for j in range(n)],
                                  dtype=np.uint8)
        self.clock_cols = {c: cols.index(c) for c in fmt.clock_columns}
        self.comma = fmt.decimal == ","
        self.delim = fmt.delimiter
        self.rows = _Rows(p, len(self.keep), fmt.has_time, size=size, max_samples=max_samples)
        self.decimals = 0
        self.clock_first: dict[str, str] = {}
        self.clock_last: dict[str, str] = {}
        self.line = 0                               # lines read
        self.chars = 0                              # characters read

    # -- reading -------------------------------------------------------------------------
    def _grew(self) -> InputError:
        return InputError(f"{self.p}: larger than max_bytes = {self.max_bytes} (the file "
                          "grew while read?)")

    def _long(self, line: int) -> InputError:
        return InputError(f"{self.p}: line {line} is longer than {self.max_line} characters")

    def _readline(self) -> str | None:
        raw = self.f.readline(self.max_line + 2)
        if not raw:
            return None
        self.line += 1
        self.chars += len(raw)
        if self.chars > self.max_bytes:
            raise self._grew()
        text = raw.rstrip("\r\n")
        if len(text) > self.max_line:
            raise self._long(self.line)
        return text

    def run(self) -> None:
        first = None
        while (text := self._readline()) is not None:
            if self.line <= self.fmt.skip_lines:
                continue
            s = text.strip()
            if s and not s.startswith("#"):
                first = text
                break
        if first is None:
            raise InputError(f"{self.p}: the file is empty (no data rows)")
        pending = [] if self._is_header(first, self.line) else [first]
        start = self.line - len(pending)            # lines before the chunk's first
        while True:
            # equal chunks of at most CHUNK characters (no short tail chunk)
            remaining = self.size - self.chars
            size = CHUNK if remaining <= 0 else \
                min(CHUNK, -(-remaining // -(-remaining // CHUNK)) + 64)
            text = self.f.read(size)
            if text and not text.endswith("\n"):
                text += self.f.readline(self.max_line + 2)
            if not text and not pending:
                break
            self.chars += len(text)
            if self.chars > self.max_bytes:
                raise self._grew()
            if pending:
                text = pending[0] + "\n" + text
            self.line = start + self._chunk(start, text)
            start, pending = self.line, []
            if not text:
                break
        if self.rows.n == 0:
            raise InputError(f"{self.p}: no data rows after the header")

    def _is_header(self, text: str, k: int) -> bool:
        """Whether the first content line is the header (and the delimiter, if detected)."""
        n, fmt = self.n, self.fmt
        if self.delim is None:
            self.delim = _detect_delimiter(text, n, fmt.decimal, self.p, k)
        raw = self._fields(text, k)
        if fmt.header is not None:
            return fmt.header
        fields = [_clean(s) for s in raw]
        named = [f for f, c in zip(fields, fmt.columns, strict=True) if c != SKIP]
        if named == [c for c in fmt.columns if c != SKIP]:
            return True  # the columns' own names, numbers or not ("101", "102")
        numbers = [_is_number(fields[j], fmt.decimal) or (j in self.gaps and _is_gap(fields[j]))
                   for j in self.numeric]
        if not any(numbers) and not all(fields[j].lower().lstrip("+-") in _NON_FINITE
                                        for j in self.numeric):
            return True  # (a row of NaN is a logger's first samples, not a header)
        if not all(numbers):
            j = self.numeric[numbers.index(False)]
            raise InputError(
                f"{self.p}: line {k} is neither a header (it has numbers) nor data "
                f"(column {fmt.columns[j]!r}: {_bad_field(fields[j], fmt.decimal)}); set the "
                "format's header")
        return False

    def _fields(self, text: str, k: int) -> list[str]:
        """The raw fields of a line, checked for their count and length."""
        n, delim = self.n, self.delim
        raw = _split(text, delim, n)
        if len(raw) != n:
            raise InputError(f"{self.p}: line {k} has {len(raw)} fields, the format has {n} "
                             f"columns (delimiter {_delim_name(delim)})")
        longest = max(range(n), key=lambda j: len(raw[j]))
        if len(raw[longest]) > self.max_field:
            raise InputError(f"{self.p}: line {k}, field {longest + 1} is longer than "
                             f"max_field = {self.max_field} characters")
        return raw

    # -- one chunk -----------------------------------------------------------------------
    def _chunk(self, start: int, text: str) -> int:
        """Parse the chunk ``text``: file lines ``start + 1, ...``, each ended by a newline
        (the file's last maybe not); the number of its lines."""
        if self.vectorised and (n_lines := self._fast(start, text)) is not None:
            return n_lines
        lines = text.split("\n")
        if lines[-1] == "":
            lines.pop()
        if not lines:
            return 0
        if max(map(len, lines)) > self.max_line:
            i = next(i for i, s in enumerate(lines) if len(s) > self.max_line)
            self._slow(start, lines[:i])            # an earlier problem comes first
            raise self._long(start + i + 1)
        if "#" in text or "\n\n" in text or text.startswith("\n"):
            n_rows = sum(1 for s in lines if (t := s.strip()) and t[0] != "#")
            if not n_rows:
                return len(lines)
        else:
            n_rows = len(lines)                     # (lines of spaces counted: see _fast)
        if self.rows.n + n_rows > self.max_samples:
            self._slow(start, lines)                # raises at the row past the limit
            return len(lines)
        self.rows.reserve(n_rows, self.chars)
        self._slow(start, lines)
        return len(lines)

    def _fast(self, start: int, text: str) -> int | None:
        """Parse the chunk at once (:func:`bwim.io.field_kernels.scan_rows`): the number of
        its lines, or None (nothing added) when anything is unusual: the chunk is then read
        line by line."""
        data = text.encode()
        got = scan_rows(data, n_chars=len(text), delimiter=self.delim, slots=self.slots,
                        gaps=self.gap_flags, n_channels=len(self.keep),
                        has_time=self.t_col is not None, comma=self.comma,
                        max_line=self.max_line, max_field=self.max_field,
                        max_rows=self.max_samples - self.rows.n, first_line=start + 1)
        if got.status is not Scan.OK:
            return None
        decimals = self._others(got, data)
        if decimals is None:
            return None
        m_rows = got.lines.size
        # the rows the line-by-line route reserves room for: a chunk without a comment
        # or an empty line counts its lines of spaces too (it never splits such a chunk)
        n_rows = m_rows
        if got.space_lines and not ("#" in text or "\n\n" in text or text.startswith("\n")):
            n_rows += got.space_lines
        if n_rows == 0:
            return got.n_lines
        self.rows.reserve(m_rows if self.rows.n + n_rows > self.max_samples else n_rows,
                          self.chars)
        if m_rows == 0:
            return got.n_lines
        self.decimals = decimals
        self.rows.add(got.values, got.time, got.lines)
        if self.clock_cols:
            e = got.edges
            if not self.clock_first:
                self.clock_first = {c: _clean(data[e[0, j]:e[1, j]].decode())
                                    for c, j in self.clock_cols.items()}
            self.clock_last = {c: _clean(data[e[2, j]:e[3, j]].decode())
                               for c, j in self.clock_cols.items()}
        return got.n_lines

    def _others(self, got: ChunkRows, data: bytes) -> int | None:
        """Read the numeric fields the scan left (not plain decimals) as the line-by-line
        route reads them, into ``got``; the time column's decimals, or None if one is not
        a finite number."""
        decimals = max(self.decimals, got.decimals)
        for r, j, s, e in got.bad.tolist():
            field_ = _clean(data[s:e].decode())
            if j in self.gaps and _is_gap(field_):
                got.values[r, self.slots[j]] = math.nan
                continue
            s = _point(field_, self.comma)
            if _NUMBER.fullmatch(s) is None:
                return None
            v = float(s)
            if not math.isfinite(v):
                return None
            if j == self.t_col:
                got.time[r] = v
                dot = s.find(".")
                if dot >= 0 and "e" not in s and "E" not in s:
                    decimals = max(decimals, len(s) - dot - 1)
            else:
                got.values[r, self.slots[j]] = v
        return decimals

    def _slow(self, start: int, lines: list[str]) -> None:
        """Parse lines one by one, with the precise message for the first problem."""
        fmt, p = self.fmt, self.p
        t_col, comma = self.t_col, self.comma
        buf: list[float] = []
        times: list[float] = []
        numbers: list[int] = []
        decimals = self.decimals
        for i, text in enumerate(lines):
            k = start + i + 1
            s = text.strip()
            if not s or s.startswith("#"):
                continue
            fields = [_clean(f) for f in self._fields(text, k)]
            if self.rows.n + len(numbers) >= self.max_samples:
                raise InputError(f"{p}: more than max_samples = {self.max_samples} data rows")
            for j in self.numeric:
                s = _point(fields[j], comma)
                if j in self.gaps and _is_gap(fields[j]):
                    buf.append(math.nan)
                    continue
                if _NUMBER.fullmatch(s) is None:
                    raise InputError(f"{p}: line {k}, column {fmt.columns[j]!r}: "
                                     f"{_bad_field(fields[j], fmt.decimal)}")
                v = float(s)
                if not math.isfinite(v):
                    raise InputError(f"{p}: line {k}, column {fmt.columns[j]!r}: "
                                     "infinite sample (overflow)")
                if j == t_col:
                    times.append(v)
                    dot = s.find(".")
                    if dot >= 0 and "e" not in s and "E" not in s:
                        decimals = max(decimals, len(s) - dot - 1)
                else:
                    buf.append(v)
            numbers.append(k)
            if self.clock_cols:
                row = {c: fields[j] for c, j in self.clock_cols.items()}
                if not self.clock_first:
                    self.clock_first = row
                self.clock_last = row
        if not numbers:
            return
        self.decimals = decimals
        self.rows.reserve(len(numbers), self.chars)
        values = np.array(buf, dtype=float).reshape(len(numbers), len(self.keep))
        self.rows.add(values, np.array(times) if t_col is not None else None,
                      np.array(numbers, dtype=np.int64))
