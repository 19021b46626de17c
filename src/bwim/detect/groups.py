"""A vehicle's axle groups chosen again among evenly spaced axles (model selection).

Contract
--------
* Input: a :class:`~bwim.detect.vehicle_fit.Problem`, a vehicle's axle times and speed
  (refined), the misfit threshold an axle must pass and the smallest spacing.
* The rest and the axles are fitted on the vehicle's span and the rest taken off: what
  is left of both detectors' readings (the second's moved back by the lag, each over its
  largest) is cut into **axle groups** where it dips below :data:`GROUP_DIP` of the lower
  neighbouring peak (:func:`segments`); a group may lie where its readings exceed
  :data:`GROUP_EXTENT` of its peak, :data:`SEGMENT_MARGIN` m more each side.  An axle the
  pursuit missed is found here; axles outside every group are dropped.
* Each group, the other groups' axles taken off too, is chosen among 1 …
  :data:`GROUP_AXLES` **evenly spaced** axles (spacings from the smallest to
  :data:`GROUP_SPACING`, positions on the window's sampling grid): the most axles such
  that each more lowers the misfit by the threshold and by :data:`LEVEL_GAIN` times the
  vehicle's residual per sample (:data:`RARE_GROUP` times more for a fourth: dynamic tyre
  forces beyond the calibration truck's make spurious splits cheaper), with every
  axle's amplitudes positive and seen by both detectors.  Fast: a hypothesis's misfit
  needs only the readings' correlation with one axle's response and that response's
  autocorrelation (:func:`explained`; evenly spaced axles' systems depend on their
  spacing alone: one inverse per spacing and window, :func:`evenly_explained`,
  :func:`group_counts`).  A group whose count stands keeps its refined times unless they
  fit worse by the threshold.  A segment that holds none of the vehicle's axles and where
  no single axle could fit (:func:`one_axle_may_fit`: the one-axle test made once over
  the window, widened by a bound on its rounding) is noise and skipped without changing
  any choice.
* Compiled: the vehicle's least squares on its window is numpy's (through
  :mod:`bwim.detect.vehicle_fit`); everything after it (the rest and the axles taken off,
  the responses on the samples, the segments, the correlations, every count's
  hypotheses and the choice) is one call of
  :func:`bwim.detect.group_kernels.choose_in_window` (numba), whose loops compute the
  same equations with numpy's numbers (its contract says how; one exception: a
  logarithm's last bit); :func:`segments`, :func:`one_axle_may_fit`,
  :func:`evenly_explained`, :func:`group_counts` and :func:`explained` call the same
  kernels.
* Misfits in level variances (see :mod:`bwim.detect.vehicle_fit`); times in s, distances
  in m, speeds in m/s.
"""

from __future__ import annotations

import math

import numpy as np

from .group_kernels import (
    choose_in_window,
    evenly_kernel,
    explained_kernel,
    group_choices,
    one_axle_points,
    response_on_samples,
    segment_bounds,
)
from .vehicle_fit import REACH, Problem, ridged_normal

__all__ = ["GROUP_AXLES", "GROUP_DIP", "GROUP_EXTENT", "GROUP_SPACING", "LEVEL_GAIN",
           "PEAK_FLOOR", "RARE_GROUP", "SEGMENT_MARGIN", "choose_groups", "evenly_explained",
           "explained", "group_counts", "hypotheses", "one_axle_may_fit", "responses",
           "segments", "templates"]

#: Largest spacing within an axle group (tandem, tridem) whose count is chosen again, m.
GROUP_SPACING = 2.2
#: Axle groups are cut where the detectors' readings dip below this share of the lower
#: neighbouring peak (under a response 1.2 m wide at half height: axles 1.3 m apart dip
#: to about 0.8, 2 m apart to about 0.3, 2.5 m apart to about 0.1).
GROUP_DIP = 0.25
#: An axle group spans where the readings exceed this share of its highest peak (an
#: axle's response falls to it about 0.65 m away) ...
GROUP_EXTENT = 0.3
#: ... and this much more each side, m.
SEGMENT_MARGIN = 0.3
#: Peaks of the readings lower than this share of the highest, or rising less above
#: their surroundings, do not start a group.
PEAK_FLOOR = 0.1
#: Most axles of a group.
GROUP_AXLES = 4
#: One more axle in a group must lower the misfit by this many times the vehicle's
#: residual per sample (the dynamic force of its tyres, beyond what the calibration
#: truck showed) ...
LEVEL_GAIN = 180.0
#: ... times this for a fourth axle in a group (groups of four are rare; a tridem's
#: dynamic forces make a fourth axle cheaper).
RARE_GROUP = 1.5


def templates(pb: Problem, v: float) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Per detector the weighted response of an axle passing detector 1 at sample 0, on
    the samples where it is not zero: (first sample offset, values, autocorrelation)."""
    return [(j0, h, np.correlate(h, h, mode="full")[h.size - 1:])
            for j0, h in responses(pb, v)]


def responses(pb: Problem, v: float) -> list[tuple[int, np.ndarray]]:
    """:func:`templates` without their autocorrelation: (first sample offset, values)
    (:func:`bwim.detect.group_kernels.response_on_samples`)."""
    return [response_on_samples(u, k, float(pb.w[c]), float(v), float(pb.fs),
                                float(pb.shift[c]))
            for c, (u, k, _) in enumerate(pb.grids)]


def choose_groups(pb: Problem, taus: np.ndarray, v: float, limit: float, min_sp: float,
                  span: tuple[float, float]) -> np.ndarray | None:
    """Each axle group of the vehicle (where the detectors' readings, with the rest and
    the other groups' axles fitted and taken off, stand out between dips: see
    :func:`segments`) chosen again among 1 … GROUP_AXLES evenly spaced axles at the
    vehicle's speed: the most axles such that each more lowers the misfit by ``limit``
    and both detectors see every axle.  Fast: with the other axles and the rest fitted and
    taken off, a group's misfit needs only the readings' correlation with one axle's
    response and that response's autocorrelation (on the window's sampling grid).  The new
    times, or None."""
    taus = np.sort(taus)
    lo = int(pb.t.searchsorted(span[0] - REACH / v))
    hi = int(pb.t.searchsorted(span[1] + (pb.shift[1] + REACH) / v, side="right"))
    # the window's rows (C order: the arrays numpy's products and the kernel read)
    y_all, rest_all = pb.stacked
    t, y, rest = pb.t[lo:hi], np.ascontiguousarray(y_all[:, lo:hi]), np.ascontiguousarray(
        rest_all[:, lo:hi])
    # both detectors' least squares as one stack of two (the same numbers as two)
    X = pb.both_atoms(v, t[:, None] - taus[None, :])[0]
    Mt, G = ridged_normal(np.concatenate([X, rest], axis=2))
    coef = np.linalg.solve(G, Mt @ y)
    st = pb.step  # hypotheses on every st-th sample
    (u0, k0, _), (u1, k1, _) = pb.grids
    # the rest taken off, the segments, their correlations and choices, compiled (see the
    # module contract)
    new, changed = choose_in_window(
        pb.t, lo, taus, y, rest, X, coef, u0, k0, u1, k1, pb.w, float(pb.shift[0]),
        float(pb.shift[1]), float(v), float(pb.fs), st, round(pb.shift[1] / v * pb.fs),
        round(SEGMENT_MARGIN / v * pb.fs), max(1, math.ceil(min_sp / v * pb.fs / st)),
        math.floor(GROUP_SPACING / v * pb.fs / st), float(pb.ratio), float(pb.bound),
        float(limit), GROUP_AXLES, LEVEL_GAIN, RARE_GROUP, GROUP_DIP, GROUP_EXTENT,
        PEAK_FLOOR)
    return new if changed else None


def one_axle_may_fit(pb: Problem, resid, tpl, auto, st: int, n_grid: int) -> np.ndarray:
    """Cumulative count over the grid points (``n_grid + 1``, from 0) of those where one
    axle might fit the vehicle's residual ``resid`` (per detector, on the window's rows)
    with amplitudes positive at both detectors in their gain ratio, as
    :func:`choose_groups` tests it on a segment holding none of the vehicle's axles
    (``tpl``: the :func:`templates`; ``auto``: their autocorrelations every ``st``-th
    sample).  A segment without such a point is skipped.  Computed once over the window,
    so with rounding of its own: the test is widened by a bound on that rounding and only
    ever lets more segments through to the exact test."""
    return one_axle_points(np.ascontiguousarray(resid, dtype=float), tpl[0][1], tpl[1][1],
                           np.array([tpl[0][0], tpl[1][0]]), float(auto[0][0]),
                           float(auto[1][0]), int(st), int(n_grid), float(pb.ratio),
                           float(pb.bound))


def segments(pb: Problem, local, v: float, margin: int, st: int) -> list[tuple[int, int]]:
    """The vehicle's axle groups in its window: (first, last) grid points where a group's
    axles may be.  Both detectors' local readings (the second's moved back by the lag,
    each over its largest) are added; groups are cut where their sum dips below GROUP_DIP
    of the lower of the two peaks beside, and span where the sum exceeds GROUP_EXTENT of
    their highest, ``margin`` samples more each side (not past a cut)."""
    return [tuple(x) for x in segment_bounds(
        np.ascontiguousarray(local, dtype=float), pb.grids[0][1], pb.grids[1][1],
        round(pb.shift[1] / v * pb.fs), int(margin), int(st), GROUP_DIP, GROUP_EXTENT,
        PEAK_FLOOR).tolist()]


def hypotheses(first: int, last: int, k: int, s_min: int, s_max: int) -> np.ndarray:
    """Sample indices (n_hyp, k) of k evenly spaced axles between ``first`` and ``last``
    (spacings s_min … s_max samples)."""
    if k == 1:
        return np.arange(first, last + 1)[:, None]
    start, sp = np.nonzero(np.arange(first, last + 1)[:, None]
                           + (k - 1) * np.arange(s_min, s_max + 1)[None, :] <= last)
    return (first + start)[:, None] + (s_min + sp)[:, None] * np.arange(k)[None, :]


def evenly_explained(lengths: np.ndarray, k: int, s_min: int, s_max: int, corr, auto
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`hypotheses` ``(0, L - 1, k, s_min, s_max)`` (k ≥ 2) of every segment of
    ``lengths`` grid points, whose correlations ``corr`` (per detector) lie end to end,
    and what :func:`explained` gives for each: ``(hyp, owner, gained, amps)``, ``hyp`` in
    each segment's own grid points, ``owner`` its segment (ascending; in a segment the
    order of :func:`hypotheses`).  Evenly spaced axles' systems depend on their spacing
    alone (the autocorrelation at multiples of it), so each spacing's is inverted once
    and applied to every start of every segment (the numbers of solving each, to
    rounding)."""
    hyp, owner, gained, amps, _ = evenly_kernel(
        np.asarray(lengths, dtype=np.int64), int(k), int(s_min), int(s_max),
        *_floats(corr), *_floats(auto), 1.0, np.inf)
    return hyp, owner, gained, amps


def group_counts(pb: Problem, corr, auto, lengths: np.ndarray, outside, energies,
                 limit: float, n_samples: int, s_min: int, s_max: int) -> list:
    """Each segment's choice (:func:`choose_groups`): ``(misfit removed, grid points)``
    of the most evenly spaced axles such that each more lowers the misfit by ``limit``
    and by LEVEL_GAIN times the residual per sample with one axle fewer (``(outside +
    (energy - removed)) / n_samples``: the vehicle's residual outside the segment, the
    segment's readings' energy), every axle positive and seen by both detectors; None
    where no single axle is.  ``corr``: the segments' correlations end to end; compiled
    (:func:`bwim.detect.group_kernels.group_choices`: one segment after the other, each
    spacing's inverse made once)."""
    gained, counts, pos = group_choices(
        *_floats(corr), np.asarray(lengths, dtype=np.int64), *_floats(auto),
        np.asarray(outside, dtype=float), np.asarray(energies, dtype=float), float(limit),
        float(n_samples), int(s_min), int(s_max), float(pb.ratio), float(pb.bound),
        GROUP_AXLES, LEVEL_GAIN, RARE_GROUP)
    return [None if k == 0 else (float(g), p[:k].copy())
            for g, k, p in zip(gained.tolist(), counts.tolist(), pos, strict=True)]


def explained(hyp: np.ndarray, corr, auto) -> tuple[np.ndarray, np.ndarray]:
    """Misfit each hypothesis removes (both detectors) and its amplitudes (n_hyp, k, 2)."""
    return explained_kernel(np.ascontiguousarray(hyp, dtype=np.int64), *_floats(corr),
                            *_floats(auto))


def _floats(pair) -> tuple[np.ndarray, np.ndarray]:
    """Both detectors' arrays as float64 in C order (the kernels' one signature)."""
    return (np.ascontiguousarray(pair[0], dtype=float),
            np.ascontiguousarray(pair[1], dtype=float))
