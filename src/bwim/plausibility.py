"""Plausibility of weights: no weight leaves bwim without these checks.

Contract
--------
* A weighing carries ``flags`` (strings, written as they are to summary.csv) and a
  ``quality``: ``"reject"`` if any flag of :data:`HARD_FLAGS` is set (the weights must not
  be used or written as a result), ``"warning"`` if only flags of :data:`SOFT_FLAGS` are,
  ``"ok"`` otherwise.
* :func:`weight_flags` checks axle and group weights (N) against :class:`Limits`; the
  weighing functions (:func:`bwim.wim.weigh`, :func:`bwim.wim.weigh_static`) add their own
  fit checks (residual, truncation, conditioning) with the same vocabulary.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_finite, require_positive

__all__ = ["HARD_FLAGS", "SOFT_FLAGS", "Limits", "ordered_flags", "quality_of",
           "weight_flags"]

#: Flags that make a weighing unusable (quality "reject").
HARD_FLAGS = (
    "undetermined",          # the weights are not determined (rank-deficient fit)
    "negative_axle_weight",  # an axle weight < 0
    "negative_group_weight",  # a group weight < 0
    "axle_weight_high",      # an axle weight > Limits.axle_max
    "axle_weight_low",       # an axle weight in [0, Limits.axle_min)
    "gvw_high",              # GVW > Limits.gvw_max
    "gvw_low",               # GVW < Limits.gvw_min
    "residual_high",         # misfit > the calibration's misfit limit
    "truncated_start",       # an axle is already on the lines' support at the first sample
    "truncated_end",         # an axle is still on the lines' support at the last sample
    "no_baseline",           # too few samples without an axle on the support for the offsets
    "lateral_outlier",       # lateral position an outlier of its lane's day (bwim.site.wander)
    "unconfirmed_gauge_fault",  # a gauge the day finds healthy disagreed (another vehicle)
    "group_off_path",        # an axle group off the vehicle's wheel path (bwim.site.wheelpath)
    "split_across_records",  # the vehicle goes on in another record (bwim.site.split)
    "negative_force",        # MFI: an axle's force tensile where it is weighed
    "open_at_start",         # a long recording begins within the event (bwim.stream)
    "open_at_end",           # ... or ends within it: the vehicle may go on beyond it
    "max_duration",          # the trigger closed at its max_duration with the signal up
)
#: Flags that call for a look but keep the weights (quality "warning").
SOFT_FLAGS = (
    "outside_calibration_time",  # clock time outside the calibration runs' span
    "no_drift",                  # a drift correction asked for, none could be made
    "lateral_extrapolated",      # lateral covariate outside the calibration runs' range
    "ill_conditioned",           # condition number > Limits.condition
)


@dataclass(frozen=True, kw_only=True)
class Limits:
    """Plausibility thresholds of :func:`weigh` (N, dimensionless).

    Attributes
    ----------
    axle_max, axle_min : float
        An axle heavier than ``axle_max`` (250 kN: 2.2 × the EU 115 kN drive-axle limit)
        or lighter than ``axle_min`` (1 kN, far below any road vehicle's axle) is absurd.
    gvw_max, gvw_min : float
        GVW above ``gvw_max`` (1000 kN: 2.5 × the EU 40 t limit; abnormal loads need a
        permit and an escort) or below ``gvw_min`` (5 kN, a light car is ≈ 10 kN).
    misfit : float
        A misfit above ``misfit`` × the calibration runs' median misfit is
        ``residual_high``.  The misfit is in units of the expected residual deviation of a
        vehicle of the weighed weight (:meth:`~bwim.wim.multirun.MultiRunCalibration.
        error_covariance`: noise plus dynamics scaled with the load), so neither light nor
        heavy vehicles are flagged for their weight, while a second vehicle's response,
        a wrong passage or a faulty channel stand out.
    condition : float
        Condition number of the (whitened) least-squares matrix above which the weights
        are ``ill_conditioned``.
    lateral_tolerance : float
        A lateral covariate may leave the calibrated range by this much before it is
        ``lateral_extrapolated`` (units of the covariate).
    min_baseline : int
        Samples without an axle on the support needed to fit the offsets.
    """

    axle_max: float = 250e3
    axle_min: float = 1e3
    gvw_max: float = 1000e3
    gvw_min: float = 5e3
    misfit: float = 3.0
    condition: float = 100.0
    lateral_tolerance: float = 0.0
    min_baseline: int = 8

    def __post_init__(self) -> None:
        for name in ("axle_max", "gvw_max", "condition", "misfit"):
            require_positive(f"Limits.{name}", getattr(self, name))
        for name in ("axle_min", "gvw_min", "lateral_tolerance"):
            if require_finite(f"Limits.{name}", getattr(self, name)) < 0:
                raise InputError(f"Limits.{name} must be >= 0")
        if int(self.min_baseline) < 1:
            raise InputError(f"Limits.min_baseline must be >= 1, got {self.min_baseline!r}")


def weight_flags(axle_weights, group_weights, limits: Limits) -> list[str]:
    """Flags of implausible axle and group weights (N): negative, absurdly high or low,
    and a gross weight outside the limits; NaN weights (undetermined) are left to the
    caller's ``undetermined`` flag."""
    axle_w = np.asarray(axle_weights, dtype=float)
    group_w = np.asarray(group_weights, dtype=float)
    flags = []
    if np.any(axle_w < 0):
        flags.append("negative_axle_weight")
    if np.any(group_w < 0):
        flags.append("negative_group_weight")
    if np.any(axle_w > limits.axle_max):
        flags.append("axle_weight_high")
    if np.any((axle_w >= 0) & (axle_w < limits.axle_min)):
        flags.append("axle_weight_low")
    gvw = float(axle_w.sum())
    if gvw > limits.gvw_max:
        flags.append("gvw_high")
    if gvw < limits.gvw_min:
        flags.append("gvw_low")
    return flags


def ordered_flags(flags: Iterable[str]) -> tuple[str, ...]:
    """``flags`` without repeats, in the order of :data:`HARD_FLAGS` then
    :data:`SOFT_FLAGS` (unknown flags after them, in the order given)."""
    given = list(dict.fromkeys(flags))
    known = [f for f in HARD_FLAGS + SOFT_FLAGS if f in given]
    return tuple(known + [f for f in given if f not in known])


def quality_of(flags: Iterable[str]) -> str:
    """``"reject"``, ``"warning"`` or ``"ok"`` (see the module docstring)."""
    flags = tuple(flags)
    if any(f in HARD_FLAGS for f in flags):
        return "reject"
    return "warning" if flags else "ok"
