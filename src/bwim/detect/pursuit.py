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
  and :data:`MIN_SPACING_WIDTH` of the responses' width: closer peaks are one axle whose
  force changed while it passed.
* Confidence of a vehicle = ``c_snr × c_both``: ``c_snr = clip(√Δ / (2 snr_threshold),
  0.5, 1)`` with ``Δ`` the smallest misfit reduction (level variances) of its axles;
  ``c_both`` the mean over its axles of ``exp(−½ (ln(A_2 / (ρ A_1)) / (2 s))²)``, ``s``
  the learned spread (at least ``MIN_RATIO_BOUND / RATIO_SPREADS``), at least 0.5.
* Times in s, distances in m, speeds in m/s.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

from .assemble import VehicleEstimate
from .response import (
    HIGH_PASS,
    LearnedResponses,
    band_pass,
    high_pass,
    xcorr_lag,
)

__all__ = ["GAIN_SHARE", "GROUP_AXLES", "GROUP_DIP", "GROUP_SPACING", "LEVEL_GAIN",
           "MIN_RATIO_BOUND", "MIN_SPACING_WIDTH", "PURSUIT_SHARE", "RATIO_SPREADS",
           "SPEED_SLACK", "pursue_axles"]

#: An upper bound on the axles of one record.
MAX_AXLES = 40
#: Samples a vehicle's fit looks at beyond its first and last axle, m of travel.
REACH = 2.0
#: An axle's two amplitudes may differ from the gain ratio by this many learned spreads.
RATIO_SPREADS = 4.0
#: ... and at least by this factor (natural log: a factor 3).
MIN_RATIO_BOUND = float(np.log(3.0))
#: In the pursuit, the second detector's atom of an axle may be off the first speed
#: estimate by this share of the lag between the detectors.
SPEED_SLACK = 0.08
#: The pursuit stops at an axle lowering the misfit by less than this share of what the
#: record's strongest did (the axle groups are chosen again after).
PURSUIT_SHARE = 0.1
#: An axle must lower the misfit by this share of what the record's strongest axle did.
GAIN_SHARE = 0.02
#: ... and, one more in an axle group, by this many times the vehicle's residual per
#: sample (the dynamic force of its tyres, beyond what the calibration truck showed).
LEVEL_GAIN = 180.0
#: ... times this for a fourth axle in a group (groups of four are rare; a tridem's
#: dynamic forces make a fourth axle cheaper).
RARE_GROUP = 1.5
#: Axles closer than this share of the responses' width (at half height) are one axle
#: whose force changed while it passed.
MIN_SPACING_WIDTH = 0.8
#: A new axle is looked for no closer to one already found than this share of the
#: smallest spacing (the refinement moves them apart).
EXCLUDE = 0.5
#: Largest spacing within an axle group (tandem, tridem) whose count is chosen again, m.
GROUP_SPACING = 2.2
#: Axle groups are cut where the detectors' readings dip below this share of the lower
#: neighbouring peak (a 1.3 m tandem under a 1.2 m wide response dips to about 0.8, axles
#: 2.2 m apart to about 0.2).
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
#: Samples per response width (at half height) a vehicle's fit keeps at least.
WINDOW_SAMPLES = 9
#: Levenberg–Marquardt iterations of a refinement, at most.
MAX_LM = 15
#: ... of the first, which sets the speed at which the axle groups are chosen.
FIRST_LM = 4
#: ... which stops when the misfit falls by less than this share (or the times move by
#: less than 5 mm of travel).
CONVERGED = 3e-3


@dataclass(frozen=True, eq=False)
class _Problem:
    """One record's two channels, weighted, their rest's columns and the responses."""

    t: np.ndarray
    y: np.ndarray  # (n_t, 2) weighted (level units); high-passed without gauges
    rest: tuple[np.ndarray, np.ndarray]  # per detector (n_t, k) weighted columns
    q_rest: tuple[np.ndarray, np.ndarray]  # their orthonormal bases (all samples)
    w: np.ndarray  # (2,) 1 / level
    ratio: float  # the second detector's gain over the first's
    bound: float  # largest |ln(A_2 / (ratio A_1))| of an axle
    spread: float  # learned spread of that log ratio
    shift: tuple[float, float]  # D_d
    grids: tuple  # per detector (u, K, dK/du), high-passed without gauges
    steps: tuple  # per detector K's differences between ordinates (0 after the last)
    fs: float
    step: int  # every step-th sample in a vehicle's window

    def atoms(self, taus: np.ndarray, v: float, rows: slice | np.ndarray = slice(None),
              slopes: bool = False, only: int | None = None):
        """Per detector the weighted columns K(v (t − τ_i) − D_d), (n_rows, n), K linear
        between its ordinates; with ``slopes`` also their slopes dK/du (of the linear
        pieces) at the same points; with ``only`` that detector's (None for the other)."""
        t = self.t[rows]
        out, der = [], []
        for c, (u, k, _) in enumerate(self.grids):
            if only is not None and c != only:
                out.append(None)
                der.append(None)
                continue
            du = u[1] - u[0]
            x = (v * (t[:, None] - taus[None, :]) - (self.shift[c] + u[0])) * (1.0 / du)
            np.clip(x, 0.0, u.size - 1.000001, out=x)  # the grids end in zeros
            j = x.astype(np.intp)
            x -= j
            step = self.steps[c][j]
            out.append((k[j] + x * step) * self.w[c])
            if slopes:
                der.append(step * (self.w[c] / du))
        return (out, der) if slopes else out

    def log_ratio(self, amps: np.ndarray) -> np.ndarray:
        """``ln(A_2 / (ratio A_1))`` per axle (±inf where one detector sees nothing)."""
        a1 = np.maximum(amps[:, 0], 0.0)
        a2 = np.maximum(amps[:, 1], 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log(a2 / (self.ratio * a1))
        return np.where(np.isnan(r), np.inf, r)

    def seen_by_both(self, amps: np.ndarray) -> np.ndarray:
        return np.abs(self.log_ratio(amps)) <= self.bound


@dataclass(frozen=True, eq=False)
class _Fit:
    """A vehicle's fit on its window: times, speed, amplitudes (n, 2), misfit, each axle's
    removal cost (level variances)."""

    taus: np.ndarray
    v: float
    amps: np.ndarray
    chi: float
    gains: np.ndarray


def _problem(t: np.ndarray, y: np.ndarray, gauges: np.ndarray | None,
             learned: LearnedResponses, v: float) -> _Problem:
    fs = 1.0 / float(np.median(np.diff(t)))
    w = 1.0 / np.array([max(r.level, 1e-300) for r in learned.responses])
    spread = float(learned.amplitude_spread)
    bound = max(RATIO_SPREADS * spread, MIN_RATIO_BOUND)
    # a vehicle's fit samples every step-th reading: at least WINDOW_SAMPLES per response
    # width at half height (the response is smooth on that scale)
    width = min(r.fwhm for r in learned.responses) / v * fs
    step = max(1, int(width // WINDOW_SAMPLES))
    common = dict(t=t, w=w, ratio=float(learned.gain_ratio), bound=bound, spread=spread,
                  shift=(0.0, learned.distance), fs=fs, step=step)
    if learned.gauges and gauges is not None:
        g = gauges - gauges.mean(axis=0)
        tc = t - t.mean()
        tc = tc / max(float(np.ptp(tc)), 1e-300)
        rest = tuple(np.column_stack([g @ r.bending, np.ones_like(tc), tc]) * w[c]
                     for c, r in enumerate(learned.responses))
        grids = tuple(r.padded() for r in learned.responses)
        return _Problem(y=(y - y.mean(axis=0)) * w, rest=rest,
                        q_rest=tuple(np.linalg.qr(r)[0] for r in rest), grids=grids,
                        steps=tuple(np.append(np.diff(g[1]), 0.0) for g in grids), **common)
    y_hp = high_pass(y, HIGH_PASS / v * fs) * w
    empty = np.zeros((t.size, 0))
    grids = tuple(r.high_passed() for r in learned.responses)
    return _Problem(y=y_hp, rest=(empty, empty), q_rest=(empty, empty), grids=grids,
                    steps=tuple(np.append(np.diff(g[1]), 0.0) for g in grids), **common)


def _speed(y: np.ndarray, fs: float, distance: float, speed_range: tuple[float, float],
           sign: np.ndarray) -> float | None:
    """Speed from the lag of the band-passed detectors (made positive by the responses'
    ``sign``), None if they do not correlate in the speed range."""
    z = band_pass(y, fs) * sign
    lag = xcorr_lag(z[:, 0], z[:, 1], np.floor(distance / speed_range[1] * fs),
                    np.ceil(distance / speed_range[0] * fs))
    return None if lag is None else distance / (lag / fs)


def _best_new(pb: _Problem, res: np.ndarray, v: float, taken: np.ndarray, min_gap: float,
              slack: int = 0) -> tuple[float, float]:
    """The axle time whose atoms (both detectors, one amplitude in their gain ratio) best
    match the residual ``res`` (all samples); the second detector's atom may be up to
    ``slack`` samples off the speed ``v``.  Returns the time at detector 1 and the time
    the second detector's atom says (both at detector 1 for the speed ``v``)."""
    n = pb.t.size
    corr = []
    energy = 0.0
    for c, (u, k, _) in enumerate(pb.grids):
        d = pb.shift[c]
        m_lo = int(np.floor((u[0] + d) / v * pb.fs)) - 1
        m_hi = int(np.ceil((u[-1] + d) / v * pb.fs)) + 1
        scale = pb.w[c] * (pb.ratio if c else 1.0)
        atom = np.interp(v * np.arange(m_lo, m_hi + 1) / pb.fs - d, u, k, left=0.0,
                         right=0.0) * scale
        energy += float(atom @ atom)
        lo, hi = max(0, -m_lo), max(0, m_hi)
        r = np.concatenate([np.zeros(lo), res[:, c], np.zeros(hi)])
        corr.append(np.correlate(r, atom, mode="valid")[m_lo + lo:m_lo + lo + n])
    if slack:
        padded = np.concatenate([np.full(slack, -np.inf), corr[1], np.full(slack, -np.inf)])
        stack = np.lib.stride_tricks.sliding_window_view(padded, 2 * slack + 1)
        off = np.argmax(stack, axis=1) - slack
        c2 = corr[1][np.arange(n) + off]
    else:
        off, c2 = np.zeros(n, dtype=int), corr[1]
    score = np.maximum(corr[0] + c2, 0.0) ** 2 / max(energy, 1e-300)
    for tk in taken:  # not on an axle already found
        score[np.abs(pb.t - tk) < min_gap / v] = 0.0
    m = int(np.argmax(score))
    return float(pb.t[m]), float(pb.t[m + off[m]])


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
    fs = 1.0 / float(np.median(np.diff(t)))
    if not (learned.gauges and gauges is not None):
        gauges = None
    if gauges is not None:
        g = np.asarray(gauges, dtype=float)
        g = g - g.mean(axis=0)
        bend = np.column_stack([g @ r.bending for r in learned.responses])
        y0 = y - bend
    else:
        y0 = y
    v0 = _speed(y0, fs, learned.distance, speed_range,
                np.array([r.sign for r in learned.responses]))
    if v0 is None:
        return []
    pb = _problem(t, y, gauges, learned, v0)
    thr2 = snr_threshold**2
    min_sp = max(min_axle_spacing, MIN_SPACING_WIDTH * float(np.mean(
        [r.fwhm for r in learned.responses])))
    omp = _Pursuit(pb, v0)
    first = 0.0
    refused = np.zeros(0)  # candidates one detector does not see: not tried again
    lag = learned.distance / v0
    slack = int(np.ceil(SPEED_SLACK * lag * fs))
    for _ in range(2 * MAX_AXLES):
        tk, tk2 = _best_new(pb, omp.res, v0, np.append(omp.taus, refused),
                            EXCLUDE * min_sp, slack)
        amps, chi_new, state = omp.trial(tk, tk2)
        gain = omp.chi - chi_new
        first = max(first, gain)
        if gain < max(thr2, PURSUIT_SHARE * first) or omp.taus.size >= MAX_AXLES:
            break
        if not _acceptable(pb, amps, min_height):
            refused = np.append(refused, tk)
            continue
        omp.accept(tk, tk2, chi_new, state)
    order = np.argsort(omp.taus)
    taus = omp.taus[order]
    lags = lag + omp.taus2[order] - taus  # each axle's own lag between the detectors
    if taus.size == 0:
        return []
    limit = max(thr2, GAIN_SHARE * first)
    out = []
    groups = np.split(np.arange(taus.size),
                      np.flatnonzero(np.diff(taus) * v0 > max_axle_spacing) + 1)
    # each vehicle's axles may lie between the midpoints to its neighbours' (the pursuit
    # may have missed some: the axle groups are found again there)
    edges = [t[0], *(0.5 * (taus[a[-1]] + taus[b[0]])
                     for a, b in itertools.pairwise(groups)), t[-1]]
    for k, group in enumerate(groups):
        # the vehicle's speed from its axles' lags
        v = learned.distance / float(np.median(lags[group]))
        if not speed_range[0] <= v <= speed_range[1]:
            v = v0
        veh = _vehicle(pb, taus[group], v, limit, min_sp, min_height, snr_threshold,
                       (edges[k], edges[k + 1]))
        if veh is not None:
            out.append(veh)
    return out


def _acceptable(pb: _Problem, amps: np.ndarray, min_height: float) -> bool:
    """Whether the last axle of ``amps`` reaches ``min_height`` of the largest amplitude
    at both detectors (the gain ratio is checked on the refined vehicle: merged peaks
    explained in part share their amplitudes unevenly between the detectors)."""
    return bool(_relative(amps)[-1].min() >= min_height)


class _Pursuit:
    """Orthogonal matching pursuit over the whole record: the axles' responses with each
    detector's rest projected out, their Gram matrix and least-squares amplitudes kept up
    to date as axles are added."""

    def __init__(self, pb: _Problem, v: float):
        self.pb, self.v = pb, v
        self.taus = np.zeros(0)  # at detector 1
        self.taus2 = np.zeros(0)  # the second detector's, less D / v
        self.y = []
        for c in range(2):
            Q = pb.q_rest[c]
            self.y.append(pb.y[:, c] - Q @ (Q.T @ pb.y[:, c]))
        self.cols = [np.zeros((pb.t.size, 0)), np.zeros((pb.t.size, 0))]
        self.res = np.column_stack(self.y)
        self.chi = float(np.sum(self.res**2))

    def trial(self, tk: float, tk2: float):
        """Amplitudes (n + 1, 2; the new axle last), misfit and state with an axle at
        ``tk`` added (at ``tk2`` for the second detector)."""
        new = [self.pb.atoms(np.array([tk]), self.v, only=0)[0],
               self.pb.atoms(np.array([tk2]), self.v, only=1)[1]]
        cols, amps, res = [], np.zeros((self.taus.size + 1, 2)), np.empty_like(self.res)
        for c in range(2):
            Q = self.pb.q_rest[c]
            x = new[c][:, 0]
            x = x - Q @ (Q.T @ x)
            X = np.column_stack([self.cols[c], x])
            G = X.T @ X
            G.flat[::G.shape[0] + 1] += 1e-12 * (np.trace(G) / G.shape[0] + 1e-300)
            a = np.linalg.solve(G, X.T @ self.y[c])
            amps[:, c] = a
            res[:, c] = self.y[c] - X @ a
            cols.append(X)
        return amps, float(np.sum(res**2)), (cols, res)

    def accept(self, tk: float, tk2: float, chi: float, state) -> None:
        self.cols, self.res = state
        self.taus = np.append(self.taus, tk)
        self.taus2 = np.append(self.taus2, tk2)
        self.chi = chi


def _relative(amps: np.ndarray) -> np.ndarray:
    """Amplitudes over each detector's largest, (n, 2)."""
    top = amps.max(axis=0) if amps.size else np.zeros(2)
    return amps / np.where(top > 0, top, 1.0)


def _window(pb: _Problem, taus: np.ndarray, v: float) -> np.ndarray:
    """Samples from REACH m of travel before the first axle reaches detector 1 to REACH m
    after the last leaves detector 2."""
    lo = np.searchsorted(pb.t, taus.min() - REACH / v)
    hi = np.searchsorted(pb.t, taus.max() + (pb.shift[1] + REACH) / v, side="right")
    return np.arange(lo, hi, pb.step)


def _solve(pb: _Problem, taus: np.ndarray, v: float, rows: np.ndarray, slopes: bool):
    """Per detector the least-squares amplitudes and rest on ``rows`` (free in sign), the
    residual; with ``slopes`` the variable-projection Jacobian (Kaufman) of the residual
    with respect to (τ_1 … τ_n, v); each axle's removal cost.  Residual and costs are
    scaled by the window's sampling step (misfits of all samples)."""
    n = taus.size
    if slopes:
        X, dX = pb.atoms(taus, v, rows, slopes=True)
    else:
        X = pb.atoms(taus, v, rows)
    res, jac, amps, gains = [], [], np.zeros((n, 2)), np.zeros(n)
    for c in range(2):
        M = np.hstack([X[c], pb.rest[c][rows]])
        yc = pb.y[rows, c]
        G = M.T @ M
        G.flat[::G.shape[0] + 1] += 1e-12 * (np.trace(G) / G.shape[0] + 1e-300)
        try:
            Ginv = np.linalg.inv(G)
        except np.linalg.LinAlgError:
            Ginv = np.linalg.pinv(G)
        coef = Ginv @ (M.T @ yc)
        r = yc - M @ coef
        res.append(r)
        a = coef[:n]
        amps[:, c] = a
        # removing regressor i raises the misfit by coef_i² / [(MᵀM)⁻¹]_ii
        gains += a**2 / np.maximum(np.diag(Ginv)[:n], 1e-300)
        if slopes:
            D = np.empty((rows.size, n + 1))
            D[:, :n] = -v * dX[c] * a  # ∂(X a)/∂τ_i
            D[:, n] = (dX[c] * (pb.t[rows][:, None] - taus[None, :])) @ a  # ∂(X a)/∂v
            jac.append(M @ (Ginv @ (M.T @ D)) - D)
    # every step-th sample: scaled to the misfit of all samples
    k = np.sqrt(pb.step)
    return (np.concatenate(res) * k, (np.vstack(jac) * k if slopes else None), amps,
            gains * pb.step)


def _refine(pb: _Problem, taus: np.ndarray, v: float, iterations: int = MAX_LM) -> _Fit:
    """The vehicle's axle times and speed by Levenberg–Marquardt on the variable
    projection (amplitudes and rest by least squares inside), on a fixed window."""
    taus = np.sort(np.asarray(taus, dtype=float))
    rows = _window(pb, taus, v)
    p = np.append(taus, v)
    r, J, amps, gains = _solve(pb, taus, v, rows, True)
    cost = float(r @ r)
    lam = 1e-3
    scale = np.append(np.full(taus.size, 1.0 / v), 1.0 / v)  # τ in s, v in m/s: metres
    for _ in range(iterations):
        Js = J * scale
        A = Js.T @ Js
        g = Js.T @ r
        improved = False
        for _ in range(8):
            step = -np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-12), g) * scale
            trial = p + step
            tt, vv = np.sort(trial[:-1]), trial[-1]
            if vv <= 0:
                lam *= 10.0
                continue
            r2, J2, amps2, gains2 = _solve(pb, tt, vv, rows, True)
            c2 = float(r2 @ r2)
            if c2 < cost:
                rel = (cost - c2) / max(cost, 1e-300)
                p, r, J, amps, gains, cost = np.append(tt, vv), r2, J2, amps2, gains2, c2
                lam = max(lam / 3.0, 1e-7)
                improved = True
                break
            lam *= 10.0
        if not improved or rel < CONVERGED or np.max(np.abs(step[:-1])) * p[-1] < 5e-3:
            break
    return _Fit(taus=p[:-1], v=float(p[-1]), amps=amps, chi=cost, gains=gains)


def _drop_close(fit: _Fit, min_sp: float) -> np.ndarray | None:
    """The times without the weaker of the closest pair closer than ``min_sp``; None if
    none is that close."""
    if fit.taus.size < 2:
        return None
    d = np.diff(fit.taus) * fit.v
    i = int(np.argmin(d))
    if d[i] >= min_sp:
        return None
    weaker = i if fit.gains[i] < fit.gains[i + 1] else i + 1
    return np.delete(fit.taus, weaker)


def _vehicle(pb: _Problem, taus: np.ndarray, v: float, limit: float, min_sp: float,
             min_height: float, snr_threshold: float, span: tuple[float, float]
             ) -> VehicleEstimate | None:
    """A first refinement (the speed), the axle groups chosen again in ``span`` (record
    times at detector 1), the final refinement and backward check; the vehicle's
    estimate."""
    fit = _refine(pb, _prune(pb, taus, v, limit), v, FIRST_LM)
    kept = _prune(pb, fit.taus, fit.v, limit, both=True)
    grouped = _group_search(pb, kept, fit.v, limit, min_sp, span)
    if grouped is not None or kept.size < fit.taus.size:
        fit = _refine(pb, kept if grouped is None else grouped, fit.v)
    for _ in range(MAX_AXLES):
        close = _drop_close(fit, min_sp)
        if close is not None:
            fit = _refine(pb, close, fit.v)
            continue
        weak = ((fit.gains < limit) | (_relative(fit.amps).min(axis=1) < min_height)
                | ~pb.seen_by_both(fit.amps))
        if weak.any() and fit.taus.size > 1:
            i = int(np.argmin(np.where(weak, fit.gains, np.inf)))
            fit = _refine(pb, np.delete(fit.taus, i), fit.v)
            continue
        break
    if fit.taus.size == 0 or not pb.seen_by_both(fit.amps).any():
        return None
    snr = float(np.sqrt(max(float(fit.gains.min()), 0.0)))
    c_snr = float(np.clip(snr / (2.0 * snr_threshold), 0.5, 1.0))
    lr = np.minimum(np.abs(pb.log_ratio(fit.amps)), 1e3)
    s = max(pb.spread, MIN_RATIO_BOUND / RATIO_SPREADS)
    c_both = max(0.5, float(np.mean(np.exp(-0.5 * (lr / (2 * s)) ** 2))))
    det_times = np.column_stack([fit.taus, fit.taus + pb.shift[1] / fit.v])
    rel = np.maximum(fit.amps[:, 0], 0.0) + np.maximum(fit.amps[:, 1], 0.0) / pb.ratio
    return VehicleEstimate(times=fit.taus, speed=fit.v, confidence=c_snr * c_both,
                           amplitudes=rel / max(float(rel.max()), 1e-300), snr=snr,
                           detector_times=det_times)


def _prune(pb: _Problem, taus: np.ndarray, v: float, limit: float, both: bool = False
           ) -> np.ndarray:
    """``taus`` less, one by one, the weakest axle while it lowers the misfit by less
    than ``limit`` (or, with ``both``, one detector does not see it), at the given times
    and speed: a cheap pass without refinement."""
    while taus.size > 1:
        _, _, amps, gains = _solve(pb, taus, v, _window(pb, taus, v), False)
        weak = gains < limit
        if both:
            weak |= ~pb.seen_by_both(amps)
        if not weak.any():
            break
        taus = np.delete(taus, int(np.argmin(np.where(weak, gains, np.inf))))
    return taus


def _templates(pb: _Problem, v: float) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Per detector the weighted response of an axle passing detector 1 at sample 0, on
    the samples where it is not zero: (first sample offset, values, autocorrelation)."""
    out = []
    for c, (u, k, _) in enumerate(pb.grids):
        d = pb.shift[c]
        j0 = int(np.ceil((u[0] + d) / v * pb.fs))
        j1 = int(np.floor((u[-1] + d) / v * pb.fs))
        h = np.interp(v * np.arange(j0, j1 + 1) / pb.fs - d, u, k) * pb.w[c]
        out.append((j0, h, np.correlate(h, h, mode="full")[h.size - 1:]))
    return out


def _group_search(pb: _Problem, taus: np.ndarray, v: float, limit: float, min_sp: float,
                  span: tuple[float, float]) -> np.ndarray | None:
    """Each axle group of the vehicle (where the detectors' readings, with the rest and
    the other groups' axles fitted and taken off, stand out between dips: see
    :func:`_segments`) chosen again among 1 … GROUP_AXLES evenly spaced axles at the
    vehicle's speed: the most axles such that each more lowers the misfit by ``limit``
    and both detectors see every axle.  Fast: with the other axles and the rest fitted and
    taken off, a group's misfit needs only the readings' correlation with one axle's
    response and that response's autocorrelation (on the window's sampling grid).  The new
    times, or None."""
    n = taus.size
    lo = int(np.searchsorted(pb.t, span[0] - REACH / v))
    hi = int(np.searchsorted(pb.t, span[1] + (pb.shift[1] + REACH) / v, side="right"))
    rows = np.arange(lo, hi)
    X = pb.atoms(taus, v, rows)
    local, parts = [], []
    for c in range(2):
        M = np.hstack([X[c], pb.rest[c][rows]])
        G = M.T @ M
        G.flat[::G.shape[0] + 1] += 1e-12 * (np.trace(G) / G.shape[0] + 1e-300)
        coef = np.linalg.solve(G, M.T @ pb.y[rows, c])
        local.append(pb.y[rows, c] - pb.rest[c][rows] @ coef[n:])
        parts.append(X[c] * coef[:n])
    fitted = [p.sum(axis=1) for p in parts]
    resid = [local[c] - fitted[c] for c in range(2)]
    r_total = sum(float(r @ r) for r in resid)
    n_samples = 2 * rows.size
    tpl = _templates(pb, v)
    st = pb.step  # hypotheses on every st-th sample
    at = np.round((taus - pb.t[lo]) * pb.fs / st).astype(int)  # axles' grid points
    margin = round(SEGMENT_MARGIN / v * pb.fs)
    s_min = max(1, int(np.ceil(min_sp / v * pb.fs / st)))
    s_max = int(np.floor(GROUP_SPACING / v * pb.fs / st))
    n_grid = (rows.size - 1) // st + 1
    out, changed = [], False
    segments = _segments(pb, local, v, margin, st)
    for first, last in segments:
        g = np.flatnonzero((at >= first) & (at <= last))
        corr, auto = [], []
        first, last = max(first, 0), min(last, n_grid - 1)
        energy = r_inside = 0.0  # the group's readings and residual where it acts
        for c, (j0, h, r) in enumerate(tpl):
            z = local[c] - fitted[c] + parts[c][:, g].sum(axis=1)  # less the others
            a, b = max(first * st + j0, 0), min(last * st + j0 + h.size, rows.size)
            energy += float(z[a:b] @ z[a:b])
            r_inside += float(resid[c][a:b] @ resid[c][a:b])
            # correlation with an axle at grid point m (sample st m), on the segment:
            # Σ_j z[st m + j0 + j] h[j], zero where the response leaves the window
            full = np.zeros(n_grid)
            q0 = max(first * st + j0, 0)
            q1 = min(last * st + j0, rows.size - h.size)
            if q1 >= q0:
                cc = np.correlate(z[q0:q1 + h.size], h, mode="valid")  # q = q0 … q1
                m = np.arange(first, last + 1)
                q = st * m + j0
                ok = (q >= q0) & (q <= q1)
                full[m[ok]] = cc[q[ok] - q0]
            corr.append(full)
            r = r[::st]
            auto.append(np.concatenate([r, np.zeros(max(0, s_max * GROUP_AXLES - r.size + 1))]))
        best = None
        for k in range(1, GROUP_AXLES + 1):
            hyp = _hypotheses(first, last, k, s_min, s_max)
            if hyp.shape[0] == 0:
                break
            explained, amps = _explained(hyp, corr, auto)
            positive = np.all(amps > 0, axis=(1, 2))
            with np.errstate(divide="ignore", invalid="ignore"):
                lr = np.log(amps[..., 1] / (pb.ratio * amps[..., 0]))
            valid = positive & np.all(np.abs(np.where(positive[:, None], lr, np.inf))
                                      <= pb.bound, axis=1)
            if not valid.any():
                break
            j = int(np.argmax(np.where(valid, explained, -np.inf)))
            if best is not None:
                gain = explained[j] - best[0]
                left = energy - best[0]  # the group's residual with one axle fewer
                level = (r_total - r_inside + left) / n_samples
                rare = RARE_GROUP if k > 3 else 1.0
                if gain < limit or gain < LEVEL_GAIN * rare * level:
                    break
            best = (float(explained[j]), hyp[j])
        if best is None:
            out.extend(taus[g])
            continue
        if best[1].size == g.size:
            # the count stands: the refined times stay unless they fit worse by more
            # than the threshold (two of a tridem's axles on one merged peak)
            mine = np.clip(at[g], first, last)[None, :]
            if _explained(mine, corr, auto)[0][0] > best[0] - limit:
                out.extend(taus[g])
                continue
        out.extend(pb.t[lo + st * best[1]])
        changed = True
    # axles outside every segment: noise the pursuit took
    changed |= not all(any(a <= m <= b for a, b in segments) for m in at)
    return np.sort(np.array(out)) if changed else None


def _segments(pb: _Problem, local, v: float, margin: int, st: int) -> list[tuple[int, int]]:
    """The vehicle's axle groups in its window: (first, last) grid points where a group's
    axles may be.  Both detectors' local readings (the second's moved back by the lag,
    each over its largest) are added; groups are cut where their sum dips below GROUP_DIP
    of the lower of the two peaks beside, and span where the sum exceeds GROUP_EXTENT of
    their highest, ``margin`` samples more each side (not past a cut)."""
    lag = round(pb.shift[1] / v * pb.fs)
    e = np.zeros(local[0].size)
    for c, r in enumerate(pb.grids):
        z = local[c] * np.sign(r[1][int(np.argmax(np.abs(r[1])))])
        z = np.maximum(z, 0.0)
        top = float(z.max())
        if top <= 0:
            continue
        shift = lag if c else 0
        e[:e.size - shift] += z[shift:] / top
    if not e.max() > 0:
        return []
    floor = PEAK_FLOOR * float(e.max())
    peaks, _ = find_peaks(e, height=floor, prominence=floor)
    if peaks.size == 0:
        return []
    cuts = [0]
    for a, b in itertools.pairwise(peaks):
        m = a + int(np.argmin(e[a:b + 1]))
        if e[m] < GROUP_DIP * min(e[a], e[b]):
            cuts.append(m)
    cuts.append(e.size - 1)
    out = []
    for a, b in itertools.pairwise(cuts):
        part = e[a:b + 1]
        above = np.flatnonzero(part >= GROUP_EXTENT * float(part.max()))
        lo = max(a + int(above[0]) - margin, a)
        hi = min(a + int(above[-1]) + margin, b)
        out.append((lo // st, hi // st))
    return out


def _hypotheses(first: int, last: int, k: int, s_min: int, s_max: int) -> np.ndarray:
    """Sample indices (n_hyp, k) of k evenly spaced axles between ``first`` and ``last``
    (spacings s_min … s_max samples)."""
    if k == 1:
        return np.arange(first, last + 1)[:, None]
    start, sp = np.nonzero(np.arange(first, last + 1)[:, None]
                           + (k - 1) * np.arange(s_min, s_max + 1)[None, :] <= last)
    return (first + start)[:, None] + (s_min + sp)[:, None] * np.arange(k)[None, :]


def _explained(hyp: np.ndarray, corr, auto) -> tuple[np.ndarray, np.ndarray]:
    """Misfit each hypothesis removes (both detectors) and its amplitudes (n_hyp, k, 2)."""
    k = hyp.shape[1]
    if k == 1:
        b = np.stack([corr[0][hyp[:, 0]], corr[1][hyp[:, 0]]], axis=-1)  # (n_hyp, 2)
        a = b / np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
        return np.sum(a * b, axis=1), a[:, None, :]
    lag = np.abs(hyp[:, :, None] - hyp[:, None, :])
    total = np.zeros(hyp.shape[0])
    amps = np.zeros((*hyp.shape, 2))
    for c in range(2):
        b = corr[c][hyp]
        G = auto[c][lag] + 1e-12 * auto[c][0] * np.eye(k)
        a = np.linalg.solve(G, b[..., None])[..., 0]
        total += np.sum(a * b, axis=1)
        amps[..., c] = a
    return total, amps
