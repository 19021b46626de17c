"""Bad input raises InputError naming the argument and the value."""

import math

import numpy as np
import pytest

import bwim
from bwim.errors import InputError, NumericalError

PLATE = dict(length=12.0, width=8.0, nx=12, ny=8, thickness=0.65, E=35e9, mu=1560.0)


def _plate(**kw):
    return bwim.Bridge.plate(**{**PLATE, **kw})


@pytest.mark.parametrize(
    ("arg", "value", "pattern"),
    [
        ("length", 0.0, r"length must be positive, got 0"),
        ("width", -8.0, r"width must be positive, got -8"),
        ("thickness", -0.1, r"thickness must be positive, got -0.1"),
        ("E", -35e9, r"E_x must be positive, got -3.5e\+10"),
        ("mu", 0.0, r"mu must be positive, got 0"),
        ("mu", math.nan, r"mu must be positive, got nan"),
        ("poisson", 0.5, r"poisson must lie in \[0, 0.5\), got 0.5"),
        ("poisson", -0.1, r"poisson must lie in \[0, 0.5\), got -0.1"),
        ("nx", 0, r"nx must be a positive integer, got 0"),
        ("ny", 2.5, r"ny must be a positive integer, got 2.5"),
        ("supports", "pinned", r"unknown supports 'pinned'"),
        ("supports", {"x0": "hinged"}, r"unknown support 'hinged' for edge x0"),
        ("supports", {"left": "free"}, r"unknown support edge\(s\) \['left'\]"),
        ("zones", (5, 0), r"zones = \(5, 0\)"),
        ("damping_ratio", -0.01, r"damping_ratio must lie in \[0, 1\], got -0.01"),
        # issue 22: these reached the eigen-solver and ended in its traceback
        ("E", 1e300, r"E_x / mu = 6.41e\+296 is outside 1e-30 … 1e\+30"),
        ("mu", 1e-300, r"E_x / mu = inf is outside"),
    ],
)
def test_plate_rejects(arg, value, pattern):
    with pytest.raises(InputError, match=pattern):
        _plate(**{arg: value})


def test_modulus_arguments():
    with pytest.raises(InputError, match="either E or E_x/E_y"):
        _plate(E_x=3e10)
    kw = {k: v for k, v in PLATE.items() if k != "E"}
    with pytest.raises(InputError, match="needs E, or both E_x and E_y"):
        bwim.Bridge.plate(**kw, E_x=3e10)
    with pytest.raises(InputError, match=r"E_y must be a scalar or have shape \(4,\)"):
        bwim.Bridge.plate(**kw, E_x=3e10, E_y=[3e10, 3e10], zones=(2, 2))
    with pytest.raises(InputError, match=r"E_x must be positive, got -1"):
        _plate().with_params(E_x=-1.0)
    with pytest.raises(InputError, match=r"unknown parameter\(s\) \['E_girder'\]"):
        _plate().with_params(E_girder=3e10)


def test_girder_off_node_line():
    g = bwim.Girder(y=2.5, I=0.1, z_bottom=0.8, E=35e9, mu=1000.0)
    with pytest.raises(InputError, match=r"girders\[0\].y = 2.5 m is not on a node line"):
        _plate(girders=[g])
    off = bwim.Girder(y=9.0, I=0.1, z_bottom=0.8, E=35e9, mu=1000.0)
    with pytest.raises(InputError, match=r"girders\[0\].y = 9 m is off the deck"):
        _plate(girders=[off])
    with pytest.raises(InputError, match=r"Girder.I must be positive, got -0.1"):
        bwim.Girder(y=2.0, I=-0.1, z_bottom=0.8, E=35e9, mu=1000.0)


def test_sensor_and_load_off_deck():
    bridge = _plate()
    ok = [bwim.Sensor(x=6.0, y=4.0)]
    with pytest.raises(InputError, match=r"sensor 'strain_x@12.5,4' at x = 12.5 m, y = 4 m "
                                         r"is off the deck \(12 m × 8 m\)"):
        bridge.static([bwim.PointLoad(x=6.0, y=4.0, P=1.0)], [bwim.Sensor(x=12.5, y=4.0)])
    with pytest.raises(InputError, match=r"load at x = 3 m, y = -1 m is off the deck"):
        bridge.static([bwim.PointLoad(x=3.0, y=-1.0, P=1.0)], ok)
    with pytest.raises(InputError, match="unknown sensor kind 'stress'"):
        bwim.Sensor(x=1.0, y=1.0, kind="stress")
    with pytest.raises(InputError, match=r"PointLoad.P must be finite, got inf"):
        bwim.PointLoad(x=1.0, y=1.0, P=np.inf)


def test_beam_specific_errors():
    beam = bwim.Bridge.beam(length=20.0, n_elements=10, E=3e10, I=1.0, mu=1e4)
    with pytest.raises(InputError, match="needs z_bottom"):
        beam.static([bwim.PointLoad(x=10.0, P=1.0)], [bwim.Sensor(x=10.0)])
    with pytest.raises(InputError, match="no strain_y"):
        beam.sensor_matrix([bwim.Sensor(x=10.0, kind="strain_y")])
    with pytest.raises(InputError, match=r"n_elements must be a positive integer, got None"):
        bwim.Bridge.beam(length=20.0, E=3e10, I=1.0, mu=1e4)
    with pytest.raises(InputError, match=r"I must be positive, got 0"):
        bwim.Bridge.beam(length=20.0, n_elements=10, E=3e10, I=0.0, mu=1e4)


def test_mechanism_is_a_numerical_error():
    free = _plate(supports={"x0": "free", "x_end": "free"})
    with pytest.raises(NumericalError, match="not positive definite"):
        free.static([bwim.PointLoad(x=6.0, y=4.0, P=1.0)], [bwim.Sensor(x=6.0, y=4.0)])
