"""The paper's method on the realistic site: the FE model calibrated from the logger files
alone, then traffic weighed by moving force identification, side by side with bwim's
multi-run influence lines on the same events (issue 23, target 1).

Data: the two days of ``benchmarks/bench_realsite.py`` (seeds 31 and 32, used in no
development; the ``short-span-4-lane`` site on a 0.5 m plate whose gauges read the mean
strain over the load's spread, 3-D trucks over WIM-grade roads, gauge noise, offsets and
gains, detector responses of real shape, the day's drift and other traffic).  The model
is the scenario's ``[bridge]``: the geometry on a 0.75 m mesh with point gauges and
nominal concrete (30 GPa, 2500 kg/m³; the simulation has 35 GPa, 2400 kg/m³).  No passage,
no road and no gauge factor is given: the calibration runs are detected as ``bwim weigh``
detects them and the model's stiffness ratio, the logger's gain, the channels' offsets
and the detectors' place on the deck are fitted (:func:`bwim.site.calibrate_site_model`).

Printed: the model (parameters, the leave-one-out GVW errors of its own runs, the time it
took) and COST 323 (RR2, I) of the traffic date's single-vehicle lane-1 trucks weighed
with the lines and with the model, each with the runs' time-of-day drift factor and with
the traffic's own drift correction (the default).  ``python benchmarks/bench_site_model.py``
(the days are cached as for ``bench_realsite``; about ten minutes with the days cached).

Last table (issue 23: "the mesh correction chosen as the mesh check asks, ``auto`` as the
default where it costs little; measure what it costs"): per seed, the model calibrated
with no mesh correction, with ``auto`` (the default) and with one bisection: the
bisections made, E_y/E_x, the weighing scale, the leave-one-out errors, the wall time of
the calibration (self-check included) and its ratio to no correction, and the time of
one traffic event's weighing with the model.  ``--mesh-correction N`` weighs the traffic
with that model instead of the default's.
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np

from benchmarks._timing import median_time, print_table
from benchmarks.bench_realsite import CRITERIA, SEEDS, cell, site_day
from bwim.accuracy import assess
from bwim.batch import executor_for, weigh_events
from bwim.io import read_reference
from bwim.scenario import (
    build_bridge,
    build_site_setup,
    load_record,
    read_toml,
    scenario_from_dict,
)
from bwim.site import calibrate_site, calibrate_site_model, correct_drift, weigh_event
from bwim.synthetic.layout import SHORT_SPAN_4_LANE
from bwim.synthetic.sitedays import nominal_bridge


def site_scenario(day):
    """The day's scenario; a day cached before the scenario carried its ``[bridge]`` and
    the gauges' x gets them as the writer now writes them."""
    doc = read_toml(day / "scenario.toml")
    if "bridge" not in doc:
        doc["bridge"] = nominal_bridge(SHORT_SPAN_4_LANE)
        gauges = doc["sensors"][0]
        gauges["x"] = float(SHORT_SPAN_4_LANE.gauges[0].x)
    return scenario_from_dict(doc, source=day / "scenario.toml", folder=day)


def run_day(seed: int, jobs: int = 2, gains: str = "common",
            mesh_correction: int | str = "auto") -> dict:
    return run_folder(site_day(seed), seed, jobs, gains, mesh_correction)


def mesh_cost(seed: int) -> list[list]:
    """Rows of the last table (module docstring) for the day of ``seed``."""
    day = site_day(seed)
    scenario = site_scenario(day)
    records = [load_record(p, scenario) for p in sorted((day / "calibration").glob("*.txt"))]
    site = calibrate_site(records, build_site_setup(scenario))
    event = load_record(sorted((day / "traffic").glob("*.txt"))[0], scenario)
    rows, base = [], None
    for mc in (0, "auto", 1):
        t0 = time.perf_counter()
        model = calibrate_site_model(records, site, build_bridge(scenario),
                                     mesh_correction=mc)
        dt = time.perf_counter() - t0
        base = dt if base is None else base
        weigh = median_time(lambda m=model: weigh_event(event, site, bridge=m), repeat=3)
        corr = model.fit.mesh_correction
        g = model.bridge.model.grid
        rows.append([seed, str(mc), corr.levels if corr else 0, f"{g.nx}x{g.ny}",
                     f"{model.bridge.params['E_y'][0] / model.bridge.params['E_x'][0]:.3f}",
                     f"{model.weighing_scale:.4f}",
                     " ".join(f"{100 * e:+.1f}" for e in model.gvw_errors),
                     f"{dt:.0f} s ({dt / base:.2f}×)", f"{weigh:.2f} s"])
    return rows


def run_folder(day, seed: int, jobs: int = 2, gains: str = "common",
               mesh_correction: int | str = "auto") -> dict:
    """One simulated site's folder: the model, and both weighings of its traffic date."""
    scenario = site_scenario(day)
    runs = sorted((day / "calibration").glob("*.txt"))
    records = [load_record(p, scenario) for p in runs]
    site = calibrate_site(records, build_site_setup(scenario))
    t0 = time.perf_counter()
    model = calibrate_site_model(records, site, build_bridge(scenario), gains=gains,
                                 mesh_correction=mesh_correction)
    t_model = time.perf_counter() - t0
    paths = (sorted((day / "calibration_day_traffic").glob("*.txt"))
             + sorted((day / "traffic").glob("*.txt")))
    read = partial(load_record, scenario=scenario)
    reference = [r for r in read_reference(day / "reference.csv") if r.lane == 1]
    results, rates = {}, {}
    for label, bridge in (("influence lines", None), ("FE model (MFI)", model)):
        t0 = time.perf_counter()
        outcomes = list(weigh_events(paths, site, read=read, bridge=bridge, keep=False,
                                     executor=executor_for(jobs)))
        rates[label] = len(paths) / (time.perf_counter() - t0)
        rows = [r for o in sorted(outcomes, key=lambda o: o.index) for r in o.rows]
        corrected, _ = correct_drift(rows, site)
        results[f"{label}, time of day"] = assess(rows, reference)
        results[f"{label}, traffic drift"] = assess(corrected, reference)
    return {"seed": seed, "model": model, "t_model": t_model, "results": results,
            "rates": rates, "n_used": site.n_used, "n_runs": len(runs)}


def main(argv: list[str] | None = None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--gains", choices=["common", "per_channel"], default="common",
                        help="the logger's gains: one for all gauges or one per gauge")
    parser.add_argument("--mesh-correction", default="auto",
                        help="the model's mesh correction: auto (default), 0, 1 or 2")
    args = parser.parse_args([] if argv is None else argv)
    mc = args.mesh_correction
    mc = int(mc) if mc.isdigit() else mc
    days = [run_day(seed, gains=args.gains, mesh_correction=mc) for seed in SEEDS]
    rows = []
    for d in days:
        m = d["model"]
        err = m.gvw_errors
        rows.append([d["seed"], f"{d['n_used']}/{d['n_runs']}",
                     f"{m.bridge.params['E_y'][0] / m.bridge.params['E_x'][0]:.3f}",
                     f"{m.origin:.3f}", f"{m.lateral:+.3f}",
                     f"{np.mean(list(m.gains.values())):.4g}",
                     " ".join(f"{100 * e:+.1f}" for e in err),
                     "yes" if m.accepted else f"no: {m.reason}", f"{d['t_model']:.0f} s"])
    print_table(f"The site model calibrated from the logger files ({args.gains} gains, mesh "
                f"correction {mc}; "
                "E_y/E_x: the deck is isotropic, 1; origin: ad1 stands at x = 1.5 m; gain: "
                "logger units per unit model strain, the mean)",
                ["seed", "runs used", "E_y/E_x", "origin (m)", "lateral (m)", "gain",
                 "leave-one-out GVW errors %", "accepted", "calibration time"], rows)
    for d in days:
        print_table(f"Seed {d['seed']}: COST 323 (RR2, I) on the traffic date's lane-1 "
                    "trucks, error % mean ± sd and class",
                    ["weighing", "weighed", "gross weight", "group of axles", "single axle",
                     "axle of group", "overall"],
                    [[label, f"{res.n_vehicles}/{res.n_reference}",
                      *[cell(res, c) for c in CRITERIA], res.overall_class or "-"]
                     for label, res in d["results"].items()])
        print("events/s (2 processes): " + ", ".join(f"{k} {v:.1f}"
                                                      for k, v in d["rates"].items()))
    print_table("The mesh correction's cost: the model calibrated with none, auto (the "
                "default) and one bisection (time: calibration with its self-check, and "
                "its ratio to none; weighing: one traffic event with the model, median of 3)",
                ["seed", "mesh correction", "bisections", "model mesh", "E_y/E_x",
                 "weighing scale", "leave-one-out GVW errors %", "calibration time",
                 "weighing"], [r for seed in SEEDS for r in mesh_cost(seed)])


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
