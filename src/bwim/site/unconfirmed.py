"""A gauge fault the day does not confirm: another vehicle, not a faulty gauge.

The gauge check of one event (:mod:`bwim.site.health`) leaves out a gauge that disagrees
with what the others predict and weighs the vehicle without it (``gauge_fault:NAME``).
A faulty gauge disagrees in most of the day's vehicles.  A healthy gauge disagrees only
when something the lines do not model loads it: most often a vehicle that no detector
saw in the lane next to it (the far gauges read it, the lines of the weighed vehicle do
not), whose strain the other gauges near it still carry into the weights.

Contract
--------
* :func:`refuse_unconfirmed_faults` counts, over a batch's rows weighed
  (``status == "weighed"``), how many carry ``gauge_fault:NAME`` for each gauge.  A
  gauge flagged in at least ``confirm`` (:data:`CONFIRM`) of them is **confirmed**
  faulty: its rows keep their weights.  A gauge flagged in fewer is not: each weighed
  row that carries its flag is refused (weights dropped, ``unconfirmed_gauge_fault``
  added to its flags, quality ``"reject"``, a reason naming the gauge and the day's
  count).  With fewer than ``min_vehicles`` (:data:`MIN_VEHICLES`) weighed rows the day
  cannot judge: every row is kept.
* A gauge that is faulty only now and then (clipping under the heaviest trucks, a loose
  connector) is not confirmed either: its vehicles are refused rather than weighed with
  a fault no day confirms (a refused weight is never a wrong one).
* Rows other than weighed ones are returned unchanged, in order.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.summary import SummaryRow

__all__ = ["CONFIRM", "FLAG_UNCONFIRMED", "MIN_VEHICLES", "FaultCheck",
           "refuse_unconfirmed_faults"]

#: The share of a day's weighed vehicles in which a gauge must be found faulty for its
#: fault to be the gauge's own: most of them.
CONFIRM = 0.5
#: Weighed rows a day needs before it judges a gauge's faults.
MIN_VEHICLES = 30
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
        Weighed rows flagged faulty per gauge.
    n_weighed : int
        Weighed rows judged (0 when fewer than ``min_vehicles``: not judged).
    confirmed : tuple of str
        Gauges whose faults the day confirms.
    refused : tuple of (str, int)
        ``(record, vehicle)`` of the rows refused here.
    """

    rows: tuple[SummaryRow, ...]
    counts: dict[str, int]
    n_weighed: int
    confirmed: tuple[str, ...]
    refused: tuple[tuple[str, int], ...]

    def __repr__(self) -> str:
        return (f"FaultCheck({len(self.rows)} rows, {self.n_weighed} weighed judged, "
                f"confirmed {list(self.confirmed)}, {len(self.refused)} refused)")


def _faults(row: SummaryRow) -> list[str]:
    return [f[len(_PREFIX):] for f in row.flags if f.startswith(_PREFIX)]


def refuse_unconfirmed_faults(rows: Sequence[SummaryRow], *, confirm: float = CONFIRM,
                              min_vehicles: int = MIN_VEHICLES) -> FaultCheck:
    """Refuse the weighed rows of gauge faults the day does not confirm (see the module
    docstring)."""
    confirm = float(confirm)
    if not np.isfinite(confirm) or not 0.0 < confirm <= 1.0:
        raise InputError(f"confirm must be a share in (0, 1], got {confirm!r}")
    if isinstance(min_vehicles, bool) or not isinstance(min_vehicles, int) \
            or min_vehicles < 1:
        raise InputError(f"min_vehicles must be a positive integer, got {min_vehicles!r}")
    weighed = [r for r in rows if r.status == "weighed"]
    counts = Counter(g for r in weighed for g in dict.fromkeys(_faults(r)))
    if len(weighed) < min_vehicles:
        return FaultCheck(rows=tuple(rows), counts=dict(counts), n_weighed=0,
                          confirmed=tuple(sorted(counts)), refused=())
    n = len(weighed)
    confirmed = tuple(sorted(g for g, k in counts.items() if k >= confirm * n))
    out, refused = [], []
    for r in rows:
        doubtful = [g for g in _faults(r) if g not in confirmed] if r.status == "weighed" \
            else []
        if not doubtful:
            out.append(r)
            continue
        said = ", ".join(f"{g} in {counts[g]} of {n}" for g in doubtful)
        out.append(dataclasses.replace(
            r, status="refused", axle_weights=(), group_weights=(), gvw=None,
            flags=tuple(dict.fromkeys([*r.flags, FLAG_UNCONFIRMED])), quality="reject",
            reason=f"a gauge disagreed that the day finds healthy ({said} vehicles "
                   "weighed): another vehicle no detector saw loads the gauges"))
        refused.append((r.record, r.vehicle))
    return FaultCheck(rows=tuple(out), counts=dict(counts), n_weighed=n,
                      confirmed=confirmed, refused=tuple(refused))
