"""A B-WIM installation's chain: detect every vehicle in every lane, calibrate lines from
the calibration truck's runs, weigh the traffic, correct the day's drift, and check every
weight before it leaves.

    setup = bwim.scenario.build_site_setup(scenario)       # lanes, detectors, truck
    site = bwim.site.calibrate_site(runs, setup)           # responses, lines, drift
    event = bwim.site.weigh_event(record, site)            # every vehicle of one event
    day = bwim.site.finish_day(rows, site)                 # the day's checks and drift

Contract
--------
* :mod:`bwim.site.setup`: what the installation knows (:class:`SiteSetup`,
  :class:`DetectorLane`, :class:`Lane`).
* :mod:`bwim.site.calibrate`: :func:`calibrate_site` (:class:`SiteCalibration`).
* :mod:`bwim.site.lanes`: the vehicles of an event in every lane, multiple presence.
* :mod:`bwim.site.event`: :func:`weigh_event` (:class:`EventWeighing`, one
  :class:`VehicleWeighing` per vehicle, each a summary row).
* :mod:`bwim.site.isolate`: the part of a record a vehicle has to itself (vehicles one
  after the other in one file, each detected, weighed and calibrated on its own part).
* :mod:`bwim.site.health`: :func:`check_gauges` (:class:`GaugeHealth`), the gauges of a
  vehicle judged before it is weighed: a faulty one left out (``gauge_fault:NAME``).
* :mod:`bwim.site.drift`: the drift of the strain-to-load ratio from one day to the next
  (temperature, the traffic itself, the time of day); :func:`correct_drift` applies the
  traffic method to a batch's summary rows.
* :mod:`bwim.site.unconfirmed`: a gauge fault the day does not confirm (another vehicle).
* :mod:`bwim.site.wander`: a vehicle's lateral position against its lane's traffic (a
  vehicle beside it no detector saw).
* :mod:`bwim.site.wheelpath`: each axle group's lateral position against its vehicle's
  other groups (an axle of a vehicle beside it weighed as this one's).
* :mod:`bwim.site.speeds`: a counted vehicle whose speed its lane's traffic around it
  does not drive (a trace of another vehicle), left out.
* :mod:`bwim.site.split`: a vehicle split across two records (a logger file closed
  between a truck and its trailer), refused.
* :mod:`bwim.site.day`: :func:`finish_day`, the day-level steps (unconfirmed gauge faults,
  the lanes' lateral check, the axle groups' check, the counted vehicles' speeds, the
  vehicles split across records, then the traffic's drift) on a batch's rows
  (:class:`DayResult`).
"""

from bwim.site.calibrate import (
    SPACING_TOLERANCE,
    STRAIN_ONLY_PASSES,
    SiteCalibration,
    calibrate_site,
)
from bwim.site.day import DayResult, correct_drift, finish_day
from bwim.site.drift import DRIFT_METHODS, DriftSetup, TrafficDrift
from bwim.site.event import EventWeighing, VehicleWeighing, weigh_event
from bwim.site.health import GaugeFault, GaugeHealth, check_gauges
from bwim.site.model import ModelRun, SiteModel, calibrate_site_model
from bwim.site.setup import DETECTION_METHODS, DetectorLane, Lane, SiteSetup
from bwim.site.speeds import SpeedCheck, drop_speed_outliers
from bwim.site.split import SplitCheck, refuse_split_vehicles
from bwim.site.unconfirmed import FaultCheck, refuse_unconfirmed_faults
from bwim.site.wander import LaneWander, WanderCheck, refuse_lateral_outliers
from bwim.site.wheelpath import PathCheck, refuse_off_path

__all__ = [
    "DETECTION_METHODS",
    "DRIFT_METHODS",
    "SPACING_TOLERANCE",
    "STRAIN_ONLY_PASSES",
    "DayResult",
    "DetectorLane",
    "DriftSetup",
    "EventWeighing",
    "FaultCheck",
    "GaugeFault",
    "GaugeHealth",
    "Lane",
    "LaneWander",
    "ModelRun",
    "PathCheck",
    "SiteCalibration",
    "SiteModel",
    "SiteSetup",
    "SpeedCheck",
    "SplitCheck",
    "TrafficDrift",
    "VehicleWeighing",
    "WanderCheck",
    "calibrate_site",
    "calibrate_site_model",
    "check_gauges",
    "correct_drift",
    "drop_speed_outliers",
    "finish_day",
    "refuse_lateral_outliers",
    "refuse_off_path",
    "refuse_split_vehicles",
    "refuse_unconfirmed_faults",
    "weigh_event",
]
