"""Vehicle classes from the axle configuration.

Contract
--------
* :func:`axle_configuration` is the vehicle's axle groups as digits, front to back: each
  digit counts the axles of one group (consecutive axles closer than ``group_spacing``,
  :func:`bwim.wim.group_axles`).  A two-axle rigid truck is ``"11"``, a rigid truck with a
  tandem ``"12"``, a tractor (steer, drive) with a tri-axle semi-trailer ``"113"``, with a
  tandem drive ``"123"``.  This is the axle-group code that European WIM systems use to
  class heavy vehicles (COST 323 reports results per such class); it needs nothing but
  the measured spacings, so it is the default ``class`` of a summary row.
* Spacings in m; an empty code for an unknown layout.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from bwim.wim.moses import group_axles

__all__ = ["DEFAULT_GROUP_SPACING", "axle_configuration"]

#: Consecutive axles closer than this (m) are one group (tandems and tridems are 1.0–1.8 m
#: apart; a steer axle is more than 2.5 m ahead of the next).
DEFAULT_GROUP_SPACING = 2.0


def axle_configuration(spacings: Sequence[float] | np.ndarray | None, *,
                       group_spacing: float = DEFAULT_GROUP_SPACING) -> str:
    """The axle-group code of a vehicle with these axle ``spacings`` (m), e.g. ``"113"``;
    ``""`` when the spacings are unknown (None)."""
    if spacings is None:
        return ""
    sp = np.asarray(spacings, dtype=float).ravel()
    if not np.all(np.isfinite(sp)):
        return ""
    return "".join(str(len(g)) for g in group_axles(sp, group_spacing))
