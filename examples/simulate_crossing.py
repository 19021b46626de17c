"""The paper's truck crossing the paper's slab bridge over a rough road.

Run: ``python examples/simulate_crossing.py`` (the test suite runs it too).
"""

import numpy as np

import bwim


def main() -> None:
    bridge = bwim.paper.slab_bridge()
    sensors = bwim.paper.sensors()
    truck = bwim.paper.truck()
    road = bwim.paper.road(seed=1)
    rec = bwim.simulate(bridge, truck, speed=20.0, lane=2.0, sensors=sensors, road=road,
                        sampling_rate=1000.0, method="coupled", approach=100.0)
    mid = [k for k, s in enumerate(rec.sensors) if s.kind.value == "strain_x" and s.x == 6.0]
    print(f"{rec.time.size} samples at {rec.sampling_rate:g} Hz")
    print("peak mid-span strains (µε):", np.round(rec.data[:, mid].max(axis=0) / 1e-6, 1))
    truth = rec.truth
    dyn = truth.axle_forces / truth.static_axle_loads
    print("axle force / static load, min … max:",
          [f"{lo:.2f} … {hi:.2f}" for lo, hi in zip(dyn.min(0), dyn.max(0), strict=True)])


if __name__ == "__main__":
    main()
