"""Axles from two wide-response detectors by sparse deconvolution (matching pursuit).

Contract
--------
* Input: the two detector channels of a record and their learned responses
  (:class:`~bwim.detect.response.LearnedResponses`).  Model of each vehicle's axles,
  both detectors at once::

      y_d(t) = c_d(t) + Σ_i A_id K_d(v (t − τ_i) − D_d) + e,   D_1 = 0, D_2 = D,

  ``τ_i`` the time axle ``i`` passes detector 1, ``v`` the vehicle's speed,
  ``A_id = g_d a_i`` its amplitude at each detector (``a_i ≥ 0`` one per axle, ``g_d`` the
  detectors' gains as learned: a lane's two detectors lie on one line across the lane,
  so they see every axle through the same tyres and lateral position, and what one
  detector shows without the other, such as a tyre force's dynamics while it passes, is
  not taken for an axle), ``c_d`` a
  slowly varying baseline (offset, drift, the span's bending) and noise ``e``, each
  channel weighted by its level (:attr:`~bwim.detect.response.DetectorResponse.level`:
  its noise, or what the learned response missed of the calibration truck's axles if
  that is more).  Readings and model are **high-passed in space**
  (:func:`~bwim.detect.response.high_pass` over
  :data:`~bwim.detect.response.HIGH_PASS` m of travel at the vehicle's speed), as the
  responses were learned: what identifies an axle is its own local peak; the slab's
  global bending, which depends on where the other axles and vehicles are, and any
  offset or drift, are left out.
* Steps: (1) the speed, from the band-passed detectors' lag; (2) **matching pursuit**: the
  axle time that most reduces the weighted misfit of both detectors together is added and
  every amplitude refitted (non-negative least squares, both detectors in one), while the
  reduction exceeds ``snr_threshold²`` noise variances and ``min_height²`` of what the
  record's strongest axle gave (an axle ``min_height`` as tall as the largest: what the
  learned response misses of a big axle must not pass for a small one), and its amplitude
  is at least ``min_height`` of the largest; (3) axles are grouped into vehicles (gaps
  larger than ``max_axle_spacing``) and each vehicle's axle times, speed and amplitudes
  refined jointly (Levenberg–Marquardt, analytic Jacobian); (4) **backward check**: an
  axle whose removal costs less than the threshold, or closer than ``min_axle_spacing`` to
  another, is dropped and the vehicle refitted; one more pursuit step may add an axle the
  first pass missed. Merged peaks (a tridem 1.3 m apart under a 1 m wide response) come
  apart because the fit knows the response; the detectors never "disagree" on the count,
  since one fit counts for both: their agreement enters the confidence instead.
* Confidence of a vehicle = ``c_snr × c_both``: ``c_snr = clip(√Δ / (2 snr_threshold),
  0.5, 1)`` with ``Δ`` the smallest misfit reduction (level variances) of its axles;
  ``c_both`` the share of its axles that each detector fitted alone sees with at least
  0.4 of the joint amplitude, at least 0.5.
* Times in s, distances in m, speeds in m/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, nnls

from .assemble import VehicleEstimate
from .response import (
    HIGH_PASS,
    LearnedResponses,
    band_pass,
    high_pass,
    peak_polarity,
    xcorr_lag,
)

__all__ = ["pursue_axles"]

#: An upper bound on the axles of one record.
MAX_AXLES = 40
#: Samples a vehicle's fit looks at beyond its first and last axle, m of travel.
REACH = 4.0


@dataclass(frozen=True, eq=False)
class _Problem:
    """One record's two channels, high-passed and weighted, and the high-passed
    responses in space."""

    t: np.ndarray
    y: np.ndarray  # (n_t, 2) high-passed, weighted (level units)
    w: np.ndarray  # (2,) 1 / level
    ratio: np.ndarray  # (2,) the detectors' gains relative to the first
    shift: tuple[float, float]  # D_d
    grids: tuple  # per detector (u, K_hp, dK_hp/du)
    fs: float

    def atoms(self, taus: np.ndarray, v: float, rows: slice | np.ndarray = slice(None),
              slopes: bool = False):
        """Per detector the weighted columns K_hp(v (t − τ_i) − D_d), (n_rows, n); with
        ``slopes`` also their slopes dK_hp/du at the same points."""
        t = self.t[rows]
        out, der = [], []
        for c, (u, k, dk) in enumerate(self.grids):
            x = v * (t[:, None] - taus[None, :]) - self.shift[c]
            scale = self.w[c] * self.ratio[c]
            out.append(np.interp(x, u, k, left=0.0, right=0.0) * scale)
            if slopes:
                der.append(np.interp(x, u, dk, left=0.0, right=0.0) * scale)
        return (out, der) if slopes else out

    def fit(self, taus: np.ndarray, v: float, rows: slice | np.ndarray = slice(None)
            ) -> tuple[np.ndarray, float, np.ndarray]:
        """One amplitude ≥ 0 per axle (both detectors, in their gains' ratio), the
        misfit, the residual (rows)."""
        y = self.y[rows]
        if not taus.size:
            return np.zeros(0), float(np.sum(y**2)), y.copy()
        X = self.atoms(taus, v, rows)
        a, _ = nnls(np.vstack(X), np.concatenate([y[:, 0], y[:, 1]]))
        res = y - np.column_stack([X[0] @ a, X[1] @ a])
        return a, float(np.sum(res**2)), res

    def separate(self, taus: np.ndarray, v: float, rows) -> np.ndarray:
        """Each detector's own amplitudes ≥ 0 (n, 2), in units of the first's gain."""
        y = self.y[rows]
        return np.column_stack([nnls(X, y[:, c])[0]
                                for c, X in enumerate(self.atoms(taus, v, rows))])


def _problem(t: np.ndarray, y: np.ndarray, learned: LearnedResponses, v: float) -> _Problem:
    fs = 1.0 / float(np.median(np.diff(t)))
    w = 1.0 / np.array([max(r.level, 1e-300) for r in learned.responses])
    y_hp = high_pass(y, HIGH_PASS / v * fs) * w
    amps = np.abs(learned.amplitudes)
    ratio = float(np.median(amps[:, 1] / np.maximum(amps[:, 0], 1e-300)))
    return _Problem(t=t, y=y_hp, w=w, ratio=np.array([1.0, ratio]),
                    shift=(0.0, learned.distance),
                    grids=tuple(r.high_passed() for r in learned.responses), fs=fs)


def _speed(y: np.ndarray, fs: float, distance: float, speed_range: tuple[float, float]
           ) -> float | None:
    z = band_pass(y, fs)
    z = z * peak_polarity(z)
    lag = xcorr_lag(z[:, 0], z[:, 1], np.floor(distance / speed_range[1] * fs),
                    np.ceil(distance / speed_range[0] * fs))
    return None if lag is None else distance / (lag / fs)


def _best_new(pb: _Problem, res: np.ndarray, v: float, taken: np.ndarray, min_gap: float
              ) -> float:
    """The axle time whose atoms (both detectors, each its own amplitude ≥ 0) most reduce
    the residual ``res`` (all samples)."""
    n = pb.t.size
    corr = np.zeros(n)
    energy = 0.0
    for c, (u, k, _) in enumerate(pb.grids):
        d = pb.shift[c]
        m_lo = int(np.floor((u[0] + d) / v * pb.fs)) - 1
        m_hi = int(np.ceil((u[-1] + d) / v * pb.fs)) + 1
        atom = np.interp(v * np.arange(m_lo, m_hi + 1) / pb.fs - d, u, k, left=0.0,
                         right=0.0) * pb.w[c] * pb.ratio[c]
        energy += float(atom @ atom)
        lo, hi = max(0, -m_lo), max(0, m_hi)
        r = np.concatenate([np.zeros(lo), res[:, c], np.zeros(hi)])
        corr += np.correlate(r, atom, mode="valid")[m_lo + lo:m_lo + lo + n]
    score = np.maximum(corr, 0.0) ** 2 / max(energy, 1e-300)
    for tk in taken:  # not on an axle already found
        score[np.abs(pb.t - tk) < min_gap / v] = 0.0
    return float(pb.t[int(np.argmax(score))])


def pursue_axles(record_time: np.ndarray, y: np.ndarray, learned: LearnedResponses, *,
                 speed_range: tuple[float, float], min_axle_spacing: float,
                 max_axle_spacing: float, snr_threshold: float, min_height: float
                 ) -> list[VehicleEstimate]:
    """Vehicles of one record (see the module docstring).

    ``y`` (n_t, 2) are the two detector channels (in the responses' order), ``record_time``
    their times.  Returns the vehicles' estimates (empty when no axle stands out)."""
    t = np.asarray(record_time, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    v0 = _speed(y, fs, learned.distance, speed_range)
    if v0 is None:
        return []
    pb = _problem(t, np.asarray(y, dtype=float), learned, v0)
    thr2 = snr_threshold**2
    taus = np.zeros(0)
    _, chi, res = pb.fit(taus, v0)
    first = 0.0
    for _ in range(MAX_AXLES):
        tk = _best_new(pb, res, v0, taus, min_axle_spacing)
        trial = np.sort(np.append(taus, tk))
        amps, chi_new, res_new = pb.fit(trial, v0)
        gain = chi - chi_new
        first = max(first, gain)
        if gain < max(thr2, min_height**2 * first) or not _tall(amps, trial, tk, min_height):
            break
        taus, chi, res = trial, chi_new, res_new
    if taus.size == 0:
        return []
    limit = max(thr2, min_height**2 * first)
    out = []
    for group in _groups(taus, v0, max_axle_spacing):
        veh = _check(pb, *_refine(pb, group, v0), limit, min_axle_spacing, min_height,
                     snr_threshold)
        if veh is not None:
            out.append(veh)
    return out


def _tall(amps: np.ndarray, taus: np.ndarray, tk: float, min_height: float) -> bool:
    """Whether the axle at ``tk`` reaches ``min_height`` of the largest amplitude at one
    detector at least."""
    i = int(np.flatnonzero(taus == tk)[0])
    return bool(_relative(amps)[i] >= min_height)


def _relative(amps: np.ndarray) -> np.ndarray:
    top = float(amps.max()) if amps.size else 0.0
    return amps / top if top > 0 else amps


def _groups(taus: np.ndarray, v: float, max_spacing: float) -> list[np.ndarray]:
    taus = np.sort(taus)
    return np.split(taus, np.flatnonzero(np.diff(taus) * v > max_spacing) + 1)


def _window(pb: _Problem, taus: np.ndarray, v: float) -> np.ndarray:
    """Samples from REACH m of travel before the first axle reaches detector 1 to REACH m
    after the last leaves detector 2."""
    return np.flatnonzero((pb.t >= taus[0] - REACH / v)
                          & (pb.t <= taus[-1] + (pb.shift[1] + REACH) / v))


def _refine(pb: _Problem, taus: np.ndarray, v0: float) -> tuple[np.ndarray, float]:
    """The vehicle's axle times and speed, jointly with its amplitudes (free in sign here:
    the non-negative amplitudes are refitted after), analytic Jacobian."""
    n = taus.size
    rows = _window(pb, taus, v0)
    y = pb.y[rows]
    amps, _, _ = pb.fit(taus, v0, rows)

    def unpack(p):
        return p[:n], p[n], p[n + 1:]

    def resid(p: np.ndarray) -> np.ndarray:
        tt, v, a = unpack(p)
        X = pb.atoms(tt, v, rows)
        return np.concatenate([y[:, c] - X[c] @ a for c in range(2)])

    def jac(p: np.ndarray) -> np.ndarray:
        tt, v, a = unpack(p)
        X, dX = pb.atoms(tt, v, rows, slopes=True)
        dt = pb.t[rows][:, None] - tt[None, :]
        blocks = []
        for c in range(2):
            J = np.zeros((rows.size, 2 * n + 1))
            J[:, :n] = dX[c] * a * v  # d/dτ_i of −a K(v (t − τ_i) − D)
            J[:, n] = -(dX[c] * dt) @ a
            J[:, n + 1:] = -X[c]
            blocks.append(J)
        return np.vstack(blocks)

    p0 = np.concatenate([taus, [v0], amps])
    sol = least_squares(resid, p0, jac=jac, method="lm",
                        x_scale=np.concatenate([np.full(n, 2e-3), [0.02 * v0],
                                                np.maximum(amps, 1e-3)]))
    tt, v, _ = unpack(sol.x)
    order = np.argsort(tt)
    return tt[order], float(v)


def _gains(pb: _Problem, taus: np.ndarray, v: float, chi: float, rows) -> np.ndarray:
    """How much the misfit rises when each axle is left out (noise variances)."""
    return np.array([pb.fit(np.delete(taus, i), v, rows)[1] - chi for i in range(taus.size)])


def _check(pb: _Problem, taus: np.ndarray, v: float, limit: float, min_spacing: float,
           min_height: float, snr_threshold: float) -> VehicleEstimate | None:
    """Backward elimination and one more pursuit step; the vehicle's estimate."""
    for _ in range(4):
        changed = False
        while taus.size > 1 and np.min(np.diff(taus)) * v < min_spacing:
            i = int(np.argmin(np.diff(taus)))
            taus = np.delete(taus, i + 1)
            changed = True
        rows = _window(pb, taus, v)
        amps, chi, _ = pb.fit(taus, v, rows)
        weak = (_gains(pb, taus, v, chi, rows) < limit) | (_relative(amps) < min_height)
        if weak.any() and taus.size > 1:
            taus = np.delete(taus, int(np.flatnonzero(weak)[0]))
            changed = True
        else:
            _, _, res = pb.fit(taus, v)
            tk = _best_new(pb, res, v, taus, min_spacing)
            if taus[0] - REACH / v <= tk <= taus[-1] + REACH / v:
                trial = np.sort(np.append(taus, tk))
                rows2 = _window(pb, trial, v)
                amps2, chi2, _ = pb.fit(trial, v, rows2)
                _, chi1, _ = pb.fit(taus, v, rows2)
                if chi1 - chi2 >= limit and _tall(amps2, trial, tk, min_height):
                    taus = trial
                    changed = True
        if not changed:
            break
        taus, v = _refine(pb, taus, v)
    if taus.size == 0:
        return None
    rows = _window(pb, taus, v)
    amps, chi, _ = pb.fit(taus, v, rows)
    gains = _gains(pb, taus, v, chi, rows)
    snr = float(np.sqrt(max(float(gains.min()), 0.0)))
    c_snr = float(np.clip(snr / (2.0 * snr_threshold), 0.5, 1.0))
    own = pb.separate(taus, v, rows)  # each detector alone: does it see the axle?
    seen = (own / np.maximum(amps[:, None], 1e-300) >= 0.4).all(axis=1)
    c_both = max(0.5, float(np.mean(seen)))
    det_times = np.column_stack([taus, taus + pb.shift[1] / v])
    return VehicleEstimate(times=taus, speed=v, confidence=c_snr * c_both,
                           amplitudes=_relative(amps), snr=snr, detector_times=det_times)
