"""Longitudinal joints as zones (bwim.fe.joints), in the scenario's [bridge] and in the
site's logger fit.

References: the grid's own lines (which column holds a y, counted by hand below), the
parameters same-model readings were made with (the fit's algebra only: its accuracy on
data from another model is ``tests/validation/test_site_model.py``).
"""


import numpy as np
import pytest

from bwim.calibration import calibrate_logger
from bwim.calibration.quasistatic import moving_force_columns
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.fe.convergence import refine
from bwim.fe.joints import joint_zones, with_joints
from bwim.records import Passage, Record
from bwim.scenario import build_bridge, scenario_from_dict
from bwim.sensors import Sensor


def _plate(ny=6):
    return Bridge.plate(length=8.0, width=6.0, nx=4, ny=ny, thickness=0.5, mu=1200.0,
                        E=30e9, poisson=0.2, damping_ratio=0.03)


def test_a_joint_is_the_column_of_elements_that_holds_its_line():
    """6 m wide, 6 elements: y = 2.5 lies in column 2 (2–3 m), y = 4.0 on a line belongs
    to column 4 (its +y side), y = 5.99 to column 5; every element of a column along the
    span carries the joint's label."""
    zones = joint_zones(_plate().model.grid, [2.5, 4.0, 5.99])
    assert zones.shape == (4, 6)
    np.testing.assert_array_equal(zones[0], [0, 0, 1, 0, 2, 3])
    assert np.all(zones == zones[0])


def test_with_joints_gives_each_joint_its_zone_and_stiffness():
    """The joints' E_y is the deck's × their stiffness; E_x and mu the deck's; a
    bisection keeps the joint (both halves of its column)."""
    b = with_joints(_plate(), [2.5], [0.1])
    assert b.model.n_zones == 2
    np.testing.assert_allclose(b.E_y, [30e9, 3e9])
    np.testing.assert_allclose(b.E_x, [30e9, 30e9])
    fine = refine(b).model
    np.testing.assert_array_equal(fine.zone_of_element.reshape(8, 12)[0],
                                  [0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0])


@pytest.mark.parametrize("joints, stiffness, match", [
    ([], None, "one or more"), ([7.0], None, "inside the deck"), ([2.2, 2.8], None,
                                                                  "one column"),
    ([2.5], [0.0], "stiffness"), ([2.5], [0.1, 0.2], "stiffness"),
])
def test_bad_joints_are_one_line_errors(joints, stiffness, match):
    with pytest.raises(InputError, match=match):
        with_joints(_plate(), joints, stiffness)


def test_the_scenarios_joints():
    """``joints = [y]`` in a plate's [bridge] makes the zones; with zones it is refused."""
    table = {"kind": "plate", "length": 8.0, "width": 6.0, "nx": 4, "ny": 6,
             "thickness": 0.5, "E": 30e9, "mu": 1200.0, "joints": [2.5]}
    b = build_bridge(scenario_from_dict({"bridge": table}, source="s.toml"))
    np.testing.assert_array_equal(b.model.zone_of_element.reshape(4, 6)[1],
                                  [0, 0, 1, 0, 0, 0])
    with pytest.raises(InputError, match="joints"):
        scenario_from_dict({"bridge": {**table, "zones": [2, 1]}}, source="s.toml")


FS = 256.0
LOADS = np.array([60e3, 110e3, 90e3])


def test_the_logger_fit_finds_a_joints_stiffness():
    """Same-model readings from the plate with a joint at y = 2.5 m of stiffness 0.1
    (below the deck's ratio bound of 1/5): declared as a joint, the fit returns the
    deck's and the joint's E_y (measured within 2e-7; tolerance 2e-6); not declared as a
    joint, the same zone stops at the deck's bound and the fit is no success."""
    truth = with_joints(_plate(), [2.5], [0.1]).with_params(E_y=np.array([0.8, 0.08]) * 30e9)
    start = with_joints(_plate(), [2.5])
    sensors = tuple(Sensor(x=4.0, y=y, kind="strain_x", name=f"g{k}")
                    for k, y in enumerate((0.5, 1.5, 2.5, 3.5, 4.5, 5.5)))
    rng = np.random.default_rng(2)
    records = []
    for speed, lane in ((18.0, 1.4), (22.0, 2.0), (20.0, 3.3)):
        p = Passage(speed=speed, lane=lane, axle_spacings=(3.5, 5.0), track_width=1.8,
                    delay=0.4)
        t = np.arange(int(2.2 * FS)) / FS
        x = p.wheel_x(t)
        cols = moving_force_columns(truth, sensors, x, np.broadcast_to(p.wheel_y, x.shape),
                                    np.repeat(LOADS / 2, 2), p.wheel_axle,
                                    np.ones((t.size, 3, 1)), fs=FS, n_modes=0)
        data = 2e5 * cols[:, :, 0].sum(axis=1) + 1e-6 * rng.standard_normal((t.size, 6))
        records.append(Record(time=t, data=data, sensors=sensors, passages=(p,)))
    kw = {"origin": 0.0, "lateral": None, "n_basis": 2, "inertia_modes": 0, "mass": False}
    cal = calibrate_logger(start, records, LOADS, joints=(1,), **kw)
    assert cal.success, cal.message
    assert cal.params["E_y[0]"] / 30e9 == pytest.approx(0.8, rel=2e-6)
    assert cal.params["E_y[1]"] / 30e9 == pytest.approx(0.08, rel=2e-6)
    stiff = calibrate_logger(start, records, LOADS, **kw)
    assert not stiff.success and "E_y[1]" in stiff.at_bound
    with pytest.raises(InputError, match="joints"):
        calibrate_logger(start, records, LOADS, joints=(2,), **kw)
