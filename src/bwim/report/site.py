"""The operator's site report: a day of weighed traffic in tables and figures.

Contract
--------
* :class:`TrafficSummary` is a named summary (rows of :class:`bwim.summary.SummaryRow`,
  e.g. :func:`bwim.io.read_summary` of ``summary.csv``).
* :func:`site_sections` makes the report's sections (:class:`~bwim.report.page.Section`),
  in order: the overview (a short summary table, the per-vehicle table behind it in a
  scrolling box), the traffic figures (gross weight histogram, axle-load spectrum,
  speeds, vehicles by class and by lane, flow per hour: :mod:`bwim.plots.traffic`), the
  overloads (:mod:`bwim.report.overloads`), the flags and reasons in words
  (:mod:`bwim.report.flags`), and when given the COST 323 accuracy against a static
  reference (:func:`bwim.accuracy.assess`; weighed-against-static scatter and error
  histogram with the class's tolerance, :mod:`bwim.plots.accuracy`) and the calibration
  runs (:mod:`bwim.report.runs`, :mod:`bwim.plots.runs`).
* What the data cannot show is left out **with a note**, never an error: no time column
  (no flow per hour), no lane or class, no weighed vehicle, no reference, no runs.
* :func:`reference_pairs` pairs weighed rows with reference rows by the matching rule of
  :func:`bwim.accuracy.assess` (record and vehicle; a record's one row; else the row in
  the reference's lane, a weighed one first; a reference given by time: the one row
  within the time tolerance).
* Weights in kN, speeds in km/h and m/s, lateral positions in the summary's
  ``lateral_unit`` (metres or gauge index: the column header says which).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.conventions import KILONEWTON
from bwim.records import clock_key
from bwim.report.flags import FLAG_GROUPS, explain
from bwim.report.overloads import OverloadLimits, overloads
from bwim.report.page import Section
from bwim.summary import SummaryRow
from bwim.tables import Table

__all__ = ["TrafficSummary", "reference_pairs", "runs_section", "site_sections"]

_KMH = 3.6


@dataclass(frozen=True, kw_only=True)
class TrafficSummary:
    """The rows of one summary and its name (a file name)."""

    name: str
    rows: tuple[SummaryRow, ...]


def _kn(v: float | None, digits: int = 1) -> str:
    return "" if v is None else f"{v / KILONEWTON:.{digits}f}"


def _time(t) -> str:
    return "" if t is None else t.isoformat(timespec="seconds")


def _lateral_header(rows: Sequence[SummaryRow]) -> str:
    units = {r.lateral_unit for r in rows if r.lateral is not None}
    if units == {"m"}:
        return "strain centre across (m from right edge)"
    if units == {"gauge index"}:
        return "lateral (gauge index)"
    return "lateral"


def _lateral_cell(r: SummaryRow, uniform: bool) -> str:
    if r.lateral is None:
        return ""
    if uniform or not r.lateral_unit:
        return f"{r.lateral:.2f}"
    return f"{r.lateral:.2f} {'m' if r.lateral_unit == 'm' else '(gauge index)'}"


def _vehicle_table(rows: Sequence[SummaryRow]) -> Table:
    lat = _lateral_header(rows)
    uniform = lat != "lateral"
    header = ("record", "vehicle", "time", "lane", "direction", "class", "axles",
              "speed (km/h)", "axle spacings (m)", "axle weights (kN)", "GVW (kN)", lat,
              "status", "quality", "flags", "reason")
    body = tuple((
        r.record, str(r.vehicle), _time(r.time), "" if r.lane is None else str(r.lane),
        r.direction, r.vehicle_class, "" if r.n_axles is None else str(r.n_axles),
        "" if r.speed is None else f"{r.speed * _KMH:.1f}",
        " ".join(f"{s:.2f}" for s in r.axle_spacings),
        " ".join(_kn(w) for w in r.axle_weights), _kn(r.gvw), _lateral_cell(r, uniform),
        r.status or "", r.quality, " ".join(r.flags), r.reason) for r in rows)
    return Table(f"Every vehicle ({len(rows)} rows)", header, body)


def _overview(summary: TrafficSummary, notes: list[str], n_over: int) -> Section:
    rows = summary.rows
    vs = [r for r in rows if r.status != "failed"]
    weighed = [r for r in rows if r.weighed]
    gvw = np.array([r.gvw for r in weighed])
    times = [r.time for r in vs if r.time is not None]
    times.sort(key=clock_key(times))
    lanes = sorted({r.lane for r in vs if r.lane is not None})
    classes = Counter(r.vehicle_class for r in weighed if r.vehicle_class)
    items = [
        ("vehicles seen", str(len(vs))),
        ("weighed", f"{len(weighed)} ({100 * len(weighed) / len(vs):.0f} %)" if vs else "0"),
        ("refused (seen, not weighed)", str(sum(r.status == "refused" for r in rows))),
        ("failed records (not read or processed)", str(sum(r.status == "failed"
                                                           for r in rows))),
        ("weighed with warnings", str(sum(r.quality == "warning" for r in weighed))),
        ("period", f"{_time(times[0])} to {_time(times[-1])}" if times else "no time column"),
        ("lanes", ", ".join(map(str, lanes)) or "unknown"),
        ("most frequent classes (weighed)",
         ", ".join(f"{c}: {n}" for c, n in classes.most_common(4)) or "unknown"),
        ("gross weight, median / mean / max (kN)",
         " / ".join(f"{v / KILONEWTON:.1f}" for v in (np.median(gvw), gvw.mean(), gvw.max()))
         if gvw.size else "no weighed vehicle"),
        ("overloads", str(n_over)),
    ]
    note = " ".join(notes)
    return Section(f"Site summary: {summary.name}",
                   (Table("Summary", ("", "value"), items),), note=note,
                   details=(_vehicle_table(rows),))


def _traffic(rows: Sequence[SummaryRow], limits: OverloadLimits, notes: list[str]
             ) -> Section:
    from bwim.plots import traffic as tp

    vs = tp.seen(rows)
    figures = []
    if any(r.weighed for r in rows):
        figures.append(("Gross vehicle weight histogram",
                        tp.plot_gvw_histogram(rows, limit=limits.gvw)))
        figures.append(("Axle-load spectrum", tp.plot_axle_load_spectrum(
            rows, limit=limits.axle)))
    else:
        notes.append("No vehicle was weighed: the gross weight histogram and the axle-load "
                     "spectrum are left out.")
    if any(r.speed is not None for r in vs):
        figures.append(("Speed distribution", tp.plot_speed_distribution(rows)))
    else:
        notes.append("No speed in the summary: the speed distribution is left out.")
    if any(r.vehicle_class for r in vs):
        figures.append(("Vehicles by class", tp.plot_counts(rows, by="class")))
    else:
        notes.append("No class column: the counts by class are left out.")
    if any(r.lane is not None for r in vs):
        figures.append(("Vehicles by lane", tp.plot_counts(rows, by="lane")))
    else:
        notes.append("No lane column: the counts by lane are left out.")
    if any(r.time is not None for r in vs):
        figures.append(("Flow per hour", tp.plot_hourly_flow(rows)))
    else:
        notes.append("No time column: the flow per hour is left out.")
    return Section("Traffic", figures=tuple(figures),
                   note="Weights of weighed vehicles only; counts of every vehicle seen "
                        "(grey: seen but not weighed).")


def _limit_text(limits: OverloadLimits) -> str:
    parts = []
    if limits.gvw is not None:
        parts.append(f"gross weight above {limits.gvw / KILONEWTON:.1f} kN")
    if limits.axle is not None:
        parts.append(f"an axle above {limits.axle / KILONEWTON:.1f} kN")
    return " or ".join(parts) or "no limit set"


def _overloads(rows: Sequence[SummaryRow], limits: OverloadLimits) -> tuple[Section, int]:
    found = overloads(rows, limits)
    table = Table(f"Overloads ({len(found)})",
                  ("record", "vehicle", "time", "lane", "class", "GVW (kN)",
                   "heaviest axle (kN)", "over", "excess (%)"),
                  tuple((o.row.record, str(o.row.vehicle), _time(o.row.time),
                         "" if o.row.lane is None else str(o.row.lane),
                         o.row.vehicle_class, _kn(o.row.gvw),
                         _kn(max(o.row.axle_weights, default=None)), " and ".join(o.what),
                         f"{o.excess_pct:.1f}") for o in found))
    note = (f"Weighed vehicles with {_limit_text(limits)} (configurable; the defaults are "
            "the EU limits of Directive 96/53/EC: 40 t gross, 11.5 t driving axle). A WIM "
            "weight is a dynamic estimate within the system's accuracy class: this list "
            "selects vehicles for a static check.")
    if not found:
        return Section("Overloads", note=note + " None found."), 0
    return Section("Overloads", note=note, details=(table,)), len(found)


def _flags(rows: Sequence[SummaryRow]) -> Section:
    counts = Counter(f for r in rows for f in r.flags)
    quality = Counter(r.quality or "–" for r in rows if r.status != "failed")
    tables = [Table("Quality of the vehicles seen", ("quality", "vehicles"),
                    tuple((q, str(n)) for q, n in sorted(quality.items())))]
    if counts:
        body = []
        for f, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
            m = explain(f)
            body.append((f, m.group, str(n), m.meaning, m.look_at))
        tables.append(Table("Flags raised", ("flag", "kind", "vehicles", "meaning",
                                             "what to look at"), body))
    reasons = Counter(r.reason for r in rows if r.reason)
    if reasons:
        top = reasons.most_common(15)
        more = ", the 15 most frequent" if len(reasons) > 15 else ""
        tables.append(Table(f"Why vehicles were not weighed ({sum(reasons.values())} rows, "
                            f"{len(reasons)} distinct reasons{more})",
                            ("reason", "rows"), tuple((t, str(n)) for t, n in top)))
    note = ("Kinds: " + "; ".join(f"{k}: {v}" for k, v in FLAG_GROUPS.items()
                                   if k != "unknown") + ". The full vocabulary is "
            "docs/flags.md.") if counts else "No flag was raised."
    return Section("Flags and reasons", tuple(tables), note=note)


def reference_pairs(rows: Sequence[SummaryRow], reference: Sequence, *,
                    time_tolerance: float = 5.0) -> tuple[tuple[SummaryRow, object], ...]:
    """(weighed row, reference row) of every reference vehicle the summary weighed, by
    the matching rule of :func:`bwim.accuracy.assess` (:func:`bwim.accuracy.
    match_references`)."""
    from bwim.accuracy import match_references

    return tuple((m.row, m.reference) for m in match_references(
        rows, reference, time_tolerance=time_tolerance) if m.row is not None and m.row.weighed)


def _accuracy(rows: Sequence[SummaryRow], reference: Sequence, summary_name: str, name: str,
              *, repeatability: str, environment: str, time_tolerance: float) -> Section:
    from bwim.accuracy import assess, relative_errors
    from bwim.plots.accuracy import plot_error_histogram, plot_weighed_vs_reference

    result = assess(rows, reference, repeatability=repeatability, environment=environment,
                    time_tolerance=time_tolerance)
    notes = [f"{n}." for n in result.notes()]
    pairs = reference_pairs(rows, reference, time_tolerance=time_tolerance)
    figures = []
    if pairs:
        w = np.array([p[0].gvw for p in pairs])
        s = np.array([p[1].gvw for p in pairs])
        gross = next((c for c in result.criteria if c.name == "gross_weight"), None)
        tol = None if gross is None else gross.delta
        cls = "" if gross is None else gross.class_name
        if gross is None:
            notes.append("Too few vehicles for a gross-weight class: no tolerance drawn.")
        figures = [("Weighed against static gross weight",
                    plot_weighed_vs_reference(w, s, tolerance=tol, class_name=cls)),
                   ("Gross weight error histogram",
                    plot_error_histogram(relative_errors(w, s), tolerance=tol,
                                         class_name=cls))]
    else:
        notes.append("No reference vehicle was weighed: the scatter and the error "
                     "histogram are left out.")
    return Section(f"COST 323 accuracy of {summary_name} against {name}", (result.table(),),
                   tuple(figures),
                   note=" ".join(notes))


def runs_section(runs) -> Section:
    """The calibration runs' section: their table (scrolling), scale factor over the day
    and residuals (:mod:`bwim.plots.runs`)."""
    from bwim.plots.runs import plot_run_residuals, plot_run_scales, run_hours

    def num(v, fmt):
        return "" if v is None else format(v, fmt)

    table = Table(f"Calibration runs ({runs.n_used} of {len(runs.runs)} used)",
                  ("run", "time", "speed (km/h)", "lateral", "scale", "residual", "status"),
                  tuple((r.name, _time(r.time),
                         "" if r.speed is None else f"{r.speed * _KMH:.1f}",
                         num(r.lateral, ".2f"), num(r.scale, ".4f"), num(r.residual, ".3g"),
                         r.status) for r in runs.runs))
    note = ("Scale: each run's strain-to-load factor relative to the fitted lines (1 = the "
            "lines); its trend over the day is the drift the weights are corrected for. "
            "Residual: relative misfit of each run.")
    if run_hours(runs) is None:
        note += (" The runs table has no time for every run: the scale factors are drawn "
                 "in the table's order, not over the day.")
    figures = (("Calibration runs: scale factor over the day", plot_run_scales(runs)),
               ("Calibration runs: residual of each run", plot_run_residuals(runs)))
    return Section(f"Calibration runs: {runs.name}", figures=figures, note=note,
                   details=(table,))


def site_sections(summary: TrafficSummary, *, reference: Sequence | None = None,
                  reference_name: str = "the static reference", runs=None,
                  limits: OverloadLimits | None = None, repeatability: str = "RR2",
                  environment: str = "I", time_tolerance: float = 5.0) -> list[Section]:
    """The site report's sections (see the module docstring).

    Parameters
    ----------
    summary : TrafficSummary
        The weighed day.
    reference : sequence of bwim.accuracy.ReferenceRow, optional
        Static weights of some vehicles: adds the COST 323 section.
    reference_name : str
        What the reference is (a file name), for the section's title.
    runs : bwim.report.runs.CalibrationRuns, optional
        The calibration runs: adds their section.
    limits : OverloadLimits, optional
        The overload limits (default: the EU's, :class:`OverloadLimits`).
    repeatability, environment : str
        COST 323 test conditions (:func:`bwim.accuracy.assess`).
    time_tolerance : float
        s: how far a reference given by time may lie from its vehicle's row
        (:func:`bwim.accuracy.assess`).
    """
    lim = OverloadLimits() if limits is None else limits
    rows = summary.rows
    notes: list[str] = []
    traffic = _traffic(rows, lim, notes)
    over, n_over = _overloads(rows, lim)
    extra = []
    if reference is not None:
        extra.append(_accuracy(rows, reference, summary.name, reference_name,
                               repeatability=repeatability, environment=environment,
                               time_tolerance=time_tolerance))
    else:
        notes.append("No static reference given (--reference): no accuracy section.")
    if runs is not None:
        extra.append(runs_section(runs))
    else:
        notes.append("No calibration runs table given: no calibration section.")
    return [_overview(summary, notes, n_over), traffic, over, _flags(rows), *extra]
