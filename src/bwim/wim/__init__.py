"""Static Bridge WIM: influence-line calibration (matrix method) and Moses' algorithm.

The baseline every commercial B-WIM system uses (docs/theory.md §5; many runs and
weighing: §14–15): calibrate the influence line of a channel (usually the summed
longitudinal gauges of mid-span) from crossings of a truck of known weight, then weigh
any vehicle by least squares against it.

    il = calibrate_influence_line([cal_rec], truck)      # OBrien et al. (2006)
    static = weigh_static(rec, influence=il)             # Moses (1979)
    fe = model_influence_line(bridge, like=il)           # the FE model's line, to compare

Many calibration runs of an installation (per-gauge lines, lateral model, per-run scale
factors and their trend over the day, outlier runs rejected), and unknown traffic weighed
with them (gauges combined by GLS, axle groups, plausibility flags):

    cal = calibrate_lines(records, passages, truck_axle_loads)
    w = weigh(record, passage, cal)                      # .gvw, .group_weights, .flags
"""

from bwim.wim.influence_line import (
    DEFAULT_SMOOTHING,
    Channel,
    InfluenceLine,
    calibrate_influence_line,
    model_influence_line,
    resolve_channels,
)
from bwim.wim.moses import StaticWeights, group_axles, weigh_static
from bwim.wim.multirun import (
    MultiRunCalibration,
    OutlierRule,
    RunFit,
    ScaleTrend,
    calibrate_lines,
)
from bwim.wim.weigh import Limits, Weighing, weigh

__all__ = [
    "DEFAULT_SMOOTHING",
    "Channel",
    "InfluenceLine",
    "Limits",
    "MultiRunCalibration",
    "OutlierRule",
    "RunFit",
    "ScaleTrend",
    "StaticWeights",
    "Weighing",
    "calibrate_influence_line",
    "calibrate_lines",
    "group_axles",
    "model_influence_line",
    "resolve_channels",
    "weigh",
    "weigh_static",
]
