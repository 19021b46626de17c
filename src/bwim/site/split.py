"""A vehicle split across two records: the logger closed one file between its axles.

A logger that writes one file per event closes it once the gauges have been quiet for
its post-trigger time.  On a short span a combination whose axles leave a gap longer than
the span (a rigid truck and its drawbar trailer, a tractor and a long semi-trailer's
setback) can leave the span empty long enough: the file is closed after the front part
and a new one opened for the rear.  Each file then holds a vehicle that looks whole (a
truck of three axles, a trailer of two), with an empty span at both its ends, so no
event can tell (``truncated`` needs a loaded end).  The day can: the rear part's first
axle follows the front part's last closer than two vehicles following each other can.

Contract
--------
* :func:`refuse_split_vehicles` takes a batch's rows.  A row takes part when it has a
  clock time (datetime, or a clock time of day: the two kinds are judged apart), a speed,
  axles and a direction (``failed`` rows never).  Per lane and direction, in time order,
  each pair of consecutive rows **from different records** is judged (a record's own
  vehicles were told apart by its detection, :func:`bwim.site.lanes.split_long`): the
  gap (m) between the front row's last axle and the rear row's first,
  ``(t_rear − t_front − L_front / v_front) × v`` (``t``: a row's ``time``, when its first
  axle passes the detectors' reference; ``L``: the sum of its axle spacings; ``v``: the
  mean of both speeds, m/s), against the room two vehicles following each other need,
  ``MIN_OVERHANGS + MIN_HEADWAY × v`` (:data:`bwim.site.lanes.MIN_OVERHANGS`,
  :data:`~bwim.site.lanes.MIN_HEADWAY`: the rule that cuts a record's own vehicles).  A
  gap below it (negative included: records that overlap and hold the same axles) makes
  both rows parts of one vehicle: a weighed one is refused (weights dropped, the flag
  ``split_across_records``, :data:`FLAG_SPLIT`, quality ``"reject"``, a reason naming
  the other record); a row not weighed gets the flag, keeping its status and reason.
* Rows without a clock cannot be placed against each other and are returned unchanged
  (the record's name is no clock).  Every row is returned, in the input's order.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from datetime import time as dtime

from bwim.records import local_seconds, seconds_of_day
from bwim.site.lanes import MIN_HEADWAY, MIN_OVERHANGS
from bwim.summary import SummaryRow

__all__ = ["FLAG_SPLIT", "SplitCheck", "refuse_split_vehicles"]

#: The flag of a row whose vehicle goes on in another record.
FLAG_SPLIT = "split_across_records"


@dataclass(frozen=True, kw_only=True, eq=False)
class SplitCheck:
    """The rows after :func:`refuse_split_vehicles`.

    Attributes
    ----------
    rows : tuple of SummaryRow
        Every input row, in order; the parts of vehicles split across records flagged,
        the weighed ones refused.
    pairs : tuple of ((str, int), (str, int), float)
        Each pair judged one vehicle: the front row's ``(record, vehicle)``, the rear
        row's, and the gap between them (m).
    judged : int
        Pairs of consecutive rows from different records judged.
    refused : tuple of (str, int)
        ``(record, vehicle)`` of the rows refused here (weighed before).
    """

    rows: tuple[SummaryRow, ...]
    pairs: tuple[tuple[tuple[str, int], tuple[str, int], float], ...]
    judged: int
    refused: tuple[tuple[str, int], ...]

    def __repr__(self) -> str:
        return (f"SplitCheck({len(self.rows)} rows, {self.judged} pairs judged, "
                f"{len(self.pairs)} split, {len(self.refused)} refused)")


def _clock(row: SummaryRow) -> tuple[str, float] | None:
    """The row's kind of clock and its time on it (s), or None without one."""
    t = row.time
    if isinstance(t, datetime):
        return "datetime", local_seconds(t)
    if isinstance(t, dtime):
        return "time of day", seconds_of_day(t)
    return None


def _judged(row: SummaryRow) -> bool:
    return (row.status != "failed" and row.direction != "" and row.speed is not None
            and row.speed > 0 and bool(row.n_axles) and _clock(row) is not None)


def refuse_split_vehicles(rows: Sequence[SummaryRow]) -> SplitCheck:
    """Flag and refuse the parts of vehicles split across two records (see the module
    docstring)."""
    streams: dict[tuple, list[tuple[float, int]]] = {}
    for k, r in enumerate(rows):
        if _judged(r):
            kind, t = _clock(r)  # type: ignore[misc]
            streams.setdefault((kind, r.direction, r.lane), []).append((t, k))
    other: dict[int, list[tuple[SummaryRow, float]]] = {}
    pairs, judged = [], 0
    for stream in streams.values():
        stream.sort()
        for (t0, a), (t1, b) in itertools.pairwise(stream):
            front, rear = rows[a], rows[b]
            if front.record == rear.record:
                continue
            judged += 1
            v = 0.5 * (float(front.speed) + float(rear.speed))  # type: ignore[arg-type]
            length = float(sum(front.axle_spacings))
            gap = (t1 - t0 - length / float(front.speed)) * v  # type: ignore[arg-type]
            if gap < MIN_OVERHANGS + MIN_HEADWAY * v:
                pairs.append((front.key, rear.key, gap))
                other.setdefault(a, []).append((rear, gap))
                other.setdefault(b, []).append((front, gap))
    out, refused = list(rows), []
    for k, parts in sorted(other.items()):
        r = rows[k]
        said = "; ".join(f"{p.record} vehicle {p.vehicle}, {gap:.1f} m from it"
                         for p, gap in parts)
        if r.weighed:
            out[k] = r.refused(f"one vehicle across two records ({said}: closer than two "
                               "vehicles following each other can be)", FLAG_SPLIT)
            refused.append(r.key)
        else:
            out[k] = dataclasses.replace(r, flags=tuple(dict.fromkeys([*r.flags,
                                                                       FLAG_SPLIT])))
    return SplitCheck(rows=tuple(out), pairs=tuple(pairs), judged=judged,
                      refused=tuple(refused))
