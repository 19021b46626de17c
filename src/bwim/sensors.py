"""Sensors on the bridge deck.

Contract
--------
* A :class:`Sensor` is a point ``(x, y)`` on the deck (m; see :mod:`bwim.conventions`)
  and a kind: ``strain_x`` (longitudinal strain at the soffit), ``strain_y`` (transverse
  strain at the soffit), ``deflection`` (w, m, positive down), ``axle_detector`` (a
  logger channel with a local response to each axle passing; any unit, ``-``) or
  ``temperature`` (°C; a logger channel that reads no load).  The first three are
  *structural* (:attr:`SensorKind.is_structural`): they read the bridge's response.
* The position is optional: a channel read from a logger file may have ``x = y = None``
  (no finite-element model is used, e.g. influence-line weighing).  ``y`` may be known
  without ``x`` (gauges across the width: lateral position).  Given ``x`` alone, ``y``
  is 0.0 (a beam ignores it).  A sensor without ``x`` must have a ``name``.  Every
  finite-element entry point (:meth:`bwim.fe.model.FEModel.sensor_matrix`, hence
  ``Bridge.static``, ``Bridge.influence``, ``simulate``, calibration) refuses a sensor
  without ``(x, y)`` and an axle detector with :class:`~bwim.errors.InputError`.
* On a plate, ``strain_x`` at a point on a girder line reads the **girder's** soffit
  strain (``−z_b w_xx``); elsewhere the slab soffit (``−(h/2) w_xx``).  On a 1-D beam
  bridge ``y`` is ignored and ``strain_y`` is not available.
* Curvature is discontinuous between C¹ elements, so a strain sensor on an element edge or
  node reads the average of the elements that touch it.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from bwim.errors import InputError, parse_enum, require_finite

__all__ = ["Sensor", "SensorKind"]


class SensorKind(StrEnum):
    """What a sensor measures."""

    STRAIN_X = "strain_x"
    STRAIN_Y = "strain_y"
    DEFLECTION = "deflection"
    AXLE_DETECTOR = "axle_detector"
    TEMPERATURE = "temperature"

    @property
    def is_strain(self) -> bool:
        return self in (SensorKind.STRAIN_X, SensorKind.STRAIN_Y)

    @property
    def is_structural(self) -> bool:
        """Strain or deflection: a reading of the bridge's response to load."""
        return self in (SensorKind.STRAIN_X, SensorKind.STRAIN_Y, SensorKind.DEFLECTION)

    @property
    def unit(self) -> str:
        if self is SensorKind.AXLE_DETECTOR:
            return "-"
        if self is SensorKind.TEMPERATURE:
            return "degC"
        return "m" if self is SensorKind.DEFLECTION else "m/m"


@dataclass(frozen=True, kw_only=True)
class Sensor:
    """A strain gauge or displacement transducer on the deck.

    Parameters
    ----------
    x : float or None
        Position along the bridge, m from the first support; None: unknown (then a
        ``name`` is required).
    y : float or None
        Position across the deck, m from the right-hand edge (ignored on a beam);
        default 0.0 when ``x`` is given, None (unknown) otherwise.
    kind : SensorKind or str
        ``"strain_x"`` (default), ``"strain_y"``, ``"deflection"``, ``"axle_detector"``
        or ``"temperature"``.
    name : str, optional
        Channel name (default built from kind and position), used for CSV columns.
    """

    x: float | None = None
    y: float | None = None
    kind: SensorKind = SensorKind.STRAIN_X
    name: str = ""

    def __post_init__(self) -> None:
        if self.x is not None:
            object.__setattr__(self, "x", require_finite("Sensor.x", self.x))
            if self.y is None:
                object.__setattr__(self, "y", 0.0)
        if self.y is not None:
            object.__setattr__(self, "y", require_finite("Sensor.y", self.y))
        if self.name is None:
            object.__setattr__(self, "name", "")
        if not isinstance(self.name, str):
            raise InputError(f"Sensor.name must be a string, got {self.name!r}")
        kind = parse_enum(SensorKind, self.kind, "sensor kind")
        object.__setattr__(self, "kind", kind)
        if not self.name:
            if self.x is None:
                raise InputError(
                    f"a {kind.value} sensor without a position (x) needs a name")
            object.__setattr__(self, "name", f"{kind.value}@{self.x:g},{self.y:g}")

    @property
    def has_position(self) -> bool:
        """True when both ``x`` and ``y`` are known (a finite-element model needs them)."""
        return self.x is not None and self.y is not None
