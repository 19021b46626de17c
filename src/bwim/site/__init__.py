"""A B-WIM installation's chain: detect every vehicle in every lane, calibrate lines from
the calibration truck's runs, weigh the traffic, correct the day's drift, and check every
weight before it leaves.

    setup = bwim.scenario.build_site_setup(scenario)       # lanes, detectors, truck
    site = bwim.site.calibrate_site(runs, setup)           # responses, lines, drift
    event = bwim.site.weigh_event(record, site)            # every vehicle of one event
    rows = bwim.site.correct_drift(rows, site)             # the traffic's own reference

Contract
--------
* :mod:`bwim.site.setup`: what the installation knows (:class:`SiteSetup`,
  :class:`DetectorLane`, :class:`Lane`).
* :mod:`bwim.site.calibrate`: :func:`calibrate_site` (:class:`SiteCalibration`).
* :mod:`bwim.site.lanes`: the vehicles of an event in every lane, multiple presence.
* :mod:`bwim.site.event`: :func:`weigh_event` (:class:`EventWeighing`, one
  :class:`VehicleWeighing` per vehicle, each a summary row).
* :mod:`bwim.site.health`: :func:`check_gauges` (:class:`GaugeHealth`), the gauges of a
  vehicle judged before it is weighed: a faulty one left out (``gauge_fault:NAME``).
* :mod:`bwim.site.drift`: the drift of the strain-to-load ratio from one day to the next
  (temperature, the traffic itself, the time of day); :func:`correct_drift` applies the
  traffic method to a batch's summary rows.
"""

from collections.abc import Sequence

from bwim.site.calibrate import (
    SPACING_TOLERANCE,
    STRAIN_ONLY_PASSES,
    SiteCalibration,
    calibrate_site,
)
from bwim.site.drift import (
    DRIFT_METHODS,
    DriftSetup,
    TrafficDrift,
    apply_traffic_drift,
    traffic_drift,
)
from bwim.site.event import EventWeighing, VehicleWeighing, weigh_event
from bwim.site.health import GaugeFault, GaugeHealth, check_gauges
from bwim.site.model import ModelRun, SiteModel, calibrate_site_model
from bwim.site.setup import DETECTION_METHODS, DetectorLane, Lane, SiteSetup
from bwim.summary import SummaryRow

__all__ = [
    "DETECTION_METHODS",
    "DRIFT_METHODS",
    "SPACING_TOLERANCE",
    "STRAIN_ONLY_PASSES",
    "DetectorLane",
    "DriftSetup",
    "EventWeighing",
    "GaugeFault",
    "GaugeHealth",
    "Lane",
    "ModelRun",
    "SiteCalibration",
    "SiteModel",
    "SiteSetup",
    "TrafficDrift",
    "VehicleWeighing",
    "calibrate_site",
    "calibrate_site_model",
    "check_gauges",
    "correct_drift",
    "weigh_event",
]


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
