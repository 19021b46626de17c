"""The FE model in a few lines: modes, a static response, an influence line.

Run: ``python examples/fe_basics.py`` (the test suite runs it too).
"""

import numpy as np

import bwim
from bwim import paper


def main() -> None:
    bridge = paper.slab_bridge()
    modes = bridge.modes(4)
    print("frequencies (Hz):", np.round(modes.frequencies, 2))

    sensor = bwim.Sensor(x=6.0, y=2.0, kind="strain_x")
    surface = bridge.influence([sensor])
    x = np.linspace(0.0, bridge.length, 13)
    line = surface.at(x, np.full_like(x, 2.0))[:, 0]  # strain per newton along y = 2 m
    print("mid-span strain influence line (µε per 100 kN):")
    print("  " + " ".join(f"{v * 1e5 / 1e-6:5.1f}" for v in line))

    stiffer = bridge.with_params(E_x=1.1 * bridge.E_x)
    load = [bwim.PointLoad(x=6.0, y=2.0, P=100e3)]
    ratio = stiffer.static(load, [sensor])[0] / bridge.static(load, [sensor])[0]
    print(f"strain ratio after +10 % E_x: {ratio:.3f}")


if __name__ == "__main__":
    main()
