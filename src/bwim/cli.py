"""The ``bwim`` command line.

Contract
--------
``main(argv=None) -> int`` parses arguments, calls the library and prints; it holds no
numerics.  Bad input (a scenario, record or model file, an option, an output path) ends
with a one-line message ``bwim: error: ...`` on stderr and exit code 2, never a traceback,
and leaves no partial output file (every writer is atomic, outputs are checked before the
work starts).  Progress bars (tqdm, on stderr) show only when stdout is a terminal.

Subcommands:

``simulate SCENARIO [-o RECORD] [--bridge MODEL]``
    Simulate the scenario's crossing and write the record (``.h5`` or ``.csv``).
``calibrate SCENARIO RECORD... [-o MODEL] [--method] [--jobs] [--seed]``
    Calibrate the scenario's bridge (the starting model) from records of the scenario's
    vehicle; write the model (TOML) and print start → calibrated ± uncertainty.
``identify SCENARIO RECORD... [--bridge MODEL] [-o FOLDER|SUMMARY.csv] [--jobs|--scheduler]``
    Moving force identification on each record (folders expanded), in parallel with
    joblib or on a dask.distributed scheduler; a CSV summary (one row per vehicle) and one
    HDF5 result per record.
``weigh SCENARIO RECORD... (--calibration-records REC... | --influence IL.h5) [-o FOLDER]``
    Static weights by Moses' algorithm, the influence line calibrated from crossings of
    the scenario's vehicle (and written) or read from a file.
``report RESULTS... -o REPORT.html``
    A single-file HTML report (tables, embedded figures) of result files and folders.
``demo [--out FOLDER] [--quick]``
    The whole chain on the paper's slab bridge: simulate a calibration crossing,
    calibrate, identify a second vehicle's forces with the calibrated model, weigh it by
    Moses; a table against the truth, figures and ``report.html``.
``reproduce {5.1,5.2,5.3,5.4,compare,all}``
    The paper's experiments: tables with the paper's numbers beside ours, figures in
    ``--out`` (default ``bwim-out/reproduce``).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bwim import paper
from bwim.calibration import Method
from bwim.conventions import KILONEWTON, MICROSTRAIN
from bwim.errors import BwimError, InputError
from bwim.loads import PointLoad

__all__ = ["main"]

_RECORD_SUFFIXES = (".h5", ".hdf5", ".hdf", ".csv", ".txt")


# --- shared helpers ------------------------------------------------------------------------
def _quiet() -> bool:
    return not sys.stdout.isatty()


def _bar(total: int | None, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, disable=_quiet(), file=sys.stderr, leave=False)


def _out_file(path: str | Path, suffixes: Sequence[str] | None = None) -> Path:
    """An output file that can be written (checked before any work)."""
    from bwim.io import check_writable

    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{p}: unknown output format {p.suffix!r}; use "
                         f"{' or '.join(suffixes)}")
    return check_writable(p)


def _out_folder(path: str | Path) -> Path:
    """An output folder, created if needed, that can be written."""
    from bwim.io import check_writable

    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(f"cannot write in {p}: it is a file, not a folder")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder {p}: {exc.strerror or exc}") from None
    check_writable(p / "summary.csv")
    return p


def _record_paths(items: Sequence[str]) -> list[Path]:
    """Record files, folders expanded to the records they hold (sorted)."""
    from bwim.io.paths import expand_paths

    return expand_paths(items, _RECORD_SUFFIXES, what="records")


def _load_records(paths: Sequence[Path], scenario) -> list:
    from bwim.io import load_record

    records = []
    with _bar(len(paths) if len(paths) > 1 else None, "reading records") as bar:
        for p in paths:
            records.append(load_record(p, scenario))
            bar.update()
    return records


def _unique_stems(paths: Sequence[Path]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for p in paths:
        n = seen.get(p.stem, 0)
        seen[p.stem] = n + 1
        out.append(p.stem if n == 0 else f"{p.stem}_{n + 1}")
    return out


def _bridge(args: argparse.Namespace, scenario):
    from bwim.io import build_bridge, load_bridge

    return load_bridge(args.bridge) if args.bridge else build_bridge(scenario)


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], title: str = "") -> str:
    cells = [list(header), *[list(map(str, r)) for r in rows]]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    line = "  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True))
    out = ([title] if title else []) + [line, "-" * len(line)]
    out += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells[1:]]
    return "\n".join(out)


def _kn(values) -> list[str]:
    return [f"{v / KILONEWTON:.1f}" for v in np.atleast_1d(values)]


def _pct(value: float, ref: float) -> str:
    return f"{100.0 * (value / ref - 1.0):+.2f}"


def _write_csv(path: Path, header: Sequence[str], rows: Sequence[Sequence]) -> None:
    from bwim.io import atomic_open

    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


class _CalibrationProgress:
    """A tqdm bar fed by ``calibrate``'s callback: one tick per optimiser iteration."""

    def __init__(self) -> None:
        self.bar = _bar(None, "calibrating")
        self.stage = None

    def __call__(self, stage: str, iteration: int, best: float) -> None:
        if stage != self.stage:
            self.stage = stage
            self.bar.set_description(f"calibrating: {stage}")
        self.bar.set_postfix(best=f"{best:.3g}", refresh=False)
        self.bar.update()

    def close(self) -> None:
        self.bar.close()


# --- simulate --------------------------------------------------------------------------------
def _simulate(args: argparse.Namespace) -> int:
    from bwim.io import load_scenario, simulate_scenario, write_csv_record, write_record

    out = _out_file(args.output, (".h5", ".hdf5", ".hdf", ".csv"))
    scenario = load_scenario(args.scenario)
    bridge = _bridge(args, scenario) if args.bridge else None
    t0 = time.perf_counter()
    record = simulate_scenario(scenario, bridge=bridge)
    if out.suffix.lower() == ".csv":
        write_csv_record(record, out)
    else:
        write_record(record, out)
    p = record.passage
    print(f"simulated {scenario.title or scenario.source}: {p.n_axles}-axle vehicle at "
          f"{p.speed:g} m/s in lane {p.lane:g} m, {len(record.sensors)} channels × "
          f"{record.time.size} samples at {record.sampling_rate:g} Hz "
          f"({time.perf_counter() - t0:.1f} s)")
    if record.truths:
        print(f"true static axle loads (kN): {', '.join(_kn(record.truth.static_axle_loads))}; "
              f"GVW {record.truth.gvw / KILONEWTON:.1f} kN")
    print(f"record: {out}")
    return 0


# --- calibrate -------------------------------------------------------------------------------
def _param_rows(start: dict, cal) -> list[tuple[str, ...]]:
    rows = []
    for key, values in cal.params.items():
        for z, v in enumerate(np.atleast_1d(values)):
            s0 = np.atleast_1d(start[key])[z]
            u = np.atleast_1d(cal.uncertainty[key])[z]
            name = key if np.size(values) == 1 else f"{key}[{z}]"
            rows.append((name, f"{s0:.5g}", f"{v:.5g}", f"± {u:.3g}", _pct(v, s0)))
    return rows


def _calibrate(args: argparse.Namespace) -> int:
    from bwim.calibration import calibrate
    from bwim.io import build_bridge, build_road, build_vehicle, load_scenario, save_bridge

    out = _out_file(args.output, (".toml",))
    scenario = load_scenario(args.scenario)
    start = build_bridge(scenario)
    vehicle = build_vehicle(scenario)
    road = build_road(scenario)
    records = _load_records(_record_paths(args.records), scenario)
    kwargs = scenario.calibrate.kwargs() if scenario.calibrate is not None else {}
    for key in ("method", "seed"):
        if getattr(args, key) is not None:
            kwargs[key] = getattr(args, key)
    if args.jobs is not None:
        kwargs["n_jobs"] = args.jobs
    progress = _CalibrationProgress()
    try:
        cal = calibrate(start, records, vehicle, road=road, callback=progress, **kwargs)
    finally:
        progress.close()
    save_bridge(cal.bridge, out, title=f"calibrated from {len(records)} record(s) of "
                f"{scenario.title or scenario.source}")
    print(_table(("parameter", "start", "calibrated", "uncertainty", "change %"),
                 _param_rows(start.params, cal),
                 f"Calibrated parameters (SI: Pa, kg/m²), {len(records)} record(s):"))
    print()
    print(_table(("stage", "unknowns", "evaluations", "time (s)"),
                 [(s.name, ", ".join(s.labels), str(s.nfev), f"{s.wall_time:.1f}")
                  for s in cal.stages]))
    print(f"\nidentifiability: {cal.identifiability.summary().replace(chr(10), '; ')}")
    print(f"{cal.nfev} evaluations, wall time {cal.wall_time:.1f} s")
    print(f"calibrated model: {out}")
    return 0


# --- identify --------------------------------------------------------------------------------
def _identify_one(bridge, record, kwargs):
    """One record's identification (a top-level function: it runs in worker processes)."""
    from bwim.mfi import identify_forces

    return identify_forces(bridge, record, **kwargs)


def _identify_all(bridge, records, kwargs, *, jobs: int, scheduler: str | None) -> list:
    n = len(records)
    results: list = [None] * n
    with _bar(n if n > 1 else None, "identifying forces") as bar:
        if scheduler:
            from distributed import Client, as_completed

            try:
                client = Client(scheduler, timeout=10)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"cannot reach the dask scheduler {scheduler}: {exc}") from None
            try:
                [b] = client.scatter([bridge], broadcast=True)
                futures = [client.submit(_identify_one, b, r, kwargs, pure=False)
                           for r in records]
                index = {f.key: i for i, f in enumerate(futures)}
                for fut in as_completed(futures):
                    results[index[fut.key]] = fut.result()
                    bar.update()
            finally:
                client.close()
        elif jobs == 1 or n == 1:
            for i, r in enumerate(records):
                results[i] = _identify_one(bridge, r, kwargs)
                bar.update()
        else:
            from joblib import Parallel, delayed

            run = Parallel(n_jobs=jobs, return_as="generator")
            for i, res in enumerate(run(delayed(_identify_one)(bridge, r, kwargs)
                                        for r in records)):
                results[i] = res
                bar.update()
    return results


def _identify(args: argparse.Namespace) -> int:
    from bwim.io import load_scenario, write_identification

    if args.jobs < 1 and args.jobs != -1:
        raise InputError(f"--jobs must be a positive number or -1 (all cores), got {args.jobs}")
    out = Path(args.output)
    if out.suffix.lower() == ".csv":
        summary = _out_file(out)
        folder = summary.parent
    else:
        folder = _out_folder(out)
        summary = folder / "summary.csv"
    scenario = load_scenario(args.scenario)
    bridge = _bridge(args, scenario)
    paths = _record_paths(args.records)
    records = _load_records(paths, scenario)
    kwargs = scenario.identify.kwargs() if scenario.identify is not None else {}
    t0 = time.perf_counter()
    results = _identify_all(bridge, records, kwargs, jobs=args.jobs, scheduler=args.scheduler)
    n_max = max(ident.axle_weights.size for ident in results)
    header = ["record", "vehicle", "axles", *(f"axle_{i + 1}_kN" for i in range(n_max)),
              "gvw_kN", "lambda"]
    rows, shown = [], []
    for path, stem, ident in zip(paths, _unique_stems(paths), results, strict=True):
        write_identification(ident, folder / f"{stem}_forces.h5")
        a0 = 0
        for v, p in enumerate(ident.passages):
            w = ident.axle_weights[a0:a0 + p.n_axles]
            a0 += p.n_axles
            cells = _kn(w)
            rows.append([path.name, v + 1, p.n_axles, *cells, *[""] * (n_max - len(cells)),
                         f"{ident.gvw[v] / KILONEWTON:.2f}", f"{ident.lam:.4g}"])
            shown.append((path.name, str(v + 1), ", ".join(cells),
                           f"{ident.gvw[v] / KILONEWTON:.1f}", f"{ident.lam:.3g}"))
    _write_csv(summary, header, rows)
    print(_table(("record", "vehicle", "axle weights (kN)", "GVW (kN)", "λ"), shown,
                 f"Moving force identification, {len(records)} record(s), "
                 f"{time.perf_counter() - t0:.1f} s:"))
    print(f"summary: {summary}\nforces: {folder}/<record>_forces.h5")
    return 0


# --- weigh -----------------------------------------------------------------------------------
def _weigh(args: argparse.Namespace) -> int:
    from bwim.io import (
        build_vehicle,
        load_scenario,
        read_influence_line,
        write_influence_line,
        write_static_weights,
    )
    from bwim.wim import calibrate_influence_line, weigh_static

    folder = _out_folder(args.output)
    scenario = load_scenario(args.scenario)
    paths = _record_paths(args.records)
    records = _load_records(paths, scenario)
    if args.influence:
        il = read_influence_line(args.influence)
        print(f"influence line: {args.influence}")
    else:
        cal_records = _load_records(_record_paths(args.calibration_records), scenario)
        il = calibrate_influence_line(cal_records, build_vehicle(scenario))
        target = folder / "influence_line.h5"
        write_influence_line(il, target)
        print(f"influence line calibrated from {len(cal_records)} crossing(s) "
              f"(residual {il.residual:.3g}): {target}")
    n_max = 0
    results = []
    with _bar(len(records) if len(records) > 1 else None, "weighing") as bar:
        for path, rec in zip(paths, records, strict=True):
            try:
                results.append(weigh_static(rec, il))
            except InputError as exc:
                raise InputError(f"{path}: {exc}") from None
            n_max = max(n_max, results[-1].n_axles)
            bar.update()
    header = ["record", "axles", *(f"axle_{i + 1}_kN" for i in range(n_max)), "gvw_kN",
              "residual"]
    rows, shown = [], []
    for path, stem, w in zip(paths, _unique_stems(paths), results, strict=True):
        write_static_weights(w, folder / f"{stem}_static.h5")
        cells = _kn(w.axle_weights)
        rows.append([path.name, w.n_axles, *cells, *[""] * (n_max - len(cells)),
                     f"{w.gvw / KILONEWTON:.2f}", f"{w.residual:.4g}"])
        shown.append((path.name, ", ".join(cells), f"{w.gvw / KILONEWTON:.1f}",
                      f"{w.residual:.3g}"))
    _write_csv(folder / "summary.csv", header, rows)
    print(_table(("record", "axle weights (kN)", "GVW (kN)", "residual"), shown,
                 "Static weights (Moses):"))
    print(f"summary: {folder / 'summary.csv'}\nweights: {folder}/<record>_static.h5")
    return 0


# --- report ----------------------------------------------------------------------------------
def _report(args: argparse.Namespace) -> int:
    from bwim import report

    out = _out_file(args.output, (".html", ".htm"))
    items = report.read_results(args.results)
    sections = [report.section(obj, name) for name, obj in items]
    report.write_report(out, sections, title=args.title)
    print(f"report of {len(items)} result(s): {out}")
    return 0


# --- demo ------------------------------------------------------------------------------------
def _bridge_summary(modes_n: int) -> None:
    bridge = paper.slab_bridge()
    grid = bridge.model.grid
    print("bwim demo: the paper's slab bridge (Dowling, OBrien & González 2012, §5.1)")
    print(f"  {grid.length:g} m × {grid.width:g} m slab, {grid.nx} × {grid.ny} BFS elements, "
          f"{bridge.n_free} free DOF, E = {paper.SLAB_E / 1e9:g} GPa, "
          f"μ = {paper.SLAB_MU:g} kg/m², h = {paper.SLAB_THICKNESS:g} m (assumed)")
    modes = bridge.modes(modes_n)
    print(f"\nLowest {modes_n} natural frequencies (Hz):")
    print("  " + "  ".join(f"{f:7.2f}" for f in modes.frequencies))

    x2 = grid.length / 2  # rear (heavier) axle at mid-span
    x1 = x2 + paper.AXLE_SPACING
    half = paper.TRACK_WIDTH / 2
    loads = [
        PointLoad(x=x, y=paper.LANE + dy, P=p / 2)
        for x, p in ((x1, paper.AXLE_LOADS[0]), (x2, paper.AXLE_LOADS[1]))
        if x <= grid.length
        for dy in (-half, half)
    ]
    sensors = [s for s in paper.sensors() if s.kind.value == "strain_x"]
    strains = bridge.static(loads, sensors) / MICROSTRAIN
    print(f"\nStatic longitudinal soffit strain (µε), rear axle "
          f"({paper.AXLE_LOADS[1] / 1e3:g} kN) at mid-span, lane centre y = {paper.LANE:g} m:")
    xs = sorted({s.x for s in sensors})
    ys = sorted({s.y for s in sensors})
    table = np.array(strains).reshape(len(xs), len(ys))
    print("   y (m) " + "".join(f"{'x = ' + format(x, 'g') + ' m':>12}" for x in xs))
    for j, y in enumerate(ys):
        print(f"  {y:6.1f} " + "".join(f"{table[i, j]:12.2f}" for i in range(len(xs))))


#: Demo settings: (approach m, CE populations, convergences); --quick for tests.
#: The second (weighed) vehicle: a 3-axle rigid truck at another speed, on another road.


def _demo(args: argparse.Namespace) -> int:
    from bwim import report
    from bwim.demo import DEMO_ROAD_SEED, DEMO_SPEED, SETTINGS, run_demo
    from bwim.io import (
        atomic_output,
        save_bridge,
        write_identification,
        write_influence_line,
        write_record,
        write_static_weights,
    )
    from bwim.mfi import force_errors

    if not 1 <= args.modes <= 50:
        raise InputError(f"--modes must be between 1 and 50, got {args.modes}")
    out = _out_folder(args.out)
    t0 = time.perf_counter()
    _bridge_summary(args.modes)
    settings = SETTINGS[args.quick]
    approach, population = settings.approach, settings.population
    steps = {
        1: f"\n1. Calibration crossing: the paper's {paper.truck().n_axles}-axle truck at "
           f"{paper.SPEED:g} m/s, lane {paper.LANE:g} m, road class C, {approach:g} m "
           "approach (vehicle-bridge interaction simulated on the true bridge)",
        2: "2. Calibrating E_x, E_y, μ by Cross-Entropy from E_x×0.8, E_y×1.2, μ×1.25 "
           f"(populations {population[0]}/{population[1]}) …",
        3: None,
    }

    def on_step(n, _text):
        if steps[n]:
            print(steps[n], flush=True)

    progress = _CalibrationProgress()
    try:
        result = run_demo(quick=args.quick, seed=args.seed, n_jobs=args.jobs,
                          callback=progress, on_step=on_step)
    finally:
        progress.close()
    truth, start, cal = result.truth, result.start, result.calibration
    cal_rec, rec = result.calibration_record, result.second_record
    ident, ident_start = result.identified, result.identified_start
    il, moses = result.influence_line, result.moses
    unknowns = tuple(cal.params)
    vehicle = rec.passage
    rows = []
    for u in unknowns:
        s0, c, t = start.params[u][0], cal.params[u][0], truth.params[u][0]
        rows.append((u, f"{t:.5g}", f"{s0:.5g}", _pct(s0, t), f"{c:.5g}", _pct(c, t),
                     f"{cal.uncertainty[u][0]:.3g}"))
    print(_table(("parameter", "true", "start", "error %", "calibrated", "error %",
                  "uncertainty"), rows,
                 f"   {cal.nfev} evaluations, {cal.wall_time:.1f} s:"))

    print(f"\n3. A second vehicle: {vehicle.n_axles}-axle rigid truck at {DEMO_SPEED:g} m/s "
          f"over another stretch of road (seed {DEMO_ROAD_SEED}); forces identified with "
          "the calibrated and the starting model (longitudinal strains, L-curve λ), and "
          "Moses with the influence line calibrated from crossing 1", flush=True)
    true = rec.truth
    header = ("method", *(f"axle {i + 1} (kN)" for i in range(vehicle.n_axles)), "GVW (kN)",
              *(f"axle {i + 1} err %" for i in range(vehicle.n_axles)), "GVW err %")

    def row(name, w):
        return (name, *_kn(w), f"{np.sum(w) / KILONEWTON:.1f}",
                *(_pct(a, b) for a, b in zip(w, true.static_axle_loads, strict=True)),
                _pct(np.sum(w), true.gvw))

    print(_table(header, [
        row("truth (static)", true.static_axle_loads),
        row("MFI, calibrated model", ident.axle_weights),
        row("MFI, starting model", ident_start.axle_weights),
        row("Moses, calibrated IL", moses.axle_weights),
    ]))
    err = force_errors(ident, true)
    print("   MFI (calibrated) force RMS error, % of static axle load: "
          + ", ".join(f"{100 * e:.1f}" for e in err.rms_error) + f"; λ = {ident.lam:.3g}")

    save_bridge(cal.bridge, out / "calibrated_bridge.toml", title="bwim demo: calibrated")
    write_record(cal_rec, out / "calibration_crossing.h5")
    write_record(rec, out / "second_vehicle.h5")
    write_identification(ident, out / "second_vehicle_forces.h5")
    write_static_weights(moses, out / "second_vehicle_static.h5")
    write_influence_line(il, out / "influence_line.h5")
    sections = [
        report.section(cal, "E_x, E_y, μ of the paper's slab", start=start, true_bridge=truth),
        report.section(cal_rec, "calibration crossing (2-axle truck)", length=truth.length),
        report.section(rec, "second vehicle (3-axle truck)", length=truth.length),
        report.section(ident, "second vehicle, calibrated model", truth=true),
        report.section(ident_start, "second vehicle, starting (uncalibrated) model",
                       truth=true),
        report.section(il, "calibrated from crossing 1", true_bridge=truth),
        report.section(moses, "second vehicle", truth=true),
    ]
    for s in sections:
        for k, (_, fig) in enumerate(s.figures):
            name = "".join(c if c.isalnum() else "_" for c in s.title.lower())[:48]
            with atomic_output(out / f"{name.strip('_')}_{k + 1}.png") as tmp:
                fig.savefig(tmp, format="png", dpi=100)
    page = report.write_report(
        out / "report.html", sections, title="bwim demo: the paper's slab bridge",
        intro="Everything below was computed by this run: a simulated calibration crossing "
              "of the paper's truck, a Cross-Entropy calibration from a wrong starting "
              "model, and the weighing of a second vehicle by moving force identification "
              "(calibrated and starting model) and by Moses' static algorithm.")
    print(f"\nfiles in {out}: calibrated_bridge.toml, records, results (.h5), figures (.png)")
    print(f"report: {page}")
    print(f"demo took {time.perf_counter() - t0:.1f} s")
    return 0


def _reproduce(args: argparse.Namespace) -> int:
    from bwim import reproduce
    from bwim.io.atomic import atomic_output, check_writable

    names = list(reproduce.CASES) if args.case == "all" else [args.case]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    check_writable(out / ".probe")
    t0 = time.perf_counter()
    for name in names:
        print(f"== reproducing {name}{' (quick)' if args.quick else ''} ==", flush=True)
        kwargs = {"quick": args.quick}
        if name != "compare":
            kwargs["n_jobs"] = args.jobs
        report = reproduce.CASES[name](**kwargs)
        print(report.render(), flush=True)
        if not args.no_figures:
            from bwim.plots.reproduce import report_figures

            for fig_name, fig in report_figures(report).items():
                target = out / f"{name.replace('.', '_')}_{fig_name}.png"
                with atomic_output(target) as tmp:
                    fig.savefig(tmp, format="png", dpi=110)
                print(f"  figure: {target}")
        print()
    print(f"total {time.perf_counter() - t0:.1f} s")
    return 0


def _parser() -> argparse.ArgumentParser:
    fmt = argparse.RawDescriptionHelpFormatter
    p = argparse.ArgumentParser(
        prog="bwim",
        description="Calibrated, dynamic Bridge Weigh-in-Motion: simulate crossings, "
        "calibrate the bridge's FE model from a truck of known weight, identify the moving "
        "axle forces of other vehicles, weigh them statically (Moses), report.",
        epilog="Scenario files (TOML) describe the bridge, the sensors, the vehicle, the "
        "road and the run; see examples/paper_slab.toml.  Units are SI.",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser(
        "simulate", formatter_class=fmt,
        help="simulate a scenario's vehicle crossing and write the strain record",
        description="Simulate the scenario's vehicle crossing its bridge (vehicle-bridge "
        "interaction over the road profile) and write what the sensors read.\n\n"
        "  bwim simulate examples/paper_slab.toml -o crossing.h5")
    s.add_argument("scenario", metavar="SCENARIO.toml", help="the scenario file")
    s.add_argument("-o", "--output", default="record.h5", metavar="RECORD",
                   help="output record: .h5 (with positions, passage and true forces) or "
                   ".csv (time and readings only); default record.h5")
    s.add_argument("--bridge", metavar="MODEL.toml",
                   help="use this bridge model (e.g. a calibrated one) instead of the "
                   "scenario's [bridge]")
    s.set_defaults(run=_simulate)

    c = sub.add_parser(
        "calibrate", formatter_class=fmt,
        help="calibrate the bridge model from crossings of a truck of known weight",
        description="Calibrate the stiffness (E_x, E_y, …) and mass (mu) of the scenario's "
        "bridge from strain records of the scenario's vehicle, the calibration truck of "
        "known static axle loads.  The scenario's [bridge] is the starting model and its "
        "[calibrate] section gives the defaults; the records must be crossings at the "
        "scenario's [run] speed, lane and approach, over its [road].\n\n"
        "  bwim calibrate examples/paper_slab.toml crossing.h5 -o calibrated.toml")
    c.add_argument("scenario", metavar="SCENARIO.toml")
    c.add_argument("records", nargs="+", metavar="RECORD",
                   help="records of the calibration truck (.h5 or .csv; folders expanded)")
    c.add_argument("-o", "--output", default="calibrated.toml", metavar="MODEL.toml",
                   help="the calibrated bridge model (default calibrated.toml)")
    c.add_argument("--method", choices=[m.value for m in Method],
                   help="optimiser: ce = Cross-Entropy (the paper's), lm = "
                   "Levenberg-Marquardt, cma = CMA-ES (default: the scenario's, else ce)")
    c.add_argument("--jobs", type=int, help="worker processes for the populations")
    c.add_argument("--seed", type=int, help="random seed of the optimiser")
    c.set_defaults(run=_calibrate)

    i = sub.add_parser(
        "identify", formatter_class=fmt,
        help="identify the moving axle forces and weights of vehicles (MFI)",
        description="Moving force identification: the time history of each axle's force, "
        "its static weight and the gross vehicle weight, from each record and the bridge "
        "model (ideally a calibrated one).  Many records run in parallel on this machine "
        "(--jobs) or on a dask.distributed cluster (--scheduler).  Writes a CSV summary, "
        "one row per vehicle, and <record>_forces.h5 per record.\n\n"
        "  bwim identify examples/paper_slab.toml records/ --bridge calibrated.toml -o out/")
    i.add_argument("scenario", metavar="SCENARIO.toml",
                   help="the scenario (sensor positions; passage of CSV records)")
    i.add_argument("records", nargs="+", metavar="RECORD",
                   help="records (.h5 or .csv) or folders of them")
    i.add_argument("--bridge", metavar="MODEL.toml",
                   help="bridge model (default: the scenario's [bridge])")
    i.add_argument("-o", "--output", default="bwim-out/identify", metavar="OUT",
                   help="a results folder, or summary.csv (results beside it); default "
                   "bwim-out/identify")
    par = i.add_mutually_exclusive_group()
    par.add_argument("--jobs", type=int, default=1,
                     help="worker processes on this machine (-1: all cores); default 1")
    par.add_argument("--scheduler", metavar="ADDRESS",
                     help="address of a dask.distributed scheduler, e.g. tcp://host:8786")
    i.set_defaults(run=_identify)

    w = sub.add_parser(
        "weigh", formatter_class=fmt,
        help="static weights by Moses' algorithm from an influence line",
        description="Static axle weights and GVW by Moses' algorithm.  The influence line "
        "is either calibrated from crossings of the scenario's vehicle (the calibration "
        "truck) and written to the output folder, or read from a file.\n\n"
        "  bwim weigh examples/paper_slab.toml truck.h5 --calibration-records crossing.h5")
    w.add_argument("scenario", metavar="SCENARIO.toml")
    w.add_argument("records", nargs="+", metavar="RECORD",
                   help="records of the vehicles to weigh (.h5 or .csv; folders expanded)")
    il = w.add_mutually_exclusive_group(required=True)
    il.add_argument("--calibration-records", nargs="+", metavar="REC",
                    help="crossings of the scenario's vehicle to calibrate the influence "
                    "line from")
    il.add_argument("--influence", metavar="IL.h5", help="a saved influence line")
    w.add_argument("-o", "--output", default="bwim-out/weigh", metavar="FOLDER",
                   help="results folder (default bwim-out/weigh)")
    w.set_defaults(run=_weigh)

    r = sub.add_parser(
        "report", formatter_class=fmt,
        help="a single-file HTML report of result files",
        description="A self-contained HTML page (figures embedded) of result files: force "
        "identifications, static weights, influence lines, records (.h5), bridge models "
        "(.toml) and summaries (.csv); folders are expanded.\n\n"
        "  bwim report out/ -o report.html")
    r.add_argument("results", nargs="+", metavar="RESULTS")
    r.add_argument("-o", "--output", default="report.html", metavar="REPORT.html",
                   help="default report.html")
    r.add_argument("--title", default="bwim report", help="the page title")
    r.set_defaults(run=_report)

    d = sub.add_parser(
        "demo", formatter_class=fmt,
        help="the whole chain on the paper's slab bridge, in under a minute",
        description="On the paper's 12 m × 8 m slab: simulate a calibration crossing, "
        "calibrate E_x, E_y and mu from a wrong start by Cross-Entropy, identify a second "
        "vehicle's axle forces with the calibrated model and weigh it by Moses; print the "
        "results against the truth and write figures and report.html to --out.")
    d.add_argument("--modes", type=int, default=6, help="natural frequencies to print "
                   "(default 6)")
    d.add_argument("--out", default="bwim-out", help="output folder (default bwim-out)")
    d.add_argument("--seed", type=int, default=0, help="seed of the calibration")
    d.add_argument("--jobs", type=int, default=1, help="worker processes for calibration")
    d.add_argument("--quick", action="store_true",
                   help="a smaller, faster calibration (for tests)")
    d.set_defaults(run=_demo)

    rp = sub.add_parser(
        "reproduce",
        help="the paper's experiments with its numbers side by side",
        description="Reproduce Dowling, OBrien & González (2012) §5: 5.1 identical "
        "elements, 5.2 noise, 5.3 sixteen zones, 5.4 beam-and-slab bridge, and a comparison "
        "of optimisers ('compare').  Full runs take minutes (5.3 the longest); --quick runs "
        "small versions.",
    )
    rp.add_argument("case", choices=["5.1", "5.2", "5.3", "5.4", "compare", "all"])
    rp.add_argument("--quick", action="store_true", help="small, fast versions")
    rp.add_argument("--out", default="bwim-out/reproduce", help="folder for the figures")
    rp.add_argument("--jobs", type=int, default=1, help="worker processes for populations")
    rp.add_argument("--no-figures", action="store_true", help="tables only")
    rp.set_defaults(run=_reproduce)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``bwim`` command; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args))
    except BwimError as exc:
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"bwim: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bwim: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
