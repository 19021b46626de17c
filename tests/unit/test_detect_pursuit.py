"""Axle detection on wide detector responses: responses learned from a calibration
truck's runs, then sparse deconvolution (bwim.detect.response, bwim.detect.pursuit).

No inverse crime: the detectors here follow this suite's own model (tests/detect_data.py
``wide_pulse``: a local peak of about 1 m at half height seen through a lateral
sensitivity, less the span's bending, the steering axle seen at 0.45 of its load, gains
4x apart, offsets, drift, 1 % noise), which bwim never assumes: it learns a response
from the runs and detects traffic with it.  References: the simulated layouts and speeds.
"""

import numpy as np
import pytest

from bwim.detect import detect_axles
from bwim.detect.response import learn_responses
from bwim.errors import InputError

from tests.detect_data import CAL_LOADS, CAL_SPACINGS, DISTANCE, wide_record

#: (spacings m, loads N) of traffic trucks: 2+1 rigid, 2+3 artic, 3+3 artic, 2-axle, 2+2
TRUCKS = (((3.6, 1.35), (60e3, 90e3, 90e3)),
          ((3.5, 6.5, 1.31, 1.31), (65e3, 110e3, 80e3, 80e3, 80e3)),
          ((3.2, 1.35, 5.9, 1.3, 1.3), (70e3, 95e3, 95e3, 75e3, 75e3, 75e3)),
          ((5.0,), (50e3, 90e3)),
          ((3.8, 5.5, 1.3), (60e3, 100e3, 70e3, 70e3)))


def _runs(n=8, seed=1, distance=DISTANCE):
    rng = np.random.default_rng(seed)
    runs, speeds = [], []
    for k in range(n):
        v, lat = rng.uniform(15, 25), rng.uniform(-0.3, 0.3)
        runs.append(wide_record([(v, CAL_SPACINGS, CAL_LOADS, 0.4, lat)],
                                duration=0.7 + (sum(CAL_SPACINGS) + 6) / v, seed=k))
        speeds.append(v)
    return runs, np.array(speeds)


@pytest.fixture(scope="module")
def learned():
    runs, speeds = _runs()
    return learn_responses(runs, ("ad1", "ad2"), DISTANCE, CAL_SPACINGS, loads=CAL_LOADS), speeds


def test_learned_responses_time_the_runs(learned):
    """Each run's speed within 0.1 % (measured ≤ 0.03 %) and first axle within 1 ms; the
    local responses peak at u = 0 and are about a metre wide (the model's 1.0 m half-height
    width, high-pass aside: measured 0.9-1.0 m); the steering axle is seen weakest (the
    model: 0.45 × its load's share, i.e. 0.26 of the drive axle)."""
    L, speeds = learned
    np.testing.assert_allclose(L.speeds, speeds, rtol=1e-3)
    np.testing.assert_allclose(L.first_axle_times, 0.4, atol=1e-3)
    for r in L.responses:
        assert r.k[np.argmin(np.abs(r.u))] == pytest.approx(1.0, abs=0.02)
        assert 0.7 < r.fwhm < 1.2
    f = L.amplitudes[:, 0] / L.amplitudes[:, 0].max()
    assert np.argmin(f) == 0 and f[0] < 0.4
    assert abs(L.distance_offset) < 0.03 and not any(L.reasons)


@pytest.mark.parametrize("k", range(10))
def test_traffic_axles_from_merged_peaks(learned, k):
    """Every axle count right (tandems and tridems 1.3 m apart merge into one wide peak),
    spacings within 0.1 m and speed within 0.5 % (the issue's targets; measured ≤ 2.2 cm
    and ≤ 0.38 %), at 12-28 m/s and ±0.4 m lateral wander."""
    L, _ = learned
    rng = np.random.default_rng(100 + k)
    spacings, loads = TRUCKS[k % len(TRUCKS)]
    v, lat = rng.uniform(12, 28), rng.uniform(-0.4, 0.4)
    rec = wide_record([(v, spacings, loads, 0.4, lat)], duration=0.7 + (sum(spacings) + 6) / v,
                      seed=200 + k)
    det = detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L)
    veh = det.single
    assert veh.n_axles == len(loads)
    np.testing.assert_allclose(veh.axle_spacings, spacings, atol=0.1)
    assert veh.speed == pytest.approx(v, rel=5e-3)
    assert veh.confidence > 0.9 and det.method == "learned responses"


def test_peak_detection_fails_where_pursuit_does_not(learned):
    """The reference point of the issue: a detector that needs separated peaks miscounts
    the merged tridem of a 2+3 artic; the learned responses do not."""
    L, _ = learned
    spacings, loads = TRUCKS[1]
    rec = wide_record([(22.0, spacings, loads, 0.4, 0.0)], duration=1.6, seed=7)
    peaks = detect_axles(rec, ("ad1", "ad2"), DISTANCE)
    assert peaks.n_vehicles != 1 or peaks.vehicles[0].n_axles != 5
    assert detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L).single.n_axles == 5


def test_two_vehicles_one_lane(learned):
    """A 2-axle truck 14 m behind an artic at the same speed: two vehicles, each right."""
    L, _ = learned
    (s1, l1), (s2, l2) = TRUCKS[1], TRUCKS[3]
    v = 20.0
    gap = (sum(s1) + 14.0) / v
    rec = wide_record([(v, s1, l1, 0.4, 0.0), (v, s2, l2, 0.4 + gap, 0.2)], duration=2.4,
                      seed=9)
    det = detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L)
    assert [vh.n_axles for vh in det.vehicles] == [5, 2]


def test_a_wrong_detector_distance_is_refused():
    """Declared 2.5 m where the detectors are 3 m apart: the truck's known spacings say
    otherwise, and the message says by how much (measured 3.0 m)."""
    runs, _ = _runs(n=5)
    with pytest.raises(InputError, match=r"distance of 2\.5 m contradicts.*give 3\.0"):
        learn_responses(runs, ("ad1", "ad2"), 2.5, CAL_SPACINGS, loads=CAL_LOADS)
