"""Static B-WIM accuracy on the paper's bridge (issue 5): axle-weight and GVW errors.

The paper's slab bridge and sensors (Dowling, OBrien & González 2012, §5.1); the summed
longitudinal gauges of mid-span as the weighing channel (standard B-WIM practice); the
influence line calibrated by the matrix method (OBrien et al. 2006) from a few crossings
of the paper's truck over the paper's road (other seeds than the weighing runs).  Each
weighing method then weighs the paper truck, the 3-axle truck and the 5-axle
tractor–semitrailer at several speeds over several road seeds, and the table reports the
mean and maximum absolute error of each axle (in axle order) and of the GVW, in % of the
true static loads.

A weighing method is ``fn(record, bridge, calibration) -> axle weights (N)``; adding one
(for example moving force identification) is one more entry in :data:`METHODS`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from benchmarks._timing import print_table
from bwim import paper
from bwim.dynamics import simulate
from bwim.fe.bridge import Bridge
from bwim.mfi import identify_forces
from bwim.records import Record
from bwim.vehicles import named
from bwim.wim import (
    InfluenceLine,
    calibrate_influence_line,
    group_axles,
    model_influence_line,
    weigh_static,
)

VEHICLES = ("two_axle_truck", "three_axle_truck", "tractor_semitrailer")
SPEEDS = (15.0, 20.0, 25.0)
SEEDS = (1, 2, 3)
#: (speed m/s, road seed) of the calibration crossings of the paper truck.
CALIBRATION_RUNS = ((16.0, 101), (18.0, 102), (20.0, 103), (22.0, 104), (24.0, 105))


@dataclass
class Calibration:
    """The calibration crossings of the paper truck; what methods derive from them is
    computed once and kept (the influence line)."""

    bridge: Bridge
    records: Sequence[Record]
    vehicle: object
    _cache: dict = field(default_factory=dict, repr=False)

    def influence_line(self) -> InfluenceLine:
        if "il" not in self._cache:
            self._cache["il"] = calibrate_influence_line(self.records, self.vehicle)
        return self._cache["il"]

    def model_line(self) -> InfluenceLine:
        if "fe" not in self._cache:
            self._cache["fe"] = model_influence_line(self.bridge, like=self.influence_line())
        return self._cache["fe"]


def moses_calibrated(record: Record, bridge: Bridge, calibration: Calibration) -> np.ndarray:
    """Moses' algorithm with the matrix-method influence line (what B-WIM systems do)."""
    return weigh_static(record, influence=calibration.influence_line()).axle_weights


def moses_grouped(record: Record, bridge: Bridge, calibration: Calibration) -> np.ndarray:
    """As :func:`moses_calibrated`, axles closer than 2 m sharing their group's weight."""
    return weigh_static(record, influence=calibration.influence_line(),
                        groups=group_axles(record.passage)).axle_weights


def moses_model(record: Record, bridge: Bridge, calibration: Calibration) -> np.ndarray:
    """Moses' algorithm with the FE model's static influence line (here the true bridge's):
    what is left is the error of the dynamics alone."""
    return weigh_static(record, influence=calibration.model_line()).axle_weights


def mfi_exact(record: Record, bridge: Bridge, calibration: Calibration) -> np.ndarray:
    """First-order moving force identification with the exact FE model (all 18 channels,
    L-curve λ): the dynamic B-WIM of the paper before any calibration error."""
    return identify_forces(bridge, record).axle_weights


Method = Callable[[Record, Bridge, Calibration], np.ndarray]
METHODS: list[tuple[str, Method]] = [
    ("Moses, calibrated IL", moses_calibrated),
    ("Moses, calibrated IL, axle groups", moses_grouped),
    ("Moses, FE static IL", moses_model),
    ("MFI, exact FE model", mfi_exact),
]


def _fmt(values: np.ndarray) -> str:
    return "/".join(f"{v:.1f}" for v in values)


def run(
    *,
    vehicles: Sequence[str] = VEHICLES,
    speeds: Sequence[float] = SPEEDS,
    seeds: Sequence[int] = SEEDS,
    calibration_runs: Sequence[tuple[float, int]] = CALIBRATION_RUNS,
    approach: float = paper.APPROACH,
    methods: Sequence[tuple[str, Method]] = METHODS,
) -> list[list[object]]:
    """Rows: method, vehicle, speed (or "all"), crossings, mean |error| per axle, max
    |error| per axle, mean and max |GVW error| (%)."""
    bridge, sensors, lane = paper.slab_bridge(), paper.sensors(), paper.LANE
    truck = paper.truck()
    cal_recs = [simulate(bridge, truck, speed=v, lane=lane, sensors=sensors,
                         road=paper.road(seed, approach=approach), approach=approach)
                for v, seed in calibration_runs]
    calibration = Calibration(bridge=bridge, records=cal_recs, vehicle=truck)
    errors: dict[tuple[str, str, float], list[np.ndarray]] = {}
    for name in vehicles:
        vehicle = named(name)
        for v in speeds:
            for seed in seeds:
                rec = simulate(bridge, vehicle, speed=v, lane=lane, sensors=sensors,
                               road=paper.road(seed, approach=approach), approach=approach)
                true = rec.truth.static_axle_loads
                for label, method in methods:
                    w = np.asarray(method(rec, bridge, calibration), dtype=float)
                    err = 100.0 * np.append(w / true - 1.0, w.sum() / true.sum() - 1.0)
                    errors.setdefault((label, name, v), []).append(err)
    rows = []
    for label, _ in methods:
        for name in vehicles:
            groups = [(f"{v:g}", [errors[label, name, v]]) for v in speeds]
            groups.append(("all", [errors[label, name, v] for v in speeds]))
            for speed_label, parts in groups:
                e = np.abs(np.concatenate([np.array(p) for p in parts]))
                rows.append([label, name, speed_label, e.shape[0], _fmt(e[:, :-1].mean(0)),
                             _fmt(e[:, :-1].max(0)), f"{e[:, -1].mean():.1f}",
                             f"{e[:, -1].max():.1f}"])
    return rows


def main() -> None:
    rows = run()
    print_table(
        "Static B-WIM on the paper bridge: |error| % of static loads (summed mid-span "
        f"gauges; IL from {len(CALIBRATION_RUNS)} paper-truck runs; road seeds "
        f"{', '.join(map(str, SEEDS))})",
        ["method", "vehicle", "speed (m/s)", "runs", "axles mean", "axles max", "GVW mean",
         "GVW max"],
        rows,
    )


if __name__ == "__main__":
    main()
