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
  uniform grid over ``|u| ≤`` :data:`NEAR`, zero beyond, normalised so that its largest
  magnitude is 1, at ``u = 0``, with its sign kept (the axle's own peak defines where the
  detector is).
* The rest of a detector's reading is the span's global **bending** (it depends on every
  axle on the span, in every lane), an offset and drift.  Two ways to keep it out:

  - **gauges** (when the runs hold strain gauges): the bending a detector sees is a fixed
    linear combination of what the gauges read, ``b_d(t) = Σ_j w_dj (g_j(t) − ḡ_j)``
    (:attr:`DetectorResponse.bending`, learned with the response); readings are modelled
    as ``Σ_i A_id K_d(u_i) + β_d b_d(t) + c_d + s_d t``.  The gauges share the detectors'
    strain factor, so ``β_d`` stays near 1 from day to day; it is refitted per record.
  - **high-pass** (no gauges): readings and model are high-passed in space
    (:func:`high_pass`: a signal less its Gaussian average over :data:`HIGH_PASS` m of
    travel), which takes out bending, offset and drift with part of the peak.

* :func:`learn_responses` fits both detectors' responses to the runs of a calibration
  truck whose axle spacings ``a_i`` are known.  Reading of detector ``d`` in run ``r``::

      y_rd(t) = Σ_i A_rid K_d(v_r (t − τ_r) − a_i − D_d) + b_d(t) + c_rd + s_rd t + e,

  ``D_1 = 0``, ``D_2 = D``, ``v_r`` the run's speed, ``τ_r`` when its first axle passes
  detector 1, ``A_rid`` each axle's amplitude in each run at each detector (free: the
  tyres' dynamic forces differ from run to run and from one detector to the next).  For
  fixed amplitudes ``K_d`` (with the gauge weights and offsets) is linear least squares on
  the matrix method's hat functions with a light second-difference smoothing; for fixed
  responses the amplitudes are linear least squares (alternated); then each run's
  ``(τ_r, v_r)`` is refitted to both detectors at once by nonlinear least squares (the
  known spacings set the speeds), and the cycle repeated.  With ``symmetric`` (the
  default with gauges) each response is even about its detector: ``K_d(−u) = K_d(u)``
  (a tyre's local effect on a detector in a uniform slab is; and then the calibration
  truck's own dynamic forces at the detectors, much the same in every run, cannot skew
  the responses nor the traffic speeds measured with them).  Otherwise detector 1's
  response is re-centred on its peak (it defines where the axles are; the runs' times
  follow it) and, without gauges, detector 2's too (its peak is the declared distance; a
  high-passed response also holds what the high-pass leaves of the truck's bending);
  with gauges and ``symmetric=False`` detector 2's response stays where the runs put it.
  The known spacing of two separate axles checks ``D`` independently of the responses'
  shapes (the time between their peaks at detector 1): the difference is
  :attr:`LearnedResponses.distance_offset`; beyond :data:`DISTANCE_TOLERANCE` of ``D``
  the calibration is refused.
* From the amplitudes: the detectors' **gain ratio** ``ρ`` (median of ``A_ri2 / A_ri1``)
  and the **spread** of ``ln(A_ri2 / (ρ A_ri1))`` (robust σ): how differently the two
  detectors see one axle (its dynamic force at two instants).  From the residual: each
  detector's **misfit** (RMS while the truck crosses) and **relative misfit** (misfit over
  the RMS axle amplitude): what one response cannot explain of a real axle.
* Start: each run's speed from the cross-correlation of the band-passed detectors over
  the declared distance, its first axle by aligning the known layout with a bump of one
  metre; runs whose fit stays poor (relative residual beyond the median by
  :data:`RUN_OUTLIER` robust standard deviations and 1.5 times it: another vehicle on the
  detectors) are left out and named in ``reasons``.
* Units: u and spacings in m, time in s, speeds in m/s; readings in the logger's units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.fft
import scipy.linalg
from scipy.ndimage import gaussian_filter1d
from scipy.optimize import least_squares

from bwim.errors import InputError, NumericalError, require_positive
from bwim.records import Record, axle_offsets, record_list
from bwim.wim.influence_line import hat_design

from .options import check_speed_range
from .signals import gaussian_average, robust_sigma

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
#: Ridge on the gauge weights of the bending, relative to the mean diagonal of their
#: normal equations (the gauges of one section read much alike).
GAUGE_RIDGE = 1e-3


def high_pass(y: np.ndarray, sigma: float) -> np.ndarray:
    """``y`` (along axis 0) less its Gaussian average of ``sigma`` samples (ends extended
    by their edge values: :func:`~bwim.detect.signals.gaussian_average`)."""
    return y - gaussian_average(y, [(sigma, 1.0)])


def band_pass(y: np.ndarray, fs: float, *, short: float = 0.01, long: float = 0.06
              ) -> np.ndarray:
    """``y`` (n_t,) or (n_t, k) smoothed over ``short`` s less smoothed over ``long`` s
    (Gaussian σ): the axles' peaks (tens of ms wide at road speeds) stay, offsets and the
    slab's global bending (hundreds of ms) go.  Used where only timing matters (the
    detectors' lag, aligning a layout, timing two peaks).  Ends extended by their edge
    values; both averages as one filter (:func:`~bwim.detect.signals.gaussian_average`)."""
    return gaussian_average(y, [(short * fs, 1.0), (long * fs, -1.0)])


def _read_only(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    for a in arrays:
        a.setflags(write=False)
    return arrays


@dataclass(frozen=True, kw_only=True, eq=False)
class DetectorResponse:
    """One detector's local response to one axle (see the module docstring).

    Attributes
    ----------
    channel : str
        The logger channel.
    u : ndarray, shape (n,)
        Grid of axle distances past the detector, m, ascending and uniform.
    k : ndarray, shape (n,)
        ``K(u)`` on the grid: reading per unit amplitude; ``K(0)`` is ±1.
    noise : float
        The channel's noise standard deviation in the runs, reading units.
    misfit : float
        Root-mean-square of the runs' residual while the truck crosses, reading units:
        what one response cannot explain of a real axle (its dynamic force while it
        passes, its tyres and lateral position), the level an axle must stand out of.
    bending : ndarray, shape (n_gauges,)
        Weights of :attr:`LearnedResponses.gauges` whose combination is the bending this
        detector reads (reading units per gauge unit); empty without gauges.
    relative_misfit : float
        ``misfit`` over the root-mean-square amplitude of the truck's axles.
    """

    channel: str
    u: np.ndarray
    k: np.ndarray
    noise: float
    misfit: float = 0.0
    bending: np.ndarray = field(default_factory=lambda: np.zeros(0))
    relative_misfit: float = 0.0

    @property
    def level(self) -> float:
        """The larger of ``noise`` and ``misfit``: the scale detection weighs with."""
        return max(self.noise, self.misfit)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """``K`` at distances ``u`` (m), zero outside the grid."""
        return np.interp(u, self.u, self.k, left=0.0, right=0.0)

    def padded(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(u, K, dK/du)`` on the grid widened by one spacing each side (zeros); computed
        once per response, read-only."""
        return self._padded

    @cached_property
    def _padded(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        du = float(self.u[1] - self.u[0])
        u = self.u[0] + du * np.arange(-1, self.u.size + 1)
        k = self(u)
        return _read_only(u, k, np.gradient(k, du))

    def high_passed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The response high-passed in space (:data:`HIGH_PASS` m), on a grid widened by
        the filter's reach: ``(u, K_hp, dK_hp/du)``.  For a vehicle at speed ``v`` the
        high-pass in time over ``HIGH_PASS / v`` s of a reading is this in space, so
        detection compares high-passed readings with ``K_hp`` directly.  Computed once per
        response, read-only."""
        return self._high_passed

    @cached_property
    def _high_passed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        du = float(self.u[1] - self.u[0])
        pad = int(np.ceil(5 * HIGH_PASS / du))
        u = self.u[0] + du * np.arange(-pad, self.u.size + pad)
        k = self(u)
        k_hp = k - gaussian_filter1d(k, HIGH_PASS / du, mode="constant")
        return _read_only(u, k_hp, np.gradient(k_hp, du))

    @cached_property
    def sign(self) -> float:
        """+1 for pulses that rise, −1 for pulses that fall."""
        return float(np.sign(self.k[int(np.argmax(np.abs(self.k)))]) or 1.0)

    @cached_property
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
        The calibration truck's axle amplitudes at each detector (reading units, mean
        over the runs used).
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
    gauges : tuple of str
        The gauge channels whose combination models each detector's bending (empty: the
        readings are high-passed instead).
    gain_ratio : float
        The second detector's amplitude of an axle over the first's (median over the
        runs' axles).
    amplitude_spread : float
        Robust standard deviation of ``ln(A_2 / (gain_ratio A_1))`` over the runs' axles.
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
    gauges: tuple[str, ...] = ()
    gain_ratio: float = 1.0
    amplitude_spread: float = 0.0

    def __repr__(self) -> str:
        used = sum(1 for r in self.reasons if not r)
        return (f"LearnedResponses({self.channels[0]}, {self.channels[1]}: "
                f"{self.distance:g} m apart, {used} of {len(self.reasons)} runs, gain ratio "
                f"{self.gain_ratio:.3g}, {len(self.gauges)} bending gauges)")

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
    size = scipy.fft.next_fast_len(2 * n, real=True)  # ≥ 2n − 1: linear, not circular
    # both spectra from one call (numpy transforms each row on its own, with the plan of
    # its length: the numbers of one call each)
    both = np.empty((2, n))
    both[0] = y1[::-1]
    both[1] = y2
    spec = np.fft.rfft(both, size)
    full = np.fft.irfft(spec[0] * spec[1], size)  # index n-1+L  <->  lag L
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


def resolve_gauges(record: Record, detectors: Sequence[str], gauges) -> tuple[str, ...]:
    """The gauge channels named by ``gauges``: "auto" every structural channel of
    ``record`` other than the detectors, None or () none, else the names given."""
    if gauges is None:
        return ()
    if isinstance(gauges, str):
        if gauges != "auto":
            raise InputError(f"gauges must be 'auto', None or channel names, got {gauges!r}")
        return tuple(s.name for s in record.sensors
                     if s.kind.is_structural and s.name not in detectors)
    names = tuple(str(g) for g in gauges)
    have = {s.name for s in record.sensors}
    for g in names:
        if g not in have:
            raise InputError(f"gauges: no channel {g!r} in this record")
        if g in detectors:
            raise InputError(f"gauges: {g!r} is an axle detector")
    return names


@dataclass
class _Run:
    t: np.ndarray
    y: np.ndarray  # (n_t, 2): high-passed readings, or readings (gauge mode)
    g: np.ndarray  # (n_t, n_gauges): gauge readings less their mean (gauge mode)
    sigma: float  # samples of the high-pass
    tau: float
    v: float

    @property
    def nuisance(self) -> np.ndarray:
        """Offset and slope columns (gauge mode)."""
        tc = self.t - self.t.mean()
        return np.column_stack([np.ones_like(tc), tc / max(float(np.ptp(tc)), 1e-300)])


def _start(rec: Record, chans: tuple[str, str], gauges: tuple[str, ...], distance: float,
           offsets: np.ndarray, loads: np.ndarray, v_range: tuple[float, float]) -> _Run:
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
    tau = float(t[0]) + _best_shift(z[:, 0], u, v, loads, fs, float(t[-1] - t[0]))
    sigma = HIGH_PASS / v * fs
    if gauges:
        g = rec.channels(list(gauges)).data.astype(float)
        return _Run(t=t, y=raw - raw.mean(axis=0), g=g - g.mean(axis=0), sigma=sigma,
                    tau=tau, v=v)
    return _Run(t=t, y=high_pass(raw, sigma), g=np.zeros((t.size, 0)), sigma=sigma,
                tau=tau, v=v)


#: Shifts of :func:`_best_shift` made at once (memory: this many band-passed records).
_SHIFT_BLOCK = 64


def _best_shift(z: np.ndarray, u: np.ndarray, v: float, loads: np.ndarray, fs: float,
                duration: float) -> float:
    """The time shift (s: multiples of 0.1 m of travel from 0 up to ``duration``) at
    which the truck's layout of bumps (``u``: each axle's distance past detector 1 at
    every sample for a first axle at the record's start), band-passed, best matches the
    band-passed detector ``z``; the first of equal best scores.  Each score is
    ``z @ band_pass(_bump(u - v shift) @ loads)`` (the same products as one shift at a
    time, band-passed :data:`_SHIFT_BLOCK` shifts together)."""
    shifts = np.arange(0.0, duration, 0.1 / v)
    best, at = -np.inf, 0.0
    for start in range(0, shifts.size, _SHIFT_BLOCK):
        block = shifts[start:start + _SHIFT_BLOCK]
        layouts = np.empty((u.shape[0], block.size))
        for j, shift in enumerate(block):
            layouts[:, j] = _bump(u - v * shift) @ loads
        # each shift's band-passed layout, one contiguous row each (the dot products of
        # contiguous vectors, as one shift at a time)
        passed = np.ascontiguousarray(band_pass(layouts, fs).T)
        for j, row in enumerate(passed):
            score = float(z @ row)
            if score > best:
                best, at = score, float(block[j])
    return at


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


def _transform(run: _Run, cols: np.ndarray, gauge_mode: bool) -> np.ndarray:
    return cols if gauge_mode else high_pass(cols, run.sigma)


class _Design:
    """Stacked least squares over the runs for one detector: per-run blocks (amplitudes
    or offsets), shared blocks (response ordinates, gauge weights), a ridge on some."""

    def __init__(self, runs: Sequence[_Run], col: int, gauge_mode: bool):
        self.runs, self.col, self.gauge_mode = runs, col, gauge_mode
        self.rows = np.cumsum([0] + [r.t.size for r in runs])

    def solve(self, shared: list[np.ndarray], per_run: list[np.ndarray],
              penalty: np.ndarray, noise: float) -> tuple[np.ndarray, list[np.ndarray]]:
        """``shared``: per run (n_t, p) columns with one coefficient set for all runs;
        ``per_run``: per run (n_t, q) columns with their own coefficients; ``penalty``
        (p, p) added to the shared block's normal equations.  Returns the shared
        coefficients and each run's own."""
        p = shared[0].shape[1]
        qs = [c.shape[1] for c in per_run]
        n_col = p + sum(qs)
        M = np.zeros((self.rows[-1], n_col))
        z = np.zeros(self.rows[-1])
        off = p
        for k, r in enumerate(self.runs):
            a, b = self.rows[k], self.rows[k + 1]
            M[a:b, :p] = shared[k]
            M[a:b, off:off + qs[k]] = per_run[k]
            z[a:b] = r.y[:, self.col]
            off += qs[k]
        M /= noise
        z = z / noise
        A = M.T @ M
        if p:
            A[:p, :p] += penalty * float(np.mean(np.diag(A)[:p]))
        A[np.diag_indices_from(A)] += 1e-12 * float(np.mean(np.diag(A)))
        try:
            x = scipy.linalg.solve(A, M.T @ z, assume_a="pos")
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
            raise NumericalError("the detector response is not determined by the runs") from None
        own, off = [], p
        for q in qs:
            own.append(x[off:off + q])
            off += q
        return x[:p], own


def _mirror(m: int) -> np.ndarray:
    """(m, ⌈m/2⌉) matrix spreading the ordinates of one half (centre last) of a symmetric
    response over its m interior ordinates (m odd: the centre is a node)."""
    half = (m + 1) // 2
    S = np.zeros((m, half))
    for j in range(m):
        S[j, min(j, m - 1 - j)] = 1.0
    return S


def _learn_kernel(runs: Sequence[_Run], offsets: np.ndarray, amps: np.ndarray,
                  d_shift: float, col: int, grid: np.ndarray, ell: float, noise: float,
                  gauge_mode: bool, symmetric: bool) -> tuple[np.ndarray, np.ndarray]:
    """K on ``grid`` (zero at its ends; even about u = 0 if ``symmetric``) and the gauge
    weights for fixed amplitudes ``amps`` (n_runs, n_axles): least squares on the hat
    functions, smoothed."""
    h = grid[1] - grid[0]
    n = grid.size - 1
    n_g = runs[0].g.shape[1]
    S = _mirror(n - 1) if symmetric else np.eye(n - 1)
    m = S.shape[1]
    shared, own = [], []
    for r, a in zip(runs, amps, strict=True):
        G = hat_design(_positions(r, offsets, d_shift), a, grid[0], h, n) @ S
        shared.append(np.hstack([_transform(r, G, gauge_mode), r.g]))
        own.append(r.nuisance if gauge_mode else np.zeros((r.t.size, 0)))
    pen = np.zeros((m + n_g, m + n_g))
    if ell > 0:
        pen[:m, :m] = S.T @ _smoothing(n - 1, ell, h) @ S
    pen[m:, m:] = GAUGE_RIDGE * np.eye(n_g)
    x, _ = _Design(runs, col, gauge_mode).solve(shared, own, pen, noise)
    return np.concatenate([[0.0], S @ x[:m], [0.0]]), x[m:]


def _atoms(run: _Run, offsets: np.ndarray, d_shift: float, grid: np.ndarray,
           k: np.ndarray, gauge_mode: bool) -> np.ndarray:
    """Each axle's response in one run, (n_t, n_axles) (high-passed without gauges)."""
    return _transform(run, np.interp(_positions(run, offsets, d_shift), grid, k, left=0.0,
                                     right=0.0), gauge_mode)


def _learn_amplitudes(runs: Sequence[_Run], offsets: np.ndarray, grid: np.ndarray,
                      k: np.ndarray, d_shift: float, col: int, noise: float,
                      gauge_mode: bool) -> tuple[np.ndarray, np.ndarray]:
    """Each run's axle amplitudes (n_runs, n_axles) and the gauge weights for a fixed
    response."""
    n_g = runs[0].g.shape[1]
    shared = [r.g for r in runs]
    own = [np.hstack([_atoms(r, offsets, d_shift, grid, k, gauge_mode),
                      r.nuisance if gauge_mode else np.zeros((r.t.size, 0))]) for r in runs]
    w, x = _Design(runs, col, gauge_mode).solve(shared, own, GAUGE_RIDGE * np.eye(n_g),
                                                noise)
    return np.array([xi[:offsets.size] for xi in x]), w


def _run_fit(run: _Run, offsets: np.ndarray, kernels, weights, distance: float,
             noise: np.ndarray, gauge_mode: bool) -> tuple[np.ndarray, np.ndarray]:
    """Residual (both detectors, in noise units) and amplitudes (n_axles, 2) of one run
    for its (τ, v), each detector's amplitudes, bending scale and offsets free."""
    res, amps = [], []
    for c, (grid, k) in enumerate(kernels):
        X = _atoms(run, offsets, distance if c else 0.0, grid, k, gauge_mode)
        if gauge_mode:
            X = np.hstack([X, (run.g @ weights[c])[:, None], run.nuisance])
        coef, *_ = np.linalg.lstsq(X, run.y[:, c], rcond=None)
        res.append((run.y[:, c] - X @ coef) / noise[c])
        amps.append(coef[:offsets.size])
    return np.concatenate(res), np.column_stack(amps)


def _refit_run(run: _Run, offsets: np.ndarray, kernels, weights, distance: float,
               noise: np.ndarray, gauge_mode: bool) -> tuple[_Run, float]:
    """(τ, v) of one run against fixed responses, both detectors; the relative residual."""

    def resid(p: np.ndarray) -> np.ndarray:
        trial = _Run(t=run.t, y=run.y, g=run.g, sigma=run.sigma, tau=p[0], v=p[1])
        return _run_fit(trial, offsets, kernels, weights, distance, noise, gauge_mode)[0]

    sol = least_squares(resid, np.array([run.tau, run.v]), x_scale=np.array([1e-3, 0.1]),
                        method="lm")
    new = _Run(t=run.t, y=run.y, g=run.g, sigma=run.sigma, tau=float(sol.x[0]),
               v=float(sol.x[1]))
    yw = np.concatenate([(run.y[:, c] - run.y[:, c].mean()) / noise[c] for c in range(2)])
    return new, float(np.linalg.norm(sol.fun) / max(np.linalg.norm(yw), 1e-300))


def _misfits(runs: Sequence[_Run], offsets: np.ndarray, kernels, weights, distance: float,
             noise: np.ndarray, gauge_mode: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per detector, the RMS residual of the runs while the truck crosses (from NEAR m
    before its first axle reaches detector 1 to NEAR m after its last leaves detector 2),
    and every run's amplitudes (n_runs, n_axles, 2)."""
    sq = np.zeros(2)
    count = 0
    amps = []
    for r in runs:
        on = ((r.t >= r.tau - NEAR / r.v)
              & (r.t <= r.tau + (offsets[-1] + distance + NEAR) / r.v))
        res, a = _run_fit(r, offsets, kernels, weights, distance, noise, gauge_mode)
        e = res.reshape(2, -1) * noise[:, None]
        sq += (e[:, on] ** 2).sum(axis=1)
        count += int(on.sum())
        amps.append(a)
    return np.sqrt(sq / max(count, 1)), np.array(amps)


def learn_responses(records: Sequence[Record], detectors: Sequence[str], distance: float,
                    spacings: Sequence[float], *, loads: Sequence[float] | None = None,
                    gauges: Sequence[str] | str | None = "auto",
                    speed_range: tuple[float, float] = (5.0, 40.0),
                    smoothing: float = 0.05, spacing: float | None = None,
                    iterations: int = 4, symmetric: bool | None = None
                    ) -> LearnedResponses:
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
        Its static axle loads (N): only to align the layout at the start (default equal).
    gauges : "auto", None or sequence of str
        Strain gauges whose combination models each detector's bending: "auto" every
        structural channel of the first run (none: high-pass instead); None: high-pass.
    speed_range : (float, float)
        Speeds the runs may have, m/s.
    smoothing : float
        Smoothing length of the responses, m (the matrix method's ``regularization``).
    spacing : float, optional
        Grid spacing of the responses, m; default the largest distance a run moves in one
        sample.
    iterations : int
        Outer cycles of (responses and amplitudes, then each run's timing and speed).
    symmetric : bool, optional
        Learn responses even about the detector (``K(−u) = K(u)``): a tyre's local effect
        on a detector in a uniform slab is, and the calibration truck's own dynamic
        forces at the detectors, the same in every run, then cannot skew the responses
        (nor the speeds measured with them).  Default: with gauges; not without (the
        high-passed response also holds what the high-pass leaves of the truck's bending,
        which is not even).

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
    gnames = resolve_gauges(recs[0], chans, gauges)
    gauge_mode = bool(gnames)
    symmetric = gauge_mode if symmetric is None else bool(symmetric)

    runs: list[_Run | None] = []
    reasons = [""] * len(recs)
    for k, rec in enumerate(recs):
        try:
            runs.append(_start(rec, chans, gnames, dist, offs, w / w.max(), v_range))
        except InputError as exc:
            runs.append(None)
            reasons[k] = str(exc)
    used = [k for k, r in enumerate(runs) if r is not None]
    if len(used) < 2:
        raise InputError(f"detector responses need at least two usable runs; "
                         f"{'; '.join(f'run {k + 1}: {r}' for k, r in enumerate(reasons) if r)}")
    noise = np.array([robust_sigma(np.diff(np.concatenate([
        recs[k].channels([chans[c]]).data[:, 0] for k in used]))) / np.sqrt(2.0)
        for c in range(2)])
    noise = np.where(noise > 0, noise, 1.0)
    h = spacing if spacing is not None else max(runs[k].v / recs[k].sampling_rate for k in used)
    n = max(int(np.ceil(2 * NEAR / require_positive("spacing", h))), 4)
    n += n % 2  # even: u = 0 is a node
    grid = -NEAR + 2 * NEAR / n * np.arange(n + 1)

    kernels = [(grid, _bump(grid)), (grid, _bump(grid))]
    weights = [np.zeros(len(gnames)), np.zeros(len(gnames))]
    resid = np.full(len(recs), np.nan)
    nit = 0
    for _ in range(int(iterations)):
        nit += 1
        active = [runs[k] for k in used]
        for _ in range(3):  # amplitudes and responses, alternated
            for c in range(2):
                shift = dist if c else 0.0
                amps, weights[c] = _learn_amplitudes(active, offs, grid, kernels[c][1], shift,
                                                     c, noise[c], gauge_mode)
                kk, weights[c] = _learn_kernel(active, offs, amps, shift, c, grid, smoothing,
                                               noise[c], gauge_mode, symmetric)
                kernels[c] = (grid, kk)
        # anchor: detector 1's response peaks at u = 0 (it defines where the axles are,
        # so the runs' times follow it).  Detector 2's stays where the runs put it with
        # gauges (the runs' known spacings set their speeds, so its place relative to
        # the declared distance is measured); without gauges its shape holds what the
        # high-pass left of the truck's bending, and its peak is the declared distance.
        for c, (g, kk) in enumerate(kernels):
            at, top = _peak(g, kk)
            if symmetric:
                at = 0.0
            elif c == 0 or not gauge_mode:
                kk = np.interp(g + at, g, kk, left=0.0, right=0.0)
            if c == 0:
                for k in used:
                    runs[k].tau += at / runs[k].v
            kernels[c] = (g, kk / abs(top))
        for k in used:
            runs[k], resid[k] = _refit_run(runs[k], offs, kernels, weights, dist, noise,
                                           gauge_mode)
        med = float(np.median(resid[used]))
        rsd = 1.4826 * float(np.median(np.abs(resid[used] - med)))
        worst = max(used, key=lambda k: resid[k])
        if (len(used) > 2 and resid[worst] > med + RUN_OUTLIER * rsd
                and resid[worst] > 1.5 * med):
            reasons[worst] = (f"relative residual {resid[worst]:.3g} against the others' "
                              f"median {med:.3g}: another vehicle on the detectors?")
            used.remove(worst)

    active = [runs[k] for k in used]
    misfit, run_amps = _misfits(active, offs, kernels, weights, dist, noise, gauge_mode)
    a1, a2 = run_amps[..., 0].ravel(), run_amps[..., 1].ravel()
    ok = (a1 > 0) & (a2 > 0)
    if not ok.any():
        raise NumericalError("the calibration runs give no positive axle amplitudes")
    log_ratio = np.log(a2[ok] / a1[ok])
    gain_ratio = float(np.exp(np.median(log_ratio)))
    spread = robust_sigma(log_ratio)
    responses = []
    for c, (g, kk) in enumerate(kernels):
        rms_amp = float(np.sqrt(np.mean(run_amps[..., c] ** 2)))
        responses.append(DetectorResponse(
            channel=chans[c], u=g.copy(), k=kk, noise=float(noise[c]),
            misfit=float(misfit[c]), bending=np.asarray(weights[c], dtype=float),
            relative_misfit=float(misfit[c] / max(rms_amp, 1e-300))))
    offset = _distance_offset(active, offs, dist)
    if abs(offset) > DISTANCE_TOLERANCE * dist:
        raise InputError(
            f"the axle detectors' distance of {dist:g} m contradicts the calibration runs' "
            f"known axle spacings: they give {dist + offset:.2f} m (the speeds from the "
            "spacing of the truck's separate axles against those from the detectors' lag): "
            "a wrong distance, or the truck drove another lane than these detectors'")
    taus = np.array([np.nan if r is None else r.tau for r in runs])
    speeds = np.array([np.nan if r is None else r.v for r in runs])
    for k in range(len(recs)):
        if k not in used:
            resid[k] = np.nan
    return LearnedResponses(responses=(responses[0], responses[1]), distance=dist,
                            amplitudes=run_amps.mean(axis=0), speeds=speeds,
                            first_axle_times=taus, residuals=resid, reasons=tuple(reasons),
                            distance_offset=float(offset), nit=nit, gauges=gnames,
                            gain_ratio=gain_ratio, amplitude_spread=float(spread))
