"""Reading numeric CSV tables (logger records, road profiles) with precise messages.

Contract
--------
* :func:`read_numeric_csv` reads a header row of column names and rows of numbers.  Lines
  that are blank or start with ``#`` are skipped anywhere; a UTF-8 byte-order mark is
  ignored; the delimiter is ``,`` unless the header has none and has ``;`` or a tab.
* Every problem is an :class:`~bwim.errors.InputError` naming the file and, where it has
  one, the line (counted in the file, from 1) and the column: an empty file, a duplicate
  or empty column name, a row with the wrong number of fields, an empty cell, text that is
  not a number, a NaN or infinite sample, and no data rows.
* The file's size is checked against :func:`bwim.limits.check_memory` before it is read,
  and a line longer than :data:`MAX_LINE` characters is refused (read line by line).
* :func:`open_regular` opens a file for reading only if it is a regular file: a folder, a
  FIFO (named pipe), a device or a socket is refused at once with a one-line
  :class:`~bwim.errors.InputError` (it is opened without blocking and never read, so a
  FIFO without a writer cannot hang the reader).
* :func:`check_time` validates a time column (s) read from a file: strictly increasing
  always; with a ``tolerance``, also uniformly sampled (no dropped sample, no jitter).
"""

from __future__ import annotations

import csv
import io
import math
import os
import stat
from pathlib import Path

import numpy as np

from bwim.errors import InputError
from bwim.limits import check_memory

__all__ = ["check_time", "decimal_resolution", "open_regular", "read_numeric_csv", "rounding"]


#: Longest line (characters) a numeric CSV file may have: 64 Ki characters hold thousands
#: of channels; a longer line is a damaged or hostile file.
MAX_LINE = 65536

#: Bytes of memory per byte of CSV text while it is parsed (lines, floats, the array).
_BYTES_PER_CHAR = 8


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def _cannot_read(path: Path, exc: BaseException) -> InputError:
    why = getattr(exc, "strerror", None) or str(exc)
    return InputError(f"{path}: cannot read: {why.lower()}")


def open_regular(path: str | os.PathLike) -> io.BufferedReader:
    """``path`` opened for binary reading if it is a regular file (symbolic links
    followed); anything else is refused before a byte is read.

    Raises
    ------
    InputError
        No such file, not a regular file (a folder, a FIFO, a device, a socket), or not
        readable; the message names the path.
    """
    p = Path(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(p, flags)
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except (OSError, ValueError) as exc:
        raise _cannot_read(p, exc) from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = next((name for test, name in _KINDS if test(mode)), "not a file")
            raise InputError(f"{p}: is {kind}, not a regular file")
        if flags & getattr(os, "O_NONBLOCK", 0) and hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return open(fd, "rb", closefd=True)
    except BaseException as exc:
        os.close(fd)
        if isinstance(exc, OSError):
            raise _cannot_read(p, exc) from None
        raise


def _read_lines(path: Path) -> list[str]:
    try:
        with open_regular(path) as raw:
            size = os.fstat(raw.fileno()).st_size
            check_memory(size * _BYTES_PER_CHAR, f"{path}: reading a CSV file of {size} bytes")
            lines = []
            f = io.TextIOWrapper(raw, encoding="utf-8-sig", newline="")
            while line := f.readline(MAX_LINE + 2):
                text = line.rstrip("\r\n")
                if len(text) > MAX_LINE:
                    raise InputError(f"{path}: line {len(lines) + 1} is longer than "
                                     f"{MAX_LINE} characters")
                lines.append(text)
        return lines
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {(exc.strerror or str(exc)).lower()}") from None


def _delimiter(header_line: str) -> str:
    if "," in header_line:
        return ","
    if ";" in header_line:
        return ";"
    if "\t" in header_line:
        return "\t"
    return ","


def read_numeric_csv(
    path: str | os.PathLike, *, delimiter: str | None = None
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Column names, values and line numbers of a numeric CSV file.

    Parameters
    ----------
    path : str or path
    delimiter : str, optional
        Field separator (default: detected from the header).

    Returns
    -------
    names : list of str
        Column names (stripped of surrounding spaces).
    values : ndarray, shape (n_rows, n_columns)
        Every sample finite.
    lines : ndarray of int, shape (n_rows,)
        File line number of each row.
    """
    p = Path(path)
    rows: list[list[float]] = []
    line_numbers: list[int] = []
    content = [(k, line) for k, line in enumerate(_read_lines(p), start=1)
               if line.strip() and not line.lstrip().startswith("#")]
    if not content:
        raise InputError(f"{p}: the file is empty")
    header_no, header_line = content[0]
    sep = _delimiter(header_line) if delimiter is None else delimiter
    names = [n.strip() for n in next(csv.reader([header_line], delimiter=sep))]
    for j, n in enumerate(names):
        if not n:
            raise InputError(f"{p}: line {header_no}: column {j + 1} has no name")
        if n in names[:j]:
            raise InputError(f"{p}: line {header_no}: column {n!r} appears twice")
    try:
        float(names[0])
    except ValueError:
        pass
    else:
        raise InputError(f"{p}: line {header_no}: the first line must name the columns, "
                         f"got {header_line.strip()!r}")
    n_cols = len(names)
    reader = csv.reader((line for _, line in content[1:]), delimiter=sep)
    for (k, _), fields_ in zip(content[1:], reader, strict=True):
        if len(fields_) != n_cols:
            raise InputError(f"{p}: line {k} has {len(fields_)} fields, the header has "
                             f"{n_cols}")
        try:
            row = [float(v) for v in fields_]
        except ValueError:
            row = []
            for j, v in enumerate(fields_):
                try:
                    row.append(float(v))
                except ValueError:
                    what = "empty cell" if not v.strip() else f"{v.strip()!r} is not a number"
                    raise InputError(f"{p}: line {k}, column {names[j]!r}: {what}") from None
        if not all(math.isfinite(v) for v in row):
            j = next(j for j, v in enumerate(row) if not math.isfinite(v))
            what = "NaN sample" if math.isnan(row[j]) else "infinite sample"
            raise InputError(f"{p}: line {k}, column {names[j]!r}: {what}")
        rows.append(row)
        line_numbers.append(k)
    if not rows:
        raise InputError(f"{p}: no data rows after the header")
    return names, np.array(rows, dtype=float), np.array(line_numbers, dtype=int)


def check_time(
    time: np.ndarray,
    lines: np.ndarray,
    *,
    where: object,
    tolerance: float | None = None,
    resolution: float = 0.0,
) -> float:
    """Check a file's time column; return its median step, s.

    Parameters
    ----------
    time : ndarray, shape (n_t,)
        Sample times, s, finite, n_t >= 2.
    lines : ndarray of int, shape (n_t,), or any sequence indexable by sample
        File line number of each sample (for the messages).
    where : str or path
        The file, first word of every message.
    tolerance : float, optional
        Uniform sampling: every step must lie within ``tolerance`` × median step (plus
        ``resolution``) of the median step, and a step longer than 1.5 × the median is a
        dropped sample.  None: only the increase is checked.
    resolution : float
        How finely the file writes time, s (one unit in its last written decimal): steps
        of rounded times differ by up to this much on a perfectly uniform clock (by no
        more than 99 % of the steps differ from the median, when that is less).

    Raises
    ------
    InputError
        A time that does not increase (backwards or repeated), a dropped sample, or a
        step off the median; the message names the file and the line.
    """
    t = np.asarray(time, dtype=float)
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        k = int(bad[0]) + 1
        raise InputError(f"{where}: line {lines[k]}: time {t[k]:g} s does not increase "
                         f"(previous sample {t[k - 1]:g} s)")
    h = float(np.median(dt))
    if tolerance is None:
        return h
    resolution = _allowance(dt, h, t, resolution)
    gap = np.flatnonzero(dt > 1.5 * h + resolution)
    if gap.size:
        k = int(gap[0]) + 1
        raise InputError(f"{where}: line {lines[k]}: time step {dt[k - 1]:g} s after "
                         f"{t[k - 1]:g} s is {dt[k - 1] / h:.3g} x the median step {h:g} s "
                         "(a dropped sample)")
    off = np.flatnonzero(np.abs(dt - h) > tolerance * h + resolution)
    if off.size:
        k = int(off[0]) + 1
        raise InputError(f"{where}: line {lines[k]}: time step {dt[k - 1]:g} s differs from "
                         f"the median step {h:g} s by more than {tolerance:.3g} of it "
                         "(non-uniform sampling)")
    return h


def rounding(time: np.ndarray, resolution: float) -> float:
    """How far rounding may move a step of ``time`` (s) written to ``resolution``: up to
    the resolution, or as much as 99 % of the steps show when that is less (a clock whose
    steps the written decimals hold exactly: 100 Hz written to 2 decimals steps 0.01 s
    every time, and a step of 0.02 s is a dropped sample), plus the floats' own error."""
    t = np.asarray(time, dtype=float)
    dt = np.diff(t)
    return _allowance(dt, float(np.median(dt)), t, resolution)


def _allowance(dt: np.ndarray, h: float, t: np.ndarray, resolution: float) -> float:
    """:func:`rounding` from the steps ``dt`` and their median ``h`` already made."""
    dev = np.abs(dt - h)
    # (the quantile of steps that all equal their median, a clock written exactly, is 0)
    q99 = float(np.quantile(dev, 0.99)) if resolution > 0 and dev.max() > 0 else 0.0
    return min(resolution, q99) + 1e-9 * float(np.max(np.abs(t)))


def decimal_resolution(time: np.ndarray, *, max_decimals: int = 12) -> float:
    """How finely ``time`` was written, s: ``10**-d`` for the fewest decimals ``d`` that
    hold every value (to 1e-9 of a unit in that decimal); 0 when none up to
    ``max_decimals`` does (full precision)."""
    t = np.asarray(time, dtype=float)
    for d in range(max_decimals + 1):
        unit = 10.0 ** -d
        if np.all(np.abs(t / unit - np.round(t / unit)) < 1e-6):
            return unit
    return 0.0
