"""bwim: calibrated, dynamic Bridge Weigh-in-Motion.

The public API is listed in ``__all__``; units, axes and signs are in
:mod:`bwim.conventions`.  This package never imports matplotlib.
"""

from importlib.metadata import PackageNotFoundError, version

from bwim import conventions, errors, fe
from bwim.errors import BwimError, InputError, NumericalError
from bwim.fe import Bridge, Girder, Modes, Supports, composite_section, grid_lines
from bwim.loads import PointLoad
from bwim.sensors import Sensor, SensorKind

try:
    __version__ = version("bwim")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

__all__ = [
    "Bridge",
    "BwimError",
    "Girder",
    "InputError",
    "Modes",
    "NumericalError",
    "PointLoad",
    "Sensor",
    "SensorKind",
    "Supports",
    "__version__",
    "composite_section",
    "conventions",
    "errors",
    "fe",
    "grid_lines",
]
