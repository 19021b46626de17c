"""What a detector pair reads of the span's bending (bwim.site.bending).

References: the readings are built here as a known combination of "gauge" signals plus
offset, slope, noise and sparse axle peaks, so the fitted combination must come back
(a closed form of the data: the weights that made it); the share left once the bending is
out is 1 for a reading with no bending at all and about the noise's share for a reading
that is bending alone (algebra of the projection)."""

from __future__ import annotations

import numpy as np
import pytest

from bwim.errors import InputError
from bwim.records import Record
from bwim.sensors import Sensor, SensorKind
from bwim.site.bending import TRACE_SHARE, DetectorBending, learn_bending

FS = 512.0
GAUGES = ("g1", "g2", "g3")
W = np.array([[0.8, -0.3, 0.1], [0.2, 0.5, -0.4]])


def _record(rng, *, peaks=(), bending=1.0, n=1024) -> Record:
    t = np.arange(n) / FS
    # three smooth, independent "gauge" humps (a vehicle crossing), different shapes
    g = np.column_stack([np.exp(-0.5 * ((t - c) / s) ** 2) * a
                         for c, s, a in ((0.5, 0.15, 100.0), (1.0, 0.2, 80.0),
                                         (1.5, 0.15, 60.0))])
    g += rng.normal(0.0, 0.1, g.shape)
    det = bending * g @ W.T + np.array([5.0, -3.0]) + np.outer(t, [0.7, -0.2])
    det += rng.normal(0.0, 0.05, det.shape)
    for tp, amp in peaks:  # an axle crossing both detectors (about a metre at 20 m/s)
        det += amp * np.exp(-0.5 * ((t[:, None] - tp - np.array([0.0, 0.15])) / 0.02) ** 2)
    sensors = (*(Sensor(name=n, kind=SensorKind.STRAIN_X) for n in GAUGES),
               Sensor(name="ad3", kind=SensorKind.AXLE_DETECTOR),
               Sensor(name="ad4", kind=SensorKind.AXLE_DETECTOR))
    return Record(time=t, data=np.column_stack([g, det]), sensors=sensors)


@pytest.fixture
def runs(rng):
    # one run with a vehicle over the pair: its peaks are the robust fit's outliers
    return [_record(rng) for _ in range(4)] + [_record(rng, peaks=((0.9, 150.0),))]


def test_the_combination_that_made_the_readings_comes_back(runs):
    b = learn_bending(runs, ("ad3", "ad4"), GAUGES)
    # measured: within 1.1e-3 of the weights (noise 0.05 on readings of ~100; the ridge
    # shrinks them by about 1e-3 of themselves)
    assert np.allclose(b.weights, W, atol=3e-3)
    assert b.channels == ("ad3", "ad4") and b.gauges == GAUGES


def test_bending_alone_is_a_trace_and_axles_are_not(runs, rng):
    b = learn_bending(runs, ("ad3", "ad4"), GAUGES)
    window = (0.3, 1.6)
    alone = _record(rng, bending=1.7)  # a heavier vehicle elsewhere: the same shape
    share = b.left_share(alone, window)
    assert share < 0.05 and b.is_trace(alone, window)
    # axles crossing the pair on the same bending, their peaks above it (a real site's
    # bending between axle groups is 0.3-0.6 of the largest peak): they stay
    crossing = _record(rng, peaks=((0.7, 150.0), (1.0, 150.0)))
    assert b.left_share(crossing, window) > 0.8 and not b.is_trace(crossing, window)
    # no bending at all: everything is left
    clean = _record(rng, bending=0.0, peaks=((0.7, 150.0),))
    assert b.left_share(clean, window) == pytest.approx(1.0, abs=0.02)
    assert 0.05 < TRACE_SHARE < 0.8


def test_without_a_window_nothing_is_decided(runs, rng):
    b = learn_bending(runs, ("ad3", "ad4"), GAUGES)
    rec = _record(rng)
    assert not b.is_trace(rec, None)
    assert np.isnan(b.left_share(rec, (5.0, 6.0)))  # no sample in the window


def test_bad_inputs(runs):
    with pytest.raises(InputError, match="runs and gauges"):
        learn_bending([], ("ad3", "ad4"), GAUGES)
    with pytest.raises(InputError, match="runs and gauges"):
        learn_bending(runs, ("ad3", "ad4"), ())
    with pytest.raises(InputError):
        learn_bending(runs, ("ad3", "nope"), GAUGES)
    assert isinstance(learn_bending(runs, ("ad3", "ad4"), GAUGES), DetectorBending)
