"""Detection's faster constructs give numpy's own numbers, bit for bit (issue 21: speed
with results unchanged).

References: the numpy constructs each replaces, run here on the same arrays —
``values.sum(axis=-1)`` for :func:`bwim.detect.signals.last_axis_sum`, ``np.delete`` for
the pursuit's ``_without``, and the Gaussian average's padding by
``np.concatenate`` of ``np.broadcast_to`` (the code before) for
:func:`bwim.detect.signals.gaussian_average`.  Compared as bytes, so the sign of every
zero and every NaN counts.  Data: random arrays of magnitudes 1e-12 … 1e12 with signed
zeros, inf and NaN, in C, Fortran and strided layouts.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from bwim.detect.pursuit import _acceptable, _without
from bwim.detect.signals import gaussian_average, gaussian_kernel, last_axis_sum
from bwim.detect.vehicle_fit import relative


def _arrays(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for trial in range(count):
        k = int(rng.integers(1, 11))  # numpy's pairwise sum starts at 8 values
        m = int(rng.integers(0, 30))
        shape = (2, m, k) if trial % 3 else (m, k)
        x = rng.standard_normal(shape) * 10.0 ** rng.integers(-12, 13, shape)
        u = rng.random(shape)
        x[u < 0.08] = -0.0
        x[(u >= 0.08) & (u < 0.1)] = 0.0
        if trial % 13 == 0:
            x[u > 0.97] = np.inf
        if trial % 17 == 0:
            x[u > 0.98] = np.nan
        if trial % 3 == 1:
            x = np.asfortranarray(x)
        elif trial % 5 == 2:  # the last axis strided (a diagonal's layout)
            x = np.repeat(x, 3, axis=-1)[..., ::3]
        yield x


def test_last_axis_sum_is_numpys_sum_bit_for_bit():
    """4000 arrays, last axes of 1 … 10 values (short ones by slices, from 8 numpy's own
    pairwise sum): the same bytes, the shape included."""
    n_short = 0
    for x in _arrays(3, 4000):
        got, ref = last_axis_sum(x), x.sum(axis=-1)
        assert got.shape == ref.shape
        assert got.tobytes() == ref.tobytes(), x
        n_short += 2 <= x.shape[-1] < 8
    assert n_short > 1500  # the sliced path was exercised


def test_last_axis_sum_of_negative_zeros_is_positive_zero_as_numpys():
    """numpy's sum starts from +0.0: a row of −0.0 sums to +0.0."""
    x = np.full((3, 4), -0.0)
    assert np.signbit(x.sum(axis=-1)).sum() == 0
    assert last_axis_sum(x).tobytes() == x.sum(axis=-1).tobytes()


def test_without_is_np_delete():
    rng = np.random.default_rng(5)
    for n in range(1, 12):
        taus = rng.random(n)
        for i in range(n):
            got = _without(taus, i)
            assert got.tobytes() == np.delete(taus, i).tobytes()


def test_acceptable_is_the_relative_amplitudes_test():
    """The pursuit's test of a new axle (its amplitudes over each detector's largest, both
    at least min_height) equals the numpy expression it replaces, relative(amps)[-1].min()
    >= min_height, on amplitudes of both signs, zeros, ties and NaN."""
    rng = np.random.default_rng(8)
    n_true = 0
    for trial in range(3000):
        amps = rng.standard_normal((int(rng.integers(1, 7)), 2)) + 0.8
        if trial % 5 == 0:
            amps[rng.integers(0, amps.shape[0]), rng.integers(0, 2)] = 0.0
        if trial % 7 == 0:
            amps[-1] = amps.max(axis=0)  # ties at the top
        if trial % 11 == 0:
            amps[rng.integers(0, amps.shape[0]), rng.integers(0, 2)] = np.nan
        h = float(rng.choice([0.0, 0.1, 0.5, 1.0]))
        ref = bool(relative(amps)[-1].min() >= h)
        assert _acceptable(None, amps, h) is ref
        n_true += ref
    assert 300 < n_true < 2700  # both outcomes exercised


def _gaussian_average_before(y, filters):
    """The Gaussian average as written before its padding was made by assignment."""
    y = np.asarray(y, dtype=float)
    kernels = [(gaussian_kernel(s), float(w)) for s, w in filters]
    r = max(k.size // 2 for k, _ in kernels)
    kernel = np.zeros(2 * r + 1)
    for k, w in kernels:
        h = k.size // 2
        kernel[r - h:r + h + 1] += w * k
    n = y.shape[0]
    shape = (r, *y.shape[1:])
    padded = np.concatenate([np.broadcast_to(y[:1], shape), y,
                             np.broadcast_to(y[-1:], shape)])
    size = scipy.fft.next_fast_len(n + 4 * r, real=True)
    spec = np.fft.rfft(padded, size, axis=0)
    spec *= np.fft.rfft(kernel, size).reshape(-1, *([1] * (y.ndim - 1)))
    return np.fft.irfft(spec, size, axis=0)[2 * r:2 * r + n]


def test_gaussian_average_padding_gives_the_same_bytes():
    rng = np.random.default_rng(11)
    for shape in [(1,), (7,), (300,), (250, 2), (64, 3), (1, 2)]:
        y = rng.standard_normal(shape) * 50.0 + 3.0
        for filters in ([(2.5, 1.0)], [(5.12, 1.0), (30.72, -1.0)]):
            got = gaussian_average(y, filters)
            assert got.tobytes() == _gaussian_average_before(y, filters).tobytes()


def _problem(gauges: bool):
    """A Problem of two Gaussian responses (1.2 m at half height, gains 4 apart) on random
    readings, with 6 random-walk gauges or high-passed (algebra only: no detection)."""
    from bwim.detect.response import DetectorResponse, LearnedResponses
    from bwim.detect.vehicle_fit import make_problem

    u = np.linspace(-1.5, 1.5, 61)
    k = np.exp(-4 * np.log(2) * (u / 1.2) ** 2)
    k[[0, -1]] = 0.0
    names = tuple(f"g{j}" for j in range(6)) if gauges else ()
    resp = tuple(DetectorResponse(channel=c, u=u, k=k, noise=1.0, misfit=1.0,
                                  bending=-0.2 * np.ones(len(names))) for c in ("a", "b"))
    learned = LearnedResponses(responses=resp, distance=3.0, amplitudes=np.ones((2, 2)),
                               speeds=np.ones(2), first_axle_times=np.zeros(2),
                               residuals=np.zeros(2), reasons=("", ""), distance_offset=0.0,
                               nit=1, gauges=names, gain_ratio=0.25, amplitude_spread=0.1)
    rng = np.random.default_rng(2)
    n = 600
    t = np.arange(n) / 512.0
    g = rng.standard_normal((n, 6)).cumsum(axis=0) if gauges else None
    return make_problem(t, rng.standard_normal((n, 2)), g, learned, 20.0)


def test_rows_read_through_a_slice_give_the_same_fit():
    """A window's rows read through a slice (views) or gathered by their index array: the
    same residual, amplitudes, removal costs and Jacobian, as bytes."""
    from bwim.detect.vehicle_fit import Rows, Solution, window

    for gauges in (True, False):
        pb = _problem(gauges)
        taus = np.array([0.25, 0.31, 0.52])
        rows = window(pb, taus, 20.0)
        assert pb.step > 1 and rows.size > 20
        a = Solution(pb, taus, 20.0, Rows(pb, rows), True)
        b = Solution(pb, taus, 20.0, Rows(pb, rows, slice(int(rows[0]), int(rows[-1]) + 1,
                                                          pb.step)), True)
        for x, y in ((a.res, b.res), (a.amps, b.amps), (a.gains, b.gains),
                     (a.jacobian(), b.jacobian())):
            assert x.tobytes() == y.tobytes()


def test_grid_steps_are_np_diff_then_np_append():
    from bwim.detect.vehicle_fit import _steps

    rng = np.random.default_rng(4)
    for n in (2, 3, 61, 400):
        k = rng.standard_normal(n) * 10.0 ** rng.integers(-6, 6, n)
        k[[0, -1]] = 0.0
        got = _steps([(None, k, None), (None, -k, None)])
        for s, kk in zip(got, (k, -k), strict=True):
            assert s.tobytes() == np.append(np.diff(kk), 0.0).tobytes()
