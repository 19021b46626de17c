"""Vehicles from the strain gauges alone (no axle detectors), with an influence line.

Contract
--------
* Model: the static response ``ε(t) = Σ_i A_i I(v (t − τ_i)) + c + d t`` of axles of load
  ``A_i ≥ 0`` passing x = 0 of the influence-line frame at ``τ_i`` at speed ``v``, with an
  unknown offset and linear drift per channel (projected out of every fit).  Channels are
  scaled by their line's peak absolute ordinate (as in Moses' algorithm) and fitted
  together.
* Free search (``known_spacings=None``): the readings are block-averaged to about
  ``rate`` Hz.  For each of ``n_speeds`` trial speeds (geometric in ``speed_range``) a
  non-negative orthogonal matching pursuit picks axles one at a time on a grid of arrival
  times (one per averaged sample; loads by NNLS) until an axle lowers the residual by
  less than 1 % of ‖ε‖; the grid times of one axle (closer than ``min_axle_spacing``)
  merge, axles under ``min_axle_fraction`` of the heaviest are dropped.  The three trials
  with the smallest *penalised* residual (relative residual + 0.005 per axle: an extra
  axle must pay for itself, or a wrong speed fits the bridge's vibration with spurious
  axles) are refined — speed and every arrival time together, by nonlinear least squares
  with the loads by linear least squares inside — and the best, refined again on the
  full-rate readings, wins.  Vehicles are split at gaps over ``max_axle_spacing``.
* ``known_spacings`` (a calibration truck): only the speed and the arrival time are
  unknown.  For each trial speed the arrival time maximising the correlation of the
  readings with the layout's unit-load response is taken; the best trials are refined
  as above.
* ``vibration=True``: the bridge's own vibration is the largest misfit of a static model
  (at the bridge's first frequency, phase-locked to the axles).  The dominant frequency of the first
  fit's residual (2 Hz … min(60, rate/4) Hz, a clear spectral peak) is projected out —
  sine and cosine times hat functions every 0.25 s, a slowly varying amplitude — and the
  search repeated.
* Confidence = ``0.5 × clip(1 − residual / 0.25, 0, 1)`` with ``residual`` the relative
  residual ‖fit − readings‖ / ‖readings‖ of the final fit (offset, drift and the
  projected vibration removed): at
  most 0.5, because nothing independent of the influence line times the axles; a
  residual of 25 % (a poor or wrong line, heavy dynamics) gives 0.  Every vehicle carries
  the flag ``strain_only``.
* Accuracy is limited by the bridge's dynamics (a static model) more than by the line's
  shape, and is below that of two axle detectors; speed, arrival and axle count are
  measured by ``benchmarks/bench_detect.py`` and bounded by
  ``tests/validation/test_vehicle_detection.py``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares, nnls

from bwim.errors import InputError, require_instance, require_positive
from bwim.records import Record
from bwim.wim import InfluenceLine

from .assemble import VehicleEstimate, assemble_detection
from .lateral import section_gauges
from .options import DetectOptions
from .presence import resolve_span
from .result import FLAG_NO_AXLES, FLAG_SINGLE_AXLE, FLAG_STRAIN_ONLY, Detection
from .signals import parabolic_vertex

__all__ = ["detect_from_strain"]

#: Residual at which the strain-only confidence reaches zero.
_RESIDUAL_ZERO = 0.25
#: Most axles the free search looks for in one record.
_MAX_AXLES = 16
#: The free search stops adding axles that reduce the residual by less than this × ‖ε‖.
_MIN_GAIN = 0.01
#: Relative residual charged per axle when trial fits with different axle counts compete.
_AXLE_PENALTY = 0.005
#: Trial speeds refined by nonlinear least squares (the best by penalised residual).
_N_REFINE = 3
#: Knot spacing of the vibration amplitude envelope, s, and highest frequency sought, Hz.
_VIBRATION_KNOT = 0.25
_VIBRATION_MAX_HZ = 60.0


class _Model:
    """Scaled readings, the influence line and the projection that removes offset and
    drift, on a (possibly block-averaged) time axis."""

    def __init__(self, t: np.ndarray, readings: np.ndarray, il_x: np.ndarray,
                 ords: np.ndarray, nuisance: np.ndarray | None = None) -> None:
        self.t = t
        self.n_c = readings.shape[1]
        tc = (t - t.mean()) / max(np.ptp(t), 1e-12)
        cols = [np.ones_like(t), tc]
        if nuisance is not None:
            cols += list(np.asarray(nuisance).T)
        self.basis, _ = np.linalg.qr(np.column_stack(cols))
        self.b = np.concatenate([self._project(readings[:, c]) for c in range(self.n_c)])
        self.il_x = il_x
        self.ords = ords

    def _project(self, v: np.ndarray) -> np.ndarray:
        return v - self.basis @ (self.basis.T @ v)

    def raw(self, speed: float, tau: np.ndarray) -> np.ndarray:
        """Response of unit axles arriving at ``tau``, channels stacked, (n_t n_c, n_tau)."""
        x = speed * (self.t[:, None] - tau[None, :])
        return np.vstack([np.interp(x.ravel(), self.il_x, self.ords[:, c], left=0.0,
                                    right=0.0).reshape(x.shape) for c in range(self.n_c)])

    def project(self, G: np.ndarray) -> np.ndarray:
        """``G`` (channels stacked) without its offset, drift and nuisance components."""
        n = self.t.size
        out = G.copy()
        for c in range(self.n_c):
            blk = out[c * n:(c + 1) * n]
            blk -= self.basis @ (self.basis.T @ blk)
        return out

    def design(self, speed: float, tau: np.ndarray) -> np.ndarray:
        """Projected response of unit axles arriving at ``tau``, (n_t n_c, n_tau)."""
        return self.project(self.raw(speed, tau))

    def norm_b(self) -> float:
        return max(float(np.linalg.norm(self.b)), np.finfo(float).tiny)


def _pursuit(G: np.ndarray, b: np.ndarray, max_axles: int, min_gain: float
             ) -> tuple[np.ndarray, float]:
    """Non-negative orthogonal matching pursuit: add the column most correlated with the
    residual, refit the chosen columns by NNLS, until the residual falls by less than
    ``min_gain`` × ‖b‖.  Returns the loads (zero off the chosen columns), residual norm."""
    norms = np.linalg.norm(G, axis=0)
    norms[norms == 0] = np.inf
    chosen: list[int] = []
    a = np.zeros(G.shape[1])
    r, rn = b.copy(), float(np.linalg.norm(b))
    for _ in range(max_axles):
        j = int(np.argmax((G.T @ r) / norms))
        if j in chosen or G[:, j] @ r <= 0:
            break
        w, rn_new = nnls(G[:, [*chosen, j]], b)
        if rn - rn_new < min_gain * np.linalg.norm(b):
            break
        chosen.append(j)
        keep = w > 0
        chosen = [c for c, k in zip(chosen, keep, strict=True) if k]
        a[:] = 0.0
        a[chosen] = w[keep]
        r, rn = b - G[:, chosen] @ a[chosen], rn_new
    return a, rn


def _clusters(tau: np.ndarray, load: np.ndarray, merge: float, frac: float
              ) -> list[tuple[float, float]]:
    """(time, load) of each cluster of loaded grid times closer than ``merge`` s; clusters
    lighter than ``frac`` × the heaviest dropped."""
    on = np.flatnonzero(load > 0)
    if on.size == 0:
        return []
    groups, cur = [], [on[0]]
    for k in on[1:]:
        if tau[k] - tau[cur[-1]] <= merge:
            cur.append(k)
        else:
            groups.append(cur)
            cur = [k]
    groups.append(cur)
    out = [(float(load[g] @ tau[g] / load[g].sum()), float(load[g].sum())) for g in groups]
    top = max(w for _, w in out)
    return [(tt, w) for tt, w in out if w >= frac * top]


@dataclass(frozen=True, kw_only=True, eq=False)
class _Fit:
    speed: float
    times: np.ndarray
    loads: np.ndarray
    residual: float

    def score(self, penalty: float) -> float:
        return self.residual + penalty * self.times.size


def _refine(model: _Model, speed: float, tau: np.ndarray, offsets: np.ndarray | None,
            v_lo: float, v_hi: float) -> _Fit:
    """Least-squares speed and arrival times (free: every ``tau``; known layout:
    ``offsets`` and one arrival time), the loads by linear least squares inside."""

    def times(p):
        return p[1] + offsets / p[0] if offsets is not None else p[1:]

    def resid(p):
        G = model.design(p[0], times(p))
        a, *_ = np.linalg.lstsq(G, model.b, rcond=None)
        return G @ a - model.b

    p0 = np.concatenate([[np.clip(speed, v_lo, v_hi)], tau[:1] if offsets is not None
                         else tau])
    lo, hi = np.full(p0.size, -np.inf), np.full(p0.size, np.inf)
    lo[0], hi[0] = v_lo, v_hi
    dt = float(np.median(np.diff(model.t)))
    sol = least_squares(resid, p0, bounds=(lo, hi), method="trf", xtol=1e-8, ftol=1e-8,
                        x_scale=np.concatenate([[0.01 * p0[0]], np.full(p0.size - 1, dt)]),
                        max_nfev=50 * p0.size)
    v = float(sol.x[0])
    tt = np.sort(times(sol.x))
    G = model.design(v, tt)
    a, *_ = np.linalg.lstsq(G, model.b, rcond=None)
    rel = float(np.linalg.norm(G @ a - model.b) / model.norm_b())
    return _Fit(speed=v, times=tt, loads=a, residual=rel)


def _vibration_frequency(model: _Model, fit: _Fit, f_max: float) -> float | None:
    """The dominant frequency of a fit's residual between 2 Hz and ``f_max``, Hz; None
    when its spectrum has no clear peak (3 × the band's median)."""
    G = model.design(fit.speed, fit.times)
    res = (model.b - G @ fit.loads).reshape(model.n_c, -1).sum(axis=0)
    spec = np.abs(np.fft.rfft(res * np.hanning(res.size)))
    freq = np.fft.rfftfreq(res.size, float(np.median(np.diff(model.t))))
    band = np.flatnonzero((freq >= 2.0) & (freq <= f_max))
    if band.size < 3:
        return None
    k = band[int(np.argmax(spec[band]))]
    if k in (band[0], band[-1]) or spec[k] < 3.0 * np.median(spec[band]):
        return None
    return float(parabolic_vertex(spec, np.array([k]))[0] * (freq[1] - freq[0]))


def _vibration_basis(t: np.ndarray, t_start: float, f: float) -> np.ndarray:
    """Sine and cosine at ``f`` Hz times hat functions every ``_VIBRATION_KNOT`` s from
    ``t_start`` (a slowly varying amplitude and phase), shape (n_t, k)."""
    tt = t - t_start
    knots = np.arange(0.0, tt[-1] + _VIBRATION_KNOT, _VIBRATION_KNOT)
    hats = np.clip(1.0 - np.abs(tt[:, None] - knots[None, :]) / _VIBRATION_KNOT, 0.0, None)
    w = 2.0 * np.pi * f * tt[:, None]
    return np.hstack([hats * np.sin(w), hats * np.cos(w)])


def _merge_close(times: np.ndarray, loads: np.ndarray, gap: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Axles closer than ``gap`` s merged into one (load-weighted time, summed load)."""
    t_out, w_out = [float(times[0])], [float(loads[0])]
    for t, w in zip(times[1:], loads[1:], strict=True):
        if t - t_out[-1] < gap and w_out[-1] + w > 0:
            total = w_out[-1] + w
            t_out[-1] = (t_out[-1] * max(w_out[-1], 0.0) + t * max(w, 0.0)) / max(
                max(w_out[-1], 0.0) + max(w, 0.0), np.finfo(float).tiny)
            w_out[-1] = total
        else:
            t_out.append(float(t))
            w_out.append(float(w))
    return np.array(t_out), np.array(w_out)


def _decimate(t: np.ndarray, readings: np.ndarray, q: int) -> tuple[np.ndarray, np.ndarray]:
    nd = t.size // q
    return (t[:nd * q].reshape(nd, q).mean(axis=1),
            readings[:nd * q].reshape(nd, q, -1).mean(axis=1))


def _search(coarse: _Model, full: _Model, *, offsets: np.ndarray | None, v_lo: float,
            v_hi: float, n_speeds: int, frac: float, min_sp: float,
            support: tuple[float, float]) -> _Fit | None:
    """Trial speeds on ``coarse``, the best refined on ``coarse``, the winner on ``full``."""
    x0, x1 = support
    td = coarse.t
    step = float(np.median(np.diff(td)))
    nb = coarse.norm_b()
    trials: list[tuple[float, float, np.ndarray]] = []  # (score, speed, arrival times)
    for v in np.geomspace(v_lo, v_hi, n_speeds):
        if offsets is None:
            # arrival times whose response is centred inside the record
            mid = 0.5 * (x0 + x1) / v
            tau = np.arange(td[0] - mid, td[-1] - mid + step, step)
            a, rn = _pursuit(coarse.design(v, tau), coarse.b, _MAX_AXLES, _MIN_GAIN)
            cl = _clusters(tau, a, min_sp / v, frac)
            if cl:
                trials.append((rn / nb + _AXLE_PENALTY * len(cl), float(v),
                               np.array([c[0] for c in cl])))
        else:
            # the unit-load response of the layout, correlated with the readings at
            # every arrival time on the grid
            tau = np.arange(td[0] - (x1 + offsets[-1]) / v, td[-1] - x0 / v + step, step)
            arrivals = (tau[:, None] + offsets[None, :] / v).ravel()
            unit = coarse.project(coarse.raw(v, arrivals).reshape(-1, tau.size, offsets.size)
                                  .sum(axis=2))
            nrm = np.linalg.norm(unit, axis=0)
            score = np.where(nrm > 0, (coarse.b @ unit) / np.where(nrm > 0, nrm, 1.0),
                             -np.inf)
            t0 = tau[int(np.argmax(score))]
            _, rn = nnls(coarse.design(v, t0 + offsets / v), coarse.b)
            trials.append((rn / nb, float(v), np.array([t0])))
    if not trials:
        return None
    trials.sort(key=lambda z: z[0])
    fits = [_refine(coarse, v, tau, offsets, v_lo, v_hi) for _, v, tau in trials[:_N_REFINE]]
    best = min(fits, key=lambda f: f.score(_AXLE_PENALTY))
    return _refine(full, best.speed, best.times if offsets is None else best.times[:1],
                   offsets, v_lo, v_hi)


def detect_from_strain(
    record: Record,
    influence_line: InfluenceLine,
    *,
    channels: Sequence[str] | None = None,
    known_spacings: Sequence[float] | None = None,
    vibration: bool = True,
    n_speeds: int = 24,
    rate: float = 128.0,
    min_axle_fraction: float = 0.1,
    **options: Any,
) -> Detection:
    """Vehicles (speed, axles, spacings, arrival, lateral position) from the strain alone.

    Parameters
    ----------
    record : Record
        Holds every sensor of the influence line's channels.
    influence_line : InfluenceLine
        Calibrated or from a model; its frame is the passages' frame.
    channels : sequence of str, optional
        Names of the line's channels to fit (default all).
    known_spacings : sequence of float, optional
        Axle spacings of a known vehicle (m): fit only its speed and arrival time.
    vibration : bool
        Refit with the bridge's vibration at the residual's dominant frequency projected
        out (see the module docstring).
    n_speeds : int
        Trial speeds of the search (≥ 4).
    rate : float
        Rate the readings are block-averaged to for the search, Hz.
    min_axle_fraction : float
        Deconvolved axles lighter than this fraction of the heaviest are dropped.
    **options
        The keywords of :class:`~bwim.detect.options.DetectOptions`: ``speed_range``,
        ``min_axle_spacing``, ``max_axle_spacing``, ``span`` (None: the influence line's
        support), ``gauges``, ``lateral_threshold``, ``unexplained_fraction``.

    Returns
    -------
    Detection
        ``method="strain"``; confidence as in the module docstring.
    """
    require_instance("record", record, Record)
    require_instance("influence_line", influence_line, InfluenceLine)
    opts = DetectOptions(**options)
    il = influence_line
    if channels is None:
        idx = list(range(len(il.channels)))
    else:
        if isinstance(channels, str):
            channels = [channels]
        idx = []
        for c in channels:
            if c not in il.channel_names:
                raise InputError(f"channels: the influence line has no channel {c!r}; it has "
                                 f"{list(il.channel_names)}")
            idx.append(il.channel_names.index(c))
    v_lo, v_hi = opts.speed_range
    if int(n_speeds) < 4:
        raise InputError(f"n_speeds must be at least 4, got {n_speeds!r}")
    rate = require_positive("rate", rate)
    frac = float(min_axle_fraction)
    if not 0.0 <= frac < 1.0:
        raise InputError(f"min_axle_fraction must lie in [0, 1), got {min_axle_fraction!r}")
    min_sp, max_sp = opts.min_axle_spacing, opts.max_axle_spacing
    offsets = None
    if known_spacings is not None:
        ks = np.array(known_spacings, dtype=float, ndmin=1)
        if ks.ndim != 1 or not np.all(np.isfinite(ks)) or np.any(ks <= 0):
            raise InputError(f"known_spacings must be positive distances, got "
                             f"{np.asarray(known_spacings).tolist()}")
        offsets = np.concatenate([[0.0], np.cumsum(ks)])
    span_x = resolve_span(il if opts.span is None else opts.span)
    chans = [il.channels[k] for k in idx]
    ords = il.ordinates[:, idx]
    scale = np.abs(ords).max(axis=0)
    if np.any(scale == 0):
        raise InputError("the influence line is zero in a channel")
    ords = ords / scale
    readings = np.column_stack([c.read(record) for c in chans]) / scale
    gauge_sens = section_gauges(record, opts.gauges)
    x0, x1 = il.support
    t = record.time
    method = "strain"

    full = _Model(t, readings, il.x, ords)
    if np.linalg.norm(full.b) == 0:
        return Detection(flags=(FLAG_NO_AXLES,), message="the strain readings are flat",
                         method=method)
    q = max(1, int(record.sampling_rate // rate))
    td, rd = _decimate(t, readings, q)
    search = dict(offsets=offsets, v_lo=v_lo, v_hi=v_hi, n_speeds=int(n_speeds), frac=frac,
                  min_sp=min_sp, support=(x0, x1))
    fit = _search(_Model(td, rd, il.x, ords), full, **search)
    if fit is None:
        return Detection(flags=(FLAG_NO_AXLES,), message="no axle load found in the "
                         "strain readings", method=method)
    if vibration:
        f = _vibration_frequency(full, fit, min(_VIBRATION_MAX_HZ, 0.25 * rate))
        if f is not None:
            again = _search(_Model(td, rd, il.x, ords, nuisance=_vibration_basis(td, t[0], f)),
                            _Model(t, readings, il.x, ords,
                                   nuisance=_vibration_basis(t, t[0], f)), **search)
            fit = fit if again is None else again
    tt, loads, v = fit.times, fit.loads, fit.speed
    if loads.max() <= 0:
        return Detection(flags=(FLAG_NO_AXLES,), message="no positive axle load fits the "
                         "strain readings (is the influence line's sign right?)",
                         method=method)
    if offsets is None:
        tt, loads = _merge_close(tt, loads, min_sp / v)
        keep = loads >= frac * loads.max()
        tt, loads = tt[keep], loads[keep]
    groups = np.split(np.arange(tt.size), np.flatnonzero(np.diff(tt) * v > max_sp) + 1)
    conf = 0.5 * float(np.clip(1.0 - fit.residual / _RESIDUAL_ZERO, 0.0, 1.0))
    estimates = []
    for g in groups:
        flags = [FLAG_STRAIN_ONLY] + ([FLAG_SINGLE_AXLE] if g.size == 1 else [])
        top = loads[g].max()
        estimates.append(VehicleEstimate(
            times=tt[g], speed=v, confidence=conf * (0.5 if g.size == 1 else 1.0),
            flags=tuple(flags), amplitudes=loads[g] / top if top > 0 else loads[g],
            snr=1.0 / max(fit.residual, 1e-12), residual=fit.residual))
    return assemble_detection(record, estimates, method=method, span=span_x,
                              gauges=gauge_sens, lateral_threshold=opts.lateral_threshold,
                              unexplained_fraction=opts.unexplained_fraction)
