"""A real installation end to end: COST 323 classes of bwim's chain against Moses' baseline.

Data (:func:`bwim.synthetic.make_test_day`, seed 1: not a day the code was developed on):
a 9 m slab on a 0.25 m mesh with 14 gauges across mid-span and two axle detectors 3 m
apart, 512 Hz logger files with 2 % absolute gauge noise, offsets, baseline drift, gauge
gains, a ±8 % drift of the strain-to-load ratio over the day, 12 runs of a 40 t 5-axle
calibration truck and 100 traffic events (2–6 axles, 10–50 t, 4 with two trucks), 3-D
trucks over ISO 8608 roads.  Two days: roads from the class A mean to the class B mean
(the default), and a WIM-grade approach within class A (a B-WIM site is chosen on even
pavement).  Nothing of the simulation is known to the weighing: no FE model, no passages.

* **bwim**: ``bwim weigh`` on the logger files (detection, per-gauge lines from the runs
  stacked with per-run scale factors and their trend, gauges combined, axle groups).
* **Moses baseline**: the classic single line of the summed gauges by the matrix method
  (OBrien et al. 2006) from the same detected calibration passages and over the same
  support, channels zeroed before the first axle arrives (pre-trigger), no per-run
  factors; Moses with the same detected passages and axle groups, and the same
  plausibility checks.

Prints the COST 323 class per criterion (test RR2, environment I: a sample of traffic
over one day), the detection against the truth (axle count, speed, spacings) and the
weighing throughput (events/s, one core).  Targets (issue 11): gross weight A(5), every
criterion B+(7) or better; axle count right for ≥ 99 %, speed within 0.5 %, spacings
within 0.1 m; ≥ 100 events/s.
"""

from __future__ import annotations

import csv
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from bwim.accuracy import SummaryRow, assess
from bwim.cli import main as bwim_main
from bwim.io import read_reference, read_summary
from bwim.scenario import build_site_setup, build_vehicle, load_record, load_scenario
from bwim.site import calibrate_site, weigh_event
from bwim.synthetic import make_test_day
from bwim.synthetic.testday import ROUGHNESS, WIM_GRADE_ROUGHNESS
from bwim.wim import calibrate_influence_line, group_axles, weigh_static

SEED = 1
DAYS = {"class A-B roads": ROUGHNESS, "WIM-grade (class A) roads": WIM_GRADE_ROUGHNESS}


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def zeroed(record, passage, support):
    """The record less each channel's mean before the first axle reaches the line (the
    classic pre-trigger zeroing of a B-WIM system)."""
    before = passage.axle_x(record.time)[:, 0] < support[0]
    if before.sum() < 8:
        return record
    return dataclasses.replace(record, data=record.data - record.data[before].mean(axis=0))


def moses_baseline(calibration, scenario, site, traffic) -> list[SummaryRow]:
    """Moses with one summed-gauge line, on bwim's detected passages, over the support
    bwim estimated, with pre-trigger zeroing.  ``calibration``: the runs' paths (in the
    order ``site`` was calibrated from); ``traffic``: (name, record, EventWeighing)."""
    support = site.lines.support
    used = [k for k, r in enumerate(site.reasons) if not r]
    # the summed gauges are the classic lane-insensitive channel: one line for all runs
    passages = [dataclasses.replace(site.detections[k].vehicles[0].passage, lane=0.0)
                for k in used]
    cal_records = [dataclasses.replace(zeroed(load_record(calibration[k], scenario),
                                               p, support), passages=(p,))
                   for k, p in zip(used, passages, strict=True)]
    il = calibrate_influence_line(cal_records, build_vehicle(scenario), channels="sum",
                                  support=support)
    rows = []
    for name, rec, ev in traffic:
        if ev.passage is None or ev.detection is None or len(ev.detection.vehicles) != 1:
            rows.append(SummaryRow(record=name))
            continue
        p = dataclasses.replace(ev.passage, lane=il.lane)
        w = weigh_static(zeroed(rec, p, support), il, passage=p, groups=group_axles(p))
        ok = w.quality != "reject"
        rows.append(SummaryRow(record=name, gvw=w.gvw if ok else None,
                               axle_weights=tuple(w.axle_weights) if ok else (),
                               axle_spacings=tuple(p.axle_spacings), n_axles=p.n_axles))
    return rows


def run_day(label: str, roughness, folder: Path) -> dict:
    t0 = time.perf_counter()
    day = make_test_day(folder / "day", seed=SEED, roughness=roughness)
    t_gen = time.perf_counter() - t0
    out = folder / "out"
    code = bwim_main(["weigh", str(day.scenario), str(day.traffic[0].parent),
                      "--calibration-records", str(day.calibration[0].parent), "-o", str(out)])
    reference = read_reference(day.reference)
    ours = assess(read_summary(out / "summary.csv"), reference)

    scenario = load_scenario(day.scenario)
    setup_site = calibrate_site([load_record(p, scenario) for p in day.calibration],
                                build_site_setup(scenario))
    t0 = time.perf_counter()
    records = [(p.name, load_record(p, scenario)) for p in day.traffic]
    t_read = time.perf_counter() - t0
    t0 = time.process_time()
    traffic = [(name, rec, weigh_event(rec, setup_site)) for name, rec in records]
    t_weigh = time.process_time() - t0
    base = assess(moses_baseline(day.calibration, scenario, setup_site, traffic), reference)

    truth = {}
    for r in _rows(day.truth):
        truth.setdefault(r["record"], []).append(r)
    n = n_count = 0
    speed_err, spacing_err = [], []
    for name, _, ev in traffic:
        t = truth[name]
        if len(t) != 1:
            continue
        n += 1
        p = ev.passage
        if p is None or p.n_axles != int(t[0]["n_axles"]):
            continue
        n_count += 1
        speed_err.append(abs(p.speed / float(t[0]["speed_m_s"]) - 1) * 100)
        sp = np.array([float(v) for v in t[0]["axle_spacings_m"].split(";")])
        spacing_err.append(float(np.max(np.abs(p.axle_spacings - sp))))
    return {"label": label, "ours": ours, "base": base, "exit": code, "gen": t_gen,
            "n": n, "count": n_count, "speed": max(speed_err), "spacing": max(spacing_err),
            "rate": len(traffic) / t_weigh, "read": len(records) / t_read,
            "multiple": sum(1 for name, _, ev in traffic if len(truth[name]) > 1
                            and not ev.weighed and "multiple" in ev.reason),
            "n_multiple": sum(1 for t in truth.values() if len(t) > 1)}


def _class_rows(res) -> list[list[str]]:
    rows = []
    for name in ("gross_weight", "group_of_axles", "single_axle", "axle_of_group"):
        cells = [name.replace("_", " ")]
        for key in ("ours", "base"):
            c = next((c for c in res[key].criteria if c.name == name), None)
            cells += (["-", "-"] if c is None else
                      [f"{c.mean:+.2f} ± {c.std:.2f}", c.class_name])
        rows.append(cells)
    rows.append(["overall", "", res["ours"].overall_class or "-", "",
                 res["base"].overall_class or "-"])
    return rows


def main() -> None:
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, roughness) in enumerate(DAYS.items()):
            results.append(run_day(label, roughness, Path(tmp) / f"day{k}"))
    for res in results:
        print_table(f"COST 323 (RR2, I) on the simulated test day, {res['label']} "
                    f"(seed {SEED}; {res['ours'].n_vehicles} of {res['ours'].n_reference} "
                    f"reference trucks weighed by bwim, {res['base'].n_vehicles} by Moses)",
                    ["criterion", "bwim error %", "bwim class", "Moses error %",
                     "Moses class"], _class_rows(res))
    rows = []
    for res in results:
        rows.append([res["label"], f"{100 * res['count'] / res['n']:.1f} % (target ≥ 99)",
                     f"{res['speed']:.3f} % (< 0.5)", f"{res['spacing']:.3f} m (< 0.1)",
                     f"{res['multiple']}/{res['n_multiple']}",
                     f"{res['rate']:.0f}/s (≥ 100)", f"{res['read']:.0f}/s",
                     f"{res['gen']:.0f} s"])
    print_table("Detection against the truth, and throughput (one core)",
                ["day", "axle count right", "max speed error", "max spacing error",
                 "two-truck events flagged", "detect + weigh", "file reading",
                 "day generated in"], rows)


if __name__ == "__main__":
    main()
