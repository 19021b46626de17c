"""An axle detector's own response to one axle, learned from the calibration truck's runs.

Real axle detectors do not give sharp pulses: a strain sensor near the surface sees each
axle as a peak about a metre wide, on the slab's global bending, which pulls its baseline
below zero between axle groups, and closely spaced axles (a tridem 1.3 m apart) merge.
A detector that looks for separated peaks fails exactly there; one that knows the
detector's response to one axle can take the merged peaks apart (:mod:`bwim.detect.pursuit`).

Contract
--------
* A :class:`DetectorResponse` is ``K(u)``: an axle's **local** response at one detector
  when the axle is ``u`` metres past it (``u < 0``: not yet there), piecewise linear on a
  uniform grid over ``|u| ≤`` :data:`NEAR`, zero beyond, as seen through a spatial
  **high-pass** (:func:`high_pass`: a signal less its Gaussian average over
  :data:`HIGH_PASS` m of travel): the high-passed readings are modelled as the high-pass
  of ``Σ_i A_i K(u_i)``.  The span's global bending, which pulls a detector's baseline
  down between axle groups, depends on every axle on the span and no single response
  holds it; the high-pass takes it out of readings and model alike, with any offset and
  drift, and leaves what identifies an axle: its own local peak.  Normalised so that
  its largest magnitude is 1, at ``u = 0``, with its sign kept (a detector whose pulses go
  negative has a negative peak): the axle's own peak defines where the detector is.
* :func:`learn_responses` fits both detectors' responses to the runs of a calibration
  truck whose axle spacings ``a_i`` are known.  High-passed reading of detector ``d`` in
  run ``r``::

      y_rd(t) = Σ_i A_id K_d(v_r (t − τ_r) − a_i − D_d) + e,    D_1 = 0, D_2 = D,

  with ``v_r`` the run's speed, ``τ_r`` when its first axle passes detector 1 and
  ``A_id = g_d f_i`` each axle's amplitude (shared by the runs: the same truck; a
  visibility ``f_i ≥ 0`` per axle that both detectors share, since a steering axle's
  single tyres are seen weaker by both, and a gain ``g_d`` per detector).  For fixed
  amplitudes ``K_d`` is linear least squares on the matrix method's hat functions with
  a light second-difference smoothing; for fixed responses the visibilities are
  non-negative least squares and the gains a ratio (alternated); each response is
  re-centred on its peak; then each run's ``(τ_r, v_r)`` is refitted to both detectors
  at once by nonlinear least squares (the declared distance ``D`` sets the speeds), and
  the cycle repeated.  The known spacing of two separate axles checks ``D``
  independently of the responses' shapes (the time between their peaks at detector 1):
  the difference is :attr:`LearnedResponses.distance_offset`; beyond
  :data:`DISTANCE_TOLERANCE` of ``D`` the calibration is refused.
* Start: each run's speed from the cross-correlation of the band-passed detectors over
  the declared distance, its first axle by aligning the known layout with a bump of one
  metre; runs whose fit stays poor (relative residual beyond the median by
  :data:`RUN_OUTLIER` robust standard deviations and 1.5 times it: another vehicle on the
  detectors) are left out and named in ``reasons``.
* Units: u and spacings in m, time in s, speeds in m/s; readings in the logger's units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.ndimage import gaussian_filter1d
from scipy.optimize import least_squares, nnls

from bwim.errors import InputError, NumericalError, require_positive
from bwim.records import Record, axle_offsets, record_list
from bwim.wim.influence_line import hat_design

from .options import check_speed_range
from .signals import robust_sigma

__all__ = ["DISTANCE_TOLERANCE", "HIGH_PASS", "NEAR", "RUN_OUTLIER", "DetectorResponse",
           "LearnedResponses", "band_pass", "high_pass", "learn_responses", "xcorr_lag"]

#: A declared detector distance off by more than this share is refused (the runs'
#: known spacings contradict it).
DISTANCE_TOLERANCE = 0.05
#: A run whose relative residual exceeds the median by this many robust standard
#: deviations (and 1.5 × the median) is left out of the responses.
RUN_OUTLIER = 4.0
#: Half-width of an axle's local response, m.
NEAR = 1.5
#: Length of the spatial high-pass, m (σ of the Gaussian average taken off): an axle's
#: local peak (about a metre wide) passes, the span's bending (several metres) does not.
HIGH_PASS = 0.6


def high_pass(y: np.ndarray, sigma: float) -> np.ndarray:
    """``y`` (along axis 0) less its Gaussian average of ``sigma`` samples."""
    return y - gaussian_filter1d(y, sigma, axis=0, mode="nearest")


def band_pass(y: np.ndarray, fs: float, *, short: float = 0.01, long: float = 0.06
              ) -> np.ndarray:
    """``y`` (n_t,) or (n_t, k) smoothed over ``short`` s less smoothed over ``long`` s
    (Gaussian σ): the axles' peaks (tens of ms wide at road speeds) stay, offsets and the
    slab's global bending (hundreds of ms) go.  Used where only timing matters (the
    detectors' lag, aligning a layout, timing two peaks)."""
    return (gaussian_filter1d(y, short * fs, axis=0, mode="nearest")
            - gaussian_filter1d(y, long * fs, axis=0, mode="nearest"))


@dataclass(frozen=True, kw_only=True, eq=False)
class DetectorResponse:
    """One detector's local, high-passed response to one axle (see the module docstring).

    Attributes
    ----------
    channel : str
        The logger channel.
    u : ndarray, shape (n,)
        Grid of axle distances past the detector, m, ascending and uniform.
    k : ndarray, shape (n,)
        ``K(u)`` on the grid: reading per unit amplitude (before the high-pass);
        ``K(0)`` is ±1.
    noise : float
        The channel's noise standard deviation in the runs, reading units.
    misfit : float
        Root-mean-square of the runs' residual while the truck crosses, reading units:
        what one response cannot explain of a real axle (its dynamic force while it
        passes, its tyres and lateral position), the level an axle must stand out of.
    """

    channel: str
    u: np.ndarray
    k: np.ndarray
    noise: float
    misfit: float = 0.0

    @property
    def level(self) -> float:
        """The larger of ``noise`` and ``misfit``: the scale detection weighs with."""
        return max(self.noise, self.misfit)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """``K`` at distances ``u`` (m), zero outside the grid."""
        return np.interp(u, self.u, self.k, left=0.0, right=0.0)

    def high_passed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The response high-passed in space (:data:`HIGH_PASS` m), on a grid widened by
        the filter's reach: ``(u, K_hp, dK_hp/du)``.  For a vehicle at speed ``v`` the
        high-pass in time over ``HIGH_PASS / v`` s of a reading is this in space, so
        detection compares high-passed readings with ``K_hp`` directly."""
        du = float(self.u[1] - self.u[0])
        pad = int(np.ceil(5 * HIGH_PASS / du))
        u = self.u[0] + du * np.arange(-pad, self.u.size + pad)
        k = self(u)
        k_hp = k - gaussian_filter1d(k, HIGH_PASS / du, mode="constant")
        return u, k_hp, np.gradient(k_hp, du)

    @property
    def sign(self) -> float:
        """+1 for pulses that rise, −1 for pulses that fall."""
        return float(np.sign(self.k[int(np.argmax(np.abs(self.k)))]) or 1.0)

    @property
    def fwhm(self) -> float:
        """Full width of the axle's local peak at half its height, m."""
        k = self.sign * self.k
        j0 = int(np.argmax(k))
        half = 0.5 * k[j0]
        lo = j0
        while lo > 0 and k[lo] > half:
            lo -= 1
        hi = j0
        while hi < k.size - 1 and k[hi] > half:
            hi += 1

        def cross(a: int, b: int) -> float:
            f = (half - k[a]) / (k[b] - k[a]) if k[b] != k[a] else 0.0
            return float(self.u[a] + f * (self.u[b] - self.u[a]))

        return cross(hi - 1, hi) - cross(lo, lo + 1)


@dataclass(frozen=True, kw_only=True, eq=False)
class LearnedResponses:
    """Both detectors' responses learned from calibration runs (:func:`learn_responses`).

    Attributes
    ----------
    responses : (DetectorResponse, DetectorResponse)
        In the order traffic meets the detectors.
    distance : float
        The declared distance between them, m.
    amplitudes : ndarray, shape (n_axles, 2)
        The calibration truck's axle amplitudes at each detector (reading units).
    speeds, first_axle_times, residuals : ndarray, shape (n_runs,)
        Each run's fitted speed (m/s), the time its first axle passes detector 1 (s) and
        its relative residual (NaN for a run left out).
    reasons : tuple of str
        Why a run was left out ("" when used).
    distance_offset : float
        The distance the truck's known spacings give less the declared one, m (the
        speeds are measured through the declared distance: a small offset is the
        measurement's noise, a large one refuses the calibration).
    nit : int
        Outer iterations made.
    """

    responses: tuple[DetectorResponse, DetectorResponse]
    distance: float
    amplitudes: np.ndarray
    speeds: np.ndarray
    first_axle_times: np.ndarray
    residuals: np.ndarray
    reasons: tuple[str, ...]
    distance_offset: float
    nit: int

    @property
    def channels(self) -> tuple[str, str]:
        return self.responses[0].channel, self.responses[1].channel


def xcorr_lag(y1: np.ndarray, y2: np.ndarray, lo: int, hi: int) -> float | None:
    """Sub-sample lag (samples) in ``[lo, hi]`` maximising ``Σ y1[n] y2[n + L]``; None if
    the maximum lies on a bound or nothing correlates."""
    n = y1.size
    lo, hi = max(int(lo), 1), min(int(hi), n - 2)
    if hi - lo < 2:
        return None
    spec = np.fft.rfft(y1[::-1], 2 * n) * np.fft.rfft(y2, 2 * n)
    full = np.fft.irfft(spec, 2 * n)  # index n-1+L  <->  lag L
    r = full[n - 1 + lo:n - 1 + hi + 1]
    k = int(np.argmax(r))
    if k == 0 or k == r.size - 1 or r[k] <= 0:
        return None
    den = r[k - 1] - 2 * r[k] + r[k + 1]
    shift = 0.5 * (r[k - 1] - r[k + 1]) / den if den < 0 else 0.0
    return float(lo + k + np.clip(shift, -0.5, 0.5))


def peak_polarity(z: np.ndarray) -> np.ndarray:
    """+1 or −1 per column of band-passed readings: the sign of their larger excursion."""
    return np.where(z.max(axis=0) >= -z.min(axis=0), 1.0, -1.0)


def _bump(u: np.ndarray) -> np.ndarray:
    """A smooth bump of 1 m full width at half maximum: the first guess of a response."""
    return np.exp(-4.0 * np.log(2.0) * u**2)


@dataclass
class _Run:
    t: np.ndarray
    y: np.ndarray  # (n_t, 2), high-passed
    sigma: float  # samples of the high-pass
    tau: float
    v: float


def _start(rec: Record, chans: tuple[str, str], distance: float, offsets: np.ndarray,
           loads: np.ndarray, v_range: tuple[float, float]) -> _Run:
    """Speed from the detectors' lag, first axle by aligning the layout with a bump."""
    raw = rec.channels(list(chans)).data.astype(float)
    t = rec.time
    fs = rec.sampling_rate
    z = band_pass(raw, fs)
    z = z * peak_polarity(z)
    lag = xcorr_lag(z[:, 0], z[:, 1], np.floor(distance / v_range[1] * fs),
                    np.ceil(distance / v_range[0] * fs))
    if lag is None:
        raise InputError("the two axle detectors do not correlate within the speed range")
    v = distance / (lag / fs)
    u = v * (t[:, None] - t[0]) - offsets[None, :]  # axle positions if tau = t[0]
    best, tau = -np.inf, float(t[0])
    for shift in np.arange(0.0, t[-1] - t[0], 0.1 / v):
        score = float(z[:, 0] @ band_pass(_bump(u - v * shift) @ loads, fs))
        if score > best:
            best, tau = score, float(t[0] + shift)
    sigma = HIGH_PASS / v * fs
    return _Run(t=t, y=high_pass(raw, sigma), sigma=sigma, tau=tau, v=v)


def _peak(grid: np.ndarray, k: np.ndarray) -> tuple[float, float]:
    """Where ``|k|`` peaks on ``grid`` (parabola through three ordinates) and the value."""
    j = int(np.argmax(np.abs(k)))
    frac = 0.0
    if 0 < j < k.size - 1:
        a, b, c = np.abs(k[j - 1:j + 2])
        den = a - 2 * b + c
        frac = float(np.clip(0.5 * (a - c) / den, -0.5, 0.5)) if den < 0 else 0.0
    return float(grid[j] + frac * (grid[1] - grid[0])), float(k[j])


def _peak_time(t: np.ndarray, z: np.ndarray, t_pred: float, half: float) -> float | None:
    """Sub-sample time of the largest sample of ``z`` within ``half`` s of ``t_pred``."""
    win = np.flatnonzero(np.abs(t - t_pred) <= half)
    if win.size < 3:
        return None
    m = win[int(np.argmax(z[win]))]
    if m in (0, z.size - 1) or m in (win[0], win[-1]):
        return None
    den = z[m - 1] - 2 * z[m] + z[m + 1]
    frac = 0.5 * (z[m - 1] - z[m + 1]) / den if den < 0 else 0.0
    return float(t[m] + frac * (t[1] - t[0]))


def _distance_offset(runs: Sequence[_Run], offsets: np.ndarray, distance: float) -> float:
    """How far the declared distance is from what the truck's spacings say, m.

    Independently of the responses' shapes and of the fitted speeds: the known spacing
    between two separate axles (each > 2.5 m from its neighbours) and the time between
    their peaks at detector 1 give the speed; the time between one axle's peaks at the two
    detectors then gives their distance (band-passed readings, sub-sample vertices).
    Median over the runs and the separate axles, less the declared distance; 0 without
    two separate axles."""
    iso = [i for i in range(offsets.size)
           if (i == 0 or offsets[i] - offsets[i - 1] > 2.5)
           and (i == offsets.size - 1 or offsets[i + 1] - offsets[i] > 2.5)]
    if len(iso) < 2:
        return 0.0
    i, j = iso[0], iso[1]
    found = []
    for r in runs:
        fs = 1.0 / float(np.median(np.diff(r.t)))
        z = band_pass(r.y, fs)
        z = z * peak_polarity(z)
        half = 1.2 / r.v  # less than half the 2.5 m between separate axles
        t1 = [_peak_time(r.t, z[:, 0], r.tau + offsets[a] / r.v, half) for a in (i, j)]
        if None in t1 or t1[1] <= t1[0]:
            continue
        v = (offsets[j] - offsets[i]) / (t1[1] - t1[0])
        for _a, ta in zip((i, j), t1, strict=True):
            t2 = _peak_time(r.t, z[:, 1], ta + distance / r.v, half)
            if t2 is not None and t2 > ta:
                found.append(v * (t2 - ta))
    return float(np.median(found) - distance) if found else 0.0


def _positions(run: _Run, offsets: np.ndarray, d_shift: float) -> np.ndarray:
    return run.v * (run.t[:, None] - run.tau) - offsets[None, :] - d_shift


def _smoothing(m: int, ell: float, h: float) -> np.ndarray:
    """``(ℓ / h)⁴ D₂ᵀ D₂`` on ``m`` interior ordinates (the matrix method's smoothing)."""
    D = np.zeros((m, m))
    idx = np.arange(m)
    D[idx, idx] = -2.0
    D[idx[1:], idx[:-1]] = 1.0
    D[idx[:-1], idx[1:]] = 1.0
    return (ell / h) ** 4 * (D.T @ D)


def _learn_kernel(runs: Sequence[_Run], offsets: np.ndarray, amps: np.ndarray,
                  d_shift: float, col: int, grid: np.ndarray, ell: float) -> np.ndarray:
    """K on ``grid`` (zero at its ends) for fixed amplitudes: least squares on the
    high-passed hat functions, smoothed."""
    h = grid[1] - grid[0]
    n = grid.size - 1
    A = np.zeros((n - 1, n - 1))
    b = np.zeros(n - 1)
    for r in runs:
        G = high_pass(hat_design(_positions(r, offsets, d_shift), amps, grid[0], h, n)
                      .toarray(), r.sigma)
        A += G.T @ G
        b += G.T @ r.y[:, col]
    if ell > 0:
        A += float(np.mean(np.diag(A))) * _smoothing(n - 1, ell, h)
    try:
        inner = scipy.linalg.solve(A, b, assume_a="pos")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        raise NumericalError("the detector response is not determined by the runs") from None
    return np.concatenate([[0.0], inner, [0.0]])


def _columns(run: _Run, offsets: np.ndarray, d_shift: float, grid: np.ndarray,
             k: np.ndarray) -> np.ndarray:
    """High-passed responses of each axle in one run, (n_t, n_axles)."""
    return high_pass(np.interp(_positions(run, offsets, d_shift), grid, k, left=0.0,
                               right=0.0), run.sigma)


def _learn_amplitudes(runs: Sequence[_Run], offsets: np.ndarray, kernels, amps: np.ndarray,
                      distance: float, noise: np.ndarray) -> np.ndarray:
    """Amplitudes ``A_id = g_d f_i`` for fixed responses (see the module docstring),
    alternated from ``amps``, (n_axles, 2)."""
    X, z = [], []
    for c, (grid, k) in enumerate(kernels):
        X.append(np.vstack([_columns(r, offsets, distance if c else 0.0, grid, k)
                            for r in runs]) / noise[c])
        z.append(np.concatenate([r.y[:, c] for r in runs]) / noise[c])
    g = np.maximum(amps.max(axis=0), 1e-300)
    f = amps[:, 0] / g[0]
    for _ in range(5):
        f, _ = nnls(np.vstack([g[c] * X[c] for c in range(2)]), np.concatenate(z))
        if not np.any(f > 0):
            break
        f = f / f.max()
        g = np.array([max(float((X[c] @ f) @ z[c]) / max(float((X[c] @ f) @ (X[c] @ f)),
                                                            1e-300), 1e-300)
                      for c in range(2)])
    return np.outer(f, g)


def _refit_run(run: _Run, offsets: np.ndarray, kernels, amps: np.ndarray, distance: float,
               noise: np.ndarray) -> tuple[_Run, float]:
    """(τ, v) of one run against fixed responses, both detectors; the relative residual."""

    def resid(p: np.ndarray) -> np.ndarray:
        trial = _Run(t=run.t, y=run.y, sigma=run.sigma, tau=p[0], v=p[1])
        return np.concatenate([
            (run.y[:, c] - _columns(trial, offsets, distance if c else 0.0, grid, k)
             @ amps[:, c]) / noise[c] for c, (grid, k) in enumerate(kernels)])

    sol = least_squares(resid, np.array([run.tau, run.v]), x_scale=np.array([1e-3, 0.1]),
                        method="lm")
    new = _Run(t=run.t, y=run.y, sigma=run.sigma, tau=float(sol.x[0]), v=float(sol.x[1]))
    yw = np.concatenate([run.y[:, c] / noise[c] for c in range(2)])
    return new, float(np.linalg.norm(sol.fun) / max(np.linalg.norm(yw), 1e-300))


def _misfits(runs: Sequence[_Run], offsets: np.ndarray, kernels, amps: np.ndarray,
             distance: float) -> np.ndarray:
    """Per detector, the RMS residual of the runs while the truck crosses (from NEAR m
    before its first axle reaches detector 1 to NEAR m after its last leaves detector 2)."""
    sq = np.zeros(2)
    count = 0
    for r in runs:
        on = ((r.t >= r.tau - NEAR / r.v)
              & (r.t <= r.tau + (offsets[-1] + distance + NEAR) / r.v))
        for c, (grid, k) in enumerate(kernels):
            e = r.y[on, c] - _columns(r, offsets, distance if c else 0.0, grid, k)[on] \
                @ amps[:, c]
            sq[c] += float(e @ e)
        count += int(on.sum())
    return np.sqrt(sq / max(count, 1))


def learn_responses(records: Sequence[Record], detectors: Sequence[str], distance: float,
                    spacings: Sequence[float], *, loads: Sequence[float] | None = None,
                    speed_range: tuple[float, float] = (5.0, 40.0),
                    smoothing: float = 0.05, spacing: float | None = None,
                    iterations: int = 4) -> LearnedResponses:
    """Each detector's response to one axle, from runs of a truck with known ``spacings``.

    Parameters
    ----------
    records : sequence of Record
        The calibration truck's runs (each holding both detector channels).
    detectors : (str, str)
        The channels, in the order traffic meets them.
    distance : float
        Declared distance between the detectors, m.
    spacings : sequence of float
        The truck's axle spacings, m.
    loads : sequence of float, optional
        Its static axle loads (N): the amplitudes' first guess (default equal).
    speed_range : (float, float)
        Speeds the runs may have, m/s.
    smoothing : float
        Smoothing length of the responses, m (the matrix method's ``regularization``).
    spacing : float, optional
        Grid spacing of the responses, m; default the largest distance a run moves in one
        sample.
    iterations : int
        Outer cycles of (responses and amplitudes, then each run's timing and speed).

    Returns
    -------
    LearnedResponses

    Raises
    ------
    InputError
        Fewer than two usable runs, detectors that do not correlate, or a declared
        distance the runs contradict (by more than :data:`DISTANCE_TOLERANCE`).
    """
    recs = record_list(records, needs="learning a detector's response needs runs")
    if isinstance(detectors, str) or len(detectors) != 2 or detectors[0] == detectors[1]:
        raise InputError(f"detectors must name two different channels, got {detectors!r}")
    chans = (str(detectors[0]), str(detectors[1]))
    dist = require_positive("distance", distance)
    offs = axle_offsets(np.asarray(spacings, dtype=float))
    n_ax = offs.size
    w = np.ones(n_ax) if loads is None else np.asarray(loads, dtype=float)
    if w.shape != (n_ax,) or not np.all(w > 0):
        raise InputError(f"loads must be {n_ax} positive axle loads, got {loads!r}")
    v_range = check_speed_range(speed_range)
    if int(iterations) < 1:
        raise InputError(f"iterations must be >= 1, got {iterations!r}")

    runs: list[_Run | None] = []
    reasons = [""] * len(recs)
    for k, rec in enumerate(recs):
        try:
            runs.append(_start(rec, chans, dist, offs, w / w.max(), v_range))
        except InputError as exc:
            runs.append(None)
            reasons[k] = str(exc)
    used = [k for k, r in enumerate(runs) if r is not None]
    if len(used) < 2:
        raise InputError(f"detector responses need at least two usable runs; "
                         f"{'; '.join(f'run {k + 1}: {r}' for k, r in enumerate(reasons) if r)}")
    noise = np.array([robust_sigma(np.diff(np.concatenate([runs[k].y[:, c] for k in used])))
                      / np.sqrt(2.0) for c in range(2)])
    noise = np.where(noise > 0, noise, 1.0)
    h = spacing if spacing is not None else max(runs[k].v / recs[k].sampling_rate for k in used)
    n = max(int(np.ceil(2 * NEAR / require_positive("spacing", h))), 4)
    grid = -NEAR + 2 * NEAR / n * np.arange(n + 1)

    amps = np.column_stack([w / w.max(), w / w.max()])
    kernels = [(grid, _bump(grid)), (grid, _bump(grid))]
    resid = np.full(len(recs), np.nan)
    nit = 0
    for _ in range(int(iterations)):
        nit += 1
        active = [runs[k] for k in used]
        for _ in range(3):  # responses and amplitudes, alternated
            kernels = [(grid, _learn_kernel(active, offs, amps[:, c], dist if c else 0.0, c,
                                            grid, smoothing)) for c in range(2)]
            amps = _learn_amplitudes(active, offs, kernels, amps, dist, noise)
        # anchor: each response's peak at u = 0 (detector 1's defines where the axles are,
        # so the runs' times follow it; detector 2's is the declared distance)
        for c, (g, kk) in enumerate(kernels):
            at, _ = _peak(g, kk)
            kernels[c] = (g, np.interp(g + at, g, kk, left=0.0, right=0.0))
            if c == 0:
                for k in used:
                    runs[k].tau += at / runs[k].v
        for k in used:
            runs[k], resid[k] = _refit_run(runs[k], offs, kernels, amps, dist, noise)
        med = float(np.median(resid[used]))
        rsd = 1.4826 * float(np.median(np.abs(resid[used] - med)))
        worst = max(used, key=lambda k: resid[k])
        if (len(used) > 2 and resid[worst] > med + RUN_OUTLIER * rsd
                and resid[worst] > 1.5 * med):
            reasons[worst] = (f"relative residual {resid[worst]:.3g} against the others' "
                              f"median {med:.3g}: another vehicle on the detectors?")
            used.remove(worst)

    misfit = _misfits([runs[k] for k in used], offs, kernels, amps, dist)
    responses = []
    for c, (g, kk) in enumerate(kernels):
        _, top = _peak(g, kk)
        scale = abs(top)
        responses.append(DetectorResponse(channel=chans[c], u=g.copy(), k=kk / scale,
                                          noise=float(noise[c]), misfit=float(misfit[c])))
        amps[:, c] *= scale
    offset = _distance_offset([runs[k] for k in used], offs, dist)
    if abs(offset) > DISTANCE_TOLERANCE * dist:
        raise InputError(
            f"the axle detectors' distance of {dist:g} m contradicts the calibration runs' "
            f"known axle spacings: they give {dist + offset:.2f} m (the speeds from the "
            "spacing of the truck's separate axles against those from the detectors' lag)")
    taus = np.array([np.nan if r is None else r.tau for r in runs])
    speeds = np.array([np.nan if r is None else r.v for r in runs])
    for k in range(len(recs)):
        if k not in used:
            resid[k] = np.nan
    return LearnedResponses(responses=(responses[0], responses[1]), distance=dist,
                            amplitudes=amps, speeds=speeds, first_axle_times=taus,
                            residuals=resid, reasons=tuple(reasons),
                            distance_offset=float(offset), nit=nit)
