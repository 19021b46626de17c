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

from bwim.detect.pursuit import _without
from bwim.detect.signals import gaussian_average, gaussian_kernel, last_axis_sum


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
