"""Static B-WIM on the paper's slab bridge: the matrix method against the FE model's static
influence line, and Moses' algorithm with the calibrated line.

References
----------
* Matrix method: OBrien, Quilligan & Karoumi (2006), "Calculating an influence line from
  direct measurements", Proc. ICE Bridge Eng. 159(1) — the calibrated line is the static
  influence line when the records are static, and averages the dynamics of several
  crossings otherwise.
* The reference line is the FE model's static influence line (influence surfaces by
  reciprocity, docs/theory.md §1.5), checked against direct static solutions in
  tests/unit/test_wim.py.
* Moses (1979), ASCE J. Transp. Eng. 105(3): static least squares for the axle weights.

The slab's first mode is 7.9 Hz, so at 20 m/s the speed parameter v / (2 f₁ L) is 0.11:
the bridge's own vibration under constant moving forces is part of every 20 m/s record
(measured below), and a quasi-static crossing (2 m/s) is the tight check.
"""

import dataclasses

import numpy as np
import pytest

from bwim import paper
from bwim.dynamics import simulate
from bwim.vehicles import MovingForces
from bwim.wim import calibrate_influence_line, model_influence_line, weigh_static

LANE = paper.LANE


def _error(il, bridge):
    """Max and RMS difference from the FE static line, relative to its peak."""
    fe = model_influence_line(bridge, like=il)
    d = il.ordinates - fe.ordinates
    peak = np.abs(fe.ordinates).max()
    return np.abs(d).max() / peak, np.sqrt(np.mean(d**2)) / peak


@pytest.fixture(scope="module")
def setup():
    bridge, sensors = paper.slab_bridge(), paper.sensors()
    two = MovingForces(axle_loads=paper.AXLE_LOADS, axle_spacings=[paper.AXLE_SPACING],
                       track_width=paper.TRACK_WIDTH)
    three = MovingForces(axle_loads=[70e3, 110e3, 95e3], axle_spacings=[4.0, 1.4],
                         track_width=paper.TRACK_WIDTH)
    return bridge, sensors, two, three


def test_static_records_give_the_fe_line(setup):
    """Readings from the FE static influence surfaces (no dynamics): the matrix method
    returns the FE line, exactly without smoothing."""
    bridge, sensors, two, _ = setup
    rec = simulate(bridge, two, speed=20.0, lane=LANE, sensors=sensors, approach=0.0)
    p = rec.passage
    static = bridge.influence(sensors).response(p.wheel_x(rec.time), p.wheel_y[None, :],
                                                rec.truth.static_wheel_loads[None, :])
    srec = dataclasses.replace(rec, data=static)
    exact = calibrate_influence_line([srec], two, regularization=0.0)
    assert exact.support == pytest.approx((0.0, 12.0), abs=0.02)
    assert _error(exact, bridge)[0] < 1e-12  # measured 6e-16
    smoothed = calibrate_influence_line([srec], two)
    assert _error(smoothed, bridge)[0] < 1e-3  # measured 3.6e-4: the 0.1 m smoothing


def test_quasi_static_crossing_calibrates_and_weighs(setup):
    """Constant forces at 2 m/s (speed parameter 0.01): the calibrated line is the FE static
    line, and Moses weighs a different, 3-axle vehicle with it."""
    bridge, sensors, two, three = setup
    kw = dict(lane=LANE, sensors=sensors, approach=0.0, sampling_rate=100.0)
    il = calibrate_influence_line([simulate(bridge, two, speed=2.0, **kw)], two)
    assert il.channel_names == ("x6_2+x6_4+x6_6",)  # summed mid-span longitudinal gauges
    max_err, _ = _error(il, bridge)
    assert max_err < 2e-3  # measured 7.6e-4
    w = weigh_static(simulate(bridge, three, speed=2.0, **kw), influence=il)
    # measured −0.06 / +0.10 / −0.08 %, GVW −0.005 %
    np.testing.assert_allclose(w.axle_weights, three.axle_loads, rtol=2e-3)
    assert w.gvw == pytest.approx(three.axle_loads.sum(), rel=2e-4)


def test_crossing_at_20_m_per_s(setup):
    """Constant forces at 20 m/s, 1 kHz, smooth road: the calibrated line carries the
    bridge's vibration (measured 9.5 % max, 4.6 % RMS from the FE static line), and it
    weighs a different vehicle at that speed better than the static FE line does."""
    bridge, sensors, two, three = setup
    kw = dict(speed=20.0, lane=LANE, sensors=sensors, approach=0.0)
    il = calibrate_influence_line([simulate(bridge, two, **kw)], two)
    max_err, rms = _error(il, bridge)
    assert max_err < 0.12 and rms < 0.06
    rec = simulate(bridge, three, **kw)
    w = weigh_static(rec, influence=il)
    err = w.axle_weights / three.axle_loads - 1
    # measured −0.59 / +1.10 / −0.78 %, GVW +0.018 %
    assert np.abs(err).max() < 0.015
    assert w.gvw == pytest.approx(three.axle_loads.sum(), rel=5e-4)
    fe = weigh_static(rec, influence=model_influence_line(bridge, like=il))
    # with the static FE line: measured −4.0 / +5.3 / −2.4 %
    assert np.abs(fe.axle_weights / three.axle_loads - 1).max() > 2 * np.abs(err).max()


def test_several_runs_improve_the_line_on_a_rough_road():
    """The paper's sprung truck over the paper's road (axle forces vary by up to 40 %):
    one crossing gives a poor line; stacking crossings at other speeds and road seeds
    averages the dynamics out (OBrien et al. 2006 calibrate with several runs)."""
    bridge, sensors, truck = paper.slab_bridge(), paper.sensors(), paper.truck()
    runs = [simulate(bridge, truck, speed=v, lane=LANE, sensors=sensors,
                     road=paper.road(seed, approach=50.0), approach=50.0)
            for v, seed in ((20.0, 1), (16.0, 2), (24.0, 3), (18.0, 4), (22.0, 5))]
    errors = [_error(calibrate_influence_line(runs[:n], truck), bridge) for n in (1, 3, 5)]
    # measured max 29.9 / 12.7 / 10.4 %, RMS 16.2 / 6.6 / 5.5 % for 1 / 3 / 5 runs
    rms = [e[1] for e in errors]
    assert rms[0] > rms[1] > rms[2]
    assert rms[2] < 0.5 * rms[0] and rms[2] < 0.07
    assert errors[2][0] < 0.5 * errors[0][0]
