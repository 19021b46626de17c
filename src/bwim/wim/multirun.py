"""Influence lines from many calibration runs: per-gauge lines, a lateral model, a scale
factor per run, outlier runs rejected, and the factors' trend over the day.

Contract
--------
* :func:`calibrate_lines` stacks every sample of every run of a calibration truck of known
  static axle loads ``W_i`` (N) into one least-squares problem (the matrix method of
  OBrien, Quilligan & Karoumi 2006, generalised; docs/theory.md §14).  Reading of channel
  ``g`` in run ``r`` at sample ``k``::

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
* The calibration is a sequence of named steps; the concepts they use live in their own
  modules:

  1. the inputs checked and every run's readings and axle positions read;
  2. runs flagged upstream (e.g. multiple presence) rejected
     (:func:`~bwim.wim.outliers.upstream_rejections`);
  3. the kept runs fitted (:mod:`bwim.wim.support` estimates where the lines may be
     non-zero, in two passes unless given; :class:`~bwim.wim.stacked_fit.AlternatingLines`
     solves the bilinear problem in lines and factors), and the worst outlier run removed
     (:func:`~bwim.wim.outliers.worst_run`, :class:`OutlierRule`), repeatedly until none
     is left;
  4. every run, kept or rejected, evaluated against the final lines (:class:`RunFit`),
     the channels' noise estimated, and the factors' :class:`ScaleTrend` fitted
     (:mod:`bwim.wim.scale_trend`: local-linear over the runs' clock time,
     ``record.clock_seconds()``, bandwidth by cross-validation).
* The calibration keeps what weighing needs to combine the channels and judge a fit: the
  residual covariance between channels, the channels' noise (samples before the truck
  arrives) and the runs' misfits.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bwim.errors import InputError, require_finite, require_positive
from bwim.optimize import OptimizeResult
from bwim.records import Passage, Record, record_list
from bwim.sensors import SensorKind
from bwim.wim.influence_line import (
    DEFAULT_SMOOTHING,
    Channel,
    InfluenceLine,
    read_channels,
    resolve_channels,
    smoothing_penalty,
    static_axle_loads,
)
from bwim.wim.outliers import (
    DEFAULT_OUTLIER_RULE,
    OutlierRule,
    Rejection,
    run_flag_tuples,
    upstream_rejections,
    worst_run,
)
from bwim.wim.scale_trend import CV_BANDWIDTHS, ScaleTrend
from bwim.wim.stacked_fit import (
    AlternatingLines,
    LinesFit,
    RunData,
    relative_residual,
    run_data,
    run_misfit,
    run_residual,
    run_scale,
)
from bwim.wim.support import (
    Grid,
    generous_grid,
    signal_window,
    trimmed_support,
    uniform_grid,
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


# --- results ------------------------------------------------------------------------------

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
        Why the run was rejected ("" when kept); a factor or misfit it quotes is that of
        the fit that rejected it (the runs kept then), not this RunFit's.
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

    def __repr__(self) -> str:
        why = self.reason if len(self.reason) <= 60 else self.reason[:59] + "…"
        state = f"rejected: {why}" if self.rejected else "used"
        return (f"RunFit({self.index}: {self.speed:.2f} m/s, lateral {self.lateral:.2f}, "
                f"scale {self.scale:.4f}, residual {self.residual:.3g}, {state})")


@dataclass(frozen=True, kw_only=True, eq=False)
class MultiRunCalibration(OptimizeResult):
    """Influence lines calibrated from many runs (:func:`calibrate_lines`), with the
    alternating least squares' outcome in :mod:`scipy.optimize`'s vocabulary.

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
        Clock time of the first kept run's start and of the last one's end, s (a
        vehicle crossing later is weighed ``outside_calibration_time``).
    core_support : (float, float) or None
        With ``support_lobes``, the support without the lobes beyond the line's first
        zeros (m): a record may end (or start) while an axle is still on a lobe, not on
        this part, without being truncated (:func:`bwim.wim.weigh`).  None: the support.
    x : ndarray, shape (n_kept,)
        The kept runs' scale factors, in the order given (mean 1; all 1 without per-run
        factors; as :attr:`scale_factors`): the unknowns of the bilinear problem's
        nonlinear part, the lines being the linear least-squares solution given them.
    fun : float
        The residual sum of squares of the final fit over the kept runs' samples and
        channels, ``Σ_r ‖ε_r − c_r − s_r G_r I‖²`` (reading units², without the
        smoothing term).
    nfev : int
        Linear least-squares solves of the lines over the whole calibration (both support
        passes of every fit, and the refits after each rejection).
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
    core_support: tuple[float, float] | None = None

    def __repr__(self) -> str:
        used = sum(1 for r in self.runs if not r.rejected)
        return (f"MultiRunCalibration({len(self.line.channels)} channels, {used} of "
                f"{len(self.runs)} runs, support {self.support[0]:.2f}–"
                f"{self.support[1]:.2f} m, truck {self.truck_weight / 1e3:.1f} kN, "
                f"success={self.success})")

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

    def error_variance(self, weight: float | None = None) -> np.ndarray:
        """The diagonal of :meth:`error_covariance` (each channel's expected residual
        variance), (n_c,): the same numbers, without the matrix."""
        C = np.diag(self.channel_covariance)
        if weight is None:
            return C.copy()
        rho = max(require_finite("weight", weight) / self.truck_weight, 0.0)
        if rho >= 1.0:
            return rho * C
        N = np.minimum(self.channel_noise**2, C)
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


def structural_sensors(record: Record) -> tuple:
    """The sensors of ``record`` that read the structure (strain, deflection), in order."""
    return tuple(s for s in record.sensors if s.kind in STRUCTURAL_KINDS)


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
    outlier: OutlierRule | None = DEFAULT_OUTLIER_RULE,
    run_flags: Sequence[Sequence[str] | str] | None = None,
    signal_threshold: float = 0.05,
    support_lobes: bool = False,
    trend_bandwidth: float | None = None,
    tol: float = 1e-7,
    max_iter: int = 200,
) -> MultiRunCalibration:
    """Influence lines of every channel from many runs of a truck of known axle loads.

    See the module docstring for the model and the steps.  Runs may differ in speed,
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
    support_lobes : bool
        Keep a lobe of the first-pass lines beyond the zero where the line returns to
        zero, when it rises above ``signal_threshold`` × the peak again (a slab continuous
        over its supports: :func:`~bwim.wim.support.trimmed_support` with
        ``keep_lobes``).  Off by default: the lines then reach further than the span, and
        records that end sooner after the last axle leaves are truncated for them.
    trend_bandwidth : float, optional
        Bandwidth of the :class:`ScaleTrend`, s (default chosen by cross-validation, see
        :meth:`ScaleTrend.fit`).
    tol, max_iter
        Convergence of the alternating solution (largest change of a factor).

    Returns
    -------
    MultiRunCalibration
    """
    runs = _read_runs(records, passages, axle_loads, channels=channels, lateral=lateral,
                      per_run_scale=per_run_scale, smoothing=smoothing, spacing=spacing,
                      support=support, outlier=outlier, run_flags=run_flags,
                      signal_threshold=signal_threshold, support_lobes=support_lobes,
                      trend_bandwidth=trend_bandwidth, tol=tol, max_iter=max_iter)
    reasons = upstream_rejections(runs.flags, runs.outlier or DEFAULT_OUTLIER_RULE)
    final = _reject_outliers(runs, reasons)
    evaluation = _evaluate_runs(runs, final)
    return _result(runs, final, evaluation)


# --- step 1: the inputs -------------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Runs:
    """The checked inputs of :func:`calibrate_lines` and every run's readings."""

    records: list[Record]
    passages: list[Passage]
    loads: np.ndarray  # (n_axles,) N
    channels: tuple[Channel, ...]
    readings: list[np.ndarray]  # per run (n_t, n_c)
    positions: list[np.ndarray]  # per run (n_t, n_axles), m
    lanes: np.ndarray  # (n_runs,) lateral covariates
    times: np.ndarray  # (n_runs,) clock times, s
    flags: list[tuple[str, ...]]
    h_req: float  # requested ordinate spacing, m
    fixed_grid: Grid | None  # the given support's grid
    lateral: bool
    per_run_scale: bool
    smoothing: float
    threshold: float
    lobes: bool  # keep lobes beyond the line's zero (trimmed_support's keep_lobes)
    trend_bandwidth: float | None
    outlier: OutlierRule | None
    tol: float
    max_iter: int
    penalties: dict = field(default_factory=dict)  # smoothing terms by (intervals, spacing)

    @property
    def n(self) -> int:
        return len(self.records)

    def penalty(self, grid: Grid) -> np.ndarray | None:
        """The smoothing term on ``grid`` (None without smoothing)."""
        if self.smoothing == 0:
            return None
        key = (grid.n, grid.h)  # the term is (ℓ / h)⁴ D₂ᵀ D₂: both matter
        if key not in self.penalties:
            self.penalties[key] = smoothing_penalty(grid.n - 1, self.smoothing, grid.h)
        return self.penalties[key]


def _read_runs(records, passages, axle_loads, *, channels, lateral, per_run_scale,
               smoothing, spacing, support, outlier, run_flags, signal_threshold,
               support_lobes, trend_bandwidth, tol, max_iter) -> _Runs:
    """The inputs checked (one-line InputErrors), the channels resolved and read."""
    recs, pas = _records_and_passages(records, passages)
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
    flags = run_flag_tuples(run_flags, len(recs))

    sens = structural_sensors(recs[0])
    if isinstance(channels, str) and channels == "each":
        chans = resolve_channels(sens, "each")
    else:
        chans = resolve_channels(sens, channels)
    if spacing is None:
        h_req = max(p.speed / r.sampling_rate for r, p in zip(recs, pas, strict=True))
    else:
        h_req = require_positive("spacing", spacing)
    return _Runs(
        records=recs, passages=pas, loads=loads, channels=chans,
        readings=[read_channels(r, chans) for r in recs],
        positions=[p.axle_x(r.time) for r, p in zip(recs, pas, strict=True)],
        lanes=np.array([p.lane for p in pas]),
        times=np.array([r.clock_seconds() for r in recs]), flags=flags, h_req=h_req,
        fixed_grid=None if support is None else _given_grid(support, h_req),
        lateral=lateral is not None, per_run_scale=per_run_scale, smoothing=ell,
        threshold=thr, lobes=bool(support_lobes), trend_bandwidth=trend_bandwidth,
        outlier=outlier, tol=tol,
        max_iter=int(max_iter))


def _records_and_passages(records, passages) -> tuple[list[Record], list[Passage]]:
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


def _given_grid(support, h_req: float) -> Grid:
    if not isinstance(support, (tuple, list, np.ndarray)) or len(support) != 2:
        raise InputError(f"support must be (start, end) in m, got {support!r}")
    sx0, sx1 = (require_finite("support", v) for v in support)
    if sx1 <= sx0:
        raise InputError(f"support must be (start, end) with end > start, got {support!r}")
    return uniform_grid(sx0, sx1, h_req)


# --- step 3: fit the kept runs, reject the worst, again -----------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _GridFit:
    """The kept runs fitted on one grid."""

    grid: Grid
    data: list[RunData]
    fit: LinesFit


@dataclass(frozen=True, kw_only=True, eq=False)
class _KeptFit:
    """The lines of a set of kept runs, with their residuals."""

    kept: list[int]  # a list: it indexes the runs' arrays
    ybar: float
    final: _GridFit
    residuals: list[np.ndarray]  # per kept run, (n_c, n_c) residual cross-products
    cov: np.ndarray  # (n_c, n_c) residual covariance between channels
    var: np.ndarray  # its diagonal, clipped to > 0
    reasons: dict[int, str]  # every rejected run's reason so far
    nfev: int  # line solves so far
    core: tuple[float, float] | None = None  # the support without its lobes (lobes kept)


def _reject_outliers(runs: _Runs, reasons: dict[int, str]) -> _KeptFit:
    """Fit the runs not rejected, remove the worst outlier run, repeat until none is."""
    kept = [k for k in range(runs.n) if k not in reasons]
    if len(kept) < 1:
        raise InputError("every calibration run is flagged upstream; nothing to calibrate")
    current = _fit_kept(runs, kept, reasons, nfev=0)
    while (rejection := _next_rejection(runs, current)) is not None:
        current = _fit_kept(runs, [k for k in current.kept if k != rejection.index],
                            {**current.reasons, rejection.index: rejection.reason},
                            nfev=current.nfev)
    return current


def _fit_kept(runs: _Runs, kept: list[int], reasons: dict[int, str], *,
              nfev: int) -> _KeptFit:
    """The lines of the ``kept`` runs (support estimated unless given) and their residual
    covariance between channels."""
    if runs.lateral and np.ptp(runs.lanes[kept]) <= 0:
        raise InputError("lateral='linear' needs runs at different lateral positions "
                         "(passage.lane); all kept runs are at "
                         f"{runs.lanes[kept][0]:g}")
    ybar = float(runs.lanes[kept].mean())
    passes = _support_passes(runs, kept, ybar)
    final = passes[-1]
    core = None
    if runs.lobes and len(passes) == 2:  # the support without the lobes it kept
        x0, x1 = trimmed_support(passes[0].fit.theta0, passes[0].grid, runs.threshold)
        if x0 > final.grid.x0 or x1 < final.grid.x[-1]:
            core = (float(x0), float(x1))
    grid, data, fit = final.grid, final.data, final.fit
    n_par = (grid.n - 1) * (2 if runs.lateral else 1) + len(kept) * (
        2 if runs.per_run_scale else 1)
    residuals = [run_residual(d, fit.lines_at(y - ybar), s).cross
                 for d, y, s in zip(data, runs.lanes[kept], fit.scales, strict=True)]
    cov = sum(residuals) / max(sum(d.n_t for d in data) - n_par, 1)
    var = np.clip(np.diag(cov), np.finfo(float).tiny, None)
    return _KeptFit(kept=kept, ybar=ybar, final=final, residuals=residuals, cov=cov, var=var,
                    reasons=reasons, nfev=nfev + sum(p.fit.nfev for p in passes), core=core)


def _support_passes(runs: _Runs, kept: list[int], ybar: float) -> list[_GridFit]:
    """The fits on the given support, or on the generous then the trimmed support."""
    if runs.fixed_grid is not None:
        return [_fit_on(runs, kept, runs.fixed_grid, ybar)]
    windows = [signal_window(runs.readings[k], runs.positions[k], runs.threshold,
                             runs.records[k].sampling_rate) for k in kept]
    if any(w is None for w in windows):
        bad = kept[[w is None for w in windows].index(True)]
        raise InputError(f"records[{bad}] has no significant signal; remove it or give "
                         "support=")
    cover = (min(float(runs.positions[k][0, 0]) for k in kept),
             max(float(runs.positions[k][-1, -1]) for k in kept))
    first = _fit_on(runs, kept, generous_grid(windows, cover, runs.h_req), ybar)
    x0, x1 = trimmed_support(first.fit.theta0, first.grid, runs.threshold,
                             keep_lobes=runs.lobes)
    return [first, _fit_on(runs, kept, uniform_grid(x0, x1, runs.h_req), ybar)]


def _fit_on(runs: _Runs, kept: list[int], grid: Grid, ybar: float) -> _GridFit:
    """The kept runs' lines and factors on ``grid``."""
    data = [run_data(runs.readings[k], runs.positions[k], runs.loads, grid) for k in kept]
    for k, d in zip(kept, data, strict=True):
        if not d.on:
            raise InputError(f"no axle of records[{k}] is on the support {grid.x0:g} … "
                             f"{grid.x[-1]:g} m")
    solver = AlternatingLines(data, runs.lanes[kept] - ybar, lateral=runs.lateral,
                              per_run_scale=runs.per_run_scale, penalty=runs.penalty(grid))
    return _GridFit(grid=grid, data=data, fit=solver.solve(tol=runs.tol,
                                                           max_iter=runs.max_iter))


def _next_rejection(runs: _Runs, current: _KeptFit) -> Rejection | None:
    """The worst outlier among the kept runs (None: none, no rule, or too few runs)."""
    rule, kept = runs.outlier, current.kept
    if rule is None or len(kept) <= rule.min_runs:
        return None
    mis = np.array([run_misfit(r, current.var, d.n_t)
                    for r, d in zip(current.residuals, current.final.data, strict=True)])
    return worst_run(kept, mis, current.final.fit.scales if runs.per_run_scale else None,
                     runs.times[kept], rule, runs.trend_bandwidth)


# --- step 4: every run against the final lines, the noise, the result ---------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Evaluation:
    """Every run against the final lines."""

    runs: tuple[RunFit, ...]
    rss: float  # residual sum of squares over the kept runs
    residual: float  # overall relative residual of the kept runs
    sum_misfit_median: float


def _evaluate_runs(runs: _Runs, current: _KeptFit) -> _Evaluation:
    """Each run (kept: its calibrated factor; rejected: its best factor) against the final
    lines: factor, offsets, relative residual and misfit."""
    grid, data, fit = current.final.grid, current.final.data, current.final.fit
    kept_pos = {k: i for i, k in enumerate(current.kept)}
    total_res = total_ee = 0.0
    sum_var = float(np.sum(current.cov))  # variance of the summed channels' residual
    sum_misfits = []
    out = []
    for k in range(runs.n):
        T = fit.lines_at(runs.lanes[k] - current.ybar)
        if k in kept_pos:
            d = data[kept_pos[k]]
            s = float(fit.scales[kept_pos[k]])
        else:
            d = run_data(runs.readings[k], runs.positions[k], runs.loads, grid)
            s = run_scale(d, T)
        if np.isfinite(s):
            res = run_residual(d, T, s)
            offsets = res.offsets
            rel = relative_residual(res.cross, d)
            mis = run_misfit(res.cross, current.var, d.n_t)
            if k in kept_pos:
                total_res += float(np.trace(res.cross))
                total_ee += float(np.trace(d.EE))
                sum_misfits.append(float(np.sqrt(max(float(np.sum(res.cross)), 0.0)
                                                 / (d.n_t * max(sum_var, np.finfo(float).tiny)))))
        else:
            offsets, rel, mis = d.ebar, float("nan"), float("nan")
        out.append(RunFit(index=k, time=float(runs.times[k]), speed=runs.passages[k].speed,
                          lateral=float(runs.lanes[k]), scale=s, residual=rel, misfit=mis,
                          offsets=offsets, rejected=k in current.reasons,
                          reason=current.reasons.get(k, "")))
    overall = float(np.sqrt(max(total_res, 0.0) / total_ee)) if total_ee > 0 else float("nan")
    return _Evaluation(runs=tuple(out), rss=total_res, residual=overall,
                       sum_misfit_median=float(np.median(sum_misfits)))


def _channel_noise(runs: _Runs, kept: list[int], grid: Grid) -> np.ndarray:
    """Each channel's standard deviation before the first axle reaches the support (the
    bridge at rest), pooled over the kept runs; zeros without such samples."""
    noise_ss, noise_n = np.zeros(len(runs.channels)), 0
    for k in kept:
        P = runs.positions[k]
        lead = int(np.argmax(P[:, 0] > grid.x0)) if P[-1, 0] > grid.x0 else 0
        if lead >= 8:
            noise_ss += (lead - 1) * np.var(runs.readings[k][:lead], axis=0, ddof=1)
            noise_n += lead - 1
    return np.sqrt(noise_ss / noise_n) if noise_n else np.zeros(len(runs.channels))


def _result(runs: _Runs, current: _KeptFit, evaluation: _Evaluation) -> MultiRunCalibration:
    """The lines on their full grid (zero ends), the trend and the statistics."""
    grid, fit, kept, cov = current.final.grid, current.final.fit, current.kept, current.cov
    full0 = np.zeros((grid.n + 1, len(runs.channels)))
    full0[1:-1] = fit.theta0
    slope = None
    if fit.theta1 is not None:
        slope = np.zeros_like(full0)
        slope[1:-1] = fit.theta1
    line = InfluenceLine(x=grid.x, ordinates=full0, channels=runs.channels, lane=current.ybar,
                         track_width=runs.passages[kept[0]].track_width,
                         source="multi-run matrix method", residual=evaluation.residual)
    trend = None
    if runs.per_run_scale:
        trend = ScaleTrend.fit(runs.times[kept], fit.scales, bandwidth=runs.trend_bandwidth)
    return MultiRunCalibration(
        line=line, lateral_slope=slope,
        lateral_range=(float(runs.lanes[kept].min()), float(runs.lanes[kept].max())),
        runs=evaluation.runs, channel_std=np.sqrt(np.diag(cov).clip(0.0)),
        channel_noise=_channel_noise(runs, kept, grid), channel_covariance=cov,
        truck_weight=float(runs.loads.sum()),
        misfit_median=float(np.median([evaluation.runs[k].misfit for k in kept])),
        sum_misfit_median=evaluation.sum_misfit_median,
        scale_trend=trend,
        # from the first kept run's start to the last one's end: a vehicle is dated by
        # its crossing, the runs by their records' starts (the last run's own truck
        # crosses after it)
        time_span=(float(runs.times[kept].min()),
                   max(float(runs.times[k]) + float(runs.records[k].time[-1]
                                                    - runs.records[k].time[0])
                       for k in kept)),
        core_support=current.core,
        x=fit.scales, fun=evaluation.rss, nfev=current.nfev, nit=fit.nit,
        success=fit.success, message=fit.message,
    )
