"""Influence lines from many calibration runs: per-gauge lines, a lateral model, a scale
factor per run, outlier runs rejected, and the factors' trend over the day.

Contract
--------
* :func:`calibrate_lines` stacks every sample of every run of a calibration truck of known
  static axle loads ``W_i`` (N) into one least-squares problem (the matrix method of
  OBrien, Quilligan & Karoumi 2006, generalised).  Reading of channel ``g`` in run ``r`` at
  sample ``k``::

      ε_rg(t_k) = s_r Σ_i W_i I_g(x_rik; y_r) + c_rg + e_rgk,
      x_rik = v_r (t_k − delay_r) − a_i,
      I_g(x; y) = I0_g(x) + (y − ȳ) I1_g(x)          (lateral="linear"; else I0_g only)

  ``I0_g``/``I1_g`` piecewise linear on a uniform grid, zero at both ends of the support;
  ``s_r`` the run's scale factor (the bridge's strain-to-load ratio drifts with
  temperature), normalised so that the kept runs' factors have mean 1; ``c_rg`` the
  run's baseline offset per channel (an unknown of the fit, eliminated exactly by centring
  each run's rows, Frisch–Waugh–Lovell); ``y_r`` the run's lateral covariate,
  ``passage.lane`` (metres when the gauges' y are known, otherwise the dimensionless
  lateral index detection reports; the unit is the caller's and only enters through
  ``y − ȳ``).
* Positions are in the passages' frame: with detected passages, x = 0 is the first axle
  detector and the support may start at negative x.  Units: x in m, ordinates in reading
  per newton (``I1`` per newton and per unit of the lateral covariate), time in s (the
  records' clock), factors dimensionless.
* The bilinear problem in (lines, factors) is solved by alternating least squares: given
  the factors, the lines are one linear least-squares problem with a light
  second-difference smoothing (:func:`~bwim.wim.influence_line.smoothing_penalty`);
  given the lines, the factors minimise the same misfit (one quadratic
  ``a_r s_r² − 2 b_r s_r`` per run, centred rows, channels alike) subject to
  ``mean(s) = 1`` and, with the lateral model, ``Σ_r s_r (y_r − ȳ) = 0`` — closed form by
  Lagrange multipliers.  The second constraint removes a near-degeneracy: a factor linear
  in ``y`` is, to first order, the same as a lateral line ``I1 ∝ I0``; it is given to the
  line.  Each half-step minimises the penalised misfit over its block, so it never rises;
  iteration stops when no factor changes by more than ``tol`` (a few iterations: the
  coupling between lines and factors is weak).
* Outlier runs are removed one at a time (the worst first) and the rest recalibrated,
  until none is left: see :class:`OutlierRule`.  Runs flagged upstream (e.g. multiple
  presence) are rejected before fitting.
* :class:`ScaleTrend` is the kept runs' factors against the runs' clock time
  (``record.clock_seconds()``): a local-linear Gaussian smoother at the runs' times (bandwidth by
  cross-validation), piecewise linear between them, constant beyond the first and last.
* The calibration keeps what weighing needs to combine the channels and judge a fit: the
  residual covariance between channels, the channels' noise (samples before the truck
  arrives) and the runs' misfits.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from bwim.errors import InputError, NumericalError, require_finite, require_positive
from bwim.records import Passage, Record, record_list
from bwim.sensors import SensorKind
from bwim.wim.influence_line import (
    DEFAULT_SMOOTHING,
    Channel,
    InfluenceLine,
    hat_design,
    read_channels,
    resolve_channels,
    smoothing_penalty,
    static_axle_loads,
)

__all__ = [
    "CV_BANDWIDTHS",
    "STRUCTURAL_KINDS",
    "MultiRunCalibration",
    "OutlierRule",
    "RunFit",
    "ScaleTrend",
    "calibrate_lines",
    "structural_sensors",
]

#: Sensor kinds that read the structure (axle detectors and any other kind are skipped).
STRUCTURAL_KINDS = tuple(k for k in SensorKind if k.is_structural)


# --- the factors' trend -------------------------------------------------------------------

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
    def fit(cls, time: Any, factor: Any, *, bandwidth: float | None = None) -> ScaleTrend:
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
            bw = _cv_bandwidth(t, f)
        else:
            bw = require_finite("bandwidth", bandwidth)
            if bw < 0:
                raise InputError(f"bandwidth must be >= 0 s, got {bw:g}")
        if bw == 0.0 or knots.size < 3:
            smooth = raw.copy()
        else:
            smooth = _local_linear(knots, raw, counts.astype(float), knots, bw)
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


#: Candidate bandwidths of the :class:`ScaleTrend`, in median spacings of the runs' times.
CV_BANDWIDTHS = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0)


def _cv_bandwidth(t: np.ndarray, f: np.ndarray) -> float:
    """Leave-one-out cross-validated bandwidth of the local-linear smoother, s (0 if there
    are fewer than 4 distinct times)."""
    knots = np.unique(t)
    if knots.size < 4:
        return 0.0
    spacing = float(np.median(np.diff(knots)))
    best, best_err = 0.0, np.inf
    for mult in CV_BANDWIDTHS:
        bw = mult * spacing
        err = 0.0
        for i in range(f.size):
            w = np.ones(f.size)
            w[i] = 0.0
            err += (f[i] - _local_linear(t, f, w, t[i:i + 1], bw)[0]) ** 2
        if err < best_err * (1 - 1e-9):
            best, best_err = bw, err
    return best


def _local_linear(t: np.ndarray, f: np.ndarray, w: np.ndarray, at: np.ndarray,
                  bw: float) -> np.ndarray:
    """Local-linear regression of ``f(t)`` (prior weights ``w``) at ``at``, Gaussian kernel
    of standard deviation ``bw``; the weighted mean where a line is not determined."""
    d = (t[None, :] - at[:, None]) / bw  # row j: distances from at[j]
    k = w[None, :] * np.exp(-0.5 * d**2)
    s0, s1, s2 = k.sum(1), (k * d).sum(1), (k * d**2).sum(1)
    b0, b1 = (k * f).sum(1), (k * d * f).sum(1)
    det = s0 * s2 - s1**2
    ok = det > 1e-12 * s0 * s2
    mean = b0 / np.where(s0 > 0, s0, 1.0)
    return np.where(ok, (s2 * b0 - s1 * b1) / np.where(ok, det, 1.0), mean)


def _robust_departures(t: np.ndarray, f: np.ndarray, bw: float | None) -> np.ndarray:
    """Relative departure ``f_i / trend_i(t_i) − 1`` of each run from the local-linear
    trend of the *other* runs (leave one out), with bisquare robustness weights
    (Cleveland 1979) so that one outlying factor does not drag its neighbours' trend."""
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
            dev[i] = f[i] / _local_linear(t, f, wi, t[i:i + 1], bw)[0] - 1.0
        mad = float(np.median(np.abs(dev)))
        if mad == 0:
            break
        u = dev / (6.0 * mad)
        w = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
    return dev


# --- results ------------------------------------------------------------------------------

@dataclass(frozen=True, kw_only=True)
class OutlierRule:
    """When a calibration run is rejected (the worst first, then recalibrate).

    Robust statistics over the kept runs: median and ``1.4826 × MAD`` (median absolute
    deviation), the standard deviation of normal data.

    Attributes
    ----------
    misfit : float
        Reject a run whose misfit (:attr:`RunFit.misfit`) exceeds the median by more than
        ``misfit`` robust standard deviations ...
    misfit_floor : float
        ... and is more than ``misfit_floor`` × the median (so that very uniform runs do
        not reject good ones).  A second vehicle on the bridge or a wrong passage shows
        here.
    scale : float
        Reject a run whose factor departs from the trend of the other runs' factors over
        clock time (local-linear as :class:`ScaleTrend`, bandwidth ``trend_bandwidth`` or
        two median spacings of the runs' times, bisquare robustness weights) by more than
        ``scale`` robust standard deviations of those departures ...
    scale_floor : float
        ... and by more than this relative amount.  A truck loaded differently, a second
        vehicle or a wrong speed shows here.
    reject_flags : tuple of str
        Runs carrying any of these upstream flags are rejected before fitting.
    min_runs : int
        Never keep fewer runs than this.
    """

    misfit: float = 5.0
    misfit_floor: float = 1.5
    scale: float = 4.0
    scale_floor: float = 0.03
    reject_flags: tuple[str, ...] = ("multiple_presence",)
    min_runs: int = 3

    def __post_init__(self) -> None:
        for name in ("misfit", "misfit_floor", "scale"):
            require_positive(f"OutlierRule.{name}", getattr(self, name))
        if require_finite("OutlierRule.scale_floor", self.scale_floor) < 0:
            raise InputError("OutlierRule.scale_floor must be >= 0")
        object.__setattr__(self, "reject_flags", tuple(str(f) for f in self.reject_flags))
        if int(self.min_runs) < 1:
            raise InputError(f"OutlierRule.min_runs must be >= 1, got {self.min_runs!r}")


@dataclass(frozen=True, kw_only=True, eq=False)
class RunFit:
    """One calibration run against the final lines.

    Attributes
    ----------
    index : int
        Position in the records given to :func:`calibrate_lines`.
    time : float
        Clock time of the run, ``record.clock_seconds()``, s.
    speed, lateral : float
        The passage's speed (m/s) and lateral covariate (``lane``).
    scale : float
        The run's factor (kept runs: the calibrated one; rejected runs: the best factor
        against the final lines; nan if the run has no axle on the final support).
    residual : float
        Relative residual ‖ε − c − s G I‖ / ‖ε − c‖ of the run over all its samples and
        channels, against the final lines (nan as above).
    misfit : float
        RMS over samples and channels of the residual divided by each channel's
        :attr:`MultiRunCalibration.channel_std` (≈ 1 for a typical kept run).
    offsets : ndarray, shape (n_channels,)
        Fitted baseline offset of each channel.
    rejected : bool
    reason : str
        Why the run was rejected ("" when kept).
    """

    index: int
    time: float
    speed: float
    lateral: float
    scale: float
    residual: float
    misfit: float
    offsets: np.ndarray
    rejected: bool = False
    reason: str = ""


@dataclass(frozen=True, kw_only=True, eq=False)
class MultiRunCalibration:
    """Influence lines calibrated from many runs (:func:`calibrate_lines`).

    Attributes
    ----------
    line : InfluenceLine
        ``I0``: one column per channel, at the mean lateral covariate of the kept runs
        (``line.lane``); ``line.residual`` is the overall relative residual.
    lateral_slope : ndarray, shape (n_x, n_channels) or None
        ``I1`` (reading per newton per unit of lateral covariate) on ``line.x``; None
        without the lateral model.
    lateral_range : (float, float)
        Smallest and largest lateral covariate of the kept runs.
    runs : tuple of RunFit
        Every run given, kept or rejected, in the order given.
    channel_std : ndarray, shape (n_channels,)
        Standard deviation of the fit's residual per channel (reading units): noise,
        dynamics and model mismatch together.
    channel_covariance : ndarray, shape (n_channels, n_channels)
        Covariance of the residuals between channels (same samples).
    channel_noise : ndarray, shape (n_channels,)
        Standard deviation of each channel before the first axle reaches the support
        (the bridge at rest: gauge and logger noise), pooled over the kept runs; zeros if
        the records have no such samples.
    truck_weight : float
        The calibration truck's static weight, N.
    misfit_median : float
        Median misfit of the kept runs (≈ 1); a weighing's misfit is compared with a
        multiple of it (:class:`~bwim.wim.weigh.Limits`).
    sum_misfit_median : float
        The same for the sum of the channels (residual of the summed readings in units of
        its standard deviation ``sqrt(1ᵀ C 1)``): the reference of a weighing made with
        the gauges summed (``combine="sum"``), which per-gauge misfits would overstate
        outside the calibrated lateral range.
    scale_trend : ScaleTrend or None
        The factors over clock time (None with ``per_run_scale=False``).
    time_span : (float, float)
        First and last clock time of the kept runs, s.
    nit : int
        Alternating iterations of the final fit.
    success : bool
        Whether the alternation converged (always True without per-run factors).
    message : str
    """

    line: InfluenceLine
    lateral_slope: np.ndarray | None
    lateral_range: tuple[float, float]
    runs: tuple[RunFit, ...]
    channel_std: np.ndarray
    channel_covariance: np.ndarray
    channel_noise: np.ndarray
    truck_weight: float
    misfit_median: float
    sum_misfit_median: float
    scale_trend: ScaleTrend | None
    time_span: tuple[float, float]
    nit: int
    success: bool
    message: str

    @property
    def channels(self) -> tuple[Channel, ...]:
        return self.line.channels

    @property
    def lateral_center(self) -> float:
        """ȳ: the lateral covariate the line ``I0`` applies to."""
        return self.line.lane

    @property
    def support(self) -> tuple[float, float]:
        return self.line.support

    @property
    def kept(self) -> tuple[int, ...]:
        """Indices of the runs the lines were fitted to."""
        return tuple(r.index for r in self.runs if not r.rejected)

    @property
    def rejected(self) -> tuple[RunFit, ...]:
        return tuple(r for r in self.runs if r.rejected)

    @property
    def scale_factors(self) -> np.ndarray:
        """The kept runs' factors (mean 1 with per-run factors, else all 1)."""
        return np.array([r.scale for r in self.runs if not r.rejected])

    def error_covariance(self, weight: float | None = None) -> np.ndarray:
        """Expected covariance of a vehicle's residual between channels, (n_c, n_c).

        The calibration residual is noise (``channel_noise``, independent between
        channels) plus dynamics and mismatch, which grow with the load, though less than
        in proportion: lighter vehicles bounce relatively more (a higher dynamic load
        coefficient), and the dynamic part's variance is taken proportional to the weight
        (its amplitude to √weight).  For ``ρ = weight / truck_weight``,
        ``C(ρ) = N + ρ (C − N)`` for ``ρ ≤ 1`` (a positive combination of ``C`` and
        ``N``) and ``ρ C`` above; ``weight=None`` gives ``C``, the calibration's
        ``channel_covariance``.  (``benchmarks/bench_multirun.py`` compares ρ with ρ² by
        the misfits of light and heavy trucks.)
        """
        C = self.channel_covariance
        if weight is None:
            return C
        rho = max(require_finite("weight", weight) / self.truck_weight, 0.0)
        if rho >= 1.0:
            return rho * C
        N = np.diag(np.minimum(self.channel_noise**2, np.diag(C)))
        return N + rho * (C - N)

    def ordinates_at(self, lateral: float | None = None) -> np.ndarray:
        """``I0 + (y − ȳ) I1`` on ``line.x`` at lateral covariate ``y`` (default ȳ), shape
        (n_x, n_channels)."""
        if lateral is None or self.lateral_slope is None:
            return self.line.ordinates
        y = require_finite("lateral", lateral)
        return self.line.ordinates + (y - self.lateral_center) * self.lateral_slope

    def line_at(self, lateral: float | None = None) -> InfluenceLine:
        """The lines at lateral covariate ``lateral`` as an :class:`InfluenceLine` (usable
        with :func:`~bwim.wim.weigh_static`)."""
        y = self.lateral_center if lateral is None else require_finite("lateral", lateral)
        return InfluenceLine(x=self.line.x, ordinates=self.ordinates_at(y),
                             channels=self.line.channels, lane=y,
                             track_width=self.line.track_width, source=self.line.source,
                             residual=self.line.residual)


# --- input --------------------------------------------------------------------------------

def structural_sensors(record: Record) -> tuple:
    """The sensors of ``record`` that read the structure (strain, deflection), in order."""
    return tuple(s for s in record.sensors if s.kind in STRUCTURAL_KINDS)


def _runs(records, passages) -> tuple[list[Record], list[Passage]]:
    recs = record_list(records, needs="calibration needs at least one run")
    if passages is None:
        for k, r in enumerate(recs):
            if len(r.passages) != 1:
                raise InputError(
                    f"records[{k}] has {len(r.passages)} passages; give passages= (one per "
                    "record: the calibration truck's detected passage)")
        return recs, [r.passage for r in recs]
    if isinstance(passages, Passage):
        passages = [passages]
    pas = list(passages)
    if len(pas) != len(recs):
        raise InputError(f"passages needs one Passage per record ({len(recs)}), got "
                         f"{len(pas)}")
    for k, p in enumerate(pas):
        if not isinstance(p, Passage):
            raise InputError(f"passages[{k}] is a {type(p).__name__}, not a bwim Passage")
    return recs, pas


def _run_flags(run_flags, n: int) -> list[tuple[str, ...]]:
    if run_flags is None:
        return [()] * n
    flags = list(run_flags)
    if len(flags) != n:
        raise InputError(f"run_flags needs one entry per record ({n}), got {len(flags)}")
    out = []
    for f in flags:
        out.append((f,) if isinstance(f, str) else tuple(str(x) for x in (f or ())))
    return out


# --- the stacked least squares ------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Grid:
    x0: float
    h: float
    n: int  # intervals; n − 1 interior ordinates

    @property
    def x(self) -> np.ndarray:
        return self.x0 + self.h * np.arange(self.n + 1)


@dataclass(frozen=True, kw_only=True, eq=False)
class _RunData:
    """One run's centred normal-equation pieces on a grid (offsets eliminated)."""

    n_t: int
    gbar: np.ndarray  # (m,) mean row of G
    ebar: np.ndarray  # (n_c,) mean reading
    N: np.ndarray  # (m, m) centred GᵀG
    R: np.ndarray  # (m, n_c) centred Gᵀε
    EE: np.ndarray  # (n_c, n_c) centred εᵀε
    on: bool  # any axle on the support


def _run_data(E: np.ndarray, P: np.ndarray, loads: np.ndarray, grid: _Grid) -> _RunData:
    G = hat_design(P, loads, grid.x0, grid.h, grid.n)
    n_t = E.shape[0]
    gbar = np.asarray(G.sum(axis=0)).ravel() / n_t
    ebar = E.mean(axis=0)
    Ec = E - ebar
    N = (G.T @ G).toarray() - n_t * np.outer(gbar, gbar)
    R = np.asarray(G.T @ E) - n_t * np.outer(gbar, ebar)
    return _RunData(n_t=n_t, gbar=gbar, ebar=ebar, N=N, R=R, EE=Ec.T @ Ec, on=G.nnz > 0)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Fit:
    theta0: np.ndarray  # (m, n_c)
    theta1: np.ndarray | None
    scales: np.ndarray  # (n_runs,)
    nit: int
    success: bool
    message: str


def _solve_lines(data: list[_RunData], s: np.ndarray, dy: np.ndarray, lateral: bool,
                 penalty: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    m = data[0].N.shape[0]
    A0 = sum(si**2 * d.N for si, d in zip(s, data, strict=True))
    b0 = sum(si * d.R for si, d in zip(s, data, strict=True))
    if not lateral:
        K, b = A0.copy(), b0
        if penalty is not None:
            K += float(np.mean(np.diag(A0))) * penalty
    else:
        A1 = sum(si**2 * y * d.N for si, y, d in zip(s, dy, data, strict=True))
        A2 = sum(si**2 * y**2 * d.N for si, y, d in zip(s, dy, data, strict=True))
        b1 = sum(si * y * d.R for si, y, d in zip(s, dy, data, strict=True))
        K = np.block([[A0, A1], [A1, A2]])
        if penalty is not None:
            K[:m, :m] += float(np.mean(np.diag(A0))) * penalty
            K[m:, m:] += float(np.mean(np.diag(A2))) * penalty
        b = np.vstack([b0, b1])
    try:
        theta = scipy.linalg.solve(K, b, assume_a="pos")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        raise NumericalError(
            f"the influence-line ordinates are not determined by the runs ({K.shape[0]} "
            "unknowns per channel): use a larger spacing or smoothing > 0") from None
    if not lateral:
        return theta, None
    return theta[:m], theta[m:]


def _scale_terms(d: _RunData, T: np.ndarray) -> tuple[float, float]:
    """``a = ‖G T‖²`` and ``b = ⟨G T, ε⟩`` (centred, channels alike) of a run: its misfit
    is ``a s² − 2 b s + const``."""
    if not d.on:
        return 0.0, 0.0
    return float(np.sum(T * (d.N @ T))), float(np.sum(T * d.R))


def _run_scale(d: _RunData, T: np.ndarray) -> float:
    a, b = _scale_terms(d, T)
    return b / a if a > 0 else float("nan")


def _factor_step(a: np.ndarray, b: np.ndarray, dy: np.ndarray | None) -> np.ndarray:
    """Factors minimising ``Σ_r a_r s_r² − 2 b_r s_r`` subject to ``mean(s) = 1`` and, with
    the lateral model, ``Σ_r s_r dy_r = 0`` (Lagrange multipliers, closed form)."""
    C = np.ones((1, a.size)) if dy is None else np.vstack([np.ones(a.size), dy])
    target = np.zeros(C.shape[0])
    target[0] = a.size
    Ci = C / a  # C A⁻¹
    lam = np.linalg.solve(Ci @ C.T, Ci @ b - target)
    return (b - C.T @ lam) / a


def _fit(data: list[_RunData], dy: np.ndarray, *, lateral: bool, per_run_scale: bool,
         penalty: np.ndarray | None, tol: float, max_iter: int) -> _Fit:
    s = np.ones(len(data))
    theta0, theta1 = _solve_lines(data, s, dy, lateral, penalty)
    if not per_run_scale:
        return _Fit(theta0=theta0, theta1=theta1, scales=s, nit=1, success=True,
                    message="one linear least-squares solve (no per-run factors)")
    change = np.inf
    for it in range(1, max_iter + 1):
        ab = np.array([_scale_terms(d, theta0 if theta1 is None else theta0 + y * theta1)
                       for d, y in zip(data, dy, strict=True)])
        if not np.all(ab[:, 0] > 0):
            raise NumericalError("a run of the fit has no axle on the lines' support")
        new = _factor_step(ab[:, 0], ab[:, 1], dy if lateral else None)
        if not np.all(new > 0):
            bad = int(np.flatnonzero(~(new > 0))[0])
            raise NumericalError(
                f"run {bad} of the fit gets a non-positive scale factor: its readings do "
                "not follow the lines (wrong passage or loads?)")
        change = float(np.max(np.abs(new - s)))
        s = new
        theta0, theta1 = _solve_lines(data, s, dy, lateral, penalty)
        if change < tol:
            return _Fit(theta0=theta0, theta1=theta1, scales=s, nit=it, success=True,
                        message=f"factors converged (largest change {change:.1e} < {tol:g})")
    return _Fit(theta0=theta0, theta1=theta1, scales=s, nit=max_iter, success=False,
                message=f"factors not converged after {max_iter} iterations (largest "
                        f"change {change:.1e})")


def _evaluate(d: _RunData, T: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
    """Residual cross-product matrix (n_c, n_c) of a run and its offsets (n_c,)."""
    NT = d.N @ T
    cross = T.T @ d.R
    res = d.EE - s * (cross + cross.T) + s**2 * (T.T @ NT)
    return res, d.ebar - s * (d.gbar @ T)


def _relative(res: np.ndarray, d: _RunData) -> float:
    den = float(np.trace(d.EE))
    return float(np.sqrt(max(float(np.trace(res)), 0.0) / den)) if den > 0 else float("nan")


# --- support ------------------------------------------------------------------------------

def _signal_window(E: np.ndarray, P: np.ndarray, threshold: float,
                   fs: float) -> tuple[float, float] | None:
    """First-axle position where a run's signal becomes significant and last-axle position
    where it stops being so, m (None if it never is).  Each channel, less its median over
    the first samples, is averaged over 30 ms and divided by its noise there; the envelope
    (root-sum-square over channels) is significant above ``threshold`` × its peak and 5 ×
    its level in the first samples."""
    n0 = max(8, E.shape[0] // 20)
    width = max(1, round(0.03 * fs))
    kernel = np.ones(width) / width
    Z = np.stack([np.convolve(c, kernel, mode="same") for c in (E - np.median(E[:n0], 0)).T],
                 axis=1)
    sd = Z[width:n0].std(axis=0) if n0 > width + 2 else np.zeros(E.shape[1])
    floor = max(float(sd.max()), 1e-9 * float(np.abs(Z).max()), np.finfo(float).tiny)
    sd = np.where(sd > 0, sd, floor)  # noise-free channels
    env = np.sqrt(((Z / sd) ** 2).sum(axis=1))
    noise = float(np.sqrt(np.mean(env[width:n0] ** 2))) if n0 > width + 2 else 0.0
    thr = max(threshold * float(env.max()), 5.0 * noise)
    idx = np.flatnonzero(env > thr)
    if idx.size == 0:
        return None
    return float(P[idx[0], 0]), float(P[idx[-1], -1])


def _trimmed(theta0: np.ndarray, grid: _Grid, threshold: float) -> tuple[float, float]:
    """The support of first-pass lines, m: from the peak of their magnitude (root-sum-square
    over channels) outward to where it falls below ``threshold`` × the peak, then on to
    the next local minimum (where the line returns to zero; beyond it a first-pass line
    carries the bridge's free vibration, phase-locked to the axles) or to where it is
    negligible (0.1 % of the peak), plus 2 spacings."""
    mag = np.concatenate([[0.0], np.sqrt((theta0**2).sum(axis=1)), [0.0]])  # on grid.x
    peak = int(np.argmax(mag))
    small = mag < threshold * mag[peak]
    negligible = 1e-3 * mag[peak]

    def walk(step: int) -> int:
        j = peak
        while 0 < j < mag.size - 1 and not small[j]:
            j += step
        while 0 < j < mag.size - 1 and mag[j + step] < mag[j] and mag[j] > negligible:
            j += step
        return j

    x = grid.x
    return (max(x[walk(-1)] - 2 * grid.h, x[0]), min(x[walk(+1)] + 2 * grid.h, x[-1]))


def _grid(x0: float, x1: float, h_req: float) -> _Grid:
    n = max(int(np.ceil((x1 - x0) / h_req - 1e-9)), 2)
    return _Grid(x0=x0, h=(x1 - x0) / n, n=n)


# --- the calibration ----------------------------------------------------------------------

def calibrate_lines(
    records: Sequence[Record] | Record,
    passages: Sequence[Passage] | None,
    axle_loads: Any,
    *,
    channels: Any = "each",
    lateral: str | None = None,
    per_run_scale: bool = True,
    smoothing: float = DEFAULT_SMOOTHING,
    spacing: float | None = None,
    support: tuple[float, float] | None = None,
    outlier: OutlierRule | None = OutlierRule(),
    run_flags: Sequence[Sequence[str] | str] | None = None,
    signal_threshold: float = 0.05,
    trend_bandwidth: float | None = None,
    tol: float = 1e-7,
    max_iter: int = 200,
) -> MultiRunCalibration:
    """Influence lines of every channel from many runs of a truck of known axle loads.

    See the module docstring for the model and the solution.  Runs may differ in speed,
    lateral position and clock time (temperature).

    Parameters
    ----------
    records : sequence of Record
        The calibration runs, one crossing of the truck each, with clock time
        (``record.clock_seconds()`` is when the run was recorded).
    passages : sequence of Passage or None
        One per record (speed, lane = lateral covariate, axle spacings, delay), e.g. from
        detection; None: each record's own single passage.
    axle_loads : sequence of float or vehicle
        The truck's static axle loads, N (or a vehicle with ``static_axle_loads``).
    channels : "each", "sum" or sequence
        ``"each"``: one line per structural sensor (strain or deflection; axle detectors
        are skipped); ``"sum"`` or a sequence: as :func:`~bwim.wim.resolve_channels`.
    lateral : None or "linear"
        ``"linear"``: ordinates linear in the lateral covariate,
        ``I0(x) + (y − ȳ) I1(x)`` (needs runs at different lateral positions).
    per_run_scale : bool
        Fit a scale factor per run (mean 1) and its :class:`ScaleTrend`.
    smoothing : float
        Smoothing length ℓ, m, as ``regularization`` of
        :func:`~bwim.wim.calibrate_influence_line` (``I1`` is smoothed alike).
    spacing : float, optional
        Ordinate spacing, m; default the largest distance a truck moves between samples.
    support : (float, float), optional
        Where the lines may be non-zero, m (passage frame).  Default estimated from the
        data in two passes.  First a generous fit: over where the runs' signals are
        significant (envelope of the channels, each averaged over 30 ms and divided by
        its noise in the first samples, above ``signal_threshold`` × its peak and 5 × its
        level there), widened by that length on each side (within the records).  Then,
        from the peak of the first-pass lines' magnitude (root-sum-square over channels)
        outward to where it falls below ``signal_threshold`` × the peak and on to the
        next local minimum — where the line has returned to zero; beyond it a first
        pass carries the bridge's free vibration, phase-locked to the axles — or to
        0.1 % of the peak, plus 2 spacings; the lines are refitted there.  (Checked
        against the true support by ``benchmarks/bench_multirun.py``.)
    outlier : OutlierRule or None
        How runs are rejected; None keeps every run not flagged upstream (and then no
        factor test is made).
    run_flags : sequence, optional
        Upstream flags of each run (a string or a sequence of strings, e.g.
        ``"multiple_presence"``); runs with one of ``outlier.reject_flags`` (with
        ``outlier=None``, the default rule's) are rejected.
    signal_threshold : float
        See ``support`` (default 5 %).
    trend_bandwidth : float, optional
        Bandwidth of the :class:`ScaleTrend`, s (default chosen by cross-validation, see
        :meth:`ScaleTrend.fit`).
    tol, max_iter
        Convergence of the alternating solution (largest change of a factor).

    Returns
    -------
    MultiRunCalibration
    """
    recs, pas = _runs(records, passages)
    loads = static_axle_loads(axle_loads)
    for k, p in enumerate(pas):
        if p.n_axles != loads.size:
            raise InputError(f"the calibration truck has {loads.size} axles but passages[{k}] "
                             f"has {p.n_axles}")
    if lateral not in (None, "linear"):
        raise InputError(f"lateral must be None or 'linear', got {lateral!r}")
    ell = require_finite("smoothing", smoothing)
    if ell < 0:
        raise InputError(f"smoothing (a length, m) must be >= 0, got {ell:g}")
    thr = require_finite("signal_threshold", signal_threshold)
    if not 0 < thr < 1:
        raise InputError(f"signal_threshold must lie in (0, 1), got {thr:g}")
    tol = require_positive("tol", tol)
    if int(max_iter) < 1:
        raise InputError(f"max_iter must be >= 1, got {max_iter!r}")
    if outlier is not None and not isinstance(outlier, OutlierRule):
        raise InputError(f"outlier must be an OutlierRule or None, got {outlier!r}")
    flags = _run_flags(run_flags, len(recs))

    sens = structural_sensors(recs[0])
    if isinstance(channels, str) and channels == "each":
        chans = resolve_channels(sens, "each")
    else:
        chans = resolve_channels(sens, channels)
    E_all = [read_channels(r, chans) for r in recs]
    P_all = [p.axle_x(r.time) for r, p in zip(recs, pas, strict=True)]
    lanes = np.array([p.lane for p in pas])
    times = np.array([r.clock_seconds() for r in recs])
    if spacing is None:
        h_req = max(p.speed / r.sampling_rate for r, p in zip(recs, pas, strict=True))
    else:
        h_req = require_positive("spacing", spacing)
    if support is not None:
        if not isinstance(support, (tuple, list, np.ndarray)) or len(support) != 2:
            raise InputError(f"support must be (start, end) in m, got {support!r}")
        sx0, sx1 = (require_finite("support", v) for v in support)
        if sx1 <= sx0:
            raise InputError(f"support must be (start, end) with end > start, got {support!r}")
        fixed_grid = _grid(sx0, sx1, h_req)
    else:
        fixed_grid = None

    reasons: dict[int, str] = {}
    reject = set((outlier or OutlierRule()).reject_flags)
    for k, f in enumerate(flags):
        hit = [x for x in f if x in reject]
        if hit:
            reasons[k] = f"flagged upstream: {', '.join(hit)}"
    min_runs = outlier.min_runs if outlier is not None else 1
    penalty_cache: dict[int, np.ndarray] = {}

    def penalty(grid: _Grid) -> np.ndarray | None:
        if ell == 0:
            return None
        if grid.n not in penalty_cache:
            penalty_cache[grid.n] = smoothing_penalty(grid.n - 1, ell, grid.h)
        return penalty_cache[grid.n]

    def fit_on(kept: list[int], grid: _Grid, ybar: float) -> tuple[_Fit, list[_RunData]]:
        data = [_run_data(E_all[k], P_all[k], loads, grid) for k in kept]
        for k, d in zip(kept, data, strict=True):
            if not d.on:
                raise InputError(f"no axle of records[{k}] is on the support {grid.x0:g} … "
                                 f"{grid.x[-1]:g} m")
        return _fit(data, lanes[kept] - ybar, lateral=lateral is not None,
                    per_run_scale=per_run_scale, penalty=penalty(grid), tol=tol,
                    max_iter=int(max_iter)), data

    def calibrate(kept: list[int]) -> tuple[_Fit, list[_RunData], _Grid, float]:
        if lateral is not None and np.ptp(lanes[kept]) <= 0:
            raise InputError("lateral='linear' needs runs at different lateral positions "
                             "(passage.lane); all kept runs are at "
                             f"{lanes[kept][0]:g}")
        ybar = float(lanes[kept].mean())
        if fixed_grid is not None:
            fit, data = fit_on(kept, fixed_grid, ybar)
            return fit, data, fixed_grid, ybar
        windows = [_signal_window(E_all[k], P_all[k], thr, recs[k].sampling_rate)
                   for k in kept]
        if any(w is None for w in windows):
            bad = kept[[w is None for w in windows].index(True)]
            raise InputError(f"records[{bad}] has no significant signal; remove it or give "
                             "support=")
        lo = min(w[0] for w in windows)
        hi = max(w[1] for w in windows)
        if hi <= lo:
            hi = lo + max(h_req * 10, 1.0)
        pad = hi - lo
        cover_lo = min(float(P_all[k][0, 0]) for k in kept)
        cover_hi = max(float(P_all[k][-1, -1]) for k in kept)
        first = _grid(max(lo - pad, cover_lo), min(hi + pad, cover_hi), h_req)
        fit1, _ = fit_on(kept, first, ybar)
        x0, x1 = _trimmed(fit1.theta0, first, thr)
        grid = _grid(x0, x1, h_req)
        fit, data = fit_on(kept, grid, ybar)
        return fit, data, grid, ybar

    kept = [k for k in range(len(recs)) if k not in reasons]
    if len(kept) < 1:
        raise InputError("every calibration run is flagged upstream; nothing to calibrate")
    n_c = len(chans)
    while True:
        fit, data, grid, ybar = calibrate(kept)
        n_par = (grid.n - 1) * (2 if lateral is not None else 1) + len(kept) * (
            2 if per_run_scale else 1)
        res_k = [_evaluate(d, _t(fit, y - ybar), s)[0]
                 for d, y, s in zip(data, lanes[kept], fit.scales, strict=True)]
        cov = sum(res_k) / max(sum(d.n_t for d in data) - n_par, 1)
        var = np.clip(np.diag(cov), np.finfo(float).tiny, None)
        if outlier is None or len(kept) <= min_runs:
            break
        mis = np.array([_misfit(r, var, d.n_t) for r, d in zip(res_k, data, strict=True)])
        worst, why = _worst(kept, mis, fit.scales if per_run_scale else None, times[kept],
                            outlier, trend_bandwidth)
        if worst is None:
            break
        reasons[worst] = why
        kept = [k for k in kept if k != worst]

    # every run against the final lines
    runs = []
    kept_pos = {k: i for i, k in enumerate(kept)}
    total_res = total_ee = 0.0
    sum_var = float(np.sum(cov))  # variance of the summed channels' residual
    sum_misfits = []
    for k in range(len(recs)):
        T = _t(fit, lanes[k] - ybar)
        if k in kept_pos:
            d = data[kept_pos[k]]
            s = float(fit.scales[kept_pos[k]])
        else:
            d = _run_data(E_all[k], P_all[k], loads, grid)
            s = _run_scale(d, T)
        if np.isfinite(s):
            res, offsets = _evaluate(d, T, s)
            rel, mis = _relative(res, d), _misfit(res, var, d.n_t)
            if k in kept_pos:
                total_res += float(np.trace(res))
                total_ee += float(np.trace(d.EE))
                sum_misfits.append(float(np.sqrt(max(float(np.sum(res)), 0.0)
                                                 / (d.n_t * max(sum_var, np.finfo(float).tiny)))))
        else:
            offsets, rel, mis = d.ebar, float("nan"), float("nan")
        runs.append(RunFit(index=k, time=float(times[k]), speed=pas[k].speed,
                           lateral=float(lanes[k]), scale=s, residual=rel, misfit=mis,
                           offsets=offsets, rejected=k in reasons,
                           reason=reasons.get(k, "")))
    # noise: the readings before the first axle reaches the support (bridge at rest)
    noise_ss, noise_n = np.zeros(n_c), 0
    for k in kept:
        lead = int(np.argmax(P_all[k][:, 0] > grid.x0)) if P_all[k][-1, 0] > grid.x0 else 0
        if lead >= 8:
            noise_ss += (lead - 1) * np.var(E_all[k][:lead], axis=0, ddof=1)
            noise_n += lead - 1
    noise = np.sqrt(noise_ss / noise_n) if noise_n else np.zeros(n_c)

    full0 = np.zeros((grid.n + 1, n_c))
    full0[1:-1] = fit.theta0
    slope = None
    if fit.theta1 is not None:
        slope = np.zeros_like(full0)
        slope[1:-1] = fit.theta1
    overall = float(np.sqrt(max(total_res, 0.0) / total_ee)) if total_ee > 0 else float("nan")
    line = InfluenceLine(x=grid.x, ordinates=full0, channels=chans, lane=ybar,
                         track_width=pas[kept[0]].track_width,
                         source="multi-run matrix method", residual=overall)
    trend = None
    if per_run_scale:
        trend = ScaleTrend.fit(times[kept], fit.scales, bandwidth=trend_bandwidth)
    return MultiRunCalibration(
        line=line, lateral_slope=slope,
        lateral_range=(float(lanes[kept].min()), float(lanes[kept].max())),
        runs=tuple(runs), channel_std=np.sqrt(np.diag(cov).clip(0.0)), channel_noise=noise,
        channel_covariance=cov, truck_weight=float(loads.sum()),
        misfit_median=float(np.median([runs[k].misfit for k in kept])),
        sum_misfit_median=float(np.median(sum_misfits)),
        scale_trend=trend, time_span=(float(times[kept].min()), float(times[kept].max())),
        nit=fit.nit, success=fit.success, message=fit.message,
    )


def _misfit(res: np.ndarray, var: np.ndarray, n_t: int) -> float:
    """RMS over samples and channels of a run's residual in units of ``sqrt(var)``."""
    return float(np.sqrt(max(float(np.sum(np.diag(res) / var)), 0.0) / (n_t * var.size)))


def _t(fit: _Fit, dy: float) -> np.ndarray:
    return fit.theta0 if fit.theta1 is None else fit.theta0 + dy * fit.theta1


def _worst(kept: list[int], misfit: np.ndarray, scales: np.ndarray | None,
           times: np.ndarray, rule: OutlierRule, bandwidth: float | None
           ) -> tuple[int | None, str]:
    """The run most beyond the rule's limits, with the reason (None if none is)."""
    med = float(np.median(misfit))
    rsd = 1.4826 * float(np.median(np.abs(misfit - med)))
    limit = max(med + rule.misfit * rsd, rule.misfit_floor * med)
    severity = misfit / limit if limit > 0 else np.zeros_like(misfit)
    why = [f"misfit {m:.3g} > {limit:.3g} (median {med:.3g} + {rule.misfit:g} robust sd "
           f"{rsd:.3g}, and > {rule.misfit_floor:g} x median)" for m in misfit]
    if scales is not None and len(kept) >= 3:
        dev = _robust_departures(times, scales, bandwidth)
        sd = 1.4826 * float(np.median(np.abs(dev)))
        lim = max(rule.scale * sd, rule.scale_floor)
        for i in range(len(kept)):
            sev = abs(dev[i]) / lim
            if sev > severity[i]:
                severity[i] = sev
                why[i] = (f"scale factor {scales[i]:.4g} departs {100 * dev[i]:+.1f} % from "
                          f"the runs' robust trend (limit {100 * lim:.1f} %)")
    i = int(np.argmax(severity))
    if severity[i] <= 1.0:
        return None, ""
    return kept[i], why[i]
