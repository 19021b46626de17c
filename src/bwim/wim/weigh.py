"""Weigh unknown traffic with multi-run influence lines: Moses' algorithm with the gauges
combined optimally, axle groups, baseline offsets, the scale trend, and plausibility flags.

Contract
--------
* :func:`weigh` fits the static weights of one vehicle whose passage (speed, lane, axle
  spacings, delay; from detection) is known, with the lines of a
  :class:`~bwim.wim.multirun.MultiRunCalibration`::

      ε_g(t_k) = s(t₀) Σ_j w_j Σ_{i ∈ group j} I_g(x_ik; y) / n_j + c_g + e_gk

  ``w_j`` the weight of axle group ``j`` (its axles share it equally, as B-WIM systems
  report groups), ``s(t₀)`` the calibration's :class:`~bwim.wim.scale_trend.ScaleTrend` at
  the record's clock time ``t₀ = record.clock_seconds()``, ``I_g(·; y)`` channel ``g``'s line at
  the vehicle's lateral covariate ``y``, ``c_g`` the channel's baseline offset.
* :func:`weighing_model` makes everything of a weighing that does not depend on the
  scale (the readings, the lines' readings of a unit weight on each axle group, their
  offsets removed) once; its :meth:`WeighingModel.weigh` gives :func:`weigh`'s result
  for any ``scale_correction`` and ``scale``, the same numbers.
* Weights in N; readings in the calibration's units; positions in the passages' frame.
* Every result carries plausibility ``flags`` (strings, written as they are to
  summary.csv) and a ``quality``: ``"reject"`` if any flag of :data:`HARD_FLAGS` is set,
  ``"warning"`` if only flags of :data:`SOFT_FLAGS` are, ``"ok"`` otherwise.  No weight is
  returned without these checks.

Combining the gauges
--------------------
Stack the offset-free readings of all channels, ``y = A w + e``.  If the errors ``e``
(noise, the bridge's and the vehicle's dynamics, line mismatch) have zero mean, are
uncorrelated from sample to sample and have covariance ``C`` between channels at one
sample, ``Cov(e) = V = I ⊗ C``.  Among the linear unbiased estimators ``ŵ = K y``
(``K A = I``) the Gauss–Markov/Aitken estimator ``K* = (Aᵀ V⁻¹ A)⁻¹ Aᵀ V⁻¹`` has the least
covariance: writing any other as ``K = K* + D`` with ``D A = 0``,
``K V Kᵀ = K* V K*ᵀ + D V Dᵀ`` (the cross term is ``(Aᵀ V⁻¹ A)⁻¹ Aᵀ Dᵀ = 0``), and
``D V Dᵀ ⪰ 0``.  The plain sum of the gauges against the summed line is one such ``K``
(``K_Σ = (A_Σᵀ A_Σ)⁻¹ A_Σᵀ (I ⊗ 1ᵀ)``), so it can only be as good when the model holds.
It is computed by whitening: with ``C = L Lᵀ`` (Cholesky), ordinary least squares on
``L⁻¹``-transformed channels.  ``C`` is the calibration residual's covariance between
channels, rescaled to the vehicle's weight
(:meth:`~bwim.wim.multirun.MultiRunCalibration.error_covariance`: the noise stays, the
dynamics shrink for lighter vehicles; a first solve with the plain sum gives the
weight).  ``combine="blue"`` uses the full ``C``; ``combine="gls"`` its
diagonal only (weights ``1/σ_g²``, robust when the cross-channel
covariance of a new vehicle's dynamics differs from the calibration truck's);
``combine="sum"`` adds the gauges and their lines (classic B-WIM): the sum of the
gauges across a section reads the section's total moment, which hardly depends on where
the vehicle is across the deck, whereas each gauge's line does.  So ``combine="auto"``
(the default) uses "gls" for vehicles inside the calibration runs' lateral range and the
sum outside it (a lane the truck never drove).  The errors are in fact correlated in
time (dynamics), so "best" holds for the model, not exactly; the combinations, with and
without the lateral model, are compared by ``benchmarks/bench_multirun.py``
(docs/theory.md §15).  Most of the error is the vehicles' own dynamics, common to all
gauges.

Baseline offsets
----------------
``baseline="fit"``: one unknown offset per channel in the least squares, eliminated
exactly by centring each channel over the record (Frisch–Waugh–Lovell); it is determined
by the samples at which no axle is on the lines' support (pre- and post-trigger), at
least ``Limits.min_baseline`` of them or the flag ``no_baseline`` is set.
``baseline="pretrigger"``: subtract each channel's mean over the samples before the first
axle reaches the support.  ``baseline="none"``: readings are taken as offset-free.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from bwim.errors import InputError, require_finite, require_instance
from bwim.plausibility import (
    HARD_FLAGS,
    SOFT_FLAGS,
    Limits,
    ordered_flags,
    quality_of,
    weight_flags,
)
from bwim.records import Passage, Record
from bwim.wim.influence_line import Channel, read_channels
from bwim.wim.moses import AxleGroups, group_axles, group_share
from bwim.wim.multirun import MultiRunCalibration
from bwim.wim.weigh_kernels import (
    axle_positions,
    channel_products,
    column_centred,
    fit_residual,
    group_readings,
    nan_sum,
    on_support,
)

__all__ = ["HARD_FLAGS", "NORMAL_CONDITION", "SOFT_FLAGS", "Limits", "Weighing",
           "WeighingModel", "weigh", "weighing_model"]

@dataclass(frozen=True, kw_only=True, eq=False)
class Weighing:
    """Static weights of one vehicle, with plausibility flags (:func:`weigh`).

    Attributes
    ----------
    axle_weights : ndarray, shape (n_axles,)
        N (a group's weight split equally between its axles).
    group_weights : ndarray, shape (n_groups,)
        N.
    groups : tuple of tuple of int
        Axle indices of each group.
    gvw : float
        Gross vehicle weight, N.
    residual : float
        Relative residual ‖ε − c − fitted‖ / ‖ε − c‖ over all samples and channels (as the
        calibration runs' residuals).
    misfit : float
        RMS of the residual over all samples and channels, each channel divided by the
        expected residual deviation of a vehicle of this weight (as the calibration runs'
        misfits, ≈ 1 for them).
    condition : float
        Condition number of the whitened least-squares matrix.
    scale_factor : float
        The factor the readings were divided by (the scale trend at the clock time).
    flags : tuple of str
        Plausibility flags (:data:`HARD_FLAGS`, :data:`SOFT_FLAGS`), empty if none.
    quality : str
        ``"ok"``, ``"warning"`` or ``"reject"``.
    passage : Passage
    lateral : float
        Lateral covariate the lines were taken at.
    clock_time : float
        ``record.clock_seconds()``, s.
    combine, baseline : str
        How the gauges were combined ("gls", "blue" or "sum"; "auto" resolved) and the
        offsets removed.
    offsets : ndarray, shape (n_channels,)
        Baseline offset of each channel.
    channels : tuple of Channel
    time : ndarray, shape (n_w,)
        Samples with an axle on the support, s.
    measured, fitted : ndarray, shape (n_w, n_channels)
        Offset-free readings and the fitted static readings at those samples.
    """

    axle_weights: np.ndarray
    group_weights: np.ndarray
    groups: tuple[tuple[int, ...], ...]
    gvw: float
    residual: float
    misfit: float
    condition: float
    scale_factor: float
    flags: tuple[str, ...]
    quality: str
    passage: Passage
    lateral: float
    clock_time: float
    combine: str
    baseline: str
    offsets: np.ndarray
    channels: tuple[Channel, ...]
    time: np.ndarray
    measured: np.ndarray
    fitted: np.ndarray

    @property
    def n_axles(self) -> int:
        return self.axle_weights.size

    @property
    def ok(self) -> bool:
        return self.quality == "ok"


_COMBINE = ("auto", "gls", "blue", "sum")
_BASELINE = ("fit", "pretrigger", "none")


def _groups(groups: Any, passage: Passage) -> AxleGroups:
    if isinstance(groups, str):
        if groups != "auto":
            raise InputError(f"groups must be 'auto', None or a sequence of axle index "
                             f"sequences, got {groups!r}")
        groups = group_axles(passage)
    return group_share(groups, passage.n_axles)


def _whitener(C: np.ndarray, combine: str) -> np.ndarray | None:
    """Matrix T (n_c', n_c) applied to the channel axis: ``T C Tᵀ = I`` for "blue"; for
    "gls" its diagonal version, given as the vector of its diagonal (n_c,), from C's
    diagonal (:func:`_gls_whitener`); None for the plain sum."""
    if combine == "sum":
        return None
    if combine == "gls":
        return _gls_whitener(np.diag(C))
    try:
        L = np.linalg.cholesky(C)
    except np.linalg.LinAlgError:
        raise InputError("combine='blue' needs a positive definite channel covariance; "
                         "use 'gls' or 'sum'") from None
    return scipy.linalg.solve_triangular(L, np.eye(L.shape[0]), lower=True)


def _gls_whitener(var: np.ndarray) -> np.ndarray:
    """The diagonal whitener of "gls" (n_c,) from each channel's residual variance."""
    if np.any(var <= 0):
        raise InputError("combine='gls' needs a positive residual variance per channel "
                         "(the calibration fitted a channel exactly); use 'sum'")
    return 1.0 / np.sqrt(var)


#: Fits whose design is conditioned better than this (ratio of its largest to its smallest
#: singular value, ten times ``Limits.condition``'s default) are solved by their normal
#: equations; others by ``numpy.linalg.lstsq`` (its rank and minimum-norm solution).
NORMAL_CONDITION = 1e3


def _system(Ec: np.ndarray, Mc: np.ndarray, s: float, T: np.ndarray | None
            ) -> tuple[np.ndarray, np.ndarray]:
    """The least-squares design ``A`` (channel-major rows) and readings ``b`` of the
    (whitened) channels: ``T`` None (their sum), a vector (a diagonal whitener) or a
    matrix."""
    if T is None:
        Ew, Mw = Ec.sum(axis=1, keepdims=True), Mc.sum(axis=2, keepdims=True)
    elif T.ndim == 1:  # diagonal: scale the channels
        Ew, Mw = Ec * T, Mc * T
    else:
        Ew, Mw = Ec @ T.T, Mc @ T.T
    n_g = Mc.shape[1]
    return s * Mw.transpose(2, 0, 1).reshape(-1, n_g), Ew.T.ravel()


def _solve(centred: _Centred, s: float, T: np.ndarray | None
           ) -> tuple[np.ndarray, int, np.ndarray]:
    """Least squares of the (whitened) channels (``T`` as :func:`_system`'s): group
    weights, rank, singular values (descending).  By the normal equations when the
    design's condition number is below :data:`NORMAL_CONDITION` (then of full rank), else
    by ``numpy.linalg.lstsq``.  The normal equations of the sum and of a diagonal
    whitener are made of the centred design's per-channel products
    (:class:`_Centred`: ``AᵀA = s² Σ_c T_c² G_c``, the numbers of ``A.T @ A`` to
    rounding), without the design."""
    Ec, Mc = centred.readings, centred.groups
    # the normal equations where they are well conditioned (the lstsq numbers to rounding:
    # relative error about eps × cond², far below the weights' own), lstsq otherwise
    if T is None:
        G, rhs = (s * s) * centred.sum_gram, s * centred.sum_rhs
    elif T.ndim == 1:
        w = T * T
        # numpy.tensordot(w, gram, 1)'s own product: (1, n_c) @ (n_c, n_g²), gram
        # C-contiguous (channel_products)
        n_c = w.shape[0]
        Gw = np.dot(w.reshape(1, n_c), centred.gram.reshape(n_c, -1)).reshape(
            centred.gram.shape[1:])
        G, rhs = (s * s) * Gw, s * (w @ centred.rhs)
    else:
        A, b = _system(Ec, Mc, s, T)
        G, rhs = A.T @ A, A.T @ b
    n_g = Mc.shape[1]
    lam = np.linalg.eigvalsh(G)[::-1]  # σ² of A, descending
    if lam.size and lam[-1] > 0 and lam[0] <= NORMAL_CONDITION**2 * lam[-1]:
        return np.linalg.solve(G, rhs), n_g, np.sqrt(lam)
    A, b = _system(Ec, Mc, s, T)
    sol, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    return sol, int(rank), sv


def weigh(
    record: Record,
    passage: Passage | None,
    calibration: MultiRunCalibration,
    *,
    groups: Any = "auto",
    combine: str = "auto",
    lateral: float | None = None,
    baseline: str = "fit",
    scale_correction: bool = True,
    scale: float | None = None,
    limits: Limits | None = None,
) -> Weighing:
    """Static axle and group weights of one vehicle, with plausibility flags.

    Parameters
    ----------
    record : Record
        The event: readings of every channel of the calibration, clock time in
        ``record.time``.
    passage : Passage or None
        The vehicle's passage (speed, lane, axle spacings, delay) in the calibration's
        frame; None: the record's single passage.
    calibration : MultiRunCalibration
    groups : "auto", None or sequence
        ``"auto"``: :func:`~bwim.wim.group_axles` (axles closer than 2 m form a group,
        weighed as one unknown and split equally); None: every axle on its own; or explicit
        groups of axle indices.
    combine : "auto", "gls", "blue" or "sum"
        How the channels are combined (module docstring); "auto": "gls" when the
        vehicle's lateral covariate lies in the calibrated range (widened by
        ``limits.lateral_tolerance``), else "sum".
    lateral : float, optional
        The vehicle's lateral covariate; default ``passage.lane``.
    baseline : "fit", "pretrigger" or "none"
        How the channels' offsets are removed (module docstring).
    scale_correction : bool
        Divide by the calibration's scale trend at ``record.clock_seconds()`` (no effect
        without per-run factors).
    scale : float, optional
        Divide by this strain-to-load factor instead (a drift correction the caller made,
        :mod:`bwim.site.drift`); the clock time is then the caller's to check.
    limits : Limits
        Plausibility thresholds.

    Returns
    -------
    Weighing
    """
    event = _inputs(record, passage, calibration, groups=groups, combine=combine,
                    lateral=lateral, baseline=baseline, limits=limits)
    _check_scale(scale)
    return _model(record, calibration, event).weigh(scale_correction=scale_correction,
                                                    scale=scale)


def _check_scale(scale: float | None) -> None:
    if scale is not None and not (np.isfinite(scale) and scale > 0):
        raise InputError(f"scale must be a positive factor, got {scale!r}")


def weighing_model(
    record: Record,
    passage: Passage | None,
    calibration: MultiRunCalibration,
    *,
    groups: Any = "auto",
    combine: str = "auto",
    lateral: float | None = None,
    baseline: str = "fit",
    limits: Limits | None = None,
    readings: np.ndarray | None = None,
) -> WeighingModel:
    """What :func:`weigh` makes before the scale: the checked options, the readings and
    the lines' readings of a unit weight on each axle group, offsets removed; the
    arguments are :func:`weigh`'s.  Its :meth:`WeighingModel.weigh` gives the weighing
    (the numbers of :func:`weigh` with the same arguments) for any scale: two weighings
    of one vehicle that differ by their scale only (the gauge check's and the drift
    corrected one, :mod:`bwim.site.event`) make the model once.  ``readings``: the
    calibration's channels' readings of ``record``, (n_t, n_channels), as
    :func:`~bwim.wim.influence_line.read_channels` gives them, when already read (not
    to be changed afterwards)."""
    event = _inputs(record, passage, calibration, groups=groups, combine=combine,
                    lateral=lateral, baseline=baseline, limits=limits)
    if readings is not None:
        readings = np.asarray(readings, dtype=float)
        shape = (record.time.size, len(calibration.channels))
        if readings.shape != shape:
            raise InputError(f"readings must have shape (n_t, n_channels) = {shape}, got "
                             f"{readings.shape}")
    return _model(record, calibration, event, readings)


def _model(record: Record, calibration: MultiRunCalibration, event: _Inputs,
           readings: np.ndarray | None = None) -> WeighingModel:
    design = _design(record, event, calibration, readings)
    return WeighingModel(record=record, calibration=calibration, event=event,
                         design=design, centred=_centred(design, event))


@dataclass(frozen=True, kw_only=True, eq=False)
class WeighingModel:
    """One vehicle's weighing before its scale (:func:`weighing_model`)."""

    record: Record
    calibration: MultiRunCalibration
    event: _Inputs
    design: _Design
    centred: _Centred

    @property
    def readings(self) -> np.ndarray:
        """The calibration's channels' readings over the record, (n_t, n_channels), as
        :func:`bwim.wim.influence_line.read_channels` gives them (not to be changed)."""
        return self.design.readings

    @property
    def on_support(self) -> np.ndarray:
        """The samples with an axle on the lines' support, bool (n_t,): those its
        weighings fit (their ``time``, ``measured`` and ``fitted``; not to be changed)."""
        return self.design.on

    def weigh(self, *, scale_correction: bool = True, scale: float | None = None
              ) -> Weighing:
        """The weighing with :func:`weigh`'s ``scale_correction`` and ``scale``."""
        _check_scale(scale)
        record, calibration, event = self.record, self.calibration, self.event
        design = self.design
        s, trend_used = _scale(design, calibration, scale_correction, scale)
        centred = self.centred
        fit = _fit(design, centred, event, calibration, s)
        flags = _flags(event, design, centred, fit, calibration, trend_used)
        return _weighing(record, calibration, event, design, fit, flags, s)


def _weighing(record: Record, calibration: MultiRunCalibration, event: _Inputs,
              design: _Design, fit: _Fit, flags: tuple[str, ...], s: float) -> Weighing:
    on = design.on_index  # the samples on the support (numpy's [design.on]'s rows)
    return Weighing(
        axle_weights=fit.axle_weights, group_weights=fit.group_weights,
        groups=event.groups.groups, gvw=float(fit.axle_weights.sum()), residual=fit.residual,
        misfit=fit.misfit, condition=fit.condition, scale_factor=s, flags=flags,
        quality=quality_of(flags), passage=event.passage, lateral=event.lateral,
        clock_time=design.clock_time, combine=event.combine, baseline=event.baseline,
        offsets=fit.offsets, channels=calibration.line.channels,
        time=record.time.take(on), measured=fit.measured.take(on, axis=0),
        fitted=fit.fitted.take(on, axis=0),
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class _Inputs:
    """The checked options of one weighing."""

    passage: Passage
    lateral: float  # the vehicle's lateral covariate
    lateral_ok: bool  # within the calibrated range (widened by the tolerance)
    combine: str  # "auto" resolved
    baseline: str
    groups: AxleGroups
    limits: Limits


def _inputs(record, passage, calibration, *, groups, combine, lateral, baseline,
            limits) -> _Inputs:
    """The inputs checked (one-line InputErrors) and the options resolved."""
    require_instance("record", record, Record)
    if not isinstance(calibration, MultiRunCalibration):
        raise InputError(f"calibration must be a MultiRunCalibration, got "
                         f"{type(calibration).__name__}")
    if passage is None:
        if len(record.passages) != 1:
            raise InputError(f"the record has {len(record.passages)} passages; give passage=")
        passage = record.passage
    else:
        require_instance("passage", passage, Passage)
    if combine not in _COMBINE:
        raise InputError(f"combine must be one of {', '.join(_COMBINE)}, got {combine!r}")
    if baseline not in _BASELINE:
        raise InputError(f"baseline must be one of {', '.join(_BASELINE)}, got {baseline!r}")
    limits = Limits() if limits is None else limits
    if not isinstance(limits, Limits):
        raise InputError(f"limits must be a Limits, got {type(limits).__name__}")
    y = passage.lane if lateral is None else require_finite("lateral", lateral)
    y_lo, y_hi = calibration.lateral_range
    lateral_ok = y_lo - limits.lateral_tolerance <= y <= y_hi + limits.lateral_tolerance
    if combine == "auto":
        combine = "gls" if lateral_ok else "sum"
    return _Inputs(passage=passage, lateral=y, lateral_ok=lateral_ok, combine=combine,
                   baseline=baseline, groups=_groups(groups, passage), limits=limits)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Design:
    """The readings and the lines' readings of a unit weight on each axle group."""

    readings: np.ndarray  # (n_t, n_c)
    positions: np.ndarray  # (n_t, n_axles) axle positions, m
    groups: np.ndarray  # (n_t, n_groups, n_c) static readings of a unit group weight
    on: np.ndarray  # (n_t,) an axle on the lines' support
    on_index: np.ndarray  # (n_on,) those samples' indices, in order
    support: tuple[float, float]  # the lines' support, m
    clock_time: float  # record.clock_seconds(), s


def _design(record: Record, event: _Inputs, calibration: MultiRunCalibration,
            readings: np.ndarray | None = None) -> _Design:
    """The model of the readings (``readings`` when already read): the lines at the
    vehicle's lateral covariate under each axle, summed by group (at the scale factor 1:
    :func:`_scale` gives a weighing's)."""
    line = calibration.line
    E = read_channels(record, line.channels) if readings is None else readings  # (n_t, n_c)
    ords = calibration.ordinates_at(event.lateral)[1:-1]  # interior ordinates (m, n_c)
    p = event.passage  # (n_t, n_axles): Passage.axle_x's numbers
    pos = axle_positions(record.time, p.speed, p.delay, p.axle_offsets)
    # (n_t, n_groups, n_c): Σ_i share_ig M_kic, M the readings under each axle
    Mg = group_readings(pos, ords, line.x[0], line.spacing, line.x.size - 1,
                        event.groups.share)
    lo, hi = line.support
    on = on_support(pos, lo, hi)  # ((pos > lo) & (pos < hi)).any(axis=1)
    return _Design(readings=E, positions=pos, groups=Mg, on=on, on_index=np.flatnonzero(on),
                   support=(lo, hi), clock_time=record.clock_seconds())


def _scale(design: _Design, calibration: MultiRunCalibration, scale_correction: bool,
           scale: float | None) -> tuple[float, bool]:
    """The factor a weighing divides ``design``'s readings by: ``scale`` when given, else
    the scale trend's at the clock time with ``scale_correction``, else 1; and whether it
    is the trend's."""
    trend = calibration.scale_trend
    if scale is not None:
        s = float(scale)
    else:
        s = float(trend(design.clock_time)) if (scale_correction and trend is not None) \
            else 1.0
    return s, scale is None and scale_correction and trend is not None


@dataclass(frozen=True, kw_only=True, eq=False)
class _Centred:
    """The readings and the design with the channels' offsets removed, and their
    products of the normal equations (independent of the scale and the whitening)."""

    readings: np.ndarray  # (n_t, n_c)
    groups: np.ndarray  # (n_t, n_groups, n_c)
    offsets: np.ndarray | None  # the offsets removed (None: fitted, baseline="fit")
    flags: tuple[str, ...]  # "no_baseline" when too few samples determine them
    gram: np.ndarray  # (n_c, n_groups, n_groups): G_c = Σ_k groups[k, :, c] ⊗ groups[k, :, c]
    rhs: np.ndarray  # (n_c, n_groups): Σ_k groups[k, :, c] readings[k, c]
    sum_gram: np.ndarray  # (n_groups, n_groups): the same of the channels' sum
    sum_rhs: np.ndarray  # (n_groups,)


def _centred_of(readings: np.ndarray, groups: np.ndarray, offsets: np.ndarray | None,
                flags: tuple[str, ...]) -> _Centred:
    """The centred readings and design with their normal equations' products."""
    p = channel_products(groups, readings)
    return _Centred(readings=readings, groups=groups, offsets=offsets, flags=flags,
                    gram=p.gram, rhs=p.rhs, sum_gram=p.sum_gram, sum_rhs=p.sum_rhs)


def _centred(design: _Design, event: _Inputs) -> _Centred:
    """The offsets removed as ``baseline`` says (module docstring)."""
    E, Mg, limits = design.readings, design.groups, event.limits
    flags = []
    if event.baseline == "fit":
        if np.count_nonzero(~design.on) < limits.min_baseline:
            flags.append("no_baseline")
        # E - E.mean(axis=0), Mg - Mg.mean(axis=0) (group_readings' table C-ordered, the
        # readings mostly a record's Fortran-ordered columns: the kernel sums as numpy)
        Ec = (column_centred(E) if E.dtype == np.float64 and (
            E.flags.c_contiguous or (E.ndim == 2 and E.flags.f_contiguous))
            else E - E.mean(axis=0))
        return _centred_of(Ec, column_centred(Mg), None, tuple(flags))
    if event.baseline == "pretrigger":
        pre = design.positions[:, 0] <= design.support[0]
        n_pre = int(np.argmin(pre)) if not pre.all() else E.shape[0]
        if n_pre < limits.min_baseline:
            flags.append("no_baseline")
        off = E[:n_pre].mean(axis=0) if n_pre else np.zeros(E.shape[1])
    else:
        off = np.zeros(E.shape[1])
    return _centred_of(E - off, Mg, off, tuple(flags))


@dataclass(frozen=True, kw_only=True, eq=False)
class _Fit:
    """The weights and how well they fit."""

    group_weights: np.ndarray  # (n_groups,) N (nan: undetermined)
    axle_weights: np.ndarray  # (n_axles,) N
    undetermined: bool
    condition: float
    offsets: np.ndarray  # (n_c,)
    measured: np.ndarray  # (n_t, n_c) offset-free readings
    fitted: np.ndarray  # (n_t, n_c) fitted static readings
    residual: float
    misfit: float
    misfit_ref: float  # the calibration runs' median misfit of the same kind


def _fit(design: _Design, centred: _Centred, event: _Inputs,
         calibration: MultiRunCalibration, s: float) -> _Fit:
    """Least squares of the combined channels, then the residual and the misfit.

    The error covariance depends on the vehicle's weight, so a first solve with the plain
    sum gives the weight for the second.
    """
    share, combine = event.groups.share, event.combine
    n_g = share.shape[1]
    sol, rank, sv = _solve(centred, s, None)
    # numpy.nansum's number (weigh_kernels.nan_sum)
    weight = float(nan_sum(share @ sol)) if rank == n_g else None
    if combine == "gls":  # the channels' variances alone (error_covariance's diagonal)
        var = calibration.error_variance(weight)
        sol, rank, sv = _solve(centred, s, _gls_whitener(var))
    else:
        C = calibration.error_covariance(weight)
        if combine != "sum":
            sol, rank, sv = _solve(centred, s, _whitener(C, combine))
    condition = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if rank < n_g:
        sol = np.full(n_g, np.nan)
    group_w = sol
    axle_w = share @ group_w

    E = design.readings
    summed = combine == "sum"  # the summed readings were fitted: judge their residual
    if summed:
        sd = np.sqrt(max(float(np.sum(C)), np.finfo(float).tiny))
        misfit_ref = calibration.sum_misfit_median
    else:
        sd = np.sqrt(np.clip(var if combine == "gls" else np.diag(C), np.finfo(float).tiny,
                             None))
        misfit_ref = calibration.misfit_median
    # fitted readings, offsets (fitted: the mean of reading − fit), the sums of squares
    finite = group_w if np.isfinite(group_w).all() else np.nan_to_num(group_w)
    r = fit_residual(E, design.groups, finite, s,
                     offsets=None if event.baseline == "fit" else centred.offsets,
                     deviation=sd, summed=summed)
    den = np.sqrt(r.sum_measured)
    resid = float(np.sqrt(r.sum_residual) / den) if den > 0 else float("inf")
    count = E.shape[0] * (1 if summed else E.shape[1])  # the residuals the misfit averages
    misfit = float(np.sqrt(r.sum_misfit / count)) if count else float("nan")
    return _Fit(group_weights=group_w, axle_weights=axle_w, undetermined=rank < n_g,
                condition=condition, offsets=r.offsets, measured=r.measured,
                fitted=r.fitted, residual=resid, misfit=misfit, misfit_ref=misfit_ref)


def _flags(event: _Inputs, design: _Design, centred: _Centred, fit: _Fit,
           calibration: MultiRunCalibration, trend_used: bool) -> tuple[str, ...]:
    """The plausibility flags of the weighing, in the canonical order."""
    limits, pos = event.limits, design.positions
    # a lobe beyond the line's zeros (support_lobes) may be cut by the record's ends
    lo, hi = calibration.core_support or design.support
    flags: list[str] = []
    if pos[0, 0] > lo:
        flags.append("truncated_start")
    if pos[-1, -1] < hi:
        flags.append("truncated_end")
    flags += centred.flags
    if fit.undetermined:
        flags.append("undetermined")
    flags += weight_flags(fit.axle_weights, fit.group_weights, limits)
    if not fit.misfit <= limits.misfit * fit.misfit_ref:
        flags.append("residual_high")
    t_lo, t_hi = calibration.time_span
    if trend_used and not t_lo <= design.clock_time <= t_hi:
        flags.append("outside_calibration_time")
    if not event.lateral_ok:
        flags.append("lateral_extrapolated")
    if fit.condition > limits.condition:
        flags.append("ill_conditioned")
    return ordered_flags(flags)
