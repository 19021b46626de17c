"""Vehicle detection (issue 11): accuracy and time per event of bwim.detect.

Synthetic logger records of tests/detect_data.py (no inverse crime: a detector pulse
shape the detector does not assume; strain from the coupled simulation of a fine 9 m ×
10 m slab, detection with a coarse model's or a calibrated influence line).  Prints, for
the two axle detectors, the speed, spacing and arrival errors of the calibration truck
at 18–25 m/s over 10 noise seeds, the tridem at 25 m/s and the time per 1.5 s event;
for the strain-only path, speed and arrival errors with known spacings and without.

    python -m benchmarks.bench_detect
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._timing import median_time, print_table
from bwim.detect import detect_axles, detect_from_strain
from bwim.vehicles import MovingForces
from bwim.wim import calibrate_influence_line, model_influence_line

from tests.detect_data import (
    CAL_LOADS,
    CAL_SPACINGS,
    T0,
    coarse_plate,
    detector_record,
    fine_plate,
    gauges,
    strain_record,
    with_detectors,
)


def detector_rows(speeds=(18.0, 20.0, 22.0, 25.0), seeds=range(10), noises=(0.02, 0.05)):
    rows = []
    for noise in noises:
        ev, es, ed = [], [], []
        for v in speeds:
            for seed in seeds:
                t_first = T0 + 0.2 + 0.013 * seed
                veh = detect_axles(detector_record([(v, CAL_SPACINGS, CAL_LOADS, t_first)],
                                                   seed=seed, noise=noise)).single
                ev.append(veh.speed / v - 1)
                es.append(np.abs(veh.axle_spacings - CAL_SPACINGS).max())
                ed.append(veh.passage.delay - t_first)
        rows.append((f"truck, noise {noise:g} V", len(ev), f"{100 * np.abs(ev).max():.3f}",
                     f"{100 * np.sqrt(np.mean(np.square(ev))):.3f}",
                     f"{1e3 * max(es):.1f}", f"{1e3 * np.abs(ed).max():.2f}"))
    ev, es = [], []
    for seed in seeds:
        t_first = T0 + 0.3 + 0.011 * seed
        veh = detect_axles(detector_record([(25.0, (1.3, 1.3), (80e3,) * 3, t_first)],
                                           seed=seed)).single
        ev.append(veh.speed / 25.0 - 1)
        es.append(np.abs(veh.axle_spacings - 1.3).max() if veh.n_axles == 3 else np.inf)
    rows.append(("tridem 1.3 m, 25 m/s", len(ev), f"{100 * np.abs(ev).max():.3f}",
                 f"{100 * np.sqrt(np.mean(np.square(ev))):.3f}", f"{1e3 * max(es):.1f}", "-"))
    return rows


def strain_rows(speeds=(15.0, 18.0, 20.0, 22.0, 25.0)):
    plate = fine_plate()
    truck = MovingForces(axle_loads=CAL_LOADS, axle_spacings=CAL_SPACINGS, track_width=2.0)
    cal = []
    for v, seed in ((17.0, 101), (21.0, 102), (24.0, 103)):
        rec = strain_record(plate, truck, speed=v, lane=3.0, seed=seed, offsets=False)
        full = with_detectors(rec, [(v, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)],
                              seed=seed)
        cal.append(detect_axles(full, span=9.0).annotate(rec))
    lines = {"coarse model": model_influence_line(coarse_plate(), gauges(), channels="sum",
                                                  lane=3.0, track_width=2.0),
             "calibrated": calibrate_influence_line(cal, CAL_LOADS, lane_tolerance=1.0,
                                                    support=(-0.5, 9.5))}
    records = [(v, strain_record(plate, truck, speed=v, lane=3.0, seed=int(v)))
               for v in speeds]
    rows = []
    for name, il in lines.items():
        for known in (True, False):
            ev, ed, na, el = [], [], [], []
            for v, rec in records:
                t0 = time.perf_counter()
                det = detect_from_strain(rec, il,
                                         known_spacings=CAL_SPACINGS if known else None)
                el.append(time.perf_counter() - t0)
                veh = det.vehicles[0]
                ev.append(veh.speed / v - 1)
                ed.append(veh.passage.delay - rec.passage.delay)
                na.append(sum(x.n_axles for x in det.vehicles))
            rows.append((name, "known" if known else "free", f"{100 * np.abs(ev).max():.2f}",
                         f"{100 * np.median(np.abs(ev)):.2f}", f"{1e3 * np.abs(ed).max():.1f}",
                         "/".join(str(n) for n in na), f"{1e3 * np.mean(el):.0f}"))
    return rows


def timing_rows():
    plate = fine_plate()
    truck = MovingForces(axle_loads=CAL_LOADS, axle_spacings=CAL_SPACINGS, track_width=2.0)
    rec = strain_record(plate, truck, speed=20.0, lane=3.0, seed=1, tail=0.13)
    full = with_detectors(rec, [(20.0, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)], seed=1)
    two = full.channels(["ad1", "ad2"])
    return [("ad1, ad2", f"{1e3 * median_time(lambda: detect_axles(two)):.2f}"),
            ("ad1, ad2 + 14 gauges, span",
             f"{1e3 * median_time(lambda: detect_axles(full, span=9.0)):.2f}")]


def main() -> None:
    print_table("Axle detectors at 512 Hz (max/rms speed error %, max spacing error mm, "
                "max arrival error ms)",
                ("case", "events", "speed max %", "speed rms %", "spacing mm", "arrival ms"),
                detector_rows())
    print_table("detect_axles time per 1.5 s event (median)", ("channels", "ms"),
                timing_rows())
    print_table("Strain only, calibration truck 15–25 m/s, 9 m slab",
                ("line", "spacings", "speed max %", "speed median %", "arrival ms",
                 "axles found", "ms/event"), strain_rows())


if __name__ == "__main__":
    main()
