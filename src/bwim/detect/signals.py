"""Signal helpers for vehicle detection: baseline removal, robust noise, sub-sample peaks.

Contract
--------
* :func:`remove_baseline` subtracts a running median (a high-pass filter that ignores
  short pulses): a constant offset and any drift slower than the window disappear, and a
  pulse much shorter than half the window keeps its shape and timing (no phase shift).
* :func:`robust_sigma` is the normalised median absolute deviation, 1.4826 MAD, the
  standard deviation of Gaussian noise that ignores a minority of large samples (pulses).
* :func:`median` is ``numpy.median`` of a 1-D array (the mean of the two middle values
  for an even count; NaN if any value is), the same number by one compiled selection
  (:func:`bwim.detect.order_stats.median_of`; equal as numbers: where numpy gives +0.0,
  ties of signed zeros may give -0.0); :func:`column_medians` is
  ``numpy.median(values, axis=0)`` of a 2-D array (or of some of its rows), the same
  numbers bit for bit, by one compiled selection in each column
  (:func:`bwim.detect.order_stats.row_medians_of` of the columns one after the other:
  no copy of a Fortran-ordered table, a record's columns), or, when a median is zero (whose
  sign rests on numpy's order of equal values), by numpy's partial sort of each column
  laid out contiguously.
* :func:`last_axis_sum` is ``values.sum(axis=-1)``, the same numbers: numpy adds a last
  axis shorter than 8 one value after the other from 0 (its pairwise sum starts at 8
  values), as this does with one array operation per value instead of numpy's reduction
  machinery over many short rows; longer axes are numpy's own sum.
* :func:`parabolic_vertex` gives the sub-sample position of local maxima: the vertex of
  the parabola through the three samples around each (fractional sample index).
* :func:`split_vehicles` cuts a sequence of axles into vehicles at gaps longer than a
  plausible axle spacing.
* :func:`channel_data` is a record's readings of some channels, (n_t, k): those of
  :meth:`bwim.Record.channels` without making a new record (Fortran-ordered, as numpy's
  indexing of the columns gives them: its reductions sum in that order);
  :func:`channel_rows` those of some samples only, in one gather (C-ordered, as
  ``channel_data(...)[rows]``).
* :func:`gaussian_average` is the Gaussian average along axis 0 of
  ``scipy.ndimage.gaussian_filter1d(y, sigma, axis=0, mode="nearest")`` (the same kernel:
  ``exp(−x²/2σ²)`` over ``|x| ≤ int(4σ + 0.5)`` samples, normalised to sum 1; the ends
  extended by their edge values), made by one FFT of the padded signal instead of a
  direct sum: the same numbers to rounding (relative to the signal's largest magnitude),
  faster for wide kernels; given several ``(σ, weight)`` it returns their weighted sum
  from the same FFT (a band-pass as one filter).

* :func:`despike` replaces isolated spikes (one or two samples standing more than
  :data:`SPIKE_SIGMAS` robust deviations, and more than :data:`SPIKE_SHARE` of the
  channel's range, off the median of their five-sample neighbourhood) by that median;
  only for signals whose narrowest pulse is much wider than a spike (the caller checks).
  Finite readings go through one compiled kernel
  (:func:`bwim.detect.order_stats.despike_columns`: the numbers of
  ``scipy.ndimage.median_filter`` and :func:`robust_sigma`), others through scipy.

Arrays are 1-D in samples unless stated; times in s, distances in m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.fft
from scipy.ndimage import median_filter

from bwim.records import Record
from bwim.sensors import Sensor

from .order_stats import despike_columns, mad_of, median_of, row_medians_of

__all__ = ["SPIKE_SHARE", "SPIKE_SIGMAS", "Despiked", "channel_data", "channel_rows",
           "column_medians", "despike", "gaussian_average", "gaussian_kernel",
           "last_axis_sum", "median", "parabolic_vertex", "remove_baseline", "robust_sigma",
           "split_vehicles"]

#: Gaussian kernels reach this many standard deviations (scipy.ndimage's default).
TRUNCATE = 4.0

#: Normalised MAD: 1 / Φ⁻¹(3/4), so that robust_sigma of Gaussian noise is its σ.
MAD_TO_SIGMA = 1.482602218505602
#: A spike stands this many robust deviations off its five-sample median ...
SPIKE_SIGMAS = 12.0
#: ... and this share of the range of the channel's five-sample medians.
SPIKE_SHARE = 0.1


@dataclass(frozen=True, eq=False)
class Despiked:
    """:func:`despike`'s result: the readings with the spikes replaced, (n_t, k), and
    where they were (bool, the same shape)."""

    values: np.ndarray
    spikes: np.ndarray

    @property
    def any(self) -> bool:
        return bool(self.spikes.any())


def despike(y: np.ndarray) -> Despiked:
    """``y`` (n_t, k) with isolated spikes replaced by the median of their five-sample
    neighbourhood (see the module docstring).  A smooth pulse moves off that median by
    its curvature only (under 2 % of its height for a pulse 12 samples wide at half
    height); a one- or two-sample spike by its own height.  The deviations' robust σ is
    each channel's noise."""
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[0] < 5:
        return Despiked(values=y, spikes=np.zeros(y.shape, dtype=bool))
    med, spikes, count, finite = despike_columns(np.ascontiguousarray(y), SPIKE_SIGMAS,
                                                 SPIKE_SHARE, MAD_TO_SIGMA)
    if not finite:  # scipy's handling of NaN and infinities
        med = median_filter(y, size=(5, 1), mode="nearest")
        dev = y - med
        sigma = np.array([robust_sigma(dev[:, c]) for c in range(dev.shape[1])])
        span = np.ptp(med, axis=0)
        spikes = (np.abs(dev) > SPIKE_SIGMAS * sigma) & (np.abs(dev) > SPIKE_SHARE * span)
        count = int(spikes.sum())
    if not count:
        return Despiked(values=y, spikes=spikes)
    return Despiked(values=np.where(spikes, med, y), spikes=spikes)


def median(values: np.ndarray) -> float:
    """The median of the values of a 1-D array (see the module docstring); NaN for none."""
    return float(median_of(np.ascontiguousarray(values, dtype=float).reshape(-1)))


def column_medians(values: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """The median of each column of a 2-D array (n, k), shape (k,) (see the module
    docstring); NaN for a column holding one, and for every column when n = 0.  With
    ``rows`` (bool, (n,)): of ``values[rows]``, without copying them first."""
    v = np.asarray(values, dtype=float)
    if rows is None:
        rows = np.ones(v.shape[0], dtype=bool)
    else:
        rows = np.ascontiguousarray(rows, dtype=bool)
    if not rows.any():
        return np.full(v.shape[1], np.nan)
    # the columns one after the other: a record's columns (Fortran-ordered) as they are
    out, zero = row_medians_of(np.ascontiguousarray(v.T), rows)
    if not zero:
        return out
    cols = np.ascontiguousarray(v[rows].T)  # each column's values one after the other
    n = cols.shape[1]
    k = n // 2
    # the middle order statistics (the mean of the two for an even count) and the
    # largest, NaN when the column holds one (NaN sorts last): numpy.median's partial
    # sort, the same indices (so the same order of equal values, e.g. 0 and -0)
    cols.partition([k, -1] if n % 2 else [k - 1, k, -1], axis=1)
    middle = cols[:, k:k + 1] if n % 2 else cols[:, k - 1:k + 1]
    out = np.add.reduce(middle, axis=1)  # their mean as numpy.mean makes it
    out /= middle.shape[1]
    nan = np.isnan(cols[:, -1])
    if nan.any():
        out[nan] = np.nan
    return out


def last_axis_sum(values: np.ndarray) -> np.ndarray:
    """``values.sum(axis=-1)`` of a float array, the same numbers (see the module
    docstring): faster for many short rows."""
    v = np.asarray(values, dtype=float)
    k = v.shape[-1]
    if not 2 <= k < 8:
        return v.sum(axis=-1)
    out = v[..., 0] + 0.0  # numpy's sum starts from 0 (-0.0 + 0.0 is 0.0)
    for i in range(1, k):
        out += v[..., i]
    return out


def robust_sigma(values: np.ndarray) -> float:
    """1.4826 × median |v − median v|: the noise standard deviation, robust to pulses."""
    v = np.ascontiguousarray(values, dtype=float).reshape(-1)
    return float(MAD_TO_SIGMA * mad_of(v)) if v.size else 0.0


def remove_baseline(values: np.ndarray, window: int) -> np.ndarray:
    """``values`` minus their running median over ``window`` samples (made odd, ≥ 3)."""
    v = np.asarray(values, dtype=float)
    w = max(3, int(window) | 1)
    if w >= v.size:
        return v - np.median(v)
    return v - median_filter(v, size=w, mode="nearest")


def parabolic_vertex(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Fractional sample position of the maxima at ``index`` (parabola through three
    samples; the sample itself at the ends of the array or on a flat top)."""
    v = np.asarray(values, dtype=float)
    i = np.asarray(index, dtype=int)
    out = i.astype(float)
    inner = (i > 0) & (i < v.size - 1)
    if not np.any(inner):
        return out
    k = i[inner]
    ym, y0, yp = v[k - 1], v[k], v[k + 1]
    den = ym - 2.0 * y0 + yp
    safe = den < 0  # a true maximum
    shift = np.zeros(k.size)
    shift[safe] = 0.5 * (ym[safe] - yp[safe]) / den[safe]
    out[inner] = k + np.clip(shift, -0.5, 0.5)
    return out


def split_vehicles(positions: np.ndarray, max_axle_spacing: float) -> list[np.ndarray]:
    """Index arrays of the vehicles in a sorted sequence of axle ``positions`` (m, e.g.
    axle time × speed): a new vehicle starts where consecutive axles are more than
    ``max_axle_spacing`` apart."""
    p = np.asarray(positions, dtype=float)
    if p.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(p) > max_axle_spacing) + 1
    return np.split(np.arange(p.size), cuts)


def channel_data(record: Record, sensors: Sequence[str | Sensor]) -> np.ndarray:
    """The readings (n_t, k) of the channels ``sensors`` (names or Sensors), in that
    order: ``record.channels(sensors).data`` without making a record; InputError for a
    channel the record does not have."""
    return record.data[:, record.channel_indices(sensors)]


def channel_rows(record: Record, sensors: Sequence[str | Sensor], rows: np.ndarray
                 ) -> np.ndarray:
    """``channel_data(record, sensors)[rows]`` (``rows``: sample indices, in order) read
    in one gather: the same numbers, a new C-ordered table (n_rows, k)."""
    cols = np.array(record.channel_indices(sensors), dtype=np.intp)
    return record.data.take(np.asarray(rows, dtype=np.intp), axis=0).take(cols, axis=1)


def gaussian_kernel(sigma: float) -> np.ndarray:
    """The normalised Gaussian weights of ``sigma`` samples over ``|x| ≤ int(4σ + 0.5)``
    (those of ``scipy.ndimage.gaussian_filter1d``, which sum to 1)."""
    radius = int(TRUNCATE * float(sigma) + 0.5)
    x = np.arange(-radius, radius + 1, dtype=float)
    phi = np.exp(-0.5 / (float(sigma) * float(sigma)) * x * x)
    return phi / phi.sum()


def gaussian_average(y: np.ndarray, filters: Sequence[tuple[float, float]]) -> np.ndarray:
    """``Σ weight × (y averaged by a Gaussian of σ samples)`` along axis 0, over
    ``filters`` (``(σ, weight)`` pairs), the ends extended by their edge values: the
    numbers of ``Σ weight × gaussian_filter1d(y, σ, axis=0, mode="nearest")`` to rounding
    (see the module docstring), by one FFT of ``y`` padded by the widest kernel's
    radius.  ``y`` (n,) or (n, k)."""
    y = np.asarray(y, dtype=float)
    kernels = [(gaussian_kernel(s), float(w)) for s, w in filters]
    r = max(k.size // 2 for k, _ in kernels)
    kernel = np.zeros(2 * r + 1)
    for k, w in kernels:  # each centred in the widest one's span
        h = k.size // 2
        kernel[r - h:r + h + 1] += w * k
    n = y.shape[0]
    if n == 0:
        return np.zeros_like(y)
    padded = np.empty((n + 2 * r, *y.shape[1:]))  # the ends extended by their edge values
    padded[:r] = y[0]
    padded[r:r + n] = y
    padded[r + n:] = y[-1]
    size = scipy.fft.next_fast_len(n + 4 * r, real=True)  # linear, not circular
    spec = np.fft.rfft(padded, size, axis=0)
    spec *= np.fft.rfft(kernel, size).reshape(-1, *([1] * (y.ndim - 1)))
    # the full convolution's sample 2 r + i is output sample i (the kernel is symmetric)
    return np.fft.irfft(spec, size, axis=0)[2 * r:2 * r + n]
