"""A chunk of a logger file's text, split into rows and fields and read in one compiled pass.

Contract
--------
* :func:`scan_rows` reads a chunk of a logger file for :mod:`bwim.io.logger`: whole lines
  as UTF-8 ``bytes``, ``\\n`` ending each (the file is read with universal newlines;
  the file's last line may lack it).  In one pass over the bytes it skips blank lines
  (spaces and tabs only) and comment lines (``#`` the first non-blank character), splits
  every other line into fields (the delimiter ``" "``: runs of spaces and tabs; else the
  one byte ``;``, ``,`` or tab, one empty field past the last column dropped), checks
  their count and lengths, and reads the time column's and the channels' fields that are
  **plain decimals** (an optional sign ``+`` or ``-``, 1 to :data:`MAX_DIGITS` digits,
  at most one decimal mark, ``.`` or with ``comma`` ``,``, nothing else) while it looks
  for their ends; an empty or NaN field (``nan`` in any case, signs before it, spaces
  and tabs around it) of a gap column (a temperature channel) is NaN.
  Skipped and clock columns are never read as numbers.
* **Exactness.**  A plain field's digits, the mark left out, form an integer ``m <
  10**14 < 2**53`` (built in 64 bits from at most ``MAX_DIGITS + 2`` bytes, so it never
  overflows), exact as a double, and its value is ``m / 10**d`` (``d`` digits after the
  mark; ``10**d`` exact): one rounding, the double that ``float`` gives (Clinger's fast
  path: W. D. Clinger, *How to read floating point numbers accurately*, PLDI 1990; a
  sign negates it exactly, ``-0`` included).  The reference in the tests is ``float``
  itself (tests/unit/test_field_kernels.py).  The reading is written out in the
  kernel, not called (as a separate compiled function, inlined or not, the kernel took
  30 to 70 % longer).
* What it is not sure of it leaves to the caller, who reads the chunk line by line (the
  precise messages, :mod:`bwim.io.logger`): :attr:`ChunkRows.status` is then not
  :attr:`Scan.OK` and nothing else is meaningful.  So: a line longer than ``max_line``
  bytes or a field longer than ``max_field`` bytes (limits in characters: a character is
  never more than one byte, the line-by-line path decides), a content row with too few
  or too many fields (or text past its last column), more than ``max_rows`` content
  rows, more numeric fields that are not plain decimals than one per 8 characters (their
  list's memory), and any byte whose meaning ``str.strip`` or ``str.split`` may change:
  a control character other than tab in a content row or as a line's first non-blank
  character, a non-ASCII first non-blank character (perhaps Unicode whitespace), and
  non-ASCII anywhere in a content row with the whitespace delimiter.  A numeric field
  that is not a plain decimal (``1e-06``, ``" 2"``, ``"3"`` in quotes, a 17-digit
  repr, text) is listed in :attr:`ChunkRows.bad` for the caller to read as ``float``
  does, or to refuse.
* Units: byte offsets into the chunk; line numbers counted from ``first_line`` (the
  chunk's first line); numbers as written (no scale).
* Compiled with numba (``njit(cache=True)``, no fastmath, no parallel; one signature:
  :func:`scan_rows` passes the same types every time); the first call in a process
  compiles it or loads it from numba's cache.
* Memory: at most ``n_chars // n_columns + 1`` rows (a content row has at least one
  character per column, its newline counted) of 8 bytes per number and line number:
  at most 16 bytes per character of the chunk; the list of fields that are not plain at
  most 32 bytes per 8 characters (12 bytes per character while it grows).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["GAP", "MAX_DIGITS", "SKIP", "TIME", "ChunkRows", "Scan", "scan_rows"]

#: Digits a plain field may have (its integer, the mark left out, stays below 2**53).
MAX_DIGITS = 14

#: ``slots`` entry of a column that is not read (skipped, a clock column).
SKIP = -1
#: ``slots`` entry of the time column.
TIME = -2
#: ``gaps`` marks a column whose empty or NaN fields are NaN (a temperature channel).
GAP = 1


def _powers_of_ten() -> np.ndarray:
    """10**0 … 10**MAX_DIGITS, each exact (products of exact integers below 2**53),
    read-only."""
    out = np.ones(MAX_DIGITS + 1)
    for i in range(1, out.size):
        out[i] = out[i - 1] * 10.0
    out.flags.writeable = False
    return out


_POWERS_OF_TEN = _powers_of_ten()


class Scan(enum.IntEnum):
    """What :func:`scan_rows` made of a chunk: read (``OK``), or why not."""

    OK = 0
    LONG_LINE = 1      #: a line longer than ``max_line`` bytes
    FIELD_COUNT = 2    #: a content row with too many or too few fields
    LONG_FIELD = 3     #: a field longer than ``max_field`` bytes
    MANY_ROWS = 4      #: more than ``max_rows`` content rows
    UNUSUAL = 5        #: a byte whose meaning the line-by-line rules may change
    OTHERS = 6         #: more numeric fields that are not plain than one per 8 characters


@dataclass(frozen=True, eq=False)
class ChunkRows:
    """:func:`scan_rows`' result (its arrays are the caller's to fill in: ``bad``).

    ``values`` (rows, n_channels) the channels' numbers in ``slots`` order, ``time``
    (rows,) the time column (None without one), ``lines`` (rows,) each row's line number,
    ``decimals`` the most digits after the mark among the time column's plain fields,
    ``edges`` (4, n_columns) the first and the last row's field starts and ends, ``bad``
    (k, 4) row, column, start, end of the numeric fields that are not plain decimals,
    ``space_lines`` the lines of spaces and tabs only (blank but not empty), ``n_lines``
    the chunk's lines; when the status is not OK nothing is meaningful."""

    status: Scan
    values: np.ndarray
    time: np.ndarray | None
    lines: np.ndarray
    decimals: int
    edges: np.ndarray
    bad: np.ndarray
    space_lines: int
    n_lines: int


@numba.njit(cache=True, nogil=True)
def _is_gap(a, s, e):  # pragma: no cover - compiled
    """Whether ``a[s:e]`` is blanks, or ``[+-]*nan`` (any case) between blanks."""
    while s < e and (a[s] == 32 or a[s] == 9):
        s += 1
    while e > s and (a[e - 1] == 32 or a[e - 1] == 9):
        e -= 1
    while s < e and (a[s] == 43 or a[s] == 45):
        s += 1
    if s == e:
        return True
    return (e - s == 3 and (a[s] | 32) == 110 and (a[s + 1] | 32) == 97
            and (a[s + 2] | 32) == 110)


@numba.njit(cache=True, nogil=True)
def _spans(a, pos, delim, fs, fe):  # pragma: no cover - compiled
    """Starts and ends of the fields of the content row at ``pos`` (one already read)."""
    size = a.size
    i = pos
    for j in range(fs.size):
        if delim == 0:
            while i < size and (a[i] == 32 or a[i] == 9):
                i += 1
        elif j > 0:
            i += 1
        fs[j] = i
        while i < size and a[i] != 10 and (a[i] != delim if delim != 0
                                           else (a[i] != 32 and a[i] != 9)):
            i += 1
        fe[j] = i


@numba.njit(cache=True, nogil=True)
def _scan(a, n_chars, delim, slots, gaps, n_channels, has_time, mark, max_line, max_field,
          max_rows, first_line, max_digits, p10):  # pragma: no cover - compiled
    size = a.size
    n = slots.size
    cap = n_chars // n + 1  # a content row has at least n characters, its newline counted
    max_bad = n_chars // 8 + 16
    values = np.empty((cap, n_channels))
    time = np.empty(cap if has_time else 0)
    lines = np.empty(cap, dtype=np.int64)
    bad = np.empty((16, 4), dtype=np.int64)
    n_bad = 0
    decimals = 0
    spaces = 0
    m = 0
    line = first_line
    pos = 0
    first_row = 0
    last_row = 0
    status = 0
    while pos < size:
        q = pos
        while q < size and (a[q] == 32 or a[q] == 9):
            q += 1
        c = a[q] if q < size else 10
        if c == 10 or c == 35:  # a blank line, a comment: to its end
            end = q
            while end < size and a[end] != 10:
                end += 1
            if end - pos > max_line:
                status = 1
                break
            if c == 10 and q > pos:
                spaces += 1
            pos = end + 1
            line += 1
            continue
        if c < 32 or c >= 128:
            status = 5
            break
        if m == max_rows or m == cap:
            status = 4
            break
        # a content row, field by field; i: where the field starts, then its end
        i = q if delim == 0 else pos
        for j in range(n):
            if j > 0:  # i is at the end of the field before
                if delim == 0:
                    while i < size and (a[i] == 32 or a[i] == 9):
                        i += 1
                if i >= size or a[i] == 10:
                    status = 2  # too few fields
                    break
                if delim != 0:
                    i += 1
            s = i
            slot = slots[j]
            v = np.nan
            after = -1
            if slot != -1:
                # the plain decimal the field starts with (written out here, not called:
                # see the contract); at most max_digits + 2 bytes
                limit = min(size, s + max_digits + 2)
                negative = False
                if i < limit:
                    lead = a[i]
                    if lead == 45:
                        negative = True
                        i += 1
                    elif lead == 43:
                        i += 1
                mantissa = 0  # the digits, the mark left out (< 10**16: no overflow)
                n_digit = 0
                n_mark = 0
                after = 0
                while i < limit:
                    d = np.int64(a[i])
                    if 48 <= d <= 57:
                        mantissa = mantissa * 10 + (d - 48)
                        n_digit += 1
                        after += n_mark
                    elif d == mark and n_mark == 0:
                        n_mark = 1
                    else:
                        break
                    i += 1
                if n_digit < 1 or n_digit > max_digits:
                    after = -1
                else:
                    v = float(mantissa) / p10[after]  # both exact: one rounding
                    if negative:
                        v = -v
            plain_end = i
            # the field's end
            if delim == 0:
                while i < size:
                    c = a[i]
                    if c == 32 or c == 9 or c == 10:
                        break
                    if c < 32 or c >= 128:
                        status = 5
                        break
                    i += 1
            else:
                while i < size:
                    c = a[i]
                    if c == delim or c == 10:
                        break
                    if c < 32 and c != 9:
                        status = 5
                        break
                    i += 1
            if status != 0:
                break
            if i - s > max_field:
                status = 3
                break
            if slot == -1:
                continue
            if i != plain_end or after < 0:  # not a plain decimal
                after = -1
                v = np.nan
                if gaps[j] != 1 or not _is_gap(a, s, i):
                    if n_bad == max_bad:
                        status = 6
                        break
                    if n_bad == bad.shape[0]:
                        grown = np.empty((2 * n_bad, 4), dtype=np.int64)
                        grown[:n_bad] = bad
                        bad = grown
                    bad[n_bad, 0] = m
                    bad[n_bad, 1] = j
                    bad[n_bad, 2] = s
                    bad[n_bad, 3] = i
                    n_bad += 1
            if slot == -2:
                time[m] = v
                if after > decimals:
                    decimals = after
            else:
                values[m, slot] = v
        if status != 0:
            break
        # past the last field: the line's end (a trailing delimiter: an empty field)
        if delim == 0:
            while i < size and (a[i] == 32 or a[i] == 9):
                i += 1
        elif i < size and a[i] == delim:
            i += 1
        if i < size and a[i] != 10:
            status = 2  # more fields
            break
        if i - pos > max_line:
            status = 1
            break
        if m == 0:
            first_row = pos
        last_row = pos
        lines[m] = line
        m += 1
        pos = i + 1
        line += 1
    edges = np.zeros((4, n), dtype=np.int64)
    if status != 0:
        m = 0
        n_bad = 0
    elif m > 0:
        _spans(a, first_row, delim, edges[0], edges[1])
        _spans(a, last_row, delim, edges[2], edges[3])
    return (status, m, values, time, lines, decimals, edges, bad[:n_bad].copy(), spaces,
            line - first_line)


def scan_rows(data: bytes, *, n_chars: int, delimiter: str, slots: np.ndarray,
              gaps: np.ndarray, n_channels: int, has_time: bool, comma: bool, max_line: int,
              max_field: int, max_rows: int, first_line: int) -> ChunkRows:
    """The content rows of the chunk ``data`` (UTF-8 bytes of whole lines; ``n_chars``
    characters), see the module docstring.

    ``delimiter`` is ``" "`` (runs of spaces and tabs) or one of ``;`` ``,`` tab;
    ``slots`` (n_columns,) int64 says where each column's numbers go: a channel's index
    in ``values`` (0 … n_channels − 1), :data:`TIME`, or :data:`SKIP`; ``gaps``
    (n_columns,) uint8, :data:`GAP` for a column whose empty or NaN fields are NaN;
    ``comma``: the decimal mark is ``,``; ``max_line``, ``max_field`` in bytes;
    ``max_rows`` content rows at most; ``first_line`` the number of the chunk's first
    line."""
    status, m, values, time, lines, decimals, edges, bad, spaces, n_lines = _scan(
        np.frombuffer(data, dtype=np.uint8), n_chars,
        0 if delimiter == " " else ord(delimiter), slots, gaps, n_channels, has_time,
        44 if comma else 46, max_line, max_field, max_rows, first_line, MAX_DIGITS,
        _POWERS_OF_TEN)
    return ChunkRows(status=Scan(status), values=values[:m],
                     time=time[:m] if has_time else None, lines=lines[:m],
                     decimals=int(decimals), edges=edges, bad=bad, space_lines=int(spaces),
                     n_lines=int(n_lines))
