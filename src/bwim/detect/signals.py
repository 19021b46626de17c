"""Signal helpers for vehicle detection: baseline removal, robust noise, sub-sample peaks.

Contract
--------
* :func:`remove_baseline` subtracts a running median (a high-pass filter that ignores
  short pulses): a constant offset and any drift slower than the window disappear, and a
  pulse much shorter than half the window keeps its shape and timing (no phase shift).
* :func:`robust_sigma` is the normalised median absolute deviation, 1.4826 MAD, the
  standard deviation of Gaussian noise that ignores a minority of large samples (pulses).
* :func:`parabolic_vertex` gives the sub-sample position of local maxima: the vertex of
  the parabola through the three samples around each (fractional sample index).
* :func:`split_vehicles` cuts a sequence of axles into vehicles at gaps longer than a
  plausible axle spacing.
* :func:`channel_data` is a record's readings of some channels, (n_t, k): those of
  :meth:`bwim.Record.channels` without making a new record.

Arrays are 1-D in samples unless stated; times in s, distances in m.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.ndimage import median_filter

from bwim.records import Record
from bwim.sensors import Sensor

__all__ = ["channel_data", "parabolic_vertex", "remove_baseline", "robust_sigma",
           "split_vehicles"]

#: Normalised MAD: 1 / Φ⁻¹(3/4), so that robust_sigma of Gaussian noise is its σ.
MAD_TO_SIGMA = 1.482602218505602


def robust_sigma(values: np.ndarray) -> float:
    """1.4826 × median |v − median v|: the noise standard deviation, robust to pulses."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return 0.0
    return float(MAD_TO_SIGMA * np.median(np.abs(v - np.median(v))))


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
