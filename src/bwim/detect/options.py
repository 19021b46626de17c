"""The options both detectors share: speeds, axle spacings, the span and the flagging.

Contract
--------
* :class:`DetectOptions` holds, validated, what :func:`~bwim.detect.detect_axles` and
  :func:`~bwim.detect.detect_from_strain` both take as keywords (``speed_range``,
  ``min_axle_spacing``, ``max_axle_spacing``, ``span``, ``gauges``, ``lateral_threshold``,
  ``unexplained_fraction``), with one default and one meaning each.  An invalid value
  raises :class:`~bwim.errors.InputError` naming it; an unknown keyword a TypeError.
* Speeds in m/s, distances in m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from bwim.errors import InputError, require_positive

if TYPE_CHECKING:
    from bwim.wim import InfluenceLine

__all__ = ["DEFAULT_MAX_AXLE_SPACING", "DetectOptions", "check_speed_range"]

#: Longest distance between consecutive axles of one vehicle, m.  Common heavy vehicles
#: have at most 7–10 m between consecutive axles (the gap between a tractor's drive axles
#: and a long semi-trailer's axle group; EU Directive 96/53/EC caps articulated vehicles
#: at 16.5 m overall, so no spacing inside one reaches 12 m), while two vehicles following
#: one another have the rear overhang, the headway and the front overhang between their
#: axles (≥ 12 m at a 0.5 s headway at 80 km/h).
DEFAULT_MAX_AXLE_SPACING = 12.0


def check_speed_range(speed_range: Any) -> tuple[float, float]:
    """``(v_min, v_max)`` in m/s, 0 < v_min < v_max, or InputError."""
    try:
        lo, hi = (float(v) for v in speed_range)
    except (TypeError, ValueError):
        raise InputError(f"speed_range must be (v_min, v_max) in m/s, got {speed_range!r}"
                         ) from None
    lo, hi = require_positive("speed_range[0]", lo), require_positive("speed_range[1]", hi)
    if hi <= lo:
        raise InputError(f"speed_range must have v_min < v_max, got ({lo:g}, {hi:g})")
    return lo, hi


@dataclass(frozen=True, kw_only=True)
class DetectOptions:
    """The detectors' shared keywords (see the module contract).

    Attributes
    ----------
    speed_range : (float, float)
        Plausible speeds, m/s (checked: 0 < v_min < v_max).
    min_axle_spacing : float
        Closest axles to resolve, m: closer ones merge.
    max_axle_spacing : float
        Axles farther apart belong to different vehicles, m (see
        :data:`DEFAULT_MAX_AXLE_SPACING`); more than ``min_axle_spacing``.
    span : float, (x_start, x_end), InfluenceLine or None
        The instrumented span in the influence-line frame (a length L means (0, L)), for
        each vehicle's time on the span (multiple presence, truncation, unexplained
        strain, the lateral-position window).  None: the detector's default.
    gauges : sequence of str, optional
        Strain gauges across one section for the lateral position and the strain
        activity check (default :func:`~bwim.detect.lateral.section_gauges`).
    lateral_threshold : float
        See :func:`~bwim.detect.lateral.lateral_position`.
    unexplained_fraction : float
        Strain activity outside every vehicle's time on the span larger than this
        fraction of the largest activity inside flags ``unexplained_strain``.
    """

    speed_range: tuple[float, float] = (5.0, 40.0)
    min_axle_spacing: float = 0.8
    max_axle_spacing: float = DEFAULT_MAX_AXLE_SPACING
    span: float | Sequence[float] | InfluenceLine | None = None
    gauges: Sequence[str] | None = None
    lateral_threshold: float = 0.5
    unexplained_fraction: float = 0.2

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed_range", check_speed_range(self.speed_range))
        min_sp = require_positive("min_axle_spacing", self.min_axle_spacing)
        max_sp = require_positive("max_axle_spacing", self.max_axle_spacing)
        if max_sp <= min_sp:
            raise InputError("max_axle_spacing must exceed min_axle_spacing")
        object.__setattr__(self, "min_axle_spacing", min_sp)
        object.__setattr__(self, "max_axle_spacing", max_sp)
