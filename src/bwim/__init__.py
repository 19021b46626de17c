"""bwim: calibrated, dynamic Bridge Weigh-in-Motion.

The public API is listed in ``__all__``; units, axes and signs are in
:mod:`bwim.conventions`.  This package never imports matplotlib.
"""

from importlib.metadata import PackageNotFoundError, version

from bwim import conventions, dynamics, errors, fe, mfi, optimize, paper, vehicles, wim
from bwim.calibration import Calibration, calibrate
from bwim.dynamics import simulate
from bwim.errors import BwimError, InputError, NumericalError
from bwim.fe import Bridge, Girder, Modes, Supports, composite_section, grid_lines
from bwim.loads import PointLoad
from bwim.mfi import ForceIdentification, force_errors, identify_forces
from bwim.records import Passage, Record, SimulationSettings, Truth
from bwim.road import RoadProfile
from bwim.sensors import Sensor, SensorKind
from bwim.vehicles import HalfCar, MovingForces, SprungMass, TractorSemitrailer, Truck3D
from bwim.wim import (
    InfluenceLine,
    StaticWeights,
    calibrate_influence_line,
    model_influence_line,
    weigh_static,
)

try:
    __version__ = version("bwim")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

__all__ = [
    "Bridge",
    "BwimError",
    "Calibration",
    "ForceIdentification",
    "Girder",
    "HalfCar",
    "InfluenceLine",
    "InputError",
    "Modes",
    "MovingForces",
    "NumericalError",
    "Passage",
    "PointLoad",
    "Record",
    "RoadProfile",
    "Sensor",
    "SensorKind",
    "SimulationSettings",
    "SprungMass",
    "StaticWeights",
    "Supports",
    "TractorSemitrailer",
    "Truck3D",
    "Truth",
    "__version__",
    "calibrate",
    "calibrate_influence_line",
    "composite_section",
    "conventions",
    "dynamics",
    "errors",
    "fe",
    "force_errors",
    "grid_lines",
    "identify_forces",
    "mfi",
    "model_influence_line",
    "optimize",
    "paper",
    "simulate",
    "vehicles",
    "weigh_static",
    "wim",
]
