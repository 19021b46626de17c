"""The compiled order statistics (bwim.detect.order_stats) against numpy and scipy.

References: ``numpy.median``, ``numpy.median(|v − median v|)`` and
``scipy.ndimage.median_filter(y, size=(5, 1), mode="nearest")`` themselves, and
:func:`bwim.detect.signals.despike`'s formula written out with them (the code before the
kernel).  Data: random arrays, odd and even counts, with many ties (quantised readings,
zeros of both signs), ±inf, NaN, and spikes added.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import median_filter

from bwim.detect.order_stats import (
    column_medians_of,
    despike_columns,
    end_excursion,
    mad_of,
    median_of,
    outside_activity,
    outside_windows,
    row_medians_of,
    signed_extremes,
    window_peaks,
)
from bwim.detect.presence import signal_noise, unexplained_activity
from bwim.detect.signals import (
    MAD_TO_SIGMA,
    SPIKE_SHARE,
    SPIKE_SIGMAS,
    despike,
    median,
    robust_sigma,
)


def _vectors(rng, count=3000):
    for trial in range(count):
        n = int(rng.integers(1, 80))
        v = rng.normal(size=n)
        if trial % 3 == 0:
            v = np.round(v * 0.6)  # many ties, zeros of both signs
        if trial % 7 == 0:
            v[rng.integers(0, n)] = np.inf
        if trial % 11 == 0:
            v[rng.integers(0, n)] = -np.inf
        if trial % 13 == 0:
            v[rng.integers(0, n)] = np.nan
        yield v


def test_median_and_mad_are_numpys():
    rng = np.random.default_rng(3)
    for v in _vectors(rng):
        with np.errstate(invalid="ignore"):
            ref = np.median(v)
            ref_mad = np.median(np.abs(v - ref))
        assert np.array_equal(median_of(v), ref, equal_nan=True), (v, median_of(v), ref)
        assert np.array_equal(mad_of(v), ref_mad, equal_nan=True), (v, mad_of(v), ref_mad)
        assert np.array_equal(median(v), ref, equal_nan=True)
        assert np.array_equal(robust_sigma(v), MAD_TO_SIGMA * ref_mad, equal_nan=True)
    assert np.isnan(median_of(np.zeros(0))) and mad_of(np.zeros(0)) == 0.0
    assert robust_sigma(np.zeros(0)) == 0.0
    big = rng.normal(size=5001)  # a long one, and one all equal
    assert median_of(big) == np.median(big) and median_of(np.ones(100)) == 1.0


def _reference_despike(y):
    """despike's formula with scipy's median filter and numpy's median."""
    med = median_filter(y, size=(5, 1), mode="nearest")
    dev = y - med
    sigma = np.array([MAD_TO_SIGMA * np.median(np.abs(dev[:, c] - np.median(dev[:, c])))
                      for c in range(y.shape[1])])
    span = np.ptp(med, axis=0)
    spikes = (np.abs(dev) > SPIKE_SIGMAS * sigma) & (np.abs(dev) > SPIKE_SHARE * span)
    return med, spikes, np.where(spikes, med, y)


def test_running_median_and_spikes_are_scipys():
    rng = np.random.default_rng(5)
    n_spiked = 0
    for trial in range(1500):
        n, k = int(rng.integers(5, 120)), int(rng.integers(1, 4))
        y = np.cumsum(rng.normal(size=(n, k)), axis=0) * 0.05 + rng.normal(size=(n, k)) * 0.01
        if trial % 3 == 0:
            y = np.round(y * 4.0)  # quantised: runs of equal values
        for _ in range(int(rng.integers(0, 3))):  # one- and two-sample spikes
            i, c = int(rng.integers(0, n - 1)), int(rng.integers(0, k))
            y[i:i + int(rng.integers(1, 3)), c] += rng.choice([-1, 1]) * 30.0
        med, spikes, count, finite = despike_columns(y, SPIKE_SIGMAS, SPIKE_SHARE, MAD_TO_SIGMA)
        ref_med, ref_spikes, ref_values = _reference_despike(y)
        assert finite
        assert np.array_equal(med, ref_med), (y, med, ref_med)
        assert np.array_equal(spikes, ref_spikes) and count == ref_spikes.sum()
        got = despike(y)
        assert np.array_equal(got.values, ref_values) and np.array_equal(got.spikes, ref_spikes)
        n_spiked += int(count > 0)
    assert n_spiked > 300  # the spikes were found


def test_non_finite_readings_take_scipys_path():
    y = np.random.default_rng(2).normal(size=(40, 2))
    y[7, 1] = 25.0
    y[20, 0] = np.nan
    assert not despike_columns(y, SPIKE_SIGMAS, SPIKE_SHARE, MAD_TO_SIGMA)[3]
    _, ref_spikes, ref_values = _reference_despike(y)
    got = despike(y)
    assert np.array_equal(got.spikes, ref_spikes)
    assert np.array_equal(got.values, ref_values, equal_nan=True)


def _reference_activity(t, s, w, margin, fraction, snr):
    """unexplained_activity's active samples with numpy (its code before the kernel)."""
    inside = np.zeros(t.size, dtype=bool)
    for a, b in w:
        inside |= (t >= a - margin) & (t <= b + margin)
    outside = ~inside
    if outside.sum() < 0.1 * t.size or not inside.any():
        return None
    dev = s - np.median(s[outside])
    d = np.diff(s)
    noise = (MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) if d.size else 0.0) / np.sqrt(2.0)
    limit = max(fraction * np.abs(dev[inside]).max(), snr * noise)
    return outside & (np.abs(dev) > limit)


def test_outside_activity_is_numpys():
    rng = np.random.default_rng(11)
    n_active = n_none = 0
    for trial in range(2000):
        n = int(rng.integers(1, 300))
        t = np.arange(n) / 512.0 + float(rng.normal())
        s = rng.normal(size=n) * 0.1 + float(rng.normal()) * 5
        if trial % 3 == 0:
            s = np.round(s * 20.0)  # quantised
        for _ in range(int(rng.integers(0, 3))):  # pulses
            i = int(rng.integers(0, n))
            s[i:i + int(rng.integers(1, 40))] += float(rng.normal()) * 10
        m = int(rng.integers(0, 4))
        lo = rng.uniform(t[0] - 0.2, t[-1] + 0.1, size=m)
        w = np.column_stack([lo, lo + rng.uniform(0.0, 0.4, size=m)])
        margin, fraction, snr = 0.05, float(rng.uniform(0.05, 0.5)), float(rng.uniform(2, 10))
        status, active = outside_activity(t, s, w, margin, fraction, snr, MAD_TO_SIGMA,
                                          np.nan)
        # the noise made once (presence.signal_noise) and given: the same samples
        given = outside_activity(t, s, w, margin, fraction, snr, MAD_TO_SIGMA,
                                 signal_noise(s))
        ref = _reference_activity(t, s, w, margin, fraction, snr)
        if ref is None:
            assert status == 0 and given[0] == 0
            n_none += 1
        else:
            assert status == 1 and np.array_equal(active, ref), (trial, active, ref)
            assert given[0] == 1 and np.array_equal(given[1], ref), trial
            n_active += int(ref.any())
    assert n_active > 200 and n_none > 200
    s = np.ones(50)
    s[3] = np.nan
    assert outside_activity(np.arange(50.0), s, np.array([[10.0, 20.0]]), 0.05, 0.2, 8.0,
                            MAD_TO_SIGMA, np.nan)[0] == 2


def test_unexplained_activity_with_its_noise_and_step_given():
    """unexplained_activity with the signal's noise and the median time step made once
    (a signal judged against several sets of windows): the same intervals."""
    rng = np.random.default_rng(23)
    n_found = 0
    for trial in range(600):
        n = int(rng.integers(2, 400))
        t = np.arange(n) / 512.0 + float(rng.normal())
        s = rng.normal(size=n) * 0.1
        for _ in range(int(rng.integers(0, 4))):
            i = int(rng.integers(0, n))
            s[i:i + int(rng.integers(1, 60))] += float(rng.normal()) * 10
        if trial % 9 == 0:
            s[int(rng.integers(0, n))] = np.nan  # numpy's path
        lo = rng.uniform(t[0], t[-1], size=int(rng.integers(1, 3)))
        w = np.column_stack([lo, lo + rng.uniform(0.0, 0.2, size=lo.size)])
        with np.errstate(invalid="ignore"):
            ref = unexplained_activity(t, s, w)
            got = unexplained_activity(t, s, w, noise=signal_noise(s),
                                       step=median(np.diff(t)))
        assert np.array_equal(got, ref), trial
        n_found += len(ref) > 0
    assert n_found > 50


def test_column_medians_of_are_numpys():
    rng = np.random.default_rng(13)
    n_zero = 0
    for trial in range(3000):
        n, k = int(rng.integers(1, 70)), int(rng.integers(1, 6))
        a = rng.normal(size=(n, k))
        if trial % 3 == 0:
            a = np.round(a * 0.7)  # ties, zeros of both signs
        if trial % 7 == 0:
            a[rng.integers(0, n), rng.integers(0, k)] = np.nan
        if trial % 11 == 0:
            a[rng.integers(0, n), rng.integers(0, k)] = np.inf
        with np.errstate(invalid="ignore"):
            ref = np.median(a, axis=0)
        got, zero = column_medians_of(a, np.ones(n, dtype=bool))
        assert np.array_equal(got, ref, equal_nan=True), (a, got, ref)
        assert zero == bool(np.any(ref == 0))
        n_zero += zero
        rows = rng.random(n) < 0.6
        if rows.any():
            with np.errstate(invalid="ignore"):
                ref = np.median(a[rows], axis=0)
            got, zero = column_medians_of(a, rows)
            assert np.array_equal(got, ref, equal_nan=True), (a, rows, got, ref)
            assert zero == bool(np.any(ref == 0))
    assert n_zero > 300


def _reference_peaks(t, data, lo, hi, level, threshold):
    """lateral_positions' peak weights of one window, written with numpy (the code
    before the kernel): (status, weights) as window_peaks gives them."""
    inside = (t >= lo) & (t <= hi)
    if not inside.any():
        return 0, None
    w = np.maximum(data[inside].max(axis=0) - level, 0.0)
    if not (w > 0).any():
        return 1, None
    return 2, np.maximum(w - threshold * w.max(), 0.0)


def test_window_peaks_are_numpys():
    """2000 tables (ties, NaN, ±inf; windows inside, across the ends, empty): the same
    status, and the same weights (equal as numbers, NaN where numpy's is)."""
    rng = np.random.default_rng(17)
    counts = [0, 0, 0]
    for trial in range(2000):
        n, k = int(rng.integers(1, 80)), int(rng.integers(1, 14))
        t = np.arange(n) / 256.0 + float(rng.normal())
        data = rng.normal(size=(n, k))
        if trial % 3 == 0:
            data = np.round(data * 0.7)
        if trial % 7 == 0:
            data[rng.integers(0, n), rng.integers(0, k)] = np.nan
        if trial % 11 == 0:
            data[rng.integers(0, n), rng.integers(0, k)] = np.inf
        level = rng.normal(size=k) * (0.0 if trial % 5 == 0 else 1.0) + (
            3.0 if trial % 4 == 0 else 0.0)  # some windows without a positive weight
        lo = float(rng.uniform(t[0] - 0.1, t[-1] + 0.02))
        hi = lo + float(rng.uniform(0.0, 0.2))
        thr = float(rng.choice([0.0, 0.5, rng.uniform(0, 1)]))
        status, w = window_peaks(t, np.ascontiguousarray(data.T), lo, hi, level, thr)
        with np.errstate(invalid="ignore"):
            ref_status, ref = _reference_peaks(t, data, lo, hi, level, thr)
        assert status == ref_status, (trial, status, ref_status)
        if ref is not None:
            assert np.array_equal(w, ref, equal_nan=True), (trial, w, ref)
        counts[status] += 1
    assert min(counts) > 100, counts


def test_row_medians_are_column_medians_of_the_transpose():
    """A table's columns one after the other (a Fortran-ordered table's transpose, no
    copy): the medians of its columns, numpy's."""
    rng = np.random.default_rng(29)
    for trial in range(1000):
        n, k = int(rng.integers(1, 80)), int(rng.integers(1, 14))
        a = np.asfortranarray(rng.normal(size=(n, k)))
        if trial % 3 == 0:
            a = np.asfortranarray(np.round(a * 0.7))
        if trial % 7 == 0:
            a[rng.integers(0, n), rng.integers(0, k)] = np.nan
        rows = rng.random(n) < 0.7
        rows[rng.integers(0, n)] = True
        with np.errstate(invalid="ignore"):
            ref = np.median(a[rows], axis=0)
        got, zero = row_medians_of(a.T, rows)
        assert np.array_equal(got, ref, equal_nan=True), (trial, got, ref)
        assert zero == bool(np.any(ref == 0))


def test_outside_windows_are_numpys():
    rng = np.random.default_rng(31)
    for _ in range(500):
        n = int(rng.integers(1, 300))
        t = np.arange(n) / 512.0 + float(rng.normal())
        lo = rng.uniform(t[0] - 0.2, t[-1] + 0.1, size=int(rng.integers(0, 4)))
        w = np.column_stack([lo, lo + rng.uniform(0.0, 0.4, size=lo.size)])
        inside = np.zeros(n, dtype=bool)
        for a, b in w:
            inside |= (t >= a - 0.05) & (t <= b + 0.05)
        outside, count = outside_windows(t, w.reshape(-1, 2), 0.05)
        assert np.array_equal(outside, ~inside) and count == int((~inside).sum())


def test_end_excursion_is_numpys():
    """ends_loaded's means (numpy's pairwise sums: stretches beyond 8 and 128 values)
    and its argmax of the excursion (ties, a NaN)."""
    rng = np.random.default_rng(37)
    for trial in range(1500):
        n = int(rng.integers(2, 300))
        y = rng.normal(size=int(rng.integers(2 * n, 5 * n))) * 10.0 ** rng.uniform(-8, 2)
        if trial % 4 == 0:
            y = np.round(y / np.abs(y).max() * 3)  # ties
        if trial % 23 == 0:
            y[rng.integers(0, y.size)] = np.nan
        start, end, middle, k, excursion = end_excursion(y, n)
        ref_start = float(y[:n].mean())
        assert start == ref_start or (start != start and ref_start != ref_start)
        assert end == float(y[-n:].mean()) or np.isnan(end)
        assert middle == float(y[n:2 * n].mean()) or np.isnan(middle)
        dev = y - ref_start
        assert k == int(np.argmax(np.abs(dev)))
        assert excursion == dev[k] or (np.isnan(excursion) and np.isnan(dev[k]))


def test_signed_extremes_are_numpys():
    """diagnose's excursions: ``z = (y - rest) * signs``, ``z.max(axis=0)`` and
    ``-z.min(axis=0)`` (ties, NaN anywhere, one row)."""
    rng = np.random.default_rng(41)
    for trial in range(1500):
        n = int(rng.integers(1, 200))
        y = rng.normal(size=(n, 2)) * 10.0 ** rng.uniform(-6, 2)
        if trial % 3 == 0:
            y = np.round(y / np.abs(y).max() * 3)
        if trial % 13 == 0:
            y[rng.integers(0, n), rng.integers(0, 2)] = np.nan
        rest = rng.normal(size=2) * (trial % 2)
        signs = rng.choice([-1.0, 1.0], size=2)
        z = (y - rest) * signs
        up, down = signed_extremes(y, rest, signs)
        assert np.array_equal(up, z.max(axis=0), equal_nan=True), trial
        assert np.array_equal(down, -z.min(axis=0), equal_nan=True), trial


def test_medians_of_long_and_patterned_vectors_are_numpys():
    """The selection on long vectors (its partitions, not only its final insertion
    sort): sorted, reversed, organ-pipe, constant, two values, quantised, ±inf; the
    median, the MAD and the column medians equal numpy's."""
    rng = np.random.default_rng(43)
    for trial in range(600):
        n = int(rng.integers(17, 2500))
        v = rng.normal(size=n) * 10.0 ** rng.uniform(-6, 3)
        kind = trial % 8
        if kind == 1:
            v = np.sort(v)
        elif kind == 2:
            v = np.sort(v)[::-1].copy()
        elif kind == 3:
            s = np.sort(v)
            v = np.concatenate([s[::2], s[1::2][::-1]])  # organ pipe
        elif kind == 4:
            v = np.full(n, float(rng.normal()))
        elif kind == 5:
            v = rng.choice([-1.5, 2.0], size=n)
        elif kind == 6:
            v = np.round(v / np.abs(v).max() * 4)
        elif kind == 7:
            v[rng.integers(0, n, 3)] = [np.inf, -np.inf, np.inf]
        assert median_of(v) == np.median(v), trial
        assert mad_of(v) == np.median(np.abs(v - np.median(v))), trial
        rows = rng.random(n) < 0.7
        rows[0] = True
        a = np.vstack([v, v[::-1]])
        got, _ = row_medians_of(a, rows)
        assert np.array_equal(got, np.median(a[:, rows], axis=1)), trial
