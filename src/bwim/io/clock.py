"""The wall-clock time of a logger file: from its name or from its columns.

Contract
--------
* A logger file's **clock** is the date and time (naive: the site's local time, as the
  logger writes it) of its first data row.  :func:`bwim.io.read_logger` turns it into
  :attr:`bwim.Record.clock`, the clock at record time 0:
  ``Record.clock = clock of the first row − time[0]`` (``time[0]`` in s).  With a time
  column that starts at 0 (the common case: one file per event) record time 0 *is* the
  file's instant; with a time column that holds the clock time of day it is that day's
  midnight, so :meth:`bwim.Record.clock_seconds` is right either way.
* Where the clock comes from is a :class:`ClockSpec` (``LoggerFormat.clock``; None is
  ``ClockSpec()``):

  - **file name, default forms** (``ClockSpec()``): the leftmost valid timestamp of the
    file name (extension included) in one of the common forms

    * ``YYYY-MM-DD-HH-MM-SS[-mmm]`` anywhere in the name (``2015-09-29-09-28-46-125.txt``,
      ``PL1_2015-10-01-09-45-52-576.txt``; ``mmm`` are milliseconds, exactly 3 digits);
    * ``YYYYMMDD_HHMMSS`` (separator ``_``, ``T`` or ``-``), with fractional seconds
      after ``.`` or ``,`` (``20151001_094552.576``);
    * ISO 8601 ``YYYY-MM-DDTHH:MM:SS[.f]``, with ``:`` replaced by ``-`` or omitted as
      file names need (``2015-10-01T09-45-52.576``, ``2015-10-01T094552``), date and time
      also separated by ``_``, ``-`` or a space.

    Digits run on either side are not part of a timestamp; a candidate that is not a
    valid date and time is skipped; fractions beyond microseconds are cut; a UTC offset
    after the time is not read (the clock is naive local time).  A name with no timestamp
    gives **no clock** (None): not an error (older files keep the clock time in their time
    column).
  - **file name, a pattern** (``pattern="%Y%m%d_%H%M%S"``): strptime directives ``%Y``
    (4 digits), ``%y`` ``%m`` ``%d`` ``%H`` ``%I`` ``%M`` ``%S`` (2 digits), ``%j`` (3),
    ``%f`` (1–6 digits, a fraction of a second: ``576`` is 0.576 s), ``%p``, ``%b``,
    ``%B``, ``%%``; other characters literal.  The leftmost valid match anywhere in the
    name (not inside a longer run of digits) is the clock; the pattern must hold a year
    and a month and day (or ``%j``).  A pattern without a time of day (``%Y-%m-%d``) gives
    the date only: the time column is then the time of day, s since that midnight
    (``Record.clock`` = the midnight).  **No match is an error** (the file and the pattern
    named).
  - **a column** (``column="clock"``): the column (named in ``LoggerFormat.columns``; not a
    channel) holds the clock of each row: a number (s since midnight, the format's decimal
    mark; six digits with a leading zero, ``083000``, are refused: HHMMSS or padded
    seconds, the ``format`` says which), ISO 8601 text with date and time
    (``2015-10-01T09:45:52.576``, ``2015-10-01 09:45:52``), a time of day
    (``09:45:52.576``), or text in ``format`` (strptime, as above but full match). A time
    of day takes its date from ``date_column`` (ISO ``YYYY-MM-DD`` or, with ``format``, the
    text ``"DATE TIME"`` joined by one space), else from the file name (``pattern``, or the
    default forms unless ``from_name`` is False: the name's date, or the day before or
    after, whichever puts the first row within 12 h of the name's own time of day, as a
    file named just after midnight may begin before it); no date anywhere is an error.
    ``column="time"`` says the time column itself is the time of day (s since midnight):
    only the date is looked for. Only the first and the last data rows' clock fields are
    read (text columns need no numbers): the first gives the clock, the last checks that
    the column runs with the record's time (within its own resolution plus ``tolerance`` ×
    the duration; a time of day that wraps past midnight goes on to the next day).
  - **none** (``ClockSpec(from_name=False)``): no clock.

* Every refusal is an :class:`~bwim.errors.InputError` with a one-line message that starts
  with the file (a bad spec: with ``ClockSpec``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import date, datetime, time, timedelta
from pathlib import Path
from types import MappingProxyType

from bwim.errors import InputError

__all__ = ["ClockRow", "ClockSpec", "NameStamp", "logger_clock", "name_timestamp"]

#: The time column's name in ``LoggerFormat.columns`` (``column="time"``).
TIME = "time"

_DIRECTIVES = {
    "Y": r"\d{4}", "y": r"\d{2}", "m": r"\d{2}", "d": r"\d{2}", "j": r"\d{3}",
    "H": r"\d{2}", "I": r"\d{2}", "M": r"\d{2}", "S": r"\d{2}", "f": r"\d{1,6}",
    "p": r"(?:[AaPp][Mm])", "b": r"[A-Za-z]{3}", "B": r"[A-Za-z]{3,9}", "%": "%",
}
_TIME_DIRECTIVES = frozenset("HIMSfp")
_NUMERIC_EDGE = frozenset("YymdjHIMSf")

_EXTENDED = re.compile(
    r"(?<!\d)(?P<Y>\d{4})-(?P<m>\d{2})-(?P<d>\d{2})[-T_ ](?P<H>\d{2})(?P<c>[:-]?)(?P<M>\d{2})"
    r"(?P=c)(?P<S>\d{2})(?:[.,](?P<f>\d{1,9})|-(?P<ms>\d{3}))?(?!\d)")
_BASIC = re.compile(
    r"(?<!\d)(?P<Y>\d{4})(?P<m>\d{2})(?P<d>\d{2})[T_-](?P<H>\d{2})(?P<M>\d{2})(?P<S>\d{2})"
    r"(?:[.,](?P<f>\d{1,9}))?(?!\d)")
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
#: Six digits with a leading zero (and maybe a fraction): a compact HHMMSS clock as likely
#: as seconds since midnight written zero-padded.
_COMPACT = re.compile(r"0\d{5}(?:\.\d*)?", re.ASCII)
_FRACTION = re.compile(r"[.,](\d+)")


def _parse_pattern(pattern: str, what: str) -> tuple[str, frozenset[str]]:
    """A strptime pattern as a regex (its text) and the set of its directives."""
    out: list[str] = []
    tokens: list[str] = []                          # directive letter, or "" for a literal
    k = 0
    while k < len(pattern):
        ch = pattern[k]
        if ch != "%":
            out.append(re.escape(ch))
            tokens.append("")
            k += 1
            continue
        d = pattern[k + 1] if k + 1 < len(pattern) else ""
        if d not in _DIRECTIVES:
            shown = f"%{d}" if d else "a lone %"
            raise InputError(f"ClockSpec.{what}: {shown} is not supported (use %Y %y %m %d %j "
                             f"%H %I %M %S %f %p %b %B %%), got {pattern!r}")
        out.append(_DIRECTIVES[d])
        tokens.append(d)
        k += 2
    regex = "".join(out)
    if tokens[0] in _NUMERIC_EDGE:
        regex = r"(?<!\d)" + regex                  # not inside a longer run of digits
    if tokens[-1] in _NUMERIC_EDGE:
        regex += r"(?!\d)"
    return regex, frozenset(t for t in tokens if t)


def _has_date(used: frozenset[str]) -> bool:
    """Whether strptime directives give a full date: a year, and a day of the year or a
    month and a day."""
    month_day = bool(used & {"m", "b", "B"}) and "d" in used
    return bool(used & {"Y", "y"}) and ("j" in used or month_day)


@dataclass(frozen=True, kw_only=True)
class ClockSpec:
    """Where a logger file's clock comes from (see the module docstring).

    Parameters
    ----------
    pattern : str, optional
        A strptime-like pattern searched in the file name; no match is an error.
    column : str, optional
        The column that holds each row's clock (``"time"``: the time column is the time of
        day, s since midnight).
    date_column : str, optional
        The column that holds the date of a time-of-day ``column``.
    format : str, optional
        strptime pattern of the ``column`` text (with ``date_column``: of
        ``"DATE TIME"``); default ISO 8601.
    from_name : bool
        Whether the file name is searched (default forms or ``pattern``): False with no
        column means no clock.
    """

    pattern: str | None = None
    column: str | None = None
    date_column: str | None = None
    format: str | None = None
    from_name: bool = True
    _pattern_regex: re.Pattern | None = field(default=None, init=False, repr=False,
                                              compare=False)
    _pattern_has_time: bool = field(default=False, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.from_name, bool):
            raise InputError(f"ClockSpec.from_name must be true or false, got "
                             f"{self.from_name!r}")
        for name in ("pattern", "column", "date_column", "format"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, str) or not v.strip() or v != v.strip()):
                raise InputError(f"ClockSpec.{name} must be a non-empty text without "
                                 f"surrounding spaces, got {v!r}")
        if self.pattern is not None:
            if not self.from_name:
                raise InputError("ClockSpec: a pattern reads the file name, but from_name is "
                                 "false")
            regex, used = _parse_pattern(self.pattern, "pattern")
            if not _has_date(used):
                raise InputError(f"ClockSpec.pattern must hold a year (%Y or %y) and a month "
                                 f"and day (or %j), got {self.pattern!r}")
            object.__setattr__(self, "_pattern_regex", re.compile(regex))
            object.__setattr__(self, "_pattern_has_time", bool(used & _TIME_DIRECTIVES))
        if self.column is not None and self.column == "-":
            raise InputError("ClockSpec.column cannot be '-' (a skipped column)")
        if self.date_column is not None:
            if self.column is None:
                raise InputError("ClockSpec.date_column needs the column of the time of day "
                                 "(ClockSpec.column)")
            if self.date_column in (self.column, TIME, "-"):
                raise InputError(f"ClockSpec.date_column {self.date_column!r} must be another "
                                 "column than the clock's and the time column")
        if self.format is not None:
            if self.column is None or self.column == TIME:
                raise InputError("ClockSpec.format reads the text of a clock column: give "
                                 "ClockSpec.column (other than 'time')")
            _, used = _parse_pattern(self.format, "format")
            if not used & _TIME_DIRECTIVES:
                raise InputError(f"ClockSpec.format must hold a time of day (%H, %M, %S...), "
                                 f"got {self.format!r}")
            if self.date_column is not None and not _has_date(used):
                raise InputError(f"ClockSpec.format reads 'DATE TIME' (date_column and "
                                 f"column): it must hold the date too, got {self.format!r}")

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns the clock reads (the time column excluded)."""
        return tuple(c for c in (self.date_column, self.column) if c not in (None, TIME))


@dataclass(frozen=True, kw_only=True)
class NameStamp:
    """A timestamp found in a file name."""

    instant: datetime
    """The date and time it says (midnight for a date-only pattern)."""
    has_time: bool
    """Whether it gives the time of day (False: a date-only pattern)."""
    text: str
    """The characters of the name it was read from."""


@dataclass(frozen=True, kw_only=True)
class ClockRow:
    """The clock fields of one data row of a logger file (for :func:`logger_clock`)."""

    line: int
    """Line number in the file (from 1)."""
    time: float
    """Record time of the row, s (the time column, or k / sampling_rate)."""
    fields: Mapping[str, str] = field(default_factory=dict)
    """Cleaned text of the clock columns (by column name)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "fields", MappingProxyType(dict(self.fields)))


def _microseconds(frac: str | None) -> int:
    return 0 if not frac else int(frac[:6].ljust(6, "0"))


def _default_stamp(name: str) -> NameStamp | None:
    found: list[tuple[int, int, NameStamp]] = []
    for regex in (_EXTENDED, _BASIC):
        for m in regex.finditer(name):
            g = m.groupdict()
            try:
                instant = datetime(int(g["Y"]), int(g["m"]), int(g["d"]), int(g["H"]),
                                   int(g["M"]), int(g["S"]),
                                   _microseconds(g.get("f") or g.get("ms")))
            except ValueError:
                continue                                # not a valid date and time
            found.append((m.start(), -len(m.group(0)),
                          NameStamp(instant=instant, has_time=True, text=m.group(0))))
            break
    if not found:
        return None
    return min(found, key=lambda f: (f[0], f[1]))[2]


def name_timestamp(name: str, pattern: str | None = None) -> NameStamp | None:
    """The timestamp in a file name, or None.

    Parameters
    ----------
    name : str
        The file name (its last path component is used).
    pattern : str, optional
        A strptime-like pattern (see the module docstring); default: the common forms.

    Raises
    ------
    InputError
        A bad pattern (a pattern that does not match gives None here; :func:`logger_clock`
        refuses it).
    """
    name = Path(str(name)).name
    if pattern is None:
        return _default_stamp(name)
    spec = ClockSpec(pattern=pattern)
    for m in spec._pattern_regex.finditer(name):
        try:
            instant = datetime.strptime(m.group(0), pattern)
        except ValueError:
            continue
        return NameStamp(instant=instant, has_time=spec._pattern_has_time, text=m.group(0))
    return None


# --- from columns ----------------------------------------------------------------------------

class _Bad(Exception):
    """A clock field that cannot be read (the message's tail)."""


class _NoDate(Exception):
    """A time of day with no date anywhere."""


@dataclass(frozen=True)
class _Clock:
    value: datetime
    day_less: bool          # a time of day whose date is not in the row itself
    resolution: float       # s, how finely it is written


def _decimals(text: str) -> float:
    """Resolution of a number or an ISO time written with a fraction of a second, s."""
    m = _FRACTION.search(text.rsplit(":", 1)[-1])
    return 10.0 ** -len(m.group(1)) if m else 1.0


def _time_of_day(text: str, decimal: str) -> float | None:
    """Seconds since midnight of a number or a time text; None if it is neither."""
    s = text.replace(",", ".") if decimal == "," else text
    if _NUMBER.fullmatch(s):
        if _COMPACT.fullmatch(s):  # 083000: HHMMSS, or seconds padded? it cannot tell
            raise _Bad(f"{text!r} reads as HHMMSS or as seconds since midnight: set the "
                       "clock's format (\"%H%M%S\") for the first")
        v = float(s)
        if not (math.isfinite(v) and 0.0 <= v < 86400.0):
            raise _Bad(f"{text!r} is not a time of day (s since midnight, 0 to 86400)")
        return v
    try:
        t = time.fromisoformat(text)
    except ValueError:
        return None
    return t.hour * 3600.0 + t.minute * 60.0 + t.second + t.microsecond * 1e-6


def _parse_date(text: str) -> date:
    try:
        return date.fromisoformat(text)
    except ValueError:
        raise _Bad(f"{text!r} is not a date (YYYY-MM-DD; or set the clock format)") from None


def _midnight(day: date) -> datetime:
    return datetime.combine(day, time())


def _formatted(spec: ClockSpec, row: ClockRow, name_date: date | None) -> _Clock:
    text = row.fields.get(spec.column, "")
    joined = text if spec.date_column is None else \
        f"{row.fields.get(spec.date_column, '')} {text}"
    try:
        dt = datetime.strptime(joined, spec.format)
    except ValueError:
        raise _Bad(f"{joined!r} does not fit the clock format {spec.format!r}") from None
    used = _parse_pattern(spec.format, "format")[1]
    resolution = 1.0 if used & {"S", "f"} else 60.0 if "M" in used else 3600.0
    if _has_date(used):
        return _Clock(value=dt, day_less=False, resolution=resolution)
    if name_date is None:
        raise _NoDate
    return _Clock(value=datetime.combine(name_date, dt.time()), day_less=True,
                  resolution=resolution)


def _row_clock(spec: ClockSpec, row: ClockRow, decimal: str, name_date: date | None) -> _Clock:
    if spec.format is not None:
        return _formatted(spec, row, name_date)
    text = row.fields.get(spec.column, "")
    seconds = _time_of_day(text, decimal)
    if seconds is not None:
        if spec.date_column is not None:
            day = _parse_date(row.fields.get(spec.date_column, ""))
            return _Clock(value=_midnight(day) + timedelta(seconds=seconds), day_less=False,
                          resolution=_decimals(text))
        if name_date is None:
            raise _NoDate
        return _Clock(value=_midnight(name_date) + timedelta(seconds=seconds), day_less=True,
                      resolution=_decimals(text))
    if spec.date_column is not None:
        raise _Bad(f"{text!r} is not a time of day (s since midnight or HH:MM:SS[.f])")
    try:
        date.fromisoformat(text)
    except ValueError:
        pass
    else:
        raise _Bad(f"{text!r} is a date, not a clock time (name its column date_column)")
    try:
        dt = datetime.fromisoformat(text)
    except ValueError:
        raise _Bad(f"{text!r} is not a clock time (s since midnight, ISO 8601 date and time, "
                   "or HH:MM:SS[.f]; or set the clock format)") from None
    return _Clock(value=dt.replace(tzinfo=None), day_less=False, resolution=_decimals(text))


def _name_stamp(spec: ClockSpec, path: Path) -> NameStamp | None:
    if not spec.from_name:
        return None
    stamp = name_timestamp(path.name, spec.pattern)
    if stamp is None and spec.pattern is not None:
        raise InputError(f"{path}: the file name has no clock time in the pattern "
                         f"{spec.pattern!r}")
    return stamp


def logger_clock(spec: ClockSpec | None, path: str | Path, first: ClockRow, last: ClockRow,
                 *, decimal: str = ".", tolerance: float = 0.01) -> datetime | None:
    """The clock at record time 0 of a logger file (``Record.clock``), or None.

    Parameters
    ----------
    spec : ClockSpec or None
        Where the clock comes from (None: the default forms in the file name).
    path : str or path
        The file (its name is searched; messages start with it).
    first, last : ClockRow
        The first and last data rows: their record times and clock fields.
    decimal : str
        The file's decimal mark (for a clock column in s since midnight).
    tolerance : float
        Allowed relative difference between the clock column's and the record's durations,
        on top of the clock's written resolution.

    Raises
    ------
    InputError
        A pattern that the name does not match; a clock column that cannot be read, has no
        date, or does not run with the record's time.
    """
    spec = ClockSpec() if spec is None else spec
    p = Path(path)
    if spec.column is None:
        stamp = _name_stamp(spec, p)
        if stamp is None:
            return None
        if not stamp.has_time:
            return stamp.instant
        return stamp.instant - timedelta(seconds=first.time)
    stamp = None if spec.date_column is not None else _name_stamp(spec, p)
    name_date = None if stamp is None else stamp.instant.date()
    no_date = (f"{p}: the clock column {spec.column!r} gives the time of day, but no date "
               "column is set and the file name has no date")
    if spec.column == TIME:
        if spec.date_column is None:
            if name_date is None:
                raise InputError(no_date)
            midnight = _midnight(name_date)
            return midnight + _day_shift(midnight + timedelta(seconds=first.time), stamp)
        try:
            return _midnight(_parse_date(first.fields.get(spec.date_column, "")))
        except _Bad as exc:
            raise InputError(f"{p}: line {first.line}, column {spec.date_column!r}: "
                             f"{exc}") from None
    clocks = []
    for row in (first, last):
        try:
            clocks.append(_row_clock(spec, row, decimal, name_date))
        except _NoDate:
            raise InputError(no_date) from None
        except _Bad as exc:
            raise InputError(f"{p}: line {row.line}, column {spec.column!r}: {exc}") from None
    c0, c1 = clocks
    start, end = c0.value, c1.value
    if c0.day_less:  # the name's date: the one nearer the name's own time (a file named
        shift = _day_shift(start, stamp)  # 00:00:00.2 whose first row is 23:59:59.7)
        start, end = start + shift, end + shift
    if c1.day_less and end < start:
        end += timedelta(days=1)                    # the time of day wrapped past midnight
    span_clock = (end - start).total_seconds()
    span_time = last.time - first.time
    allowed = max(c0.resolution, c1.resolution) + tolerance * abs(span_time) + 1e-6
    if abs(span_clock - span_time) > allowed:
        raise InputError(f"{p}: the clock column {spec.column!r} runs {span_clock:g} s from "
                         f"line {first.line} to line {last.line}, but the record's time "
                         f"{span_time:g} s (not a clock of these samples?)")
    return start - timedelta(seconds=first.time)


def _day_shift(value: datetime, stamp: NameStamp | None) -> timedelta:
    """Whole days that bring a clock given the file name's date within 12 h of the name's
    own time (none when the name has no time of day)."""
    if stamp is None or not stamp.has_time:
        return timedelta(0)
    days = round((stamp.instant - value).total_seconds() / 86400.0)
    return timedelta(days=days)
