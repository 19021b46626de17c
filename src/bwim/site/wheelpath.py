"""An axle group off its vehicle's wheel path: the check for an axle of another vehicle
weighed as this vehicle's.

All axles of one vehicle follow one wheel path (on a straight road an articulated
vehicle's trailer tracks its tractor within centimetres).  A vehicle's lateral position,
one number for the whole vehicle, cannot show two things that break that: an axle of a
vehicle in the next lane that this lane's detectors felt and counted as this vehicle's
(it pulls that one "axle" towards the other lane), and a vehicle beside it that no
detector saw, abreast of some of its axles only (it pulls those).  The lines weigh both
as one vehicle, and the load centre of the whole stays inside the lane's spread
(:mod:`bwim.site.wander`), so neither the fit nor the lane check sees them.  The
positions of the vehicle's axle groups, taken one at a time, do.

Contract
--------
* :func:`group_laterals` measures the lateral position of each axle group of a detected
  vehicle (groups: consecutive axles closer than ``group_spacing``, m, default
  :data:`bwim.classify.DEFAULT_GROUP_SPACING`, as :func:`bwim.wim.group_axles` and the
  weighing group them): the section gauges' load centroid
  (:func:`bwim.detect.lateral.lateral_position`, peak weights, its default threshold)
  over a short window around the record time at which the group's centre crosses the
  gauge line.  The window's half-width is the smaller of :data:`HALF_WINDOW` (m) and a
  quarter of the gap to the nearest axle of a neighbouring group, in time at the
  vehicle's speed.  The gauge line is ``gauge_line`` (m, in the passages' frame; for
  lines, :func:`gauge_line` gives it), the quiet level of each gauge its median outside
  ``window`` (the vehicle's time on the span; when less than a tenth of the record lies
  outside it, or without ``window``, that of ``lateral_position``'s default).  Unit: that of
  :func:`~bwim.detect.lateral.lateral_position` (m, else gauge index).  Empty when a
  group's window lies outside the record or no gauge responded.
* The groups' positions differ, for a vehicle alone, only by how each group's tyres
  spread its load over the gauges (a single-tyred steering axle against a tridem of
  wide tyres), which is alike from one vehicle to the next.  :func:`deviations` gives,
  per group, its position less the mean of the other groups' (a row with fewer than two
  groups has none), with its role: ``"first"``, ``"middle"`` or ``"last"``.
* :func:`refuse_off_path` is the day-level check: per ``(lane, direction, lateral unit,
  role)`` over the weighed rows with group positions, the median and robust σ (1.4826 ×
  MAD, at least :data:`bwim.site.wander.SIGMA_FLOOR`; at least ``min_vehicles`` rows,
  :data:`bwim.site.wander.MIN_VEHICLES`) of the deviations; a weighed row any of whose
  groups lies beyond ``limit`` robust σ (:data:`OFF_PATH_Z`) is refused, flagged
  ``group_off_path`` (:data:`FLAG_GROUP_OFF_PATH`), its reason naming the group
  furthest off (in the lateral's unit) of those beyond the limit.  Other
  rows are returned unchanged, in order.
* Limits: on a span long enough that several groups load the gauge line at once, each
  group's window also sees its neighbours, the groups' positions are pulled together
  and the check loses power; it does not refuse more.  A vehicle that changes lanes on
  the bridge is refused too: one lateral position cannot weigh it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.classify import DEFAULT_GROUP_SPACING
from bwim.detect.lateral import lateral_position, lateral_positions, section_gauges
from bwim.detect.signals import robust_sigma
from bwim.errors import InputError, require_positive
from bwim.records import Passage, Record
from bwim.site.wander import MIN_VEHICLES, SIGMA_FLOOR
from bwim.summary import SummaryRow
from bwim.wim import MultiRunCalibration, group_axles

__all__ = [
    "FLAG_GROUP_OFF_PATH",
    "HALF_WINDOW",
    "OFF_PATH_Z",
    "GroupSpread",
    "PathCheck",
    "deviations",
    "gauge_line",
    "group_laterals",
    "refuse_off_path",
]

#: The flag of a row refused here.
FLAG_GROUP_OFF_PATH = "group_off_path"
#: m: the largest half-width of a group's window (its peak is where the group is over the
#: gauge line; a wider window only lets its neighbours in).
HALF_WINDOW = 0.6
#: The modified z-score (robust σ of the lane's traffic) beyond which a group is off its
#: vehicle's path.  Not the 3.5 of Iglewicz & Hoaglin (1993) for normal data: the groups'
#: deviations have heavier tails (a light steering axle's position is noisier, and the
#: tyres' dynamic loads move each group's peak), and a vehicle alone reaches about 6 σ
#: (benchmarks/bench_realsite.py prints the refusals of vehicles alone and of pairs).
OFF_PATH_Z = 6.0
#: The roles of a group in its vehicle.
ROLES = ("first", "middle", "last")


def gauge_line(lines: MultiRunCalibration) -> float:
    """x (m, in the passages' frame) of the gauge line: the median over the channels of
    the position of each channel's largest ordinate (in magnitude) at the lines' mean
    lateral position."""
    x = lines.line.x  # the lines at their mean lateral position (lines.line_at()'s)
    ords = np.abs(np.asarray(lines.ordinates_at(lines.lateral_center), dtype=float))
    at = sorted(x[np.argmax(ords.reshape(x.size, -1), axis=0)].tolist())
    n = len(at)  # their median, numpy.median's number: the middle one or two, their mean
    if n == 0:
        return float("nan")
    return 0.0 + at[n // 2] if n % 2 else ((0.0 + at[n // 2 - 1]) + at[n // 2]) / 2.0


def group_laterals(record: Record, passage: Passage, *, gauge_line: float,
                   window: tuple[float, float] | None = None,
                   gauges: Sequence[str] | None = None,
                   group_spacing: float = DEFAULT_GROUP_SPACING) -> tuple[float, ...]:
    """Each axle group's lateral position (see the module docstring), in order."""
    if not isinstance(record, Record):
        raise InputError(f"record must be a bwim.Record, got {type(record).__name__}")
    if not isinstance(passage, Passage):
        raise InputError(f"passage must be a bwim.Passage, got {type(passage).__name__}")
    group_spacing = require_positive("group_spacing", group_spacing)
    x_line = float(gauge_line)
    if not np.isfinite(x_line):
        raise InputError(f"gauge_line must be finite, got {gauge_line!r}")
    t = record.time
    offsets = passage.axle_offsets
    groups = [list(g) for g in group_axles(passage, group_spacing)]
    quiet = None
    if window is not None:
        quiet = (t < window[0]) | (t > window[1])
        if quiet.sum() < max(3, t.size // 10):
            quiet = None
    windows = []
    t_first, t_last = float(t[0]), float(t[-1])
    off = offsets.tolist()  # the same numbers as Python floats
    for k, g in enumerate(groups):
        vals = [off[i] for i in g]
        # numpy.mean's number: below 8 values numpy adds them one after the other (the
        # offsets are 0 or positive: as Python's sum), else its pairwise sum
        centre = sum(vals) / len(vals) if len(vals) < 8 else float(np.mean(offsets[g]))
        gaps = []
        if k > 0:
            gaps.append(off[g[0]] - off[groups[k - 1][-1]])
        if k + 1 < len(groups):
            gaps.append(off[groups[k + 1][0]] - off[g[-1]])
        half = min([HALF_WINDOW, *(0.25 * gp for gp in gaps)]) / passage.speed
        tg = passage.delay + (x_line + centre) / passage.speed
        if tg - half < t_first or tg + half > t_last:
            if windows:  # the groups before it were measured: a gauge it lacks is named
                section_gauges(record, gauges)
            return ()
        windows.append((tg - half, tg + half))
    if quiet is not None:  # one quiet mask: the gauges read and their levels taken once
        found = lateral_positions(record, windows, quiet=quiet, gauges=gauges)
    else:  # each group's own quiet samples (lateral_position's default)
        found = [lateral_position(record, window=w, gauges=gauges) for w in windows]
    out = []
    for p in found:
        if not np.isfinite(p.value):
            return ()
        out.append(float(p.value))
    return tuple(out)


def deviations(group_laterals: Sequence[float]) -> tuple[tuple[str, float], ...]:
    """``(role, deviation)`` per group: its position less the mean of the others'."""
    y = np.asarray(group_laterals, dtype=float)
    n = y.size
    if n < 2:
        return ()
    others = (y.sum() - y) / (n - 1)
    roles = ["first", *(["middle"] * (n - 2)), "last"]
    return tuple((r, float(d)) for r, d in zip(roles, y - others, strict=True))


@dataclass(frozen=True, kw_only=True)
class GroupSpread:
    """The spread of one group role's deviations in one lane over a batch.

    Attributes
    ----------
    lane : int or None
    direction : str
    unit : str
        ``"m"`` or ``"gauge index"``.
    role : str
        ``"first"``, ``"middle"`` or ``"last"``.
    median, sigma : float
        Median and robust σ of the deviations (at least ``SIGMA_FLOOR``), in ``unit``.
    n : int
        Deviations measured.
    """

    lane: int | None
    direction: str
    unit: str
    role: str
    median: float
    sigma: float
    n: int

    def z(self, deviation: float) -> float:
        """The modified z-score of a deviation (signed, in σ)."""
        return (float(deviation) - self.median) / self.sigma


@dataclass(frozen=True, kw_only=True, eq=False)
class PathCheck:
    """The rows after :func:`refuse_off_path`.

    Attributes
    ----------
    rows : tuple of SummaryRow
        Every input row, in order; those with a group off the path refused.
    spreads : tuple of GroupSpread
        The (lane, role) spreads measured.
    refused : tuple of (str, int)
        ``(record, vehicle)`` of the rows refused here.
    limit : float
        The modified z-score used.
    """

    rows: tuple[SummaryRow, ...]
    spreads: tuple[GroupSpread, ...]
    refused: tuple[tuple[str, int], ...]
    limit: float

    def __repr__(self) -> str:
        return (f"PathCheck({len(self.rows)} rows, {len(self.spreads)} spread(s) measured, "
                f"{len(self.refused)} refused beyond {self.limit} σ)")


def _measurable(row: SummaryRow) -> bool:
    return row.status == "weighed" and len(row.group_laterals) >= 2 and bool(row.lateral_unit)


def _spreads(rows: Sequence[SummaryRow], min_vehicles: int) -> tuple[GroupSpread, ...]:
    by_key: dict[tuple[int | None, str, str, str], list[float]] = {}
    for r in rows:
        if _measurable(r):
            for role, d in deviations(r.group_laterals):
                by_key.setdefault((r.lane, r.direction, r.lateral_unit, role), []).append(d)
    out = []
    for (lane, direction, unit, role), values in by_key.items():
        if len(values) < min_vehicles:
            continue
        d = np.asarray(values)
        out.append(GroupSpread(lane=lane, direction=direction, unit=unit, role=role,
                               median=float(np.median(d)),
                               sigma=max(robust_sigma(d), SIGMA_FLOOR), n=d.size))
    return tuple(sorted(out, key=lambda s: (s.lane is None, s.lane or 0, s.direction,
                                            s.unit, ROLES.index(s.role))))


def _refused(row: SummaryRow, k: int, spread: GroupSpread, d: float, z: float
             ) -> SummaryRow:
    unit = " m" if spread.unit == "m" else " (gauge index)"
    reason = (f"its axle group {k + 1} lies {d:+.2f}{unit} off the vehicle's other groups, "
              f"{abs(z):.1f} robust σ from its lane's traffic (median {spread.median:+.2f}, "
              f"σ {spread.sigma:.2f} over {spread.n} vehicles): an axle of a vehicle beside "
              "it, weighed as this one's")
    return row.refused(reason, FLAG_GROUP_OFF_PATH)


def refuse_off_path(rows: Sequence[SummaryRow], *, limit: float = OFF_PATH_Z,
                    min_vehicles: int = MIN_VEHICLES) -> PathCheck:
    """Refuse the weighed rows with an axle group off their wheel path (see the module
    docstring)."""
    limit = float(limit)
    if not np.isfinite(limit) or limit <= 0:
        raise InputError(f"limit must be a positive number of σ, got {limit!r}")
    if isinstance(min_vehicles, bool) or not isinstance(min_vehicles, int) \
            or min_vehicles < 3:
        raise InputError(f"min_vehicles must be an integer >= 3, got {min_vehicles!r}")
    spreads = _spreads(rows, min_vehicles)
    by_key = {(s.lane, s.direction, s.unit, s.role): s for s in spreads}
    out, refused = [], []
    for r in rows:
        worst = None
        if _measurable(r):
            for k, (role, d) in enumerate(deviations(r.group_laterals)):
                s = by_key.get((r.lane, r.direction, r.lateral_unit, role))
                # the group furthest off names the row (one group off moves the
                # others' deviations the other way, by a share of it)
                if s is not None and abs(z := s.z(d)) > limit and (
                        worst is None or abs(d) > abs(worst[2])):
                    worst = (k, s, d, z)
        if worst is None:
            out.append(r)
        else:
            out.append(_refused(r, *worst))
            refused.append((r.record, r.vehicle))
    return PathCheck(rows=tuple(out), spreads=spreads, refused=tuple(refused), limit=limit)
