"""Moving force identification: the DP recursion equals the batch Tikhonov solution, and
bad input is rejected."""

import numpy as np
import pytest

import bwim
from bwim.errors import InputError
from bwim.mfi import build_model, identify_forces, record_band, solve_batch, solve_dp
from bwim.mfi.identify import BAND_SEGMENT, DEFAULT_MAX_MODES
from bwim.mfi.statespace import ForceUnknowns, Order
from bwim.records import Record


def _beam_crossing(sampling_rate: float):
    """Two axle forces crossing a 10 m beam at 25 m/s, read by three strain sensors."""
    beam = bwim.Bridge.beam(length=10.0, n_elements=10, E=3e10, I=0.5, mu=5e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x) for x in (2.5, 5.0, 7.5)]
    rec = bwim.simulate(beam, bwim.MovingForces(axle_loads=[5e4, 8e4], axle_spacings=[3.0]),
                        speed=25.0, sensors=sensors, sampling_rate=sampling_rate, approach=0.0)
    return beam, sensors, rec


@pytest.fixture(scope="module")
def small():
    """The crossing sampled at 100 Hz: 53 samples, for the solver-level comparisons."""
    return _beam_crossing(100.0)


@pytest.fixture(scope="module")
def crossing():
    """The same crossing sampled at 1 kHz, for the public identify_forces API."""
    return _beam_crossing(1000.0)


@pytest.mark.parametrize("order", [Order.FIRST, Order.ZEROTH])
@pytest.mark.parametrize("static_correction", [True, False])
@pytest.mark.parametrize("lam", [1e-3, 1.0])
def test_dp_equals_batch_tikhonov(small, order, static_correction, lam):
    beam, _, rec = small
    scale = np.abs(rec.data).max()
    model = build_model(beam, beam.modes(4), rec, scale,
                        unknowns=ForceUnknowns.AXLE, order=order,
                        static_correction=static_correction)
    d = rec.data / scale
    w = np.array([1.0, 2.0, 0.5])
    dp, batch = solve_dp(model, d, lam, w), solve_batch(model, d, lam, w)
    # measured: 1e-13 relative (round-off)
    np.testing.assert_allclose(dp.X, batch.X, atol=1e-10 * np.abs(batch.X).max())
    assert dp.residual_norm == pytest.approx(batch.residual_norm, rel=1e-9)
    assert dp.seminorm == pytest.approx(batch.seminorm, rel=1e-9)


@pytest.mark.parametrize("order", [Order.FIRST, Order.ZEROTH])
@pytest.mark.parametrize("block_min_modes", [1, 1000])
def test_stacked_sweep_equals_batch_tikhonov(small, order, block_min_modes):
    """The stacked λ sweep (the L-curve's solver), with P's products by its 2 × 2 blocks
    (block_min_modes=1) or dense (1000), against the batch solution at each λ."""
    from bwim.mfi.dp import sweep

    beam, _, rec = small
    scale = np.abs(rec.data).max()
    model = build_model(beam, beam.modes(4), rec, scale, unknowns=ForceUnknowns.AXLE,
                        order=order)
    d = rec.data / scale
    w = np.array([1.0, 2.0, 0.5])
    lams = np.array([1e-3, 1e-1, 10.0])
    sw = sweep(model, d, lams, w, keep=True, block_min_modes=block_min_modes)
    for k, lam in enumerate(lams):
        batch = solve_batch(model, d, lam, w)
        # round-off, as the DP solve (1e-13 relative)
        np.testing.assert_allclose(sw.X[k], batch.X, atol=1e-10 * np.abs(batch.X).max())
        assert sw.residual_norm[k] == pytest.approx(batch.residual_norm, rel=1e-9)
        assert sw.seminorm[k] == pytest.approx(batch.seminorm, rel=1e-9)


def test_lambda_units_round_trip(crossing):
    beam, _, rec = crossing
    scale = np.abs(rec.data).max()
    model = build_model(beam, beam.modes(2), rec, scale,
                        unknowns=ForceUnknowns.AXLE, order=Order.FIRST)
    assert model.lam_scaled(model.lam_physical(0.37)) == pytest.approx(0.37)
    # physical λ multiplies (N/s)²: scaled λ = λ_phys (f_scale / dt)² / d_scale²
    assert model.lam_physical(1.0) == pytest.approx((scale * model.dt / model.f_scale) ** 2)
    ident = identify_forces(beam, rec, lam=model.lam_physical(0.37), n_modes=2)
    assert ident.lam_scaled == pytest.approx(0.37, rel=1e-9)


def test_identified_forces_shapes(crossing):
    beam, _, rec = crossing
    ident = identify_forces(beam, rec, n_modes=2, lam=1e-20)
    assert ident.unknowns is ForceUnknowns.AXLE  # a beam: one force per axle
    assert ident.axle_forces.shape == (rec.time.size, 2)
    np.testing.assert_allclose(ident.wheel_forces, ident.axle_forces)
    assert ident.gvw.shape == (1,) and ident.gvw[0] == pytest.approx(ident.axle_weights.sum())
    assert np.all(ident.axle_windows[:, 1] > ident.axle_windows[:, 0])


def test_bad_identification_input(crossing):
    beam, _, rec = crossing
    with pytest.raises(InputError, match="no passage"):
        identify_forces(beam, Record(time=rec.time, data=rec.data, sensors=rec.sensors))
    with pytest.raises(InputError, match="unknown order 'second'"):
        identify_forces(beam, rec, order="second")
    with pytest.raises(InputError, match="unknown lam 'best'"):
        identify_forces(beam, rec, lam="best", n_modes=2)
    with pytest.raises(InputError, match="lam must be positive"):
        identify_forces(beam, rec, lam=-1.0, n_modes=2)
    with pytest.raises(InputError, match="too low for the modes in use"):
        identify_forces(beam, rec, n_modes=9)
    off = Record(time=rec.time, data=rec.data,
                 sensors=(bwim.Sensor(x=2.5), bwim.Sensor(x=5.0), bwim.Sensor(x=12.0)),
                 passages=rec.passages)
    with pytest.raises(InputError, match="off the deck"):
        identify_forces(beam, off, n_modes=2)
    with pytest.raises(InputError, match=r"non-finite"):
        Record(time=rec.time, data=np.where(rec.data > 0, np.nan, rec.data),
               sensors=rec.sensors, passages=rec.passages)


def test_too_few_channels_for_wheel_unknowns():
    bridge = bwim.paper.slab_bridge()
    sensors = [bwim.Sensor(x=6.0, y=2.0), bwim.Sensor(x=6.0, y=6.0), bwim.Sensor(x=3.0, y=4.0)]
    rec = bwim.simulate(bridge, bwim.MovingForces(axle_loads=[50e3, 80e3], axle_spacings=[4.0],
                                                  track_width=2.0),
                        speed=20.0, lane=3.0, sensors=sensors, approach=0.0, sampling_rate=500.0)
    with pytest.raises(InputError, match="3 sensor channels cannot identify 4 wheel forces"):
        identify_forces(bridge, rec, unknowns="wheel")
    ident = identify_forces(bridge, rec, unknowns="axle", lam=1e-22)
    assert ident.axle_forces.shape[1] == 2


def _tones(freqs, noise, n=2000, fs=1000.0, seed=0):
    """Three channels of sinusoids at ``freqs`` (Hz, unit amplitude) plus white noise of
    standard deviation ``noise``."""
    t = np.arange(n) / fs
    rng = np.random.default_rng(seed)
    phases = (0.3, 1.1, 2.0)[:len(freqs)]
    clean = sum(np.sin(2 * np.pi * f * t + p) for f, p in zip(freqs, phases, strict=True))
    data = clean[:, None] * np.array([1.0, 0.7, -0.4]) + noise * rng.standard_normal((n, 3))
    return Record(time=t, data=data, sensors=tuple(bwim.Sensor(x=x) for x in (2.0, 5.0, 8.0)))


def test_record_band_ends_above_the_highest_tone():
    """Reference: the spectrum of tones at 10 and 60 Hz in white noise is the flat noise
    floor except at the tones (the gap between them does not end the band), so the band
    ends past 60 Hz within the Hann window's main lobe (two 7.8 Hz Welch bins each side)
    plus one bin; without noise there is no floor below fs/4 and no cut."""
    bin_width = 1000.0 / BAND_SEGMENT
    for seed in range(3):
        band = record_band(_tones((10.0, 60.0), noise=0.3, seed=seed))
        assert 60.0 < band <= 60.0 + 3 * bin_width
    assert record_band(_tones((10.0, 60.0), noise=0.0)) == np.inf


def test_record_band_of_pure_noise_is_the_lowest_cut():
    """No bin stands out of white noise (the detrended response is below it at every
    frequency): the lowest cut, the first bin above 0 Hz, not 'no cut' (which would keep
    every mode for a record that resolves none)."""
    t = np.arange(2000) / 1000.0
    for seed in range(3):
        data = np.random.default_rng(seed).standard_normal((t.size, 3))
        rec = Record(time=t, data=data,
                     sensors=tuple(bwim.Sensor(x=x) for x in (2.0, 5.0, 8.0)))
        assert record_band(rec) == pytest.approx(1000.0 / BAND_SEGMENT, rel=1e-9)


def test_lcurve_corner_only_among_admissible_lambdas():
    """The corner search skips λ below the smallest one from which every grid λ is
    admissible, and takes the largest grid λ when none is (reference: the rule itself on
    an L-shaped curve whose true corner is at log λ = 0)."""
    from bwim.mfi.lcurve import _corner, _lowest_admissible

    t = np.linspace(-6.0, 6.0, 13)
    rho = np.exp(np.where(t > 0, t, 0.0)) + 1.0  # flat, then rising
    eta = np.exp(np.where(t < 0, -t, 0.0)) + 1.0  # falling, then flat
    assert abs(_corner(t, rho, eta)[1]) < 1.0
    ok = t >= 2.0
    lo = _lowest_admissible(t, ok)
    assert lo == 2.0 and _corner(t, rho, eta, lo)[1] >= 2.0
    assert _lowest_admissible(t, np.zeros(13, bool)) == np.inf
    assert _corner(t, rho, eta, np.inf)[1] == t[-1]
    assert _lowest_admissible(t, np.ones(13, bool)) == t[0]
    assert _lowest_admissible(t, None) is None
    assert _lowest_admissible(t, t != -3.0) == -2.0  # a tensile λ inside the grid


def test_identify_forces_chooses_fewer_modes_on_noisy_records(crossing):
    """With the L-curve the model order follows the record: a noisy record keeps fewer
    modes than its clean version, and the default cap holds; a given λ keeps the cap."""
    beam, _, rec = crossing
    noisy_rec = rec.with_noise(0.05, seed=3)
    clean = identify_forces(beam, rec)
    noisy = identify_forces(beam, noisy_rec)
    assert 1 <= noisy.n_modes < clean.n_modes <= DEFAULT_MAX_MODES
    assert identify_forces(beam, noisy_rec, lam=1e-3).n_modes == clean.n_modes
