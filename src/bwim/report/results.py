"""Sections of bwim result objects and the reading of result files.

Contract
--------
* :func:`section` turns one result object into a :class:`~bwim.report.page.Section` (a
  title, tables and matplotlib figures from :mod:`bwim.plots`): a
  :class:`~bwim.ForceIdentification` (forces, L-curve), :class:`~bwim.StaticWeights`
  (Moses' fit), an :class:`~bwim.InfluenceLine`, a :class:`~bwim.Record` (its channels),
  a :class:`~bwim.calibration.Calibration` (parameters, CE convergence), a
  :class:`~bwim.Bridge` (its parameters), a COST 323
  :class:`~bwim.accuracy.AccuracyResult`, a calibration runs table
  (:func:`bwim.report.site.runs_section`) or a :class:`~bwim.tables.Table`.  A simulated
  record's truth, when given, is drawn and tabulated beside identified forces and weights.
* :func:`read_results` reads result files: any bwim HDF5 (identification, static weights,
  influence line, record), a bridge model TOML (:func:`bwim.scenario.save_bridge`), a weigh
  ``summary.csv`` (as a :class:`~bwim.report.site.TrafficSummary`, for the site report
  :func:`bwim.report.site.site_sections`), a ``calibration_runs.csv``
  (:class:`~bwim.report.runs.CalibrationRuns`) and any other CSV (shown as a table);
  folders are expanded to the files they hold.
* Bad input is an :class:`~bwim.errors.InputError` naming the file.  This package is above
  the core and may import matplotlib; the core never imports it.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bwim.errors import InputError
from bwim.io.paths import expand_paths
from bwim.report.page import Section
from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values

__all__ = ["RESULT_SUFFIXES", "read_results", "result_paths", "section"]

#: File suffixes :func:`read_results` picks up in a folder.
RESULT_SUFFIXES = (".h5", ".hdf5", ".hdf", ".toml", ".csv")


def _weight_table(title: str, weights: np.ndarray, truth) -> Table:
    """Static axle weights in kN, with the truth and the error % beside them if known."""
    n = weights.size
    rows = [("axle weights (kN)", *format_kn_each(weights))]
    if truth is not None and truth.static_axle_loads.size == n:
        true = truth.static_axle_loads
        rows.append(("true static (kN)", *format_kn_each(true)))
        rows.append(("error (%)", *(format_pct(w, t, 1) for w, t in zip(weights, true,
                                                                         strict=True))))
    return Table(title, ("", *(f"axle {i + 1}" for i in range(n))), tuple(rows))


def _identification(name: str, ident, truth) -> Section:
    from bwim.plots.mfi import plot_forces, plot_lcurve

    table = _weight_table("Identified static axle weights", ident.axle_weights, truth)
    gvw = Table("Gross vehicle weight and regularisation",
                ("vehicle", "GVW (kN)", "true GVW (kN)", "λ"),
                tuple((i + 1, format_kn(g),
                       format_kn(truth.gvw) if truth is not None and i == 0 else "–",
                       f"{ident.lam:.3g}") for i, g in enumerate(ident.gvw)))
    figures = [("Identified axle forces (dashed: truth)" if truth is not None
                else "Identified axle forces", plot_forces(ident, truth=truth))]
    if ident.lcurve is not None:
        figures.append(("L-curve and the λ chosen at its corner", plot_lcurve(ident)))
    return Section(f"Moving force identification: {name}", (table, gvw), tuple(figures))


def _static(name: str, weights, truth) -> Section:
    from bwim.plots.wim import plot_static_fit

    table = _weight_table("Moses static axle weights", weights.axle_weights, truth)
    summary = Table("Fit", ("GVW (kN)", "relative residual", "condition number"),
                    ((format_kn(weights.gvw), f"{weights.residual:.3g}",
                      f"{weights.condition:.3g}"),))
    return Section(f"Static weighing (Moses): {name}", (table, summary),
                   (("Measured readings and Moses' static fit", plot_static_fit(weights)),))


def _influence(name: str, il, bridge=None) -> Section:
    from bwim.plots.wim import plot_influence_line
    from bwim.wim import model_influence_line

    lo, hi = il.support
    table = Table("Influence line", ("source", "channels", "lateral", "support (m)",
                                     "spacing (m)", "residual"),
                  ((il.source or "–", ", ".join(il.channel_names), f"{il.lane:g}",
                    f"{lo:g} … {hi:g}", f"{il.spacing:.3g}",
                    "–" if il.residual is None else f"{il.residual:.3g}"),))
    ref = None if bridge is None else model_influence_line(bridge, like=il)
    figure = plot_influence_line(il, reference=ref)
    return Section(f"Influence line: {name}", (table,),
                   (("Influence line per kN of axle load", figure),))


def _record(name: str, record, length) -> Section:
    from bwim.plots.records import plot_record

    rows = tuple((str(i + 1), f"{p.speed:g}", f"{p.lane:g}", str(p.n_axles))
                 for i, p in enumerate(record.passages))
    table = Table(f"{len(record.sensors)} channels, {record.time.size} samples at "
                  f"{record.sampling_rate:g} Hz", ("vehicle", "speed (m/s)", "lane (m)", "axles"),
                  rows)
    return Section(f"Record: {name}", (table,) if rows else (),
                   (("Readings", plot_record(record, length=length)),))


def _calibration(name: str, cal, start, true_bridge) -> Section:
    from bwim.plots.calibration import plot_ce_convergence

    # the paper's two stages beside the final (refined, mesh-corrected) answer
    header = ["parameter"] + (["start"] if start is not None else []) + [
        "two stages", "calibrated", "uncertainty"]
    if true_bridge is not None:
        header += ["true", "two-stage error (%)", "error (%)"]
    rows = []
    for label, v, s0, v2, u, t in param_values(
            cal.params, None if start is None else start.params, cal.two_stage,
            cal.uncertainty, None if true_bridge is None else true_bridge.params):
        v2 = v if v2 is None else v2
        row = [label] + ([] if start is None else [f"{s0:.5g}"]) + [f"{v2:.5g}", f"{v:.5g}",
                                                                     f"{u:.3g}"]
        if true_bridge is not None:
            row += (["–", "–", "–"] if t is None else
                    [f"{t:.5g}", format_pct(v2, t, 3), format_pct(v, t, 3)])
        rows.append(row)
    table = Table("Calibrated parameters (SI units: Pa, kg/m²)", header, rows)
    from bwim.optimize.ce import CEHistory

    stages = Table("Stages", ("stage", "unknowns", "evaluations", "iterations", "time (s)"),
                   tuple((s.name, ", ".join(s.labels), str(s.nfev), str(s.nit),
                          f"{s.wall_time:.1f}") for s in cal.stages))
    figures = []
    for s in cal.stages:
        if isinstance(s.history, CEHistory):
            for k, label in enumerate(s.labels):
                figures.append((f"Cross-Entropy convergence, {s.name}: {label}",
                                plot_ce_convergence(s, parameter=k)))
    note = (f"{cal.nfev} objective evaluations in {cal.wall_time:.1f} s. "
            + cal.identifiability.summary().replace("\n", "; ") + "."
            + ("" if cal.mesh_correction is None else f" {cal.mesh_correction.summary()}."))
    return Section(f"Calibration: {name}", (table, stages), tuple(figures), note)


def _bridge(name: str, bridge) -> Section:
    return Section(f"Bridge model: {name}",
                   (Table("Parameters (SI units: Pa, kg/m²)", ("parameter", "value"),
                          [(label, f"{v:.5g}") for label, v in param_values(bridge.params)]),))


def section(obj: Any, name: str = "", *, truth=None, length: float | None = None,
            start=None, true_bridge=None) -> Section:
    """The report section of one result object (see module docstring).

    Parameters
    ----------
    obj
        A result: ForceIdentification, StaticWeights, InfluenceLine, Record, Calibration,
        Bridge, AccuracyResult (COST 323 classes), CalibrationRuns, a :class:`Table` or a ready
        :class:`Section`.
    name : str
        What the result is (a file name, a vehicle), shown in the title.
    truth : Truth, optional
        The simulated truth of the weighed vehicle.
    length : float, optional
        Span, m, to shade when a vehicle is on the deck in record plots.
    start, true_bridge : Bridge, optional
        For a calibration: the starting model and the true one (simulations); for an
        influence line, ``true_bridge`` adds its FE static line as the reference.
    """
    from bwim.calibration import Calibration
    from bwim.fe.bridge import Bridge
    from bwim.mfi import ForceIdentification
    from bwim.records import Record
    from bwim.wim import InfluenceLine, StaticWeights

    if isinstance(obj, Section):
        return obj
    if isinstance(obj, Table):
        return Section(name or obj.title, (obj,))
    if isinstance(obj, ForceIdentification):
        return _identification(name, obj, truth)
    if isinstance(obj, StaticWeights):
        return _static(name, obj, truth)
    if isinstance(obj, InfluenceLine):
        return _influence(name, obj, true_bridge)
    if isinstance(obj, Record):
        return _record(name, obj, length)
    if isinstance(obj, Calibration):
        return _calibration(name, obj, start, true_bridge)
    if isinstance(obj, Bridge):
        return _bridge(name, obj)
    from bwim.accuracy import AccuracyResult

    if isinstance(obj, AccuracyResult):
        return Section(f"COST 323 accuracy{f' of {name}' if name else ''}", (obj.table(),),
                       note=" ".join(f"{n}." for n in obj.notes()))
    from bwim.report.runs import CalibrationRuns
    from bwim.report.site import TrafficSummary, runs_section

    if isinstance(obj, CalibrationRuns):
        return runs_section(obj)
    if isinstance(obj, TrafficSummary):
        raise InputError("a summary makes a site report of several sections: use "
                         "bwim.report.site_sections")
    raise InputError(f"cannot report a {type(obj).__name__}")


def _read_csv_table(path: Path) -> Table:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = [r for r in csv.reader(f) if r]
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    if not rows:
        raise InputError(f"{path}: empty CSV file")
    return Table(path.name, tuple(rows[0]), tuple(tuple(r) for r in rows[1:]))


def _read_csv(path: Path):
    """A summary, a calibration runs table or any other CSV file (a table)."""
    from bwim.io.summary import is_summary, read_summary
    from bwim.report.runs import is_runs_table, read_calibration_runs
    from bwim.report.site import TrafficSummary

    if is_summary(path):  # named with its folder: two results' summaries are told apart
        name = f"{path.parent.name}/{path.name}" if path.parent.name else path.name
        return TrafficSummary(name=name, rows=read_summary(path))
    if is_runs_table(path):
        return read_calibration_runs(path)
    return _read_csv_table(path)


def _read_h5(path: Path):
    from bwim.io import read_identification, read_influence_line, read_record, read_static_weights

    last = None
    for reader in (read_identification, read_static_weights, read_influence_line,
                   read_record):
        try:
            return reader(path)
        except InputError as exc:
            if "holds a bwim" not in str(exc):
                raise
            last = exc
    raise last


def result_paths(paths: Iterable[str | os.PathLike]) -> list[Path]:
    """The result files of ``paths``, folders expanded (sorted)."""
    return expand_paths(paths, RESULT_SUFFIXES, what="result files")


def read_results(paths: Sequence[str | os.PathLike]) -> list[tuple[str, Any]]:
    """(name, object) of each result file (folders expanded), in order."""
    from bwim.scenario import load_bridge

    out = []
    for p in result_paths(paths):
        suffix = p.suffix.lower()
        if suffix in (".h5", ".hdf5", ".hdf"):
            out.append((p.name, _read_h5(p)))
        elif suffix == ".toml":
            out.append((p.name, load_bridge(p)))
        elif suffix == ".csv":
            out.append((p.name, _read_csv(p)))
        else:
            raise InputError(f"{p}: unknown result format {p.suffix!r}; use .h5, .toml or .csv")
    return out
