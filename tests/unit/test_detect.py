"""bwim.detect: signal helpers, result types, input checks, lateral position and presence
against closed forms.

References: parabola vertex (three-point interpolation is exact for a parabola); the MAD of
Gaussian noise is 0.6745 σ (normal quantile Φ⁻¹(3/4)); a running median of a straight
line is the line; the centroid of readings symmetric about the load on gauges symmetric
about it is the load's position; time on the span of a constant-speed vehicle, from its
kinematics x = v (t − delay) − a_i.
"""

import dataclasses

import numpy as np
import pytest

import bwim
from bwim.detect import (
    FLAG_COUNT_MISMATCH,
    FLAG_NO_AXLES,
    Detection,
    VehicleDetection,
    detect_axles,
    detect_from_strain,
    lateral_position,
    section_gauges,
)
from bwim.detect.presence import overlapping, span_windows, unexplained_activity
from bwim.detect.signals import (
    channel_data,
    parabolic_vertex,
    remove_baseline,
    robust_sigma,
    split_vehicles,
)
from bwim.errors import InputError
from bwim.sensors import Sensor
from bwim.wim import Channel, InfluenceLine

from tests.detect_data import CAL_LOADS, CAL_SPACINGS, FS, T0, detector_record

# --- signal helpers ------------------------------------------------------------------------

def test_robust_sigma_ignores_pulses(rng):
    """MAD × 1.4826 of Gaussian noise is σ; 3 % of samples replaced by pulses 50 σ high
    move it by about 4 % (the median's shift by 1.5 % of the ranks), the plain std ×9."""
    x = 0.1 * rng.standard_normal(20000)
    x[rng.choice(x.size, 600, replace=False)] += 5.0
    assert robust_sigma(x) == pytest.approx(0.1, rel=0.06)
    assert np.std(x) > 8 * 0.1


def test_parabolic_vertex_is_exact_for_a_parabola():
    n = np.arange(30.0)
    for peak in (10.0, 10.3, 17.49, 5.5):
        y = 2.0 - 0.7 * (n - peak) ** 2
        k = int(np.argmax(y))
        assert parabolic_vertex(y, np.array([k]))[0] == pytest.approx(peak, abs=1e-12)


def test_remove_baseline_leaves_the_pulses():
    """Offset + linear drift under a pulse train.  The running median of a line is the
    line; k raised samples in a window move its median by at most ⌈k/2⌉ ranks, i.e.
    ⌈k/2⌉ × the slope: the bound below.  Pulses keep their position."""
    n = np.arange(2000.0)
    slope, window = 3e-3, 129
    pulses = np.zeros(n.size)
    for c in (400, 430, 1200):
        pulses += np.exp(-0.5 * ((n - c) / 2.0) ** 2)
    y = remove_baseline(0.7 + slope * n + pulses, window)
    raised = np.convolve(pulses > 1e-9, np.ones(window), mode="same")
    bound = np.ceil(0.5 * raised) * slope + 1e-12
    inner = slice(window // 2, -(window // 2))
    err = np.abs(y - pulses)
    assert np.all(err[inner] <= bound[inner])
    assert np.abs(err[inner]).max() > 0.3 * bound.max()  # the bound is not vacuous
    for c in (400, 430, 1200):
        assert int(np.argmax(y[c - 5:c + 6])) == 5


def test_channel_data_is_the_channels_readings():
    """channel_data gives the columns Record.channels gives (by name or Sensor, in the
    order asked), and the same one-line error for a channel the record lacks."""
    rec = detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)])
    names = [s.name for s in rec.sensors]
    ask = [names[-1], rec.sensors[0]]
    np.testing.assert_array_equal(channel_data(rec, ask), rec.channels(ask).data)
    with pytest.raises(InputError, match="no channel 'nope'"):
        channel_data(rec, ["nope"])


def test_split_vehicles_at_long_gaps():
    parts = split_vehicles(np.array([0.0, 3.8, 9.8, 11.1, 12.4, 30.0, 34.0]), 12.0)
    assert [p.tolist() for p in parts] == [[0, 1, 2, 3, 4], [5, 6]]
    assert split_vehicles(np.zeros(0), 12.0) == []


# --- result types ---------------------------------------------------------------------------

def _vehicle(**kw):
    p = bwim.Passage(speed=20.0, axle_spacings=[3.0], delay=1.0)
    return VehicleDetection(passage=p, confidence=kw.pop("confidence", 0.9), **kw)


def test_results_are_frozen_and_checked():
    v = _vehicle()
    with pytest.raises(dataclasses.FrozenInstanceError):
        v.confidence = 0.5
    with pytest.raises(InputError, match="confidence"):
        _vehicle(confidence=1.5)
    with pytest.raises(InputError, match="lateral_unit"):
        _vehicle(lateral_unit="ft")
    with pytest.raises(TypeError):
        VehicleDetection(bwim.Passage(speed=1.0), 0.5)  # keyword-only


def test_single_names_the_flags_and_annotate_sets_passages():
    two = Detection(vehicles=(_vehicle(), _vehicle()), flags=("multiple_presence",),
                    message="vehicles 1, 2 on the span at the same time")
    with pytest.raises(InputError, match=r"2 vehicles.*multiple_presence"):
        _ = two.single
    none = Detection(flags=(FLAG_NO_AXLES,), message="no axle found")
    with pytest.raises(InputError, match=r"no axle found.*no_axles"):
        _ = none.single
    one = Detection(vehicles=(_vehicle(),))
    assert one.single.speed == 20.0 and one.n_vehicles == 1
    rec = bwim.Record(time=np.arange(4.0), data=np.zeros((4, 1)), sensors=[Sensor(x=0.0)])
    assert one.annotate(rec).passage is one.single.passage


# --- detect_axles: inputs and empty results ------------------------------------------------

def test_detect_axles_checks_its_arguments():
    rec = detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)])
    with pytest.raises(InputError, match="'ad3'"):
        detect_axles(rec, ("ad1", "ad3"))
    with pytest.raises(InputError, match="two different"):
        detect_axles(rec, ("ad1", "ad1"))
    with pytest.raises(InputError, match="distance"):
        detect_axles(rec, distance=0.0)
    with pytest.raises(InputError, match="speed_range"):
        detect_axles(rec, speed_range=(30.0, 10.0))
    with pytest.raises(InputError, match="polarity"):
        detect_axles(rec, polarity=2)
    with pytest.raises(InputError, match="span"):
        detect_axles(rec, span=(5.0, 1.0))


def test_no_axle_gives_a_reason_not_an_exception():
    """Noise only, and a dead second detector: empty detections with the reason."""
    d = detect_axles(detector_record([]))
    assert d.n_vehicles == 0 and FLAG_NO_AXLES in d.flags
    assert "no axle found" in d.message
    dead = detect_axles(detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)],
                                        gains=(1.0, 0.0)))
    assert dead.n_vehicles == 0
    assert set(dead.flags) == {FLAG_NO_AXLES, FLAG_COUNT_MISMATCH}
    assert "ad2" in dead.message and "5 axle" in dead.message


def test_position_shifts_the_delay_by_position_over_speed():
    """delay = time at the first detector − position / speed (the frame's definition)."""
    rec = detector_record([(22.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)], seed=2)
    a, b = detect_axles(rec).single, detect_axles(rec, position=-1.5).single
    assert b.speed == a.speed
    # exact up to the round-off of clock times near 36000 s (eps × 36000 ≈ 1e-11 s)
    assert b.passage.delay - a.passage.delay == pytest.approx(1.5 / a.speed, abs=1e-10)
    np.testing.assert_allclose(b.axle_times - a.axle_times, 1.5 / a.speed, atol=1e-10)


def test_negative_pulses_are_found_by_polarity():
    """A detector wired the other way round gives the same vehicle (auto polarity)."""
    rec = detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)], seed=4)
    flipped = dataclasses.replace(rec, data=-rec.data)
    a, b = detect_axles(rec).single, detect_axles(flipped).single
    assert b.n_axles == 5 and b.speed == pytest.approx(a.speed, rel=1e-12)
    assert detect_axles(flipped, polarity=-1).single.speed == pytest.approx(a.speed, rel=1e-12)


# --- presence ------------------------------------------------------------------------------

def test_span_windows_from_kinematics():
    """First axle enters at delay + x0/v, last leaves at delay + (x1 + a_last)/v."""
    p = bwim.Passage(speed=20.0, axle_spacings=[3.8, 6.0], delay=2.0)
    w = span_windows([p], (-1.0, 9.0))
    np.testing.assert_allclose(w, [[2.0 - 1.0 / 20, 2.0 + (9.0 + 9.8) / 20]])
    assert overlapping(np.array([[0, 1], [0.9, 2], [2.5, 3]])).tolist() == [True, True, False]


def test_unexplained_activity_outside_the_windows(rng):
    t = np.arange(0, 3, 1 / FS)
    hump = lambda c, w: np.clip(1 - np.abs(t - c) / w, 0, None)  # noqa: E731
    s = 100e-6 * hump(1.5, 0.4) + 1e-7 * rng.standard_normal(t.size)
    win = np.array([[1.1, 1.9]])
    assert unexplained_activity(t, s, win).shape == (0, 2)
    s2 = s + 50e-6 * hump(0.5, 0.2)  # a vehicle the detectors did not see
    extra = unexplained_activity(t, s2, win)
    assert extra.shape == (1, 2)
    assert extra[0, 0] < 0.5 < extra[0, 1]
    # a small bump (10 % of the vehicle's response) is below the default 20 %
    assert unexplained_activity(t, s + 10e-6 * hump(0.5, 0.2), win).size == 0


# --- lateral position --------------------------------------------------------------------

def _gauge_record(ys, lane, *, names=None, y_known=True):
    """Gauges at ``ys`` reading a Lorentzian profile about ``lane`` (a symmetric stand-in
    for the transverse spread) during 0.5–1.0 s."""
    t = np.arange(0, 1.5, 1 / FS)
    shape = np.clip(np.sin(np.pi * (t - 0.5) / 0.5), 0, None) * ((t > 0.5) & (t < 1.0))
    prof = 1.0 / (1.0 + ((np.asarray(ys) - lane) / 2.0) ** 2)
    names = names or [f"s{k + 1:02d}" for k in range(len(ys))]
    sens = [Sensor(x=4.5, y=y if y_known else 0.0, name=n) for y, n in zip(ys, names,
                                                                         strict=True)]
    return bwim.Record(time=t, data=40e-6 * shape[:, None] * prof[None, :], sensors=sens)


def test_lateral_centroid_of_a_symmetric_profile_is_the_load():
    ys = np.linspace(0.5, 9.5, 14)
    for k in (4, 6, 8):  # loads half-way between gauges k-1 and k: the set is symmetric
        lane = 0.5 * (ys[k - 1] + ys[k])
        sel = slice(max(0, 2 * k - 14), min(14, 2 * k))  # gauges symmetric about the lane
        rec = _gauge_record(ys[sel], lane)
        for thr in (0.0, 0.5):
            lat = lateral_position(rec, window=(0.5, 1.0), threshold=thr)
            assert lat.unit == "m"
            assert lat.value == pytest.approx(lane, abs=1e-12)


def test_lateral_plain_centroid_and_gauge_index():
    """threshold 0: the weighted mean Σ y w / Σ w; without y positions the same centroid
    in gauge-order units (1 = first gauge)."""
    ys = np.linspace(0.5, 9.5, 14)
    rec = _gauge_record(ys, 3.0)
    w = 1.0 / (1.0 + ((ys - 3.0) / 2.0) ** 2)
    lat = lateral_position(rec, threshold=0.0)
    assert lat.value == pytest.approx(w @ ys / w.sum(), rel=1e-9)
    idx = lateral_position(_gauge_record(ys, 3.0, y_known=False), threshold=0.0)
    assert idx.unit == "gauge index"
    assert idx.value == pytest.approx(w @ np.arange(1, 15) / w.sum(), rel=1e-9)
    # the index maps back to metres with the gauge pitch
    pitch = ys[1] - ys[0]
    assert ys[0] + (idx.value - 1) * pitch == pytest.approx(lat.value, rel=1e-9)
    with pytest.raises(InputError, match="weight"):
        lateral_position(rec, weight="max")


def test_section_gauges_takes_the_fullest_section():
    sens = ([Sensor(x=2.0, y=y, name=f"a{y}") for y in (1.0, 2.0)]
            + [Sensor(x=4.5, y=y, name=f"m{y}") for y in (1.0, 2.0, 3.0)]
            + [Sensor(x=4.5, y=1.0, kind="strain_y", name="t1"),
               Sensor(x=0.0, name="ad1", kind="axle_detector")])
    rec = bwim.Record(time=np.arange(3.0), data=np.zeros((3, len(sens))), sensors=sens)
    assert [s.name for s in section_gauges(rec)] == ["m1.0", "m2.0", "m3.0"]
    assert [s.name for s in section_gauges(rec, ["a1.0"])] == ["a1.0"]
    with pytest.raises(InputError, match="gauges"):
        section_gauges(rec, ["zz"])


# --- detect_from_strain on a closed-form line ----------------------------------------------

def _beam_deflection_line(L, x):
    """Mid-span deflection of a simply supported beam per unit load at x, × 48 EI / L³
    (Maxwell–Betti: the deflection at x under a central load), for 0 ≤ x ≤ L."""
    xi = np.minimum(x, L - x) / L
    return np.where((x >= 0) & (x <= L), 3 * xi - 4 * xi**3, 0.0)


def test_strain_only_on_a_closed_form_line(rng):
    """Readings from the closed-form (cubic) line at every sample; detection uses its
    piecewise-linear version on 0.25 m ordinates, with noise (0.1 % of the peak) and an
    offset: static, so speed, spacings and arrival come back to the line's interpolation
    error (measured ≤ 0.008 %, 0.5 mm, 35 µs, free search and known spacings)."""
    L = 9.0
    s = Sensor(x=4.5, y=0.0, name="g")
    il = InfluenceLine(x=np.arange(0, L + 1e-9, 0.25),
                       ordinates=_beam_deflection_line(L, np.arange(0, L + 1e-9, 0.25)),
                       channels=(Channel.of([s]),), lane=0.0)
    v, delay, spacings, loads = 18.0, T0 + 0.3, np.array([3.8, 6.0]), np.array([6, 11, 9.0])
    t = T0 + np.arange(int(1.6 * FS)) / FS
    offs = np.concatenate([[0.0], np.cumsum(spacings)])
    y = sum(w * _beam_deflection_line(L, v * (t - delay) - a) for a, w in zip(offs, loads,
                                                                                strict=True))
    rec = bwim.Record(time=t, data=(y + 0.5 + 0.01 * rng.standard_normal(t.size))[:, None],
                      sensors=[s])
    for det in (detect_from_strain(rec, il), detect_from_strain(rec, il,
                                                                 known_spacings=spacings)):
        veh = det.single
        assert veh.n_axles == 3
        assert veh.speed == pytest.approx(v, rel=3e-4)
        np.testing.assert_allclose(veh.axle_spacings, spacings, atol=3e-3)
        assert veh.passage.delay == pytest.approx(delay, abs=1e-4)
        assert "strain_only" in veh.flags and veh.confidence <= 0.5
    with pytest.raises(InputError, match="channel"):
        detect_from_strain(rec, il, channels=["nope"])
    with pytest.raises(InputError, match="InfluenceLine"):
        detect_from_strain(rec, "il")


def test_quantised_detector_channels():
    """A 12-bit-like logger: readings in 0.05 V steps with noise below one step, so most
    samples share a level and the MAD is 0; the quantisation noise (step / √12) then sets
    the threshold and the truck is still found whole."""
    rec = detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)], noise=0.005,
                          drifts=(0.0, 0.0), seed=5)
    q = dataclasses.replace(rec, data=np.round(rec.data / 0.05) * 0.05)
    assert robust_sigma(q.data[:, 0] - np.median(q.data[:, 0])) == 0.0
    veh = detect_axles(q).single
    assert veh.n_axles == 5
    assert veh.speed == pytest.approx(20.0, rel=1e-3)  # measured ≤ 0.03 % over 5 seeds


def test_sensors_without_positions():
    """Logger channels without x/y: detectors found by name, the lateral position is the
    gauge index (1 = first gauge); gauges with y only give metres."""
    ys = np.linspace(0.5, 9.5, 14)
    gauges = _gauge_record(ys, 3.0)
    t = T0 + gauges.time
    ad = detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)], duration=1.5)
    n = min(t.size, ad.time.size)
    for with_y, unit in ((False, "gauge index"), (True, "m")):
        sens = ([Sensor(name="ad1", kind="axle_detector"), Sensor(name="ad2",
                                                                 kind="axle_detector")]
                + [Sensor(name=f"s{k + 1:02d}", y=y if with_y else None)
                   for k, y in enumerate(ys)])
        rec = bwim.Record(time=t[:n], data=np.hstack([ad.data[:n], gauges.data[:n]]),
                          sensors=sens)
        veh = detect_axles(rec).single
        assert veh.n_axles == 5 and veh.lateral_unit == unit
        assert np.isfinite(veh.lateral) and veh.passage.lane == veh.lateral
