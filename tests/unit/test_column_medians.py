"""The detection's medians without numpy.median's overhead, the same numbers
(bwim.detect.signals.column_medians; bwim.detect.lateral.lateral_position).

References: ``numpy.median(values, axis=0)`` itself (the function replaced: equal bit for
bit, the sign of a zero included), and the lateral position's documented formula written
out here with numpy's own median, maximum and clip (the code before it was made faster).
Data: random arrays with ties, signed zeros, NaN and inf (the cases where a partial sort's
order of equal values or numpy's NaN rule show), and the small realistic site's lane-1
truck (an FE plate with noise and offsets) for the lateral position.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bwim.detect.lateral import lateral_position
from bwim.detect.signals import channel_data, column_medians


def _cases():
    rng = np.random.default_rng(7)
    for trial in range(3000):
        n, k = int(rng.integers(1, 60)), int(rng.integers(1, 5))
        a = rng.normal(size=(n, k))
        if trial % 3 == 0:
            a = np.round(a * 0.4)  # many ties, zeros of both signs
        if trial % 7 == 0:
            a[rng.integers(0, n), rng.integers(0, k)] = np.nan
        if trial % 11 == 0:
            a[rng.integers(0, n), rng.integers(0, k)] = -np.inf
        yield a


def test_column_medians_are_numpys_bit_for_bit():
    """3000 arrays (1 … 59 rows, odd and even counts): the same values, NaN where numpy
    gives NaN and the same sign of every zero."""
    n_signed = 0
    for a in _cases():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            ref = np.median(a, axis=0)
        got = column_medians(a)
        assert got.shape == ref.shape
        assert np.array_equal(got, ref, equal_nan=True), (a, got, ref)
        assert np.array_equal(np.signbit(got), np.signbit(ref)), (a, got, ref)
        # a zero median of a column holding -0 (numpy's mean of the middle gives +0)
        n_signed += int(np.any((ref == 0) & np.any((a == 0) & np.signbit(a), axis=0)))
    assert n_signed > 100  # the signed zeros were exercised
    assert column_medians(np.zeros((0, 3))).shape == (3,)


def _reference_lateral(record, window, quiet, gauges, threshold, weight):
    """The lateral position's formula (docs: bwim.detect.lateral) with numpy.median."""
    data = channel_data(record, gauges)
    t = record.time
    inside = (t >= window[0]) & (t <= window[1])
    dev = data[inside] - np.median(data[quiet], axis=0)
    if weight == "peak":
        w = np.clip(dev.max(axis=0), 0.0, None)
    else:
        w = np.clip(dev, 0.0, None).sum(axis=0) * float(np.median(np.diff(t)))
    w = np.clip(w - threshold * w.max(), 0.0, None)
    ys = np.array([s.y for s in record.sensors if s.name in gauges])
    return float(w @ ys / w.sum()), w


@pytest.mark.parametrize("weight", ["peak", "area"])
def test_lateral_position_is_the_formula_with_numpys_median(small_site_truck, weight):
    """The lane-1 truck's lateral position over windows across its crossing (and the
    groups' short windows), thresholds 0 and 0.5: value and weights equal bit for bit."""
    _, record = small_site_truck
    gauges = [s.name for s in record.sensors if s.kind.value == "strain_x"]
    t = record.time
    n = 0
    for a, b in [(0.2, 0.8), (0.3, 0.45), (0.5, 0.55), (0.1, 0.9)]:
        window = (t[0] + a * (t[-1] - t[0]), t[0] + b * (t[-1] - t[0]))
        quiet = (t < window[0]) | (t > window[1])
        for thr in (0.0, 0.5):
            got = lateral_position(record, window=window, quiet=quiet, gauges=gauges,
                                   threshold=thr, weight=weight)
            value, w = _reference_lateral(record, window, quiet, gauges, thr, weight)
            assert got.unit == "m"
            assert got.value == value and np.array_equal(got.weights, w)
            n += 1
    assert n == 8


def test_channel_rows_are_channel_datas_rows():
    """channel_rows: channel_data(record, names)[rows].astype(float) in one gather, the
    same numbers and the same C-ordered layout (what BLAS then reads); a missing channel
    is named as channel_data names it."""
    from bwim.detect.signals import channel_rows
    from bwim.errors import InputError
    from bwim.records import Record
    from bwim.sensors import Sensor

    rng = np.random.default_rng(3)
    sensors = tuple(Sensor(x=1.0, y=float(k), name=f"g{k}") for k in range(7))
    rec = Record(time=np.arange(300) / 256.0, data=rng.normal(size=(300, 7)),
                 sensors=sensors)
    for names in (["g2", "g3", "g4"], ["g6", "g0"], ["g1"]):
        for m in (rng.random(300) < 0.5, np.ones(300, dtype=bool)):
            ref = channel_data(rec, names)[m].astype(float)
            got = channel_rows(rec, names, np.flatnonzero(m))
            assert np.array_equal(got, ref) and got.strides == ref.strides
            assert got.flags.c_contiguous and got.flags.owndata
    with pytest.raises(InputError, match="no channel 'g9'"):
        channel_rows(rec, ["g1", "g9"], np.arange(3))
