"""Calibration of the bridge FE model from strains under a truck of known weight."""

from bwim.calibration.driver import Calibration, MassSource, Refine, calibrate
from bwim.calibration.logger import LoggerCalibration, calibrate_logger
from bwim.calibration.meshdefect import MeshCorrection, mesh_defects
from bwim.calibration.problem import (
    DynamicObjective,
    ParameterSpace,
    StaticObjective,
    estimate_noise,
    neighbour_map,
    noise_weights,
    peak_weights,
)
from bwim.calibration.quasistatic import (
    MassFit,
    QuasiStaticCalibration,
    calibrate_quasistatic,
    fit_mass,
)
from bwim.calibration.sensitivity import (
    Identifiability,
    RoadSensitivity,
    identifiability,
    road_sensitivity,
)
from bwim.calibration.stages import Method, StageResult, run_stage

__all__ = [
    "Calibration",
    "DynamicObjective",
    "Identifiability",
    "LoggerCalibration",
    "MassFit",
    "MassSource",
    "MeshCorrection",
    "Method",
    "ParameterSpace",
    "QuasiStaticCalibration",
    "Refine",
    "RoadSensitivity",
    "StageResult",
    "StaticObjective",
    "calibrate",
    "calibrate_logger",
    "calibrate_quasistatic",
    "estimate_noise",
    "fit_mass",
    "identifiability",
    "mesh_defects",
    "neighbour_map",
    "noise_weights",
    "peak_weights",
    "road_sensitivity",
    "run_stage",
]
