"""Calibration of the bridge FE model from strains under a truck of known weight."""

from bwim.calibration.driver import Calibration, Refine, calibrate
from bwim.calibration.problem import (
    DynamicObjective,
    ParameterSpace,
    StaticObjective,
    neighbour_map,
    peak_weights,
)
from bwim.calibration.sensitivity import Identifiability, identifiability
from bwim.calibration.stages import Method, StageResult, run_stage

__all__ = [
    "Calibration",
    "DynamicObjective",
    "Identifiability",
    "Method",
    "ParameterSpace",
    "Refine",
    "StageResult",
    "StaticObjective",
    "calibrate",
    "identifiability",
    "neighbour_map",
    "peak_weights",
    "run_stage",
]
