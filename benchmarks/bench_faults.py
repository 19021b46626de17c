"""Faulty gauges on the realistic site (issue 22): no silent wrong weight.

Data: a realistic simulated day (:func:`bwim.synthetic.make_test_day`, ``short-span-4-lane``,
seed 41, never used while developing; 80 traffic events, a 0.6 m mesh; cached under
``BWIM_BENCH_CACHE`` like ``bench_realsite``).  Each of the first ``N_VEHICLES`` lane-1
trucks weighed from its clean file is weighed again with one gauge made faulty, for every
gauge and every fault type: dead (0), stuck at its first reading, reversed, gain ×2,
gain ×0.5, clipped (held at a rail halfway from its first reading to its peak, or at its
first reading: the logger reader's clipping check passes the latter), drifting (a
baseline ramp of 30 × its calibration noise over the record).  The reference is the
same truck weighed from the clean file.

Printed per fault type: faults found (the truck flagged ``gauge_fault:<that gauge>``),
trucks refused, **silent wrong weights** (weighed without a ``gauge_fault`` flag and more
than 10 % from the clean weight: the issue's measure, 102 cases before the check) and the
largest error of a weight still written; and false alarms on the clean trucks.

Then each fault in **one calibration run** (the first of the runs the clean calibration
used; the calibration made from the used runs alone), for every gauge: the run must be
left out (by the gauge checks, naming the gauge, or as an outlier of the runs' scale
factors) or the calibration refused, and no other run lost; printed with the largest
change of the first five lane-1 trucks' weights against the calibration from the clean
runs less that one.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from bwim.errors import InputError
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site, weigh_event
from bwim.synthetic import SITE_DAYS_VERSION, make_test_day

SEED = 41
N_TRAFFIC = 80
N_VEHICLES = 15


def _rail(y: np.ndarray, fraction: float) -> np.ndarray:
    """``y`` held at a rail ``fraction`` of the way from its first reading to its farthest
    (a logger's saturation: the readings beyond it read the rail)."""
    up, down = y.max() - y[0], y[0] - y.min()
    if up >= down:
        return np.minimum(y, y[0] + fraction * up)
    return np.maximum(y, y[0] - fraction * down)


#: Each fault as ``fault(readings, noise)``, ``noise`` the gauge's noise at rest in the
#: calibration runs (logger units).
FAULTS = {
    "dead": lambda y, _: np.zeros_like(y),
    "stuck": lambda y, _: np.full_like(y, y[0]),
    "reversed": lambda y, _: -y,
    "gain ×2": lambda y, _: 2.0 * y,
    "gain ×0.5": lambda y, _: 0.5 * y,
    "clipped halfway": lambda y, _: _rail(y, 0.5),
    "clipped at rest": lambda y, _: _rail(y, 0.0),
    "drift 30σ": lambda y, noise: y + 30.0 * noise * np.linspace(0.0, 1.0, y.size),
}


def site_day() -> Path:
    """The day of :data:`SEED`, generated once into the cache (also bench_declarations')."""
    cache = Path(os.environ.get("BWIM_BENCH_CACHE", tempfile.gettempdir()))
    folder = cache / f"bwim-faults-v{SITE_DAYS_VERSION}-{SEED}-{N_TRAFFIC}"
    if not (folder / "scenario.toml").exists():  # written last: the day is complete
        shutil.rmtree(folder, ignore_errors=True)
        make_test_day(folder, site="short-span-4-lane", seed=SEED, n_traffic=N_TRAFFIC,
                      n_calibration_day_traffic=0, mesh=0.6)
    return folder


def _faulty(record, name: str, fault, noise: float) -> object:
    k = [s.name for s in record.sensors].index(name)
    data = record.data.copy()
    data[:, k] = fault(data[:, k], noise)
    return dataclasses.replace(record, data=data)


def calibration_faults(day: Path, n_trucks: int = 5) -> list[list[object]]:
    """Each fault in the first used calibration run, for every gauge (module docstring):
    rows of (fault, run left out (naming the gauge), refused, other runs lost, largest
    change of a lane-1 truck's weight against the calibration without that run)."""
    scenario = load_scenario(day / "scenario.toml")
    setup = build_site_setup(scenario)
    records = [load_record(p, scenario) for p in sorted((day / "calibration").glob("*.txt"))]
    clean = calibrate_site(records, setup)
    runs = [r for r, why in zip(records, clean.reasons, strict=True) if not why]
    without = calibrate_site(runs[1:], setup)  # the clean runs less the faulty one
    gauges = [c.name for c in clean.lines.channels]
    noise = dict(zip(gauges, clean.lines.channel_noise, strict=True))
    trucks = []
    for path in sorted((day / "traffic").glob("*.txt")):
        rec = load_record(path, scenario)
        ev = weigh_event(rec, without)
        k = next((i for i, v in enumerate(ev.vehicles) if v.weighed and v.lane == 1
                  and not any(f.startswith("gauge_fault") for f in v.flags)), None)
        if k is not None:
            trucks.append((rec, k, ev.vehicles[k].gvw))
        if len(trucks) == n_trucks:
            break
    rows = []
    for label, fault in FAULTS.items():
        found = left = refused = lost = 0
        worst = 0.0
        for g in gauges:
            try:
                cal = calibrate_site([_faulty(runs[0], g, fault, noise[g]), *runs[1:]], setup)
            except InputError:
                refused += 1
                continue
            left += bool(cal.reasons[0])
            found += cal.reasons[0].startswith((f"gauge {g} ", f"gauge {g!r} "))
            lost += sum(bool(r) for r in cal.reasons[1:])
            for rec, k, gvw in trucks:
                v = weigh_event(rec, cal).vehicles[k]
                if v.weighed:
                    worst = max(worst, abs(v.gvw / gvw - 1) * 100)
        rows.append([label, f"{left}/{len(gauges)} ({found})", refused, f"{lost} (0)",
                     f"{worst:.2f} %"])
    return rows


def main() -> None:
    t0 = time.perf_counter()
    rows = calibration_faults(site_day())
    print_table(f"One faulty gauge in one calibration run on the realistic site (seed {SEED}, "
                f"every gauge of the first used run; {time.perf_counter() - t0:.0f} s)",
                ["fault", "run left out (the gauge named)", "calibration refused",
                 "other runs lost (target)", "largest change of a lane-1 truck's weight"],
                rows)
    day = site_day()
    scenario = load_scenario(day / "scenario.toml")
    cal = calibrate_site([load_record(p, scenario)
                          for p in sorted((day / "calibration").glob("*.txt"))],
                         build_site_setup(scenario))
    gauges = [c.name for c in cal.lines.channels]
    noise = dict(zip(gauges, cal.lines.channel_noise, strict=True))
    t0 = time.perf_counter()
    clean, false_alarms, n_clean = [], 0, 0
    for path in sorted((day / "traffic").glob("*.txt")):
        rec = load_record(path, scenario)
        ev = weigh_event(rec, cal)
        for v in ev.vehicles:
            n_clean += 1
            false_alarms += any(f.startswith("gauge_fault") for f in v.flags)
        k = next((i for i, v in enumerate(ev.vehicles) if v.weighed and v.lane == 1), None)
        if k is not None and len(clean) < N_VEHICLES:
            clean.append((rec, k, ev.vehicles[k].gvw))
    rows = []
    for label, fault in FAULTS.items():
        found = refused = silent = cases = 0
        worst = 0.0
        for rec, k, gvw in clean:
            for g in gauges:
                cases += 1
                ev = weigh_event(_faulty(rec, g, fault, noise[g]), cal)
                v = ev.vehicles[k] if k < len(ev.vehicles) else None
                if v is None or not v.weighed:
                    refused += 1
                    continue
                flagged = any(f.startswith("gauge_fault") for f in v.flags)
                found += f"gauge_fault:{g}" in v.flags
                err = abs(v.gvw / gvw - 1) * 100
                worst = max(worst, err)
                silent += (not flagged) and err > 10.0
        rows.append([label, f"{found}/{cases}", refused, f"{silent} (0)", f"{worst:.1f} %"])
    print_table(f"One faulty gauge of {len(gauges)} on the realistic site (seed {SEED}, "
                f"{len(clean)} lane-1 trucks × every gauge; {false_alarms} false alarms "
                f"among {n_clean} clean vehicles; {time.perf_counter() - t0:.0f} s)",
                ["fault", "found (that gauge flagged)", "refused",
                 "silent wrong weights > 10 % (target)", "largest error still weighed"],
                rows)


if __name__ == "__main__":
    main()
