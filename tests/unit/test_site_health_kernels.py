"""The gauge check's compiled comparisons (bwim.site.health_kernels) against the numpy
expressions bwim.site.health used before them, on random data: the same numbers bit for
bit (numpy's pairwise sums, its column sums, no fused multiply-add)."""

import numpy as np
import pytest

from bwim.site.health_kernels import (
    comparison,
    gain_stats,
    held_extremes,
    loo_lines,
    residuals,
    step_noise,
)


def _lines_at(x, y, weight, at):
    """The numpy reference: per row, the weighted least-squares line at ``at``."""
    wsum = weight.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        xm = (weight * x).sum(axis=1) / wsum
        ym = (weight * y).sum(axis=1) / wsum
        dx = x - xm[:, None]
        sxx = (weight * dx ** 2).sum(axis=1)
        slope = np.where(sxx > 0, (weight * dx * (y - ym[:, None])).sum(axis=1) / sxx, 0.0)
        return np.where(wsum > 0, ym + slope * (at - xm), np.nan)


def _loo_reference(y, values, weight):
    n = len(values)
    others = ~np.eye(n, dtype=bool)

    def rows(a):
        return np.broadcast_to(a, (n, n))[others].reshape(n, n - 1)

    return _lines_at(rows(y), rows(values), rows(weight), y)


def _gain_reference(m, f):
    power = (f * f).sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (m * f).sum(axis=0) / power
    mc, fc = m - m.mean(axis=0), f - f.mean(axis=0)
    corr = (mc * fc).sum(axis=0) / np.sqrt(np.maximum((mc * mc).sum(axis=0)
                                                      * (fc * fc).sum(axis=0), 1e-300))
    return power, a, corr, np.sqrt(power / m.shape[0])


def test_leave_one_out_lines_are_numpys_row_sums():
    rng = np.random.default_rng(5)
    for trial in range(400):
        n = int(rng.integers(2, 40))
        y = np.sort(rng.uniform(0.0, 12.0, n))
        if trial % 5 == 0:
            y = np.arange(n, dtype=float)
        values = rng.normal(1.0, 0.3, n) * 10.0 ** rng.uniform(-3, 3)
        weight = rng.uniform(0.1, 40.0, n) ** 2
        if trial % 7 == 0:  # no weight at all beside one channel, no spread in x
            weight[1:] = 0.0
        if trial % 11 == 0:
            y[:] = 2.5
        got, ref = loo_lines(y, values, weight, y), _loo_reference(y, values, weight)
        assert got.tobytes() == ref.tobytes(), trial


@pytest.mark.parametrize("seed", range(4))
def test_gain_stats_are_numpys_column_sums(seed):
    rng = np.random.default_rng(seed)
    for trial in range(150):
        n, nc = int(rng.integers(1, 700)), int(rng.integers(2, 14))
        f = rng.normal(size=(n, nc)) * 10.0 ** rng.uniform(-8, 2, nc)
        m = rng.normal(0.9, 0.5, nc) * f + 1e-3 * rng.normal(size=(n, nc)) * np.abs(f).max()
        if trial % 10 == 0:
            f[:, 0] = 0.0  # no power: gain nan, as numpy's 0 / 0
        if trial % 13 == 0:
            m[:, -1] = 3.0  # no shape: correlation 0 over the floor
        got = gain_stats(m, f)
        for g, r in zip((got.power, got.gain, got.corr, got.rms), _gain_reference(m, f),
                        strict=True):
            assert g.tobytes() == r.tobytes(), trial


def _held_reference(readings, run):
    out = np.zeros(readings.shape[1], dtype=bool)
    m = readings.shape[0] - run + 1
    if m <= 0:
        return out
    for extreme in (readings.max(axis=0), readings.min(axis=0)):
        at = readings == extreme
        held = at[:m].copy()
        for j in range(1, run):
            held &= at[j:j + m]
        out |= held.any(axis=0)
    return out


def test_step_noise_is_numpys_std_of_the_steps():
    rng = np.random.default_rng(8)
    for trial in range(300):
        n, nc = int(rng.integers(2, 1500)), int(rng.integers(1, 14))
        a = np.cumsum(rng.normal(size=(n, nc)), axis=0) * 10.0 ** rng.uniform(-9, 3, nc)
        if trial % 4 == 0:  # a coarse logger: repeated samples, a constant channel
            a = np.round(a / a.std() * 3.0) if a.std() > 0 else a
            a[:, 0] = 1.5
        ref = np.std(np.diff(np.ascontiguousarray(a.T), axis=1), axis=1) / np.sqrt(2.0)
        assert step_noise(a).tobytes() == ref.tobytes(), trial
        # a record's columns (Fortran-ordered: taken as they lie)
        assert step_noise(np.asfortranarray(a)).tobytes() == ref.tobytes(), trial


def test_held_extremes_are_runs_at_the_maximum_or_minimum():
    rng = np.random.default_rng(9)
    for trial in range(400):
        n, nc, run = int(rng.integers(1, 80)), int(rng.integers(1, 8)), int(
            rng.integers(1, 8))
        a = rng.integers(-3, 4, size=(n, nc)).astype(float)  # many ties and runs
        if trial % 3 == 0:
            a = rng.normal(size=(n, nc))
            a[n // 3:n // 3 + run, 0] = a.max() + 1.0
        assert np.array_equal(held_extremes(a, run), _held_reference(a, run)), trial
        assert np.array_equal(held_extremes(np.asfortranarray(a), run),
                              _held_reference(a, run)), trial


def test_residuals_are_numpys():
    """``r = readings - offsets; r[on] -= fitted`` (the gauge check's residual before the
    kernel): equal bit for bit, signed zeros included, also for F-ordered readings (a
    record's columns) and no sample or every sample fitted."""
    rng = np.random.default_rng(21)
    for trial in range(500):
        n, nc = int(rng.integers(1, 300)), int(rng.integers(1, 13))
        readings = rng.normal(size=(n, nc)) * 1e-4
        if trial % 2:
            readings = np.asfortranarray(readings)
        if trial % 5 == 0:
            readings = np.round(readings * 1e4) * 0.0  # zeros, some negative
        offsets = rng.normal(size=nc) * 1e-4 * (trial % 3 != 0)
        on = rng.random(n) < (0.0 if trial % 17 == 0 else 1.0 if trial % 19 == 0 else 0.5)
        fitted = rng.normal(size=(int(on.sum()), nc)) * 1e-4
        ref = readings - offsets
        ref[on] -= fitted
        got = residuals(readings, offsets, on, fitted)
        assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
    with pytest.raises(ValueError, match="one fitted row"):
        residuals(np.zeros((4, 2)), np.zeros(2), np.ones(4, dtype=bool), np.zeros((3, 2)))


def _comparison_reference(m, f, var, y, trend, noise):
    """The gauge check's comparison as bwim.site.health wrote it with numpy (before the
    kernel): gain statistics, snr, the others' prediction, ratios, significances, and
    the drift beyond the others'."""
    st = gain_stats(m, f)
    if np.any(st.power <= 0):
        return None
    snr = st.rms / np.sqrt(np.clip(var, np.finfo(float).tiny, None))
    expected = loo_lines(y, st.gain, snr ** 2, y)
    keep = expected > 0
    ratio = np.divide(st.gain, expected, out=np.zeros(len(y)), where=keep)
    significance = np.abs(st.gain - expected) * snr
    shown = loo_lines(y, trend / st.rms, snr ** 2, y) * st.rms
    change = np.divide(np.abs(trend - shown), noise, out=np.zeros(len(y)), where=noise > 0)
    return st, snr, ratio, keep, significance, change


def test_comparison_is_the_numpy_check():
    """The check's comparison in one kernel: every number bit for bit (ratios where the
    prediction is positive, zero noise, tiny and nan variances, a channel without
    power refused)."""
    rng = np.random.default_rng(33)
    n_none = 0
    for trial in range(600):
        n, nc = int(rng.integers(1, 300)), int(rng.integers(2, 14))
        f = rng.normal(size=(n, nc)) * 10.0 ** rng.uniform(-6, -3, nc)
        m = f * rng.uniform(-1.5, 2.5, nc) + rng.normal(size=(n, nc)) * 1e-6
        if trial % 17 == 0:
            f[:, int(rng.integers(0, nc))] = 0.0  # no power: refused
        var = rng.uniform(1e-14, 1e-10, nc)
        var[rng.random(nc) < 0.1] = 0.0  # clipped to tiny
        if trial % 7 == 0:
            var[int(rng.integers(0, nc))] = np.nan
        y = np.sort(rng.uniform(0, 12, nc)) if trial % 4 else np.arange(nc, dtype=float)
        trend = rng.normal(size=nc) * 1e-6
        noise = rng.uniform(0, 1e-7, nc)
        noise[rng.random(nc) < 0.2] = 0.0
        with np.errstate(all="ignore"):
            ref = _comparison_reference(m, f, var, y, trend, noise)
            got = comparison(m, f, var, y, trend, noise)
            plain = comparison(m, f, var, y)
        if ref is None:
            assert got is None and plain is None
            n_none += 1
            continue
        st, snr, ratio, keep, significance, change = ref
        for a, b in ((got.gain, st.gain), (got.corr, st.corr), (got.rms, st.rms),
                     (got.snr, snr), (got.ratio, ratio), (got.kept, keep),
                     (got.significance, significance), (got.change, change),
                     (plain.ratio, ratio), (plain.significance, significance)):
            assert a.tobytes() == b.tobytes(), trial
    assert n_none > 10
