"""Overloads: weighed vehicles above configurable gross and axle weight limits.

Contract
--------
* :class:`OverloadLimits` holds the limits, N.  The defaults are the EU's maxima for
  vehicles in international traffic (Council Directive 96/53/EC, Annex I, as amended):
  40 t gross for a five- or six-axle vehicle combination and 11.5 t on a single driving
  axle, times g = 9.81 m/s²: 392.4 kN and 112.8 kN.  National limits differ (and
  permits exist); give yours.  ``None`` switches a limit off.
* :func:`overloads` lists every **weighed** row whose gross weight or heaviest axle
  exceeds a limit (strictly), in the rows' order, as :class:`Overload` (the row, what
  was exceeded, by how much, %).  A WIM weight is a dynamic estimate with the system's
  accuracy class as its tolerance: the list selects vehicles for a static check, it is
  not an enforcement record.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from bwim.errors import InputError
from bwim.summary import SummaryRow

__all__ = ["G", "Overload", "OverloadLimits", "overloads"]

#: Standard gravity, m/s², turning the Directive's tonnes into newtons.
G = 9.81


def _limit(name: str, value: float | None) -> float | None:
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number of newtons or None, got {value!r}") \
            from None
    if not v > 0.0 or v == float("inf"):
        raise InputError(f"{name} must be positive and finite, got {value!r}")
    return v


@dataclass(frozen=True, kw_only=True)
class OverloadLimits:
    """Gross (``gvw``) and single-axle (``axle``) weight limits, N; None: no limit."""

    gvw: float | None = 40_000.0 * G
    axle: float | None = 11_500.0 * G

    def __post_init__(self) -> None:
        object.__setattr__(self, "gvw", _limit("gvw", self.gvw))
        object.__setattr__(self, "axle", _limit("axle", self.axle))


@dataclass(frozen=True, kw_only=True)
class Overload:
    """A weighed row above a limit: ``what`` is ``"gvw"`` and/or ``"axle"``;
    ``excess_pct`` the largest excess over its limit, %."""

    row: SummaryRow
    what: tuple[str, ...]
    excess_pct: float


def overloads(rows: Sequence[SummaryRow], limits: OverloadLimits | None = None
              ) -> tuple[Overload, ...]:
    """The weighed rows above ``limits`` (default :class:`OverloadLimits`)."""
    lim = OverloadLimits() if limits is None else limits
    out = []
    for r in rows:
        if not r.weighed:
            continue
        what, excess = [], []
        if lim.gvw is not None and r.gvw is not None and r.gvw > lim.gvw:
            what.append("gvw")
            excess.append(100.0 * (r.gvw / lim.gvw - 1.0))
        heaviest = max(r.axle_weights, default=None)
        if lim.axle is not None and heaviest is not None and heaviest > lim.axle:
            what.append("axle")
            excess.append(100.0 * (heaviest / lim.axle - 1.0))
        if what:
            out.append(Overload(row=r, what=tuple(what), excess_pct=max(excess)))
    return tuple(out)
