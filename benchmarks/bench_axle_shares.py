"""Axle shares on the realistic simulated site (issue 20 item 5): what moves the single
axles' weights against the groups' and the gross weight's.

On the real installation the influence-line weighing gets single axles about 7 % low
while axle groups are about right (issue 20).  This benchmark measures, on the realistic
simulated site (:func:`bwim.synthetic.make_site_days`, ``short-span-4-lane``, the days of
``benchmarks/bench_realsite.py``: seeds 31 and 32, cached), the mean ± standard deviation
of the relative error (%) of single axles, of axle groups (the sum of a group, groups by
the reference spacings < 2 m), of the steering axle and of the gross weight of the traffic
date's statically weighed lane-1 vehicles, for:

* **chain**: bwim as ``bwim weigh`` runs (lines, detection and drift correction as the
  site calibration and :func:`bwim.site.correct_drift` make them);
* every other row weighs with the vehicle's **true drift factor** (relative to the
  calibration runs' mean: the lines carry that), so that only the lines' shape and the
  axle positions differ:

  - the lines as the chain finds them, on the traffic's detected passages or the true
    ones (speed, arrival, lateral position and spacings from the simulation);
  - the lines calibrated again, from the runs' true passages with the traffic's true
    ones, or from the detected with the detected (the lateral covariate must be the same
    kind in both), with the smoothing length, the support (estimated, the true span, the
    span + 0.5 m and − 0.25 m each side) and the lateral model (per-gauge lines; lines
    linear in the lateral position; one line of the summed gauges, Moses) varied.

``single − group`` is the difference of the two means (the real site's: about −7 %).
``--quick``: seed 31 only, a smaller day (250 traffic events, generated once into the
cache) and fewer variants.  ``--side-spans M``: the same seeds on the slab continuous
over its supports into side spans of M m (:class:`bwim.synthetic.layout.Continuity`,
a property of real short slabs that the default site lacks: the influence lines have a
lobe of the opposite sign beyond the supports).  ``--day FOLDER``: any day made by
:func:`bwim.synthetic.make_site_days`.  The row "support with lobes beyond the zero" is
``calibrate_lines(..., support_lobes=True)``.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np

from benchmarks._timing import print_table
from benchmarks.bench_realsite import N_TRAFFIC, site_day
from bwim.batch import Item, weigh_events
from bwim.io import read_reference
from bwim.records import Passage
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site, correct_drift
from bwim.synthetic import SITE_DAYS_VERSION, make_test_day
from bwim.synthetic.layout import SHORT_SPAN_4_LANE, Continuity
from bwim.wim import calibrate_lines, group_axles, weigh

SEEDS = (31, 32)
QUICK_TRAFFIC = 250
MESH = 0.5
GROUP_SPACING = 2.0  #: m, as COST 323 and bwim.accuracy


def _floats(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split(";")]) if text else np.zeros(0)


def cached_day(seed: int, n_traffic: int, side_spans: float | None) -> Path:
    """The realistic day of ``seed`` with ``n_traffic`` events, on the slab continuous into
    side spans of ``side_spans`` m (None: the default, simply supported), generated once
    into the cache."""
    if side_spans is None and n_traffic == N_TRAFFIC:
        return site_day(seed)  # bench_realsite's day
    cache = Path(os.environ.get("BWIM_BENCH_CACHE", tempfile.gettempdir()))
    tag = "" if side_spans is None else f"-c{side_spans:g}"
    folder = cache / f"bwim-realsite-v{SITE_DAYS_VERSION}-{seed}-{n_traffic}-{MESH}{tag}"
    if not (folder / "scenario.toml").exists():
        shutil.rmtree(folder, ignore_errors=True)
        layout = SHORT_SPAN_4_LANE if side_spans is None else dataclasses.replace(
            SHORT_SPAN_4_LANE, continuity=Continuity(side_span=side_spans))
        make_test_day(folder, site=layout, seed=seed, n_traffic=n_traffic, mesh=MESH)
    return folder


@dataclass(frozen=True, kw_only=True, eq=False)
class Day:
    """One simulated day, calibrated and its lane-1 reference trucks detected."""

    folder: Path
    site: object  # SiteCalibration
    runs: list  # calibration records
    run_truth: list  # truth.csv row of each run's truck
    refs: list  # lane-1 ReferenceRow
    records: list  # their records
    detected: list  # their detected Passage (None: not detected)
    true: list  # their true Passage
    factors: np.ndarray  # their true strain factors
    chain: list  # the chain's SummaryRow of each (drift-corrected)


def _truth(folder: Path) -> dict:
    with open(folder / "truth.csv", newline="") as f:
        out: dict = {}
        for r in csv.DictReader(f):
            out.setdefault(r["record"], []).append(r)
    return out


def true_passage(t: dict) -> Passage:
    """The passage of a truth.csv row in the lines' frame (x = 0 at lane 1's first
    detector)."""
    lane1 = next(d for d in SHORT_SPAN_4_LANE.detectors if d.lane == 1)
    to_gauges = SHORT_SPAN_4_LANE.gauges[0].x - lane1.x
    v = float(t["speed_m_s"])
    at_gauges = (datetime.fromisoformat(t["time"])
                 - datetime.fromisoformat(t["event_start"])).total_seconds()
    return Passage(speed=v, lane=float(t["lane_y_m"]), axle_spacings=_floats(t["axle_spacings_m"]),
                   delay=at_gauges - to_gauges / v)


def load_day(folder: Path) -> Day:
    scenario = load_scenario(folder / "scenario.toml")
    paths = sorted((folder / "calibration").glob("*.txt"))
    runs = [load_record(p, scenario) for p in paths]
    site = calibrate_site(runs, build_site_setup(scenario))
    truth = _truth(folder)
    refs = [r for r in read_reference(folder / "reference.csv") if r.lane == 1]
    records = [load_record(folder / "traffic" / r.record, scenario) for r in refs]
    outcomes = sorted(weigh_events([Item(r.record, rec, None)
                                    for r, rec in zip(refs, records, strict=True)], site),
                      key=lambda o: o.index)
    rows = [row for o in outcomes for row in o.rows]
    corrected, _ = correct_drift(rows, site)
    by_name = {r.record: r for r in corrected if r.lane == 1}
    detected = []
    for o in outcomes:
        w = o.event.weighing if o.event is not None else None
        detected.append(None if w is None or not o.event.weighed else w.passage)
    return Day(folder=folder, site=site, runs=runs,
               run_truth=[truth[p.name][0] for p in paths], refs=refs, records=records,
               detected=detected, true=[true_passage(truth[r.record][0]) for r in refs],
               factors=np.array([float(truth[r.record][0]["strain_factor"]) for r in refs]),
               chain=[by_name.get(r.record) for r in refs])


# --- the errors -----------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Shares:
    """Relative errors, %, as (mean, std, n) per kind of load."""

    gvw: tuple[float, float, int]
    single: tuple[float, float, int]
    group: tuple[float, float, int]
    steer: tuple[float, float, int]


def _stat(values: list[float]) -> tuple[float, float, int]:
    a = np.array(values)
    if a.size < 2:
        return (float("nan"), float("nan"), int(a.size))
    return (float(a.mean()), float(a.std(ddof=1)), int(a.size))


def shares(weights: list, refs: list, *, min_axles: int = 0) -> Shares:
    """Errors of axle ``weights`` (N per axle, or None: not weighed) against ``refs``;
    only vehicles of at least ``min_axles`` axles."""
    gvw, single, group, steer = [], [], [], []
    for w, ref in zip(weights, refs, strict=True):
        true = np.array(ref.axle_weights)
        if w is None or len(w) != true.size or true.size < min_axles:
            continue
        w = np.asarray(w)
        gvw.append(100 * (w.sum() / true.sum() - 1))
        steer.append(100 * (w[0] / true[0] - 1))
        for g in group_axles(np.array(ref.axle_spacings), GROUP_SPACING):
            g = list(g)
            err = 100 * (w[g].sum() / true[g].sum() - 1)
            (single if len(g) == 1 else group).append(err)
    return Shares(gvw=_stat(gvw), single=_stat(single), group=_stat(group), steer=_stat(steer))


def _cell(s: tuple[float, float, int]) -> str:
    return "-" if s[2] < 2 else f"{s[0]:+.1f} ± {s[1]:.1f}"


# --- the variants ---------------------------------------------------------------------------
def calibration_passages(day: Day, kind: str) -> tuple[list, list]:
    """The used runs' records and passages: detected (as the chain) or true."""
    used = [k for k, r in enumerate(day.site.reasons) if not r]
    spacings = day.site.setup.calibration_spacings
    out = []
    for k in used:
        if kind == "true":
            out.append(true_passage(day.run_truth[k]))
        else:
            p = day.site.detections[k].vehicles[0].passage
            out.append(Passage(speed=p.speed, lane=p.lane, delay=p.delay,
                               axle_spacings=spacings, track_width=p.track_width))
    return [day.runs[k] for k in used], out


def weigh_refs(day: Day, lines, kind: str, *, combine: str = "auto",
               norm: float = 1.0) -> list:
    """Axle weights (N) of the reference trucks with ``lines`` on their ``kind``
    ("true" or "detected") passages, each divided by its true drift factor / ``norm``."""
    out = []
    for rec, p_true, p_det, f in zip(day.records, day.true, day.detected, day.factors,
                                     strict=True):
        p = p_true if kind == "true" else p_det
        if p is None:
            out.append(None)
            continue
        w = weigh(rec, p, lines, combine=combine, scale=f / norm)
        out.append(None if w.quality == "reject" else w.axle_weights)
    return out


def _norm(day: Day, lines, used: list[int]) -> float:
    """The kept runs' mean true factor: the lines are normalised to it."""
    kept = [used[r.index] for r in lines.runs if not r.rejected]
    return float(np.mean([float(day.run_truth[k]["strain_factor"]) for k in kept]))


def variants(quick: bool) -> list[tuple[str, dict]]:
    """(label, calibrate_lines options) of the recalibrated lines."""
    span = SHORT_SPAN_4_LANE.span
    x_det = next(d for d in SHORT_SPAN_4_LANE.detectors if d.lane == 1).x
    true_support = (-x_det, span - x_det)
    out = [("per-gauge lines, defaults", {}),
           ("smoothing 0", {"smoothing": 0.0}),
           ("smoothing 0.3 m", {"smoothing": 0.3})]
    if not quick:
        out += [("smoothing 0.05 m", {"smoothing": 0.05}),
                ("smoothing 0.2 m", {"smoothing": 0.2}),
                ("smoothing 0.5 m", {"smoothing": 0.5})]
    out += [("support = true span", {"support": true_support}),
            ("support with lobes beyond the zero", {"support_lobes": True})]
    if not quick:
        out += [("support = span + 0.5 m each side",
                 {"support": (true_support[0] - 0.5, true_support[1] + 0.5)}),
                ("support = span − 0.25 m each side",
                 {"support": (true_support[0] + 0.25, true_support[1] - 0.25)})]
    out += [("lateral model (linear)", {"lateral": "linear"}),
            ("summed gauges (Moses)", {"channels": "sum"})]
    return out


def study(day: Day, quick: bool) -> list[list[str]]:
    rows = []

    def add(label, passages, weights):
        s = shares(weights, day.refs)
        s5 = shares(weights, day.refs, min_axles=5)
        rows.append([label, passages, f"{s.gvw[2]}", _cell(s.gvw), _cell(s.single),
                     _cell(s.group), f"{s.single[0] - s.group[0]:+.1f}", _cell(s.steer),
                     f"{s5.single[0] - s5.group[0]:+.1f}"])

    chain = [None if r is None or not r.weighed else np.array(r.axle_weights)
             for r in day.chain]
    add("chain (drift corrected)", "detected", chain)
    used = [k for k, r in enumerate(day.site.reasons) if not r]
    lines = day.site.lines
    norm = _norm(day, lines, used)
    add("chain's lines", "detected",
        weigh_refs(day, lines, "detected", combine=day.site.setup.combine, norm=norm))
    add("chain's lines", "detected cal., true traffic",
        weigh_refs(day, lines, "true", combine=day.site.setup.combine, norm=norm))
    for label, opts in variants(quick):
        for kind in ("true",) if quick else ("true", "detected"):
            records, passages = calibration_passages(day, kind)
            o = dict(opts)
            lines = calibrate_lines(records, passages, day.site.setup.calibration_loads,
                                    lateral=o.pop("lateral", None), **o)
            combine = "sum" if o.get("channels") == "sum" else "auto"
            add(label, kind, weigh_refs(day, lines, kind, combine=combine,
                                        norm=_norm(day, lines, used)))
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="seed 31 only, a small day, fewer variants")
    parser.add_argument("--side-spans", type=float, default=None, metavar="M",
                        help="the slab continuous over its supports into side spans of M m "
                        "(bwim.synthetic.layout.Continuity; days generated once)")
    parser.add_argument("--day", type=Path, action="append", default=[],
                        help="a folder made by make_site_days instead of the seeds' days; "
                        "may be repeated")
    args = parser.parse_args(argv)
    n_traffic = QUICK_TRAFFIC if args.quick else N_TRAFFIC
    days = args.day or [cached_day(s, n_traffic, args.side_spans)
                        for s in (SEEDS[:1] if args.quick else SEEDS)]
    for folder in days:
        t0 = time.perf_counter()
        day = load_day(folder)
        name = folder.name
        rows = study(day, args.quick)
        print_table(
            f"Axle shares on the realistic site, {name}: error % (mean ± sd) of the "
            f"traffic date's lane-1 reference vehicles ({len(day.refs)}); rows after the "
            f"first weigh with each truck's true drift factor ({time.perf_counter() - t0:.0f} s)",
            ["lines", "passages", "weighed", "gross weight", "single axle", "group of axles",
             "single − group", "steering axle", "single − group (≥ 5 axles)"], rows)


if __name__ == "__main__":
    main()
