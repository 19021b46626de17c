"""Static point loads.

Contract
--------
A :class:`PointLoad` is a vertical force ``P`` (N, positive pushing down) at ``(x, y)`` on
the deck (m; ``y`` ignored on a beam).  The FE model turns it into the consistent nodal
load vector ``N(x, y)ᵀ P`` of the element that contains it.
"""

from __future__ import annotations

from dataclasses import dataclass

from bwim.errors import require_finite

__all__ = ["PointLoad"]


@dataclass(frozen=True, kw_only=True)
class PointLoad:
    """A vertical point force on the deck.

    Parameters
    ----------
    x, y : float
        Position, m (``y`` from the right-hand edge; ignored on a beam).
    P : float
        Force, N, positive downward.
    """

    x: float
    y: float = 0.0
    P: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", require_finite("PointLoad.x", self.x))
        object.__setattr__(self, "y", require_finite("PointLoad.y", self.y))
        object.__setattr__(self, "P", require_finite("PointLoad.P", self.P))
