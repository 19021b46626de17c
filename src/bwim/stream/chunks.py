"""A long logger file read block by block: consecutive records in bounded memory.

Contract
--------
* :func:`read_chunks` reads a logger text file (the layout of a
  :class:`~bwim.io.LoggerFormat`) in blocks of ``rows`` data rows (the header row counts
  as one) and yields one
  :class:`~bwim.Record` per block.  Each block is parsed by :func:`bwim.io.read_logger`
  itself (its text copied verbatim into a temporary file of the same name), so every rule
  of the format, every check of a block and every message is the reader's; messages name
  the long file and its own line numbers.  The first block keeps the file's preamble
  (``skip_lines``) and header; later blocks have neither.
* The records continue one another: ``time`` is the file's time column as written (s; a
  file without one counts ``k / sampling_rate`` from its first row over the whole file)
  and every record has the clock of the first block (what :func:`bwim.io.read_logger`
  gives the whole file: the clock at record time 0).  Between blocks the time must step
  like inside them (off the first block's median step by at most ``time_tolerance`` of it
  or the largest deviation inside the first block): a dropped sample or a jump at a block
  edge is refused with the lines it lies between.
* Memory: one block's text is on disk, its array in memory: a few times
  ``rows × columns × 8`` bytes whatever the file's length (the whole file is never
  loaded, nor its size limited).  A last block of fewer than two rows joins the block
  before it.
* :func:`cut_file` cuts the file's events (:func:`bwim.stream.trigger.cut_stream` on
  :func:`read_chunks`), yielding each event as it completes.
"""

from __future__ import annotations

import dataclasses
import os
import re
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from bwim.errors import InputError
from bwim.io.logger import LoggerFormat, read_logger
from bwim.records import Record
from bwim.sensors import Sensor
from bwim.stream.events import StreamEvent
from bwim.stream.settings import TriggerSettings
from bwim.stream.trigger import cut_stream

__all__ = ["ROWS", "cut_file", "read_chunks"]

#: Default data rows per block (128 s at 512 Hz).
ROWS = 65536

_LINE = re.compile(r"(?<=\bline )(\d+)")


def _is_content(line: str) -> bool:
    s = line.strip()
    return bool(s) and not s.startswith("#")


def _relabel(exc: InputError, block: Path, path: Path, offset: int) -> InputError:
    """The reader's message about a block, told about the long file (its name and line
    numbers)."""
    text = str(exc).replace(str(block), str(path), 1)
    return InputError(_LINE.sub(lambda m: str(int(m.group(1)) + offset), text))


class _Blocks:
    """The file's lines in blocks of about ``rows`` content lines, each written to
    ``target``; yields the number of raw lines before each block and the block's raw
    lines."""

    def __init__(self, path: Path, rows: int, target: Path, skip: int) -> None:
        self.path, self.rows, self.target, self.skip = path, rows, target, skip

    def __iter__(self) -> Iterator[tuple[int, int]]:
        try:
            with open(self.path, encoding="utf-8-sig", newline=None) as f:
                yield from self._blocks(f)
        except UnicodeDecodeError:
            raise InputError(f"{self.path}: not UTF-8 text") from None
        except OSError as exc:
            why = (exc.strerror or str(exc)).lower()
            raise InputError(f"{self.path}: cannot read: {why}") from None

    def _blocks(self, f) -> Iterator[tuple[int, int]]:
        line_no = 0                 # raw lines read so far
        carry: list[str] = []       # lines read ahead for the next block
        while True:
            first = line_no - len(carry)
            with open(self.target, "w", encoding="utf-8", newline="\n") as out:
                n_content = 0
                for line in carry:
                    out.write(line)
                    n_content += _is_content(line)
                carry = []
                for line in f:
                    line_no += 1
                    out.write(line)
                    n_content += line_no > self.skip and _is_content(line)
                    if n_content >= self.rows:
                        break
                # read ahead: a last block needs at least two rows, else it joins this one
                ahead = 0
                for line in f:
                    line_no += 1
                    carry.append(line)
                    ahead += _is_content(line)
                    if ahead >= 2:
                        break
                if ahead < 2:
                    out.writelines(carry)
                    n_content += ahead
                    carry = []
            if n_content == 0 and first > 0:
                return
            yield first, line_no - len(carry) - first
            if not carry:
                return


def read_chunks(path: str | os.PathLike, fmt: LoggerFormat, *,
                sensors: Sequence[Sensor] | None = None, rows: int = ROWS,
                clip_run: int | None = 10, time_tolerance: float = 0.01,
                max_field: int = 64) -> Iterator[Record]:
    """The records of a long logger file, block by block (see the module docstring).

    Parameters
    ----------
    path : str or path
        The logger file (a regular file).
    fmt : LoggerFormat
        Its layout.
    sensors, clip_run, time_tolerance, max_field
        As for :func:`bwim.io.read_logger` (applied to each block).
    rows : int
        Data rows per block (>= 2).

    Raises
    ------
    InputError
        What :func:`bwim.io.read_logger` refuses in a block (with the long file's name and
        lines); a block that does not continue the one before.
    """
    if not isinstance(fmt, LoggerFormat):
        raise InputError(f"fmt must be a bwim.io.logger.LoggerFormat, got {type(fmt).__name__}")
    if isinstance(rows, bool) or not isinstance(rows, int) or rows < 2:
        raise InputError(f"rows must be an integer >= 2, got {rows!r}")
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file")
    if not p.is_file():
        raise InputError(f"{p}: not a regular file")
    later = dataclasses.replace(fmt, skip_lines=0, header=False)
    with tempfile.TemporaryDirectory(prefix="bwim-chunks-") as tmp:
        block = Path(tmp) / p.name          # the same name: the same clock from it
        first: Record | None = None
        step = allowed = last_time = 0.0
        last_line = offset_rows = 0
        for start, n_lines in _Blocks(p, rows, block, fmt.skip_lines):
            try:
                rec = read_logger(block, fmt if first is None else later, sensors=sensors,
                                  clip_run=clip_run, time_tolerance=time_tolerance,
                                  max_field=max_field)
            except InputError as exc:
                raise _relabel(exc, block, p, start) from None
            n = rec.time.size
            if first is None:
                first = rec
                steps = np.diff(rec.time)
                step = float(np.median(steps))
                # the jitter the reader accepted inside the first block
                allowed = max(time_tolerance * step, float(np.abs(steps - step).max())) \
                    + 1e-9 * max(1.0, abs(float(rec.time[-1])))
            else:
                if fmt.has_time:
                    gap = float(rec.time[0]) - last_time
                    if abs(gap - step) > allowed:
                        raise InputError(
                            f"{p}: the time steps {gap:g} s between line {last_line} and "
                            f"line {start + 1} (the file's step is {step:g} s: a dropped "
                            "sample or a jump)")
                else:
                    rec = dataclasses.replace(rec, time=(offset_rows + np.arange(n))
                                              / fmt.sampling_rate)
                rec = dataclasses.replace(rec, clock=first.clock)
            last_time = float(rec.time[-1])
            last_line = start + n_lines
            offset_rows += n
            yield rec


def cut_file(path: str | os.PathLike, fmt: LoggerFormat,
             settings: TriggerSettings | None = None, *,
             sensors: Sequence[Sensor] | None = None, rows: int = ROWS,
             **read: object) -> Iterator[StreamEvent]:
    """The events of a long logger file, each yielded as soon as it is complete
    (:func:`read_chunks` with ``read`` options, then
    :func:`bwim.stream.trigger.cut_stream`)."""
    yield from cut_stream(read_chunks(path, fmt, sensors=sensors, rows=rows, **read),
                          settings)
