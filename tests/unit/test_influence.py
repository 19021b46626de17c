"""Influence surfaces by reciprocity equal direct solves; sensitivities equal finite
differences (docs/theory.md §1.5)."""

import numpy as np
import pytest

import bwim
from bwim.fe import static_sensitivities


def _bridge():
    girders = [bwim.Girder(y=y, I=0.08, z_bottom=0.9, E=35e9, mu=1200.0, J=0.01)
               for y in (1.0, 5.0)]
    return bwim.Bridge.plate(length=10.0, width=6.0, nx=10, ny=6, thickness=0.25, E_x=32e9,
                             E_y=28e9, mu=600.0, zones=(2, 3), girders=girders)


SENSORS = [
    bwim.Sensor(x=5.0, y=1.0, kind="strain_x"),  # on a girder line: girder soffit strain
    bwim.Sensor(x=5.0, y=3.0, kind="strain_x"),
    bwim.Sensor(x=2.5, y=3.3, kind="strain_y"),  # inside an element
    bwim.Sensor(x=7.0, y=4.0, kind="deflection"),
]


def test_influence_surface_equals_direct_solves(rng):
    bridge = _bridge()
    inf = bridge.influence(SENSORS)
    x = rng.uniform(0, 10, 25)
    y = rng.uniform(0, 6, 25)
    ordinates = inf.at(x, y)
    direct = np.stack([bridge.static([bwim.PointLoad(x=xi, y=yi, P=1.0)], SENSORS)
                       for xi, yi in zip(x, y, strict=True)])
    np.testing.assert_allclose(ordinates, direct, rtol=1e-9, atol=1e-12 * abs(direct).max())


def test_influence_response_sums_wheels_and_ignores_points_off_deck():
    bridge = _bridge()
    inf = bridge.influence(SENSORS)
    x = np.array([[-1.0, 4.0], [3.0, 8.0], [9.0, 14.0]])
    y = np.array([[2.0, 4.0]])
    P = np.array([[5e4, 7e4]])
    resp = inf.response(x, y, P)
    for c in range(3):
        loads = [bwim.PointLoad(x=xi, y=yi, P=p) for xi, yi, p in zip(x[c], y[0], P[0], strict=True)
                 if 0 <= xi <= 10]
        np.testing.assert_allclose(resp[c], bridge.static(loads, SENSORS), rtol=1e-9,
                                   atol=1e-15)


@pytest.mark.parametrize("family", ["E_x", "E_y", "E_girder"])
def test_sensitivities_equal_finite_differences(family):
    bridge = _bridge()
    x = np.array([[3.0, 6.5], [5.0, 8.0]])
    y = np.array([[1.5, 4.5]])
    P = np.array([[6e4, 1e5]])
    sens = static_sensitivities(bridge, SENSORS, x, y, P, wrt=[family])
    base = bridge.params[family]
    for k in range(base.size):
        step = 1e-4 * base[k]  # round-off dominates below ~1e-5 (measured)
        up, down = base.copy(), base.copy()
        up[k] += step
        down[k] -= step
        r_up = bridge.with_params(**{family: up}).influence(SENSORS).response(x, y, P)
        r_dn = bridge.with_params(**{family: down}).influence(SENSORS).response(x, y, P)
        fd = (r_up - r_dn) / (2 * step)
        col = sens.values[:, :, k]
        np.testing.assert_allclose(col, fd, rtol=1e-5, atol=1e-8 * abs(fd).max() + 1e-30)
    assert sens.names == (family,) * base.size


def test_beam_influence_line_and_sensitivity():
    beam = bwim.Bridge.beam(length=20.0, n_elements=20, E=[3e10, 3.5e10], I=0.9, mu=9e3,
                            z_bottom=0.7, zones=2)
    s = [bwim.Sensor(x=10.0), bwim.Sensor(x=5.0, kind="deflection")]
    inf = beam.influence(s)
    xs = np.linspace(0, 20, 41)
    direct = np.stack([beam.static([bwim.PointLoad(x=v, P=1.0)], s) for v in xs])
    np.testing.assert_allclose(inf.at(xs), direct, rtol=1e-9, atol=1e-20)
    sens = static_sensitivities(beam, s, xs[:, None], None, np.ones((1, 1)))
    assert sens.values.shape == (41, 2, 2)
    # the homogeneous-degree-(-1) identity: Σ_p p ∂r/∂p = −r for a stiffness-linear model
    total = np.einsum("csp,p->cs", sens.values, beam.E_x)
    np.testing.assert_allclose(total, -direct, rtol=1e-9, atol=1e-20)
