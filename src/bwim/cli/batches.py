"""The batch commands: identify (moving force identification) and weigh (a site's logger
files, or records with their passages): the library's batch engine (:mod:`bwim.batch`)
with outputs, progress and tables."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Sequence
from datetime import datetime, timedelta
from pathlib import Path

from bwim.cli.common import (
    Progress,
    bridge_of,
    check_jobs,
    display_name,
    load_records,
    locked,
    out_file,
    out_folder,
    record_paths,
    refuse_existing_outputs,
    refuse_other_provenance,
    unique_stems,
    write_csv,
)
from bwim.errors import InputError
from bwim.tables import Table, format_kn, format_kn_each

__all__ = ["identify_command", "weigh_command"]


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
    """The batch's reader of one record (picklable: it goes to worker processes): the
    scenario's sensors and logger format built once."""
    from bwim.scenario import record_reader

    return record_reader(scenario)


class _CutOrRead:
    """The batch's reader for ``weigh --continuous``: a long file whose cutting failed
    gives its reason (its row fails, the batch goes on), an event file is read."""

    def __init__(self, read, failed: dict[str, str]):
        self.read, self.failed = read, dict(failed)

    def __call__(self, path):
        why = self.failed.get(str(path))
        if why is not None:
            raise InputError(why)
        return self.read(path)


def _run_batch(folder, items, run, desc: str):
    """Run a batch into its folder with a progress display; its report."""
    from bwim.batch import run_into

    with Progress(len(items), desc) as progress:
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


def _fresh(args: argparse.Namespace, folder: Path) -> bool:
    """Whether the run starts afresh: not ``--resume``, or nothing to resume (no manifest:
    the folder's files are then not this batch's, and are refused like any others)."""
    from bwim.io.outputs import MANIFEST_NAME

    return not args.resume or not (folder / MANIFEST_NAME).exists()


def _done_before(report) -> str:
    return f" ({report.n_done_before} done before)" if report.n_done_before else ""


def identify_command(args: argparse.Namespace) -> int:
    from bwim.batch import BatchFolder, Item, executor_for, identify_records
    from bwim.io.outputs import refuse_input_overwrite
    from bwim.scenario import load_scenario

    check_jobs(args.jobs)
    out = Path(args.output)
    paths = record_paths(args.records)
    if out.suffix.lower() == ".csv":
        summary = out_file(out)
        folder = summary.parent
    else:
        folder = out_folder(out)
        summary = folder / "summary.csv"
    inputs = [args.scenario, *([args.bridge] if args.bridge else []), *paths]
    items = [Item(name=display_name(p), source=p, target=folder / f"{stem}_forces.h5")
             for p, stem in zip(paths, unique_stems(paths), strict=True)]
    refuse_input_overwrite([summary, *(it.target for it in items)], inputs)
    with locked(folder):
        if _fresh(args, folder):  # no result file of a record replaced without --force
            refuse_existing_outputs([it.target for it in items], force=args.force,
                                    resumable=True)
        scenario = load_scenario(args.scenario)
        bridge = bridge_of(args, scenario)
        batch = BatchFolder(folder, resume=args.resume, force=args.force, summary=summary,
                            meta=_meta("identify", scenario=args.scenario, bridge=args.bridge),
                            parquet=args.parquet)
        kwargs = scenario.identify.kwargs() if scenario.identify is not None else {}
        executor = executor_for(args.jobs, args.scheduler)
        report = _run_batch(batch, items, lambda todo: identify_records(
            todo, bridge, read=_read(scenario), options=kwargs, executor=executor,
            keep=False), "identifying forces")
    shown = [(r.record, r.vehicle, ", ".join(format_kn_each(r.axle_weights)) if r.weighed else
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


def _first_reason(unread: Sequence[tuple[str, str]]) -> str:
    """The first file's reason (its message names the file) and how many failed."""
    name, reason = unread[0]
    where = reason if name in reason else f"{name}: {reason}"
    return (f"{len(unread)} file(s) unreadable; the first: {where}" if len(unread) > 1
            else where)


def _run_time(rec) -> str:
    """A run's start in ISO 8601 (to the ms): its date and time when the record has a
    clock, the time of day when its time axis is one (as the summary's ``time``), else
    empty."""
    clock = rec.clock_at()
    if clock is not None:
        return clock.isoformat(timespec="milliseconds")
    if rec.time_of_day:
        return (datetime.min + timedelta(seconds=float(rec.time[0]))).time().isoformat(
            timespec="milliseconds")
    return ""


def _calibrate_site(paths: Sequence[Path], scenario, folder: Path):
    """Lines from the calibration truck's logger events, and a function that writes
    their outputs (the table of the runs, the lines) into ``folder`` and prints the
    table: called once the rest of the input is known good (nothing is written before)."""
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
        raise InputError(f"no calibration run could be read ({_first_reason(unread)})")
    try:
        site = calibrate_site(records, setup)
    except InputError as exc:
        if not unread:
            raise
        raise InputError(f"{exc}; also {_first_reason(unread)}") from None
    rows = []
    for p, rec, det, reason, fit in zip(used, records, site.detections, site.reasons,
                                        site.fits, strict=True):
        v = det.vehicles[0].passage if len(det.vehicles) == 1 else None
        rows.append((p.name, _run_time(rec),
                     "" if v is None else f"{v.speed:.2f}",
                     "" if v is None else f"{v.lane:.2f}",
                     "" if fit is None else f"{fit.scale:.4f}",
                     "" if fit is None else f"{fit.residual:.3g}",
                     reason or "used"))
    rows += [(name, "", "", "", "", "", f"unreadable: {msg}") for name, msg in unread]
    # the lateral position's unit: metres where the gauges' y are known, else their index
    units = {v.lateral_unit for det in site.detections for v in det.vehicles}
    lateral = "lateral (m)" if units == {"m"} else (
        "lateral (gauge index)" if units == {"gauge index"} else "lateral")
    header = ("run", "time", "speed (m/s)", lateral, "scale", "residual", "status")

    def write() -> None:
        write_csv(folder / "calibration_runs.csv", header, rows)
        print(Table(f"Calibration runs ({site.n_used} of {len(paths)} used):", header,
                    rows).render())
        write_influence_line(site.lines.line_at(), folder / "influence_lines.h5")

    return site, write


def _print_drift(site, fit) -> None:
    """One line on how the day's drift of the strain-to-load ratio was corrected."""
    method = site.setup.drift.method
    if fit is not None:
        days = ", ".join(f"{d}: {n}" for d, n in sorted(fit.counts.items()))
        print(f"drift: the traffic's own reference (class {fit.reference_class} steering "
              f"axle, nominal {fit.nominal / 1e3:.1f} kN from the {fit.nominal_source}; "
              f"reference vehicles per date {days})")
    elif site.temperature is not None and method in ("auto", "temperature"):
        t = site.temperature
        print(f"drift: temperature (factor {t.intercept:.3f} {t.slope:+.4f}/°C about "
              f"{t.reference:.1f} °C, the runs' residual {t.residual:.3f})")
    elif method in ("auto", "traffic", "time_of_day") and site.time_of_day is not None:
        print("drift: the calibration runs' factor over the time of day " + (
            "(vehicles on other dates are flagged outside_calibration_time)"
            if site.time_of_day.dates else "(some runs have no date: vehicles on other "
            "dates cannot be told apart and are not flagged)"))
        if method != "time_of_day":
            print("note: " + _traffic_unused(site.setup.drift))
    else:
        print(f"drift: {method}")
    for note in site.notes:
        print(f"note: {note}")


def _traffic_unused(drift) -> str:
    """Why the traffic's own reference could not correct the drift, and what it needs."""
    if drift.reference_load is not None:
        return ("the traffic's own reference was not used: no vehicle of the reference "
                "class in the batch")
    return ("the traffic's own reference was not used: it needs the steering axle's nominal "
            f"load, from at least {drift.min_reference} vehicles of the commonest "
            "articulated class in the calibration date's traffic weighed in the same batch, "
            "or given as [drift] reference_kN (docs/cli.md: with a thin traffic date, give "
            "it)")


def _print_unconfirmed(check) -> None:
    """One line per gauge left out of vehicles whose neighbours in time find it healthy."""
    for gauge, n in sorted(check.unconfirmed.items()):
        print(f"gauge {gauge}: disagreed in {n} vehicle(s) but agreed in most of those "
              "weighed around them: those vehicles refused (another vehicle loaded it; "
              "unconfirmed_gauge_fault)")


def _lane_label(lane: int | None, direction: str) -> str:
    """``"lane 1 +x"``: how the day-level lines name a lane."""
    return f"lane {lane if lane is not None else '?'} {direction or ''}".rstrip()


def _print_wander(check) -> None:
    """One line per lane whose lateral spread was measured, and how many it refused; one
    per lane with vehicles weighed but too few to measure it."""
    from bwim.site.wander import MIN_VEHICLES

    for w in check.lanes:
        unit = " m" if w.unit == "m" else " (gauge index)"
        n = sum(1 for r in check.rows if "lateral_outlier" in r.flags and r.lane == w.lane
                and r.direction == w.direction)
        print(_lane_label(w.lane, w.direction)
              + f": lateral position {w.median:.2f}{unit} ± {w.sigma:.2f} over {w.n} "
              f"vehicle(s); {n} refused beyond {check.limit:g} σ (a vehicle beside it no "
              "detector saw)")
    measured = {(w.lane, w.direction) for w in check.lanes}
    thin: dict = {}
    for r in check.rows:
        if r.weighed and r.lateral is not None and (r.lane, r.direction) not in measured:
            thin[(r.lane, r.direction)] = thin.get((r.lane, r.direction), 0) + 1
    for (lane, direction), n in thin.items():
        print(_lane_label(lane, direction)
              + f": {n} vehicle(s) weighed, too few for the day's lateral checks (they "
              f"need {MIN_VEHICLES}): a vehicle beside one that no detector saw is not "
              "refused; weigh the whole day together")


def _print_paths(check) -> None:
    """One line per lane whose axle groups' positions were measured, and how many it
    refused."""
    lanes = {}
    for sp in check.spreads:
        lanes.setdefault((sp.lane, sp.direction, sp.unit), []).append(sp)
    for (lane, direction, unit), spreads in lanes.items():
        u = "m" if unit == "m" else "gauge index"
        n = sum(1 for r in check.rows if "group_off_path" in r.flags and r.lane == lane
                and r.direction == direction)
        roles = ", ".join(f"{sp.role} {sp.median:+.2f} ± {sp.sigma:.2f}" for sp in spreads)
        print(_lane_label(lane, direction)
              + f": axle groups against their vehicle's others ({u}): {roles}; {n} refused "
              f"beyond {check.limit:g} σ (an axle of a vehicle beside it)")


def _print_speeds(check) -> None:
    """One line per lane whose counted vehicles lost some as traces (speed outliers)."""
    lanes: dict = {}
    for r in check.dropped:
        lanes.setdefault((r.lane, r.direction), []).append(r)
    for (lane, direction), rows in lanes.items():
        print(_lane_label(lane, direction)
              + f": {len(rows)} vehicle(s) left out, at speeds far from the lane's traffic "
              f"around them (beyond {check.limit:g} σ: traces of another vehicle)")


def _print_split(check) -> None:
    """One line when vehicles were found split across two records."""
    if check.pairs:
        print(f"{len(check.pairs)} vehicle(s) split across two records (a file closed "
              "between a truck's axles, or two files holding the same axles): "
              f"{len(check.refused)} weighed part(s) refused, split_across_records")


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
    from bwim.io.gauge_health import GAUGE_HEALTH_NAME

    if not args.calibration_records:
        raise InputError("weighing logger files needs --calibration-records (runs of the "
                         "calibration truck)")
    paths = record_paths(args.records, any_suffix=True)
    bridge = options = None
    if args.bridge:
        from bwim.scenario import load_model
        from bwim.site import SiteModel

        bridge = load_model(args.bridge)
        if isinstance(bridge, SiteModel) and not bridge.accepted:
            raise InputError(f"{args.bridge}: the model is not accepted ({bridge.reason}): "
                             "bwim does not weigh with it")
        try:  # a model weighs with the runs and gauges it was calibrated from
            refuse_other_provenance(bridge, record_paths(args.calibration_records,
                                                         any_suffix=True), scenario)
        except InputError as exc:
            raise InputError(f"{args.bridge}: {exc}") from None
        options = scenario.identify.kwargs() if scenario.identify is not None else {}
    # the calibration before any output: bad runs end with nothing written
    site, write_calibration = _calibrate_site(
        record_paths(args.calibration_records, any_suffix=True), scenario, folder)
    cut_open: dict[str, tuple[str, ...]] = {}  # events that may not hold vehicles whole
    cut_failed: dict[str, str] = {}  # long files whose cutting failed: why
    stale: list[Path] = []  # event files of an earlier cut that the long files no longer hold
    if args.continuous:
        items = _continuous_items(paths, scenario, folder / EVENTS, resume=args.resume,
                                  cut_open=cut_open, cut_failed=cut_failed, stale=stale)
    else:
        items = [Item(name=display_name(p), source=p) for p in paths]
    batch.check_names(items)
    # a long file cut whole now: its failed row of an earlier run goes (it is repaired)
    batch.forget([*stale, *(p for p in paths if args.continuous and str(p) not in cut_failed)])
    read = _CutOrRead(_read(scenario), cut_failed) if cut_failed else _read(scenario)
    write_calibration()
    days: list = []

    def finalize(rows):  # the lanes' spread and the traffic's drift need the whole day
        from bwim.site import finish_day

        day = finish_day(rows, site)
        days[:] = [day]
        return list(day.rows)

    def weigh(todo):
        # an event that may not hold its vehicles whole is refused as it is weighed, so
        # that the manifest keeps the refusal (a --resume without its long file keeps it)
        for o in weigh_events(todo, site, read=read, bridge=bridge,
                              identify_options=options, executor=executor, keep=False):
            flags = cut_open.get(o.name)
            yield o if not flags else dataclasses.replace(
                o, rows=tuple(_open_refused(r, flags) for r in o.rows))

    batch.finalize = finalize
    batch.gauge_table = folder / GAUGE_HEALTH_NAME
    batch.gauge_names = tuple(c.name for c in site.lines.channels)
    executor = executor_for(args.jobs, args.scheduler)
    report = _run_batch(batch, items, weigh, "weighing")
    print(f"{len(items)} event(s){_done_before(report)} in {report.elapsed:.1f} s: "
          f"{report.count('weighed')} vehicle(s) weighed, {report.count('refused')} not "
          f"weighed (flagged), {report.count('failed')} record(s) failed")
    _print_drift(site, days[0].drift if days else None)
    if days:
        _print_unconfirmed(days[0].faults)
        _print_wander(days[0].wander)
        _print_paths(days[0].paths)
        _print_speeds(days[0].speeds)
        _print_split(days[0].split)
    _print_weighed(report, "Static weights (moving force identification with the FE "
                   "model):" if bridge else "Static weights (multi-run influence lines, "
                   "gauges combined):")
    _print_gauges(batch)
    print(f"summary: {batch.summary}\ngauge health: {batch.gauge_table}")
    return _report_failures(report)


def _print_gauges(batch) -> None:
    """One line per gauge left out of any vehicle: how often and why."""
    from bwim.batch.gauges import tally_gauges

    for t in tally_gauges(batch.gauge_names, batch.vehicle_gauges()):
        if t.left_out:
            why = ", ".join(f"{k} {n}" for k, n in t.kinds.items() if n)
            print(f"gauge {t.gauge}: left out of {t.left_out} of {t.judged} vehicle(s) "
                  f"({why or 'kind unknown'})")


#: Subfolder of a ``weigh --continuous`` output with the events cut from the long files.
EVENTS = "events"


#: Stream flags of an event that may not hold its vehicles whole: the recording's start
#: or end may have cut it, or its trigger was closed at max_duration with the signal up.
_OPEN = ("open_at_start", "open_at_end", "max_duration")


def _open_refused(row, flags: tuple[str, ...] | None):
    """A weighed row of an event that may not hold its vehicle whole, refused: the
    recording's start or end may have cut it (a tractor without its trailer), or the
    trigger was closed at max_duration while the signal was still up (a queue on the
    span, or a step of the baseline: a vehicle may go on beyond the event)."""
    if not flags or not row.weighed:
        return row
    if "open_at_start" in flags or "open_at_end" in flags:
        return row.refused("the recording begins or ends within this event, so the vehicle "
                           "may go on beyond it (a tractor without its trailer): its "
                           "weights cannot be whole", *flags)
    return row.refused("the trigger was closed at its max_duration with the signal still "
                       "up (a queue on the span, or a step of the baseline), so a vehicle "
                       "may go on beyond this event: its weights cannot be whole", *flags)


def _same_event(path: Path, record) -> bool:
    """Whether the event file ``path`` holds ``record`` (times, readings, channels,
    clock): a resume keeps it (and its weighing) only then."""
    import numpy as np

    from bwim.errors import BwimError
    from bwim.io import read_record

    try:
        old = read_record(path)
    except (BwimError, OSError, ValueError):
        return False
    return (old.clock == record.clock and old.data.shape == record.data.shape
            and [x.name for x in old.sensors] == [x.name for x in record.sensors]
            and np.array_equal(old.time, record.time)
            and np.array_equal(old.data, record.data, equal_nan=True))


def _continuous_items(paths: Sequence[Path], scenario, events: Path, *, resume: bool,
                      cut_open: dict[str, tuple[str, ...]] | None = None,
                      cut_failed: dict[str, str] | None = None,
                      stale: list[Path] | None = None) -> list:
    """Each long logger file cut into events (:func:`bwim.stream.cut_file`, the
    scenario's ``[trigger]``), each event written to ``events/FILE#k.h5`` (k from 1) and
    named ``FILE#k``; with ``resume`` an event file that holds the same event is kept as
    it is (another is written over: the long file changed), and the event files of a long
    file cut whole beyond its events now are deleted and listed in ``stale`` (their rows
    are dropped).  ``cut_open`` gets the names of the events that may not hold their
    vehicles whole (the recording's start or end may have cut them, or the trigger closed
    at max_duration), with those flags.  A long file whose cutting fails (a bad line: a
    logger stopped mid-write) keeps the events cut before it and is itself an item named
    after the file, whose reason ``cut_failed`` gets (its row fails; the batch goes
    on)."""
    from bwim.batch import Item
    from bwim.batch.events import BATCH_ERRORS, reason_of
    from bwim.io import write_record
    from bwim.scenario import build_logger_format, build_sensors, build_trigger
    from bwim.stream import cut_file

    fmt, sensors = build_logger_format(scenario), build_sensors(scenario) or None
    trigger = build_trigger(scenario)
    events.mkdir(parents=True, exist_ok=True)
    items, index = [], []
    for p in paths:
        n = 0
        try:
            for n, ev in enumerate(cut_file(p, fmt, trigger, sensors=sensors, clip_run=None),
                                   start=1):
                name = f"{display_name(p)}#{n}"
                target = events / f"{name}.h5"
                index.append(_index_row(name, p, ev))
                if cut_open is not None and any(f in _OPEN for f in ev.flags):
                    cut_open[name] = tuple(f for f in ev.flags if f in _OPEN)
                if not (resume and target.exists() and _same_event(target, ev.record)):
                    write_record(ev.record, target)
                items.append(Item(name=name, source=target))
        except BATCH_ERRORS as exc:
            if cut_failed is None:
                raise
            why = f"cutting stopped after {n} event(s): {reason_of(exc)}"
            cut_failed[str(p)] = why
            items.append(Item(name=display_name(p), source=p))
            print(f"{display_name(p)}: {why}")
            continue
        prefix = f"{display_name(p)}#"
        for q in sorted(events.iterdir()):  # events of an earlier cut of this file, gone
            k = q.name[len(prefix):-len(".h5")] if q.name.startswith(prefix) \
                and q.name.endswith(".h5") else ""
            if k.isdigit() and int(k) > n:
                q.unlink()
                if stale is not None:
                    stale.append(q)
        print(f"{display_name(p)}: {n} event(s) cut")
    write_csv(events.parent / EVENT_INDEX, _INDEX_HEADER, index)
    if not items:
        raise InputError("no event found in the continuous recording(s)")
    return items


#: File beside the summary of ``weigh --continuous``: each event's place in its long file.
EVENT_INDEX = "events.csv"
_INDEX_HEADER = ("event", "long_file", "start_s", "stop_s", "on_s", "off_s", "clock",
                 "peak_sigma", "flags")


def _forget_cut_events(folder: Path) -> None:
    """A fresh run with ``--force`` and without ``--continuous`` deletes an earlier
    ``--continuous`` run's index and the event files it lists (beside a summary of other
    records they would be taken for its events), and their folder once empty; a file the
    index does not list stays."""
    import csv

    index = folder / EVENT_INDEX
    if not index.is_file():
        return
    events = folder / EVENTS
    try:
        with open(index, newline="", encoding="utf-8") as f:
            listed = {row.get("event", "") for row in csv.DictReader(f)}
    except (OSError, UnicodeDecodeError, csv.Error):
        listed = set()
    if events.is_dir():
        for p in events.iterdir():
            if p.is_file() and p.suffix == ".h5" and p.stem in listed:
                p.unlink()
        if not any(events.iterdir()):
            events.rmdir()
    index.unlink()


def _index_row(name: str, path: Path, ev) -> tuple:
    """An event's row of :data:`EVENT_INDEX`: times on its long file's time axis, s."""
    clock = ev.clock
    return (name, display_name(path), f"{ev.start:.6f}", f"{ev.stop:.6f}", f"{ev.on:.6f}",
            f"{ev.off:.6f}", "" if clock is None else clock.isoformat(timespec="milliseconds"),
            f"{ev.peak:.1f}", ";".join(ev.flags))


def weigh_command(args: argparse.Namespace) -> int:
    from bwim.batch import BatchFolder
    from bwim.io.gauge_health import GAUGE_HEALTH_NAME
    from bwim.io.outputs import refuse_input_overwrite, refuse_output_in_inputs
    from bwim.scenario import load_scenario

    check_jobs(args.jobs)
    scenario = load_scenario(args.scenario)
    site = scenario.logger is not None
    paths = record_paths(args.records, any_suffix=site)
    _unique_names(paths)
    cal = (record_paths(args.calibration_records, any_suffix=site)
           if args.calibration_records else [])
    if args.continuous and not site:
        raise InputError("--continuous cuts logger files: the scenario needs a [logger] "
                         "section")
    inputs = [*args.records, *(args.calibration_records or [])]
    refuse_output_in_inputs(args.output, inputs)
    if args.continuous:  # the event files' folder is an output folder too
        refuse_output_in_inputs(Path(args.output) / EVENTS, inputs)
    folder = out_folder(args.output)  # created once the inputs are known to exist
    if site:  # a resume keeps (and follows) the event files; a fresh run replaces none
        outputs = [folder / "calibration_runs.csv", folder / "influence_lines.h5",
                   *([folder / EVENTS, folder / EVENT_INDEX]
                     if args.continuous and _fresh(args, folder) else [])]
    else:  # each record's weights, and the line unless it is given
        outputs = [*(folder / f"{stem}_static.h5" for stem in unique_stems(paths)),
                   *([] if args.influence else [folder / "influence_line.h5"])]
    tables = [folder / GAUGE_HEALTH_NAME] if site else []
    refuse_input_overwrite([folder / "summary.csv", *outputs, *tables],
                           [args.scenario, *paths, *cal,
                            *([args.influence] if args.influence else []),
                            *([args.bridge] if args.bridge else [])])
    with locked(folder):
        if _fresh(args, folder):  # no output of a command replaced without --force
            refuse_existing_outputs(outputs, force=args.force, resumable=True)
            refuse_existing_outputs(tables, force=args.force, resumable=True)
            if site and args.force and not args.continuous:
                _forget_cut_events(folder)
        batch = BatchFolder(folder, resume=args.resume, force=args.force, meta=_meta(
            "weigh", scenario=args.scenario, calibration=sorted(cal, key=str),
            influence=args.influence, bridge=args.bridge), parquet=args.parquet)
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
        il = calibrate_influence_line(load_records(cal, scenario), build_vehicle(scenario))
        target = folder / "influence_line.h5"
        write_influence_line(il, target)
        print(f"influence line calibrated from {len(cal)} crossing(s) "
              f"(residual {il.residual:.3g}): {target}")
    items = [Item(name=display_name(p), source=p, target=folder / f"{stem}_static.h5")
             for p, stem in zip(paths, unique_stems(paths), strict=True)]
    executor = executor_for(args.jobs, args.scheduler)
    report = _run_batch(batch, items, lambda todo: weigh_records(
        todo, il, read=_read(scenario), executor=executor, keep=False), "weighing")
    _print_weighed(report, f"Static weights (Moses){_done_before(report)}:")
    print(f"summary: {batch.summary}\nweights: {folder}/<record>_static.h5")
    return _report_failures(report)


