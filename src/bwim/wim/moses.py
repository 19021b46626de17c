"""Moses' static Bridge WIM algorithm: axle weights from an influence line.

Contract
--------
* :func:`weigh_static` finds the static axle weights ``A_i`` of one vehicle whose passage
  (speed, axle spacings, delay) is known by least squares on the record (Moses 1979,
  "Weigh-in-motion system using instrumented bridges", ASCE J. Transp. Eng. 105(3)):
  ``ε(t_k) ≈ Σ_i A_i I(v (t_k − delay) − a_i)`` over every sample at which an axle is on
  the influence line's support, for every channel of the line.
* It is exact for static data: readings made by the same influence line give the axle
  weights back to round-off.  Everything dynamic (bridge vibration, axle hop) is error.
* Several channels are fitted together, each scaled by its line's peak absolute ordinate
  so that channels of different size (or units) count alike.
* Closely spaced axles (tandems, tridems) are hard to tell apart on a short span: their
  individual weights are ill-determined while their sum is not.  ``groups`` makes the
  axles of a group share its weight equally (as B-WIM systems report axle groups);
  :func:`group_axles` forms groups from the axle spacings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_finite, require_instance, require_positive
from bwim.plausibility import Limits, ordered_flags, quality_of, weight_flags
from bwim.records import Passage, Record
from bwim.summary import SummaryRow
from bwim.wim.influence_line import Channel, InfluenceLine, read_channels

__all__ = ["DEFAULT_MAX_RESIDUAL", "AxleGroups", "StaticWeights", "group_axles", "group_share",
           "weigh_static"]

#: Relative residual of Moses' fit above which a weighing is ``residual_high``.  A
#: vehicle crossing a calibrated line leaves well below this (noise, the bridge's
#: vibration, axle hop; see the simulated crossings of
#: ``tests/validation/test_static_wim.py``); a wrong time axis, swapped channels or a
#: second vehicle leave far more.
DEFAULT_MAX_RESIDUAL = 0.3


@dataclass(frozen=True, kw_only=True, eq=False)
class StaticWeights:
    """Static axle weights of one vehicle by Moses' algorithm.

    Attributes
    ----------
    axle_weights : ndarray, shape (n_axles,)
        N.
    time : ndarray, shape (n_w,)
        The samples used (an axle on the influence line's support), s.
    measured, fitted : ndarray, shape (n_w, n_channels)
        The channels' readings and the static readings of the fitted weights.
    channels : tuple of Channel
    passage : Passage
        The passage the weights were computed for.
    residual : float
        Relative residual ‖fitted − measured‖ / ‖measured‖ (channels scaled as in the fit).
    condition : float
        Condition number of the least-squares matrix (large for closely spaced axles:
        their individual weights are uncertain, their sum much less so).
    groups : tuple of tuple of int
        Axle indices of each group whose axles share the group's weight equally (one
        group per axle when weighed individually).
    flags : tuple of str
        Plausibility flags (:mod:`bwim.plausibility`): implausible weights,
        ``residual_high`` (relative residual above ``max_residual``), ``truncated_start``
        / ``truncated_end`` (the record does not cover the crossing), ``ill_conditioned``.
    quality : str
        ``"reject"``, ``"warning"`` or ``"ok"``
        (:func:`~bwim.plausibility.quality_of`).
    """

    axle_weights: np.ndarray
    time: np.ndarray
    measured: np.ndarray
    fitted: np.ndarray
    channels: tuple[Channel, ...]
    passage: Passage
    residual: float
    condition: float
    groups: tuple[tuple[int, ...], ...]
    flags: tuple[str, ...] = ()
    quality: str = "ok"

    @property
    def gvw(self) -> float:
        """Gross vehicle weight, N."""
        return float(self.axle_weights.sum())

    @property
    def n_axles(self) -> int:
        return self.axle_weights.size

    @property
    def group_weights(self) -> np.ndarray:
        """Weight of each axle group, N, shape (n_groups,)."""
        return np.array([self.axle_weights[list(g)].sum() for g in self.groups])

    def to_summary_row(self, record: str) -> SummaryRow:
        """This vehicle as a summary row named ``record`` (:class:`bwim.summary.SummaryRow`):
        refused, with its flags and no weights, when the weighing is rejected."""
        from bwim.classify import axle_configuration

        p = self.passage
        ok = self.quality != "reject"
        return SummaryRow(
            record=record, status="weighed" if ok else "refused", n_axles=p.n_axles,
            speed=p.speed, axle_spacings=tuple(p.axle_spacings),
            vehicle_class=axle_configuration(p.axle_spacings),
            axle_weights=tuple(self.axle_weights) if ok else (),
            gvw=self.gvw if ok else None,
            group_weights=tuple(self.group_weights) if ok else (), flags=self.flags,
            residual=self.residual, quality=self.quality, method="moses",
            reason="" if ok else f"implausible weighing ({', '.join(self.flags)})")

    def plot(self, ax=None, **kw):
        """Measured readings and the static fit, with a simulated ``record``'s true weights
        if given (:func:`bwim.plots.wim.plot_static_fit`); returns the figure."""
        from bwim.plots.wim import plot_static_fit

        return plot_static_fit(self, ax=ax, **kw)


def group_axles(spacings: Passage | np.ndarray, max_spacing: float = 2.0
                ) -> tuple[tuple[int, ...], ...]:
    """Axle groups: consecutive axles closer than ``max_spacing`` (m) form one group.

    Parameters
    ----------
    spacings : Passage or array_like, shape (n_axles − 1,)
        A passage or its axle spacings, m.
    max_spacing : float
        Spacings below this join axles into a group, m (2.0 m keeps the tandem and tridem
        groups of common trucks, 1.0–1.8 m apart, and separates steer and drive axles).
    """
    sp = spacings.axle_spacings if isinstance(spacings, Passage) else np.array(
        spacings, dtype=float, ndmin=1)
    limit = require_finite("max_spacing", max_spacing)
    groups: list[list[int]] = [[0]]
    for i, s in enumerate(sp.tolist() if sp.ndim == 1 else sp, start=1):
        if s < limit:
            groups[-1].append(i)
        else:
            groups.append([i])
    return tuple(tuple(g) for g in groups)


@dataclass(frozen=True, kw_only=True, eq=False)
class AxleGroups:
    """Checked axle groups and how their weights are shared by their axles.

    Attributes
    ----------
    groups : tuple of tuple of int
        Axle indices (from 0) of each group; every axle once.
    share : ndarray, shape (n_axles, n_groups)
        Axle weights are ``share @ group_weights``: the axles of a group share its weight
        equally.
    """

    groups: tuple[tuple[int, ...], ...]
    share: np.ndarray


def group_share(groups, n_axles: int) -> AxleGroups:
    """The :class:`AxleGroups` of ``groups`` for a vehicle of ``n_axles`` axles.

    ``groups`` None means every axle on its own; otherwise a sequence of sequences of axle
    indices (from 0) listing every axle once.
    """
    out = _check_groups(groups, n_axles)
    rows = [[0.0] * len(out) for _ in range(n_axles)]
    for k, g in enumerate(out):
        for i in g:
            rows[i][k] = 1.0 / len(g)
    share = np.array(rows, dtype=float).reshape(n_axles, len(out))
    return AxleGroups(groups=out, share=share)


def _check_groups(groups, n_axles: int) -> tuple[tuple[int, ...], ...]:
    if groups is None:
        return tuple((i,) for i in range(n_axles))
    try:
        out = tuple(tuple(int(i) for i in g) for g in groups)
    except (TypeError, ValueError):
        raise InputError(f"groups must be sequences of axle indices, got {groups!r}") from None
    flat = sorted(i for g in out for i in g)
    if flat != list(range(n_axles)) or any(not g for g in out):
        raise InputError(
            f"groups must list every axle 0 … {n_axles - 1} exactly once, got "
            f"{[list(g) for g in out]}")
    return out


def weigh_static(
    record: Record,
    influence: InfluenceLine,
    *,
    passage: Passage | None = None,
    groups: tuple[tuple[int, ...], ...] | None = None,
    lane_tolerance: float = 0.5,
    limits: Limits | None = None,
    max_residual: float = DEFAULT_MAX_RESIDUAL,
) -> StaticWeights:
    """Static axle weights and GVW of the vehicle in ``record`` (Moses' algorithm).

    Parameters
    ----------
    record : Record
        Readings holding every sensor of the influence line's channels.
    influence : InfluenceLine
        Calibrated (:func:`~bwim.wim.calibrate_influence_line`) or from the FE model.
    passage : Passage, optional
        The vehicle's speed, lane, axle spacings and delay; default the record's (single)
        passage.
    groups : sequence of sequence of int, optional
        Axle groups (indices from 0, every axle once) whose axles share the group's weight
        equally, e.g. ``group_axles(passage)``; default every axle on its own.
    lane_tolerance : float
        The vehicle's lane may differ from the line's by at most this much, m.
    limits : Limits, optional
        Plausibility thresholds of the weights (default :class:`Limits`).
    max_residual : float
        A relative residual above this is ``residual_high``: the readings are not the
        passage's vehicle on this line (a wrong passage or time axis, swapped channels,
        readings in other units, a second vehicle).

    Returns
    -------
    StaticWeights
    """
    require_instance("record", record, Record)
    if not isinstance(influence, InfluenceLine):
        raise InputError(f"influence must be an InfluenceLine, got {type(influence).__name__}")
    if passage is None:
        if len(record.passages) != 1:
            raise InputError(
                f"the record has {len(record.passages)} passages; Moses' algorithm needs the "
                "passage (speed, axle spacings) of one vehicle: pass passage=")
        passage = record.passage
    else:
        require_instance("passage", passage, Passage)
    tol = require_finite("lane_tolerance", lane_tolerance)
    if abs(passage.lane - influence.lane) > tol:
        raise InputError(
            f"the vehicle is in lane {passage.lane:g} m but the influence line is for lane "
            f"{influence.lane:g} m (lane_tolerance {tol:g} m)")

    readings = read_channels(record, influence.channels)
    pos = passage.axle_x(record.time)  # (n_t, n_axles)
    lo, hi = influence.support
    used = ((pos > lo) & (pos < hi)).any(axis=1)
    n_ax = passage.n_axles
    ag = group_share(groups, n_ax)  # axle weight = share @ group weight
    groups, share = ag.groups, ag.share
    n_unknown = len(groups)
    if used.sum() < n_unknown:
        raise InputError(
            f"only {int(used.sum())} samples of the record have an axle on the influence "
            f"line ({lo:g} … {hi:g} m); the record must cover the crossing")
    M = influence.at(pos[used])  # (n_w, n_axles, n_channels)
    meas = readings[used]
    scale = np.abs(influence.ordinates).max(axis=0)
    if np.any(scale == 0):
        raise InputError("the influence line is zero in a channel")
    Mg = np.einsum("kic,ig->kgc", M / scale, share)
    A = Mg.transpose(2, 0, 1).reshape(-1, n_unknown)  # channel-major rows
    b = (meas / scale).T.ravel()
    sol, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    if rank < n_unknown:
        raise InputError(
            f"the axle weights are not determined by this record (rank {rank} < "
            f"{n_unknown} unknowns): does the record cover the whole crossing?")
    weights = share @ sol
    fitted = np.einsum("kic,i->kc", M, weights)
    resid = float(np.linalg.norm((fitted - meas) / scale)
                  / max(np.linalg.norm(meas / scale), np.finfo(float).tiny))
    limits = Limits() if limits is None else limits
    condition = float(sv[0] / sv[-1])
    flags = weight_flags(weights, sol, limits)
    if not resid <= require_positive("max_residual", max_residual):
        flags.append("residual_high")
    h = influence.spacing  # an axle within one ordinate of the support's end is out
    if pos[0, 0] > lo + h:
        flags.append("truncated_start")
    if pos[-1, -1] < hi - h:
        flags.append("truncated_end")
    if condition > limits.condition:
        flags.append("ill_conditioned")
    flags_t = ordered_flags(flags)
    return StaticWeights(
        axle_weights=weights, time=record.time[used], measured=meas, fitted=fitted,
        channels=influence.channels, passage=passage, residual=resid,
        condition=condition, groups=groups, flags=flags_t, quality=quality_of(flags_t),
    )
