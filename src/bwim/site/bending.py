"""What a lane's axle detectors read of the span's bending: telling a vehicle of that lane
from a trace of a vehicle elsewhere.

A slab's strain-type axle detector reads the axles that cross it as sharp peaks (about a
metre of travel wide) on the slab's global bending, which every vehicle on the span
causes.  A truck in another lane bends the span under a pair of detectors without
crossing it: detection by peaks can read those slow humps, paired across the two
detectors in the wrong order, as a slow vehicle of the pair's own lane.  The gauges read
the same bending, so the calibration runs (the truck in its own lane, nothing over the
other pairs) teach each other pair how much of its reading is bending.

Contract
--------
* :func:`learn_bending` fits, for each detector of a pair, the combination of the gauges
  that reproduces its readings in the calibration runs: robust least squares (Huber
  weights at :data:`HUBER` robust σ, :data:`IRLS` reweightings; samples with a vehicle
  over the pair are its outliers) of the detector on the gauges, each run's mean and
  slope removed, with the ridge :data:`bwim.detect.response.GAUGE_RIDGE` relative to the
  mean diagonal of the normal equations.  Units: detector reading per gauge reading.
* :meth:`DetectorBending.left_share` is, over a vehicle's time on the span (widened by
  :data:`MARGIN` s each side), the largest reading left once the bending (scaled by a
  free factor), an offset and a slope are taken out, over the largest left once only the
  offset and slope are: about 1 for axles crossing the detectors, far below for a
  reading that is bending alone.  The larger of the pair's two detectors counts.
* :meth:`DetectorBending.is_trace`: the share is below :data:`TRACE_SHARE` (most of the
  largest reading is the span's bending): the pair's "vehicle" is a trace of a vehicle
  in another lane, not one of its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.detect.response import GAUGE_RIDGE
from bwim.detect.signals import channel_data, channel_rows, robust_sigma
from bwim.errors import InputError
from bwim.records import Record

__all__ = ["HUBER", "IRLS", "MARGIN", "TRACE_SHARE", "DetectorBending", "learn_bending"]

#: Huber's constant, robust σ (95 % efficiency on normal residuals).
HUBER = 1.345
#: Reweightings of the robust fit.
IRLS = 5
#: s added before and after a vehicle's time on the span for :meth:`left_share`.
MARGIN = 0.3
#: Below this share of its largest reading left once the bending is out, a pair's vehicle
#: is a trace of a vehicle elsewhere (most of what it read is the span's bending).
TRACE_SHARE = 0.5


def _trend_basis(t: np.ndarray) -> np.ndarray:
    """An orthonormal basis (n_t, 2) of the offsets and slopes in ``t``."""
    tc = t - t.mean()
    return np.linalg.qr(np.column_stack([np.ones_like(tc), tc]))[0]


def _detrended(q: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``a`` (n_t, k) less its least-squares offset and slope in the times whose
    :func:`_trend_basis` is ``q``."""
    return a - q @ (q.T @ a)


@dataclass(frozen=True, kw_only=True, eq=False)
class DetectorBending:
    """A detector pair's reading of the span's bending as a combination of the gauges.

    Attributes
    ----------
    channels : (str, str)
        The pair's detector channels.
    gauges : tuple of str
        The gauge channels combined.
    weights : ndarray, shape (2, n_gauges)
        Each detector's combination (reading units per gauge unit).
    """

    channels: tuple[str, str]
    gauges: tuple[str, ...]
    weights: np.ndarray

    def left_share(self, record: Record, window: tuple[float, float]) -> float:
        """The share of the pair's largest reading over ``window`` (record times, s)
        left once the bending is out (see the module docstring); NaN when the window
        holds fewer than 8 samples or the detectors read nothing."""
        t = record.time
        m = (t >= window[0] - MARGIN) & (t <= window[1] + MARGIN)
        if int(m.sum()) < 8:
            return float("nan")
        q = _trend_basis(t[m])
        # channel_data(record, ...)[m] as one gather (the same C-ordered table)
        rows = np.flatnonzero(m)
        y = _detrended(q, channel_rows(record, self.channels, rows))
        g = _detrended(q, channel_rows(record, self.gauges, rows))
        share = 0.0
        for c in range(2):
            bend = g @ self.weights[c]
            norm = float(bend @ bend)
            left = y[:, c] - (bend * float(bend @ y[:, c]) / norm if norm > 0 else 0.0)
            peak = float(np.abs(y[:, c]).max())
            if peak > 0:
                share = max(share, float(np.abs(left).max()) / peak)
        return share if share > 0 else float("nan")

    def is_trace(self, record: Record, window: tuple[float, float] | None) -> bool:
        """Whether a vehicle the pair found over ``window`` is the span's bending alone
        (:data:`TRACE_SHARE`); False when it cannot be told (no window, no reading)."""
        if window is None:
            return False
        share = self.left_share(record, window)
        return bool(np.isfinite(share) and share < TRACE_SHARE)


def learn_bending(records: Sequence[Record], channels: tuple[str, str],
                  gauges: Sequence[str]) -> DetectorBending:
    """Each detector's bending combination of ``gauges`` from ``records`` (calibration
    runs in which nothing crossed these detectors but now and then; see the module
    docstring)."""
    gauges = tuple(gauges)
    if not records or not gauges:
        raise InputError("learning a detector pair's bending needs runs and gauges")
    ys, gs = [], []
    for rec in records:
        q = _trend_basis(rec.time)
        ys.append(_detrended(q, channel_data(rec, channels).astype(float)))
        gs.append(_detrended(q, channel_data(rec, gauges).astype(float)))
    y, g = np.concatenate(ys), np.concatenate(gs)
    ridge = GAUGE_RIDGE * float(np.mean(np.einsum("ij,ij->j", g, g))) * np.eye(g.shape[1])
    weights = np.zeros((2, g.shape[1]))
    for c in range(2):
        w = np.ones(y.shape[0])
        for _ in range(IRLS):
            gw = g * w[:, None]
            coef = np.linalg.solve(gw.T @ g + ridge, gw.T @ y[:, c])
            r = y[:, c] - g @ coef
            k = HUBER * max(robust_sigma(r), 1e-300)
            w = np.minimum(1.0, k / np.maximum(np.abs(r), 1e-300))
        weights[c] = coef
    return DetectorBending(channels=(channels[0], channels[1]), gauges=gauges,
                           weights=weights)
