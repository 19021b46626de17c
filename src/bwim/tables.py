"""Tables and number formats for printed and reported results (the presentation layer).

Contract
--------
* :class:`Table` is a title, a header and rows of cells, all held as ``str`` (other
  values are converted with :func:`str`).  :meth:`Table.render` is plain text: the title
  line (left out when the title is empty), the header, a rule of ``-`` as long as the
  header line, then the rows; every column is right-aligned to its widest cell and
  columns are two spaces apart.  A row shorter than the header is padded with empty
  cells.  :meth:`Table.to_html` is an HTML ``<table>`` with the title as its caption and
  every cell escaped.
* Forces are given in N and shown in kN (:data:`bwim.conventions.KILONEWTON`):
  :func:`format_kn` for one value, :func:`format_kn_each` for each value of an array;
  ``digits`` decimals (default 1).
* :func:`pct_change` is ``100 (value / ref - 1)``, elementwise, a float for scalars;
  :func:`format_pct` is that number with its sign and ``digits`` decimals (``+1.23``).
* :func:`param_values` walks parameter families (name -> array, as
  :attr:`bwim.Bridge.params` and :attr:`bwim.Calibration.params`) element by element:
  the label is the family name for a one-element family and ``name[z]`` for zone ``z``
  otherwise; beside each value stand the same element of companion families, or None
  where a companion is None or lacks the family.

This module imports only NumPy and :mod:`bwim.conventions`; the command line, the
paper's reproductions and the HTML report all format through it.
"""

from __future__ import annotations

import html
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from bwim.conventions import KILONEWTON

__all__ = ["Table", "format_kn", "format_kn_each", "format_pct", "param_values",
           "pct_change"]


@dataclass(frozen=True)
class Table:
    """A table of already formatted cells: ``Table(title, header, rows)``."""

    title: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "title", str(self.title))
        object.__setattr__(self, "header", tuple(str(h) for h in self.header))
        object.__setattr__(self, "rows", tuple(tuple(str(c) for c in r) for r in self.rows))

    def _padded(self) -> list[tuple[str, ...]]:
        n = max([len(self.header), *(len(r) for r in self.rows)])
        return [(*r, *[""] * (n - len(r))) for r in (self.header, *self.rows)]

    def render(self) -> str:
        """The table as plain text (see module docstring)."""
        cells = self._padded()
        widths = [max(len(r[i]) for r in cells) for i in range(len(cells[0]))]
        lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
        out = [self.title] if self.title else []
        return "\n".join([*out, lines[0], "-" * len(lines[0]), *lines[1:]])

    def to_html(self) -> str:
        """The table as an HTML ``<table>`` (title as caption, cells escaped)."""
        e = html.escape
        caption = f"<caption>{e(self.title)}</caption>" if self.title else ""
        head = "".join(f"<th>{e(h)}</th>" for h in self.header)
        body = "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in r) + "</tr>"
                       for r in self.rows)
        return f"<table>{caption}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def format_kn(value: float, digits: int = 1) -> str:
    """A force in N as kN with ``digits`` decimals: ``format_kn(59500.0) == '59.5'``."""
    return f"{float(value) / KILONEWTON:.{digits}f}"


def format_kn_each(values, digits: int = 1) -> list[str]:
    """:func:`format_kn` of each value of ``values`` (a scalar counts as one value)."""
    return [format_kn(v, digits) for v in np.atleast_1d(values)]


def pct_change(value, ref):
    """``100 (value / ref - 1)``: the change of ``value`` from ``ref``, in percent."""
    out = 100.0 * (np.asarray(value, dtype=float) / np.asarray(ref, dtype=float) - 1.0)
    return float(out) if out.ndim == 0 else out


def format_pct(value: float, ref: float, digits: int = 2) -> str:
    """:func:`pct_change` of two scalars as signed text: ``format_pct(1.1, 1.0) == '+10.00'``."""
    return f"{pct_change(value, ref):+.{digits}f}"


def param_values(
    params: Mapping[str, object], *companions: Mapping[str, object] | None
) -> Iterator[tuple]:
    """``(label, value, *companion values)`` for each element of each family in ``params``.

    Parameters
    ----------
    params : mapping of str to array_like
        Parameter families in order (a scalar is a one-element family).
    *companions : mapping of str to array_like, or None
        Families of the same shapes (a start, an uncertainty, a truth); an element is None
        where a companion is None or lacks the family.

    Yields
    ------
    tuple
        The label (``key``, or ``key[z]`` for a family of several zones), the value and
        one entry per companion.
    """
    for key, values in params.items():
        flat = np.atleast_1d(values)
        for z, v in enumerate(flat):
            label = key if flat.size == 1 else f"{key}[{z}]"
            others = tuple(None if c is None or key not in c else
                           float(np.atleast_1d(c[key])[z]) for c in companions)
            yield (label, float(v), *others)

