"""Reading logger text files (issue 21 item 6, issue 22 item 5): bwim.io.read_logger.

Typical event files as a real installation writes them (19 tab-separated columns with a
header: time, two lane-1 axle detectors, 12 gauges, two lane-3 detectors, two digital
status columns; 512 Hz; 1, 2 and 3 s; the time column from 0 with 6 decimals, or the
clock time of day with 9 decimals) and one long recording (``--minutes``, default 10;
``--minutes 60`` is the hour at 512 Hz × 20 channels of issue 21) are read by:

* ``read_logger`` (the default: each chunk's rows and fields found and its plain decimals
  read by one compiled pass, :mod:`bwim.io.field_kernels`);
* ``read_logger(vectorised=False)``: every line parsed one by one, the reader's reference
  path and the algorithm of the implementation before the vectorised parser (the
  baseline of the speed-up);
* ``numpy.loadtxt`` (the numeric columns, no validation) and ``pandas.read_csv`` (when
  pandas is installed; otherwise the column says so).

Every ratio is measured in the same run (median wall time of repeats, one core, one BLAS
thread).  Events/s is reading alone, one file after the other.  The long file is also read
in a child process that reports the peak of its allocated memory (tracemalloc, numpy's
arrays included) while reading, beside the size of the record's arrays (the reader
streams: the data array plus one chunk's work, then the checks' temporaries).

    python -m benchmarks.bench_logger [--minutes 60]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

from benchmarks._timing import median_time, print_table
from bwim.io.logger import LoggerFormat, read_logger

FS = 512.0
GAUGES = tuple(f"s{k:02d}" for k in range(1, 13))
DETECTORS = ("ad1", "ad2", "ad3", "ad4")
COLUMNS = ("time", "ad1", "ad2", *GAUGES, "ad3", "ad4", "-", "-")
KINDS = {d: "axle_detector" for d in DETECTORS}
N_NUMERIC = 17                    # time, 4 detectors, 12 gauges


def write_event(path: Path, seconds: float, *, clock: bool, seed: int = 0) -> None:
    """A typical event file: the layout of the module docstring, readings in logger units
    written with 3 decimals (gauges of a few hundred units, detector pulses), statuses."""
    rng = np.random.default_rng(seed)
    n = round(seconds * FS)
    t = (36000.0 if clock else 0.0) + np.arange(n) / FS
    gauges = 400.0 * np.exp(-((np.arange(n) / n - 0.5) / 0.15) ** 2)[:, None] \
        * rng.uniform(0.2, 1.0, 12) + rng.normal(0, 2.0, (n, 12)) + rng.uniform(-50, 50, 12)
    detectors = rng.normal(0, 0.3, (n, 4)) + 5.0 * (rng.uniform(size=(n, 4)) < 0.02)
    status = rng.integers(0, 2, (n, 2))
    table = np.column_stack([t, detectors[:, :2], gauges, detectors[:, 2:], status])
    fmt = ["%.9f" if clock else "%.6f"] + ["%.3f"] * 16 + ["%d", "%d"]
    header = "\t".join(["time", *COLUMNS[1:-2], "status1", "status2"])
    np.savetxt(path, table, fmt=fmt, delimiter="\t", header=header, comments="")


def write_long(path: Path, minutes: float, channels: int = 20, seed: int = 1) -> int:
    """A continuous recording: time and ``channels`` gauges at 512 Hz, written in blocks."""
    rng = np.random.default_rng(seed)
    n = round(minutes * 60 * FS)
    with open(path, "w") as f:
        f.write("\t".join(["time", *(f"g{j:02d}" for j in range(channels))]) + "\n")
        for k0 in range(0, n, 100_000):
            k = np.arange(k0, min(n, k0 + 100_000))
            v = rng.normal(0, 30.0, (k.size, channels)) + 100.0
            np.savetxt(f, np.column_stack([k / FS, v]), delimiter="\t",
                       fmt=["%.6f"] + ["%.3f"] * channels)
    return n


def _pandas():
    try:
        import pandas
    except ImportError:
        return None
    return pandas


FORMAT = LoggerFormat(columns=COLUMNS, kinds=KINDS)


def event_rows(repeat: int = 7):
    pd = _pandas()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for clock in (False, True):
            for seconds in (1.0, 2.0, 3.0):
                p = Path(tmp) / f"event_{seconds:g}s.txt"
                write_event(p, seconds, clock=clock)
                new = median_time(lambda p=p: read_logger(p, FORMAT), repeat=repeat)
                old = median_time(lambda p=p: read_logger(p, FORMAT, vectorised=False),
                                  repeat=repeat)
                lt = median_time(lambda p=p: np.loadtxt(p, delimiter="\t", skiprows=1,
                                                        usecols=range(N_NUMERIC)),
                                 repeat=repeat)
                pdt = (median_time(lambda p=p: pd.read_csv(p, sep="\t",
                                                           usecols=range(N_NUMERIC)),
                                   repeat=repeat) if pd else None)
                rows.append([
                    "clock of day, 9 dec." if clock else "from 0, 6 dec.", f"{seconds:g}",
                    f"{p.stat().st_size / 1024:.0f}", f"{1e3 * new:.2f}", f"{1 / new:.0f}",
                    f"{1e3 * old:.2f}", f"{old / new:.1f}", f"{1e3 * lt:.2f}",
                    f"{lt / new:.1f}",
                    "no pandas" if pdt is None else f"{1e3 * pdt:.2f} ({pdt / new:.1f})"])
    return rows


_CHILD = textwrap.dedent("""
    import sys, tracemalloc
    from bwim.io.logger import LoggerFormat, read_logger
    path, columns = sys.argv[1], tuple(sys.argv[2].split(","))
    fmt = LoggerFormat(columns=columns)
    tracemalloc.start()
    r = read_logger(path, fmt, max_bytes=2**33, max_samples=10**8, clip_run=None)
    print(tracemalloc.get_traced_memory()[1], r.data.nbytes + r.time.nbytes)
""")


def long_rows(minutes: float, *, baselines: bool = True):
    pd = _pandas()
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "long.txt"
        n = write_long(p, minutes)
        columns = ("time", *(f"g{j:02d}" for j in range(20)))
        fmt = LoggerFormat(columns=columns)
        size = p.stat().st_size
        kw = dict(max_bytes=2**33, max_samples=10**8, clip_run=None)

        def once(fn):
            t0 = time.perf_counter()
            fn()
            return time.perf_counter() - t0

        new = once(lambda: read_logger(p, fmt, **kw))
        out = subprocess.run([sys.executable, "-c", _CHILD, str(p), ",".join(columns)],
                             capture_output=True, text=True, check=True).stdout.split()
        peak, arrays = (float(v) for v in out)
        row = [f"{minutes:g} min, {n} rows", f"{size / 2**20:.0f}", f"{new:.2f}",
               f"{size / 2**20 / new:.0f}", f"{minutes * 60 / new:.0f}",
               f"{peak / 2**20:.0f} / {arrays / 2**20:.0f}"]
        if baselines:
            old = once(lambda: read_logger(p, fmt, vectorised=False, **kw))
            lt = once(lambda: np.loadtxt(p, delimiter="\t", skiprows=1))
            pdt = once(lambda: pd.read_csv(p, sep="\t")) if pd else None
            row += [f"{old:.1f} ({old / new:.1f})", f"{lt:.1f} ({lt / new:.1f})",
                    "no pandas" if pdt is None else f"{pdt:.1f} ({pdt / new:.1f})"]
        else:
            row += ["-", "-", "-"]
    return [row]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0,
                    help="length of the long recording (default 10; 60: one hour)")
    ap.add_argument("--no-baselines", action="store_true",
                    help="long file: read_logger only (the line-by-line path takes minutes "
                         "on an hour)")
    args = ap.parse_args(argv)
    print_table("Logger event files (19 columns, 512 Hz, tab, header): reading, one core",
                ["time column", "s", "KiB", "read_logger ms", "events/s",
                 "line by line ms", "speed-up", "loadtxt ms", "loadtxt / ours",
                 "pandas ms (/ ours)"],
                event_rows())
    print_table("A long recording (time + 20 channels, 512 Hz): streamed",
                ["file", "MiB", "read_logger s", "MiB/s", "x real time",
                 "peak / arrays MiB", "line by line s (x)", "loadtxt s (x)",
                 "pandas s (x)"],
                long_rows(args.minutes, baselines=not args.no_baselines))


if __name__ == "__main__":
    main()
