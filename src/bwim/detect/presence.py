"""When each vehicle is on the span, whether two are on it at once, and strain that no
detected vehicle explains.

Contract
--------
* The span is an interval ``(x_start, x_end)`` (m) of the influence-line frame, the frame
  of :class:`~bwim.records.Passage` (axle i at ``x = speed (t − delay) − a_i``): given as a
  length ``L`` (meaning ``(0, L)``), a pair, or an :class:`~bwim.wim.InfluenceLine` (its
  support).  A vehicle's window is ``[delay + x_start / v, delay + (x_end + a_last) / v]``:
  from its first axle entering to its last axle leaving.
* Two vehicles are *present together* when their windows overlap.
* :func:`unexplained_activity` returns the time intervals (s, shape (k, 2)) in which a
  signal (e.g. the sum of the gauges of one section) departs from its quiet level by more
  than ``fraction`` of its largest departure inside the windows and more than ``snr``
  noise standard deviations, outside every window widened by ``margin`` s (its noise,
  :func:`signal_noise`, and the median time step may be given: one signal judged against
  several sets of windows makes them once).  Finite signals go through one compiled kernel
  (:func:`bwim.detect.order_stats.outside_activity`, the same numbers), others through
  numpy.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from bwim.errors import InputError, require_finite, require_positive
from bwim.records import Passage
from bwim.wim import InfluenceLine

from .order_stats import outside_activity
from .signals import MAD_TO_SIGMA, median, robust_sigma

__all__ = ["overlapping", "resolve_span", "signal_noise", "span_windows",
           "unexplained_activity", "windows_overlap"]


def resolve_span(span: float | Sequence[float] | InfluenceLine | None
                 ) -> tuple[float, float] | None:
    """``(x_start, x_end)`` of the span in the influence-line frame, m (None: unknown)."""
    if span is None:
        return None
    if isinstance(span, InfluenceLine):
        return span.support
    if isinstance(span, tuple) and len(span) == 2 and all(
            isinstance(v, float) for v in span):  # a pair of floats: as numpy reads it
        vals = span
    elif np.ndim(span) == 0:
        return 0.0, require_positive("span", span)
    else:
        vals = np.asarray(span, dtype=float).ravel()
    if len(vals) != 2:
        raise InputError(f"span must be a length, a pair (x_start, x_end) or an "
                         f"InfluenceLine, got {span!r}")
    lo, hi = require_finite("span[0]", vals[0]), require_finite("span[1]", vals[1])
    if hi <= lo:
        raise InputError(f"span must have x_start < x_end, got ({lo:g}, {hi:g})")
    return lo, hi


def span_windows(passages: Sequence[Passage], span: tuple[float, float]) -> np.ndarray:
    """Record time at which each vehicle's first axle enters and its last axle leaves the
    span, s, shape (n_vehicles, 2)."""
    lo, hi = span
    out = np.zeros((len(passages), 2))
    for k, p in enumerate(passages):
        out[k] = p.delay + lo / p.speed, p.delay + (hi + p.axle_offsets[-1]) / p.speed
    return out


def windows_overlap(a, b) -> bool:
    """Whether two windows (start, end), s, share some time; False when either is None."""
    return a is not None and b is not None and a[0] < b[1] and b[0] < a[1]


def overlapping(windows: np.ndarray) -> np.ndarray:
    """Whether each window overlaps another one, bool, shape (n,)."""
    w = np.asarray(windows, dtype=float).reshape(-1, 2)
    hit = np.zeros(len(w), dtype=bool)
    for i in range(len(w)):
        for j in range(i + 1, len(w)):
            if windows_overlap(w[i], w[j]):
                hit[i] = hit[j] = True
    return hit


def signal_noise(signal: np.ndarray) -> float:
    """The noise :func:`unexplained_activity` takes of a signal: the robust standard
    deviation of its first difference over √2 (for several calls on one signal, made
    once)."""
    s = np.asarray(signal, dtype=float)
    return robust_sigma(np.diff(s)) / np.sqrt(2.0)


def _outside_activity(t: np.ndarray, s: np.ndarray, w: np.ndarray, margin: float,
                      fraction: float, snr: float, noise: float | None
                      ) -> np.ndarray | None:
    """:func:`unexplained_activity`'s active samples with numpy (None: nothing to
    report); :func:`bwim.detect.order_stats.outside_activity` does it compiled."""
    inside = np.zeros(t.size, dtype=bool)
    for a, b in w:
        inside |= (t >= a - margin) & (t <= b + margin)
    outside = ~inside
    if outside.sum() < 0.1 * t.size or not inside.any():
        return None
    dev = s - median(s[outside])
    if noise is None:
        noise = signal_noise(s)
    limit = max(fraction * np.abs(dev[inside]).max(), snr * noise)
    return outside & (np.abs(dev) > limit)


def unexplained_activity(
    time: np.ndarray,
    signal: np.ndarray,
    windows: np.ndarray,
    *,
    margin: float = 0.05,
    fraction: float = 0.2,
    snr: float = 8.0,
    min_duration: float = 0.03,
    noise: float | None = None,
    step: float | None = None,
) -> np.ndarray:
    """Intervals of activity outside every window, s, shape (k, 2) (k = 0: none).

    The quiet level is the median of the samples outside the windows (at least 10 % of
    the record, else nothing is reported); the noise is the robust standard deviation of
    the first difference over √2 (:func:`signal_noise`; ``noise``: that number, when
    already made).  Activity must last ``min_duration`` s (in samples of the median time
    step: ``step``, when already made).
    """
    t = np.ascontiguousarray(time, dtype=float)
    s = np.ascontiguousarray(signal, dtype=float)
    w = np.ascontiguousarray(windows, dtype=float).reshape(-1, 2)
    status, active = outside_activity(t, s, w, float(margin), float(fraction), float(snr),
                                      MAD_TO_SIGMA, np.nan if noise is None else float(noise))
    if status == 2:  # a reading not finite: numpy's NaN rules
        active = _outside_activity(t, s, w, margin, fraction, snr, noise)
    if status == 0 or active is None or not active.any():
        return np.zeros((0, 2))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], active.astype(int), [0]])))
    runs = edges.reshape(-1, 2)  # [start, stop) sample indices
    dt = median(np.diff(t)) if step is None else step
    keep = (runs[:, 1] - runs[:, 0]) * dt >= min_duration
    runs = runs[keep]
    return np.column_stack([t[runs[:, 0]], t[runs[:, 1] - 1]]) if runs.size else np.zeros((0, 2))
