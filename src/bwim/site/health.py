"""Gauge health of one vehicle: a dead, stuck, clipped, reversed, gain-changed or
drifting gauge is found against the calibration and the other gauges, left out, and
named.

Contract
--------
* :func:`check_gauges` judges every channel of the calibration's lines
  (:class:`~bwim.wim.multirun.MultiRunCalibration`) in one vehicle's record, before it
  is weighed, in three steps:

  1. **Flat** (a dead gauge, or one stuck at a value): the channel's sample-to-sample
     variation in the record, ``std(diff(reading)) / √2``, is below :data:`FLAT_NOISE` ×
     its noise at rest in the calibration runs (``channel_noise``).  A working gauge and
     its logger always show their noise; a constant channel has none.  (The plain
     deviation, not a robust one: a logger whose noise is below its resolution repeats
     most samples, and a median of the steps would call it flat.)  No weighing is
     needed for this step.
  2. **Clipped** (a logger at its rail): the channel's readings hold its maximum (or
     minimum) over the record for ``L`` ≥ :data:`CLIP_RUN` consecutive samples, and a
     run that long is unlikely from the channel's own rate ``q`` of repeated samples at
     rest (no axle on the lines' support; the run itself left out):
     ``(n − 1) q^(L − 1) <`` :data:`CLIP_CHANCE` (``n`` samples).  A logger finer than
     its noise never repeats a sample, so a few held samples are a rail; a coarse one
     repeats many, and needs a long run.  Runs that touch the record's first or last
     sample count as well (a rail at the resting reading: the first sample is then the
     channel's extreme; :func:`bwim.io.read_logger`'s clipping check leaves those out).
  3. **Gain** (reversed polarity, a changed gain): the vehicle is weighed with the
     remaining channels (:func:`bwim.wim.weigh`, the readings undivided by any drift
     factor: a factor common to all gauges does not change their ratios), and each
     channel's gain ratio ``a_g = ⟨m_g, f_g⟩ / ⟨f_g, f_g⟩`` is taken between its
     offset-free reading ``m_g`` and its fitted static reading ``f_g`` over the samples
     with an axle on the lines' support.  A healthy deck spreads a vehicle's load
     smoothly across the gauges, so the ratios of healthy gauges lie on a smooth curve
     of the gauges' lateral position ``y`` (m; the channel order when a gauge has no
     ``y``): 1 everywhere when the vehicle drives where the calibration truck drove,
     tilted when it drives beside that path.  Each channel's ratio is compared with
     ``â_g``, the straight line through the other channels' ratios against ``y``
     (weighted least squares, weights ``snr_j²``).  With
     ``snr_g = rms(f_g) / σ_g`` (``σ_g`` the expected residual deviation of a vehicle of
     this weight, :meth:`~bwim.wim.multirun.MultiRunCalibration.error_covariance`), a
     channel is faulty when

     - its ratio is off: ``a_g / â_g ≤ 0`` (reversed, or no response) or
       ``|ln(a_g / â_g)| > ln(`` :data:`GAIN_TOLERANCE` ``)``, **and**
     - the difference is significant: ``|a_g − â_g| snr_g >`` :data:`SIGNIFICANCE`
       (the residual the gain error adds, in units of the residual deviation expected).

     **Drift** (a baseline that wanders during the record), in the same weighing: each
     channel's residual over the whole record (reading − offset − fitted static reading,
     the latter 0 with no axle on the support) has a least-squares straight line in time
     whose change from the first sample to the last is ``D_g``; the others' changes, in
     proportion to their signals (``D_j / rms(f_j)``, a line against ``y`` as above),
     predict ``D̂_g``; the channel drifts when ``|D_g − D̂_g| >`` :data:`DRIFT_NOISE` ×
     its noise at rest in the calibration runs (``channel_noise``).  A channel off by
     both tests is named by what explains its residual better (the larger sum of squares
     explained by a straight line in time or by a multiple of its fitted reading).

     The most significant gain fault (else the largest drift) is left out and the
     vehicle weighed again with the others, until every remaining channel passes.
* A faulty channel is **left out** and named in the flag ``gauge_fault:NAME``
  (:data:`FLAG_GAUGE_FAULT` + ``:`` + the channel's name): a soft flag, the weights of
  the healthy channels are kept with quality ``warning`` (:meth:`GaugeHealth.mark`).
* **Too few healthy channels**: when the healthy channels are not more than half of the
  calibration's (the comparison with "the others" needs a healthy majority), or fewer
  than two, the vehicle is refused with that reason (:attr:`GaugeHealth.reason`).
* **Another vehicle on the span** (``alone=False``; :func:`bwim.site.weigh_event` for a
  vehicle flagged ``multiple_presence``): the other vehicle's strain is no part of this
  vehicle's fit, so a gauge whose ratio is off may be faulty or may feel the other
  vehicle: the vehicle is refused with that reason, and no gauge is named for it
  (a flat or clipped gauge still is: no vehicle stops a gauge's noise or holds it at a
  rail).
* :func:`gain_ratios` gives the ratios ``a_g / â_g`` of step 3 for any weighing (e.g.
  the one a vehicle was weighed with: the day's table of gauge health,
  :mod:`bwim.batch.gauges`).
* With fewer than :data:`MIN_COMPARED` channels only the flat check is made; a weighing
  that fails here (a singular fit) leaves the gain check out, and the caller's own
  weighing decides.
* Units: readings in the logger's units; ratios dimensionless; ``y`` in m.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from bwim.errors import DATA_ERRORS, InputError
from bwim.plausibility import ordered_flags, quality_of
from bwim.records import Passage, Record
from bwim.site.health_kernels import (
    Comparison,
    comparison,
    held_extremes,
    residuals,
    step_noise,
)
from bwim.wim import Weighing
from bwim.wim.influence_line import read_channels
from bwim.wim.multirun import MultiRunCalibration
from bwim.wim.weigh import WeighingModel, weighing_model

__all__ = ["CLIP_CHANCE", "CLIP_RUN", "DRIFT_NOISE", "FAULT_KINDS", "FLAG_GAUGE_FAULT",
           "FLAT_NOISE", "GAIN_TOLERANCE", "MIN_COMPARED", "SIGNIFICANCE",
           "SILENT_CORRELATION", "GaugeFault", "GaugeHealth", "check_gauges", "gain_ratios",
           "restrict_lines"]

#: The flag of a faulty gauge, written ``gauge_fault:NAME``.
FLAG_GAUGE_FAULT = "gauge_fault"
#: Every kind of fault (:attr:`GaugeFault.kind`), in the order of the checks.
FAULT_KINDS = ("flat", "clipped", "silent", "reversed", "gain", "drift")
#: A channel whose noise in the record is below this fraction of its calibration noise
#: at rest is flat (dead or stuck).
FLAT_NOISE = 0.1
#: A channel's gain ratio against what the others predict may differ from 1 by up to
#: this factor (either way) before it is a gain fault (the clean vehicles' ratios against
#: it: tests/unit/test_site_health.py).
GAIN_TOLERANCE = 1.3
#: ... and the difference must add this many expected residual deviations (a clean
#: gauge's ratio is far more precise than one sample's deviation: the ratio averages
#: the whole crossing; this only keeps a gauge with no signal out of the test).
SIGNIFICANCE = 1.0
#: A faulty channel whose reading's correlation with its fitted static reading (over the
#: samples with an axle on the support) is below this, either sign, does not respond
#: to the load at all (a broken gauge whose logger channel still shows its noise).
SILENT_CORRELATION = 0.5
#: A channel held at its maximum or minimum for at least this many consecutive samples...
CLIP_RUN = 5
#: ... is clipped when a run that long is this unlikely from its own rate of repeated
#: samples at rest (``(n − 1) q^(run − 1)``: n samples, q the rate).
CLIP_CHANCE = 1e-3
#: A channel's baseline change over the record (the change of its residual's
#: least-squares line) may differ from what the other gauges show by up to this many
#: times its noise at rest in the calibration runs before it is a drift fault.
DRIFT_NOISE = 20.0
#: Channels needed to compare one channel's ratio with the others' (a line and a check).
MIN_COMPARED = 4


@dataclass(frozen=True, kw_only=True)
class GaugeFault:
    """One faulty channel.

    Attributes
    ----------
    gauge : str
        The channel's name.
    kind : str
        ``"flat"`` (dead or stuck: no noise), ``"clipped"`` (held at a rail),
        ``"silent"`` (noise but no response to the load: uncorrelated with its fit,
        :data:`SILENT_CORRELATION`), ``"reversed"`` (a negative ratio), ``"gain"`` (a
        ratio off by more than :data:`GAIN_TOLERANCE`) or ``"drift"`` (a baseline change
        beyond :data:`DRIFT_NOISE`).
    ratio : float
        Its gain ratio over what the other channels predict, ``a_g / â_g`` (nan for a
        flat, clipped or drifting channel).
    detail : str
        One line: what was measured.
    """

    gauge: str
    kind: str
    ratio: float
    detail: str

    @property
    def flag(self) -> str:
        return f"{FLAG_GAUGE_FAULT}:{self.gauge}"


@dataclass(frozen=True, kw_only=True, eq=False)
class GaugeHealth:
    """The outcome of :func:`check_gauges`.

    Attributes
    ----------
    faults : tuple of GaugeFault
        The faulty channels, in the order found.
    healthy : tuple of str
        The channels to weigh with, in the calibration's order.
    lines : MultiRunCalibration or None
        The calibration restricted to the healthy channels (the calibration itself when
        none is faulty); None when refused.
    reason : str
        Why the vehicle cannot be weighed ("" when it can).
    ratios : mapping of str to float
        Each healthy channel's gain ratio over what the others predict, ``a_g / â_g``,
        in the last comparison (empty when none was made: another vehicle on the span,
        too few channels, a failed weighing).
    model : WeighingModel or None
        The last comparison's weighing before its scale
        (:func:`bwim.wim.weigh.weighing_model` of the record, the passage and
        :attr:`lines`, with ``combine``): the healthy channels' weighing with any scale
        without making it again; None when no comparison weighed those channels.
    """

    faults: tuple[GaugeFault, ...]
    healthy: tuple[str, ...]
    lines: MultiRunCalibration | None
    reason: str = ""
    ratios: Mapping[str, float] = field(default_factory=dict)
    model: WeighingModel | None = None

    @property
    def usable(self) -> bool:
        return not self.reason

    @property
    def flags(self) -> tuple[str, ...]:
        """``gauge_fault:NAME`` for each faulty channel."""
        return tuple(f.flag for f in self.faults)

    def mark(self, weighing: Weighing) -> Weighing:
        """``weighing`` with this check's flags added and its quality recomputed (a flag
        outside the hard flags makes it a ``warning``)."""
        if not self.faults:
            return weighing
        flags = ordered_flags((*weighing.flags, *self.flags))
        return dataclasses.replace(weighing, flags=flags, quality=quality_of(flags))


def restrict_lines(lines: MultiRunCalibration, names: Sequence[str]) -> MultiRunCalibration:
    """The calibration with only the channels ``names`` (in the calibration's order):
    their lines, lateral slopes, residual deviations, covariance and noise.  The runs'
    misfit medians are kept (each channel's misfit is in units of its own deviation)."""
    wanted = set(names)
    keep = [k for k, c in enumerate(lines.channels) if c.name in wanted]
    if len(keep) != len(wanted):
        unknown = sorted(set(names) - {c.name for c in lines.channels})
        raise InputError(f"not channels of the calibration: {', '.join(unknown)}")
    if len(keep) == len(lines.channels):
        return lines
    idx = np.array(keep)
    line = dataclasses.replace(lines.line, ordinates=lines.line.ordinates[:, idx],
                               channels=tuple(lines.channels[k] for k in keep))
    slope = None if lines.lateral_slope is None else lines.lateral_slope[:, idx]
    return dataclasses.replace(
        lines, line=line, lateral_slope=slope, channel_std=lines.channel_std[idx],
        channel_covariance=lines.channel_covariance[np.ix_(idx, idx)],
        channel_noise=lines.channel_noise[idx])


def check_gauges(record: Record, passage: Passage, lines: MultiRunCalibration, *,
                 combine: str = "auto", alone: bool = True) -> GaugeHealth:
    """The health of every channel of ``lines`` for the vehicle of ``passage`` in
    ``record`` (see the module docstring); ``combine`` as :func:`bwim.wim.weigh`'s;
    ``alone=False``: another vehicle is on the span (a gauge that disagrees refuses the
    vehicle instead of being left out)."""
    names = [c.name for c in lines.channels]
    readings = read_channels(record, lines.channels)
    faults = list(_flat(readings, lines))
    faults += _clipped(readings, lines, record, passage, skip={f.gauge for f in faults})
    bad = {f.gauge for f in faults}
    ratios: dict[str, float] = {}
    model = None  # the last comparison's, when it weighed the healthy channels
    while len(names) - len(bad) >= MIN_COMPARED and 2 * len(bad) < len(names):
        fault, ratios, model = _worst(record, passage, lines,
                                      [n for n in names if n not in bad], combine, readings)
        if fault is None:
            break
        model = None
        if not alone:
            return GaugeHealth(
                faults=tuple(faults), healthy=tuple(n for n in names if n not in bad),
                lines=None,
                reason=f"another vehicle on the span and gauge {fault.gauge} disagrees "
                       f"with the others ({fault.detail}): its strain cannot be told from "
                       "a faulty gauge")
        faults.append(fault)
        bad.add(fault.gauge)
        ratios = {}
    healthy = tuple(n for n in names if n not in bad)
    if 2 * len(healthy) <= len(names) or len(healthy) < 2:
        shown = ", ".join(f"{f.gauge} ({f.kind})" for f in faults)
        return GaugeHealth(
            faults=tuple(faults), healthy=healthy, lines=None,
            reason=f"too few healthy gauges: {len(healthy)} of {len(names)}, faulty: {shown}")
    return GaugeHealth(faults=tuple(faults), healthy=healthy,
                       lines=restrict_lines(lines, healthy),
                       ratios=MappingProxyType(ratios), model=model)


def _flat(readings: np.ndarray, lines: MultiRunCalibration) -> list[GaugeFault]:
    """Step 1: channels without their noise."""
    if readings.shape[0] < 3:
        return []
    # numpy's std of each channel's steps alone (bwim.site.health_kernels.step_noise)
    noises = step_noise(readings).tolist()
    refs = lines.channel_noise.tolist()
    out = []
    for k, c in enumerate(lines.channels):
        ref = refs[k]
        noise = noises[k]
        if ref > 0 and noise < FLAT_NOISE * ref:
            out.append(GaugeFault(
                gauge=c.name, kind="flat", ratio=float("nan"),
                detail=f"noise {noise:.3g} against {ref:.3g} in the calibration runs "
                       "(dead or stuck)"))
    return out


def _positions(lines: MultiRunCalibration) -> np.ndarray:
    """Each channel's lateral position, m (its first sensor's ``y``); the channel order
    when any is unknown."""
    ys = [c.sensors[0].y for c in lines.channels]
    if any(y is None for y in ys):
        return np.arange(len(ys), dtype=float)
    return np.array(ys, dtype=float)


def _at_rest(record: Record, passage: Passage, lines: MultiRunCalibration) -> np.ndarray:
    """Samples with no axle of the vehicle on the lines' support (True at rest)."""
    x0, x1 = lines.support
    x = passage.axle_x(record.time)
    return ~np.any((x >= x0) & (x <= x1), axis=1)


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and length of each run of True in a boolean vector."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    return starts, np.flatnonzero(edges == -1) - starts


def _held(readings: np.ndarray) -> np.ndarray:
    """Per channel whether it holds its maximum or its minimum over the record for at
    least :data:`CLIP_RUN` consecutive samples (only those can be clipped)."""
    return held_extremes(readings, CLIP_RUN)


def _clipped(readings: np.ndarray, lines: MultiRunCalibration, record: Record,
             passage: Passage, *, skip: set[str]) -> list[GaugeFault]:
    """Step 2: channels held at their extreme for longer than chance explains."""
    out = []
    n = readings.shape[0]
    if n < CLIP_RUN + 1:
        return out
    held = _held(readings)
    rest_step = None
    for k, c in enumerate(lines.channels):
        if c.name in skip or not held[k]:
            continue
        if rest_step is None:
            rest = _at_rest(record, passage, lines)
            rest_step = rest[1:] & rest[:-1]
        y = readings[:, k]
        still = np.diff(y) == 0.0
        for label, extreme in (("maximum", y.max()), ("minimum", y.min())):
            starts, lengths = _runs(y == extreme)
            j = int(np.argmax(lengths))
            run = int(lengths[j])
            if run < CLIP_RUN:
                continue
            # the channel's own rate of repeated samples at rest, the held run left out
            usable = rest_step.copy() if np.count_nonzero(rest_step) >= 2 * CLIP_RUN \
                else np.ones(n - 1, dtype=bool)
            usable[max(int(starts[j]) - 1, 0):int(starts[j]) + run] = False
            repeat = float(still[usable].mean()) if usable.any() else 0.0
            chance = (n - 1) * repeat ** (run - 1)
            if chance < CLIP_CHANCE:
                out.append(GaugeFault(
                    gauge=c.name, kind="clipped", ratio=float("nan"),
                    detail=f"held at its {label} {extreme:.6g} for {run} consecutive "
                           f"samples (repeats a sample {repeat:.0%} of the time at rest: "
                           "a rail, clipped)"))
                break
    return out


def _worst(record: Record, passage: Passage, lines: MultiRunCalibration,
           names: list[str], combine: str, readings: np.ndarray
           ) -> tuple[GaugeFault | None, dict[str, float], WeighingModel | None]:
    """Step 3: the most significant gain or drift fault among ``names`` (None when every
    one passes or the weighing fails), every channel's ratio (empty when it fails) and
    the weighing's model (None when it could not be made).  ``readings``: those of every
    channel of ``lines`` (:func:`~bwim.wim.influence_line.read_channels`)."""
    sub = restrict_lines(lines, names)
    if sub is not lines:  # the columns of the channels kept
        kept = set(names)
        readings = readings[:, [k for k, c in enumerate(lines.channels) if c.name in kept]]
    try:
        model = weighing_model(record, passage, sub, combine=combine, readings=readings)
    except DATA_ERRORS:
        return None, {}, None
    try:
        w = model.weigh(scale_correction=False)
    except DATA_ERRORS:
        return None, {}, model
    if not np.isfinite(w.gvw) or w.gvw <= 0 or w.measured.shape[0] == 0:
        return None, {}, model
    trend = _trends(record, w, model.readings, model.on_support)
    # each channel's ratio and its significance, and its drift: the residual's change
    # over the record beyond what the others' show (their changes in proportion to their
    # signals, on a line across the deck), in units of its noise (0 without noise)
    c = _compare(w, sub, trend)
    if c is None:
        return None, {}, model
    ratios = _ratios(names, c)
    worst, score = None, SIGNIFICANCE
    drifting, excess = None, 1.0
    off = np.log(GAIN_TOLERANCE)
    significances = c.significance.tolist()
    changes = c.change.tolist()
    for g in range(len(names)):
        significance = significances[g]
        if names[g] in ratios and significance > score:
            ratio = ratios[names[g]]
            if ratio <= 0 or abs(np.log(ratio)) > off:  # off
                kind = ("silent" if abs(c.corr[g]) < SILENT_CORRELATION
                        else "reversed" if ratio < 0 else "gain")
                worst, score = GaugeFault(
                    gauge=names[g], kind=kind, ratio=ratio,
                    detail=f"gain {ratio:.2f} × what the other gauges predict "
                           f"({significance:.1f} residual deviations)"), significance
        change = changes[g]
        if change / DRIFT_NOISE > excess:
            drifting, excess = GaugeFault(
                gauge=names[g], kind="drift", ratio=float("nan"),
                detail=f"baseline change {trend[g]:.3g} over the record, "
                       f"{change:.0f} × its noise beyond what the other gauges "
                       "show"), change / DRIFT_NOISE
    if worst is None:  # a gain fault first: its residual has a trend too...
        worst = drifting
    elif drifting is not None and drifting.gauge == worst.gauge and \
            _explains_drift(record, w, model.readings, model.on_support,
                            names.index(worst.gauge)):
        worst = drifting  # ... unless a baseline change explains its residual better
    return worst, ratios, model


def _residuals(w: Weighing, readings: np.ndarray, on: np.ndarray) -> np.ndarray:
    """Each channel's residual over the whole record: reading (``readings``, the
    weighing's channels) − offset − fitted static reading (0 with no axle on the
    support), logger units, shape (n_t, n_channels).  ``on``: the samples ``w`` fitted
    (:attr:`~bwim.wim.weigh.WeighingModel.on_support` of its model; numpy's
    ``readings - offsets`` less the fitted readings there, the same numbers:
    :func:`bwim.site.health_kernels.residuals`)."""
    return residuals(readings, w.offsets, on, w.fitted)


def _trends(record: Record, w: Weighing, readings: np.ndarray, on: np.ndarray
            ) -> np.ndarray:
    """Each channel's residual's least-squares straight line in time: its change from the
    first sample to the last, logger units."""
    t = record.time - record.time.mean()
    return (t @ _residuals(w, readings, on)) / (t @ t) * float(record.time[-1] - record.time[0])


def _explains_drift(record: Record, w: Weighing, readings: np.ndarray, on: np.ndarray,
                    g: int) -> bool:
    """Whether channel ``g``'s residual is explained better by a straight line in time (a
    baseline change) than by a multiple of its fitted static reading (a gain error): the
    larger sum of squares explained by the one regressor."""
    r = _residuals(w, readings, on)[:, g]
    f = np.zeros_like(r)
    f[on] = w.fitted[:, g]
    t = record.time - record.time.mean()
    return bool((r @ t) ** 2 / (t @ t) > (r @ f) ** 2 / max(f @ f, 1e-300))


def _compare(w: Weighing, sub: MultiRunCalibration, trend: np.ndarray | None = None
             ) -> Comparison | None:
    """Each channel's gain ratio, correlation and signal against its fitted static
    reading over the samples with an axle on the support (None when degenerate), its
    ratio to the gain the others predict (the weighted straight line through their gains
    against their positions, weights ``snr²``, at its own position: nan when the others
    have no weight) and that difference's significance; with ``trend``, its drift beyond
    the others' (module docstring).  The correlation takes the shape alone (both
    centred): a channel that does not respond is uncorrelated with its fit.  One
    compiled call, numpy's numbers (:func:`bwim.site.health_kernels.comparison`)."""
    if w.measured.shape[0] == 0:
        return None
    return comparison(w.measured, w.fitted, sub.error_variance(w.gvw), _positions(sub),
                      trend, None if trend is None else sub.channel_noise)


def gain_ratios(weighing: Weighing, lines: MultiRunCalibration) -> dict[str, float]:
    """Each channel of ``weighing``'s gain ratio over what the other channels predict,
    ``a_g / â_g`` (step 3 of the module docstring), from its measured and fitted
    readings; ``lines`` holds (at least) the weighing's channels.  Empty with fewer than
    :data:`MIN_COMPARED` channels or a degenerate weighing; a channel whose prediction
    is not positive is left out."""
    names = [c.name for c in weighing.channels]
    if len(names) < MIN_COMPARED or not (np.isfinite(weighing.gvw) and weighing.gvw > 0):
        return {}
    sub = restrict_lines(lines, names)
    if [c.name for c in sub.channels] != names:  # columns in another order than the lines'
        return {}
    c = _compare(weighing, sub)
    if c is None:
        return {}
    return _ratios(names, c)


def _ratios(names: Sequence[str], c: Comparison) -> dict[str, float]:
    """Each channel's gain over its prediction, ``a_g / â_g``, where the prediction is
    positive."""
    ratio = c.ratio.tolist()
    return {names[g]: ratio[g] for g in np.flatnonzero(c.kept).tolist()}
