"""Which drift correction to use when (issue 20, item 4: "show on simulated days which one
to use when").

Data: a realistic simulated site (``short-span-4-lane``, seed 33, used in no development;
800 traffic events on the traffic date, a 0.5 m data mesh) **with** the deck-temperature
channel written (``temperature_channel=True``), cached like ``bench_realsite``'s days.
The simulated strain-to-load factor is linear in the deck temperature plus a slow
non-thermal term of its own on each date (:mod:`bwim.synthetic.thermal`), and it follows
another curve on the traffic date than on the calibration date.

Each drift method (:mod:`bwim.site.drift`) weighs the same events: ``temperature`` (the
runs' factors regressed on their temperature), ``traffic`` (the steering axles of the
commonest articulated class, tracked over the traffic date), ``time_of_day`` (the
calibration date's curve) and ``none`` (the runs' mean factor).  Printed: COST 323 (RR2,
I) of the traffic date's lane-1 reference trucks, and how the traffic method fares when
the traffic is thinner: its trend made from one event in ``k`` of both dates and applied
to every vehicle, with the number of reference vehicles it had per date and how many
weights it left to the next source (``drift_traffic_thin``).

``python -m benchmarks.bench_drift`` (about five minutes with the day cached; the day
takes longer the first time).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
from functools import partial
from pathlib import Path

from benchmarks._timing import print_table
from benchmarks.bench_realsite import CRITERIA, MESH, N_TRAFFIC, cell
from bwim.accuracy import assess
from bwim.batch import executor_for, weigh_events
from bwim.io import read_reference
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site, correct_drift
from bwim.site.drift import apply_traffic_drift, traffic_drift
from bwim.synthetic import SITE_DAYS_VERSION, make_test_day

SEED = 33
METHODS = ("temperature", "traffic", "time_of_day", "none")
#: The traffic method on thinner traffic: the traffic date's events kept one in k.
THINNING = (1, 3, 10, 30)


def drift_day(seed: int = SEED, n_traffic: int = N_TRAFFIC) -> Path:
    """The day of ``seed`` with its temperature channel, generated once into the cache."""
    cache = Path(os.environ.get("BWIM_BENCH_CACHE", tempfile.gettempdir()))
    folder = cache / f"bwim-driftsite-v{SITE_DAYS_VERSION}-{seed}-{n_traffic}-{MESH}"
    if not (folder / "scenario.toml").exists():  # written last: the day is complete
        shutil.rmtree(folder, ignore_errors=True)
        make_test_day(folder, site="short-span-4-lane", seed=seed, n_traffic=n_traffic,
                      mesh=MESH, temperature_channel=True)
    return folder


def run(day: Path, jobs: int = 2) -> dict:
    """Each method's weighing of the day (module docstring), and the thinned traffic."""
    scenario = load_scenario(day / "scenario.toml")
    records = [load_record(p, scenario) for p in sorted((day / "calibration").glob("*.txt"))]
    base = build_site_setup(scenario)
    paths = (sorted((day / "calibration_day_traffic").glob("*.txt"))
             + sorted((day / "traffic").glob("*.txt")))
    reference = [r for r in read_reference(day / "reference.csv") if r.lane == 1]
    read = partial(load_record, scenario=scenario)
    out, rows_of = {}, {}
    for method in METHODS:
        setup = dataclasses.replace(base, drift=dataclasses.replace(base.drift, method=method))
        site = calibrate_site(records, setup)
        t0 = time.perf_counter()
        outcomes = list(weigh_events(paths, site, read=read, keep=False,
                                     executor=executor_for(jobs)))
        rows = [r for o in sorted(outcomes, key=lambda o: o.index) for r in o.rows]
        fixed, _ = correct_drift(rows, site)
        out[method] = (assess(fixed, reference), time.perf_counter() - t0)
        rows_of[method] = (rows, site)
    # the traffic method on thinner traffic: its trend made from one event in k, then
    # applied to every row (the reference trucks are assessed whether kept or not)
    rows, site = rows_of["traffic"]
    tod = site.time_of_day
    span = None if tod is None else tod.trend.span
    names = sorted({r.record for r in rows})
    thin = []
    for k in THINNING:
        kept = {n for i, n in enumerate(names) if i % k == 0}
        fit = traffic_drift([r for r in rows if r.record in kept], site.setup.drift,
                            calibration=tod, calibration_span=span)
        fixed = apply_traffic_drift(rows, fit) if fit is not None else list(rows)
        n_thin = sum("drift_traffic_thin" in r.flags for r in fixed if r.gvw is not None)
        refs = ("no trend (too thin on both dates)" if fit is None else
                ", ".join(f"{d}: {n}" for d, n in sorted(fit.counts.items())))
        thin.append((k, len(kept), refs, n_thin, assess(fixed, reference)))
    return {"methods": out, "thin": thin}


def main() -> None:
    day = drift_day()
    res = run(day)
    print_table(f"Drift methods on seed {SEED} (temperature channel written; COST 323 RR2/I "
                "on the traffic date's lane-1 reference trucks, error % mean ± sd and class)",
                ["method", "weighed", "gross weight", "group of axles", "single axle",
                 "axle of group", "overall", "time (s)"],
                [[m, f"{r.n_vehicles}/{r.n_reference}", *[cell(r, c) for c in CRITERIA],
                  r.overall_class or "-", f"{dt:.0f}"] for m, (r, dt) in res["methods"].items()])
    print_table("The traffic method on thinner traffic (its trend from one event in k of "
                "both dates; reference vehicles per date; weights left to the next source "
                "as drift_traffic_thin)",
                ["k", "events kept", "reference vehicles", "thin", "gross weight",
                 "overall"],
                [[k, n, refs, n_thin, cell(r, "gross_weight"), r.overall_class or "-"]
                 for k, n, refs, n_thin, r in res["thin"]])


if __name__ == "__main__":
    main()
