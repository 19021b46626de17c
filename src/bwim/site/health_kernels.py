"""The gauge check's comparisons (:mod:`bwim.site.health`), compiled: each channel's gain
against its fitted reading, and each channel's line through the other channels.

Contract
--------
* :func:`gain_stats` gives, per channel of a weighing's measured and fitted readings
  (``m``, ``f``: (n_w, n_c)), its fitted reading's power ``Σ f²``, its gain
  ``Σ m f / Σ f²``, the correlation of ``m`` with ``f`` (both centred, the product of
  their sums of squares floored at 1e-300) and the fitted reading's rms
  ``√(Σ f² / n_w)``.  A channel without power has a gain of ±inf or nan (the caller
  refuses such a comparison).
* :func:`loo_lines` gives, for each of n values, the weighted least-squares straight
  line through the other n − 1 points ``(x_j, values_j)`` (weights ``weight_j``), at
  ``at``; nan for a point whose others have no weight, the line's slope 0 when their
  ``x`` do not spread.
* :func:`step_noise` gives each channel's sample-to-sample variation,
  ``std(diff(reading)) / √2`` (numpy's ``std``: the mean, the squared deviations'
  mean, its root), and :func:`held_extremes` whether a channel holds its maximum or its
  minimum over the record for at least ``run`` consecutive samples.
* :func:`comparison` gives the gauge check's comparison of a weighing's channels
  (:mod:`bwim.site.health`) in one call: :func:`gain_stats`; None when a channel's
  power is not positive; each channel's signal-to-noise ratio ``rms / √max(var, tiny)``
  (``var`` its expected residual variance); its prediction from the others' gains
  (:func:`loo_lines` with weights ``snr²`` at the positions ``y``), its ratio to it
  where the prediction is positive (0 elsewhere), the difference's significance
  ``|gain − prediction| snr``; with a ``trend`` per channel, the others' trends in
  proportion to their signals (:func:`loo_lines` of ``trend / rms``, times ``rms``) and
  the difference from it in units of ``noise`` (0 where the noise is not positive).
  Each number is the one numpy's elementwise expressions of :mod:`bwim.site.health`
  made (``numpy.clip``, ``**2`` as a product, ``numpy.divide`` with ``where``).
* :func:`residuals` gives each channel's residual over the record: ``readings −
  offsets``, less the fitted readings (one row per sample of ``on``, in order) at the
  samples of ``on``: numpy's ``r = readings - offsets; r[on] -= fitted``, the same
  numbers (each a difference of two, then of that and the fit).
* **The numbers of numpy, bit for bit**: every sum is numpy's for the same vector
  (:func:`bwim.pairwise.pairwise_sum`: its pairwise summation, from 0), every column sum
  of a table numpy's ``sum(axis=0)`` of a C-ordered table (row after row, from 0), and
  each product and quotient is the one numpy makes element by element (no fused
  multiply-add: compiled without ``fastmath``). tests/unit/test_site_health_kernels.py holds
  them to the numpy expressions :mod:`bwim.site.health` used before, on random data.
* Compiled with numba (``cache=True``: the first call in a process compiles them, or
  loads them from numba's cache); float64 arrays in, float64 out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from bwim.pairwise import pairwise_sum

__all__ = ["Comparison", "GainStats", "comparison", "gain_stats", "held_extremes",
           "loo_lines", "residuals", "step_noise"]


@numba.njit(cache=True)
def _vsum(a):  # pragma: no cover - compiled
    """``numpy.sum`` of a contiguous vector (:func:`bwim.pairwise.pairwise_sum`)."""
    return pairwise_sum(a, 0, a.size)


@numba.njit(cache=True, error_model="numpy")
def _gain_stats(m, f):  # pragma: no cover - compiled
    n, nc = m.shape
    out = np.zeros((4, nc))  # power, gain, corr, rms
    mf = np.zeros(nc)
    ms = np.zeros(nc)
    fs = np.zeros(nc)
    for k in range(n):  # numpy's column sums: row after row, from 0
        for c in range(nc):
            out[0, c] += f[k, c] * f[k, c]
            mf[c] += m[k, c] * f[k, c]
            ms[c] += m[k, c]
            fs[c] += f[k, c]
    for c in range(nc):
        ms[c] = ms[c] / n  # the means
        fs[c] = fs[c] / n
    cmf = np.zeros(nc)
    cmm = np.zeros(nc)
    cff = np.zeros(nc)
    for k in range(n):
        for c in range(nc):
            a = m[k, c] - ms[c]
            b = f[k, c] - fs[c]
            cmf[c] += a * b
            cmm[c] += a * a
            cff[c] += b * b
    for c in range(nc):
        out[1, c] = mf[c] / out[0, c]
        p = cmm[c] * cff[c]
        if p < 1e-300:  # numpy.maximum's floor (a nan stays nan)
            p = 1e-300
        out[2, c] = cmf[c] / np.sqrt(p)
        out[3, c] = np.sqrt(out[0, c] / n)
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class GainStats:
    """:func:`gain_stats`' result, one entry per channel."""

    power: np.ndarray  # Σ f²
    gain: np.ndarray  # Σ m f / Σ f²
    corr: np.ndarray  # correlation of m with f
    rms: np.ndarray  # √(Σ f² / n_w)


def gain_stats(m: np.ndarray, f: np.ndarray) -> GainStats:
    """Each channel's gain, correlation and signal against its fitted reading (module
    docstring); ``m`` and ``f`` (n_w ≥ 1, n_c)."""
    out = _gain_stats(np.ascontiguousarray(m, dtype=float),
                      np.ascontiguousarray(f, dtype=float))
    return GainStats(power=out[0], gain=out[1], corr=out[2], rms=out[3])


@numba.njit(cache=True, error_model="numpy")
def _loo_lines(x, v, w, at):  # pragma: no cover - compiled
    n = x.size
    out = np.empty(n)
    xr = np.empty(n - 1)
    vr = np.empty(n - 1)
    wr = np.empty(n - 1)
    t = np.empty(n - 1)
    for g in range(n):
        j = 0
        for i in range(n):  # the others, in order
            if i != g:
                xr[j], vr[j], wr[j] = x[i], v[i], w[i]
                j += 1
        wsum = _vsum(wr)
        for i in range(n - 1):
            t[i] = wr[i] * xr[i]
        xm = _vsum(t) / wsum
        for i in range(n - 1):
            t[i] = wr[i] * vr[i]
        vm = _vsum(t) / wsum
        for i in range(n - 1):
            d = xr[i] - xm
            t[i] = wr[i] * (d * d)
        sxx = _vsum(t)
        for i in range(n - 1):
            t[i] = wr[i] * (xr[i] - xm) * (vr[i] - vm)
        sxy = _vsum(t)
        slope = sxy / sxx if sxx > 0 else 0.0
        out[g] = vm + slope * (at[g] - xm) if wsum > 0 else np.nan
    return out


def loo_lines(x: np.ndarray, values: np.ndarray, weight: np.ndarray, at: np.ndarray
              ) -> np.ndarray:
    """Per point, the weighted straight line through the others, at ``at`` (module
    docstring); all of shape (n,), n ≥ 2."""
    def vec(a):
        return np.ascontiguousarray(a, dtype=float).reshape(-1)

    return _loo_lines(vec(x), vec(values), vec(weight), vec(at))


@numba.njit(cache=True, error_model="numpy")
def _comparison(m, f, var, tiny, y, trend, noise, with_trend
                ):  # pragma: no cover - compiled
    st = _gain_stats(m, f)
    nc = st.shape[1]
    out = np.zeros((8, nc))  # gain, corr, snr, rms, ratio, kept, significance, change
    for c in range(nc):
        if st[0, c] <= 0.0:  # numpy.any(power <= 0): a nan power passes
            return False, out
    gain = np.empty(nc)
    snr = np.empty(nc)
    w2 = np.empty(nc)
    for c in range(nc):
        v = var[c]
        if not (v >= tiny or v != v):  # numpy.clip(var, tiny, None)
            v = tiny
        gain[c] = st[1, c]
        snr[c] = st[3, c] / np.sqrt(v)
        w2[c] = snr[c] * snr[c]  # snr ** 2
    expected = _loo_lines(y, gain, w2, y)
    for c in range(nc):
        out[0, c] = gain[c]
        out[1, c] = st[2, c]
        out[2, c] = snr[c]
        out[3, c] = st[3, c]
        e = expected[c]
        if e > 0:  # numpy.divide(gain, expected, where=expected > 0), else 0
            out[4, c] = gain[c] / e
            out[5, c] = 1.0
        out[6, c] = abs(gain[c] - e) * snr[c]
    if with_trend:
        tr = np.empty(nc)
        for c in range(nc):
            tr[c] = trend[c] / st[3, c]
        shown = _loo_lines(y, tr, w2, y)
        for c in range(nc):
            d = abs(trend[c] - shown[c] * st[3, c])
            out[7, c] = d / noise[c] if noise[c] > 0 else 0.0
    return True, out


@dataclass(frozen=True, kw_only=True, eq=False)
class Comparison:
    """:func:`comparison`'s result, one entry per channel."""

    gain: np.ndarray  # Σ m f / Σ f²
    corr: np.ndarray  # correlation of m with f
    snr: np.ndarray  # rms / σ
    rms: np.ndarray  # √(Σ f² / n_w)
    ratio: np.ndarray  # gain over its prediction from the others (0 where not positive)
    kept: np.ndarray  # bool: the prediction is positive
    significance: np.ndarray  # |gain − prediction| snr
    change: np.ndarray  # the trend beyond the others', in units of the noise (trend given)


def comparison(m: np.ndarray, f: np.ndarray, var: np.ndarray, y: np.ndarray,
               trend: np.ndarray | None = None, noise: np.ndarray | None = None
               ) -> Comparison | None:
    """The gauge check's comparison of each channel (module docstring): ``m``, ``f``
    measured and fitted readings (n_w ≥ 1, n_c ≥ 2), ``var`` each channel's expected
    residual variance, ``y`` its position; ``trend`` and ``noise`` (n_c,) for the drift
    comparison.  None when a channel's fitted reading has no power."""
    def vec(a):
        return np.ascontiguousarray(a, dtype=float).reshape(-1)

    with_trend = trend is not None
    nc = np.shape(m)[1]
    ok, out = _comparison(np.ascontiguousarray(m, dtype=float),
                          np.ascontiguousarray(f, dtype=float), vec(var),
                          float(np.finfo(float).tiny), vec(y),
                          vec(trend) if with_trend else np.zeros(nc),
                          vec(noise) if with_trend else np.zeros(nc), with_trend)
    if not ok:
        return None
    return Comparison(gain=out[0], corr=out[1], snr=out[2], rms=out[3], ratio=out[4],
                      kept=out[5] > 0, significance=out[6], change=out[7])


@numba.njit(cache=True)
def _step_noise(cols):  # pragma: no cover - compiled
    nc, n = cols.shape  # the channels one after the other
    out = np.empty(nc)
    d = np.empty(n - 1)
    for c in range(nc):
        a = cols[c]
        for k in range(n - 1):
            d[k] = a[k + 1] - a[k]
        mean = _vsum(d) / (n - 1)
        for k in range(n - 1):
            x = d[k] - mean
            d[k] = x * x
        out[c] = np.sqrt(_vsum(d) / (n - 1)) / np.sqrt(2.0)
    return out


def step_noise(readings: np.ndarray) -> np.ndarray:
    """Each channel's ``std(diff(reading)) / √2`` (module docstring); ``readings``
    (n_t ≥ 2, n_c)."""
    return _step_noise(_columns(readings))


@numba.njit(cache=True)
def _held_extremes(cols, run):  # pragma: no cover - compiled
    nc, n = cols.shape  # the channels one after the other
    out = np.zeros(nc, dtype=np.bool_)
    if n < run:
        return out
    for c in range(nc):
        a = cols[c]
        hi = a[0]
        lo = a[0]
        for k in range(1, n):
            if a[k] > hi:
                hi = a[k]
            if a[k] < lo:
                lo = a[k]
        at_hi = 0  # the current run at each extreme
        at_lo = 0
        for k in range(n):
            at_hi = at_hi + 1 if a[k] == hi else 0
            at_lo = at_lo + 1 if a[k] == lo else 0
            if at_hi >= run or at_lo >= run:
                out[c] = True
                break
    return out


def held_extremes(readings: np.ndarray, run: int) -> np.ndarray:
    """Per channel of ``readings`` (n_t, n_c; finite) whether it holds its maximum or its
    minimum for at least ``run`` ≥ 1 consecutive samples (module docstring)."""
    return _held_extremes(_columns(readings), int(run))


def _columns(readings: np.ndarray) -> np.ndarray:
    """The channels of ``readings`` (n_t, n_c) one after the other, C-contiguous (n_c,
    n_t): a record's columns (Fortran-ordered) without a copy."""
    return np.ascontiguousarray(np.asarray(readings, dtype=float).T)


@numba.njit(cache=True)
def _residuals(cols, offsets, on, fitted, out):  # pragma: no cover - compiled
    nc, n = cols.shape  # the readings' channels one after the other
    j = 0
    for k in range(n):
        for c in range(nc):
            out[k, c] = cols[c, k] - offsets[c]
        if on[k]:
            for c in range(nc):
                out[k, c] = out[k, c] - fitted[j, c]
            j += 1


def residuals(readings: np.ndarray, offsets: np.ndarray, on: np.ndarray,
              fitted: np.ndarray) -> np.ndarray:
    """Each channel's residual (module docstring): ``readings`` (n_t, n_c), ``offsets``
    (n_c,), ``on`` bool (n_t,), ``fitted`` (count of ``on``, n_c); shape (n_t, n_c)."""
    cols = _columns(readings)
    on = np.ascontiguousarray(on, dtype=bool)
    fitted = np.ascontiguousarray(fitted, dtype=float)
    if fitted.shape != (int(np.count_nonzero(on)), cols.shape[0]):
        raise ValueError("residuals: one fitted row per sample of on")
    out = np.empty(cols.shape[::-1])
    _residuals(cols, np.ascontiguousarray(offsets, dtype=float), on, fitted, out)
    return out
