"""A vehicle of known axle loads and spacings found from the strain alone, with the
influence line unknown (the calibration truck of a site without axle detectors).

Contract
--------
* Model: the sum ``s(t)`` of the section's gauges is ``Σ_i W_i I(v (t − t_a) − a_i)`` plus
  an offset and a linear drift, with ``W_i`` the known static axle loads (N), ``a_i`` the
  known distances of axle i behind the first (m) and ``I`` an unknown line (reading per N).
  The known spacings fix the time separations ``a_i / v`` of the axles, so the speed is
  identifiable although the line's length is not known: a wrong speed needs a line
  longer than the signal allows.
* ``t_a``/``t_b``: where the summed signal (its offset the median of the first and last
  10 % of the record) first and last exceeds ``signal_threshold`` × its peak.  For a trial
  speed ``v`` the line's support is from ``−margin v`` to
  ``v (t_b − t_a) − a_last + margin v`` (m, ``margin`` in s): the first axle enters it at
  ``t_a``, the last leaves at ``t_b``.  The line's ordinates (spacing ``spacing`` m, end
  ordinates zero, second-difference smoothing of length ``smoothing`` m as in
  :func:`bwim.wim.calibrate_influence_line`), offset and drift are fitted by linear least
  squares; the relative residual ‖fit − s‖ / ‖s − mean‖ is minimised over ``v``: a
  grid of line lengths shared by the runs (each run's speed follows from its window),
  then (``joint=True``, default) every run's speed and arrival by nonlinear least squares
  with one line shared by all runs (variable projection: the line, offsets and drifts
  linear inside; the first run's arrival fixes the frame), or (``joint=False``) each
  run's speed alone by a bounded Brent search of its own residual.
* Frame: the run's line is shifted so that its centroid (of its part of the peak's sign)
  is at ``x = 0``; the returned passage's ``delay`` is when the first axle passes that
  centroid.  The centroid of a summed-gauge line sits near the instrumented section, and
  is the same point for every run up to the run's dynamics: lines calibrated with such
  passages, and vehicles detected against them, share this frame.
* Accuracy is limited by the truck's and the bridge's dynamics (a static model): even
  started at the true speeds the joint optimum moves; measured by
  ``tests/validation/test_site_strain_only.py``.
* Times in s (record time), distances in m, speeds in m/s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg
from scipy.optimize import least_squares, minimize_scalar

from bwim.errors import InputError, require_instance, require_positive
from bwim.records import Record
from bwim.wim.influence_line import hat_design, smoothing_penalty

from .assemble import VehicleEstimate, assemble_detection
from .lateral import section_gauges
from .options import check_speed_range
from .result import FLAG_NO_AXLES, FLAG_STRAIN_ONLY, Detection

__all__ = ["detect_known_truck"]

#: Confidence of a strain-only truck detection reaches zero at this relative residual.
_RESIDUAL_ZERO = 0.25


class _Problem:
    """The summed signal on a (block-averaged) time axis and the fit of one trial speed."""

    def __init__(self, t: np.ndarray, s: np.ndarray, loads: np.ndarray, offsets: np.ndarray,
                 t_a: float, t_b: float, margin: float, spacing: float,
                 smoothing: float) -> None:
        self.t, self.s = t, s
        self.loads, self.offsets = loads, offsets
        self.t_a, self.t_b, self.margin = t_a, t_b, margin
        self.spacing, self.smoothing = spacing, smoothing
        tc = (t - t.mean()) / max(np.ptp(t), 1e-12)
        self.nuisance = np.column_stack([np.ones_like(t), tc])
        self.norm = max(float(np.linalg.norm(s - s.mean())), np.finfo(float).tiny)

    def support(self, v: float) -> tuple[float, float]:
        return (-self.margin * v,
                v * (self.t_b - self.t_a) - self.offsets[-1] + self.margin * v)

    def fit(self, v: float) -> tuple[float, np.ndarray, np.ndarray]:
        """Relative residual, the line's nodes and ordinates (end zeros included)."""
        x0, x1 = self.support(v)
        if x1 - x0 < 4 * self.spacing:
            return np.inf, np.zeros(0), np.zeros(0)
        n = max(int(np.ceil((x1 - x0) / self.spacing)), 4)
        h = (x1 - x0) / n
        pos = v * (self.t[:, None] - self.t_a) - self.offsets[None, :]
        G = hat_design(pos, self.loads, x0, h, n).toarray()
        A = np.hstack([G, self.nuisance])
        N = A.T @ A
        m = n - 1
        scale = float(np.mean(np.diag(N[:m, :m])))
        if scale <= 0:
            return np.inf, np.zeros(0), np.zeros(0)
        N[:m, :m] += scale * smoothing_penalty(m, self.smoothing, h)
        N[m:, m:] += 1e-12 * np.eye(N.shape[0] - m) * max(scale, 1.0)
        try:
            p = scipy.linalg.solve(N, A.T @ self.s, assume_a="pos")
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
            return np.inf, np.zeros(0), np.zeros(0)
        rel = float(np.linalg.norm(A @ p - self.s) / self.norm)
        ords = np.concatenate([[0.0], p[:m], [0.0]])
        return rel, x0 + h * np.arange(n + 1), ords


def _window(t: np.ndarray, s: np.ndarray, threshold: float) -> tuple[float, float, float]:
    """(t_a, t_b, sign of the peak) of the summed signal."""
    edge = max(1, t.size // 10)
    dev = s - np.median(np.concatenate([s[:edge], s[-edge:]]))
    k = max(1, round(0.03 / float(np.median(np.diff(t)))))
    smooth = np.convolve(dev, np.ones(k) / k, mode="same")
    sign = 1.0 if smooth.max() >= -smooth.min() else -1.0
    env = sign * smooth
    on = np.flatnonzero(env > threshold * env.max())
    return float(t[on[0]]), float(t[on[-1]]), sign


def detect_known_truck(
    records: Sequence[Record] | Record,
    axle_loads: Sequence[float],
    axle_spacings: Sequence[float],
    *,
    speed_range: tuple[float, float] = (5.0, 40.0),
    n_lengths: int = 60,
    refine: float = 0.08,
    rate: float = 128.0,
    spacing: float = 0.15,
    smoothing: float = 0.3,
    margin: float = 0.05,
    signal_threshold: float = 0.05,
    gauges: Sequence[str] | None = None,
    lateral_threshold: float = 0.5,
    joint: bool = True,
) -> tuple[Detection, ...]:
    """Each run's truck speed, arrival and lateral position from the strain, line unknown.

    The runs cross one bridge: the line's length ``L`` is shared.  For each trial ``L``
    (``n_lengths`` values geometric between the lengths the speed range allows) every run's
    speed follows from its signal window, ``v = (L + a_last) / (t_b − t_a)``, and the
    runs' relative residuals (each capped at 1) are summed; at the best ``L`` each run's
    speed is refined alone within ``± refine`` (relative) by a bounded Brent search of its
    own residual.  (A run alone cannot tell a short line at the right speed from a long
    line at a wrong one when the bridge's vibration is large; the shared length can.)

    Parameters
    ----------
    records : Record or sequence of Record
        Runs of the truck (their strain gauges; other channels are ignored).
    axle_loads : sequence of float
        The truck's static axle loads, N.
    axle_spacings : sequence of float
        Its axle spacings, m (one fewer than the loads).
    speed_range : (float, float)
        Plausible speeds, m/s.
    n_lengths : int
        Trial line lengths (≥ 4).
    refine : float
        Relative speed range of each run's own refinement, in (0, 0.5).
    rate : float
        The summed readings are block-averaged to about this rate for the search, Hz.
    spacing, smoothing : float
        The trial line's ordinate spacing and smoothing length, m.
    margin : float
        Support beyond the signal's significant window at each end, s.
    signal_threshold : float
        Fraction of the summed signal's peak that marks its window, in (0, 1).
    gauges : sequence of str, optional
        Gauges summed and used for the lateral position (default
        :func:`~bwim.detect.section_gauges`).
    lateral_threshold : float
        As in :func:`~bwim.detect.lateral_position`.

    Returns
    -------
    tuple of Detection
        One per record: one vehicle (``method="strain"``, flag ``strain_only``) in the
        frame of the module docstring, or none with the reason in ``message``.
    """
    recs = [records] if isinstance(records, Record) else list(records)
    if not recs:
        raise InputError("records: give at least one run")
    for k, r in enumerate(recs):
        require_instance(f"records[{k}]", r, Record)
    loads = np.array(axle_loads, dtype=float, ndmin=1)
    if loads.ndim != 1 or not np.all(np.isfinite(loads)) or np.any(loads <= 0):
        raise InputError("axle_loads must be positive static axle loads, N")
    spacings = np.array(axle_spacings, dtype=float, ndmin=1)
    if spacings.ndim != 1 or spacings.size != loads.size - 1 or np.any(spacings <= 0):
        raise InputError(f"axle_spacings must be {loads.size - 1} positive distances, m")
    v_lo, v_hi = check_speed_range(speed_range)
    if int(n_lengths) < 4:
        raise InputError(f"n_lengths must be at least 4, got {n_lengths!r}")
    if not 0.0 < float(refine) < 0.5:
        raise InputError(f"refine must lie in (0, 0.5), got {refine!r}")
    rate = require_positive("rate", rate)
    spacing = require_positive("spacing", spacing)
    smoothing = require_positive("smoothing", smoothing)
    margin = require_positive("margin", margin)
    thr = float(signal_threshold)
    if not 0.0 < thr < 1.0:
        raise InputError(f"signal_threshold must lie in (0, 1), got {signal_threshold!r}")
    offsets = np.concatenate([[0.0], np.cumsum(spacings)])
    a_last = float(offsets[-1])

    out: list[Detection | None] = [None] * len(recs)
    probs: dict[int, tuple[_Problem, _Problem, list]] = {}
    for k, rec in enumerate(recs):
        sens = section_gauges(rec, gauges)
        if not sens:
            raise InputError(f"records[{k}]: no strain gauges to find the truck with")
        s_full = rec.channels([g.name for g in sens]).data.sum(axis=1)
        if np.ptp(s_full) == 0:
            out[k] = Detection(flags=(FLAG_NO_AXLES,), message="the strain readings are "
                               "flat", method="strain")
            continue
        t_full = rec.time
        q = max(1, int(rec.sampling_rate // rate))
        nd = t_full.size // q
        t = t_full[:nd * q].reshape(nd, q).mean(axis=1)
        s = s_full[:nd * q].reshape(nd, q).mean(axis=1)
        t_a, t_b, sign = _window(t, s, thr)
        if t_b - t_a <= 0:
            out[k] = Detection(flags=(FLAG_NO_AXLES,), message="no strain signal above "
                               "the noise", method="strain")
            continue
        coarse = _Problem(t, sign * s, loads, offsets, t_a, t_b, margin, spacing, smoothing)
        full = _Problem(t_full, sign * s_full, loads, offsets, t_a, t_b, margin, spacing,
                        smoothing)
        probs[k] = (coarse, full, sens)
    if not probs:
        return tuple(out)
    # the shared line length: every run's speed follows from it and its window
    durations = np.array([p[0].t_b - p[0].t_a for p in probs.values()])
    l_lo = max(4 * spacing, float(np.min(v_lo * durations)) - a_last)
    l_hi = float(np.max(v_hi * durations)) - a_last
    if l_hi <= l_lo:
        for k in probs:
            out[k] = Detection(flags=(FLAG_NO_AXLES,), message="the signal is too short "
                               "for the truck's axle layout at any speed in the range",
                               method="strain")
        return tuple(out)
    lengths = np.geomspace(l_lo, l_hi, int(n_lengths))

    def total(length: float) -> float:
        cost = 0.0
        for coarse, _, _ in probs.values():
            v = (length + a_last) / (coarse.t_b - coarse.t_a)
            cost += min(coarse.fit(v)[0], 1.0) if v_lo <= v <= v_hi else 1.0
        return cost

    length = float(lengths[int(np.argmin([total(x) for x in lengths]))])
    keys = list(probs)
    v0 = np.array([np.clip((length + a_last) / (probs[k][0].t_b - probs[k][0].t_a),
                           v_lo, v_hi) for k in keys])
    if joint and len(keys) > 1:
        speeds, arrivals = _joint(
            [probs[k][0] for k in keys], v0, np.array([probs[k][0].t_a for k in keys]),
            (-margin * float(v0.min()), length + margin * float(v0.max())), v_lo, v_hi)
    else:
        speeds, arrivals = v0, np.array([probs[k][0].t_a for k in keys])
    for j, k in enumerate(keys):
        coarse, full, sens = probs[k]
        if not joint:
            lo, hi = max(v_lo, v0[j] * (1 - refine)), min(v_hi, v0[j] * (1 + refine))
            sol = minimize_scalar(lambda v, c=coarse: c.fit(v)[0], bounds=(lo, hi),
                                  method="bounded", options={"xatol": 1e-4 * v0[j]})
            speeds[j] = float(sol.x)
        full.t_a = float(arrivals[j])
        out[k] = _detection(recs[k], full, float(speeds[j]), offsets, loads, sens,
                            lateral_threshold)
    return tuple(out)


def _joint(probs: list[_Problem], v0: np.ndarray, ta0: np.ndarray,
           support: tuple[float, float], v_lo: float, v_hi: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """Every run's speed and arrival with one line shared by all runs (variable
    projection: the line, each run's offset and drift by linear least squares inside);
    the first run's arrival fixes the frame."""
    x0, x1 = support
    h = probs[0].spacing
    n = max(int(np.ceil((x1 - x0) / h)), 4)
    h = (x1 - x0) / n
    m = n - 1
    K = len(probs)
    pen = smoothing_penalty(m, probs[0].smoothing, h)
    norms = [p.norm for p in probs]

    def solve(z):
        v, ta = np.exp(z[:K]), np.concatenate([[ta0[0]], z[K:2 * K - 1]])
        c = np.ones(K)
        rows = []
        for j, p in enumerate(probs):
            pos = v[j] * (p.t[:, None] - ta[j]) - p.offsets[None, :]
            G = hat_design(pos, p.loads, x0, h, n).toarray() * (c[j] / norms[j])
            nu = np.zeros((p.t.size, 2 * K))
            nu[:, 2 * j:2 * j + 2] = p.nuisance / norms[j]
            rows.append(np.hstack([G, nu]))
        A = np.vstack(rows)
        b = np.concatenate([p.s / nj for p, nj in zip(probs, norms, strict=True)])
        N = A.T @ A
        scale = max(float(np.mean(np.diag(N[:m, :m]))), np.finfo(float).tiny)
        N[:m, :m] += scale * pen
        N[m:, m:] += 1e-10 * scale * np.eye(2 * K)
        try:
            coef = scipy.linalg.solve(N, A.T @ b, assume_a="pos")
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
            return np.full(b.size, 1e3)
        return A @ coef - b

    # per-run scale factors (the day's strain-to-load drift) are not fitted: freeing them
    # trades scale for speed (the speed error grows; tests/validation/test_site_strain_only.py)
    z0 = np.concatenate([np.log(v0), ta0[1:]])
    lo = np.concatenate([np.full(K, np.log(v_lo)), ta0[1:] - 0.5])
    hi = np.concatenate([np.full(K, np.log(v_hi)), ta0[1:] + 0.5])
    dt = float(np.median(np.diff(probs[0].t)))
    sol = least_squares(solve, np.clip(z0, lo, hi), bounds=(lo, hi), method="trf",
                        x_scale=np.concatenate([np.full(K, 0.01), np.full(K - 1, dt)]),
                        diff_step=1e-4, max_nfev=100 * K)
    return np.exp(sol.x[:K]), np.concatenate([[ta0[0]], sol.x[K:2 * K - 1]])


def _detection(record: Record, full: _Problem, v: float, offsets: np.ndarray,
               loads: np.ndarray, sens, lateral_threshold: float) -> Detection:
    """The run's Detection at speed ``v``, in the centroid frame (module docstring)."""
    rel, x, ords = full.fit(v)
    part = np.clip(ords, 0.0, None)
    if not np.isfinite(rel) or part.sum() <= 0:
        return Detection(flags=(FLAG_NO_AXLES,), message="no line of the truck's sign fits "
                         "the strain readings", method="strain")
    centroid = float(part @ x / part.sum())
    delay = full.t_a + centroid / v
    conf = 0.5 * float(np.clip(1.0 - rel / _RESIDUAL_ZERO, 0.0, 1.0))
    est = VehicleEstimate(times=delay + offsets / v, speed=v, confidence=conf,
                          flags=(FLAG_STRAIN_ONLY,), amplitudes=loads / loads.max(),
                          snr=1.0 / max(rel, 1e-12), residual=rel)
    return assemble_detection(record, [est], method="strain",
                              span=(x[0] - centroid, x[-1] - centroid), gauges=sens,
                              lateral_threshold=lateral_threshold)
