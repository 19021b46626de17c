"""Synthetic installations: simulated B-WIM data written as a real site's files.

Contract
--------
An upper layer like :mod:`bwim.paper`: it uses the core (FE, vehicles, dynamics) and
:mod:`bwim.io` for writing; nothing in the core imports it.  :func:`make_test_day` writes a
site's test data (logger files, scenario, reference weights, truth) to a folder; ``site``
picks a preset: ``basic-2-lane`` (the default; :mod:`bwim.synthetic.testday`,
:mod:`bwim.synthetic.site`, :mod:`bwim.synthetic.traffic`) or the realistic
``short-span-4-lane`` (a calibration date and a traffic date:
:mod:`bwim.synthetic.sitedays`; the site as data: :mod:`bwim.synthetic.layout`; its axle
detectors: :mod:`bwim.synthetic.detector`; drift: :mod:`bwim.synthetic.thermal`; traffic:
:mod:`bwim.synthetic.fleet`).
"""

from bwim.synthetic.continuous import ContinuousRecording, Placement, make_continuous
from bwim.synthetic.detector import DetectorResponse
from bwim.synthetic.fleet import FLEET_KINDS, TrafficVehicle, traffic_vehicle
from bwim.synthetic.layout import (
    SHORT_SPAN_4_LANE,
    AxleDetector,
    Gauge,
    Joint,
    Lane,
    SiteLayout,
)
from bwim.synthetic.site import Drift, site_bridge
from bwim.synthetic.sitedays import (
    SITE_DAYS_VERSION,
    SiteDays,
    SiteEvent,
    VehicleRun,
    make_site_days,
)
from bwim.synthetic.testday import (
    COLUMNS,
    SITE_NAMES,
    Event,
    TestDay,
    VehicleTruth,
    basic_test_day,
    make_test_day,
)
from bwim.synthetic.thermal import DeckTemperature, ThermalDrift
from bwim.synthetic.traffic import TRUCK_KINDS, calibration_truck, random_truck

__all__ = [
    "COLUMNS",
    "FLEET_KINDS",
    "SHORT_SPAN_4_LANE",
    "SITE_DAYS_VERSION",
    "SITE_NAMES",
    "TRUCK_KINDS",
    "AxleDetector",
    "ContinuousRecording",
    "DeckTemperature",
    "DetectorResponse",
    "Drift",
    "Event",
    "Gauge",
    "Joint",
    "Lane",
    "Placement",
    "SiteDays",
    "SiteEvent",
    "SiteLayout",
    "TestDay",
    "ThermalDrift",
    "TrafficVehicle",
    "VehicleRun",
    "VehicleTruth",
    "basic_test_day",
    "calibration_truck",
    "make_continuous",
    "make_site_days",
    "make_test_day",
    "random_truck",
    "site_bridge",
    "traffic_vehicle",
]
