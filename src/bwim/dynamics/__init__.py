"""Time integration and vehicle–bridge interaction."""

from bwim.dynamics.newmark import Newmark, NewmarkResult, integrate
from bwim.dynamics.simulate import VBIMethod, select_modes, simulate

__all__ = ["Newmark", "NewmarkResult", "VBIMethod", "integrate", "select_modes", "simulate"]
