"""The day-level steps of a batch of events: what one event cannot decide alone.

Contract
--------
* :func:`finish_day` takes every summary row of a batch (as :func:`bwim.site.weigh_event`
  made them) and applies, in this order:

  1. the gauges' faults the day does not confirm
     (:func:`bwim.site.unconfirmed.refuse_unconfirmed_faults`): a weighed vehicle with a
     gauge left out that is healthy in most of the vehicles weighed around it is
     refused (``unconfirmed_gauge_fault``: another vehicle loaded it);
  2. the lanes' lateral check (:func:`bwim.site.wander.refuse_lateral_outliers`): a
     weighed vehicle whose lateral position is an outlier of its lane's traffic is
     refused (``lateral_outlier``);
  3. the axle groups' check (:func:`bwim.site.wheelpath.refuse_off_path`): a weighed
     vehicle one of whose axle groups lies off its wheel path, against the lane's
     traffic, is refused (``group_off_path``: an axle of a vehicle beside it);
  4. the counted vehicles' speeds (:func:`bwim.site.speeds.drop_speed_outliers`): a
     vehicle not weighed whose speed is far from its lane's traffic around it in time
     is a trace of another vehicle (the span's bending, another truck's axles), and is
     left out of the rows (a record left without a row keeps one, refused, that says
     so);
  5. the vehicles split across two records (:func:`bwim.site.split.refuse_split_vehicles`):
     two vehicles of one lane and direction from two records, the rear one's first axle
     closer to the front one's last than two vehicles following each other can be, are
     parts of one vehicle (a logger file closed between a truck and its trailer): a
     weighed part is refused (``split_across_records``); after step 4, so that a trace
     it left out does not make a vehicle's neighbour;
  6. the traffic's own drift correction where the setup asks for it
     (:func:`correct_drift`), on the rows the steps before kept weighed.

  It returns a :class:`DayResult` (the rows, in order, less those step 4 left out, and
  what each step measured).
  ``bwim weigh`` runs it on the final summary; the benchmarks run it the same way.
* :func:`correct_drift` alone is the sixth step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from bwim.site.calibrate import SiteCalibration
from bwim.site.drift import TrafficDrift, apply_traffic_drift, traffic_drift
from bwim.site.speeds import SpeedCheck, drop_speed_outliers
from bwim.site.split import SplitCheck, refuse_split_vehicles
from bwim.site.unconfirmed import FaultCheck, refuse_unconfirmed_faults
from bwim.site.wander import WanderCheck, refuse_lateral_outliers
from bwim.site.wheelpath import PathCheck, refuse_off_path
from bwim.summary import SummaryRow

__all__ = ["DayResult", "correct_drift", "finish_day"]


@dataclass(frozen=True, kw_only=True, eq=False)
class DayResult:
    """A batch's rows after the day-level steps.

    Attributes
    ----------
    rows : tuple of SummaryRow
        Every row, in the input's order, less the traces ``speeds`` left out (each
        record keeps a row).
    faults : FaultCheck
        The day's count of each gauge's faults and the rows refused for faults it does
        not confirm.
    wander : WanderCheck
        The lanes' lateral spreads and the rows refused as outliers of them.
    paths : PathCheck
        The spreads of the axle groups' positions and the rows refused for a group off
        its vehicle's path.
    speeds : SpeedCheck
        The counted vehicles left out as traces (speed outliers of their lane).
    split : SplitCheck
        The vehicles found split across two records, and the rows refused for it.
    drift : TrafficDrift or None
        The traffic's drift fit; None when the traffic method was not applied.
    """

    rows: tuple[SummaryRow, ...]
    faults: FaultCheck
    wander: WanderCheck
    paths: PathCheck
    speeds: SpeedCheck
    split: SplitCheck
    drift: TrafficDrift | None

    def __repr__(self) -> str:
        drift = "none" if self.drift is None else f"traffic ({self.drift.reference_class})"
        return (f"DayResult({len(self.rows)} rows, {self.faults!r}, {self.wander!r}, "
                f"{self.paths!r}, {self.speeds!r}, {self.split!r}, drift {drift})")


def correct_drift(rows: Sequence[SummaryRow], calibration: SiteCalibration
                  ) -> tuple[list[SummaryRow], TrafficDrift | None]:
    """A batch's rows with the traffic method's drift correction where the setup asks for
    it (``"traffic"``, or ``"auto"`` without a temperature model) and the traffic allows
    it (:func:`bwim.site.drift.traffic_drift`); the rows as they are otherwise.  Returns
    the rows and the fit (None when not applied)."""
    setup = calibration.setup.drift
    if setup.method not in ("traffic", "auto") or (
            setup.method == "auto" and calibration.temperature is not None):
        return list(rows), None
    tod = calibration.time_of_day
    fit = traffic_drift(rows, setup, calibration=tod,
                        calibration_span=None if tod is None else tod.trend.span)
    if fit is None:
        return list(rows), None
    return apply_traffic_drift(rows, fit), fit


def finish_day(rows: Sequence[SummaryRow], calibration: SiteCalibration) -> DayResult:
    """The day-level steps on a batch's rows (see the module docstring)."""
    faults = refuse_unconfirmed_faults(rows)
    wander = refuse_lateral_outliers(faults.rows)
    paths = refuse_off_path(wander.rows)
    speeds = drop_speed_outliers(paths.rows)
    split = refuse_split_vehicles(speeds.rows)
    out, fit = correct_drift(split.rows, calibration)
    return DayResult(rows=tuple(out), faults=faults, wander=wander, paths=paths,
                     speeds=speeds, split=split, drift=fit)
