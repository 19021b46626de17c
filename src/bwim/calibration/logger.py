"""Road-free calibration from logger files: the logger's unknowns fitted with the stiffness.

Why
---
:func:`~bwim.calibration.calibrate_quasistatic` fits a bridge model to crossings whose
readings are strains and whose passages are given in the model's frame.  A logger file
has neither: its channels are in the logger's own units (a gauge factor, an amplifier
gain, a unit nobody wrote down), each channel has an offset that wanders, and a passage
found by axle detectors is known relative to the detectors, not to the bridge's supports.
Here these are unknowns of the same road-free fit (docs/theory.md §13): the readings are
modelled as

    m_s(t) = g_s · 𝓛[Σ_j G_s(x_j(t) + x₀, y_j + y₀) P_j (1 + Σ_k c_{a(j),k} φ_{a(j),k}(t))]
             + o_s + r_s (t − t̄)

``g_s`` the gain of channel s (logger units per unit of model strain; one common ``g``
with ``gains="common"``), ``x₀`` the bridge-frame position of the passages' origin (m),
``y₀`` an offset of the passages' lateral positions (m; unless ``lateral=None``),
``o_s, r_s`` a channel's offset and baseline slope in each record (a zoned plate has a
stiffness ratio per zone: a longitudinal joint's own, :mod:`bwim.fe.joints`), and the
rest as in
:mod:`bwim.calibration.quasistatic` (the low-pass 𝓛 below the first natural frequency,
the Legendre force nuisance ``c`` with zero mean over each axle's time on the span, the
dynamic correction of the lowest modes).

Identifiability
---------------
A plate's strains scale as 1/E when every modulus scales together, and so do they when
the gain scales: **with gains fitted, the overall stiffness is not identifiable** and
``E_x`` stays at the start's value (the reference of the model's scale); the fit
identifies the stiffness *ratios* (``E_y`` relative to ``E_x``, girders relative to the
deck) and the gains.  The calibrated model predicts logger units through its gains, and a
force identified from readings divided by the gains is in newtons: the product is what is
identified, which is all that weighing needs.  The mass then carries the same scale: it is
fitted from the free vibration, which fixes the ratio of stiffness to mass.

Method
------
For trial nonlinear parameters z = (log stiffness ratios, x₀, y₀) the model is linear in
the nuisance: with a common gain, in (g, g c, o, r) jointly over all records (one
least-squares solve); with a gain per channel, bilinear, solved by Gauss–Newton from the
common gain's solution to a relative step below 1e-10.  z minimises the projected
residual (variable projection, Golub & Pereyra; ``scipy.optimize.least_squares``, finite
differences).  The mass is fitted afterwards from
the free vibration (:func:`~bwim.calibration.quasistatic.fit_mass`) on the readings less
their fitted offsets, when the readings after exit stand out of the noise
(:data:`MIN_FREE_SNR`); a mass fit that is not tried, fails or stops at its bound keeps
the start's mass and says so (``mass_message``): a short record tail on a stiff, damped
deck carries too little free vibration to weigh the deck.

Mesh defect correction (``mesh_correction``; docs/theory.md §12): the model's filtered
prediction at the fit (gains, force nuisance, frame) on the model bisected ``levels`` times
less the model's own is taken off the readings, and the nonlinear parameters are fitted
again, until no parameter moves by :data:`~bwim.calibration.meshdefect.TOL` (stiffness
ratios relative, x₀ and y₀ relative to the span).  ``"auto"``: as many bisections as
:func:`bwim.fe.convergence.check_mesh` of the start needs at the channels, under the
truck's static wheel loads where the first run's response peaks, to bring its estimated
error below :data:`~bwim.calibration.meshdefect.AUTO_TOL`; none if it is already there.
The answer's ``bridge`` is then the bisected model at the fitted parameters (the model
the gains belong to; ``mesh_correction`` reports the passes).

Contract
--------
* SI units; gains in logger units per unit strain; x₀ in m; stiffness in Pa.
* ``records``: records of the calibration vehicle with structural channels only (each
  with its x, y in the model's frame) and one passage each, whose x is relative to a
  common origin (e.g. the first axle detector): the model's wheel positions are
  ``passage.wheel_x(t) + x₀``.  Every record is already divided by its own drift factor
  (the caller's business).
* ``success`` is False when the least-squares fit did not converge or a parameter ended at
  its bound (``at_bound`` names it; the message says so).
* ``explained[r]``: the share of record r's filtered load response (readings less fitted
  offsets) the model explains, ``1 − ‖residual‖² / ‖response‖²``.
* ``misfit[r]``: the RMS of record r's filtered residual divided by the channels' noise
  (:func:`~bwim.calibration.problem.estimate_noise`, raw readings).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so
from numpy.polynomial import legendre

from bwim.calibration.meshdefect import (
    AUTO_MAX_LEVELS,
    AUTO_TOL,
    DefectCorrection,
    MeshCorrection,
    requested_levels,
)
from bwim.calibration.problem import ParameterSpace, estimate_noise
from bwim.calibration.quasistatic import (
    DEFAULT_CUTOFF_FRACTION,
    MassFit,
    fit_mass,
    moving_force_columns,
)
from bwim.errors import InputError, NumericalError
from bwim.fe.bridge import Bridge
from bwim.fe.convergence import check_mesh
from bwim.optimize import OptimizeResult
from bwim.records import Record

__all__ = ["GAIN_MODES", "LoggerCalibration", "calibrate_logger"]

#: How the channels' gains are fitted.
GAIN_MODES = ("common", "per_channel")
#: Stiffness ratios are bounded to [1/RATIO_BOUND, RATIO_BOUND] × the start's.
RATIO_BOUND = 5.0
#: A joint zone's E_y ratio may fall to 1 / JOINT_BOUND of the start's.
JOINT_BOUND = 1e3
#: x₀ is searched within ± this many metres of its start.
ORIGIN_RANGE = 1.5
#: The mass is fitted only when the readings after exit exceed the noise this many times
#: (RMS): below it, the free-vibration fit's optimum is set by the noise.
MIN_FREE_SNR = 3.0
#: The mass scale's search range (× the start's); a fit at either end is no answer.
MASS_BOUNDS = (0.4, 2.5)
#: Most Gauss–Newton steps of the per-channel gains' fit.
MAX_ALTERNATIONS = 50
#: A parameter within this fraction of its bound's range is at its bound.
AT_BOUND = 1e-3
_RATIOS = ("E_y", "E_girder")
_MASS = ("mu", "mu_girder")


@dataclass(frozen=True, kw_only=True, eq=False)
class LoggerCalibration(OptimizeResult):
    """Result of :func:`calibrate_logger` (scipy.optimize vocabulary for the fit).

    Attributes
    ----------
    bridge : Bridge
        The calibrated model (stiffness ratios, and mass when the free vibration gave it).
    channels : tuple of str
        The records' channel names, the order of ``gains``.
    gains : ndarray, shape (n_channels,)
        Logger units per unit of model strain.
    origin : float
        x₀: the bridge-frame position of the passages' origin, m.
    lateral : float
        y₀: the offset added to the passages' lateral positions, m (0 unless fitted).
    params, uncertainty : dict of str to float
        The fitted stiffness families (Pa) and x₀ (``"origin"``, m) with standard errors.
    x : ndarray
        The nonlinear parameters (stiffness ratios in log, then x₀).
    fun : float
        Weighted squared filtered residual at x, in units of the noise variance.
    nfev, nit : int
    success : bool
    message : str
    at_bound : tuple of str
        Parameters that ended at a bound.
    explained, misfit : ndarray, shape (n_records,)
        See the module contract.
    cutoff : float
        The low-pass cut-off, Hz.
    mass : MassFit or None
    mass_message : str
        What became of the mass (fitted, or kept and why).
    mesh_correction : MeshCorrection or None
        The defect correction's passes (``mesh_correction=``); its ``bridge`` is
        ``bridge``.
    """

    bridge: Bridge
    channels: tuple[str, ...]
    gains: np.ndarray
    origin: float
    lateral: float
    params: dict
    uncertainty: dict
    at_bound: tuple[str, ...]
    explained: np.ndarray
    misfit: np.ndarray
    cutoff: float
    mass: MassFit | None
    mass_message: str
    mesh_correction: MeshCorrection | None = None


def calibrate_logger(
    start_bridge: Bridge,
    records: Sequence[Record],
    axle_loads: Sequence[float],
    *,
    origin: float = 0.0,
    lateral: float | None = 0.0,
    gains: str = "common",
    unknowns: Sequence[str] | None = None,
    cutoff: float | None = None,
    n_basis: int = 4,
    filter_order: int = 4,
    inertia_modes: int = 3,
    mass: bool = True,
    n_free_modes: int = 3,
    min_free_periods: float = 3.0,
    mesh_correction: int | str = 0,
    joints: Sequence[int] = (),
) -> LoggerCalibration:
    """Calibrate a bridge model from logger records of a vehicle of known axle loads.

    Parameters
    ----------
    start_bridge : Bridge
        Starting model; its ``E_x`` is the scale reference (module docstring).
    records : sequence of Record
        See the module contract.
    axle_loads : sequence of float
        The vehicle's static axle loads, N (split equally between an axle's wheels).
    origin : float
        Starting x₀, m.
    lateral : float or None
        Starting y₀, an offset of every passage's lateral position (m; detection places
        a vehicle from its detectors' or the gauges' response, which may be biased);
        None: not fitted (0).
    gains : "common" or "per_channel"
    unknowns : sequence of str, optional
        Stiffness ratios to fit (``"E_y"``, ``"E_girder"``); default those the bridge has.
    cutoff : float, optional
        Low-pass cut-off, Hz; default 0.6 × the start's first natural frequency.
    n_basis : int
        Legendre terms per axle force.
    inertia_modes : int
        Modes whose dynamic correction is added to the static response.
    mass : bool
        Fit the mass from the free vibration after exit.
    mesh_correction : int or "auto"
        Bisections of the model that correct its discretisation error (module docstring;
        0: none, 1 to :data:`~bwim.calibration.meshdefect.MAX_LEVELS`, or ``"auto"``).
    joints : sequence of int
        Zones that are longitudinal joints (:mod:`bwim.fe.joints`: zone k + 1 for joint
        k): their ``E_y`` ratio may fall to 1 / :data:`JOINT_BOUND` of the start's (a
        joint may pass almost no bending), where the deck's is bounded by
        :data:`RATIO_BOUND`.
    """
    levels = mesh_correction if isinstance(mesh_correction, str) else requested_levels(
        mesh_correction)
    if isinstance(levels, str) and levels.strip().lower() != "auto":
        raise InputError(f"mesh_correction must be an integer or 'auto', got "
                         f"{mesh_correction!r}")
    problem = _Problem(start_bridge, records, axle_loads, origin=origin, lateral=lateral,
                       gains=gains,
                       unknowns=unknowns, cutoff=cutoff, n_basis=n_basis,
                       filter_order=filter_order, inertia_modes=inertia_modes, joints=joints)
    z0 = np.array([*np.zeros(problem.n_theta), float(origin),
                   *([] if lateral is None else [float(lateral)])])
    opt, nfev, nit = _solve(problem, z0, start_bridge)
    bridge = problem.bridge(opt.x, start_bridge)
    mfit, mass_message = None, "mass not fitted (mass=False): the start's is kept"
    state = problem.evaluate(opt.x, start_bridge, detail=mass)
    if mass:
        zeroed = problem.zeroed(state, opt.x)
        snr = _free_snr(zeroed, problem.sigma, problem.length)
        if snr < MIN_FREE_SNR:  # the fit's optimum would be the noise's: not tried
            mass_message = (f"mass not identified (the free vibration after exit is "
                            f"{snr:.1f} × the noise, below {MIN_FREE_SNR:g}): the start's "
                            "is kept")
        else:
            mfit = fit_mass(bridge, zeroed, n_modes=n_free_modes, bounds=MASS_BOUNDS,
                            min_periods=min_free_periods, weights=problem.weights)
            lo, hi = MASS_BOUNDS
            if not mfit.success:
                mass_message = f"mass not identified ({mfit.message}): the start's is kept"
            elif min(mfit.x / lo, hi / mfit.x) < 1 + 1e-2:
                mass_message = (f"mass not identified (the free-vibration fit stops at its "
                                f"bound, {mfit.x:.2f} × the start's): the start's is kept")
            else:
                mass_message = f"mass from the free vibration: {mfit.x:.3f} × the start's"
                base = bridge.with_params(**{n: bridge.params[n] * mfit.x
                                             for n in _MASS if n in bridge.params})
                if inertia_modes:  # the dynamic correction depends on the mass: fit again
                    opt, nfev2, nit2 = _solve(problem, opt.x, base)
                    nfev, nit = nfev + nfev2, nit + nit2
                bridge = problem.bridge(opt.x, base)
                state = problem.evaluate(opt.x, base)
    if isinstance(levels, str):
        levels = _auto_levels(problem, state, opt.x, bridge)
    correction = None
    if levels:
        fixer = _LoggerCorrection(levels, problem=problem, base=bridge)
        correction = fixer.solve(_Pass(opt=opt, state=state))
        opt, state = fixer.state.opt, fixer.state.state
        nfev += sum(p.opt.nfev for p in fixer.states)
        nit += sum(int(p.opt.njev or 0) for p in fixer.states)
        bridge = correction.bridge
    return _result(problem, opt, state, bridge, nfev, nit, mfit, mass_message, correction)


# --- the problem -----------------------------------------------------------------------------

def _signal():
    import scipy.signal

    return scipy.signal


@dataclass(frozen=True, kw_only=True, eq=False)
class _State:
    """The projected fit at one z: residual (stacked, weighted, in noise units), the
    gains, each record's fitted offsets (2, n_s) and filtered response."""

    residual: np.ndarray
    gains: np.ndarray
    offsets: list
    parts: list  # per record: (residual (t, s), response (t, s)), weighted


class _Problem:
    def __init__(self, start, records, axle_loads, *, origin, lateral, gains, unknowns, cutoff,
                 n_basis, filter_order, inertia_modes, joints=()) -> None:
        if not isinstance(start, Bridge):
            raise InputError(f"start_bridge must be a Bridge, got {type(start).__name__}")
        records = list(records) if isinstance(records, (list, tuple)) else [records]
        if not records or not all(isinstance(r, Record) and len(r.passages) == 1
                                  for r in records):
            raise InputError("records must be one or more single-passage bwim.Record")
        if gains not in GAIN_MODES:
            raise InputError(f"gains must be one of {GAIN_MODES}, got {gains!r}")
        names = tuple(s.name for s in records[0].sensors)
        for k, r in enumerate(records):
            if tuple(s.name for s in r.sensors) != names:
                raise InputError(f"records[{k}] has other channels than records[0]")
            if any(s.x is None or (start.is_plate and s.y is None) for s in r.sensors):
                raise InputError("every channel needs its position (x, y) on the model")
            if not np.all(np.isfinite(r.data)):
                raise InputError(f"records[{k}] contains NaN or infinite samples")
        loads = np.asarray(axle_loads, dtype=float)
        if loads.ndim != 1 or not np.all(np.isfinite(loads)) or np.any(loads <= 0):
            raise InputError("axle_loads must be positive forces, N")
        for k, r in enumerate(records):
            if r.passage.n_axles != loads.size:
                raise InputError(f"records[{k}]: {r.passage.n_axles} axles, the loads "
                                 f"give {loads.size}")
        if not isinstance(n_basis, (int, np.integer)) or n_basis < 0:
            raise InputError(f"n_basis must be a non-negative integer, got {n_basis!r}")
        self.names = tuple(unknowns) if unknowns is not None else tuple(
            n for n in _RATIOS if n in start.params)
        if any(n not in _RATIOS for n in self.names):
            raise InputError(f"unknowns must be stiffness ratios {_RATIOS} (E_x is the scale "
                             f"reference when gains are fitted), got {self.names}")
        self.space = ParameterSpace(start, self.names) if self.names else None
        self.theta0 = self.space.vector() if self.space else np.zeros(0)
        self.n_theta = int(self.theta0.size)
        # (family, zone) of each entry; a family of one entry is labelled by its name
        self.index = self.space.family_index() if self.space else []
        self.labels = tuple(f if self.space.sizes[self.names.index(f)] == 1 else f"{f}[{i}]"
                            for f, i in self.index)
        zones = start.model.n_zones
        self.joints = frozenset(int(k) for k in joints)
        if any(not 0 < k < zones for k in self.joints):
            raise InputError(f"joints must be zone labels 1 … {zones - 1} of the model (zone "
                             f"0 is the deck), got {sorted(self.joints)}")
        self.origin0 = float(origin)
        self.lateral = lateral is not None
        self.lateral0 = 0.0 if lateral is None else float(lateral)
        self.records = records
        self.channels = names
        self.gain_mode = gains
        self.n_basis = int(n_basis)
        self.n_inertia = int(inertia_modes)
        self.length = start.length
        f1 = float(start.modes(1).frequencies[0])
        self.cutoff = DEFAULT_CUTOFF_FRACTION * f1 if cutoff is None else float(cutoff)
        fs = records[0].sampling_rate
        if not 0 < self.cutoff < 0.5 * fs:
            raise InputError(f"cutoff must be in (0, {0.5 * fs:g}) Hz, got {self.cutoff!r}")
        self.sos = _signal().butter(filter_order, self.cutoff, fs=fs, output="sos")
        # channel weights 1/σ² (raw noise, floored), residuals in units of the noise
        sig = estimate_noise(records)
        top = max(float(s.max()) for s in sig)
        var = [np.maximum(s, 1e-3 * top) ** 2 for s in sig]
        self.noise = float(np.sqrt(1.0 / np.mean(np.concatenate([1 / v for v in var]))))
        self.weights = [self.noise**2 / v for v in var]
        self.sqrt_w = [np.sqrt(w) for w in self.weights]
        self.sigma = sig
        self.data = [_signal().sosfiltfilt(self.sos, r.data, axis=0) * sw / self.noise
                     for r, sw in zip(records, self.sqrt_w, strict=True)]
        self.wheel_loads = [np.repeat(loads / r.passage.wheels_per_axle,
                                      r.passage.wheels_per_axle) for r in records]
        self.ramp = [(r.time - r.time.mean())[:, None] for r in records]
        # the offset and slope columns as the readings see them: filtered like them (a
        # ramp is not filtered exactly at the record's ends)
        self.trend = []
        for ramp in self.ramp:
            B = np.column_stack([np.ones(ramp.shape[0]),
                                 _signal().sosfiltfilt(self.sos, ramp[:, 0])])
            self.trend.append((B, np.linalg.pinv(B)))

    # -- the model at z -------------------------------------------------------------------
    def bridge(self, z: np.ndarray, base: Bridge) -> Bridge:
        if not self.names:
            return base
        return self.space.bridge(self.theta0 * np.exp(z[:self.n_theta]), base)

    def columns(self, z: np.ndarray, base: Bridge) -> list:
        """Per record: b (t, s) and A (t, s, n_g·K), the filtered model columns, weighted
        and in noise units (the offsets are projected off later, channel by channel)."""
        bridge = self.bridge(z, base)
        n = self.n_theta
        x0 = float(z[n])
        y0 = float(z[n + 1]) if self.lateral else 0.0
        out = []
        for rec, P, sw in zip(self.records, self.wheel_loads, self.sqrt_w, strict=True):
            p = rec.passage
            t = rec.time
            x = p.wheel_x(t) + x0
            y = np.broadcast_to(p.wheel_y + y0, x.shape)
            ax = p.axle_x(t) + x0
            n_g = p.n_axles
            basis = np.zeros((t.size, n_g, self.n_basis))
            for g in range(n_g):
                inside = (ax[:, g] >= 0) & (ax[:, g] <= self.length)
                if np.count_nonzero(inside) < 2:
                    continue
                t0, t1 = t[inside][0], t[inside][-1]
                u = 2 * (t[inside] - t0) / (t1 - t0) - 1
                for k in range(self.n_basis):
                    coef = np.zeros(k + 2)
                    coef[k + 1] = 1.0
                    basis[inside, g, k] = legendre.legval(u, coef)
            fun = np.concatenate([np.ones((t.size, n_g, 1)), basis], axis=2)
            cols = moving_force_columns(bridge, rec.sensors, x, y, P, p.wheel_axle, fun,
                                        fs=rec.sampling_rate, n_modes=self.n_inertia)
            filt = _signal().sosfiltfilt(self.sos, cols, axis=0) * (sw / self.noise)
            b = filt[:, :, 0].sum(axis=1)
            A = filt[:, :, 1:].transpose(0, 3, 1, 2).reshape(t.size, -1, n_g * self.n_basis)
            out.append((b, A))
        return out

    def evaluate(self, z: np.ndarray, base: Bridge, *, detail: bool = False) -> _State:
        """The projected fit at z; with ``detail`` also each record's offsets."""
        cols = self.columns(z, base)
        if self.gain_mode == "common":
            return self._common(cols, detail)
        return self._per_channel(cols, detail)

    def _detrend(self, k: int, a: np.ndarray) -> np.ndarray:
        """``a`` (t, s, ...) less each channel's least-squares offset and slope over record
        k (the filtered trend columns): the projection off the offset columns, which are
        channel by channel (a channel's weight is constant in time and cancels)."""
        B, pinv = self.trend[k]
        flat = a.reshape(a.shape[0], -1)
        return (flat - B @ (pinv @ flat)).reshape(a.shape)

    def nuisance(self, k: int, b: np.ndarray, A: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Record k's force nuisance c at gains ``g`` (least squares on the detrended
        readings; the same minimiser as the projected fit's)."""
        dd, bd, Ad = (self._detrend(k, a) for a in (self.data[k], b, A))
        M = (Ad * g[None, :, None]).reshape(b.size, -1)
        return (np.linalg.lstsq(M, (dd - bd * g).ravel(), rcond=None)[0] if M.shape[1]
                else np.zeros(0))

    def _offsets(self, k: int, b: np.ndarray, A: np.ndarray, g: np.ndarray,
                 detail: bool) -> np.ndarray:
        """(2, s): each channel's offset and slope in record k (logger units): those of
        the readings less the model (gains ``g``, force nuisance fitted); zeros without
        ``detail``."""
        if not detail:
            return np.zeros((2, len(self.channels)))
        c = self.nuisance(k, b, A, g)
        rest = self.data[k] - g * (b + A @ c)
        _, pinv = self.trend[k]
        return (pinv @ rest) * (self.noise / self.sqrt_w[k])[None, :]

    def _common(self, cols, detail: bool = False) -> _State:
        """(g, g c_r, o_r, r_r): the nuisance blocks are record by record and only g is
        shared, so each record's b and readings are projected off its own nuisance (offsets
        by detrending, the force functions by a thin QR) and g is the pooled least-squares
        ratio of the projections."""
        n_s = len(self.channels)
        proj = []
        for k, (b, A) in enumerate(cols):
            Ad = self._detrend(k, A).reshape(b.size, -1)
            Q = np.linalg.qr(Ad)[0] if Ad.shape[1] else np.zeros((b.size, 0))
            bd = self._detrend(k, b).ravel()
            dd = self._detrend(k, self.data[k]).ravel()
            proj.append((bd - Q @ (Q.T @ bd), dd - Q @ (Q.T @ dd)))
        g = (sum(float(pb @ pd) for pb, pd in proj)
             / max(sum(float(pb @ pb) for pb, _ in proj), 1e-300))
        res, offsets, parts = [], [], []
        for k, ((b, A), (pb, pd)) in enumerate(zip(cols, proj, strict=True)):
            r = (pd - g * pb).reshape(b.shape)
            res.append(r.ravel())
            offsets.append(self._offsets(k, b, A, np.full(n_s, g), detail))
            parts.append((r, self._detrend(k, self.data[k])))
        return _State(residual=np.concatenate(res), gains=np.full(n_s, g), offsets=offsets,
                      parts=parts)

    def _per_channel(self, cols, detail: bool = False) -> _State:
        """The gains and the force nuisance jointly by Gauss–Newton on the bilinear model
        ``g_s (b + A c_r)_s`` (offsets projected off by detrending throughout), from the
        common gain's solution; the normal equations are assembled record by record (the
        gains couple the records, each record's nuisance only itself)."""
        n_s = len(self.channels)
        det = [(self._detrend(k, b), self._detrend(k, A), self._detrend(k, self.data[k]))
               for k, (b, A) in enumerate(cols)]
        g = np.full(n_s, self._common(cols).gains[0])
        cs = []
        for bd, Ad, dd in det:
            M = (Ad * g[None, :, None]).reshape(bd.size, -1)
            cs.append(np.linalg.lstsq(M, (dd - bd * g).ravel(), rcond=None)[0]
                      if M.shape[1] else np.zeros(0))
        sizes = [c.size for c in cs]
        n = n_s + sum(sizes)
        for _ in range(MAX_ALTERNATIONS):
            H, rhs = np.zeros((n, n)), np.zeros(n)
            off = n_s
            for (bd, Ad, dd), c, m in zip(det, cs, sizes, strict=True):
                P = bd + Ad @ c if m else bd  # (t, s) the model before the gains
                r = dd - g * P
                H[np.arange(n_s), np.arange(n_s)] += (P * P).sum(axis=0)
                rhs[:n_s] += (P * r).sum(axis=0)
                if m:
                    gA = (Ad * g[None, :, None])
                    H[:n_s, off:off + m] += np.einsum("ts,tsm->sm", P, gA)
                    flat = gA.reshape(-1, m)
                    H[off:off + m, off:off + m] += flat.T @ flat
                    rhs[off:off + m] += flat.T @ r.ravel()
                off += m
            H[n_s:, :n_s] = H[:n_s, n_s:].T
            step = np.linalg.lstsq(H, rhs, rcond=None)[0]
            g = g + step[:n_s]
            cs = [c + step[o:o + m] for c, o, m in
                  zip(cs, np.cumsum([n_s, *sizes[:-1]]), sizes, strict=True)]
            if float(np.max(np.abs(step[:n_s] / g))) < 1e-10:
                break
        res, offsets, parts = [], [], []
        for k, ((bd, Ad, dd), (b, A), c) in enumerate(zip(det, cols, cs, strict=True)):
            r = dd - g * (bd + Ad @ c if c.size else bd)
            res.append(r.ravel())
            offsets.append(self._offsets(k, b, A, g, detail))
            parts.append((r, dd))
        return _State(residual=np.concatenate(res), gains=g, offsets=offsets, parts=parts)

    def zeroed(self, state: _State, z: np.ndarray) -> list[Record]:
        """The records less their fitted offsets and slopes (logger units), passages in
        the model's frame."""
        n = self.n_theta
        x0, y0 = float(z[n]), float(z[n + 1]) if self.lateral else 0.0
        out = []
        for rec, o, ramp in zip(self.records, state.offsets, self.ramp, strict=True):
            base = o[0] + ramp * o[1]
            p = rec.passage
            moved = dataclasses.replace(p, delay=p.delay - x0 / p.speed, lane=p.lane + y0)
            out.append(dataclasses.replace(rec, data=rec.data - base, passages=(moved,)))
        return out

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        n = self.n_theta
        soft = [f == "E_y" and i in self.joints for f, i in self.index]
        lo = [*np.where(soft, -np.log(JOINT_BOUND), -np.log(RATIO_BOUND)),
              self.origin0 - ORIGIN_RANGE]
        hi = [*np.full(n, np.log(RATIO_BOUND)), self.origin0 + ORIGIN_RANGE]
        if self.lateral:
            lo.append(self.lateral0 - ORIGIN_RANGE)
            hi.append(self.lateral0 + ORIGIN_RANGE)
        return np.array(lo), np.array(hi)


# --- the mesh defect correction ---------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Pass:
    """One fit of the nonlinear parameters and its projected state."""

    opt: Any
    state: _State


class _LoggerCorrection(DefectCorrection):
    """The logger fit's defect correction (module docstring): the filtered, weighted
    prediction at the fitted gains and force nuisance on the corrector model less the
    model's own, taken off the problem's readings; each pass refits z.  A state is a
    :class:`_Pass`."""

    def __init__(self, levels: int, *, problem: _Problem, base: Bridge) -> None:
        super().__init__(levels)
        self.problem, self.base = problem, base
        self.measured = list(problem.data)
        self.peak = max(float(np.abs(d).max()) for d in self.measured)

    def model(self, state: _Pass) -> Bridge:
        return self.problem.bridge(state.opt.x, self.base)

    def correct(self, state: _Pass, coarse: Bridge, fine: Bridge) -> float:
        pb, z, g = self.problem, state.opt.x, state.state.gains
        worst = 0.0  # the force nuisance is the state's own: fitted to the data it fitted
        defects = []
        for k, ((bc, Ac), (bf, Af)) in enumerate(zip(pb.columns(z, coarse),
                                                     pb.columns(z, fine), strict=True)):
            c = pb.nuisance(k, bc, Ac, g)
            dk = g * ((bf - bc) + ((Af - Ac) @ c if c.size else 0.0))
            defects.append(dk)
            worst = max(worst, float(np.abs(dk).max()))
        pb.data = [d - dk for d, dk in zip(self.measured, defects, strict=True)]
        return worst / self.peak

    def refit(self, state: _Pass, k: int) -> _Pass:
        opt, _, _ = _solve(self.problem, state.opt.x, self.base)
        return _Pass(opt=opt, state=self.problem.evaluate(opt.x, self.base, detail=True))

    def change(self, old: _Pass, new: _Pass) -> float:
        n = self.problem.n_theta
        ratios = np.abs(np.exp(new.opt.x[:n] - old.opt.x[:n]) - 1)
        frame = np.abs(new.opt.x[n:] - old.opt.x[n:]) / self.problem.length
        return float(np.max(np.concatenate([ratios, frame])))


def _auto_levels(problem: _Problem, state: _State, z: np.ndarray, bridge: Bridge) -> int:
    """Bisections ``"auto"`` asks for: the mesh check of ``bridge`` at the channels under
    the truck's static wheel loads where the model's response to the first run peaks."""
    from bwim.loads import PointLoad

    rec = problem.zeroed(state, z)[0]
    b, _ = problem.columns(z, bridge)[0]
    k = int(np.argmax(np.abs(b).sum(axis=1)))
    p = rec.passage
    x = p.wheel_x(rec.time[k:k + 1])[0]
    loads = [PointLoad(x=float(xi), y=float(yi), P=float(f))
             for xi, yi, f in zip(x, p.wheel_y, problem.wheel_loads[0], strict=True)
             if 0 < xi < bridge.length]
    mc = check_mesh(bridge, rec.sensors, loads, tol=AUTO_TOL, max_levels=AUTO_MAX_LEVELS + 1)
    return AUTO_MAX_LEVELS if mc.adequate is None else mc.meshes.index(mc.adequate)


def _free_snr(records: list[Record], sigma: list[np.ndarray], length: float) -> float:
    """RMS of the readings after the last axle leaves over their noise's RMS, pooled."""
    num = den = 0.0
    for rec, sg in zip(records, sigma, strict=True):
        sel = rec.time > rec.passage.axle_times_on(length)[-1, 1]
        num += float((rec.data[sel] ** 2).sum())
        den += float(np.count_nonzero(sel)) * float((sg ** 2).sum())
    return float(np.sqrt(num / den)) if den > 0 else 0.0


def _solve(problem: _Problem, z0: np.ndarray, base: Bridge):
    lo, hi = problem.bounds()
    z0 = np.clip(z0, lo + 1e-9, hi - 1e-9)
    try:
        opt = so.least_squares(lambda z: problem.evaluate(z, base).residual, z0,
                               method="trf", diff_step=1e-4, bounds=(lo, hi))
    except np.linalg.LinAlgError:
        raise NumericalError("trial stiffness is not positive definite") from None
    return opt, int(opt.nfev), int(opt.njev or 0)


def _result(problem: _Problem, opt, state: _State, bridge: Bridge, nfev: int, nit: int,
            mfit: MassFit | None, mass_message: str,
            correction: MeshCorrection | None) -> LoggerCalibration:
    lo, hi = problem.bounds()
    labels = (*problem.labels, "origin", *(("lateral",) if problem.lateral else ()))
    tol = AT_BOUND * (hi - lo)
    at_bound = tuple(n for n, v, a, b, t in zip(labels, opt.x, lo, hi, tol, strict=True)
                     if v - a < t or b - v < t)
    J = opt.jac
    try:
        cov = np.linalg.inv(J.T @ J)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        se = np.full(opt.x.size, np.nan)
    params, unc = {}, {}
    for i, (label, (family, zone)) in enumerate(zip(problem.labels, problem.index,
                                                     strict=True)):
        v = float(np.atleast_1d(bridge.params[family])[zone or 0])
        params[label], unc[label] = v, v * float(se[i])
    n = problem.n_theta
    for i, label in enumerate(labels[n:]):
        params[label], unc[label] = float(opt.x[n + i]), float(se[n + i])
    explained = np.array([1 - float((r**2).sum()) / max(float((d**2).sum()), 1e-300)
                          for r, d in state.parts])
    misfit = np.array([float(np.sqrt(np.mean(r**2))) for r, _ in state.parts])
    success = bool(opt.success) and not at_bound
    message = str(opt.message) if not at_bound else (
        f"{', '.join(at_bound)} ended at a bound: the data do not pin "
        f"{'it' if len(at_bound) == 1 else 'them'} within the search range")
    return LoggerCalibration(
        bridge=bridge, channels=problem.channels, gains=state.gains.copy(),
        origin=params["origin"], lateral=params.get("lateral", 0.0), params=params,
        uncertainty=unc, x=opt.x.copy(),
        fun=float(2 * opt.cost), nfev=nfev, nit=nit, success=success, message=message,
        at_bound=at_bound, explained=explained, misfit=misfit, cutoff=problem.cutoff,
        mass=mfit, mass_message=mass_message, mesh_correction=correction)
