"""Axle detection on the realistic simulated site (issue 20 item 1): counts, spacings,
speeds and time per event of bwim.detect with learned detector responses.

Data (:func:`bwim.synthetic.make_test_day`, ``site="short-span-4-lane"``, seeds 101 and
202: days the code was not developed on; 12 calibration runs, 120 traffic events, 0.5 m
mesh): the installation of issue 20 simulated with its own finite-element slab and
vehicle-bridge interaction on class A-B roads; axle detectors with wide local peaks
(1.2 m), a negative share of the slab's mid-span strain, gains 3-5x apart, tyre types
and lateral wander; half the calibration runs with a vehicle in the other direction.
bwim.detect learns the responses from the calibration runs (known layout) and detects
the traffic; nothing of the simulation is given to it.

Prints, per seed and for the single lane-1 vehicles of the traffic date: axle counts
right (one vehicle, no count-mismatch flag), the spacing and speed error percentiles and
how many meet the issue's targets (spacings within 0.1 m, speed within 0.5 %); for
reference the peak picker without responses, and the floor of the fit: the same
refinement started from the true axle times (what the tyres' dynamic forces leave of
the speed however the axles are found).  Time: detection ms per lane-1 event and per
event of the day (one core), as a ratio to reading the event's file (measured in the
same run).

    python -m benchmarks.bench_detect_site [seed ...]
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from bwim.detect import FLAG_COUNT_MISMATCH, detect_axles, learn_responses
from bwim.io import read_logger

from tests.detect_data import site_axles, site_day

SEEDS = (101, 202)
N_TRAFFIC = 120


def _floor(learned, rec, row) -> float:
    """Speed error (%) of the refinement started from the true axle times and speed."""
    from bwim.detect.vehicle_fit import make_problem, refine

    taus, v, _ = site_axles(row)
    g = rec.channels(list(learned.gauges)).data
    pb = make_problem(rec.time, rec.channels(["ad1", "ad2"]).data, g, learned, v)
    return 100.0 * (refine(pb, taus, v).v / v - 1.0)


def run_seed(seed: int, folder: Path) -> dict:
    t0 = time.perf_counter()
    day, calibration, traffic, truck = site_day(folder / f"day{seed}", seed=seed,
                                                n_traffic=N_TRAFFIC, mesh=0.5)
    t_gen = time.perf_counter() - t0
    t0 = time.perf_counter()
    learned = learn_responses(calibration, ("ad1", "ad2"), 3.0, truck["axle_spacings"],
                              loads=truck["axle_loads"])
    t_learn = time.perf_counter() - t0
    fmt = _format(day.scenario)
    t0 = time.process_time()
    for p in day.traffic:
        read_logger(p, fmt)
    t_read = (time.process_time() - t0) / len(day.traffic)

    n = right = peaks_right = 0
    spacing, speed, floor, misses = [], [], [], []
    t_lane1, t_all = [], []
    for rec, rows in traffic:
        t0 = time.process_time()
        det = detect_axles(rec, ("ad1", "ad2"), 3.0, responses=learned)
        elapsed = time.process_time() - t0
        t_all.append(elapsed)
        if len(rows) != 1 or rows[0]["lane"] != "1":
            continue
        t_lane1.append(elapsed)
        n += 1
        _, v, sp = site_axles(rows[0])
        ok = (det.n_vehicles == 1 and FLAG_COUNT_MISMATCH not in det.flags
              and det.vehicles[0].n_axles == sp.size + 1)
        peaks = detect_axles(rec, ("ad1", "ad2"), 3.0)
        peaks_right += (peaks.n_vehicles == 1 and FLAG_COUNT_MISMATCH not in peaks.flags
                        and peaks.vehicles[0].n_axles == sp.size + 1)
        floor.append(abs(_floor(learned, rec, rows[0])))
        if not ok:
            misses.append(f"{rows[0]['record']}: {sp.size + 1} axles ({rows[0]['tyres']}, "
                          f"tyre forces {rows[0]['force_ratio_min']}-"
                          f"{rows[0]['force_ratio_max']} of static), found "
                          f"{[x.n_axles for x in det.vehicles]}")
            continue
        right += 1
        veh = det.vehicles[0]
        spacing.append(float(np.abs(veh.axle_spacings - sp).max()))
        speed.append(abs(100.0 * (veh.speed / v - 1.0)))
    return {"seed": seed, "n": n, "right": right, "peaks": peaks_right,
            "spacing": np.array(spacing), "speed": np.array(speed), "floor": np.array(floor),
            "misses": misses, "t_lane1": 1e3 * float(np.mean(t_lane1)),
            "t_all": 1e3 * float(np.mean(t_all)), "t_read": 1e3 * t_read, "gen": t_gen,
            "learn": t_learn, "n_events": len(traffic)}


def _format(scenario):
    """The logger format of the site's files (as tests.detect_data.site_day reads them)."""
    import tomllib

    from bwim.io import LoggerFormat

    sc = tomllib.loads(Path(scenario).read_text())
    columns = tuple(sc["logger"]["columns"])
    return LoggerFormat(columns=columns, sampling_rate=sc["logger"]["sampling_rate"],
                        kinds={c: "axle_detector" for c in columns if c.startswith("ad")})


def _pct(a, q) -> str:
    return f"{np.percentile(a, q):.2f}" if a.size else "-"


def main(argv=None) -> None:
    seeds = tuple(int(s) for s in (argv if argv is not None else sys.argv[1:])) or SEEDS
    with tempfile.TemporaryDirectory() as tmp:
        results = [run_seed(s, Path(tmp)) for s in seeds]
    print_table(
        "Learned detector responses on the short-span-4-lane site: single lane-1 trucks "
        "(targets: every count right, spacings within 0.1 m, speed within 0.5 %)",
        ("seed", "trucks", "counts right", "peaks alone", "spacing p50/p90/max m",
         "within 0.1 m", "speed p50/p90/max %", "within 0.5 %", "floor p50/p90/max %"),
        [(r["seed"], r["n"], r["right"], r["peaks"],
          "/".join(f"{np.percentile(r['spacing'], q):.3f}" for q in (50, 90, 100)),
          int((r["spacing"] <= 0.1).sum()),
          "/".join(_pct(r["speed"], q) for q in (50, 90, 100)),
          int((r["speed"] <= 0.5).sum()),
          "/".join(_pct(r["floor"], q) for q in (50, 90, 100))) for r in results])
    print_table("Time (one core, process time)",
                ("seed", "events", "detect ms/lane-1 event", "detect ms/event",
                 "read ms/event", "detect/read", "learn s", "simulate s"),
                [(r["seed"], r["n_events"], f"{r['t_lane1']:.2f}", f"{r['t_all']:.2f}",
                  f"{r['t_read']:.2f}", f"{r['t_all'] / r['t_read']:.2f}",
                  f"{r['learn']:.2f}", f"{r['gen']:.0f}") for r in results])
    for r in results:
        for m in r["misses"]:
            print(f"  seed {r['seed']} miscount: {m}")


if __name__ == "__main__":
    main()
