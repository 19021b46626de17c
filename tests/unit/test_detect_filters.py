"""The detection's Gaussian filters and detector lag by FFT (issue 21 item 6: speed)
against their direct references.

References: ``scipy.ndimage.gaussian_filter1d`` (a direct weighted sum with the same
kernel and ``mode="nearest"`` ends) for :func:`bwim.detect.signals.gaussian_average`,
:func:`bwim.detect.response.band_pass` and :func:`~bwim.detect.response.high_pass`; the
correlation ``Σ y1[n] y2[n + L]`` summed lag by lag for
:func:`bwim.detect.response.xcorr_lag`.  The FFTs differ from the direct sums by rounding
only: measured at most 1.3e-15 of the signal's largest magnitude (tolerance 5e-15).
"""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from bwim.detect.response import band_pass, high_pass, xcorr_lag
from bwim.detect.signals import gaussian_average, gaussian_kernel

TOL = 5e-15  # of max |y|; measured ≤ 1.3e-15


def _signal(n: int, k: int | None, seed: int = 0) -> np.ndarray:
    """A random walk on an offset (a detector's bending and baseline), steps at the ends
    (the padding's edge values matter there)."""
    rng = np.random.default_rng(seed)
    shape = (n,) if k is None else (n, k)
    y = rng.standard_normal(shape).cumsum(axis=0) + 40.0
    y[:3] += 5.0
    y[-3:] -= 5.0
    return y


@pytest.mark.parametrize("n, k", [(677, 2), (1000, 3), (50, None), (5, 1)])
@pytest.mark.parametrize("sigma", [0.3, 5.12, 30.72, 100.0])
def test_gaussian_average_is_scipys_nearest_filter(n, k, sigma):
    y = _signal(n, k)
    ref = gaussian_filter1d(y, sigma, axis=0, mode="nearest")
    got = gaussian_average(y, [(sigma, 1.0)])
    assert got.shape == y.shape
    assert np.max(np.abs(got - ref)) <= TOL * np.max(np.abs(y))


def test_the_kernel_is_scipys():
    """Radius int(4σ + 0.5), weights summing to 1: scipy's filter of a unit impulse."""
    for sigma in (0.3, 2.0, 5.12, 30.72):
        k = gaussian_kernel(sigma)
        impulse = np.zeros(2 * k.size + 1)
        impulse[k.size] = 1.0
        ref = gaussian_filter1d(impulse, sigma, mode="constant")
        np.testing.assert_allclose(ref[k.size - k.size // 2:k.size + k.size // 2 + 1], k,
                                   rtol=0, atol=1e-16)
        assert np.all(np.delete(ref, np.arange(k.size - k.size // 2,
                                               k.size + k.size // 2 + 1)) == 0.0)


@pytest.mark.parametrize("n", [677, 1354, 64])
def test_band_and_high_pass_are_the_direct_filters(n):
    y = _signal(n, 2, seed=n)
    fs = 512.0
    ref = (gaussian_filter1d(y, 0.01 * fs, axis=0, mode="nearest")
           - gaussian_filter1d(y, 0.06 * fs, axis=0, mode="nearest"))
    assert np.max(np.abs(band_pass(y, fs) - ref)) <= TOL * np.max(np.abs(y))
    ref = y - gaussian_filter1d(y, 15.0, axis=0, mode="nearest")
    assert np.max(np.abs(high_pass(y, 15.0) - ref)) <= TOL * np.max(np.abs(y))


def _direct_lag(y1, y2, lo, hi):
    """The lag of the largest Σ y1[n] y2[n + L] over L = lo … hi, summed lag by lag, and
    the vertex of the parabola through it and its neighbours (xcorr_lag's contract)."""
    n = y1.size
    r = np.array([float(y1[max(0, -L):n - max(0, L)] @ y2[max(0, L):n - max(0, -L)])
                  for L in range(lo, hi + 1)])
    k = int(np.argmax(r))
    den = r[k - 1] - 2 * r[k] + r[k + 1]
    return lo + k + float(np.clip(0.5 * (r[k - 1] - r[k + 1]) / den, -0.5, 0.5))


@pytest.mark.parametrize("n", [677, 701, 1000])  # prime lengths: 2n is not a fast length
def test_xcorr_lag_is_the_direct_correlation(n):
    rng = np.random.default_rng(n)
    t = np.arange(n)
    pulse = np.exp(-0.5 * ((t[:, None] - np.array([0.2, 0.5, 0.93]) * n) / 6.0) ** 2).sum(1)
    shift = 41.3  # samples; the second pulse train runs off the record's end
    later = np.exp(-0.5 * ((t[:, None] - np.array([0.2, 0.5, 0.93]) * n - shift) / 6.0)
                   ** 2).sum(1)
    y1 = pulse + 0.01 * rng.standard_normal(n)
    y2 = later + 0.01 * rng.standard_normal(n)
    lag = xcorr_lag(y1, y2, 10, 200)
    assert lag == pytest.approx(_direct_lag(y1, y2, 10, 200), abs=1e-9)
    assert abs(lag - shift) < 1.0  # the pulses' shift, to a sample (measured 0.5 at most)


def test_xcorr_lag_s_spectra_are_one_call_each():
    """xcorr_lag transforms both signals in one call (a (2, n) array): numpy transforms
    each row on its own, so the product of the spectra is that of one call each, byte
    for byte (lengths 2 … 299 and the records' few hundred samples)."""
    import scipy.fft

    rng = np.random.default_rng(8)
    for n in (*range(2, 300), 677, 749, 896):
        y1, y2 = rng.standard_normal(n), rng.standard_normal(n)
        size = scipy.fft.next_fast_len(2 * n, real=True)
        one_each = np.fft.rfft(y1[::-1], size) * np.fft.rfft(y2, size)
        spec = np.fft.rfft(np.array([y1[::-1], y2]), size)
        assert (spec[0] * spec[1]).tobytes() == one_each.tobytes()


def test_median_is_numpys():
    """:func:`bwim.detect.signals.median` (one partial sort) equals ``numpy.median``
    exactly (the same float), odd and even counts, repeated values (a uniform clock's
    steps), and is NaN where a value is; ``robust_sigma`` with it equals 1.4826 MAD by
    ``numpy.median``."""
    from bwim.detect.signals import MAD_TO_SIGMA, median, robust_sigma

    rng = np.random.default_rng(4)
    for n in (1, 2, 3, 4, 7, 10, 101, 700):
        for x in (rng.standard_normal(n) * 10.0 ** rng.uniform(-6, 6),
                  np.round(rng.standard_normal(n), 1), np.diff(np.arange(n + 1) / 512.0)):
            assert median(x) == np.median(x)
            assert robust_sigma(x) == float(MAD_TO_SIGMA * np.median(np.abs(x - np.median(x))))
        x = rng.standard_normal(n)
        x[n // 2] = np.nan
        assert np.isnan(median(x))
