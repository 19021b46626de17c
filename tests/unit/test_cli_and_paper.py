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
    bridge = paper.vransko_bridge()
    g = bridge.model.grid
    assert (g.nx, g.ny) == (10, 10)
    np.testing.assert_allclose(np.diff(g.x_lines), 2.48)
    assert len(bridge.model.girders) == 5
    assert set(bridge.params) == {"E_x", "E_y", "mu", "E_girder", "mu_girder"}
    s = paper.vransko_sensors()
    assert len(s) == 27
    assert all(g.on_y_line(x.y) is not None and g.on_x_line(x.x) is not None for x in s)
    f = bridge.modes(3).frequencies
    assert 3.0 < f[0] < 7.0  # a 24.8 m composite span
    strains = bridge.static([bwim.PointLoad(x=12.4, y=3.0, P=1e5)], s)
    assert strains.max() > 0



def test_run_demo_checks_n_modes():
    from bwim.errors import InputError
    from bwim.paper.demo import run_demo

    with pytest.raises(InputError, match="n_modes"):
        run_demo(n_modes=0)
