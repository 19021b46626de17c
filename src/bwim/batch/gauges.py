"""The day's gauge health: per gauge, how many vehicles it was left out of and why, and
its gain ratio over the day.

Contract
--------
* :func:`vehicle_gauges` reads one weighed event (:class:`bwim.site.EventWeighing`) for
  what its gauges did, vehicle by vehicle, as :class:`VehicleGauges`:

  - a vehicle whose gauges were judged (:func:`bwim.site.health.check_gauges`: it has a
    weighing by influence lines, or a ``gauge_fault`` flag) counts as **judged**;
  - a vehicle with ``gauge_fault`` flags is judged again to learn each fault's kind
    (``flat``, ``clipped``, ``silent``, ``reversed``, ``gain``, ``drift``:
    :data:`bwim.site.health.FAULT_KINDS`; the check is deterministic, so it finds what
    the event's weighing found);
  - a vehicle weighed alone on the span (no ``multiple_presence``) gives each of its
    gauges' **gain ratio** over what the other gauges predict
    (:func:`bwim.site.health.gain_ratios` of the weighing it was weighed with: 1 for a
    healthy deck and a vehicle on the calibration truck's path).

  Vehicles refused before their gauges were judged (another direction, two vehicles of
  one direction on the span, a truncated record) and vehicles weighed by MFI are not
  judged.  :meth:`VehicleGauges.to_json` / :meth:`VehicleGauges.from_json` keep it in a
  batch's manifest (plain JSON), so a resumed batch's table still counts every vehicle.
* :func:`tally_gauges` sums them per gauge as :class:`GaugeTally` (one per gauge, in the
  calibration's order): vehicles judged, vehicles it was left out of, by kind, and the
  median of its gain ratios (nan when none).  :meth:`GaugeTally.as_row` is a row of
  :func:`bwim.io.gauge_health.write_gauge_health`.
* Units: ratios dimensionless.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from bwim.site.health import FAULT_KINDS, FLAG_GAUGE_FAULT, check_gauges, gain_ratios

__all__ = ["GaugeTally", "VehicleGauges", "tally_gauges", "vehicle_gauges"]

_PREFIX = FLAG_GAUGE_FAULT + ":"


@dataclass(frozen=True, kw_only=True)
class VehicleGauges:
    """What one judged vehicle's gauges did.

    Attributes
    ----------
    faults : mapping of str to str
        Each gauge left out, with its fault's kind.
    ratios : mapping of str to float
        Each gauge's gain ratio over what the others predict (empty unless the vehicle
        was weighed alone on the span).
    """

    faults: Mapping[str, str] = field(default_factory=dict)
    ratios: Mapping[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        return {"faults": dict(self.faults), "ratios": dict(self.ratios)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> VehicleGauges:
        return cls(faults=MappingProxyType({str(k): str(v) for k, v in
                                            dict(data.get("faults", {})).items()}),
                   ratios=MappingProxyType({str(k): float(v) for k, v in
                                            dict(data.get("ratios", {})).items()}))


def vehicle_gauges(record, event, calibration) -> tuple[VehicleGauges, ...]:
    """The judged vehicles of ``event`` (:class:`bwim.site.EventWeighing` of ``record``
    with ``calibration``, a :class:`bwim.site.SiteCalibration`), in order (see the module
    docstring)."""
    lines, combine = calibration.lines, calibration.setup.combine
    out = []
    for v in event.vehicles:
        named = [f[len(_PREFIX):] for f in v.flags if f.startswith(_PREFIX)]
        alone = "multiple_presence" not in v.flags
        if named:
            health = check_gauges(record, v.vehicle.passage, lines, combine=combine,
                                  alone="multiple_presence" not in v.vehicle.flags)
            kinds = {f.gauge: f.kind for f in health.faults}
            faults = {g: kinds.get(g, "") for g in named}
        elif v.weighing is None or v.identification is not None:
            continue  # not judged
        else:
            faults = {}
        ratios = (gain_ratios(v.weighing, lines)
                  if v.weighed and alone and v.weighing is not None else {})
        out.append(VehicleGauges(faults=MappingProxyType(faults),
                                 ratios=MappingProxyType(ratios)))
    return tuple(out)


@dataclass(frozen=True, kw_only=True)
class GaugeTally:
    """One gauge over a day.

    Attributes
    ----------
    gauge : str
    judged : int
        Vehicles whose gauges were judged.
    left_out : int
        Vehicles this gauge was left out of.
    kinds : mapping of str to int
        ``left_out`` by kind (every kind of :data:`~bwim.site.health.FAULT_KINDS`).
    median_ratio : float
        Median of its gain ratios over the vehicles weighed alone (nan when none).
    n_ratios : int
        How many ratios the median is of.
    """

    gauge: str
    judged: int
    left_out: int
    kinds: Mapping[str, int]
    median_ratio: float
    n_ratios: int

    def as_row(self) -> dict[str, Any]:
        """The row of :func:`bwim.io.gauge_health.write_gauge_health`."""
        return {"gauge": self.gauge, "vehicles_judged": self.judged,
                "left_out": self.left_out, **dict(self.kinds),
                "median_gain_ratio": self.median_ratio, "n_ratios": self.n_ratios}


def tally_gauges(gauges: Sequence[str], vehicles: Iterable[VehicleGauges]
                 ) -> tuple[GaugeTally, ...]:
    """Per gauge of ``gauges`` (then any other gauge a vehicle names), the day's tally
    of ``vehicles`` (see the module docstring)."""
    vehicles = list(vehicles)
    names = list(dict.fromkeys([*gauges, *(g for v in vehicles for g in v.faults)]))
    out = []
    for g in names:
        kinds = dict.fromkeys(FAULT_KINDS, 0)
        for v in vehicles:
            if g in v.faults and v.faults[g] in kinds:
                kinds[v.faults[g]] += 1
        ratios = [v.ratios[g] for v in vehicles if g in v.ratios]
        out.append(GaugeTally(
            gauge=g, judged=len(vehicles), left_out=sum(g in v.faults for v in vehicles),
            kinds=MappingProxyType(kinds),
            median_ratio=float(np.median(ratios)) if ratios else float("nan"),
            n_ratios=len(ratios)))
    return tuple(out)
