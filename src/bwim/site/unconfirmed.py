"""A gauge fault the day does not confirm: another vehicle, not a faulty gauge.

The gauge check of one event (:mod:`bwim.site.health`) leaves out a gauge that disagrees
with what the others predict and weighs the vehicle without it (``gauge_fault:NAME``).
A faulty gauge stays faulty: it disagrees in the vehicles before and after too.  A
healthy gauge disagrees only when something the lines do not model loads it: most often
a vehicle that no detector saw in the lane next to it (the far gauges read it, the lines
of the weighed vehicle do not), whose strain the other gauges near it still carry into
the weights.

Contract
--------
* :func:`refuse_unconfirmed_faults` orders a batch's rows weighed (``status ==
  "weighed"``) by clock time (the site's wall clock: dated rows first, then rows with a
  clock time of day, then rows without one in their place in the batch).  A weighed row
  flagged ``gauge_fault:NAME`` is **confirmed** when that
  gauge is flagged in at least ``confirm`` (:data:`CONFIRM`, most) of the
  ``neighbours`` (:data:`NEIGHBOURS`) weighed rows nearest it in that order, itself
  included (the first or last ``neighbours`` rows at the ends of the day): a gauge that
  died at noon is confirmed in every vehicle after noon.  A row with a fault not
  confirmed is refused (weights dropped, ``unconfirmed_gauge_fault`` added to its
  flags, quality ``"reject"``, a reason naming the gauge and its count among those
  rows).  With fewer than ``neighbours`` weighed rows the day cannot judge: every row is
  kept.
* A gauge faulty only now and then (clipping under the heaviest trucks, a loose
  connector) is not confirmed either: its vehicles are refused rather than weighed with
  a fault no neighbour confirms (a refused weight is never a wrong one).
* Rows other than weighed ones are returned unchanged, in order.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from datetime import time as dtime

import numpy as np

from bwim.errors import InputError
from bwim.records import local_seconds, seconds_of_day
from bwim.summary import SummaryRow

__all__ = ["CONFIRM", "FLAG_UNCONFIRMED", "NEIGHBOURS", "FaultCheck",
           "refuse_unconfirmed_faults"]

#: The share of its neighbours in which a gauge must be found faulty for a fault to be
#: the gauge's own: most of them.
CONFIRM = 0.5
#: The weighed vehicles nearest in time that judge a fault (about 20 minutes of heavy
#: traffic on a busy road); a day with fewer is not judged.
NEIGHBOURS = 30
#: The flag of a row refused here.
FLAG_UNCONFIRMED = "unconfirmed_gauge_fault"
_PREFIX = "gauge_fault:"


@dataclass(frozen=True, kw_only=True, eq=False)
class FaultCheck:
    """The rows after :func:`refuse_unconfirmed_faults`.

    Attributes
    ----------
    rows : tuple of SummaryRow
        Every input row, in order; the rows of unconfirmed faults refused.
    counts : dict of str to int
        Weighed rows flagged faulty per gauge over the day.
    n_weighed : int
        Weighed rows judged (0 when fewer than ``neighbours``: not judged).
    refused : tuple of (str, int)
        ``(record, vehicle)`` of the rows refused here.
    unconfirmed : dict of str to int
        Per gauge, the rows refused for it.
    """

    rows: tuple[SummaryRow, ...]
    counts: dict[str, int]
    n_weighed: int
    refused: tuple[tuple[str, int], ...]
    unconfirmed: dict[str, int]

    def __repr__(self) -> str:
        return (f"FaultCheck({len(self.rows)} rows, {self.n_weighed} weighed judged, "
                f"{len(self.refused)} refused)")


def _faults(row: SummaryRow) -> list[str]:
    return list(dict.fromkeys(f[len(_PREFIX):] for f in row.flags if f.startswith(_PREFIX)))


def _order_key(item: tuple[int, SummaryRow]) -> tuple:
    k, row = item
    t = row.time
    if isinstance(t, datetime):
        return (0, local_seconds(t), k)
    if isinstance(t, dtime):  # another clock: not mixed with dated rows
        return (1, seconds_of_day(t), k)
    return (2, 0.0, k)


def refuse_unconfirmed_faults(rows: Sequence[SummaryRow], *, confirm: float = CONFIRM,
                              neighbours: int = NEIGHBOURS) -> FaultCheck:
    """Refuse the weighed rows of gauge faults their neighbours do not confirm (see the
    module docstring)."""
    confirm = float(confirm)
    if not np.isfinite(confirm) or not 0.0 < confirm <= 1.0:
        raise InputError(f"confirm must be a share in (0, 1], got {confirm!r}")
    if isinstance(neighbours, bool) or not isinstance(neighbours, int) or neighbours < 1:
        raise InputError(f"neighbours must be a positive integer, got {neighbours!r}")
    weighed = sorted(((k, r) for k, r in enumerate(rows) if r.status == "weighed"),
                     key=_order_key)
    counts = Counter(g for _, r in weighed for g in _faults(r))
    n = len(weighed)
    if n < neighbours:
        return FaultCheck(rows=tuple(rows), counts=dict(counts), n_weighed=0, refused=(),
                          unconfirmed={})
    faults = [set(_faults(r)) for _, r in weighed]
    doubtful: dict[int, list[tuple[str, int]]] = {}
    for i, (k, _) in enumerate(weighed):
        if not faults[i]:
            continue
        lo = min(max(0, i - neighbours // 2), n - neighbours)
        around = faults[lo:lo + neighbours]
        for g in sorted(faults[i]):
            seen = sum(g in f for f in around)
            if seen < confirm * neighbours:
                doubtful.setdefault(k, []).append((g, seen))
    out, refused, unconfirmed = [], [], Counter()
    for k, r in enumerate(rows):
        if k not in doubtful:
            out.append(r)
            continue
        said = ", ".join(f"{g} in {seen} of the {neighbours} vehicles weighed nearest it"
                         for g, seen in doubtful[k])
        out.append(r.refused(f"a gauge disagreed that the day finds healthy ({said}): "
                             "another vehicle no detector saw loads the gauges",
                             FLAG_UNCONFIRMED))
        refused.append((r.record, r.vehicle))
        unconfirmed.update(g for g, _ in doubtful[k])
    return FaultCheck(rows=tuple(out), counts=dict(counts), n_weighed=n,
                      refused=tuple(refused), unconfirmed=dict(unconfirmed))
