"""Time integration and vehicle–bridge interaction."""

from bwim.dynamics.crossing import (
    DEFAULT_APPROACH,
    DEFAULT_SAMPLING_RATE,
    VBIMethod,
    select_modes,
    simulate,
)
from bwim.dynamics.newmark import Newmark, NewmarkResult, integrate

__all__ = [
    "DEFAULT_APPROACH",
    "DEFAULT_SAMPLING_RATE",
    "Newmark",
    "NewmarkResult",
    "VBIMethod",
    "integrate",
    "select_modes",
    "simulate",
]
