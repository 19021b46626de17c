"""Static B-WIM (bwim.wim): the matrix method and Moses' algorithm on exact static data,
channel selection, the FE model's line, plots and bad input.

References: the matrix method of OBrien, Quilligan & Karoumi (2006), "Calculating an
influence line from direct measurements", Proc. ICE Bridge Eng. 159(1) — linear least
squares in the ordinates, so data made by a piecewise-linear line on the same grid give
that line back exactly; Moses (1979), ASCE J. Transp. Eng. 105(3) — least squares in the
axle weights, exact on data made by the same influence line.
"""

import dataclasses

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.errors import InputError
from bwim.records import Passage, Record
from bwim.sensors import Sensor
from bwim.wim import (
    Channel,
    InfluenceLine,
    calibrate_influence_line,
    group_axles,
    model_influence_line,
    resolve_channels,
    weigh_static,
)

from tests.references import beam_midspan_point_load

L = 10.0  # span of the synthetic lines, m
H = 0.05  # their ordinate spacing, m
SPEED, RATE = 10.0, 200.0  # one sample per ordinate: v / fs = H
SENSORS = (Sensor(x=5.0, y=1.0, name="a"), Sensor(x=5.0, y=3.0, name="b"))


def _true_line(rng, *, smooth=False) -> InfluenceLine:
    """Two lines zero at both ends: a sine arch with a random smooth bump, plus (unless
    ``smooth``) a random 10 % wiggle at every ordinate."""
    x = np.linspace(0.0, L, round(L / H) + 1)
    cols = []
    for _ in SENSORS:
        c, a = rng.uniform(2.0, 8.0), rng.uniform(-0.3, 0.3)
        wiggle = 0.0 if smooth else 0.1 * rng.standard_normal(x.size)
        col = np.sin(np.pi * x / L) + a * np.exp(-(((x - c) / 1.0) ** 2)) + wiggle
        col[[0, -1]] = 0.0
        cols.append(1e-9 * col)
    return InfluenceLine(x=x, ordinates=np.stack(cols, axis=1),
                         channels=tuple(Channel.of([s]) for s in SENSORS), lane=2.0,
                         track_width=2.0)


def _static_record(il: InfluenceLine, loads, spacings, *, delay=0.0, speed=SPEED,
                   rate=RATE, lane=2.0) -> Record:
    """The record a static bridge of line ``il`` gives, from ``delay`` s before entry to
    the last axle's exit."""
    p = Passage(speed=speed, lane=lane, axle_spacings=spacings, track_width=2.0,
                delay=delay)
    n = round((delay + (L + p.axle_offsets[-1]) / speed) * rate)
    t = np.arange(n + 1) / rate
    return Record(time=t, data=il.response(p, np.asarray(loads, float), t), sensors=SENSORS,
                  passages=(p,))


@pytest.fixture
def line(rng):
    return _true_line(rng)


def test_matrix_method_recovers_a_piecewise_linear_line_exactly(line):
    loads = [60e3, 110e3]
    rec = _static_record(line, loads, [5.5])
    il = calibrate_influence_line([rec], loads, channels="each", regularization=0.0)
    # the default support is OBrien et al.'s: first axle's entry to last axle's exit
    assert il.support == pytest.approx((0.0, L))
    assert il.spacing == pytest.approx(H)
    assert il.channel_names == ("a", "b") and il.source == "matrix method"
    # measured 1e-15: linear least squares with exact data
    np.testing.assert_allclose(il.ordinates, line.ordinates, rtol=0,
                               atol=1e-10 * np.abs(line.ordinates).max())
    assert il.residual < 1e-10


def test_several_records_stack_and_regularization_is_scale_free(rng):
    line = _true_line(rng, smooth=True)
    loads = np.array([60e3, 110e3])
    recs = [_static_record(line, loads, [5.5], speed=v, delay=d)
            for v, d in ((10.0, 0.0), (7.0, 0.25))]
    noisy = [r.with_noise(0.02, seed=k) for k, r in enumerate(recs)]
    err = {}
    for ell in (0.0, 0.1):
        il = calibrate_influence_line(noisy, loads, channels="each", regularization=ell,
                                      support=(0.0, L))
        err[ell] = np.abs(il.ordinates - line.at(il.x)).max() / np.abs(line.ordinates).max()
        # λ is relative to the data: loads and readings × 3 give the same line
        scaled = [dataclasses.replace(r, data=3 * r.data) for r in noisy]
        il3 = calibrate_influence_line(scaled, 3 * loads, channels="each",
                                       regularization=ell, support=(0.0, L))
        np.testing.assert_allclose(il3.ordinates, il.ordinates, rtol=1e-9,
                                   atol=1e-12 * np.abs(il.ordinates).max())
    # 2 % noise: measured 4.9 % error unregularised, 1.3 % with the default 0.1 m smoothing
    assert err[0.1] < 0.02 and err[0.1] < 0.5 * err[0.0]


def test_moses_is_exact_on_static_data(line):
    loads = np.array([50e3, 90e3, 80e3])
    rec = _static_record(line, loads, [3.8, 1.3], delay=0.4)  # 0.4 s before entry
    w = weigh_static(rec, influence=line)
    np.testing.assert_allclose(w.axle_weights, loads, rtol=1e-10)
    assert w.gvw == pytest.approx(loads.sum(), rel=1e-12)
    assert w.residual < 1e-10
    # the window: from the first axle's entry to the last axle's exit
    assert w.time[0] == pytest.approx(0.4, abs=1.5 / RATE)
    assert w.time[-1] == pytest.approx(0.4 + (L + 5.1) / SPEED, abs=1.5 / RATE)
    np.testing.assert_allclose(w.fitted, w.measured, atol=1e-9 * np.abs(w.measured).max())
    assert w.groups == ((0,), (1,), (2,))


def test_moses_with_axle_groups(line):
    loads = np.array([50e3, 85e3, 85e3])
    rec = _static_record(line, loads, [3.8, 1.3])
    groups = group_axles(rec.passage)
    assert groups == ((0,), (1, 2))
    w = weigh_static(rec, influence=line, groups=groups)
    np.testing.assert_allclose(w.axle_weights, loads, rtol=1e-10)
    np.testing.assert_allclose(w.group_weights, [50e3, 170e3], rtol=1e-10)
    assert group_axles([3.6, 5.9, 1.31, 1.31]) == ((0,), (1,), (2, 3, 4))
    assert group_axles(np.zeros(0)) == ((0,),)


def test_calibrate_then_weigh_another_vehicle(rng):
    line = _true_line(rng, smooth=True)
    cal = [_static_record(line, [60e3, 110e3], [5.5], speed=v) for v in (10.0, 12.5)]
    il = calibrate_influence_line(cal, [60e3, 110e3], channels=[["a", "b"]],
                                  support=(0.0, L))
    assert il.channel_names == ("a+b",)
    loads = np.array([70e3, 80e3, 75e3, 74e3])
    rec = _static_record(line, loads, [3.0, 6.0, 1.3])
    w = weigh_static(rec, influence=il)
    # measured 0.003 %: only the light smoothing of the line differs from the truth
    np.testing.assert_allclose(w.axle_weights, loads, rtol=2e-4)


def test_influence_line_at():
    il = InfluenceLine(x=[1.0, 2.0, 3.0], ordinates=[0.0, 2.0, 0.0],
                       channels=(Channel.of([SENSORS[0]]),), lane=0.0)
    assert il.at([0.5, 1.0, 1.5, 2.0, 2.75, 3.0, 4.0])[:, 0] == pytest.approx(
        [0.0, 0.0, 1.0, 2.0, 0.5, 0.0, 0.0])
    assert il.at(np.ones((4, 3))).shape == (4, 3, 1)
    with pytest.raises(InputError, match="finite"):
        InfluenceLine(x=[1.0, 2.0], ordinates=[0.0, np.nan], channels=il.channels, lane=0.0)
    with pytest.raises(InputError, match="shape"):
        InfluenceLine(x=[1.0, 2.0], ordinates=np.zeros((2, 2)), channels=il.channels,
                      lane=0.0)


def test_resolve_channels_on_the_paper_sensors():
    sensors = paper.sensors()
    (mid,) = resolve_channels(sensors, "sum")
    assert [(s.x, s.y, s.kind.value) for s in mid.sensors] == [
        (6.0, 2.0, "strain_x"), (6.0, 4.0, "strain_x"), (6.0, 6.0, "strain_x")]
    (quarter,) = resolve_channels(sensors, "sum", section_x=2.0)
    assert {s.x for s in quarter.sensors} == {3.0}
    assert len(resolve_channels(sensors, "each")) == len(resolve_channels(sensors, None)) == 18
    chans = resolve_channels(sensors, ["x6_4", ("x3_2", sensors[1])])
    assert [c.name for c in chans] == ["x6_4", "x3_2+x3_4"]
    with pytest.raises(InputError, match="no sensor 'nope'"):
        resolve_channels(sensors, ["nope"])
    with pytest.raises(InputError, match="one kind"):
        resolve_channels(sensors, [("x6_4", "y6_4")])
    with pytest.raises(InputError, match="unknown channels 'mean'"):
        resolve_channels(sensors, "mean")
    with pytest.raises(InputError, match="strain_x"):
        resolve_channels([Sensor(x=6.0, kind="deflection")], "sum")


def test_model_line_is_the_static_response_of_a_unit_axle():
    bridge, sensors = paper.slab_bridge(), paper.sensors()
    fe = model_influence_line(bridge, sensors, lane=2.0, track_width=2.0, spacing=0.5)
    assert fe.source == "FE model" and fe.support == (0.0, 12.0)
    mid = [s for s in sensors if s.kind.value == "strain_x" and s.x == 6.0]
    k = int(np.flatnonzero(np.isclose(fe.x, 4.5))[0])
    direct = bridge.static([bwim.PointLoad(x=4.5, y=1.0, P=0.5),
                            bwim.PointLoad(x=4.5, y=3.0, P=0.5)], mid).sum()
    assert fe.ordinates[k, 0] == pytest.approx(direct, rel=1e-10)
    # one force on the centre line
    one = model_influence_line(bridge, sensors, channels=["x6_2"], lane=2.0, spacing=0.5)
    assert one.ordinates[k, 0] == pytest.approx(
        bridge.static([bwim.PointLoad(x=4.5, y=2.0, P=1.0)], mid[:1])[0], rel=1e-10)
    # a beam (y ignored): a unit load at mid-span gives the mid-span soffit strain
    # (L/4) z_b / (E I) (Roark, Table 8.1 case 1e), and the line is the triangle of the
    # mid-span moment; measured 1e-15 (cubic elements are exact for point loads at nodes)
    beam = bwim.Bridge.beam(length=10.0, n_elements=20, E=3e10, I=0.5, mu=1e4, z_bottom=0.6)
    b = model_influence_line(beam, [Sensor(x=5.0)], spacing=0.5)
    _, moment = beam_midspan_point_load(10.0, 3e10 * 0.5, 1.0)
    triangle = moment * 0.6 / (3e10 * 0.5) * np.minimum(b.x, 10.0 - b.x) / 5.0
    np.testing.assert_allclose(b.ordinates[:, 0], triangle, rtol=1e-9, atol=1e-20)
    with pytest.raises(InputError, match="off the deck"):
        model_influence_line(bridge, sensors, lane=7.5, track_width=2.0)
    with pytest.raises(InputError, match="lane"):
        model_influence_line(bridge, sensors)


def test_plots_return_figures(line):
    from matplotlib.figure import Figure

    from bwim.plots.wim import plot_influence_line, plot_static_fit

    fig = plot_influence_line(line, reference=line)
    assert isinstance(fig, Figure) and len(fig.axes[0].lines) == 2 * 2 + 1
    rec = _static_record(line, [60e3, 110e3], [5.5])
    fig = plot_static_fit(weigh_static(rec, influence=line), record=rec)
    assert isinstance(fig, Figure) and "GVW 170.0 kN" in fig.axes[0].get_title()


# --- bad input ----------------------------------------------------------------------------

@pytest.fixture
def cal(line):
    return _static_record(line, [60e3, 110e3], [5.5])


def test_calibration_rejects_bad_records(cal, line):
    loads = [60e3, 110e3]
    with pytest.raises(InputError, match="records is empty"):
        calibrate_influence_line([], loads)
    with pytest.raises(InputError, match="0 passages"):
        calibrate_influence_line([dataclasses.replace(cal, passages=())], loads)
    two = dataclasses.replace(cal, passages=(cal.passage, cal.passage))
    with pytest.raises(InputError, match="2 passages"):
        calibrate_influence_line([two], loads)
    with pytest.raises(InputError, match=r"records\[1\] is a ndarray"):
        calibrate_influence_line([cal, cal.data], loads)
    with pytest.raises(InputError, match="3 axles but records"):
        calibrate_influence_line([cal], [60e3, 110e3, 90e3])
    with pytest.raises(InputError, match="3 axles but records"):
        calibrate_influence_line([cal], bwim.vehicles.three_axle_truck())
    other_lane = dataclasses.replace(
        cal, passages=(dataclasses.replace(cal.passage, lane=6.0),))
    with pytest.raises(InputError, match="lanes"):
        calibrate_influence_line([cal, other_lane], loads)
    short = dataclasses.replace(cal, time=cal.time[:20], data=cal.data[:20])
    with pytest.raises(InputError, match="shorter than the vehicle"):
        calibrate_influence_line([short], loads)
    with pytest.raises(InputError, match="Record"):
        calibrate_influence_line("records", loads)


def test_calibration_rejects_bad_numbers(cal):
    loads = [60e3, 110e3]
    with pytest.raises(InputError, match="positive and finite"):
        calibrate_influence_line([cal], [60e3, np.nan])
    with pytest.raises(InputError, match="positive and finite"):
        calibrate_influence_line([cal], [60e3, -1.0])
    with pytest.raises(InputError, match="vehicle must be"):
        calibrate_influence_line([cal], object())
    with pytest.raises(InputError, match="regularization must be finite"):
        calibrate_influence_line([cal], loads, regularization=np.nan)
    with pytest.raises(InputError, match="regularization"):
        calibrate_influence_line([cal], loads, regularization=-0.1)
    with pytest.raises(InputError, match="spacing must be positive"):
        calibrate_influence_line([cal], loads, spacing=0.0)
    with pytest.raises(InputError, match="support"):
        calibrate_influence_line([cal], loads, support=(5.0, 1.0))
    with pytest.raises(InputError, match="support must be finite"):
        calibrate_influence_line([cal], loads, support=(0.0, np.inf))
    with pytest.raises(InputError, match="no sensor 'x'"):
        calibrate_influence_line([cal], loads, channels=["x"])
    with pytest.raises(bwim.NumericalError, match="not determined"):
        # ordinates every 10 mm, 50 mm between samples, no smoothing: a singular system
        calibrate_influence_line([cal], loads, spacing=0.01, regularization=0.0)


def test_weighing_rejects_bad_input(cal, line):
    with pytest.raises(InputError, match="InfluenceLine"):
        weigh_static(cal, influence=line.ordinates)
    with pytest.raises(InputError, match="Record"):
        weigh_static(cal.data, influence=line)
    with pytest.raises(InputError, match="0 passages"):
        weigh_static(dataclasses.replace(cal, passages=()), influence=line)
    with pytest.raises(InputError, match="no channel 'b'"):
        weigh_static(cal.channels(["a"]), influence=line)
    far = dataclasses.replace(cal.passage, lane=6.0)
    with pytest.raises(InputError, match="lane 6 m but the influence line is for lane 2 m"):
        weigh_static(cal, influence=line, passage=far)
    late = dataclasses.replace(cal.passage, delay=100.0)
    with pytest.raises(InputError, match="must cover the crossing"):
        weigh_static(cal, influence=line, passage=late)
    with pytest.raises(InputError, match="every axle 0 … 1 exactly once"):
        weigh_static(cal, influence=line, groups=[[0]])
    with pytest.raises(InputError, match="groups must be sequences"):
        weigh_static(cal, influence=line, groups=[["front"]])


def test_unit_readings_are_the_matrix_methods_design_times_the_ordinates():
    """The lines' readings under each axle (bwim.wim.weigh_kernels.group_readings, each axle
    its own group) are, byte for byte (signed zeros too), the matrix method's sparse
    design times the interior ordinates (bwim.wim.influence_line.hat_design, the
    reference): positions between nodes, on nodes, in the end cells and off the support,
    on random meshes and ordinates."""
    from bwim.wim.influence_line import hat_design
    from bwim.wim.weigh_kernels import group_readings

    rng = np.random.default_rng(7)
    for trial in range(300):
        n, h, x0 = int(rng.integers(2, 40)), rng.uniform(0.05, 1.0), rng.uniform(-5, 5)
        n_t, n_ax, n_c = int(rng.integers(1, 200)), int(rng.integers(1, 6)), int(
            rng.integers(1, 13))
        pos = x0 + rng.uniform(-2.0, n * h + 2.0, size=(n_t, n_ax))
        if trial % 3 == 0:  # exactly on the nodes, the ends and beyond
            pos[:, 0] = x0 + h * rng.integers(-1, n + 2, size=n_t)
        ords = rng.normal(size=(n - 1, n_c)) * 10.0 ** rng.uniform(-9, 3)
        ords[rng.random(ords.shape) < 0.2] = -0.0
        H = hat_design(pos.reshape(-1, 1), np.ones(1), x0, h, n)
        expect = np.asarray(H @ ords).reshape(n_t, n_ax, n_c)
        got = group_readings(pos, ords, x0, h, n, np.eye(n_ax))
        assert got.tobytes() == expect.tobytes()
