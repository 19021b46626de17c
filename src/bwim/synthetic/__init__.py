"""Synthetic installations: simulated B-WIM data written as a real site's files.

Contract
--------
An upper layer like :mod:`bwim.paper`: it uses the core (FE, vehicles, dynamics) and
:mod:`bwim.io` for writing; nothing in the core imports it.  :func:`make_test_day` writes a
whole test day (logger files, scenario, reference weights, truth) to a folder; see
:mod:`bwim.synthetic.testday` for the layout and :mod:`bwim.synthetic.site` /
:mod:`bwim.synthetic.traffic` for the bridge, sensors and trucks.
"""

from bwim.synthetic.site import Drift, site_bridge
from bwim.synthetic.testday import COLUMNS, Event, TestDay, VehicleTruth, make_test_day
from bwim.synthetic.traffic import TRUCK_KINDS, calibration_truck, random_truck

__all__ = [
    "COLUMNS",
    "TRUCK_KINDS",
    "Drift",
    "Event",
    "TestDay",
    "VehicleTruth",
    "calibration_truck",
    "make_test_day",
    "random_truck",
    "site_bridge",
]
