"""What the commands share: outputs checked before work, record paths, progress on
stderr, small writers."""

from __future__ import annotations

import argparse
import csv
import hashlib
import os
import stat
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from bwim.errors import InputError

__all__ = ["RECORD_SUFFIXES", "CalibrationProgress", "Progress", "bar", "bridge_of", "check_jobs",
           "display_name", "load_records", "locked", "out_file", "out_folder", "quiet",
           "record_paths", "refuse_existing_outputs", "refuse_other_provenance",
           "regular_file", "site_provenance", "unique_stems", "write_csv"]

RECORD_SUFFIXES = (".h5", ".hdf5", ".hdf", ".csv", ".txt")


def quiet() -> bool:
    """No progress bar: stderr (where progress goes) is not a terminal."""
    try:
        return not sys.stderr.isatty()
    except (AttributeError, ValueError):
        return True


def bar(total: int | None, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, disable=quiet(), file=sys.stderr, leave=False)


def _duration(seconds: float) -> str:
    """``"45 s"``, ``"12.5 min"``, ``"3.2 h"``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class Progress:
    """A batch's progress on stderr: a bar (count, total, rate, ETA) on a terminal, else a
    plain line every :attr:`every` seconds.  ``progress(n)``: n items finished so far;
    the first call gives those done before this run (0 if none: not part of the rate)."""

    every = 10.0

    def __init__(self, total: int, desc: str) -> None:
        self.total, self.desc = total, desc
        self.tty = not quiet()
        self.bar = bar(total, desc) if self.tty and total > 1 else None
        self.t0 = self.last = time.perf_counter()
        self.start: int | None = None
        self.n = 0

    def __call__(self, n: int) -> None:
        if self.start is None:
            self.start = n  # done before: not part of the rate
        if self.bar is not None:
            self.bar.update(n - self.n)
        self.n = n
        now = time.perf_counter()
        if not self.tty and self.total > 1 and n > self.start and \
                now - self.last >= self.every:
            self.last = now
            rate = (n - self.start) / max(now - self.t0, 1e-9)
            eta = (self.total - n) / rate
            print(f"bwim: {self.desc}: {n}/{self.total} ({100 * n / self.total:.0f} %), "
                  f"{rate:.3g}/s, ETA {_duration(eta)}", file=sys.stderr, flush=True)

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()


def out_file(path: str | Path, suffixes: Sequence[str] | None = None, *,
              inputs: Sequence[str | Path] = (), force: bool = True) -> Path:
    """An output file that can be written (checked before any work): not one of the
    ``inputs``, and not an existing file unless ``force``."""
    from bwim.io import check_writable
    from bwim.io.outputs import refuse_existing, refuse_input_overwrite

    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{p}: unknown output format {p.suffix!r}; use "
                         f"{' or '.join(suffixes)}")
    refuse_input_overwrite([p], inputs)
    check_writable(p)
    return refuse_existing(p, force=force)


def refuse_existing_outputs(paths: Sequence[Path], *, force: bool,
                            resumable: bool = False) -> None:
    """:class:`InputError` naming the first of ``paths`` that exists (unless ``force``),
    and how many do: checked before any of them is written; ``resumable``: the command
    has ``--resume``, which the message offers too."""
    if force:
        return
    there = [p for p in paths if p.exists() or p.is_symlink()]
    if there:
        more = f" (and {len(there) - 1} more of its outputs)" if len(there) > 1 else ""
        again = ", --resume to go on with what is done there," if resumable else ""
        raise InputError(f"{there[0]} exists{more}; use --force to overwrite{again} or "
                         "another output folder")


def out_folder(path: str | Path) -> Path:
    """An output folder, created if needed, that can be written."""
    from bwim.io import check_writable

    p = Path(path)
    if "\x00" in str(p):
        shown = str(p).replace("\x00", "\\x00")
        raise InputError(f"cannot write in {shown}: the path holds a NUL byte")
    if p.exists() and not p.is_dir():
        raise InputError(f"cannot write in {p}: it is a file, not a folder")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder {p}: {exc.strerror or exc}") from None
    check_writable(p / "summary.csv")
    return p


def locked(folder: Path):
    """The output folder's lock for this run (:class:`bwim.io.outputs.OutputLock`)."""
    from bwim.io.outputs import OutputLock

    return OutputLock(folder)


def record_paths(items: Sequence[str], *, any_suffix: bool = False) -> list[Path]:
    """Record files, folders expanded to the records they hold (sorted); with
    ``any_suffix`` (a logger's exports) every file of a folder."""
    from bwim.io.paths import expand_paths

    paths = expand_paths(items, None if any_suffix else RECORD_SUFFIXES, what="records")
    for p in paths:
        regular_file(p)
    return paths


_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def regular_file(path: Path) -> Path:
    """``path`` if it names a regular file (symbolic links followed); a folder, FIFO,
    device or socket is refused from its ``stat`` alone (a FIFO is never opened: opening
    one for reading waits for a writer)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the name
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InputError(f"{path}: cannot read: {reason.lower()}") from None
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "not a file")
        raise InputError(f"{path}: is {kind}, not a regular file")
    return path


def load_records(paths: Sequence[Path], scenario) -> list:
    from bwim.scenario import load_record

    records = []
    with Progress(len(paths), "reading records") as progress:
        progress(0)
        for p in paths:
            records.append(load_record(p, scenario))
            progress(len(records))
    return records


def check_jobs(jobs: int | None) -> None:
    if jobs is not None and jobs < 1 and jobs != -1:
        raise InputError(f"--jobs must be a positive number or -1 (all cores), got {jobs}")


def display_name(path: Path) -> str:
    """A file name as text that can be printed and written (a name that is not valid
    UTF-8 shows its odd bytes as U+FFFD)."""
    return os.fsencode(path.name).decode("utf-8", "replace")


def unique_stems(paths: Sequence[Path]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for p in paths:
        n = seen.get(p.stem, 0)
        seen[p.stem] = n + 1
        out.append(p.stem if n == 0 else f"{p.stem}_{n + 1}")
    return out


def bridge_of(args: argparse.Namespace, scenario):
    from bwim.scenario import build_bridge, load_bridge

    return load_bridge(args.bridge) if args.bridge else build_bridge(scenario)


def write_csv(path: Path, header: Sequence[str], rows: Sequence[Sequence]) -> None:
    from bwim.io import atomic_open

    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


class CalibrationProgress:
    """``calibrate``'s callback on stderr: a tqdm bar (one tick per optimiser iteration)
    on a terminal, else a plain line at each new stage and every :attr:`every` seconds
    (stage, iteration, best objective, time so far; the optimisers announce no total)."""

    every = 10.0

    def __init__(self) -> None:
        self.tty = not quiet()
        self.bar = bar(None, "calibrating") if self.tty else None
        self.stage = None
        self.t0 = self.last = time.perf_counter()

    def __call__(self, stage: str, iteration: int, best: float) -> None:
        now = time.perf_counter()
        new = stage != self.stage
        self.stage = stage
        if self.bar is not None:
            if new:
                self.bar.set_description(f"calibrating: {stage}")
            self.bar.set_postfix(best=f"{best:.3g}", refresh=False)
            self.bar.update()
        elif new or now - self.last >= self.every:
            self.last = now
            print(f"bwim: calibrating: {stage}: iteration {iteration}, best {best:.4g}, "
                  f"{now - self.t0:.0f} s so far", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def site_provenance(calibration: Sequence[Path], scenario) -> tuple[str, ...]:
    """What a site model is made from (:attr:`bwim.site.SiteModel.provenance`): each
    calibration run's file by name and content digest, in name order, each gauge of the
    scenario by name, kind and position, the calibration truck (axle loads and spacings)
    and how the logger's files are read (columns and scale factors): a model made with
    other loads weighs in their proportion, and one whose readings another scale turns
    reads them off by it (review of stop 37: the truck +10 % or the scale × 1.1 left the
    MFI weights as they were, or +10 %)."""
    from bwim.scenario import build_logger_format, build_sensors, build_site_setup

    runs = []
    for p in sorted(calibration, key=lambda q: q.name):
        digest = hashlib.sha256()
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
        runs.append(f"run {p.name} sha256:{digest.hexdigest()[:16]}")
    gauges = [f"gauge {g.name} {g.kind.value} x={g.x!r} y={g.y!r}"
              for g in build_sensors(scenario) if g.kind.is_structural]
    setup = build_site_setup(scenario)
    truck = (f"truck axle loads {[float(v) for v in setup.calibration_loads]!r} N, "
             f"spacings {[float(v) for v in setup.calibration_spacings]!r} m")
    fmt = build_logger_format(scenario)
    logger = (f"logger columns {list(fmt.columns)!r} scales "
              f"{[float(v) for v in fmt.scales]!r}")
    return (*runs, *gauges, truck, logger)


def refuse_other_provenance(model, calibration: Sequence[Path], scenario) -> None:
    """Refuse a site model made from other calibration runs, gauges, truck or logger
    settings than these (one line naming the first difference); a model without a record
    passes."""
    made = tuple(getattr(model, "provenance", ()))
    if not made:
        return
    now = site_provenance(calibration, scenario)
    if now != made:
        missing = [x for x in made if x not in now]
        extra = [x for x in now if x not in made]
        first = (f"it was made with {missing[0]!r}" if missing else
                 f"it was not made with {extra[0]!r}")
        raise InputError(f"the site model was calibrated from other calibration runs or "
                         f"gauges than these, or another truck or logger setting ({first}): "
                         "calibrate it again (bwim calibrate), or give its own runs and "
                         "scenario")
