"""Time integration and vehicle–bridge interaction."""

from bwim.dynamics.crossing import (
    DEFAULT_APPROACH,
    DEFAULT_SAMPLING_RATE,
    VBIMethod,
    simulate,
)
from bwim.dynamics.newmark import Newmark, NewmarkResult, integrate
from bwim.fe.modal import select_modes

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
