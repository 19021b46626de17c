"""simulate(): records, several vehicles, contact loss and bad input."""

import warnings

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.dynamics import simulate
from bwim.errors import InputError
from bwim.records import Record
from bwim.road import RoadProfile
from bwim.vehicles import MovingForces, SprungMass, two_axle_truck

SENSORS = [bwim.Sensor(x=6.0, y=y) for y in (2.0, 6.0)]


def _forces(loads=(60e3, 100e3)):
    return MovingForces(axle_loads=list(loads), axle_spacings=[5.5], track_width=2.0)


def test_record_layout_and_time_origin():
    bridge = paper.slab_bridge()
    rec = simulate(bridge, two_axle_truck(), speed=20.0, lane=2.0, sensors=SENSORS,
                   approach=10.0, tail=0.1)
    fs = 1000.0
    assert rec.time[0] == 0.0 and rec.sampling_rate == pytest.approx(fs)
    # last axle leaves at (12 + 5.5) / 20 s, then 0.1 s of free vibration
    assert rec.time[-1] == pytest.approx((12 + 5.5) / 20 + 0.1, abs=1.5 / fs)
    # the settings a re-simulation needs travel with the record
    assert rec.settings == bwim.SimulationSettings(approach=10.0, tail=0.1)
    assert rec.time_after_exit(bridge.length) == pytest.approx(0.1, abs=1.0 / fs)
    assert rec.data.shape == (rec.time.size, 2)
    truth = rec.truth
    assert truth.wheel_forces.shape == (rec.time.size, 4)
    np.testing.assert_allclose(truth.axle_forces, truth.wheel_forces.reshape(-1, 2, 2).sum(2))
    np.testing.assert_allclose(truth.static_axle_loads, [59.5e3, 108.6e3])
    assert rec.passage.speed == 20.0 and rec.passage.lane == 2.0
    # the first axle enters at t = 0: the bridge is still at rest just before
    assert np.abs(rec.data[0]).max() < 1e-3 * np.abs(rec.data).max()


def test_two_vehicles_superpose_for_moving_forces():
    bridge = paper.slab_bridge()
    a, b = _forces(), _forces((40e3, 70e3))
    both = simulate(bridge, [a, b], speed=[20.0, 18.0], lane=[2.0, 6.0], delay=[0.0, 0.2],
                    sensors=SENSORS, approach=0.0, tail=0.3)
    one = simulate(bridge, a, speed=20.0, lane=2.0, sensors=SENSORS, approach=0.0,
                   tail=both.time[-1] - (17.5 / 20.0) + 1e-3)
    two = simulate(bridge, b, speed=18.0, lane=6.0, sensors=SENSORS, approach=0.0,
                   tail=0.3 + 0.2)
    n = both.time.size
    shifted = np.zeros_like(both.data)
    k = round(0.2 * 1000)
    shifted[k:] = two.data[: n - k]
    np.testing.assert_allclose(both.data, one.data[:n] + shifted,
                               atol=1e-9 * np.abs(both.data).max())
    assert len(both.passages) == 2 and both.passages[1].delay == pytest.approx(0.2)
    with pytest.raises(InputError, match="has 2 vehicles"):
        _ = both.passage


def test_two_trucks_following():
    bridge = paper.slab_bridge()
    rec = simulate(bridge, [two_axle_truck(), two_axle_truck()], speed=20.0, lane=2.0,
                   delay=[0.0, 0.5], sensors=SENSORS, approach=5.0)
    assert len(rec.truths) == 2
    for t in rec.truths:
        assert np.all(np.abs(t.axle_forces / t.static_axle_loads - 1) < 0.2)


def test_wheel_losing_contact_is_reported():
    beam = bwim.Bridge.beam(length=20.0, n_elements=20, E=3e10, I=1.0, mu=1e4, z_bottom=0.5)
    x = np.linspace(-30, 40, 7001)
    bump = np.where((x > 5) & (x < 5.3), 0.08, 0.0)  # an 8 cm step bump
    road = RoadProfile(x=x, elevation=bump)
    light = SprungMass(mass=800.0, stiffness=2e6, damping=500.0)
    with pytest.warns(RuntimeWarning, match="lost contact"):
        rec = simulate(beam, light, speed=25.0, sensors=[bwim.Sensor(x=10.0)], road=road,
                       approach=10.0)
    assert rec.truth.contact_lost.all()
    assert rec.truth.wheel_forces.min() < 0


def test_iterative_reports_convergence():
    bridge = paper.slab_bridge()
    rec = simulate(bridge, two_axle_truck(), speed=20.0, lane=2.0, sensors=SENSORS,
                   method="iterative", approach=5.0)
    assert rec.convergence.method == "iterative" and rec.convergence.converged
    assert rec.convergence.change < 1e-6 and rec.convergence.iterations >= 2
    with pytest.warns(RuntimeWarning, match="did not converge"):
        bad = simulate(bridge, two_axle_truck(), speed=20.0, lane=2.0, sensors=SENSORS,
                       method="iterative", approach=5.0, max_iter=1)
    assert not bad.convergence.converged


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        (dict(speed=0.0), "speed must be positive, got 0"),
        (dict(speed=-5.0), "speed must be positive, got -5"),
        (dict(sampling_rate=0.0), "sampling_rate must be positive"),
        (dict(lane=7.5), r"wheel at y = 8.5 m is off the deck \(width 8 m\) for lane 7.5 m"),
        (dict(lane=None), r"lane .* is required on a plate bridge"),
        (dict(road=RoadProfile.iso8608(65e-6, length=50.0, seed=1)),
         r"road profile covers x = -37.5 … 12.5 m but the crossing needs"),
        (dict(n_modes=30, sampling_rate=200.0), "sampling_rate 200 Hz is too low"),
        (dict(method="monolithic"), "unknown method 'monolithic'"),
        (dict(approach=-1.0), "approach must be >= 0 m"),
    ],
)
def test_bad_simulation_input(kwargs, pattern):
    args = dict(speed=20.0, lane=2.0, sensors=SENSORS)
    args.update(kwargs)
    with pytest.raises(InputError, match=pattern):
        simulate(paper.slab_bridge(), two_axle_truck(), **args)


def test_record_validation_and_helpers(rng):
    s = [bwim.Sensor(x=1.0, name="a"), bwim.Sensor(x=2.0, name="b")]
    t = np.arange(5) * 0.01
    with pytest.raises(InputError, match=r"non-finite sample at t = 0\.02 s in channel 'b'"):
        Record(time=t, data=np.array([[0, 0], [0, 0], [0, np.nan], [0, 0], [0, 0]]), sensors=s)
    with pytest.raises(InputError, match="strictly increasing"):
        Record(time=t[::-1], data=np.zeros((5, 2)), sensors=s)
    rec = Record(time=t, data=rng.standard_normal((5, 2)), sensors=s)
    assert rec.channels(["b"]).data.shape == (5, 1)
    noisy = rec.with_noise(0.05, seed=1)
    assert np.all(np.abs(noisy.data - rec.data).std(axis=0) > 0)
    with pytest.raises(InputError, match="no simulated truth"):
        _ = rec.truth
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(rec.with_noise(0.0, seed=1).data, rec.data)


@pytest.fixture(scope="module")
def two_channel_record():
    return simulate(paper.slab_bridge(), two_axle_truck(), speed=20.0, lane=2.0,
                    sensors=[bwim.Sensor(x=6.0, y=2.0), bwim.Sensor(x=9.0, y=6.0)],
                    approach=10.0, tail=1.0)


def _check_noise(noise, sigma):
    """Zero-mean, independent, Gaussian of std ``sigma`` per channel, statistically: on
    n ≈ 1900 samples the sample std has relative standard error 1/√(2(n − 1)) ≈ 1.6 %, so
    |s/σ − 1| < 5 % is a > 3-standard-error band; the mean lies within 4 σ/√n of 0; the
    channels' noises are uncorrelated (|r| < 4/√n)."""
    n = noise.shape[0]
    assert n > 1800
    np.testing.assert_allclose(noise.std(axis=0, ddof=1) / sigma, 1.0, atol=0.05)
    assert np.all(np.abs(noise.mean(axis=0)) < 4 * sigma / np.sqrt(n))
    assert abs(np.corrcoef(noise.T)[0, 1]) < 4 / np.sqrt(n)


def test_with_noise_per_channel_is_the_papers_standard_deviation(two_channel_record):
    """``per_channel=True``: σ = p × each channel's own peak |reading| (the paper's §5.2)."""
    rec = two_channel_record
    p = 0.05
    sigma = p * np.abs(rec.data).max(axis=0)
    assert sigma[0] != pytest.approx(sigma[1], rel=0.1)  # the channels' scales differ
    _check_noise(rec.with_noise(p, seed=3, per_channel=True).data - rec.data, sigma)


def test_with_noise_default_is_gauge_noise(two_channel_record):
    """Default: one σ = p × the record's overall peak strain on every strain channel (a
    gauge's noise does not scale with its signal); ``sigma=`` gives it absolutely."""
    rec = two_channel_record
    p = 0.05
    sigma = np.full(2, p * np.abs(rec.data).max())
    _check_noise(rec.with_noise(p, seed=3).data - rec.data, sigma)
    _check_noise(rec.with_noise(sigma=1e-6, seed=4).data - rec.data, np.full(2, 1e-6))
    # reproducible by seed, zero noise is the identity
    np.testing.assert_array_equal(rec.with_noise(p, seed=3).data, rec.with_noise(p, seed=3).data)
    np.testing.assert_array_equal(rec.with_noise(0.0, seed=3).data, rec.data)
