"""Static Bridge WIM: influence-line calibration (matrix method) and Moses' algorithm.

The baseline every commercial B-WIM system uses (THEORY §5): calibrate the influence line
of a channel (usually the summed longitudinal gauges of mid-span) from crossings of a
truck of known weight, then weigh any vehicle by least squares against it.

    il = calibrate_influence_line([cal_rec], truck)      # OBrien et al. (2006)
    static = weigh_static(rec, influence=il)             # Moses (1979)
    fe = model_influence_line(bridge, like=il)           # the FE model's line, to compare
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

__all__ = [
    "DEFAULT_SMOOTHING",
    "Channel",
    "InfluenceLine",
    "StaticWeights",
    "calibrate_influence_line",
    "group_axles",
    "model_influence_line",
    "resolve_channels",
    "weigh_static",
]
