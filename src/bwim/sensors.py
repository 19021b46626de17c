"""Sensors on the bridge deck.

Contract
--------
* A :class:`Sensor` is a point ``(x, y)`` on the deck (m; see :mod:`bwim.conventions`)
  and a kind: ``strain_x`` (longitudinal strain at the soffit), ``strain_y`` (transverse
  strain at the soffit) or ``deflection`` (w, m, positive down).
* On a plate, ``strain_x`` at a point on a girder line reads the **girder's** soffit
  strain (``−z_b w_xx``); elsewhere the slab soffit (``−(h/2) w_xx``).  On a 1-D beam
  bridge ``y`` is ignored and ``strain_y`` is not available.
* Curvature is discontinuous between C¹ elements, so a strain sensor on an element edge or
  node reads the average of the elements that touch it.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from bwim.errors import parse_enum, require_finite

__all__ = ["Sensor", "SensorKind"]


class SensorKind(StrEnum):
    """What a sensor measures."""

    STRAIN_X = "strain_x"
    STRAIN_Y = "strain_y"
    DEFLECTION = "deflection"

    @property
    def is_strain(self) -> bool:
        return self is not SensorKind.DEFLECTION

    @property
    def unit(self) -> str:
        return "m" if self is SensorKind.DEFLECTION else "m/m"


@dataclass(frozen=True, kw_only=True)
class Sensor:
    """A strain gauge or displacement transducer on the deck.

    Parameters
    ----------
    x : float
        Position along the bridge, m from the first support.
    y : float
        Position across the deck, m from the right-hand edge (ignored on a beam).
    kind : SensorKind or str
        ``"strain_x"`` (default), ``"strain_y"`` or ``"deflection"``.
    name : str, optional
        Channel name (default built from kind and position), used for CSV columns.
    """

    x: float
    y: float = 0.0
    kind: SensorKind = SensorKind.STRAIN_X
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", require_finite("Sensor.x", self.x))
        object.__setattr__(self, "y", require_finite("Sensor.y", self.y))
        kind = parse_enum(SensorKind, self.kind, "sensor kind")
        object.__setattr__(self, "kind", kind)
        if not self.name:
            object.__setattr__(self, "name", f"{kind.value}@{self.x:g},{self.y:g}")
