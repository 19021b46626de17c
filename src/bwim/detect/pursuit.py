"""Axles from two wide-response detectors by sparse deconvolution.

Contract
--------
* Input: the two detector channels of a record (and, when the responses were learned
  with gauges, those gauges) and their learned responses
  (:class:`~bwim.detect.response.LearnedResponses`).  Model of each vehicle's axles,
  both detectors at once::

      y_d(t) = Σ_i A_id K_d(v (t − τ_i) − D_d) + n_d(t) + e,   D_1 = 0, D_2 = D,

  ``τ_i`` the time axle ``i`` passes detector 1, ``v`` the vehicle's speed, ``A_id`` its
  amplitude at each detector (free: an axle's dynamic force differs at the two instants
  it passes them), ``n_d`` the rest: with gauges ``β_d b_d(t) + c_d + s_d t`` (the span's
  bending as the gauges read it, an offset and a drift, all fitted); without, readings
  and model are high-passed in space (:func:`~bwim.detect.response.high_pass` over
  :data:`~bwim.detect.response.HIGH_PASS` m of travel at the record's first speed
  estimate).  Each channel is weighted by its level
  (:attr:`~bwim.detect.response.DetectorResponse.level`: what the learned response
  missed of the calibration truck's axles, or the noise if more): misfits below are in
  these units ("level variances").
* An axle is seen by **both** detectors: its amplitudes, in the detectors' learned gain
  ratio ``ρ``, may differ by the dynamics only: ``|ln(A_2 / (ρ A_1))|`` at most
  :data:`RATIO_SPREADS` times the spread the calibration runs showed (at least
  :data:`MIN_RATIO_BOUND`); each reaches ``min_height`` of that detector's largest.
  What one detector shows without the other (a tyre force's dynamics while it passes) is
  not an axle.  The detectors never "disagree" on the count: one fit counts for both.
* Steps.  (1) A first speed from the lag of the band-passed detectors (less their
  bending).  (2) **Orthogonal matching pursuit** over the record: the axle whose
  response, in the gain ratio at both detectors (the second's allowed
  :data:`SPEED_SLACK` of the lag off), best matches the residual is added and all
  amplitudes refitted, while the misfit falls by more than ``snr_threshold²`` and
  :data:`PURSUIT_SHARE` of the strongest axle's fall.  (3) Axles more than
  ``max_axle_spacing`` apart start new vehicles; a vehicle's speed is the median of its
  axles' own lags.  (4) Per vehicle: axles lowering the misfit by less than the
  **threshold** (``snr_threshold²`` and :data:`GAIN_SHARE` of the strongest axle's fall)
  are pruned, times and speed refined (Levenberg–Marquardt on the variable projection:
  amplitudes and rest by linear least squares inside, analytic Jacobian after Kaufman),
  axles one detector does not see pruned.  (5) **Axle groups chosen again**: with the
  rest fitted and taken off, both detectors' readings (the second's moved back by the
  lag) are cut into groups where they dip below :data:`GROUP_DIP` of the lower
  neighbouring peak, over the vehicle's whole span (an axle the pursuit missed is found
  here); each group is chosen among 1 … :data:`GROUP_AXLES` evenly spaced axles
  (spacings from the smallest to :data:`GROUP_SPACING`, all positions on the window's
  sampling grid: a group's misfit needs only the readings' correlation with one axle's
  response and that response's autocorrelation), the most axles such that each more
  lowers the misfit by the threshold and by :data:`LEVEL_GAIN` times the vehicle's
  residual per sample (dynamic tyre forces beyond the calibration truck's make spurious
  splits cheaper), and both detectors see
  every axle; a group whose count stands keeps its refined times.  (6) The vehicle is
  refined again, then axles closer than the smallest spacing (the weaker goes), below
  the threshold, lower than ``min_height`` or unseen by one detector are dropped one by
  one, refining after each.  The smallest spacing is the larger of ``min_axle_spacing``
  and :data:`MIN_SPACING_WIDTH` of the responses' width (Sparrow's limit: closer equal
  peaks sum to one peak): closer peaks are one axle whose force changed while it passed.
* Confidence of a vehicle = ``c_snr × c_both``: ``c_snr = clip(√Δ / (2 snr_threshold),
  0.5, 1)`` with ``Δ`` the smallest misfit reduction (level variances) of its axles;
  ``c_both`` the mean over its axles of ``exp(−½ (ln(A_2 / (ρ A_1)) / (2 s))²)``, ``s``
  the learned spread (at least ``MIN_RATIO_BOUND / RATIO_SPREADS``), at least 0.5.
* Compiled (:mod:`bwim.detect.fit_kernels`, numba): the pursuit's whole loop
  (:func:`~bwim.detect.fit_kernels.pursuit_loop`: the steps of :class:`_Matcher` and
  :class:`_Pursuit`, the same numbers) and the refinements' least squares
  (:mod:`bwim.detect.vehicle_fit`): the same equations, numbers agreeing with a numpy
  version's to rounding.  A vehicle's few axles are tested in Python floats (numpy's
  numbers: :meth:`~bwim.detect.vehicle_fit.Problem.log_ratios`).
* Times in s, distances in m, speeds in m/s.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .assemble import VehicleEstimate
from .fit_kernels import best_match, matcher_atom, pursuit_loop, pursuit_trial
from .groups import choose_groups
from .response import LearnedResponses, band_pass, xcorr_lag
from .signals import median
from .vehicle_fit import (
    MIN_RATIO_BOUND,
    RATIO_SPREADS,
    Problem,
    Solution,
    VehicleFit,
    make_problem,
    refine,
    solution,
)

__all__ = ["EXCLUDE", "FIRST_LM", "GAIN_SHARE", "MAX_AXLES", "MIN_SPACING_WIDTH",
           "PURSUIT_SHARE", "SPEED_SLACK", "pursue_axles"]

#: An upper bound on the axles of one record.
MAX_AXLES = 40
#: In the pursuit, the second detector's atom of an axle may be off the first speed
#: estimate by this share of the lag between the detectors.
SPEED_SLACK = 0.08
#: The pursuit stops at an axle lowering the misfit by less than this share of what the
#: record's strongest did (the axle groups are chosen again after).
PURSUIT_SHARE = 0.1
#: An axle must lower the misfit by this share of what the record's strongest axle did.
GAIN_SHARE = 0.02
#: Axles closer than this share of the responses' width (at half height) are one axle
#: whose force changed while it passed: two equal Gaussian responses of standard
#: deviation σ closer than 2σ = FWHM / √(2 ln 2) ≈ 0.85 FWHM add up to a single peak
#: with no dip between them (Sparrow's resolution limit), so no fit of their sum tells
#: them from one axle whose tyre force changed as it crossed (stop 35: at 0.8, two
#: trucks of the four bench days had a group read with one axle more, about 1 m apart).
MIN_SPACING_WIDTH = float(1.0 / np.sqrt(2.0 * np.log(2.0)))
#: A new axle is looked for no closer to one already found than this share of the
#: smallest spacing (the refinement moves them apart).
EXCLUDE = 0.5
#: Levenberg–Marquardt iterations of a vehicle's first refinement (which sets the speed
#: at which its axle groups are chosen).
FIRST_LM = 4


def _speed(y: np.ndarray, fs: float, distance: float, speed_range: tuple[float, float],
           sign: np.ndarray) -> float | None:
    """Speed from the lag of the band-passed detectors (made positive by the responses'
    ``sign``), None if they do not correlate in the speed range."""
    z = band_pass(y, fs) * sign
    lag = xcorr_lag(z[:, 0], z[:, 1], np.floor(distance / speed_range[1] * fs),
                    np.ceil(distance / speed_range[0] * fs))
    return None if lag is None else distance / (lag / fs)


class _Matcher:
    """The axle time whose atoms (both detectors, one amplitude in their gain ratio) best
    match a residual (all samples) at the speed ``v``; the second detector's atom may be
    up to ``slack`` samples off that speed.  The atoms are made once (the speed is fixed
    while the pursuit runs); the residual is read from a buffer padded by :attr:`pad`
    zeros each side (every atom's reach), the times already taken from a mask kept up to
    date (:meth:`exclude`).  The choice is compiled
    (:func:`~bwim.detect.fit_kernels.best_match`: the same equations as
    :meth:`best` states)."""

    def __init__(self, pb: Problem, v: float, slack: int, min_gap: float):
        self.pb, self.v, self.slack = pb, v, slack
        bounds = []
        for c, (u, _, _) in enumerate(pb.grids):
            d = pb.shift[c]
            bounds.append((math.floor((u[0] + d) / v * pb.fs) - 1,
                           math.ceil((u[-1] + d) / v * pb.fs) + 1))
        # the atoms as the kernel reads them: end-padded rows, first offsets, lengths;
        # each np.interp(v (m_lo … m_hi) / fs − d, u, k, left=0, right=0) × w_d (× the
        # gain ratio at the second), compiled (fit_kernels.matcher_atom: the same numbers)
        self._atoms = np.zeros((2, max(hi - lo + 1 for lo, hi in bounds)))
        self.parts = []
        energy = 0.0
        for c, (u, k, _) in enumerate(pb.grids):
            m_lo, m_hi = bounds[c]
            atom = np.empty(m_hi - m_lo + 1)  # an array of its own, as np.interp's (BLAS)
            matcher_atom(u, k, float(pb.w[c] * (pb.ratio if c else 1.0)), float(v),
                         float(pb.fs), float(pb.shift[c]), m_lo, atom)
            energy += float(atom @ atom)
            self.parts.append((m_lo, m_hi, atom))
            self._atoms[c, :atom.size] = atom
        self.energy = max(energy, 1e-300)
        self.pad = max(0, *(-m_lo for m_lo, _ in bounds), *(m_hi for _, m_hi in bounds))
        self.gap = min_gap / v
        self.excluded = np.zeros(pb.t.size, dtype=bool)
        self._lo = np.array([m_lo for m_lo, _ in bounds], dtype=np.int64)
        self._len = np.array([m_hi - m_lo + 1 for m_lo, m_hi in bounds], dtype=np.int64)
        self._corr = np.empty((2, pb.t.size))
        self._picked = np.zeros(2, dtype=np.int64)

    def exclude(self, tk: float) -> None:
        """No new axle within ``min_gap`` m of travel of the time ``tk`` (t ascending: a
        slice holds them)."""
        t, gap = self.pb.t, self.gap
        a = max(int(t.searchsorted(tk - gap)) - 1, 0)
        b = int(t.searchsorted(tk + gap, side="right")) + 1
        self.excluded[a:b] |= np.abs(t[a:b] - tk) < gap

    def best(self, res: np.ndarray) -> tuple[float, float]:
        """The best new axle for the residual ``res`` (2, pad + n_t + pad; zeros in the
        pads), not where excluded: its time at detector 1 and the time the second
        detector's atom says (both at detector 1 for the speed ``v``)."""
        # corr_d[m] = Σ_i res[m + m_lo + i] atom[i] for every sample m (zero beyond the
        # record); the score max(corr_1 + max(corr_2 within ±slack), 0)² / energy, 0
        # where excluded; its argmax m (the first of equals) and where the second
        # detector's best within ±slack of m was (the first of equals)
        best_match(np.ascontiguousarray(res, dtype=float), self._atoms, self._lo, self._len,
                   self.pad, self.slack, self.energy, self.excluded, self._corr, self._picked)
        t = self.pb.t
        return float(t[self._picked[0]]), float(t[self._picked[1]])


def pursue_axles(record_time: np.ndarray, y: np.ndarray, learned: LearnedResponses, *,
                 speed_range: tuple[float, float], min_axle_spacing: float,
                 max_axle_spacing: float, snr_threshold: float, min_height: float,
                 gauges: np.ndarray | None = None) -> list[VehicleEstimate]:
    """Vehicles of one record (see the module docstring).

    ``y`` (n_t, 2) are the two detector channels (in the responses' order), ``gauges``
    (n_t, n_gauges) the channels of ``learned.gauges`` (None: high-pass), ``record_time``
    their times.  Returns the vehicles' estimates (empty when no axle stands out)."""
    t = np.asarray(record_time, dtype=float)
    y = np.asarray(y, dtype=float)
    fs = 1.0 / median(np.diff(t))
    if not (learned.gauges and gauges is not None):
        gauges = None
    if gauges is not None:
        g = np.asarray(gauges, dtype=float)
        g = g - np.add.reduce(g, axis=0) / g.shape[0]  # g.mean(axis=0): its sum / count
        bend = np.column_stack([g @ r.bending for r in learned.responses])
        y0 = y - bend
    else:
        y0 = y
    v0 = _speed(y0, fs, learned.distance, speed_range,
                np.array([r.sign for r in learned.responses]))
    if v0 is None:
        return []
    pb = make_problem(t, y, gauges, learned, v0, fs=fs,
                      bending=None if gauges is None else bend)
    thr2 = snr_threshold**2
    widths = [float(r.fwhm) for r in learned.responses]  # their mean as np.mean makes it
    min_sp = max(min_axle_spacing, MIN_SPACING_WIDTH * ((0.0 + widths[0] + widths[1]) / 2))
    lag = learned.distance / v0
    slack = math.ceil(SPEED_SLACK * lag * fs)
    matcher = _Matcher(pb, v0, slack, EXCLUDE * min_sp)
    omp = _Pursuit(pb, v0, matcher.pad)
    first = omp.pursue(matcher, thr2, min_height)
    order = np.argsort(omp.taus)
    taus = omp.taus[order]
    lags = lag + omp.taus2[order] - taus  # each axle's own lag between the detectors
    if taus.size == 0:
        return []
    limit = max(thr2, GAIN_SHARE * first)
    out = []
    # vehicles: the axles between gaps longer than max_axle_spacing (index ranges)
    times = taus.tolist()
    cuts = [0, *(i + 1 for i, (a, b) in enumerate(itertools.pairwise(times))
                 if (b - a) * v0 > max_axle_spacing), len(times)]
    # each vehicle's axles may lie between the midpoints to its neighbours' (the pursuit
    # may have missed some: the axle groups are found again there)
    edges = [t[0], *(0.5 * (times[i - 1] + times[i]) for i in cuts[1:-1]), t[-1]]
    for k, (a, b) in enumerate(itertools.pairwise(cuts)):
        # the vehicle's speed from its axles' lags
        v = learned.distance / median(lags[a:b])
        if not speed_range[0] <= v <= speed_range[1]:
            v = v0
        veh = _vehicle(pb, taus[a:b], v, limit, min_sp, min_height, snr_threshold,
                       (edges[k], edges[k + 1]))
        if veh is not None:
            out.append(veh)
    return out


def _acceptable(pb: Problem, amps: np.ndarray, min_height: float) -> bool:
    """Whether the last axle of ``amps`` reaches ``min_height`` of the largest amplitude
    at both detectors (the gain ratio is checked on the refined vehicle: merged peaks
    explained in part share their amplitudes unevenly between the detectors)."""
    # relative(amps)[-1].min() >= min_height for the last row alone, in Python floats (the
    # same IEEE operations; a NaN fails both tests)
    top = amps.max(axis=0).tolist()
    return all(a / (m if m > 0 else 1.0) >= min_height
               for a, m in zip(amps[-1].tolist(), top, strict=True))


class _Pursuit:
    """Orthogonal matching pursuit over the whole record: the axles' responses with each
    detector's rest projected out, their Gram matrix and least-squares amplitudes kept up
    to date as axles are added.  The residual (:attr:`res`, 2 × n_t) sits in a buffer
    with ``pad`` zeros each side (what :class:`_Matcher` reads).  The responses and their
    Gram matrix live in buffers sized for MAX_AXLES + 1 axles: a trial (compiled:
    :func:`~bwim.detect.fit_kernels.pursuit_trial`) writes the new axle's row after the
    accepted ones, an accepted axle keeps it."""

    def __init__(self, pb: Problem, v: float, pad: int = 0):
        self.pb, self.v, self.pad = pb, v, pad
        self.taus = np.zeros(0)  # at detector 1
        self.taus2 = np.zeros(0)  # the second detector's, less D / v
        y = []
        for c in range(2):
            Q = pb.q_rest[c]
            # no rest (Q n_t × 0): less zeros, the readings themselves
            y.append(pb.y[:, c] - Q @ (Q.T @ pb.y[:, c]) if Q.shape[1] else pb.y[:, c])
        self.Q = np.array(pb.q_rest)  # (2, n_t, k)
        self._Qt = np.ascontiguousarray(self.Q.transpose(0, 2, 1))  # as the kernel reads
        self.y = np.array(y)[..., None]  # (2, n_t, 1)
        n = pb.t.size
        # the axles' projected responses, one per row, and their Gram matrix (no ridge):
        # the first taus.size rows (and columns) are the accepted axles'
        self._Xt = np.empty((2, MAX_AXLES + 1, n))
        self._G = np.empty((2, MAX_AXLES + 1, MAX_AXLES + 1))
        self._t = np.ascontiguousarray(pb.t, dtype=float)
        self._buffer = np.zeros((2, n + 2 * pad))
        self._buffer[:, pad:pad + n] = self.y[..., 0]
        self.chi = float(np.add.reduce(np.column_stack(y) ** 2, axis=None))  # np.sum's

    @property
    def res(self) -> np.ndarray:
        """The residual, (2, pad + n_t + pad), zeros in the pads."""
        return self._buffer

    def trial(self, tk: float, tk2: float):
        """Amplitudes (n + 1, 2; the new axle last), misfit and state with an axle at
        ``tk`` added (at ``tk2`` for the second detector).  The Gram matrix grows by the
        new response's products (the same numbers as made whole, to rounding); the ridge
        of :func:`~bwim.detect.vehicle_fit.ridged_normal`."""
        p = self.taus.size
        pb = self.pb
        amps, res = np.empty((p + 1, 2)), np.empty((self._t.size, 2))
        g = pb.table
        # the atoms (less their projection on the rest) as row p of the responses, the
        # Gram matrix's row and column p, (G + ridge) a = Xᵀy, res = y − X a
        chi = pursuit_trial(g.scalars, g.first, g.values, self._t, float(tk), float(tk2),
                            float(self.v), self._Qt, self.y[..., 0], self._Xt, self._G, p,
                            amps, res)
        return amps, chi, res

    def pursue(self, matcher: _Matcher, thr2: float, min_height: float) -> float:
        """The pursuit (compiled, :func:`~bwim.detect.fit_kernels.pursuit_loop`): up to
        2 MAX_AXLES times the matcher's best new axle (:meth:`_Matcher.best`) and its
        :meth:`trial`; stop when it lowers the misfit by less than ``thr2`` and
        PURSUIT_SHARE of the strongest fall so far, or MAX_AXLES are taken; else no new
        axle near it again (:meth:`_Matcher.exclude`) and, when it reaches
        ``min_height`` at both detectors (:func:`_acceptable`), it is taken
        (:meth:`accept`).  Returns the strongest fall."""
        taus, taus2, out = np.empty(MAX_AXLES), np.empty(MAX_AXLES), np.zeros(2)
        g = self.pb.table
        m = matcher
        count = pursuit_loop(g.scalars, g.first, g.values, self._t, float(self.v), self._Qt,
                             self.y[..., 0], self._Xt, self._G, self._buffer, self.pad,
                             m._atoms, m._lo, m._len, m.slack, m.energy, m.excluded, m._corr,
                             m.gap, self.chi, thr2, PURSUIT_SHARE, min_height, MAX_AXLES,
                             2 * MAX_AXLES, taus, taus2, out)
        self.taus = np.concatenate((self.taus, taus[:count]))
        self.taus2 = np.concatenate((self.taus2, taus2[:count]))
        self.chi = float(out[1])
        return float(out[0])

    def accept(self, tk: float, tk2: float, chi: float, state) -> None:
        """Keep the axle of the last :meth:`trial` (``state``: its residual)."""
        res = state
        self._buffer[:, self.pad:self.pad + res.shape[0]] = res.T
        self.taus = np.concatenate((self.taus, [tk]))
        self.taus2 = np.concatenate((self.taus2, [tk2]))
        self.chi = chi


def _without(taus: np.ndarray, i: int) -> np.ndarray:
    """``taus`` (1-D) without its ``i``-th value: ``np.delete(taus, i)``, by slices."""
    return np.concatenate((taus[:i], taus[i + 1:]))


def _argmin(values: list[float]) -> int:
    """``np.argmin`` of a few Python floats: the first NaN, else the first smallest."""
    best = 0
    for i, x in enumerate(values):
        if x != x:
            return i
        if x < values[best]:
            best = i
    return best


def _weakest(weak: list[bool], gains: list[float]) -> int:
    """``np.where(weak, gains, np.inf).argmin()`` (:func:`_argmin`)."""
    return _argmin([g if w else math.inf for w, g in zip(weak, gains, strict=True)])


def _drop_close(fit: VehicleFit, min_sp: float) -> np.ndarray | None:
    """The times without the weaker of the closest pair closer than ``min_sp``; None if
    none is that close."""
    if fit.taus.size < 2:
        return None
    taus, v = fit.taus.tolist(), fit.v
    d = [(b - a) * v for a, b in itertools.pairwise(taus)]  # numpy's operations
    i = _argmin(d)
    if d[i] >= min_sp:
        return None
    gains = fit.gains.tolist()
    weaker = i if gains[i] < gains[i + 1] else i + 1
    return _without(fit.taus, weaker)


def _low(amps: np.ndarray, min_height: float) -> list[bool]:
    """Per axle whether its lower share of a detector's largest amplitude is below
    ``min_height``: ``np.minimum(s[:, 0], s[:, 1]) < min_height``, ``s =
    relative(amps)``, in Python floats (the same IEEE operations; a NaN makes the
    largest NaN, divided by 1, and the share's minimum NaN: not low)."""
    rows = amps.tolist()
    tops = []
    for c in range(2):
        col = [r[c] for r in rows]
        top = max(col) if col else 0.0
        if math.isnan(sum(col)) and any(x != x for x in col):
            top = math.nan
        tops.append(top if top > 0 else 1.0)
    out = []
    for a0, a1 in rows:
        s0, s1 = a0 / tops[0], a1 / tops[1]
        out.append(s0 == s0 and s1 == s1 and (s0 < min_height or s1 < min_height))
    return out


def _vehicle(pb: Problem, taus: np.ndarray, v: float, limit: float, min_sp: float,
             min_height: float, snr_threshold: float, span: tuple[float, float]
             ) -> VehicleEstimate | None:
    """A first refinement (the speed), the axle groups chosen again in ``span`` (record
    times at detector 1), the final refinement and backward check; the vehicle's
    estimate."""
    pruned, sol = _prune(pb, taus, v, limit)
    fit = refine(pb, pruned, v, FIRST_LM, start=sol)
    kept, sol = _prune(pb, fit.taus, fit.v, limit, both=True, start=fit.solution)
    grouped = choose_groups(pb, kept, fit.v, limit, min_sp, span)
    if grouped is not None and grouped.size == 0:
        return None  # every axle lay outside the axle groups of its readings: noise
    if grouped is not None:
        fit = refine(pb, grouped, fit.v)
    elif kept.size < fit.taus.size:
        fit = refine(pb, kept, fit.v, start=sol)
    for _ in range(MAX_AXLES):
        close = _drop_close(fit, min_sp)
        if close is not None:
            fit = refine(pb, close, fit.v, start=fit.solution)
            continue
        gains = fit.gains.tolist()
        weak = [g < limit or low or not seen for g, low, seen in zip(
            gains, _low(fit.amps, min_height), pb.seen(fit.amps), strict=True)]
        if any(weak) and fit.taus.size > 1:
            fit = refine(pb, _without(fit.taus, _weakest(weak, gains)), fit.v,
                         start=fit.solution)
            continue
        break
    ratios = pb.log_ratios(fit.amps)
    if fit.taus.size == 0 or not any(abs(r) <= pb.bound for r in ratios):  # seen by both
        return None
    snr = math.sqrt(max(float(fit.gains.min()), 0.0))  # (correctly rounded, as numpy's)
    c_snr = min(max(snr / (2.0 * snr_threshold), 0.5), 1.0)  # np.clip's (a NaN stays)
    lr = np.minimum(np.abs(np.array(ratios)), 1e3)
    s = max(pb.spread, MIN_RATIO_BOUND / RATIO_SPREADS)
    c_both = max(0.5, float(np.mean(np.exp(-0.5 * (lr / (2 * s)) ** 2))))
    det_times = np.column_stack([fit.taus, fit.taus + pb.shift[1] / fit.v])
    rel = np.maximum(fit.amps[:, 0], 0.0) + np.maximum(fit.amps[:, 1], 0.0) / pb.ratio
    return VehicleEstimate(times=fit.taus, speed=fit.v, confidence=c_snr * c_both,
                           amplitudes=rel / max(float(rel.max()), 1e-300), snr=snr,
                           detector_times=det_times)


def _prune(pb: Problem, taus: np.ndarray, v: float, limit: float, both: bool = False,
           start: Solution | None = None) -> tuple[np.ndarray, Solution | None]:
    """``taus`` less, one by one, the weakest axle while it lowers the misfit by less
    than ``limit`` (or, with ``both``, one detector does not see it), at the given times
    and speed: a cheap pass without refinement.  Also the least squares of the times
    kept, with slopes (a refinement's start), when it was made; ``start``: that of
    ``taus`` when already made."""
    sol = None
    while taus.size > 1:
        sol = solution(pb, taus, v, start)
        gains = sol.gains.tolist()
        weak = [g < limit for g in gains]
        if both:
            weak = [w or not seen for w, seen in zip(weak, pb.seen(sol.amps), strict=True)]
        if not any(weak):
            return taus, sol
        taus = _without(taus, _weakest(weak, gains))
    return taus, None
