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

Safety of outputs (:mod:`bwim.io.batch`): an output that is one of the inputs is refused;
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


def _out_file(path: str | Path, suffixes: Sequence[str] | None = None, *,
              inputs: Sequence[str | Path] = (), force: bool = True) -> Path:
    """An output file that can be written (checked before any work): not one of the
    ``inputs``, and not an existing file unless ``force``."""
    from bwim.io import check_writable
    from bwim.io.batch import refuse_existing, refuse_input_overwrite

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
    """The output folder's lock for this run (:class:`bwim.io.batch.OutputLock`)."""
    from bwim.io.batch import OutputLock

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


# --- identify --------------------------------------------------------------------------------
def _reason(exc: BaseException) -> str:
    """A failed record's reason, on one line."""
    if isinstance(exc, BwimError):
        return " ".join(str(exc).split()) or type(exc).__name__
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def _identify_one(bridge, record, kwargs):
    """One record's identification (a top-level function: it runs in worker processes).

    Returns the result, or the reason (a string) why the record failed: one bad record
    must not end the batch.
    """
    from numpy.linalg import LinAlgError

    from bwim.mfi import identify_forces

    try:
        return identify_forces(bridge, record, **kwargs)
    except (BwimError, ValueError, ArithmeticError, LinAlgError) as exc:
        return _reason(exc)


def _identify_file(bridge, scenario, path: Path, target: Path, kwargs) -> tuple[list, str | None]:
    """Read one record, identify its forces, write ``target``: ``(summary rows, None)``,
    or ``([], reason)`` if the record failed.  A top-level function, run by this process
    or by a worker: only the rows travel back (the record and the result stay where they
    are read and written)."""
    from bwim.io import write_identification
    from bwim.scenario import load_record

    try:
        record = load_record(path, scenario)
    except BwimError as exc:
        return [], _reason(exc)
    res = _identify_one(bridge, record, kwargs)
    if isinstance(res, str):
        return [], res
    write_identification(res, target)
    return _identify_rows(path, res), None


def _identify_pickled(blob: bytes, scenario, path: Path, target: Path, kwargs):
    """:func:`_identify_file` with the bridge pickled once by the parent (the same bytes
    for every task: no pickling per task, and the parent's warm caches travel with it)."""
    import pickle

    return _identify_file(pickle.loads(blob), scenario, path, target, kwargs)


def _jobs(jobs: int) -> int:
    return (os.cpu_count() or 1) if jobs == -1 else jobs


def _local_iter(bridge, scenario, paths, targets, kwargs, *, jobs: int):
    """``(index, (rows, reason))`` as each record finishes, on ``jobs`` processes: this
    one and ``jobs - 1`` loky workers.  Each worker is fed by a thread the moment it is
    free (no queue to drain at the end); this process takes the next record whenever it
    has finished one.  The bridge is pickled once, and again (with its warm caches:
    modes, matrices) after this process's first record, which runs while new workers
    start (their import)."""
    import pickle
    import queue
    import threading

    n = len(paths)
    workers = min(_jobs(jobs), n) - 1
    nxt = iter(range(n))
    lock = threading.Lock()

    def take() -> int | None:
        with lock:
            return next(nxt, None)

    def here(i: int):
        return _identify_file(bridge, scenario, paths[i], targets[i], kwargs)

    if workers <= 0:
        while (i := take()) is not None:
            yield i, here(i)
        return

    # a pool of this run's own (not joblib's process-wide reusable one, which the library's
    # parallel populations share): shut down when the run ends, killed on an interrupt.
    # Each of the processes (this one included) gets its share of the cores for BLAS:
    # two processes with a BLAS thread per core each would oversubscribe them (measured
    # on 2 cores: 2.5× the CPU per record).
    from joblib.externals.loky import ProcessPoolExecutor
    from threadpoolctl import threadpool_limits

    threads = max(1, (os.cpu_count() or 1) // (workers + 1))
    executor = ProcessPoolExecutor(max_workers=workers, env={
        name: str(threads) for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                        "MKL_NUM_THREADS")})
    limits = threadpool_limits(limits=threads)
    stop = threading.Event()
    finished: queue.Queue = queue.Queue()

    def feed() -> None:
        try:
            while not stop.is_set() and (i := take()) is not None:
                fut = executor.submit(_identify_pickled, blob[0], scenario, paths[i],
                                      targets[i], kwargs)
                finished.put((i, fut.result()))
        except BaseException as exc:  # handed to the main thread
            finished.put((None, exc))
        finally:
            finished.put((None, None))

    try:
        blob = [pickle.dumps(bridge, protocol=pickle.HIGHEST_PROTOCOL)]
        first = take()
        threads = [threading.Thread(target=feed, daemon=True) for _ in range(workers)]
        for t in threads:
            t.start()
        alive = workers
        yield first, here(first)
        blob[0] = pickle.dumps(bridge, protocol=pickle.HIGHEST_PROTOCOL)  # warm caches

        def ready(block: bool):
            nonlocal alive
            while alive:
                try:
                    i, value = finished.get(block=block)
                except queue.Empty:
                    return
                if i is not None:
                    yield i, value
                elif value is None:
                    alive -= 1
                else:
                    raise value

        while (i := take()) is not None:
            yield from ready(False)
            yield i, here(i)
        yield from ready(True)
    except BaseException:
        stop.set()
        with contextlib.suppress(Exception):
            executor.shutdown(wait=False, kill_workers=True)
        raise
    finally:
        stop.set()
        limits.restore_original_limits()
        with contextlib.suppress(Exception):
            executor.shutdown(wait=False)


def _dask_iter(bridge, scenario, paths, kwargs, *, scheduler: str):
    """``(index, result or reason)`` as each record finishes on a dask scheduler.  The
    records are read here and sent (the workers need not see this file system), at most
    two per worker thread ahead: a day of records is never all in memory."""
    from distributed import Client, as_completed

    from bwim.scenario import load_record

    try:
        client = Client(scheduler, timeout=10)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"cannot reach the dask scheduler {scheduler}: {exc}") from None
    try:
        [b] = client.scatter([bridge], broadcast=True)
        ahead = 2 * max(1, sum(client.nthreads().values())) + 2
        running = as_completed()
        index = {}
        for i, path in enumerate(paths):
            try:
                record = load_record(path, scenario)
            except BwimError as exc:
                yield i, _reason(exc)
                continue
            fut = client.submit(_identify_one, b, record, kwargs, pure=False)
            index[fut.key] = i
            running.add(fut)
            while running.count() >= ahead:
                fut = next(running)
                yield index.pop(fut.key), fut.result()
        for fut in running:
            yield index.pop(fut.key), fut.result()
    finally:
        client.close()


def _check_jobs(jobs: int | None) -> None:
    if jobs is not None and jobs < 1 and jobs != -1:
        raise InputError(f"--jobs must be a positive number or -1 (all cores), got {jobs}")


def _name(path: Path) -> str:
    """A file name as text that can be printed and written (a name that is not valid
    UTF-8 shows its odd bytes as U+FFFD)."""
    return os.fsencode(path.name).decode("utf-8", "replace")


def _identify_rows(path: Path, ident) -> list[list]:
    """One row per vehicle; a vehicle whose weights fail the plausibility checks gets its
    flags and no weights."""
    rows, a0 = [], 0
    for v, (p, flags, quality) in enumerate(zip(ident.passages, ident.vehicle_flags,
                                                ident.vehicle_quality, strict=True)):
        w = ident.axle_weights[a0:a0 + p.n_axles]
        a0 += p.n_axles
        ok = quality != "reject"
        rows.append([_name(path), v + 1, p.n_axles, format_kn_each(w) if ok else [],
                     format_kn(ident.gvw[v], 2) if ok else "", f"{ident.lam:.4g}",
                     ";".join(flags)])
    return rows


def _written(res, path: Path, target: Path) -> tuple[list, str | None]:
    """A result sent back by a dask worker, written here: ``(rows, reason)``."""
    from bwim.io import write_identification

    if isinstance(res, str):
        return [], res
    write_identification(res, target)
    return _identify_rows(path, res), None


class _Saver:
    """Calls ``save`` (the manifest and the summary, each rewritten whole) at most every
    :data:`SAVE_EVERY` seconds, or 20 times the last save's duration: a batch of many
    thousand records does not spend its time rewriting them (an interrupted run saves
    in ``finally``; a killed one redoes at most the last few seconds' records)."""

    SAVE_EVERY = 1.0

    def __init__(self, save: Callable[[], object]) -> None:
        self._save = save
        self._last = time.perf_counter()
        self._cost = 0.0

    def now(self) -> None:
        t = time.perf_counter()
        self._save()
        self._last = time.perf_counter()
        self._cost = self._last - t

    def maybe(self) -> None:
        if time.perf_counter() - self._last >= max(self.SAVE_EVERY, 20 * self._cost):
            self.now()


def _identify(args: argparse.Namespace) -> int:
    from bwim.io.batch import (
        EXIT_FAILED,
        EXIT_OK,
        Manifest,
        OutputLock,
        refuse_existing,
        refuse_input_overwrite,
    )
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
    stems = _unique_stems(paths)
    targets = [folder / f"{stem}_forces.h5" for stem in stems]
    refuse_input_overwrite([summary, *targets], inputs)
    with OutputLock(folder):
        manifest = Manifest(folder, fresh=args.force)
        if not manifest.entries or not manifest.belongs_to(paths):
            # a first run, or another batch's folder: an existing summary is not ours
            refuse_existing(summary, force=args.force)
        scenario = load_scenario(args.scenario)
        bridge = _bridge(args, scenario)
        kwargs = scenario.identify.kwargs() if scenario.identify is not None else {}
        t0 = time.perf_counter()
        outcome: dict[int, tuple[list, str | None]] = {}
        todo = []
        for i, path in enumerate(paths):
            entry = manifest.done(path)
            if entry is not None:
                outcome[i] = (entry["rows"], None)
            else:
                todo.append(i)
        skipped = len(paths) - len(todo)
        if args.scheduler:
            runs = ((k, _written(res, paths[todo[k]], targets[todo[k]]))
                    for k, res in _dask_iter(bridge, scenario, [paths[i] for i in todo],
                                             kwargs, scheduler=args.scheduler))
        else:
            runs = _local_iter(bridge, scenario, [paths[i] for i in todo],
                               [targets[i] for i in todo], kwargs, jobs=args.jobs)
        saved = _Saver(lambda: (manifest.save(),
                                _write_identify_summary(summary, paths, outcome)))
        try:
            with contextlib.closing(runs), \
                    _bar(len(todo) if len(todo) > 1 else None, "identifying forces") as bar:
                for k, (rows, reason) in runs:
                    i = todo[k]
                    outcome[i] = (rows, reason)
                    manifest.record(paths[i], result=None if reason else targets[i].name,
                                    rows=rows, error=reason, save=False)
                    saved.maybe()
                    bar.update()
        finally:
            saved.now()
    failed = [(_name(paths[i]), outcome[i][1]) for i in sorted(outcome) if outcome[i][1]]
    shown = [(r[0], r[1], ", ".join(r[3]) or (r[6] if len(r) > 6 else ""), r[4], r[5])
             for i in sorted(outcome) for r in outcome[i][0]]
    print(Table(f"Moving force identification, {len(paths)} record(s)"
                f"{f' ({skipped} done before)' if skipped else ''}, "
                f"{time.perf_counter() - t0:.1f} s:",
                ("record", "vehicle", "axle weights (kN)", "GVW (kN)", "λ"), shown).render())
    for name, reason in failed:
        print(f"bwim: {name} failed: {reason}", file=sys.stderr)
    print(f"summary: {summary}\nforces: {folder}/<record>_forces.h5")
    if failed:
        print(f"bwim: {len(failed)} of {len(paths)} record(s) failed (see the summary's "
              "error column)", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def _write_identify_summary(summary: Path, paths: Sequence[Path], outcome: dict) -> None:
    """The summary of the records done so far: one row per vehicle, one per failed record
    (with its reason in the ``error`` column)."""
    n_max = max((r[2] for rows, _ in outcome.values() for r in rows), default=0)
    header = ["record", "vehicle", "axles", *(f"axle_{i + 1}_kN" for i in range(n_max)),
              "gvw_kN", "lambda", "flags", "error"]
    out = []
    for i in sorted(outcome):
        rows, error = outcome[i]
        if error is not None:
            out.append([_name(paths[i]), "", "", *[""] * n_max, "", "", "", error])
        for name, v, n_axles, cells, gvw, lam, *flags in rows:
            out.append([name, v, n_axles, *cells, *[""] * (n_max - len(cells)), gvw, lam,
                        flags[0] if flags else "", ""])
    _write_csv(summary, header, out)


# --- weigh -----------------------------------------------------------------------------------
#: summary.csv of ``bwim weigh``: the contract's columns first, then bwim's extras.
WEIGH_COLUMNS = ("record", "n_axles", "speed_m_s", "axle_spacings_m", "axle_weights_kN",
                 "gvw_kN", "flags", "group_weights_kN", "lateral", "confidence", "residual",
                 "quality", "method", "reason")


def _joined(values, fmt: str) -> str:
    return ";".join(format(float(v), fmt) for v in values)


def _weigh_row(name: str, *, passage=None, weights=None, gvw=None, groups=None, flags=(),
               lateral=None, confidence=None, residual=None, quality="", method="",
               reason="") -> list:
    """One summary row; weights are written only when given (a weighed vehicle)."""
    import numpy as np

    def num(v, fmt):
        return "" if v is None or not np.isfinite(v) else format(float(v), fmt)

    return [name,
            "" if passage is None else passage.n_axles,
            "" if passage is None else f"{passage.speed:.3f}",
            "" if passage is None else _joined(passage.axle_spacings, ".3f"),
            "" if weights is None else _joined(np.asarray(weights) / 1e3, ".2f"),
            "" if gvw is None else f"{gvw / 1e3:.2f}",
            ";".join(flags),
            "" if groups is None else _joined(np.asarray(groups) / 1e3, ".2f"),
            num(lateral, ".3f"), num(confidence, ".3f"), num(residual, ".4g"), quality,
            method, " ".join(str(reason).split())]


def _unique_names(paths: Sequence[Path]) -> None:
    """The summary names each record by its file name: two files of one name (from two
    folders) would be confused, in the summary, by ``--resume`` and by the accuracy."""
    seen: dict[str, Path] = {}
    for p in paths:
        if p.name in seen:
            raise InputError(f"two records are named {p.name!r} ({seen[p.name]} and {p}); "
                             "the summary names records by file name: rename one")
        seen[p.name] = p


def _done_rows(summary: Path, resume: bool) -> dict[str, list[str]]:
    """Rows of a previous run to keep with ``--resume`` (by record name)."""
    if not resume or not summary.exists():
        return {}
    try:
        with summary.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{summary}: cannot read it to resume ({exc})") from None
    if not rows or tuple(rows[0]) != WEIGH_COLUMNS:
        raise InputError(f"{summary}: not a bwim weigh summary; cannot resume from it")
    return {r[0]: r for r in rows[1:] if r and r[-1] == ""}


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


def _weigh_site(args: argparse.Namespace, scenario, folder: Path) -> int:
    """``bwim weigh`` on a real installation's logger files (scenario with [logger])."""
    from bwim.io.batch import refuse_existing, refuse_input_overwrite
    from bwim.scenario import load_record
    from bwim.site import weigh_event

    if not args.calibration_records:
        raise InputError("weighing logger files needs --calibration-records (runs of the "
                         "calibration truck)")
    paths = _record_paths(args.records, any_suffix=True)
    _unique_names(paths)
    cal_paths = _record_paths(args.calibration_records, any_suffix=True)
    summary = folder / "summary.csv"
    refuse_input_overwrite([summary, folder / "calibration_runs.csv",
                            folder / "influence_lines.h5"],
                           [args.scenario, *paths, *cal_paths])
    if not args.resume:
        refuse_existing(summary, force=args.force)
    done = _done_rows(summary, args.resume)
    bridge = options = None
    if args.bridge:
        from bwim.scenario import load_bridge

        bridge = load_bridge(args.bridge)
        options = scenario.identify.kwargs() if scenario.identify is not None else {}
    site = _calibrate_site(cal_paths, scenario, folder)
    rows: list[list] = []
    n_failed = n_weighed = 0
    t0 = time.perf_counter()
    try:
        with _bar(len(paths) if len(paths) > 1 else None, "weighing") as bar:
            for p in paths:
                bar.update()
                if p.name in done:
                    rows.append(done[p.name])
                    n_weighed += 1
                    continue
                try:
                    rec = load_record(p, scenario)
                except InputError as exc:
                    rows.append(_weigh_row(p.name, reason=str(exc)))
                    n_failed += 1
                    continue
                ev = weigh_event(rec, site, bridge=bridge, identify_options=options)
                det = ev.detection
                v = det.vehicles[0] if det is not None and len(det.vehicles) == 1 else None
                w, ident = ev.weighing, ev.identification
                rows.append(_weigh_row(
                    p.name, passage=None if v is None else v.passage,
                    weights=ev.axle_weights, gvw=ev.gvw,
                    groups=w.group_weights if ev.weighed and w is not None else None,
                    flags=ev.flags, lateral=None if v is None else v.lateral,
                    confidence=None if v is None else v.confidence,
                    residual=(w.residual if w is not None else
                              ident.residual if ident is not None else None),
                    quality=(w.quality if w is not None else
                             ident.vehicle_quality[0] if ident is not None else ""),
                    method=ev.method if v is not None else "", reason=ev.reason))
                n_weighed += ev.weighed
    finally:  # an interrupted run keeps what it weighed (rerun with --resume)
        _write_csv(summary, WEIGH_COLUMNS, rows)
    elapsed = time.perf_counter() - t0
    n_flagged = len(paths) - n_weighed - n_failed
    print(f"{len(paths)} event(s) in {elapsed:.1f} s: {n_weighed} weighed, {n_flagged} "
          f"not weighed (flagged), {n_failed} failed")
    shown = [(r[0], r[1], r[4].replace(";", ", "), r[5], r[6] or r[13]) for r in rows[:20]]
    print(Table("Static weights (moving force identification with the FE model):" if bridge
                else "Static weights (multi-run influence lines, gauges combined):",
                ("record", "axles", "axle weights (kN)", "GVW (kN)", "flags / reason"),
                shown).render())
    if len(rows) > 20:
        print(f"... {len(rows) - 20} more in the summary")
    print(f"summary: {summary}")
    return 1 if n_failed else 0


def _weigh(args: argparse.Namespace) -> int:
    from bwim.scenario import load_scenario

    folder = _out_folder(args.output)
    with _locked(folder):
        scenario = load_scenario(args.scenario)
        if scenario.logger is not None:
            return _weigh_site(args, scenario, folder)
        return _weigh_moses(args, scenario, folder)


def _weigh_moses(args: argparse.Namespace, scenario, folder: Path) -> int:
    """``bwim weigh`` on records with their passages (simulated, or a [run] scenario)."""
    from bwim.io import read_influence_line, write_influence_line, write_static_weights
    from bwim.io.batch import refuse_existing, refuse_input_overwrite
    from bwim.scenario import build_vehicle, load_record
    from bwim.wim import calibrate_influence_line, weigh_static

    if args.bridge:
        raise InputError("--bridge weighs logger files by MFI (a scenario with [logger]); "
                         "for records with their passages use bwim identify")
    paths = _record_paths(args.records)
    _unique_names(paths)
    cal_paths = _record_paths(args.calibration_records) if args.calibration_records else []
    summary = folder / "summary.csv"
    stems = _unique_stems(paths)
    refuse_input_overwrite(
        [summary, folder / "influence_line.h5",
         *(folder / f"{stem}_static.h5" for stem in stems)],
        [args.scenario, *paths, *cal_paths, *([args.influence] if args.influence else [])])
    if not args.resume:
        refuse_existing(summary, force=args.force)
    if args.influence:
        il = read_influence_line(args.influence)
        print(f"influence line: {args.influence}")
    else:
        cal_records = _load_records(cal_paths, scenario)
        il = calibrate_influence_line(cal_records, build_vehicle(scenario))
        target = folder / "influence_line.h5"
        write_influence_line(il, target)
        print(f"influence line calibrated from {len(cal_records)} crossing(s) "
              f"(residual {il.residual:.3g}): {target}")
    done = _done_rows(summary, args.resume)
    rows, shown = [], []
    n_failed = 0
    try:
        with _bar(len(paths) if len(paths) > 1 else None, "weighing") as bar:
            for path, stem in zip(paths, stems, strict=True):
                bar.update()
                if path.name in done:
                    rows.append(done[path.name])
                    continue
                try:
                    rec = load_record(path, scenario)
                    w = weigh_static(rec, il)
                except InputError as exc:
                    rows.append(_weigh_row(path.name, reason=str(exc)))
                    shown.append((path.name, "", "", f"failed: {exc}"))
                    n_failed += 1
                    continue
                flags = w.flags
                ok = w.quality != "reject"
                if ok:
                    write_static_weights(w, folder / f"{stem}_static.h5")
                rows.append(_weigh_row(
                    path.name, passage=w.passage, weights=w.axle_weights if ok else None,
                    gvw=w.gvw if ok else None, groups=w.group_weights if ok else None,
                    flags=flags, residual=w.residual, quality=w.quality, method="moses",
                    reason="" if ok else f"implausible weighing ({';'.join(flags)})"))
                shown.append((path.name, ", ".join(format_kn_each(w.axle_weights)) if ok
                              else "-", format_kn(w.gvw) if ok else "-",
                              ";".join(flags) or f"{w.residual:.3g}"))
    finally:  # an interrupted run keeps what it weighed (rerun with --resume)
        _write_csv(summary, WEIGH_COLUMNS, rows)
    print(Table("Static weights (Moses):",
                ("record", "axle weights (kN)", "GVW (kN)", "flags / residual"),
                shown).render())
    print(f"summary: {summary}\nweights: {folder}/<record>_static.h5")
    return 1 if n_failed else 0


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

        reference = read_reference(args.reference)
        summaries = [p for p in report.result_paths(args.results)
                     if p.suffix.lower() == ".csv" and _is_weigh_summary(p)]
        if not summaries:
            raise InputError("--reference needs a weigh summary.csv among the results")
        for p in summaries:
            sections.append(report.section(assess(read_summary(p), reference), p.name))
    report.write_report(out, sections, title=args.title)
    print(f"report of {len(items)} result(s): {out}")
    return 0


def _is_weigh_summary(path: Path) -> bool:
    with path.open(newline="", encoding="utf-8", errors="replace") as f:
        header = next(csv.reader(f), [])
    return tuple(header[:len(WEIGH_COLUMNS)]) == WEIGH_COLUMNS


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
        "fails gets a summary row with its reason and the others go on.  A rerun into "
        "the same OUT skips the records already done.  Exit code 0: all records done, "
        "1: some failed, 2: bad input.\n\n"
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
         OneOf((arg("--jobs", type=int, default=1,
                    help="worker processes on this machine (-1: all cores); default 1"),
                arg("--scheduler", metavar="ADDRESS",
                    help="address of a dask.distributed scheduler, e.g. tcp://host:8786"))),
         arg("--force", action="store_true",
             help="start afresh: redo every record and overwrite the outputs (default: "
             "records already done in OUT, per its manifest.json, are skipped)"))),
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
         arg("--resume", action="store_true",
             help="keep the records already weighed in the folder's summary.csv and weigh "
             "only the others"),
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
    from bwim.io.batch import signals_as_interrupt
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
