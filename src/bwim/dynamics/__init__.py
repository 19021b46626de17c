"""Time integration and vehicle–bridge interaction."""

from bwim.dynamics.crossing import VBIMethod, select_modes, simulate
from bwim.dynamics.newmark import Newmark, NewmarkResult, integrate

__all__ = ["Newmark", "NewmarkResult", "VBIMethod", "integrate", "select_modes", "simulate"]
