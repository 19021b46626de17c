"""A single-file HTML report of bwim results: tables and embedded figures.

Contract
--------
* :func:`section` turns one result object into a :class:`Section` (a title, tables and
  matplotlib figures from :mod:`bwim.plots`): a :class:`~bwim.ForceIdentification`
  (forces, L-curve), :class:`~bwim.StaticWeights` (Moses' fit), an
  :class:`~bwim.InfluenceLine`, a :class:`~bwim.Record` (its channels), a
  :class:`~bwim.calibration.Calibration` (parameters, CE convergence) or a
  :class:`~bwim.Bridge` (its parameters).  A simulated record's truth, when given, is
  drawn and tabulated beside identified forces and weights.
* :func:`read_results` reads result files: any bwim HDF5 (identification, static weights,
  influence line, record), a bridge model TOML (:func:`bwim.scenario.save_bridge`) and CSV
  summaries (shown as tables); folders are expanded to the files they hold.
* Tables are :class:`bwim.tables.Table` (re-exported here as :class:`Table`), rendered
  with :meth:`~bwim.tables.Table.to_html`.
* :func:`figure_files` names the sections' figures for writing them as image files.
* :func:`render_html` makes the page (figures as base64 PNG, nothing linked);
  :func:`write_report` writes it atomically.
* Bad input is an :class:`~bwim.errors.InputError` naming the file.  This module is above
  the core and may import matplotlib; the core never imports it.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from bwim.errors import InputError
from bwim.io.paths import expand_paths
from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values

__all__ = ["Section", "Table", "figure_files", "read_results", "render_html", "section",
           "write_report"]

#: File suffixes :func:`read_results` picks up in a folder.
RESULT_SUFFIXES = (".h5", ".hdf5", ".hdf", ".toml", ".csv")


@dataclass(frozen=True, eq=False)
class Section:
    """One part of the report: a title, a note, tables and (caption, Figure) pairs."""

    title: str
    tables: tuple[Table, ...] = ()
    figures: tuple[tuple[str, Any], ...] = ()
    note: str = ""


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
    table = Table("Influence line", ("source", "channels", "lane (m)", "support (m)",
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
        Bridge, AccuracyResult (COST 323 classes), a :class:`Table` or a ready
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
            out.append((p.name, _read_csv_table(p)))
        else:
            raise InputError(f"{p}: unknown result format {p.suffix!r}; use .h5, .toml or .csv")
    return out


def figure_files(sections: Sequence[Section]) -> dict[str, Any]:
    """The sections' figures by file-name stem: the section title in lower case with every
    character but letters and digits as ``_``, cut at 48 characters and stripped of
    ``_`` at both ends, then the figure's number in its section (``record__x_1``)."""
    out = {}
    for s in sections:
        name = "".join(c if c.isalnum() else "_" for c in s.title.lower())[:48].strip("_")
        for k, (_, fig) in enumerate(s.figures):
            out[f"{name}_{k + 1}"] = fig
    return out


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return base64.b64encode(buf.getvalue()).decode("ascii")


_STYLE = """
body{font-family:system-ui,sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;
color:#222}
h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;
margin-top:2em}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
caption{text-align:left;font-weight:600;padding-bottom:.3em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}
th{background:#f2f2f2}figure{margin:1em 0}img{max-width:100%}
figcaption{font-size:.85em;color:#555}.note{color:#444}
"""


def render_html(title: str, sections: Sequence[Section], *, intro: str = "") -> str:
    """The report as one self-contained HTML page."""
    e = html.escape
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{e(title)}</title><style>{_STYLE}</style></head><body>",
             f"<h1>{e(title)}</h1>", f'<p class="note">bwim report, {stamp}.</p>']
    if intro:
        parts.append(f"<p>{e(intro)}</p>")
    for s in sections:
        parts.append(f"<section><h2>{e(s.title)}</h2>")
        if s.note:
            parts.append(f'<p class="note">{e(s.note)}</p>')
        parts += [t.to_html() for t in s.tables]
        for caption, fig in s.figures:
            parts.append(f'<figure><img alt="{e(caption)}" src="data:image/png;base64,'
                         f'{_png(fig)}"><figcaption>{e(caption)}</figcaption></figure>')
        parts.append("</section>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(path: str | os.PathLike, sections: Sequence[Section], *,
                 title: str = "bwim report", intro: str = "") -> Path:
    """Render ``sections`` and write the page atomically to ``path``; returns the path."""
    from bwim.io import atomic_open, check_writable

    target = check_writable(path)
    page = render_html(title, sections, intro=intro)
    with atomic_open(target) as f:
        f.write(page)
    return target
