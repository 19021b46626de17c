"""Cutting a continuous recording into events (issue 21 item 2): bwim.stream.

A long logger file at 512 Hz with 20 columns (time, four axle detectors, twelve gauges, two
statuses: the real site's layout plus one) and a crossing every 10 s (half-sine pulses on
the gauges, noise on every channel) is cut:

* **streamed**: :func:`bwim.stream.cut_file` (blocks of :data:`bwim.stream.ROWS` rows read
  by ``read_logger``, the trigger across the blocks);
* **whole**: ``read_logger`` on the whole file, then :func:`bwim.stream.cut_events` (the
  baseline of this benchmark: the same parser, all in memory);
* **trigger alone**: :func:`bwim.stream.cut_events` on the record already in memory.

**The same vehicles as the pre-cut files** (``--day N``, default 24 traffic events): a
small realistic day (:func:`bwim.synthetic.make_test_day`, ``short-span-4-lane``, seed 7)
is written as one long file (:func:`bwim.synthetic.make_continuous`), cut by the trigger
(default settings, and wider windows), and every event is weighed
(:func:`bwim.site.weigh_event`, drift correction off: the long file moves the events'
clocks) beside its own file; also the long file cut at each file's own window (the
re-levelled samples and the gaps alone).  The table counts the events whose vehicles are
all alike (lane, direction, weighed or not, axle count, speed within 0.1 %, GVW within
0.5 %), the vehicles found and of them those that match a vehicle that crossed in their
event (``truth.csv``: direction, axle count, speed within 10 %; the others are traces of
another vehicle, the span's bending or a vehicle in a lane without detectors, which the
file's window and the trigger's can find differently), and the largest differences of
the trucks weighed from both.

Throughput is the recording's duration over the wall time (× real time, one core, one
BLAS thread), every ratio measured in the same run.  The peak of allocated memory
(tracemalloc, numpy's arrays included) is measured in a child process for the streamed
and the whole cut, beside the size of the whole record's arrays.  Both cuts must find the
same events (checked).

    python -m benchmarks.bench_stream [--minutes 60] [--day 24]
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from bwim.io.logger import LoggerFormat, read_logger
from bwim.stream import cut_events, cut_file

FS = 512.0
GAUGES = tuple(f"s{k:02d}" for k in range(1, 13))
DETECTORS = ("ad1", "ad2", "ad3", "ad4")
COLUMNS = ("time", "ad1", "ad2", *GAUGES, "ad3", "ad4", "-", "-", "-")
KINDS = {d: "axle_detector" for d in DETECTORS}
FORMAT = LoggerFormat(columns=COLUMNS, kinds=KINDS, sampling_rate=FS)
EVERY = 10.0  #: s between crossings
WHOLE = {"max_bytes": 2**34, "max_samples": 10**9}


def write_long(path: Path, minutes: float, seed: int = 0) -> int:
    """The recording of the module docstring, written in blocks; its number of rows."""
    rng = np.random.default_rng(seed)
    n = round(minutes * 60 * FS)
    weights = rng.uniform(0.2, 1.0, 12)
    offsets = rng.uniform(-50, 50, 12)
    with open(path, "w") as f:
        for k0 in range(0, n, 100_000):
            k = np.arange(k0, min(n, k0 + 100_000))
            t = k / FS
            phase = (t % EVERY) - EVERY / 2           # a 1.2 s pulse in every 10 s
            pulse = np.where(np.abs(phase) < 0.6, np.cos(np.pi * phase / 1.2), 0.0)
            gauges = 300.0 * pulse[:, None] * weights + offsets \
                + rng.normal(0, 0.5, (k.size, 12))
            det = rng.normal(0, 0.3, (k.size, 4))
            status = np.ones((k.size, 3))
            table = np.column_stack([t, det[:, :2], gauges, det[:, 2:], status])
            np.savetxt(f, table, delimiter="\t",
                       fmt=["%.9f"] + ["%.3f"] * 16 + ["%d"] * 3)
    return n


_CHILD = textwrap.dedent("""
    import sys, tracemalloc
    from benchmarks.bench_stream import FORMAT, WHOLE
    from bwim.io.logger import read_logger
    from bwim.stream import cut_events, cut_file
    path, mode = sys.argv[1], sys.argv[2]
    tracemalloc.start()
    if mode == "streamed":
        n = sum(1 for _ in cut_file(path, FORMAT))
    else:
        r = read_logger(path, FORMAT, **WHOLE)
        n = len(cut_events(r).events)
    print(tracemalloc.get_traced_memory()[1], n)
""")


def _peak(path: Path, mode: str) -> tuple[float, int]:
    root = Path(__file__).resolve().parent.parent
    out = subprocess.run([sys.executable, "-c", _CHILD, str(path), mode], cwd=root,
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), int(out[1])


def rows(minutes: float):
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "long_2026-04-17-12-00-00-000.txt"
        n = write_long(p, minutes)
        seconds = n / FS

        t0 = time.perf_counter()
        streamed = list(cut_file(p, FORMAT))
        t_stream = time.perf_counter() - t0

        t0 = time.perf_counter()
        record = read_logger(p, FORMAT, **WHOLE)
        t_read = time.perf_counter() - t0
        t0 = time.perf_counter()
        whole = cut_events(record).events
        t_trigger = time.perf_counter() - t0
        if [(e.start_index, e.stop_index) for e in whole] != \
                [(e.start_index, e.stop_index) for e in streamed]:
            raise RuntimeError("the streamed and the whole cut differ")
        arrays = record.data.nbytes + record.time.nbytes
        del record
        peak_stream, _ = _peak(p, "streamed")
        peak_whole, _ = _peak(p, "whole")
        size = p.stat().st_size / 2**20
        label = f"{minutes:g} min, {n} rows, {size:.0f} MiB"
        t_whole = t_read + t_trigger
        return [
            [label, "streamed (cut_file)", f"{t_stream:.2f}", f"{seconds / t_stream:.0f}",
             f"{peak_stream / 2**20:.0f}", f"{len(streamed)}"],
            [label, "whole (read_logger + cut_events)", f"{t_whole:.2f}",
             f"{seconds / t_whole:.0f}", f"{peak_whole / 2**20:.0f}", f"{len(whole)}"],
            [label, "trigger alone (in memory)", f"{t_trigger:.2f}",
             f"{seconds / t_trigger:.0f}", "-", f"{len(whole)}"],
            [label, "streamed / whole", f"{t_stream / t_whole:.2f}", "-",
             f"{peak_stream / peak_whole:.3f} (arrays {arrays / 2**20:.0f} MiB)", "-"],
        ]


def _vehicles(weighing):
    return [(v.weighed, v.lane, v.vehicle.passage.n_axles, v.vehicle.passage.speed, v.gvw,
             v.direction) for v in weighing.vehicles]


def _true(vehicle, truth: list[dict]) -> bool:
    """Whether a vehicle found matches one that crossed in its event (direction, axle
    count, speed within 10 %): else it is a trace of another (the span's bending, a
    vehicle in a lane without detectors, read by a pair)."""
    return any(t["direction"] == vehicle[5] and int(t["n_axles"]) == vehicle[2]
               and abs(float(t["speed_m_s"]) / vehicle[3] - 1.0) < 0.1 for t in truth)


def _alike(a, b) -> bool:
    return (a[:3] == b[:3] and a[5] == b[5] and abs(a[3] / b[3] - 1) < 1e-3
            and (a[4] is None or abs(a[4] / b[4] - 1) < 5e-3))


def day_rows(n_traffic: int, seed: int = 7):
    """The comparison of the module docstring on a simulated day."""
    import dataclasses

    from bwim.scenario import (
        build_logger_format,
        build_sensors,
        build_site_setup,
        load_record,
        load_scenario,
    )
    from bwim.site import DriftSetup, calibrate_site, weigh_event
    from bwim.stream import TriggerSettings
    from bwim.synthetic import make_continuous, make_test_day

    with tempfile.TemporaryDirectory() as tmp:
        site = make_test_day(Path(tmp) / "site", site="short-span-4-lane", seed=seed,
                             n_calibration=6, n_traffic=n_traffic,
                             n_calibration_day_traffic=0, mesh=0.6)
        cont = make_continuous(site.out_dir, Path(tmp) / "long", seed=1)
        sc = load_scenario(site.scenario)
        setup = dataclasses.replace(build_site_setup(sc), drift=DriftSetup(method="none"))
        cal = calibrate_site([load_record(p, sc) for p in site.calibration], setup)
        fmt, sensors = build_logger_format(sc), build_sensors(sc)
        refs = [_vehicles(weigh_event(load_record(p.source, sc), cal))
                for p in cont.placements]
        with open(site.truth, newline="", encoding="utf-8") as f:
            by_record: dict[str, list[dict]] = {}
            for t in csv.DictReader(f):
                by_record.setdefault(t["record"], []).append(t)
        truths = [by_record[p.source.name] for p in cont.placements]
        whole = read_logger(cont.path, fmt, sensors=sensors)
        own = []
        for p in cont.placements:
            a, b = p.start_index, p.stop_index
            own.append(dataclasses.replace(whole, time=whole.time[a:b] - whole.time[a],
                                           data=whole.data[a:b], clock=p.clock))
        cases = [("files' own windows", own)]
        for pre in (0.5, 1.0):
            settings = TriggerSettings(pre=pre, post=pre)
            cut = [e.record for e in cut_file(cont.path, fmt, settings, sensors=sensors)]
            cases.append((f"trigger, pre = post = {pre:g} s", cut))
        out = []
        for label, records in cases:
            if len(records) != len(refs):
                out.append([label, f"{len(records)} events for {len(refs)} files"] +
                           ["-"] * 5)
                continue
            got = [_vehicles(weigh_event(r, cal)) for r in records]
            alike = sum(len(a) == len(b) and all(map(_alike, a, b))
                        for a, b in zip(refs, got, strict=True))
            d_speed, d_gvw, n_w = 0.0, 0.0, 0
            for a, b in zip(refs, got, strict=True):
                wa = {v[1]: v for v in a if v[0]}
                wb = {v[1]: v for v in b if v[0]}
                for lane in wa.keys() & wb.keys():
                    n_w += 1
                    d_speed = max(d_speed, abs(wb[lane][3] / wa[lane][3] - 1))
                    d_gvw = max(d_gvw, abs(wb[lane][4] / wa[lane][4] - 1))
            true_refs = sum(_true(v, t) for vs, t in zip(refs, truths, strict=True) for v in vs)
            true_got = sum(_true(v, t) for vs, t in zip(got, truths, strict=True) for v in vs)
            out.append([label, f"{alike} / {len(refs)}",
                        f"{sum(map(len, refs))} / {sum(map(len, got))}",
                        f"{true_refs} / {true_got}",
                        f"{sum(v[0] for r in refs for v in r)} / "
                        f"{sum(v[0] for r in got for v in r)} ({n_w} in both)",
                        f"{100 * d_speed:.2f}", f"{100 * d_gvw:.2f}"])
        return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=5.0,
                    help="length of the recording (default 5; 60: the hour of issue 21)")
    ap.add_argument("--day", type=int, default=24,
                    help="traffic events of the simulated day compared with its files "
                         "(default 24; 0: skip)")
    args = ap.parse_args(argv)
    if args.day:
        print_table("A simulated day as one long file: the cut events weighed against "
                    "the pre-cut files (vehicles: files / cut)",
                    ["windows", "events alike", "vehicles", "of them true vehicles", "weighed",
                     "max speed diff %", "max GVW diff %"],
                    day_rows(args.day))
    print_table("A continuous recording (20 columns, 512 Hz, a crossing every 10 s) cut into "
                "events, one core",
                ["file", "how", "wall s", "x real time", "peak MiB", "events"],
                rows(args.minutes))


if __name__ == "__main__":
    main()
