"""A vehicle's lateral position against its lane's traffic: the day-level check for a
vehicle beside it that no detector saw.

Two vehicles side by side on a slab, one in a lane without axle detectors, load the gauges
like one vehicle of their summed weight at their load centre: with lines whose lateral
dependence is linear in the position (:class:`bwim.wim.MultiRunCalibration`) the two are
the same fit, so neither the misfit nor the gauge check sees the second vehicle.  What
does see it is the load centre: it lies between the two lanes, where no vehicle of the
lane alone drives.  One event cannot say how far a lane's trucks wander (that depends on
the lane, the trucks and how the gauges spread a wheel's load); the day's traffic can.

Contract
--------
* :func:`lane_wander` measures each lane's spread: per ``(lane, direction, lateral unit)``
  over the rows weighed (``status == "weighed"``) with a lateral position, the median
  ``m`` and the robust standard deviation ``σ = 1.4826 × MAD`` (the median absolute
  deviation scaled to a normal σ), in the lateral's own unit (metres or gauge index).
  ``σ`` is at least :data:`SIGMA_FLOOR` of that unit.  A lane with fewer than
  ``min_vehicles`` (:data:`MIN_VEHICLES`) such rows is not measured.
* :func:`refuse_lateral_outliers` refuses every weighed row whose modified z-score
  ``|lateral − m| / σ`` exceeds ``limit`` (:data:`OUTLIER_Z` = 3.5, the outlier rule of
  Iglewicz & Hoaglin 1993 for modified z-scores; docs/theory.md §15): its weights are
  dropped, ``lateral_outlier`` is added to its flags, its quality is ``"reject"`` and its
  reason says where it lies against its lane.  Other rows are returned unchanged, in
  order.  Rows of an unmeasured lane are kept as they are (the per-event reach of
  :data:`bwim.site.event.LATERAL_REACH` still applies to them).
* The spread is measured on the rows as given, the outliers included (the median and
  the MAD ignore a few): one pass, no iteration.  Run it before the traffic's drift
  correction (:func:`bwim.site.finish_day`), so that a refused row does not serve as a
  reference vehicle.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.detect.signals import robust_sigma
from bwim.errors import InputError
from bwim.summary import SummaryRow

__all__ = [
    "FLAG_LATERAL_OUTLIER",
    "MIN_VEHICLES",
    "OUTLIER_Z",
    "SIGMA_FLOOR",
    "LaneWander",
    "WanderCheck",
    "lane_wander",
    "refuse_lateral_outliers",
]

#: The modified z-score beyond which a vehicle's lateral position is an outlier of its lane
#: (Iglewicz & Hoaglin 1993: |0.6745 (x − median) / MAD| > 3.5).
OUTLIER_Z = 3.5
#: Rows with a lateral position a lane needs before its spread is measured: fewer give a
#: MAD too uncertain to refuse a weight on.
MIN_VEHICLES = 30
#: The smallest σ used, in the lateral's unit (m or gauge index): a lane of identical
#: positions (a simulation without wander) does not make every rounding an outlier.
SIGMA_FLOOR = 0.02
#: The flag of a row refused here.
FLAG_LATERAL_OUTLIER = "lateral_outlier"


@dataclass(frozen=True, kw_only=True)
class LaneWander:
    """One lane's spread of lateral positions over a batch.

    Attributes
    ----------
    lane : int or None
    direction : str
    unit : str
        ``"m"`` or ``"gauge index"`` (that of the rows' ``lateral``).
    median, sigma : float
        Median and robust σ (1.4826 × MAD, at least :data:`SIGMA_FLOOR`), in ``unit``.
    n : int
        Rows measured.
    """

    lane: int | None
    direction: str
    unit: str
    median: float
    sigma: float
    n: int

    def z(self, lateral: float) -> float:
        """The modified z-score of a lateral position (signed, in σ)."""
        return (float(lateral) - self.median) / self.sigma


@dataclass(frozen=True, kw_only=True, eq=False)
class WanderCheck:
    """The rows after :func:`refuse_lateral_outliers`.

    Attributes
    ----------
    rows : tuple of SummaryRow
        Every input row, in order; the outliers refused.
    lanes : tuple of LaneWander
        The lanes measured.
    refused : tuple of (str, int)
        ``(record, vehicle)`` of the rows refused here.
    limit : float
        The modified z-score used.
    """

    rows: tuple[SummaryRow, ...]
    lanes: tuple[LaneWander, ...]
    refused: tuple[tuple[str, int], ...]
    limit: float

    def __repr__(self) -> str:
        return (f"WanderCheck({len(self.rows)} rows, {len(self.lanes)} lane(s) measured, "
                f"{len(self.refused)} refused beyond {self.limit} σ)")


def _key(row: SummaryRow) -> tuple[int | None, str, str]:
    return (row.lane, row.direction, row.lateral_unit)


def _measurable(row: SummaryRow) -> bool:
    return row.status == "weighed" and row.lateral is not None and bool(row.lateral_unit)


def lane_wander(rows: Sequence[SummaryRow], *, min_vehicles: int = MIN_VEHICLES
                ) -> tuple[LaneWander, ...]:
    """Each lane's median lateral position and robust σ (see the module docstring)."""
    if isinstance(min_vehicles, bool) or not isinstance(min_vehicles, int) \
            or min_vehicles < 3:
        raise InputError(f"min_vehicles must be an integer >= 3, got {min_vehicles!r}")
    by_lane: dict[tuple[int | None, str, str], list[float]] = {}
    for r in rows:
        if _measurable(r):
            by_lane.setdefault(_key(r), []).append(float(r.lateral))
    out = []
    for (lane, direction, unit), values in by_lane.items():
        if len(values) < min_vehicles:
            continue
        y = np.asarray(values)
        out.append(LaneWander(lane=lane, direction=direction, unit=unit,
                              median=float(np.median(y)),
                              sigma=max(robust_sigma(y), SIGMA_FLOOR), n=y.size))
    return tuple(sorted(out, key=lambda w: (w.lane is None, w.lane or 0, w.direction,
                                            w.unit)))


def _refused(row: SummaryRow, lane: LaneWander, z: float) -> SummaryRow:
    unit = " m" if lane.unit == "m" else " (gauge index)"
    reason = (f"its lateral position {row.lateral:.2f}{unit} lies {abs(z):.1f} robust σ "
              f"from its lane's traffic (median {lane.median:.2f}, σ {lane.sigma:.2f} over "
              f"{lane.n} vehicles): a vehicle beside it no detector saw, or out of its lane")
    return row.refused(reason, FLAG_LATERAL_OUTLIER)


def refuse_lateral_outliers(rows: Sequence[SummaryRow], *, limit: float = OUTLIER_Z,
                            min_vehicles: int = MIN_VEHICLES) -> WanderCheck:
    """Refuse the weighed rows whose lateral position is an outlier of their lane's
    traffic (see the module docstring)."""
    limit = float(limit)
    if not np.isfinite(limit) or limit <= 0:
        raise InputError(f"limit must be a positive number of σ, got {limit!r}")
    lanes = lane_wander(rows, min_vehicles=min_vehicles)
    by_key = {(w.lane, w.direction, w.unit): w for w in lanes}
    out, refused = [], []
    for r in rows:
        lane = by_key.get(_key(r)) if _measurable(r) else None
        if lane is not None and abs(z := lane.z(r.lateral)) > limit:
            out.append(_refused(r, lane, z))
            refused.append((r.record, r.vehicle))
        else:
            out.append(r)
    return WanderCheck(rows=tuple(out), lanes=lanes, refused=tuple(refused), limit=limit)
