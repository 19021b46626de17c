"""The ``bwim`` command line.

Contract
--------
``main(argv=None) -> int`` parses arguments, calls the library and prints; it holds no
numerics.  The subcommands are one declarative table, :data:`COMMANDS` (name, handler,
help, description, arguments), from which the parser is built; tables are printed with
:class:`bwim.tables.Table`.  Bad input (a scenario, record or model file, an option, an
output path) ends with a one-line message ``bwim: error: ...`` on stderr and exit code 2,
never a traceback, and leaves no partial output file (every writer is atomic, outputs are
checked before the work starts).  Progress bars (tqdm, on stderr) show only when stdout is
a terminal.

Subcommands:

``simulate SCENARIO [-o RECORD] [--bridge MODEL]``
    Simulate the scenario's crossing and write the record (``.h5`` or ``.csv``).
``calibrate SCENARIO RECORD... [-o MODEL] [--method] [--jobs] [--seed]``
    Calibrate the scenario's bridge (the starting model) from records of the scenario's
    vehicle; write the model (TOML) and print start → calibrated ± uncertainty.
``identify SCENARIO RECORD... [--bridge MODEL] [-o FOLDER|SUMMARY.csv] [--jobs|--scheduler]``
    Moving force identification on each record (folders expanded), in parallel on
    ``--jobs`` processes (this one and loky workers, each reading its records and
    writing their results) or on a dask.distributed scheduler; a CSV summary (one row
    per vehicle, one with the reason per failed record) and one HDF5 result per record,
    written as each record finishes (the summary and ``manifest.json`` at most every
    second or so).  A rerun skips the records done (``manifest.json``); ``--force``
    starts afresh.  Exit code 0: all records done; 1: some failed; 2: bad input.

Safety of outputs (:mod:`bwim.io.outputs`): an output that is one of the inputs is refused;
an existing output file is refused unless ``--force``; an output folder is locked
(``.bwim.lock``) for the run; SIGTERM ends a run like Ctrl-C (temporary files removed,
worker processes stopped, exit code 130).  ``bwim --memory-limit SIZE COMMAND`` bounds the
memory of the run (:mod:`bwim.limits`).
``weigh SCENARIO RECORD... (--calibration-records REC... | --influence IL.h5) [-o FOLDER]``
    Static weights by Moses' algorithm, the influence line calibrated from crossings of
    the scenario's vehicle (and written) or read from a file.
``accuracy SUMMARY.csv --reference REF.csv [--repeatability] [--environment]``
    The COST 323 accuracy class per criterion and overall.
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
import contextlib
import csv
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from bwim.calibration import Method
from bwim.errors import BwimError, InputError
from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values

__all__ = ["main"]

_RECORD_SUFFIXES = (".h5", ".hdf5", ".hdf", ".csv", ".txt")


# --- shared helpers ------------------------------------------------------------------------
def _quiet() -> bool:
    return not sys.stdout.isatty()


def _bar(total: int | None, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, disable=_quiet(), file=sys.stderr, leave=False)


class _Progress:
    """A batch's progress on stderr: a bar (count, total, rate, ETA) on a terminal, else a
    plain line every :attr:`every` seconds.  ``progress(n)``: n items finished so far."""

    every = 10.0

    def __init__(self, total: int, desc: str) -> None:
        self.total, self.desc = total, desc
        self.tty = sys.stderr.isatty()
        self.bar = _bar(total, desc) if self.tty and total > 1 else None
        self.t0 = self.last = time.perf_counter()
        self.start = self.n = 0

    def __call__(self, n: int) -> None:
        if self.n == 0 and self.start == 0 and n > 0 and self.last == self.t0:
            self.start = n  # done before: not part of the rate
        if self.bar is not None:
            self.bar.update(n - self.n)
        self.n = n
        now = time.perf_counter()
        if not self.tty and self.total > 1 and now - self.last >= self.every:
            self.last = now
            rate = (n - self.start) / max(now - self.t0, 1e-9)
            eta = (self.total - n) / rate if rate > 0 else float("nan")
            print(f"bwim: {self.desc}: {n}/{self.total} ({100 * n / self.total:.0f} %), "
                  f"{rate:.3g}/s, ETA {eta / 60:.1f} min", file=sys.stderr, flush=True)

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()


def _out_file(path: str | Path, suffixes: Sequence[str] | None = None, *,
              inputs: Sequence[str | Path] = (), force: bool = True) -> Path:
    """An output file that can be written (checked before any work): not one of the
    ``inputs``, and not an existing file unless ``force``."""
    from bwim.io import check_writable
    from bwim.io.outputs import refuse_existing, refuse_input_overwrite

    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{p}: unknown output format {p.suffix!r}; use "
                         f"{' or '.join(suffixes)}")
    refuse_input_overwrite([p], inputs)
    check_writable(p)
    return refuse_existing(p, force=force)


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


def _locked(folder: Path):
    """The output folder's lock for this run (:class:`bwim.io.outputs.OutputLock`)."""
    from bwim.io.outputs import OutputLock

    return OutputLock(folder)


def _record_paths(items: Sequence[str], *, any_suffix: bool = False) -> list[Path]:
    """Record files, folders expanded to the records they hold (sorted); with
    ``any_suffix`` (a logger's exports) every file of a folder."""
    from bwim.io.paths import expand_paths

    return expand_paths(items, None if any_suffix else _RECORD_SUFFIXES, what="records")


def _load_records(paths: Sequence[Path], scenario) -> list:
    from bwim.scenario import load_record

    records = []
    with _bar(len(paths) if len(paths) > 1 else None, "reading records") as bar:
        for p in paths:
            records.append(load_record(p, scenario))
            bar.update()
    return records


def _check_jobs(jobs: int | None) -> None:
    if jobs is not None and jobs < 1 and jobs != -1:
        raise InputError(f"--jobs must be a positive number or -1 (all cores), got {jobs}")


def _name(path: Path) -> str:
    """A file name as text that can be printed and written (a name that is not valid
    UTF-8 shows its odd bytes as U+FFFD)."""
    return os.fsencode(path.name).decode("utf-8", "replace")


def _unique_stems(paths: Sequence[Path]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for p in paths:
        n = seen.get(p.stem, 0)
        seen[p.stem] = n + 1
        out.append(p.stem if n == 0 else f"{p.stem}_{n + 1}")
    return out


def _bridge(args: argparse.Namespace, scenario):
    from bwim.scenario import build_bridge, load_bridge

    return load_bridge(args.bridge) if args.bridge else build_bridge(scenario)


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
    from bwim.io import write_csv_record, write_record
    from bwim.scenario import load_scenario, simulate_scenario

    out = _out_file(args.output, (".h5", ".hdf5", ".hdf", ".csv"),
                    inputs=[args.scenario, *([args.bridge] if args.bridge else [])],
                    force=args.force)
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
        print("true static axle loads (kN): "
              f"{', '.join(format_kn_each(record.truth.static_axle_loads))}; "
              f"GVW {format_kn(record.truth.gvw)} kN")
    print(f"record: {out}")
    return 0


# --- calibrate -------------------------------------------------------------------------------
def _calibrate(args: argparse.Namespace) -> int:
    from bwim.calibration import calibrate
    from bwim.scenario import build_bridge, build_road, build_vehicle, load_scenario, save_bridge

    _check_jobs(args.jobs)
    paths = _record_paths(args.records)
    out = _out_file(args.output, (".toml",), inputs=[args.scenario, *paths],
                    force=args.force)
    scenario = load_scenario(args.scenario)
    start = build_bridge(scenario)
    vehicle = build_vehicle(scenario)
    road = build_road(scenario)
    records = _load_records(paths, scenario)
    kwargs = scenario.calibrate.kwargs() if scenario.calibrate is not None else {}
    for key in ("method", "seed"):
        if getattr(args, key) is not None:
            kwargs[key] = getattr(args, key)
    if args.jobs is not None:
        kwargs["n_jobs"] = args.jobs
    if args.mesh_correction is not None:
        mc = args.mesh_correction.strip().lower()
        kwargs["mesh_correction"] = int(mc) if mc.isdigit() else mc
    progress = _CalibrationProgress()
    try:
        cal = calibrate(start, records, vehicle, road=road, callback=progress, **kwargs)
    finally:
        progress.close()
    # with the mesh correction the parameters are the finer model's: save that model
    saved = cal.bridge if cal.mesh_correction is None else cal.mesh_correction.bridge
    save_bridge(saved, out, title=f"calibrated from {len(records)} record(s) of "
                f"{scenario.title or scenario.source}")
    rows = [(name, f"{s0:.5g}", f"{v:.5g}", f"± {u:.3g}", format_pct(v, s0))
            for name, v, s0, u in param_values(cal.params, start.params, cal.uncertainty)]
    print(Table(f"Calibrated parameters (SI: Pa, kg/m²), {len(records)} record(s):",
                ("parameter", "start", "calibrated", "uncertainty", "change %"),
                rows).render())
    print()
    print(Table("", ("stage", "unknowns", "evaluations", "time (s)"),
                [(s.name, ", ".join(s.labels), s.nfev, f"{s.wall_time:.1f}")
                 for s in cal.stages]).render())
    print(f"\nidentifiability: {cal.identifiability.summary().replace(chr(10), '; ')}")
    if cal.mesh_correction is not None:
        nx, ny = cal.mesh_correction.mesh
        print(f"{cal.mesh_correction.summary()}\nthe calibrated model is saved on the "
              f"{nx}x{ny} mesh the corrected parameters belong to")
    if cal.discretisation is not None:
        print(f"mesh check: {cal.discretisation.summary().replace(chr(10), '; ')}")
    print(f"{cal.nfev} evaluations, wall time {cal.wall_time:.1f} s")
    print(f"calibrated model: {out}")
    return 0


# --- batches: identify and weigh -------------------------------------------------------------
def _meta(command: str, **inputs) -> dict:
    """What a batch is, for its manifest: the command and its inputs' identities."""
    from bwim.io.outputs import file_key

    def key(p):
        if p is None:
            return None
        try:
            return file_key(p)
        except OSError:  # reported by the command's own reading, with its message
            return str(p)

    return {"command": command, **{k: [key(p) for p in v] if isinstance(v, list) else key(v)
                                   for k, v in inputs.items()}}


def _read(scenario):
    """The batch's reader of one record (picklable: it goes to worker processes)."""
    from functools import partial

    from bwim.scenario import load_record

    return partial(load_record, scenario=scenario)


def _run_batch(folder, items, run, desc: str):
    """Run a batch into its folder with a progress display; its report."""
    from bwim.batch import run_into

    with _Progress(len(items), desc) as progress:
        return run_into(folder, items, run, progress=progress)


def _report_failures(report) -> int:
    """Print each failed record on stderr; the batch's exit code."""
    from bwim.io.outputs import EXIT_FAILED, EXIT_OK

    for name, reason in report.failures:
        print(f"bwim: {name} failed: {reason}", file=sys.stderr)
    if report.failures:
        print(f"bwim: {len(report.failures)} of {report.n_inputs} record(s) failed (see the "
              "summary's reason column)", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def _done_before(report) -> str:
    return f" ({report.n_done_before} done before)" if report.n_done_before else ""


def _identify(args: argparse.Namespace) -> int:
    from bwim.batch import BatchFolder, Item, executor_for, identify_records
    from bwim.io.outputs import refuse_input_overwrite
    from bwim.scenario import load_scenario

    _check_jobs(args.jobs)
    out = Path(args.output)
    if out.suffix.lower() == ".csv":
        summary = _out_file(out)
        folder = summary.parent
    else:
        folder = _out_folder(out)
        summary = folder / "summary.csv"
    paths = _record_paths(args.records)
    inputs = [args.scenario, *([args.bridge] if args.bridge else []), *paths]
    items = [Item(name=_name(p), source=p, target=folder / f"{stem}_forces.h5")
             for p, stem in zip(paths, _unique_stems(paths), strict=True)]
    refuse_input_overwrite([summary, *(it.target for it in items)], inputs)
    with _locked(folder):
        scenario = load_scenario(args.scenario)
        bridge = _bridge(args, scenario)
        batch = BatchFolder(folder, resume=args.resume, force=args.force, summary=summary,
                            meta=_meta("identify", scenario=args.scenario, bridge=args.bridge))
        kwargs = scenario.identify.kwargs() if scenario.identify is not None else {}
        executor = executor_for(args.jobs, args.scheduler)
        report = _run_batch(batch, items, lambda todo: identify_records(
            todo, bridge, read=_read(scenario), options=kwargs, executor=executor,
            keep=False), "identifying forces")
    shown = [(r.record, r.vehicle, format_kn_each(r.axle_weights) if r.weighed else
              r.reason, format_kn(r.gvw) if r.weighed else "",
              "" if r.lam is None else f"{r.lam:.4g}") for r in report.rows]
    print(Table(f"Moving force identification, {len(paths)} record(s){_done_before(report)}, "
                f"{report.elapsed:.1f} s:",
                ("record", "vehicle", "axle weights (kN)", "GVW (kN)", "λ"), shown).render())
    print(f"summary: {summary}\nforces: {folder}/<record>_forces.h5")
    return _report_failures(report)


def _unique_names(paths: Sequence[Path]) -> None:
    """The summary names each record by its file name: two files of one name (from two
    folders) would be confused, in the summary, by ``--resume`` and by the accuracy."""
    seen: dict[str, Path] = {}
    for p in paths:
        if p.name in seen:
            raise InputError(f"two records are named {p.name!r} ({seen[p.name]} and {p}); "
                             "the summary names records by file name: rename one")
        seen[p.name] = p


def _calibrate_site(paths: Sequence[Path], scenario, folder: Path):
    """Lines from the calibration truck's logger events; a table of the runs."""
    from bwim.io import write_influence_line
    from bwim.scenario import build_site_setup, load_record
    from bwim.site import calibrate_site

    setup = build_site_setup(scenario)
    records, used, unread = [], [], []
    for p in paths:
        try:
            records.append(load_record(p, scenario))
            used.append(p)
        except InputError as exc:
            unread.append((p.name, str(exc)))
    if not records and unread:
        raise InputError(f"no calibration run could be read; {unread[0][0]}: {unread[0][1]}")
    site = calibrate_site(records, setup)
    rows = []
    for p, det, reason, fit in zip(used, site.detections, site.reasons, site.fits,
                                   strict=True):
        v = det.vehicles[0].passage if len(det.vehicles) == 1 else None
        rows.append((p.name, "" if v is None else f"{v.speed:.2f}",
                     "" if v is None else f"{v.lane:.2f}",
                     "" if fit is None else f"{fit.scale:.4f}",
                     "" if fit is None else f"{fit.residual:.3g}",
                     reason or "used"))
    rows += [(name, "", "", "", "", f"unreadable: {msg}") for name, msg in unread]
    header = ("run", "speed (m/s)", "lateral", "scale", "residual", "status")
    _write_csv(folder / "calibration_runs.csv", header, rows)
    print(Table(f"Calibration runs ({site.n_used} of {len(paths)} used):", header,
                rows).render())
    write_influence_line(site.lines.line_at(), folder / "influence_lines.h5")
    return site


def _print_weighed(report, title: str) -> None:
    rows = report.rows
    shown = [(r.record, r.vehicle, r.n_axles or "",
              ", ".join(format_kn_each(r.axle_weights)) if r.weighed else "-",
              format_kn(r.gvw) if r.weighed else "-",
              ";".join(r.flags) if r.weighed else r.reason) for r in rows[:20]]
    print(Table(title, ("record", "vehicle", "axles", "axle weights (kN)", "GVW (kN)",
                        "flags / reason"), shown).render())
    if len(rows) > 20:
        print(f"... {len(rows) - 20} more in the summary")


def _weigh_site(args: argparse.Namespace, scenario, folder: Path, batch) -> int:
    """``bwim weigh`` on a real installation's logger files (scenario with [logger])."""
    from bwim.batch import Item, executor_for, weigh_events

    if not args.calibration_records:
        raise InputError("weighing logger files needs --calibration-records (runs of the "
                         "calibration truck)")
    paths = _record_paths(args.records, any_suffix=True)
    bridge = options = None
    if args.bridge:
        from bwim.scenario import load_bridge

        bridge = load_bridge(args.bridge)
        options = scenario.identify.kwargs() if scenario.identify is not None else {}
    site = _calibrate_site(_record_paths(args.calibration_records, any_suffix=True),
                           scenario, folder)
    executor = executor_for(args.jobs, args.scheduler)
    report = _run_batch(batch, [Item(name=_name(p), source=p) for p in paths],
                        lambda todo: weigh_events(todo, site, read=_read(scenario),
                                                  bridge=bridge, identify_options=options,
                                                  executor=executor, keep=False), "weighing")
    print(f"{len(paths)} event(s){_done_before(report)} in {report.elapsed:.1f} s: "
          f"{report.count('weighed')} vehicle(s) weighed, {report.count('refused')} not "
          f"weighed (flagged), {report.count('failed')} record(s) failed")
    _print_weighed(report, "Static weights (moving force identification with the FE "
                   "model):" if bridge else "Static weights (multi-run influence lines, "
                   "gauges combined):")
    print(f"summary: {batch.summary}")
    return _report_failures(report)


def _weigh(args: argparse.Namespace) -> int:
    from bwim.batch import BatchFolder
    from bwim.io.outputs import refuse_existing, refuse_input_overwrite
    from bwim.scenario import load_scenario

    _check_jobs(args.jobs)
    folder = _out_folder(args.output)
    scenario = load_scenario(args.scenario)
    site = scenario.logger is not None
    paths = _record_paths(args.records, any_suffix=site)
    _unique_names(paths)
    cal = (_record_paths(args.calibration_records, any_suffix=site)
           if args.calibration_records else [])
    outputs = ([folder / "calibration_runs.csv", folder / "influence_lines.h5"] if site
               else [folder / "influence_line.h5"])
    refuse_input_overwrite([folder / "summary.csv", *outputs],
                           [args.scenario, *paths, *cal,
                            *([args.influence] if args.influence else []),
                            *([args.bridge] if args.bridge else [])])
    with _locked(folder):
        if not args.resume and not (site is False and args.influence):
            for p in outputs:  # no output of a command replaced without --force
                refuse_existing(p, force=args.force)
        batch = BatchFolder(folder, resume=args.resume, force=args.force, meta=_meta(
            "weigh", scenario=args.scenario, calibration=sorted(cal, key=str),
            influence=args.influence, bridge=args.bridge))
        if site:
            return _weigh_site(args, scenario, folder, batch)
        return _weigh_moses(args, scenario, folder, batch, paths, cal)


def _weigh_moses(args: argparse.Namespace, scenario, folder: Path, batch, paths, cal) -> int:
    """``bwim weigh`` on records with their passages (simulated, or a [run] scenario)."""
    from bwim.batch import Item, executor_for, weigh_records
    from bwim.io import read_influence_line, write_influence_line
    from bwim.scenario import build_vehicle
    from bwim.wim import calibrate_influence_line

    if args.bridge:
        raise InputError("--bridge weighs logger files by MFI (a scenario with [logger]); "
                         "for records with their passages use bwim identify")
    if args.influence:
        il = read_influence_line(args.influence)
        print(f"influence line: {args.influence}")
    else:
        il = calibrate_influence_line(_load_records(cal, scenario), build_vehicle(scenario))
        target = folder / "influence_line.h5"
        write_influence_line(il, target)
        print(f"influence line calibrated from {len(cal)} crossing(s) "
              f"(residual {il.residual:.3g}): {target}")
    items = [Item(name=_name(p), source=p, target=folder / f"{stem}_static.h5")
             for p, stem in zip(paths, _unique_stems(paths), strict=True)]
    executor = executor_for(args.jobs, args.scheduler)
    report = _run_batch(batch, items, lambda todo: weigh_records(
        todo, il, read=_read(scenario), executor=executor, keep=False), "weighing")
    _print_weighed(report, f"Static weights (Moses){_done_before(report)}:")
    print(f"summary: {batch.summary}\nweights: {folder}/<record>_static.h5")
    return _report_failures(report)


# --- accuracy --------------------------------------------------------------------------------
def _accuracy(args: argparse.Namespace) -> int:
    from bwim.accuracy import assess
    from bwim.io import read_reference, read_summary

    summary = read_summary(args.summary)
    reference = read_reference(args.reference)
    result = assess(summary, reference, repeatability=args.repeatability,
                    environment=args.environment, strict=args.strict)
    print(result.render())
    if args.output:
        target = _out_file(args.output, (".csv",), inputs=[args.summary, args.reference],
                           force=args.force)
        table = result.table()
        _write_csv(target, table.header, table.rows)
        print(f"table: {target}")
    return 0


# --- report ----------------------------------------------------------------------------------
def _report(args: argparse.Namespace) -> int:
    from bwim import report

    out = _out_file(args.output, (".html", ".htm"), force=args.force,
                    inputs=[*args.results, *([args.reference] if args.reference else [])])
    items = report.read_results(args.results)
    sections = [report.section(obj, name) for name, obj in items]
    if args.reference:  # COST 323 classes of every weigh summary among the results
        from bwim.accuracy import assess
        from bwim.io import read_reference, read_summary
        from bwim.io.summary import is_summary

        reference = read_reference(args.reference)
        summaries = [p for p in report.result_paths(args.results)
                     if p.suffix.lower() == ".csv" and is_summary(p)]
        if not summaries:
            raise InputError("--reference needs a weigh summary.csv among the results")
        for p in summaries:
            sections.append(report.section(assess(read_summary(p), reference), p.name))
    report.write_report(out, sections, title=args.title)
    print(f"report of {len(items)} result(s): {out}")
    return 0


# --- demo ------------------------------------------------------------------------------------
def _write_figures(figures: dict, folder: Path, *, prefix: str = "", dpi: int) -> list[Path]:
    """Each named figure as ``folder/<prefix><name>.png`` (atomically); the paths."""
    from bwim.io import atomic_output

    paths = []
    for name, fig in figures.items():
        target = folder / f"{prefix}{name}.png"
        with atomic_output(target) as tmp:
            fig.savefig(tmp, format="png", dpi=dpi)
        paths.append(target)
    return paths


def _demo(args: argparse.Namespace) -> int:
    from bwim.paper.demo import MAX_MODES

    if not 1 <= args.modes <= MAX_MODES:
        raise InputError(f"--modes must be between 1 and {MAX_MODES}, got {args.modes}")
    _check_jobs(args.jobs)
    out = _out_folder(args.out)
    with _locked(out):
        return _demo_run(args, out)


def _demo_run(args: argparse.Namespace, out: Path) -> int:
    from bwim.io import (
        write_identification,
        write_influence_line,
        write_record,
        write_static_weights,
    )
    from bwim.paper.demo import REPORT_INTRO, REPORT_TITLE, run_demo
    from bwim.report import figure_files, write_report
    from bwim.scenario import save_bridge

    t0 = time.perf_counter()
    progress = _CalibrationProgress()
    try:
        demo = run_demo(quick=args.quick, seed=args.seed, n_jobs=args.jobs, n_modes=args.modes,
                        callback=progress, echo=lambda text: print(text, flush=True))
    finally:
        progress.close()
    save_bridge(demo.calibration.bridge, out / "calibrated_bridge.toml",
                title="bwim demo: calibrated")
    write_record(demo.calibration_record, out / "calibration_crossing.h5")
    write_record(demo.second_record, out / "second_vehicle.h5")
    write_identification(demo.identified, out / "second_vehicle_forces.h5")
    write_static_weights(demo.moses, out / "second_vehicle_static.h5")
    write_influence_line(demo.influence_line, out / "influence_line.h5")
    sections = demo.sections()
    _write_figures(figure_files(sections), out, dpi=100)
    page = write_report(out / "report.html", sections, title=REPORT_TITLE, intro=REPORT_INTRO)
    print(f"\nfiles in {out}: calibrated_bridge.toml, records, results (.h5), figures (.png)")
    print(f"report: {page}")
    print(f"demo took {time.perf_counter() - t0:.1f} s")
    return 0


# --- reproduce -------------------------------------------------------------------------------
def _reproduce(args: argparse.Namespace) -> int:
    from bwim.io import check_writable
    from bwim.paper import reproduce

    names = list(reproduce.CASES) if args.case == "all" else [args.case]
    _check_jobs(args.jobs)
    out = _out_folder(args.out)
    check_writable(out / ".probe")
    with _locked(out):
        _reproduce_cases(args, names, out)
    return 0


def _reproduce_cases(args: argparse.Namespace, names: Sequence[str], out: Path) -> None:
    from bwim.paper import reproduce

    t0 = time.perf_counter()
    for name in names:
        print(f"== reproducing {name}{' (quick)' if args.quick else ''} ==", flush=True)
        kwargs = {"quick": args.quick}
        if name != "compare":
            kwargs["n_jobs"] = args.jobs
        report = reproduce.CASES[name](**kwargs)
        print(report.render(), flush=True)
        if not args.no_figures:
            for target in _write_figures(report.figures(), out,
                                         prefix=f"{name.replace('.', '_')}_", dpi=110):
                print(f"  figure: {target}")
        print()
    print(f"total {time.perf_counter() - t0:.1f} s")


# --- the parser: one declarative entry per command -------------------------------------------
@dataclass(frozen=True)
class Arg:
    """One argument: its names (flags or a positional name) and its add_argument options."""

    names: tuple[str, ...]
    options: dict = field(default_factory=dict)

    def updated(self, **options) -> Arg:
        """This argument with more (or other) add_argument options, e.g. a command's help."""
        return Arg(self.names, {**self.options, **options})


def arg(*names: str, **options) -> Arg:
    """An :class:`Arg`: ``arg("-o", "--output", default="x", help="...")``."""
    return Arg(names, options)


@dataclass(frozen=True)
class OneOf:
    """Mutually exclusive arguments (exactly one if ``required``)."""

    args: tuple[Arg, ...]
    required: bool = False


@dataclass(frozen=True)
class Command:
    """A subcommand: name, handler, one-line help, description and arguments.

    ``raw`` keeps the description's line breaks (its example line) in ``--help``.
    """

    name: str
    run: Callable[[argparse.Namespace], int]
    help: str
    description: str
    args: tuple[Arg | OneOf, ...]
    raw: bool = True


# Arguments several commands share, declared once; a command adds its own default and help.
_SCENARIO = arg("scenario", metavar="SCENARIO.toml")
_RECORDS = arg("records", nargs="+", metavar="RECORD")
_OUTPUT = arg("-o", "--output")
_BRIDGE = arg("--bridge", metavar="MODEL.toml")
_REFERENCE = arg("--reference", metavar="REF.csv")
_FORCE = arg("--force", action="store_true",
             help="overwrite existing outputs (an input is never overwritten)")
_PARALLEL = OneOf((arg("--jobs", type=int, default=1,
                       help="worker processes on this machine (-1: all cores); default 1"),
                   arg("--scheduler", metavar="ADDRESS",
                       help="address of a dask.distributed scheduler, e.g. "
                       "tcp://host:8786")))
_RESUME = arg("--resume", action="store_true",
              help="go on with the batch in OUT (its manifest.json): records done and "
              "unchanged are kept, failed ones are tried again, rows of records not given "
              "again are kept")

COMMANDS: tuple[Command, ...] = (
    Command(
        "simulate", _simulate,
        "simulate a scenario's vehicle crossing and write the strain record",
        "Simulate the scenario's vehicle crossing its bridge (vehicle-bridge interaction over "
        "the road profile) and write what the sensors read.\n\n"
        "  bwim simulate examples/paper_slab.toml -o crossing.h5",
        (_SCENARIO.updated(help="the scenario file"),
         _OUTPUT.updated(default="record.h5", metavar="RECORD",
             help="output record: .h5 (with positions, passage and true forces) or .csv "
             "(time and readings only); default record.h5"),
         _BRIDGE.updated(
             help="use this bridge model (e.g. a calibrated one) instead of the scenario's "
             "[bridge]"),
         _FORCE)),
    Command(
        "calibrate", _calibrate,
        "calibrate the bridge model from crossings of a truck of known weight",
        "Calibrate the stiffness (E_x, E_y, …) and mass (mu) of the scenario's bridge from "
        "strain records of the scenario's vehicle, the calibration truck of known static axle "
        "loads.  The scenario's [bridge] is the starting model and its [calibrate] section "
        "gives the defaults; the records must be crossings at the scenario's [run] speed, "
        "lane and approach, over its [road].\n\n"
        "  bwim calibrate examples/paper_slab.toml crossing.h5 -o calibrated.toml",
        (_SCENARIO,
         _RECORDS.updated(
             help="records of the calibration truck (.h5 or .csv; folders expanded)"),
         _OUTPUT.updated(default="calibrated.toml", metavar="MODEL.toml",
             help="the calibrated bridge model (default calibrated.toml)"),
         arg("--method", choices=[m.value for m in Method],
             help="optimiser: ce = Cross-Entropy (the paper's), lm = Levenberg-Marquardt, "
             "cma = CMA-ES (default: the scenario's, else ce)"),
         arg("--jobs", type=int, help="worker processes for the populations"),
         arg("--seed", type=int, help="random seed of the optimiser"),
         arg("--mesh-correction", metavar="N|auto",
             help="correct the model's discretisation error by a model bisected N times "
             "(1-3), or as often as its sensors need (auto); default: the scenario's, "
             "else none"),
         _FORCE)),
    Command(
        "identify", _identify,
        "identify the moving axle forces and weights of vehicles (MFI)",
        "Moving force identification: the time history of each axle's force, its static "
        "weight and the gross vehicle weight, from each record and the bridge model (ideally "
        "a calibrated one).  Many records run in parallel on this machine (--jobs) or on a "
        "dask.distributed cluster (--scheduler).  Writes a CSV summary, one row per vehicle, "
        "and <record>_forces.h5 per record, each as its record finishes; a record that "
        "fails gets a summary row with its reason and the others go on; --resume goes on "
        "with an interrupted batch.  Exit code 0: all records done, 1: some failed, 2: bad "
        "input.\n\n"
        "  bwim identify examples/paper_slab.toml records/ --bridge calibrated.toml -o out/",
        (_SCENARIO.updated(
             help="the scenario (sensor positions; passage of CSV records)"),
         _RECORDS.updated(
             help="records (.h5 or .csv) or folders of them"),
         _BRIDGE.updated(
             help="bridge model (default: the scenario's [bridge])"),
         _OUTPUT.updated(default="bwim-out/identify", metavar="OUT",
             help="a results folder, or summary.csv (results beside it); default "
             "bwim-out/identify"),
         _PARALLEL,
         _RESUME,
         _FORCE)),
    Command(
        "weigh", _weigh,
        "static weights by Moses' algorithm from influence lines",
        "Static axle weights and GVW by Moses' algorithm, one summary.csv row per record "
        "(record, n_axles, speed_m_s, axle_spacings_m, axle_weights_kN, gvw_kN, flags, ...); "
        "a record that cannot be weighed gets a row with its reason, and the exit code is 1 "
        "if a record failed.  No weight is written without its plausibility checks.\n"
        "With a scenario that has [logger] (a real installation's logger files): each "
        "vehicle is detected (axle detectors, or the strain alone), every gauge's influence "
        "line is calibrated from the calibration truck's runs (speed, lateral position and "
        "drift of each run found from the data), and traffic is weighed with the gauges "
        "combined.  Otherwise the records carry their passages and one line is calibrated "
        "from crossings of the scenario's vehicle or read from a file.\n\n"
        "  bwim weigh site.toml events/ --calibration-records calibration/ -o out/\n"
        "  bwim weigh examples/paper_slab.toml truck.h5 --calibration-records crossing.h5",
        (_SCENARIO,
         _RECORDS.updated(
             help="records of the vehicles to weigh: logger files of any extension with a "
             "[logger] scenario, else .h5 or .csv; folders expanded"),
         OneOf((arg("--calibration-records", nargs="+", metavar="REC",
                    help="crossings of the scenario's vehicle to calibrate the influence "
                    "line from"),
                arg("--influence", metavar="IL.h5", help="a saved influence line")),
               required=True),
         _OUTPUT.updated(default="bwim-out/weigh", metavar="FOLDER",
             help="results folder (default bwim-out/weigh)"),
         _PARALLEL,
         _RESUME,
         _BRIDGE.updated(
             help="logger files only: weigh each detected vehicle by moving force "
             "identification with this (calibrated) bridge model instead of Moses; the "
             "gauges need x and y, and the first detector's position its x on the bridge"),
         _FORCE)),
    Command(
        "accuracy", _accuracy,
        "COST 323 accuracy classes of weights against statically weighed references",
        "The COST 323 European WIM specification's accuracy class per criterion (gross "
        "weight, group of axles, single axle, axle of a group) and overall, from a weigh "
        "summary and a reference of the same vehicles' static weights (CSV with the columns "
        "record, n_axles, axle_spacings_m, axle_weights_kN, gvw_kN; lists ';'-separated).\n\n"
        "  bwim accuracy out/summary.csv --reference static_weights.csv",
        (arg("summary", metavar="SUMMARY.csv", help="a summary written by bwim weigh"),
         _REFERENCE.updated(required=True,
             help="static weights of the same vehicles (by record name)"),
         arg("--repeatability", choices=["r1", "r2", "RR1", "RR2"], default="RR2",
             help="test conditions: r1/r2 repeatability (one or a few vehicles passing many "
             "times), RR1/RR2 reproducibility (a few vehicles / a sample of traffic); "
             "default RR2"),
         arg("--environment", choices=["I", "II", "III"], default="I",
             help="environmental conditions: I repeatable (a day or so), II limited "
             "reproducibility, III full (seasons); default I"),
         arg("--strict", action="store_true",
             help="a reference record absent from the summary is an error"),
         _OUTPUT.updated(metavar="TABLE.csv", help="also write the table as CSV"),
         _FORCE)),
    Command(
        "report", _report,
        "a single-file HTML report of result files",
        "A self-contained HTML page (figures embedded) of result files: force "
        "identifications, static weights, influence lines, records (.h5), bridge models "
        "(.toml) and summaries (.csv); folders are expanded.\n\n"
        "  bwim report out/ -o report.html",
        (arg("results", nargs="+", metavar="RESULTS"),
         _OUTPUT.updated(default="report.html", metavar="REPORT.html",
             help="default report.html"),
         arg("--title", default="bwim report", help="the page title"),
         _REFERENCE.updated(
             help="static weights of the weighed vehicles: adds the COST 323 accuracy "
             "classes of each weigh summary.csv among the results"),
         _FORCE)),
    Command(
        "demo", _demo,
        "the whole chain on the paper's slab bridge, in under a minute",
        "On the paper's 12 m × 8 m slab: simulate a calibration crossing, calibrate E_x, E_y "
        "and mu from a wrong start by Cross-Entropy, identify a second vehicle's axle forces "
        "with the calibrated model and weigh it by Moses; print the results against the truth "
        "and write figures and report.html to --out.",
        (arg("--modes", type=int, default=6, help="natural frequencies to print (default 6)"),
         arg("--out", default="bwim-out", help="output folder (default bwim-out)"),
         arg("--seed", type=int, default=0, help="seed of the calibration"),
         arg("--jobs", type=int, default=1, help="worker processes for calibration"),
         arg("--quick", action="store_true",
             help="a smaller, faster calibration (for tests)"))),
    Command(
        "reproduce", _reproduce,
        "the paper's experiments with its numbers side by side",
        "Reproduce Dowling, OBrien & González (2012) §5: 5.1 identical elements, 5.2 noise, "
        "5.3 sixteen zones, 5.4 beam-and-slab bridge, and a comparison of optimisers "
        "('compare').  Full runs take minutes (5.3 the longest); --quick runs small versions.",
        (arg("case", choices=["5.1", "5.2", "5.3", "5.4", "compare", "all"]),
         arg("--quick", action="store_true", help="small, fast versions"),
         arg("--out", default="bwim-out/reproduce", help="folder for the figures"),
         arg("--jobs", type=int, default=1, help="worker processes for populations"),
         arg("--no-figures", action="store_true", help="tables only")),
        raw=False),
)


def _add(parser, item: Arg | OneOf) -> None:
    """Add ``item`` to ``parser`` (an ArgumentParser or a mutually exclusive group)."""
    if isinstance(item, OneOf):
        group = parser.add_mutually_exclusive_group(required=item.required)
        for a in item.args:
            _add(group, a)
    else:
        parser.add_argument(*item.names, **item.options)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="bwim",
        description="Calibrated, dynamic Bridge Weigh-in-Motion: simulate crossings, "
        "calibrate the bridge's FE model from a truck of known weight, identify the moving "
        "axle forces of other vehicles, weigh them statically (Moses), report.",
        epilog="Scenario files (TOML) describe the bridge, the sensors, the vehicle, the "
        "road and the run; see examples/paper_slab.toml.  Units are SI.",
    )
    p.add_argument("--memory-limit", metavar="SIZE",
                   help="most memory a command may use, e.g. 4G, 800M or 0.25 (a fraction "
                   "of the machine's); default: the BWIM_MEMORY_LIMIT environment variable, "
                   "else half the machine's memory")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for c in COMMANDS:
        fmt = {"formatter_class": argparse.RawDescriptionHelpFormatter} if c.raw else {}
        s = sub.add_parser(c.name, help=c.help, description=c.description, **fmt)
        for item in c.args:
            _add(s, item)
        s.set_defaults(run=c.run)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``bwim`` command; returns the exit code."""
    from bwim.io.outputs import signals_as_interrupt
    from bwim.limits import ENV_VAR, parse_size

    for stream in (sys.stdout, sys.stderr):  # file names that are not UTF-8 print too
        with contextlib.suppress(AttributeError, ValueError, OSError):
            stream.reconfigure(errors="backslashreplace")
    parser = _parser()
    args = parser.parse_args(argv)
    saved = os.environ.get(ENV_VAR)
    try:
        if args.memory_limit is not None:
            parse_size(args.memory_limit)  # a one-line error if it is not a size
            os.environ[ENV_VAR] = args.memory_limit
        with signals_as_interrupt():
            return int(args.run(args))
    except BwimError as exc:
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"bwim: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bwim: interrupted (the records finished so far are kept; rerun to go on)",
              file=sys.stderr)
        return 130
    finally:
        if saved is None:
            os.environ.pop(ENV_VAR, None)
        else:
            os.environ[ENV_VAR] = saved


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
