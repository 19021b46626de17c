"""The report page: sections of tables and figures rendered as one self-contained HTML file.

Contract
--------
* A :class:`Section` is a title, a note, tables (shown in full), figures (caption and
  matplotlib Figure pairs) and ``details``: long tables (e.g. one row per vehicle) shown
  in a scrolling box of bounded height, so that the page stays readable.
* :func:`render_html` makes the page: figures as base64 PNG (nothing linked), each in a
  ``<figure id="fig-…">`` whose image's ``alt`` is the caption; every table in a box that
  scrolls sideways when it is wider than the page, so the page itself never is (the page
  is at most 1100 CSS px wide and images shrink to it).
* :func:`figure_files` names the sections' figures for writing them as image files; the
  figure ids of the page are ``fig-`` and the same names with ``-`` for ``_``.
* :func:`write_report` writes the page atomically (:mod:`bwim.io.atomic`).
"""

from __future__ import annotations

import base64
import html
import io
import os
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from bwim.tables import Table

__all__ = ["Section", "figure_files", "render_html", "write_report"]


@dataclass(frozen=True, eq=False)
class Section:
    """One part of the report: a title, a note, tables, (caption, Figure) pairs and
    ``details`` (long tables shown in a scrolling box)."""

    title: str
    tables: tuple[Table, ...] = ()
    figures: tuple[tuple[str, Any], ...] = ()
    note: str = ""
    details: tuple[Table, ...] = ()


def _stem(title: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in title.lower())[:48].strip("_")


def figure_files(sections: Sequence[Section]) -> dict[str, Any]:
    """The sections' figures by file-name stem: the section title in lower case with every
    character but letters and digits as ``_``, cut at 48 characters and stripped of
    ``_`` at both ends, then the figure's number in its section (``record__x_1``)."""
    out = {}
    for s in sections:
        name = _stem(s.title)
        for k, (_, fig) in enumerate(s.figures):
            out[f"{name}_{k + 1}"] = fig
    return out


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return base64.b64encode(buf.getvalue()).decode("ascii")


_STYLE = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;
color:#222}
h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;
margin-top:2em}
.wide{max-width:100%;overflow-x:auto}
.scroll{max-width:100%;max-height:30em;overflow:auto;border:1px solid #ccc;margin:1em 0}
.scroll table{margin:0}.scroll thead th{position:sticky;top:0}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
caption{text-align:left;font-weight:600;padding-bottom:.3em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}
td.num{text-align:right}
.scroll th,.scroll td{white-space:nowrap}
th{background:#f2f2f2}figure{margin:1em 0}img{max-width:100%;height:auto}
.figures{display:grid;grid-template-columns:repeat(auto-fill,minmax(440px,1fr));gap:0 1.5em}
figcaption{font-size:.85em;color:#555}.note{color:#444}
"""


def _is_number(text: str) -> bool:
    head = text.split(" ")[0].replace("%", "").replace("−", "-")
    try:
        float(head)
    except ValueError:
        return False
    return True


def _table(t: Table, box: str) -> str:
    """A table in a box (see the module docstring); cells that read as numbers are
    right-aligned, text left-aligned."""
    e = html.escape
    caption = f"<caption>{e(t.title)}</caption>" if t.title else ""
    head = "".join(f"<th>{e(h)}</th>" for h in t.header)
    body = "".join(
        "<tr>" + "".join(f'<td class="num">{e(c)}</td>' if _is_number(c) else f"<td>{e(c)}</td>"
                         for c in r) + "</tr>" for r in t.rows)
    return (f'<div class="{box}"><table>{caption}<thead><tr>{head}</tr></thead>'
            f"<tbody>{body}</tbody></table></div>")


def render_html(title: str, sections: Sequence[Section], *, intro: str = "") -> str:
    """The report as one self-contained HTML page (see the module docstring)."""
    e = html.escape
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<title>{e(title)}</title><style>{_STYLE}</style></head><body>",
             f"<h1>{e(title)}</h1>", f'<p class="note">bwim report, {stamp}.</p>']
    if intro:
        parts.append(f"<p>{e(intro)}</p>")
    for s in sections:
        parts.append(f"<section><h2>{e(s.title)}</h2>")
        if s.note:
            parts.append(f'<p class="note">{e(s.note)}</p>')
        parts += [_table(t, "wide") for t in s.tables]
        stem = _stem(s.title).replace("_", "-")
        if s.figures:
            parts.append('<div class="figures">')
        for k, (caption, fig) in enumerate(s.figures):
            parts.append(f'<figure id="fig-{stem}-{k + 1}"><img alt="{e(caption)}" '
                         f'src="data:image/png;base64,{_png(fig)}">'
                         f"<figcaption>{e(caption)}</figcaption></figure>")
        if s.figures:
            parts.append("</div>")
        parts += [_table(t, "scroll") for t in s.details]
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
