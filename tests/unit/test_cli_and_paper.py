"""The command line (called as a function) and the paper's model definitions."""

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.cli import main


def test_demo_bad_input_is_one_line_exit_2(capsys):
    assert main(["demo", "--modes", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("bwim: error: --modes")


def test_paper_slab_bridge_and_sensors():
    bridge = paper.slab_bridge()
    s = paper.sensors()
    assert len(s) == 18 and {x.kind.value for x in s} == {"strain_x", "strain_y"}
    assert bridge.params["E_x"][0] == 35e9 and bridge.params["mu"][0] == 1560.0
    zoned = paper.slab_bridge(zones=(4, 4))
    assert zoned.n_zones == 16
    # every §5.3 sensor sits on an interior zone corner, touching 4 zones
    g = zoned.model.grid
    for sensor in s[:9]:
        touched = {int(zoned.model.zone_of_element[e]) for e, _, _ in
                   g.elements_at(sensor.x, sensor.y)}
        assert len(touched) == 4


def test_vransko_bridge_layout():
    """The §5.4 deck against Euler–Bernoulli beam theory for the whole cross-section
    (Clough & Penzien eq. 18-12; Roark Table 8.1 case 1e): with ΣEI the girders' composite
    rigidities (each girder with its tributary slab) and m the deck's mass per metre,
    f₁ = π/(2L²)·√(ΣEI/m) (measured: FE 0.48 % above, the slab's own plate bending and
    the mesh) and, under equal mid-span loads P on the five girders, each girder soffit
    reads ε = (5PL/4)·z_b/ΣEI (plane sections across the deck; measured within 2.2 %, the
    load sharing between girders)."""
    bridge = paper.vransko_bridge()
    g = bridge.model.grid
    assert (g.nx, g.ny) == (10, 10)
    np.testing.assert_allclose(np.diff(g.x_lines), 2.48)
    assert len(bridge.model.girders) == 5
    assert set(bridge.params) == {"E_x", "E_y", "mu", "E_girder", "mu_girder"}
    s = paper.vransko_sensors()
    assert len(s) == 27
    assert all(g.on_y_line(x.y) is not None and g.on_x_line(x.x) is not None for x in s)
    girders = bridge.model.girders
    L = paper.VRANSKO_LENGTH
    EI = sum(gd.E * gd.I for gd in girders)
    m = paper.VRANSKO_SLAB_MU * paper.VRANSKO_WIDTH + 5 * paper.VRANSKO_GIRDER_MU
    f1 = np.pi / (2 * L**2) * np.sqrt(EI / m)
    assert bridge.modes(3).frequencies[0] == pytest.approx(f1, rel=0.01)
    P = 1e5
    loads = [bwim.PointLoad(x=L / 2, y=gd.y, P=P) for gd in girders]
    at = [bwim.Sensor(x=L / 2, y=gd.y, kind="strain_x") for gd in girders]
    beam = np.array([5 * P * L / 4 * gd.z_bottom / EI for gd in girders])
    np.testing.assert_allclose(bridge.static(loads, at).ravel(), beam, rtol=0.035)


def test_run_demo_checks_n_modes():
    from bwim.errors import InputError
    from bwim.paper.demo import run_demo

    with pytest.raises(InputError, match="n_modes"):
        run_demo(n_modes=0)
