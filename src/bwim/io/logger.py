"""Logger text files of a real installation: one event per file, read into a Record.

Contract
--------
* A :class:`LoggerFormat` says what the columns of a logger file are: ``columns`` names
  each column in file order; ``"-"`` skips a column (its content is never read, so it may
  hold text such as a date or a status); ``"time"`` (at most once) is the time column, s.
  Every other name is a channel, in that order, with a :class:`~bwim.SensorKind` from
  ``kinds`` (default ``strain_x``; axle detectors are ``axle_detector``).
* :func:`read_logger` returns a :class:`~bwim.Record` with ``passages = ()``: ``time`` is
  the time column **as written** (s, not shifted: a clock time of day stays one), or
  ``k / sampling_rate`` (k = 0, 1, ...) without a time column; ``data`` (n_t, n_channels)
  is the file's numbers times ``scale`` (logger units to strain; the default 1.0 keeps the
  file's units, which is right for data already in strain and for influence-line weighing,
  which works on uncalibrated units); ``sensors`` are one :class:`~bwim.Sensor` per
  channel, the caller's (by name) when given, else ``Sensor(name=..., kind=...)`` without
  a position.
* Text layout.  Any file extension.  UTF-8, a byte-order mark ignored; LF, CRLF or CR line
  endings; blank lines and lines whose first non-blank character is ``#`` are skipped
  anywhere (no comment after data on a line); ``skip_lines`` raw lines are dropped first
  (a logger's preamble).  The delimiter is ``,``, ``;``, tab or whitespace (``" "``: any
  run of spaces and tabs); auto-detected as the first of ``;``, tab, ``,``, whitespace
  that splits the first content line into ``len(columns)`` fields.  The header (one row
  of names, at most) is auto-detected: a first content row none of whose channel and time
  fields is a number is a header, one with numbers is data, a mix is refused.  A header
  must have ``len(columns)`` fields; its names need not equal ``columns``.  A trailing
  delimiter is allowed: one empty field past the last column is dropped.  A field may be
  enclosed in double quotes (no delimiter or quote inside).  Numbers are decimal ASCII
  (``1``, ``-2.5``, ``.5``, ``3e-06``); with ``decimal=","`` the decimal mark is a comma,
  which needs a ``;``, tab or whitespace delimiter (auto-detection then never picks ``,``).
* Refused with an :class:`~bwim.errors.InputError` whose one-line message starts with the
  file and names the line (and column) where there is one: a missing, unreadable, non-UTF-8
  or empty file; a file larger than ``max_bytes`` (refused before reading); a line longer
  than the format allows or a field longer than ``max_field`` characters; a row with a
  missing or extra field; an empty field, text that is not a number, NaN or an infinite
  sample in a channel or the time column; fewer than ``min_samples`` or more than
  ``max_samples`` rows; time that goes back or repeats, a dropped sample (a step over 1.5 x
  the median step) or jitter (a step off the median by more than ``time_tolerance`` of it,
  plus one unit of the file's last written time decimal); a time column that disagrees
  with ``sampling_rate``; a clipped channel (see :func:`read_logger`).
* The file is streamed once, line by line, into one flat float buffer that becomes the
  record's data array (scaled in place): the numbers are held in memory once.
"""

from __future__ import annotations

import math
import os
import re
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TextIO

import numpy as np

from bwim.errors import InputError, parse_enum, require_positive
from bwim.io._csv import check_time
from bwim.records import Record
from bwim.sensors import Sensor, SensorKind

__all__ = ["DELIMITERS", "LoggerFormat", "read_logger"]

DELIMITERS = (";", "\t", ",", " ")
"""Delimiters in the order auto-detection tries them (``" "``: any run of whitespace)."""

SKIP = "-"
TIME = "time"
MiB = 2**20

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_NON_FINITE = {"nan": "NaN", "inf": "infinite", "infinity": "infinite"}


def _delim_name(d: str) -> str:
    return {"\t": "tab", " ": "whitespace"}.get(d, repr(d))


@dataclass(frozen=True, kw_only=True)
class LoggerFormat:
    """The layout of a logger's text files (see the module docstring).

    Parameters
    ----------
    columns : sequence of str
        One name per column, in file order: ``"time"`` (at most once), ``"-"`` (skipped)
        or a channel name (unique).
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
    """

    columns: tuple[str, ...]
    delimiter: str | None = None
    header: bool | None = None
    sampling_rate: float | None = None
    scale: float | tuple[float, ...] | Mapping[str, float] = 1.0
    decimal: str = "."
    kinds: Mapping[str, SensorKind] = field(default_factory=dict)
    skip_lines: int = 0

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
        channels = self.channels
        if not channels:
            raise InputError(f"LoggerFormat.columns names no channel (only 'time' and '-'): "
                             f"{list(cols)}")
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
    def channels(self) -> tuple[str, ...]:
        """The channel names (columns other than ``"time"`` and ``"-"``), in file order."""
        return tuple(c for c in self.columns if c not in (SKIP, TIME))

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
    return tuple(given.get(c) or Sensor(name=c, kind=fmt.kind_of(c)) for c in fmt.channels)


def _limit(name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
    return value


class _Lines:
    """Content lines of an open text file: (line number, text), with size limits."""

    def __init__(self, f: TextIO, where: Path, *, max_line: int, max_chars: int,
                 skip: int) -> None:
        self.f, self.where, self.max_line, self.max_chars = f, where, max_line, max_chars
        self.skip = skip
        self.number = 0
        self.chars = 0

    def __iter__(self):
        while True:
            raw = self.f.readline(self.max_line + 2)
            if not raw:
                return
            self.number += 1
            self.chars += len(raw)
            if self.chars > self.max_chars:
                raise InputError(f"{self.where}: larger than max_bytes = {self.max_chars} "
                                 "(the file grew while read?)")
            text = raw.rstrip("\r\n")
            if len(text) > self.max_line:
                raise InputError(f"{self.where}: line {self.number} is longer than "
                                 f"{self.max_line} characters")
            if self.number <= self.skip:
                continue
            s = text.strip()
            if s and not s.startswith("#"):
                yield self.number, text


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


def _is_number(s: str, decimal: str) -> bool:
    return _NUMBER.fullmatch(s.replace(",", ".") if decimal == "," else s) is not None


def _bad_field(s: str) -> str:
    if not s:
        return "empty field"
    kind = _NON_FINITE.get(s.lower().lstrip("+-"))
    if kind:
        return f"{kind} sample"
    shown = s if len(s) <= 20 else s[:20] + "..."
    return f"{shown!r} is not a number"


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and length of each run of True in a boolean vector."""
    edges = np.diff(np.concatenate([[0], mask.view(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    return starts, np.flatnonzero(edges == -1) - starts


def _check_clipping(values: np.ndarray, names: Sequence[str], kinds: Sequence[SensorKind],
                    lines: np.ndarray, where: Path, run: int) -> None:
    for j, (name, kind) in enumerate(zip(names, kinds, strict=True)):
        if kind is SensorKind.AXLE_DETECTOR:
            continue
        col = values[:, j]
        for label, extreme in (("maximum", col.max()), ("minimum", col.min())):
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
    max_bytes: int = 256 * MiB,
    max_samples: int = 1_000_000,
    max_field: int = 64,
    min_samples: int = 2,
    clip_run: int | None = 10,
    time_tolerance: float = 0.01,
) -> Record:
    """A record from one logger text file.

    Parameters
    ----------
    path : str or path
        The logger file (any extension).
    fmt : LoggerFormat
        Its layout.
    sensors : sequence of Sensor, optional
        Sensors of (some of) the channels, by name: they give the channels' positions and
        kinds.  Each must name a channel; a kind that contradicts ``fmt.kinds`` is refused.
        Channels without one get ``Sensor(name=channel, kind=fmt.kind_of(channel))``.
    max_bytes : int
        Larger files are refused before reading (default 256 MiB).
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
        None: no check.
    time_tolerance : float
        Allowed relative deviation of each time step from the median step (default 1 %),
        on top of one unit of the last time decimal the file writes.

    Returns
    -------
    Record
        ``time`` as in the file (s), ``data`` scaled, one sensor per channel,
        ``passages = ()``.

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
    channel_sensors = _channel_sensors(fmt, sensors)
    p = Path(path)
    try:
        size = p.stat().st_size
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except (OSError, ValueError) as exc:
        why = getattr(exc, "strerror", None) or str(exc)
        raise InputError(f"{p}: cannot read: {why.lower()}") from None
    if p.is_dir():
        raise InputError(f"{p}: is a directory, not a logger file")
    if size > max_bytes:
        raise InputError(f"{p}: {size} bytes is more than max_bytes = {max_bytes}")
    try:
        with open(p, encoding="utf-8-sig", newline=None) as f:
            values, time, lines, resolution = _parse(f, p, fmt, max_bytes=max_bytes,
                                                     max_samples=max_samples,
                                                     max_field=max_field)
    except UnicodeDecodeError:
        raise InputError(f"{p}: not UTF-8 text") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {(exc.strerror or str(exc)).lower()}") from None
    n_t = lines.size
    if n_t < min_samples:
        raise InputError(f"{p}: {n_t} data row{'s' if n_t != 1 else ''}; a record needs at "
                         f"least {min_samples} samples")
    if time is None:
        time = np.arange(n_t) / fmt.sampling_rate
    else:
        h = check_time(time, lines, where=p, tolerance=float(time_tolerance),
                       resolution=resolution)
        fs = fmt.sampling_rate
        if fs is not None and abs(h - 1.0 / fs) > time_tolerance * h + resolution:
            raise InputError(f"{p}: the time column steps {h:g} s ({1.0 / h:g} Hz) but "
                             f"sampling_rate is {fs:g} Hz")
    if clip_run is not None:
        _check_clipping(values, fmt.channels, [s.kind for s in channel_sensors], lines, p,
                        clip_run)
    scales = fmt.scales
    if np.any(scales != 1.0):
        values *= scales
        bad = np.argwhere(~np.isfinite(values))
        if bad.size:
            k, j = bad[0]
            raise InputError(f"{p}: line {lines[k]}, column {fmt.channels[j]!r}: the scaled "
                             "sample overflows")
    return Record(time=time, data=values, sensors=channel_sensors)


def _parse(f: TextIO, p: Path, fmt: LoggerFormat, *, max_bytes: int, max_samples: int,
           max_field: int):
    """Stream the rows: (values (n_t, n_channels), time or None, line numbers,
    time resolution)."""
    n = len(fmt.columns)
    keep = [j for j, c in enumerate(fmt.columns) if c not in (SKIP, TIME)]
    t_col = fmt.columns.index(TIME) if fmt.has_time else None
    numeric = keep if t_col is None else [t_col, *keep]
    comma = fmt.decimal == ","
    max_line = max(4096, (max_field + 1) * (n + 1))
    rows = _Lines(f, p, max_line=max_line, max_chars=max_bytes, skip=fmt.skip_lines)
    buf = array("d")
    times = array("d")
    line_no = array("q")
    delim = fmt.delimiter
    header = fmt.header
    decimals = 0
    first = True
    for k, text in rows:
        if delim is None:
            delim = _detect_delimiter(text, n, fmt.decimal, p, k)
        raw = _split(text, delim, n)
        if len(raw) != n:
            raise InputError(f"{p}: line {k} has {len(raw)} fields, the format has {n} "
                             f"columns (delimiter {_delim_name(delim)})")
        longest = max(range(n), key=lambda j: len(raw[j]))
        if len(raw[longest]) > max_field:
            raise InputError(f"{p}: line {k}, field {longest + 1} is longer than "
                             f"max_field = {max_field} characters")
        fields = [_clean(s) for s in raw]
        if first:
            first = False
            numbers = [_is_number(fields[j], fmt.decimal) for j in numeric]
            if header is None:
                if not any(numbers):
                    continue                        # the header row
                if not all(numbers):
                    j = numeric[numbers.index(False)]
                    raise InputError(
                        f"{p}: line {k} is neither a header (it has numbers) nor data "
                        f"(column {fmt.columns[j]!r}: {_bad_field(fields[j])}); set the "
                        "format's header")
            elif header:
                continue
        if len(line_no) >= max_samples:
            raise InputError(f"{p}: more than max_samples = {max_samples} data rows")
        for j in numeric:
            s = fields[j]
            if comma:
                s = s.replace(",", ".")
            if _NUMBER.fullmatch(s) is None:
                raise InputError(f"{p}: line {k}, column {fmt.columns[j]!r}: "
                                 f"{_bad_field(fields[j])}")
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
        line_no.append(k)
    if not line_no:
        raise InputError(f"{p}: the file is empty (no data rows)"
                         if first else f"{p}: no data rows after the header")
    values = np.frombuffer(buf, dtype=float).reshape(len(line_no), len(keep))
    time = None if t_col is None else np.frombuffer(times, dtype=float)
    resolution = 10.0 ** -decimals if decimals else 0.0
    return values, time, np.frombuffer(line_no, dtype=np.int64), resolution
