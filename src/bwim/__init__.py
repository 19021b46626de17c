"""bwim: calibrated, dynamic Bridge Weigh-in-Motion.

The public API is listed in ``__all__``; units, axes and signs are in
:mod:`bwim.conventions`.  This package never imports matplotlib.
"""

from importlib.metadata import PackageNotFoundError, version

from bwim import (
    conventions,
    dynamics,
    errors,
    fe,
    mfi,
    optimize,
    paper,
    plausibility,
    vehicles,
    wim,
)
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
    MultiRunCalibration,
    StaticWeights,
    Weighing,
    calibrate_influence_line,
    calibrate_lines,
    model_influence_line,
    weigh,
    weigh_static,
)

#: Names loaded on first use (PEP 562): the site chain pulls in scipy.signal and
#: scipy.stats, which a worker that only identifies forces should not pay for at import.
_LAZY = {
    "accuracy": ("bwim.accuracy", None), "assess": ("bwim.accuracy", "assess"),
    "detect": ("bwim.detect", None), "Detection": ("bwim.detect", "Detection"),
    "detect_axles": ("bwim.detect", "detect_axles"),
    "detect_from_strain": ("bwim.detect", "detect_from_strain"),
    "site": ("bwim.site", None), "EventWeighing": ("bwim.site", "EventWeighing"),
    "SiteCalibration": ("bwim.site", "SiteCalibration"), "SiteSetup": ("bwim.site", "SiteSetup"),
    "calibrate_site": ("bwim.site", "calibrate_site"), "weigh_event": ("bwim.site", "weigh_event"),
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        mod = importlib.import_module(module)
        return mod if attr is None else getattr(mod, attr)
    raise AttributeError(f"module 'bwim' has no attribute {name!r}")


try:
    __version__ = version("bwim")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

__all__ = [
    "Bridge",
    "BwimError",
    "Calibration",
    "Detection",
    "EventWeighing",
    "ForceIdentification",
    "Girder",
    "HalfCar",
    "InfluenceLine",
    "InputError",
    "Modes",
    "MovingForces",
    "MultiRunCalibration",
    "NumericalError",
    "Passage",
    "PointLoad",
    "Record",
    "RoadProfile",
    "Sensor",
    "SensorKind",
    "SimulationSettings",
    "SiteCalibration",
    "SiteSetup",
    "SprungMass",
    "StaticWeights",
    "Supports",
    "TractorSemitrailer",
    "Truck3D",
    "Truth",
    "Weighing",
    "__version__",
    "accuracy",
    "assess",
    "calibrate",
    "calibrate_influence_line",
    "calibrate_lines",
    "calibrate_site",
    "composite_section",
    "conventions",
    "detect",
    "detect_axles",
    "detect_from_strain",
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
    "plausibility",
    "simulate",
    "site",
    "vehicles",
    "weigh",
    "weigh_event",
    "weigh_static",
    "wim",
]
