"""The calibration runs' scale factors over the day: a local-linear smoother of the
factors against clock time, its cross-validated bandwidth, and each run's robust
departure from the others' trend.

Contract
--------
* Times are clock times in s (``record.clock_seconds()``); factors are dimensionless
  (the bridge's strain-to-load ratio of a run relative to the kept runs' mean,
  docs/theory.md §14).
* :func:`local_linear` is local-linear regression with a Gaussian kernel (Fan & Gijbels
  1996, *Local Polynomial Modelling*, §3.2): a straight line passes unchanged, only
  curvature and scatter are smoothed, and the ends carry no one-sided bias.
* :class:`ScaleTrend` is that smoother at the runs' distinct times (the knots), piecewise
  linear between them and constant before the first and after the last (no extrapolated
  drift).  Its default bandwidth is :func:`cv_bandwidth`'s, one of
  :data:`CV_BANDWIDTHS` × the median spacing of the runs' times.
* :func:`robust_departures` is each run's relative departure ``f_i / trend_i(t_i) − 1``
  from the trend of the *other* runs, with bisquare robustness weights (Cleveland 1979),
  the statistic of :class:`~bwim.wim.outliers.OutlierRule`'s factor test.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bwim.errors import InputError, require_finite

__all__ = ["CV_BANDWIDTHS", "ScaleTrend", "cv_bandwidth", "local_linear",
           "robust_departures"]

#: Candidate bandwidths of the :class:`ScaleTrend`, in median spacings of the runs' times.
CV_BANDWIDTHS = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class ScaleTrend:
    """The calibration runs' scale factors as a function of clock time.

    ``trend(t)`` is piecewise linear between the knots and constant before the first and
    after the last (no extrapolated drift); :meth:`covers` says whether ``t`` lies in the
    calibrated span.

    Attributes
    ----------
    time : ndarray, shape (n,)
        Knots: the distinct clock times of the kept runs, s, ascending.
    factor : ndarray, shape (n,)
        Smoothed factor at each knot.
    raw : ndarray, shape (n,)
        The runs' factors at each knot (mean of runs at the same time).
    bandwidth : float
        Standard deviation of the Gaussian weights of the local-linear smoother, s (0: the
        knots interpolate the raw factors).
    """

    time: np.ndarray
    factor: np.ndarray
    raw: np.ndarray
    bandwidth: float

    @classmethod
    def fit(cls, time: Any, factor: Any, *, bandwidth: float | None = None,
            candidates: Any = None) -> ScaleTrend:
        """The trend of ``factor`` (n_runs,) over clock ``time`` (n_runs,), s.

        At each knot ``t_j`` the smoothed factor is the intercept of the straight line
        fitted to all runs with weights ``exp(−½ ((t_i − t_j) / bandwidth)²)`` (local-linear
        regression: a linear drift passes unchanged, only curvature and run-to-run scatter
        are smoothed, and the ends carry no one-sided bias).  Default bandwidth: the one of
        ``CV_BANDWIDTHS`` × the median spacing of the runs' times that predicts each
        run's factor best from the others (leave-one-out cross-validation): little
        smoothing when the factors scatter little about a smooth drift, more when the
        truck's own dynamics scatter them (the bandwidth rules are compared by
        ``benchmarks/bench_multirun.py``, the trend's error against the true drift).
        ``candidates`` (s) replaces those candidates by absolute bandwidths (for many
        noisy points, e.g. the traffic's own reference vehicles, whose spacing in time
        says nothing of how fast the factor may change).
        """
        t = np.array(time, dtype=float, ndmin=1)
        f = np.array(factor, dtype=float, ndmin=1)
        if t.ndim != 1 or t.shape != f.shape or t.size == 0:
            raise InputError("time and factor must be 1-D arrays of the same, non-zero length")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
            raise InputError("time and factor must be finite")
        knots, inverse, counts = np.unique(t, return_inverse=True, return_counts=True)
        raw = np.bincount(inverse, weights=f) / counts
        if bandwidth is None:
            bw = cv_bandwidth(t, f, candidates=candidates)
        else:
            bw = require_finite("bandwidth", bandwidth)
            if bw < 0:
                raise InputError(f"bandwidth must be >= 0 s, got {bw:g}")
        if bw == 0.0 or knots.size < 3:
            smooth = raw.copy()
        else:
            smooth = local_linear(knots, raw, counts.astype(float), knots, bw)
        return cls(time=knots, factor=smooth, raw=raw, bandwidth=bw)

    @property
    def span(self) -> tuple[float, float]:
        """First and last calibration time, s."""
        return float(self.time[0]), float(self.time[-1])

    def __call__(self, t: Any) -> Any:
        """The factor at clock time(s) ``t``, s (constant outside the span)."""
        out = np.interp(np.asarray(t, dtype=float), self.time, self.factor)
        return float(out) if np.ndim(out) == 0 else out

    def covers(self, t: float) -> bool:
        """Whether clock time ``t`` lies within the calibrated span."""
        lo, hi = self.span
        return bool(lo <= float(t) <= hi)


def cv_bandwidth(t: np.ndarray, f: np.ndarray, *, candidates: Any = None) -> float:
    """Leave-one-out cross-validated bandwidth of :func:`local_linear` for factors ``f`` at
    times ``t`` (1-D, same length), s: the candidate of :data:`CV_BANDWIDTHS` × the median
    spacing of the distinct times (or of ``candidates``, s, when given) with the least
    squared prediction error (the smallest on a tie); 0 if there are fewer than 4
    distinct times."""
    knots = np.unique(t)
    if knots.size < 4:
        return 0.0
    spacing = float(np.median(np.diff(knots)))
    grid = ([m * spacing for m in CV_BANDWIDTHS] if candidates is None
            else [require_finite("bandwidth candidate", c) for c in candidates])
    best, best_err = 0.0, np.inf
    for bw in grid:
        err = 0.0
        for i in range(f.size):
            w = np.ones(f.size)
            w[i] = 0.0
            err += (f[i] - local_linear(t, f, w, t[i:i + 1], bw)[0]) ** 2
        if err < best_err * (1 - 1e-9):
            best, best_err = bw, err
    return best


def local_linear(t: np.ndarray, f: np.ndarray, w: np.ndarray, at: np.ndarray,
                 bw: float) -> np.ndarray:
    """Local-linear regression of ``f(t)`` (prior weights ``w``, all 1-D of one length) at
    the times ``at``, Gaussian kernel of standard deviation ``bw`` > 0 (s); the weighted
    mean where a line is not determined.  Shape of ``at``."""
    d = (t[None, :] - at[:, None]) / bw  # row j: distances from at[j]
    k = w[None, :] * np.exp(-0.5 * d**2)
    s0, s1, s2 = k.sum(1), (k * d).sum(1), (k * d**2).sum(1)
    b0, b1 = (k * f).sum(1), (k * d * f).sum(1)
    det = s0 * s2 - s1**2
    ok = det > 1e-12 * s0 * s2
    mean = b0 / np.where(s0 > 0, s0, 1.0)
    return np.where(ok, (s2 * b0 - s1 * b1) / np.where(ok, det, 1.0), mean)


def robust_departures(t: np.ndarray, f: np.ndarray, bw: float | None) -> np.ndarray:
    """Relative departure ``f_i / trend_i(t_i) − 1`` of each run from the local-linear
    trend of the *other* runs (leave one out), with bisquare robustness weights
    (Cleveland 1979) so that one outlying factor does not drag its neighbours' trend.

    ``bw`` (s) defaults to two median spacings of the distinct times; with fewer than 3
    distinct times (or ``bw`` = 0) the trend is the others' median.
    """
    knots = np.unique(t)
    if bw is None:
        bw = 2.0 * float(np.median(np.diff(knots))) if knots.size > 1 else 0.0
    n = f.size
    if bw <= 0 or knots.size < 3:
        return np.array([f[i] / np.median(np.delete(f, i)) - 1.0 for i in range(n)])
    w = np.ones(n)
    dev = np.zeros(n)
    for _ in range(4):
        for i in range(n):
            wi = w.copy()
            wi[i] = 0.0
            dev[i] = f[i] / local_linear(t, f, wi, t[i:i + 1], bw)[0] - 1.0
        mad = float(np.median(np.abs(dev)))
        if mad == 0:
            break
        u = dev / (6.0 * mad)
        w = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
    return dev
