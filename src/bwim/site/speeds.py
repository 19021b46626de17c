"""A vehicle counted at a speed its lane's traffic around it does not drive: a trace of
another vehicle, left out of the day's count.

A detector pair feels more than its own lane's axles: the span's bending under a truck in
another lane, and that truck's own axles, reach it too.  Each event's detection leaves
out what it can tell is such a trace (:mod:`bwim.site.lanes`, :mod:`bwim.site.bending`);
what it cannot tell comes out as a vehicle of its own whose "axles" are humps of the
bending or the other truck's axles paired across the two detectors in the wrong order,
and whose speed is therefore far from any speed the lane's traffic drives at that time
(the humps of a truck's bending read as a vehicle at walking pace, another truck's axles
paired a group apart as one at 130 km/h).  One event cannot say what speed the lane
drives; the vehicles counted around it in time can, congestion included (a queue slows
every vehicle around it).

Contract
--------
* :func:`drop_speed_outliers` judges every row that is **not weighed** (counted, or
  refused: the lines weighed nothing from it, so no weight is lost) and has a speed, a
  time and a direction, against the ``neighbours`` (:data:`NEIGHBOURS`) other such rows
  nearest in time of the same lane and direction (weighed ones included): the median
  ``m`` of their speeds and their robust σ (1.4826 × MAD, at least :data:`SIGMA_FLOOR`
  × m).  A row whose ``|speed − m| / σ`` exceeds ``limit`` (:data:`SPEED_Z`) is left out
  of the rows (it is no vehicle); the others are returned unchanged, in order.  A lane
  and direction with fewer than ``min_vehicles`` (:data:`bwim.site.wander.MIN_VEHICLES`)
  rows with a speed and a time is not judged.
* A record every row of which is left out keeps one row in their place: ``"refused"``,
  no vehicle, its first left-out row's time, the left-out rows' flags, reason
  :data:`NO_VEHICLE` (a summary has a row for every record it was given).
* A weighed row flagged ``multiple_presence`` whose record holds no other row once the
  left-out ones are gone loses that flag: the site chain weighs a vehicle with another on
  the span only when the other travels the other way (:mod:`bwim.site.event`), and here
  every such other was a trace, no vehicle.  Its quality is made again from its flags
  (:func:`bwim.plausibility.quality_of`; a row weighed by MFI keeps its quality, which
  the identification's own may set).
* Times: a row's ``time`` (datetime, or a clock time of day; rows of the two kinds are
  judged apart, each against its own kind).  Speeds in m/s.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, time

import numpy as np

from bwim.detect.result import FLAG_MULTIPLE_PRESENCE
from bwim.detect.signals import robust_sigma
from bwim.errors import InputError
from bwim.plausibility import quality_of
from bwim.records import local_seconds, seconds_of_day
from bwim.site.wander import MIN_VEHICLES
from bwim.summary import SummaryRow

__all__ = ["NEIGHBOURS", "NO_VEHICLE", "SIGMA_FLOOR", "SPEED_Z", "SpeedCheck",
           "drop_speed_outliers"]

#: The reason of the row a record keeps when every vehicle read in it was left out as a
#: trace (what was read may also be a vehicle of its own misread: none is counted).
NO_VEHICLE = ("not counted: every vehicle read in it was left out as a trace of another "
              "vehicle (its speed far from its lane's traffic around it)")

#: The vehicles of the same lane and direction nearest in time that a vehicle's speed is
#: judged against (about the traffic of a few minutes on a busy road).
NEIGHBOURS = 30
#: The modified z-score beyond which a counted vehicle's speed is a trace's.  Higher than
#: the 3.5 of Iglewicz & Hoaglin (1993): a vehicle that is truly slow or fast among
#: its neighbours loses its count when left out, and these speeds are not normal (each
#: vehicle keeps its own); benchmarks/bench_realsite.py prints what is left out.
SPEED_Z = 5.0
#: The smallest σ, as a share of the median speed (traffic of one speed, in a simulation).
SIGMA_FLOOR = 0.02


@dataclass(frozen=True, kw_only=True, eq=False)
class SpeedCheck:
    """The rows after :func:`drop_speed_outliers`.

    Attributes
    ----------
    rows : tuple of SummaryRow
        The input rows less those left out, in order (a record left without a row keeps
        one, refused with :data:`NO_VEHICLE`, where its first row was).
    dropped : tuple of SummaryRow
        The rows left out, in order.
    limit : float
        The modified z-score used.
    """

    rows: tuple[SummaryRow, ...]
    dropped: tuple[SummaryRow, ...]
    limit: float

    def __repr__(self) -> str:
        return (f"SpeedCheck({len(self.rows)} rows, {len(self.dropped)} left out beyond "
                f"{self.limit} σ)")


def _seconds(t: datetime | time) -> float:
    if isinstance(t, datetime):
        return local_seconds(t)
    return seconds_of_day(t)


def _usable(row: SummaryRow) -> bool:
    return (row.status != "failed" and row.speed is not None and row.time is not None
            and bool(row.direction))


def drop_speed_outliers(rows: Sequence[SummaryRow], *, limit: float = SPEED_Z,
                        neighbours: int = NEIGHBOURS,
                        min_vehicles: int = MIN_VEHICLES) -> SpeedCheck:
    """Leave out the counted vehicles whose speed is an outlier of their lane's traffic
    around them in time (see the module docstring)."""
    limit = float(limit)
    if not np.isfinite(limit) or limit <= 0:
        raise InputError(f"limit must be a positive number of σ, got {limit!r}")
    for name, value, low in (("neighbours", neighbours, 3), ("min_vehicles", min_vehicles, 3)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
    groups: dict[tuple[int | None, str, bool], list[int]] = {}
    for k, r in enumerate(rows):
        if _usable(r):  # dates and clock times of day are not ordered together
            groups.setdefault((r.lane, r.direction, isinstance(r.time, datetime)),
                              []).append(k)
    drop: set[int] = set()
    for members in groups.values():
        if len(members) < max(min_vehicles, 2):
            continue
        idx = np.asarray(members)
        t = np.array([_seconds(rows[k].time) for k in idx])
        v = np.array([float(rows[k].speed) for k in idx])
        n = min(neighbours, idx.size - 1)
        for j, k in enumerate(idx):
            if rows[k].weighed:
                continue
            gap = np.abs(t - t[j])
            gap[j] = np.inf
            near = np.argsort(gap, kind="stable")[:n]
            m = float(np.median(v[near]))
            sigma = max(robust_sigma(v[near]), SIGMA_FLOOR * abs(m))
            if sigma > 0 and abs(v[j] - m) / sigma > limit:
                drop.add(int(k))
    dropped = tuple(rows[k] for k in sorted(drop))
    traced = {r.record for r in dropped}
    left = Counter(r.record for k, r in enumerate(rows) if k not in drop)
    kept, emptied = [], set()
    for k, r in enumerate(rows):
        if k not in drop:
            kept.append(_alone(r) if (r.record in traced and left[r.record] == 1 and r.weighed
                                      and FLAG_MULTIPLE_PRESENCE in r.flags) else r)
        elif left[r.record] == 0 and r.record not in emptied:
            # every row of the record was a trace: the record keeps one row, which says so
            # (with the left-out rows' flags)
            emptied.add(r.record)
            flags = dict.fromkeys(f for d in dropped if d.record == r.record for f in d.flags)
            kept.append(SummaryRow(record=r.record, status="refused", time=r.time,
                                   flags=tuple(flags), reason=NO_VEHICLE))
    return SpeedCheck(rows=tuple(kept), dropped=dropped, limit=limit)


def _alone(row: SummaryRow) -> SummaryRow:
    """``row`` without ``multiple_presence`` (its only other vehicles were traces)."""
    flags = tuple(f for f in row.flags if f != FLAG_MULTIPLE_PRESENCE)
    quality = row.quality if row.method == "mfi" else quality_of(flags)
    return dataclasses.replace(row, flags=flags, quality=quality)
