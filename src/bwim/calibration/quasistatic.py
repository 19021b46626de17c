"""Road-free calibration: stiffness from the quasi-static part of the strains, mass from
the bridge's free vibration.  No road profile is needed (issue 12).

Why
---
The paper's procedure (docs/theory.md §7) needs the road the truck drove on: its dynamic
stage re-simulates the crossing, and even its pseudo-static stage is biased by the
truck's dynamic axle forces, which the road drives.  A road known to a millimetre moves
the transverse modulus by far more than the gauge noise does (measured by
``benchmarks/bench_mismatch.py``).  Here the road never enters (docs/theory.md §13).

Model
-----
The measured strain at sensor ``s`` is (docs/theory.md §1.5, §3)

    ε_s(t) = Σ_j G_s(x_j(t), y_j) F_j(t) + v_s(t) + noise,

``G_s`` the sensor's static influence surface, ``F_j`` the (unknown) contact force of
wheel ``j`` and ``v_s`` the bridge's vibration, which lives at and above the first natural
frequency ``f₁``.  With a zero-phase low-pass filter ``𝓛`` (Butterworth, forward and
backward) whose cut-off is below ``f₁``, ``𝓛 v ≈ 0``; and the forces are written

    F_j(t) = P_j (1 + Σ_k c_{a(j),k} φ_{a(j),k}(t)),

``P_j`` the static wheel load (known), ``a(j)`` its axle (or the wheel itself with
``per_wheel=True``), ``φ_{a,k} = P_k(u)`` Legendre polynomials k = 1..K of the axle's
time on the span mapped to u ∈ [−1, 1] (zero outside).  These carry the slow force
variations (body bounce); they have **zero mean over the axle's time on the span**, which
is what pins the overall stiffness scale: a force scaled by α and a stiffness scaled by α
give the same strains, so without this constraint only stiffness *ratios* would be
identifiable (E_y/E_x from the transverse/longitudinal strain ratios).  The scale comes
from the known static loads, and its error is the mean dynamic force over the crossing,
which averages down over several runs.

For trial stiffness θ the filtered prediction is linear in the nuisance c:
``𝓛ε̂ = b(θ) + A(θ) c``.  Variable projection (Golub & Pereyra): c(θ) is the weighted
linear least-squares solution, and θ minimises the projected residual
``‖W^{1/2}(𝓛ε − b − A c(θ))‖²`` (``scipy.optimize.least_squares``, finite-difference
Jacobian, θ in log space).  Each record has its own nuisance; records share θ.

Mass: after the last axle leaves, the strains are the bridge's free vibration,
``Σ_m e^{−ζ_m ω_m t}(a_{s,m} cos ω_d t + b_{s,m} sin ω_d t)``.  With the stiffness fixed,
a uniform scale of the mass scales every ω_m by ``√(μ₀/μ)``; μ (one scale for every mass
family) minimises the projected residual of that fit (amplitudes linear, a grid then a
bounded scalar search).  ζ_m is the model's Rayleigh damping.  Needs a ``tail``
recorded after exit of at least ``min_free_periods`` periods of the highest first-mode
frequency of the mass search box, ``f₁/√bounds[0]`` (``min_free_periods·√bounds[0]``
periods of the model's own ``f₁``).  The fit fails when the free vibration does not stand
out of the noise: when the energy it explains, in units of each channel's noise variance
(:func:`~bwim.calibration.problem.estimate_noise`), is below what noise alone exceeds with
probability :data:`FREE_FALSE_ALARM` (:attr:`MassFit.snr`): the fit's optimum would then be
the noise's.

Contract
--------
* SI units; θ in Pa, μ in kg/m² (kg/m for girders); strain dimensionless; time s.
* ``records``: single-passage :class:`~bwim.records.Record` of the calibration vehicle,
  passage (speed, lane, delay) known; any number.
* The result's ``force_factors[r]`` has shape (n_t, n_groups): the identified
  ``1 + Σ c φ`` of record r (1 off the span).
* ``mesh_correction=N`` removes the model's discretisation error as
  :mod:`bwim.calibration.meshdefect` does for :func:`~bwim.calibrate`: the filtered
  prediction at the fitted stiffness and force nuisance on the model bisected N times,
  minus the model's own, is taken off the filtered measurements and the stiffness is
  fitted again from its answer (then the mass), until no parameter moves by
  :data:`~bwim.calibration.meshdefect.TOL`.  The defect is static here (influence
  surfaces and the inertia correction of the lowest modes), as is the fit.
* ``uncertainty`` is the standard error from the raw channels' noise
  (:func:`~bwim.calibration.problem.estimate_noise`) through ``(JᵀWJ)⁻¹`` of the filtered
  fit (the filtered noise's correlation is accounted for by using the *raw* σ: the
  Jacobian is band-limited to the filter's pass band, where the filter's gain is 1).  It
  does not include the error of the zero-mean force assumption; ``scale_bias`` gives the
  identified force variations' mean, RMS-weighted (a diagnostic of that error).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.optimize as so
from numpy.polynomial import legendre

from bwim.calibration.meshdefect import (
    DefectCorrection,
    MeshCorrection,
    requested_levels,
)
from bwim.calibration.problem import ParameterSpace, estimate_noise
from bwim.errors import InputError, NumericalError
from bwim.fe.bridge import Bridge
from bwim.fe.influence import influence_surfaces
from bwim.optimize import OptimizeResult
from bwim.records import Record
from bwim.vehicles import Vehicle

__all__ = ["FREE_FALSE_ALARM", "MassFit", "QuasiStaticCalibration", "calibrate_quasistatic",
           "fit_mass", "moving_force_columns", "oscillator_filter"]

#: Default cut-off as a fraction of the starting model's first natural frequency.
DEFAULT_CUTOFF_FRACTION = 0.6
#: The free-vibration fit fails when noise alone would explain as much of the tail as the
#: fit does with at least this probability (:attr:`MassFit.snr_noise`).
FREE_FALSE_ALARM = 1e-4
_STIFFNESS = ("E_x", "E_y", "E_girder")
_MASS = ("mu", "mu_girder")


@dataclass(frozen=True, kw_only=True, eq=False)
class MassFit:
    """The mass scale from the free vibration after the vehicle leaves.

    Attributes
    ----------
    x : float
        Mass scale relative to the model it was fitted on (μ = x μ₀).
    fun : float
        Weighted squared residual of the free-vibration fit at x.
    frequencies : ndarray
        The fitted model's natural frequencies used, Hz.
    n_samples : int
        Free-vibration samples used (over all records and channels).
    success : bool
    message : str
    standard_error : float
        Standard error of ``x``: ``sqrt(2 s² / f''(x))``, ``f`` the projected residual
        (its curvature by central differences, ``2 JᵀJ`` of the Gauss-Newton model) and
        ``s² = fun / (n_samples − amplitudes − 1)`` the residual variance per sample
        (white residuals assumed; NaN without a fit or with a flat cost).
    snr : float
        The free vibration's signal-to-noise ratio: the energy the fit explains at x,
        ``Σ_s (‖d_s‖² − ‖r_s‖²) / σ_s²`` over the tail's channels s (d the readings, r the
        residual, σ the channel's noise, :func:`~bwim.calibration.problem.estimate_noise`;
        ``N A² / 2σ²`` for one undamped mode of amplitude A over N samples); noise alone
        gives about ``2 × modes × channels``.  Infinite when no channel has noise, NaN
        without a fit.
    snr_noise : float
        The ``snr`` noise alone exceeds with probability :data:`FREE_FALSE_ALARM`: the χ²
        quantile with ``2 × modes × channels`` degrees of freedom at ``FREE_FALSE_ALARM /
        K``, K = 1 + T Δf the independent trial frequencies of the search (T the longest
        tail, Δf the highest mode's frequency range over ``bounds``).  The fit fails when
        ``snr < snr_noise``.
    """

    x: float
    fun: float
    frequencies: np.ndarray
    n_samples: int
    success: bool
    message: str
    standard_error: float = float("nan")
    snr: float = float("nan")
    snr_noise: float = float("nan")


@dataclass(frozen=True, kw_only=True, eq=False)
class QuasiStaticCalibration(OptimizeResult):
    """Result of :func:`calibrate_quasistatic` (scipy.optimize vocabulary for the fit).

    Attributes
    ----------
    bridge : Bridge
        The calibrated model (stiffness, and mass when it was fitted).
    params, uncertainty : dict of str to ndarray
        Calibrated families and their standard errors (see module docstring).
    x : ndarray
        The stiffness vector θ (Pa), ParameterSpace order.
    fun : float
        Weighted squared filtered residual at x.
    nfev, nit : int
    success : bool
    message : str
    cutoff : float
        Low-pass cut-off used, Hz.
    force_factors : tuple of ndarray
        Per record, (n_t, n_groups) identified force factor ``1 + Σ c φ``.
    scale_bias : float
        RMS over groups and records of the mean of ``Σ c φ`` weighted by the group's
        static strain energy at the sensors; ≈ 0 by construction of the basis; kept as
        a diagnostic (non-zero when axles share little time on the span).
    mass : MassFit or None
        The mass fit, or None when not asked for / no free vibration.
    mesh_correction : MeshCorrection or None
        What the mesh defect correction did (``mesh_correction=``).
    """

    bridge: Bridge
    params: dict
    uncertainty: dict
    cutoff: float
    force_factors: tuple
    scale_bias: float
    mass: MassFit | None
    mesh_correction: MeshCorrection | None = None


def _signal():
    """scipy.signal, imported on first use (it is slow to import)."""
    import scipy.signal

    return scipy.signal


def _lowpass(cutoff: float, fs: float, order: int):
    if not 0 < cutoff < 0.5 * fs:
        raise InputError(f"cutoff must be in (0, {0.5 * fs:g}) Hz, got {cutoff!r}")
    return _signal().butter(order, cutoff, fs=fs, output="sos")


@dataclass(frozen=True, kw_only=True, eq=False)
class _Fit:
    """One stiffness/mass alternation's end: log-stiffness z, the mass-updated base, the
    last least-squares result, its counts and the last mass fit."""

    z: np.ndarray
    base: Bridge
    opt: object
    nfev: int
    nit: int
    mass: MassFit | None


class _Record:
    """One record's fixed data: filtered measurements, wheel positions, nuisance basis."""

    def __init__(self, rec: Record, static_wheels, n_basis, per_wheel, sos, length, w):
        p = rec.passage
        self.t = rec.time
        self.x = p.wheel_x(rec.time)
        self.y = np.broadcast_to(p.wheel_y, self.x.shape)
        self.P = static_wheels
        self.group = np.arange(self.P.size) if per_wheel else p.wheel_axle
        self.n_groups = int(self.group.max()) + 1
        on = p.axle_times_on(length)
        span = on[p.wheel_axle] if per_wheel else on
        basis = np.zeros((self.t.size, self.n_groups, n_basis))
        for g in range(self.n_groups):
            t0, t1 = span[g]
            inside = (self.t >= t0) & (self.t <= t1)
            u = 2 * (self.t[inside] - t0) / (t1 - t0) - 1
            for k in range(n_basis):
                coef = np.zeros(k + 2)
                coef[k + 1] = 1.0
                basis[inside, g, k] = legendre.legval(u, coef)
        self.basis = basis
        self.sos = sos
        self.fs = rec.sampling_rate
        self.sqrt_w = np.sqrt(w)
        self.data = _signal().sosfiltfilt(sos, rec.data, axis=0) * self.sqrt_w
        self.sensors = rec.sensors

    def design(self, bridge: Bridge, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
        """b (n_t·n_s,) and A (n_t·n_s, n_groups·K), filtered and weighted
        (:func:`moving_force_columns`)."""
        fun = np.concatenate([np.ones((self.t.size, self.n_groups, 1)), self.basis], axis=2)
        cols = moving_force_columns(bridge, self.sensors, self.x, self.y, self.P, self.group,
                                    fun, fs=self.fs, n_modes=n_modes)
        n_t, n_s, K = self.t.size, cols.shape[3], self.basis.shape[2]
        b = _signal().sosfiltfilt(self.sos, cols[:, :, 0].sum(axis=1), axis=0) * self.sqrt_w
        A = _signal().sosfiltfilt(self.sos, cols[:, :, 1:], axis=0) * self.sqrt_w
        A = A.transpose(0, 3, 1, 2).reshape(n_t * n_s, self.n_groups * K)
        return b.ravel(), A


def oscillator_filter(omega: float, zeta: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Digital filter ``(b, a)`` (``a[0] = 1``) of a modal coordinate's response to its
    force, ``H(s) = 1 / (s² + 2ζω s + ω²)``, by the bilinear transform ``s = K (z − 1) /
    (z + 1)``, ``K = 2 fs``: multiplying through by ``(z + 1)²`` gives, in closed form,
    ``b ∝ (1, 2, 1)`` and ``a ∝ (K² + 2ζωK + ω², 2 (ω² − K²), K² − 2ζωK + ω²)``
    (Oppenheim & Schafer, *Discrete-Time Signal Processing*, 3rd ed., § 7.2; what
    ``scipy.signal.bilinear`` gives by polynomial arithmetic, to rounding).  ``omega``
    rad/s, ``fs`` Hz."""
    K = 2.0 * fs
    c = 2.0 * zeta * omega * K
    a0 = K * K + c + omega * omega
    b = np.array([1.0, 2.0, 1.0]) / a0
    a = np.array([1.0, 2.0 * (omega * omega - K * K) / a0, (K * K - c + omega * omega) / a0])
    return b, a


def _group_sum(values: np.ndarray, group: np.ndarray, n_groups: int) -> np.ndarray:
    """``values`` (n_t, n_w, …) summed over the wheels of each group (n_t, n_groups, …),
    wheel after wheel (the order and numbers of ``np.add.at``, without its slow path)."""
    out = np.zeros((values.shape[0], n_groups, *values.shape[2:]))
    for w, g in enumerate(group.tolist()):
        out[:, g] += values[:, w]
    return out


def moving_force_columns(bridge: Bridge, sensors, x: np.ndarray, y: np.ndarray,
                         P: np.ndarray, group: np.ndarray, fun: np.ndarray, *, fs: float,
                         n_modes: int) -> np.ndarray:
    """Readings of ``sensors`` under wheel forces ``P_w f_{g(w),k}(t)``, unfiltered.

    ``x, y`` (n_t, n_w) wheel positions (m), ``P`` (n_w,) static wheel loads (N),
    ``group`` (n_w,) each wheel's force group, ``fun`` (n_t, n_groups, F) the force time
    functions of each group.  Returns (n_t, n_groups, F, n_s): column (g, k) is the reading
    when group g's wheels carry ``P_w fun[:, g, k]``.  The static response plus, for each
    of the lowest ``n_modes`` modes, its dynamic correction ``ε_m (q_m − f_m/ω_m²)`` (mode
    acceleration method): below f₁ the bridge is not static, a crossing's slow loading is
    amplified by ≈ 1/(1 − (f/f₁)²).
    """
    ins = influence_surfaces(bridge, sensors)
    n_t, n_w = x.shape
    n_groups = fun.shape[1]
    G = ins.at(x.ravel(), y.ravel()).reshape(n_t, n_w, -1) * P[None, :, None]
    R = _group_sum(G, group, n_groups)
    cols = R[:, :, None, :] * fun[:, :, :, None]  # (t, g, F, s)
    if n_modes:
        model = bridge.model
        modes = bridge.modes(n_modes)
        xs, ys = x.ravel(), y.ravel()
        on = model.grid.contains(xs, ys if bridge.is_plate else None)
        phi_w = np.zeros((xs.size, modes.n))
        if np.any(on):
            rows = model.point_rows(xs[on], ys[on] if bridge.is_plate else None)
            phi_w[on] = rows.interpolate(modes.shapes)
        phi_w = phi_w.reshape(n_t, n_w, modes.n) * P[None, :, None]
        fm = _group_sum(phi_w, group, n_groups)
        eps = bridge.sensor_matrix(sensors) @ modes.shapes  # (s, m)
        zeta = bridge.rayleigh.ratio(modes.omega)
        for m in range(modes.n):
            om, z = modes.omega[m], zeta[m]
            num, den = oscillator_filter(om, z, fs)
            f = fm[:, :, m, None] * fun  # (t, g, F)
            q = _signal().lfilter(num, den, f, axis=0) - f / om**2
            cols += q[:, :, :, None] * eps[None, None, None, :, m]
    return cols


def calibrate_quasistatic(
    start_bridge: Bridge,
    records: Record | Sequence[Record],
    vehicle: Vehicle,
    *,
    unknowns: Sequence[str] | None = None,
    cutoff: float | None = None,
    n_basis: int = 4,
    per_wheel: bool = False,
    filter_order: int = 4,
    weights: str | None = "noise",
    mass: bool = True,
    n_free_modes: int = 3,
    min_free_periods: float = 3.0,
    inertia_modes: int = 3,
    n_rounds: int = 3,
    mesh_correction: int = 0,
) -> QuasiStaticCalibration:
    """Calibrate the stiffness without a road profile (and the mass from free vibration).

    Parameters
    ----------
    start_bridge : Bridge
        Starting model (also the initial stiffness guess).
    records : Record or sequence of Record
        Crossings of ``vehicle`` (one passage each); they stack.
    vehicle : Vehicle
        The calibration vehicle (its static wheel loads are used; its dynamics are not).
    unknowns : sequence of str, optional
        Stiffness families to fit; default those of E_x, E_y, E_girder the bridge has.
    cutoff : float, optional
        Low-pass cut-off, Hz; default 0.6 × the starting model's first frequency.
    n_basis : int
        Legendre terms (degrees 1..n_basis) per axle force (0: forces = static loads).
    per_wheel : bool
        One nuisance function per wheel instead of per axle (lets the body roll).
    weights : "noise" or None
        Channel weights 1/σ̂² from each record's estimated noise, or none.
    mass : bool
        Fit the mass scale from the free vibration after exit (:func:`fit_mass`).
    inertia_modes : int
        Modes whose dynamic correction is added to the static response (0: static only).
    n_rounds : int
        Stiffness/mass alternations (with ``mass`` and ``inertia_modes``).
    mesh_correction : int
        Bisections of the corrector model (0: none; see the module contract).
    """
    checked = _check_inputs(start_bridge, records, vehicle, unknowns=unknowns,
                            n_basis=n_basis, weights=weights, mesh_correction=mesh_correction)
    problem = _RoadFree(start_bridge, checked, cutoff=cutoff, n_basis=int(n_basis),
                        per_wheel=per_wheel, filter_order=filter_order, weights=weights,
                        mass=mass, n_free_modes=n_free_modes,
                        min_free_periods=min_free_periods, inertia_modes=int(inertia_modes),
                        n_rounds=n_rounds)
    states, correction = [problem.fit(np.zeros(problem.theta0.size), start_bridge)], None
    if checked.levels:
        mesh = _StaticCorrection(checked.levels, problem=problem)
        correction = mesh.solve(states[0])
        states += mesh.states
    return _result(problem, states, correction)


# --- step 1: the inputs -------------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Checked:
    """The checked inputs of :func:`calibrate_quasistatic`."""

    records: list[Record]
    names: tuple[str, ...]  # the stiffness families fitted
    levels: int  # bisections of the corrector model (0: no mesh correction)
    static_wheels: np.ndarray  # the vehicle's static wheel loads, N


def _check_inputs(start_bridge, records, vehicle, *, unknowns, n_basis, weights,
                  mesh_correction) -> _Checked:
    """The inputs checked (one-line InputErrors)."""
    if not isinstance(start_bridge, Bridge):
        raise InputError(f"start_bridge must be a Bridge, got {type(start_bridge).__name__}")
    records = list(records) if isinstance(records, (list, tuple)) else [records]
    if not records or not all(isinstance(r, Record) and len(r.passages) == 1
                              for r in records):
        raise InputError("records must be one or more single-passage bwim.Record")
    if not isinstance(n_basis, (int, np.integer)) or n_basis < 0:
        raise InputError(f"n_basis must be a non-negative integer, got {n_basis!r}")
    if weights not in ("noise", None):
        raise InputError(f"weights must be 'noise' or None, got {weights!r}")
    levels = requested_levels(mesh_correction)
    static_wheels = vehicle.model().static_forces
    for k, r in enumerate(records):
        p = r.passage
        if p.n_axles * p.wheels_per_axle != static_wheels.size:
            raise InputError(f"records[{k}] wheel layout does not match the vehicle")
    names = tuple(unknowns) if unknowns is not None else tuple(
        n for n in _STIFFNESS if n in start_bridge.params)
    if any(n not in _STIFFNESS for n in names):
        raise InputError(f"unknowns must be stiffness families {_STIFFNESS}, got {names}")
    return _Checked(records=records, names=names, levels=levels, static_wheels=static_wheels)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Weights:
    """Channel weights per record and the unit of the residuals."""

    channels: list[np.ndarray]  # per record (n_s,), mean 1 over the channels' 1/σ²
    scale: float  # squared residual unit: the raw noise's variance


def _channel_weights(records: list[Record], weights: str | None) -> _Weights:
    """``1/σ̂²`` per channel from each record's noise (or 1), and the noise variance the
    residuals are divided by (so the optimiser's tolerances are meaningful)."""
    sig = estimate_noise(records)
    if weights == "noise":
        top = max(float(s.max()) for s in sig)
        var = [np.maximum(s, 1e-3 * top) ** 2 for s in sig]
        mean_inv = float(np.mean(np.concatenate([1 / v for v in var])))
        w = [1 / v / mean_inv for v in var]
    else:
        w = [np.ones(r.data.shape[1]) for r in records]
    # residuals in units of the raw noise σ (so the optimiser's tolerances are meaningful)
    sig2 = 1.0 / np.mean(np.concatenate([1 / np.maximum(s, 1e-30) ** 2 for s in sig]))
    scale = sig2 if weights == "noise" else float(np.mean(np.concatenate(sig) ** 2))
    return _Weights(channels=w, scale=scale)


# --- step 2: the road-free fit ------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class _Projection:
    """The projected residual at a trial stiffness and the force nuisance behind it."""

    residual: np.ndarray  # all records, filtered, weighted
    coefs: list[np.ndarray]  # per record, the Legendre coefficients c


class _RoadFree:
    """The road-free problem (module docstring): the stiffness by variable projection of
    the filtered strains, alternated with the mass from the free vibration.

    ``defects`` (filtered and weighted, per record) are taken off the measurements; the
    mesh correction sets them (zero otherwise).
    """

    def __init__(self, start: Bridge, checked: _Checked, *, cutoff, n_basis, per_wheel,
                 filter_order, weights, mass, n_free_modes, min_free_periods,
                 inertia_modes, n_rounds) -> None:
        records = checked.records
        self.names = checked.names
        self.space = ParameterSpace(start, checked.names)
        f1 = float(start.modes(1).frequencies[0])
        self.cutoff = DEFAULT_CUTOFF_FRACTION * f1 if cutoff is None else float(cutoff)
        sos = _lowpass(self.cutoff, records[0].sampling_rate, filter_order)
        self.weights = _channel_weights(records, weights)
        self.parts = [_Record(r, checked.static_wheels, n_basis, per_wheel, sos, start.length,
                              wk / self.weights.scale)
                      for r, wk in zip(records, self.weights.channels, strict=True)]
        self.records = records
        self.theta0 = self.space.vector()
        self.n_inertia = inertia_modes
        self.mass = mass
        self.n_free_modes, self.min_free_periods = n_free_modes, min_free_periods
        self.rounds = max(1, int(n_rounds)) if (mass and inertia_modes) else 1
        self.defects = [0.0] * len(self.parts)

    def bridge(self, z: np.ndarray, base: Bridge) -> Bridge:
        """The model at log-stiffness ``z`` (relative to the start), mass from ``base``."""
        return self.space.bridge(self.theta0 * np.exp(z), base)

    def project(self, z: np.ndarray, base: Bridge) -> _Projection:
        """The filtered residual with the force nuisance c(θ) projected out."""
        bridge = self.bridge(z, base)
        res, coefs = [], []
        for part, defect in zip(self.parts, self.defects, strict=True):
            b, A = part.design(bridge, self.n_inertia)
            r = part.data.ravel() - defect - b
            if A.shape[1]:
                c = np.linalg.lstsq(A, r, rcond=None)[0]
                r = r - A @ c
            else:
                c = np.zeros(0)
            res.append(r)
            coefs.append(c)
        return _Projection(residual=np.concatenate(res), coefs=coefs)

    def fit(self, z: np.ndarray, base: Bridge) -> _Fit:
        """Alternate: stiffness (mass fixed) then mass (stiffness fixed); the inertia
        correction is what couples them, weakly."""
        nfev = nit = 0
        mfit = None
        for _ in range(self.rounds):
            try:
                opt = so.least_squares(lambda z, base=base: self.project(z, base).residual, z,
                                       method="trf", diff_step=1e-4,
                                       bounds=(np.log(0.2), np.log(5.0)))
            except np.linalg.LinAlgError:
                raise NumericalError("trial stiffness is not positive definite") from None
            z, nfev, nit = opt.x, nfev + int(opt.nfev), nit + int(opt.njev or 0)
            bridge = self.bridge(z, base)
            if self.mass:
                mfit = fit_mass(bridge, self.records, n_modes=self.n_free_modes,
                                min_periods=self.min_free_periods,
                                weights=self.weights.channels)
                if not mfit.success:
                    break
                base = bridge.with_params(**{n: bridge.params[n] * mfit.x
                                             for n in _MASS if n in bridge.params})
        return _Fit(z=z, base=base, opt=opt, nfev=nfev, nit=nit, mass=mfit)


# --- step 3: the mesh correction ----------------------------------------------------------

class _StaticCorrection(DefectCorrection):
    """The road-free defect correction (module contract): the filtered prediction at the
    fitted stiffness and force nuisance on the corrector model minus the model's own; each
    pass refits the stiffness (then the mass).  A state is a :class:`_Fit`."""

    def __init__(self, levels: int, *, problem: _RoadFree) -> None:
        super().__init__(levels)
        self.problem = problem
        self.peak = max(float(np.abs(part.data).max()) for part in problem.parts)

    def model(self, state: _Fit) -> Bridge:
        return self.problem.bridge(state.z, state.base)

    def correct(self, state: _Fit, coarse: Bridge, fine: Bridge) -> float:
        pb = self.problem
        coefs = pb.project(state.z, state.base).coefs
        for k, (part, c) in enumerate(zip(pb.parts, coefs, strict=True)):
            bf, Af = part.design(fine, pb.n_inertia)
            bc, Ac = part.design(coarse, pb.n_inertia)
            pb.defects[k] = (bf - bc) + ((Af - Ac) @ c if c.size else 0.0)
        return max(float(np.abs(d).max()) for d in pb.defects) / self.peak

    def refit(self, state: _Fit, k: int) -> _Fit:
        return self.problem.fit(state.z, state.base)

    def change(self, old: _Fit, new: _Fit) -> float:
        before, after = self.model(old).params, self.model(new).params
        return max(float(np.abs(after[n] / before[n] - 1).max())
                   for n in (*self.problem.names, *(m for m in _MASS if m in after)))


# --- step 4: the result -------------------------------------------------------------------

def _result(problem: _RoadFree, states: list[_Fit],
            correction: MeshCorrection | None) -> QuasiStaticCalibration:
    """The last state's model, force factors and standard errors; counts over all fits."""
    state = states[-1]
    z, base, opt, mfit = state.z, state.base, state.opt, state.mass
    theta = problem.theta0 * np.exp(z)
    bridge = problem.space.bridge(theta, base)
    forces = _force_factors(problem.parts, problem.project(z, base).coefs)
    params = problem.space.split(theta)
    unc = problem.space.split(_standard_error(opt.jac, theta))
    if mfit is not None and mfit.success:
        params.update({n: bridge.params[n] for n in _MASS if n in bridge.params})
    return QuasiStaticCalibration(
        bridge=bridge, params=params, uncertainty=unc, x=theta,
        fun=float(2 * opt.cost * problem.weights.scale),
        nfev=sum(s.nfev for s in states), nit=sum(s.nit for s in states),
        success=bool(opt.success), message=str(opt.message), cutoff=problem.cutoff,
        force_factors=forces.factors, scale_bias=forces.scale_bias, mass=mfit,
        mesh_correction=correction)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Forces:
    """The identified force variations (:class:`QuasiStaticCalibration`'s fields)."""

    factors: tuple  # per record (n_t, n_groups): 1 + Σ c φ
    scale_bias: float


def _force_factors(parts: list[_Record], coefs: list[np.ndarray]) -> _Forces:
    """Per record the force factors ``1 + Σ c φ`` (n_t, n_groups), and the RMS over groups
    and records of their mean over each group's time on the span less 1."""
    factors, biases = [], []
    for part, c in zip(parts, coefs, strict=True):
        d = (np.einsum("tgk,gk->tg", part.basis, c.reshape(part.n_groups, -1))
             if c.size else np.zeros((part.t.size, part.n_groups)))
        factors.append(1 + d)
        on = part.basis[:, :, 0] != 0 if part.basis.shape[2] else np.zeros_like(d, bool)
        biases += [float(d[on[:, g], g].mean()) if on[:, g].any() else 0.0
                   for g in range(part.n_groups)]
    return _Forces(factors=tuple(factors),
                   scale_bias=float(np.sqrt(np.mean(np.square(biases)))) if biases else 0.0)


def _standard_error(jac: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``sqrt(diag((JᵀJ)⁻¹))`` with J (in log θ, residuals in units of σ) taken to θ; nan
    where JᵀJ is singular."""
    J = jac / theta[None, :]
    try:
        cov = np.linalg.inv(J.T @ J)
        return np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        return np.full(theta.size, np.nan)


def fit_mass(
    bridge: Bridge,
    records: Record | Sequence[Record],
    *,
    n_modes: int = 3,
    min_periods: float = 3.0,
    bounds: tuple[float, float] = (0.4, 2.5),
    weights: Sequence[np.ndarray] | None = None,
) -> MassFit:
    """The mass scale x (μ = x μ₀ for every mass family of ``bridge``) from the free
    vibration after the last axle leaves (see module docstring).  No road needed.

    Parameters
    ----------
    bridge : Bridge
        The model (its stiffness and damping fixed; x scales its masses).
    records : Record or sequence of Record
        Records whose passages have left the span before the record ends.
    n_modes : int
        Modes of the free vibration fitted.
    min_periods : float
        A record's tail counts when it holds this many periods of the highest first-mode
        frequency of the search, ``f₁ / √bounds[0]`` (f₁ the model's):
        ``min_periods × √bounds[0]`` periods of f₁.  Without such a tail the fit fails
        with ``n_samples = 0``.
    bounds : (float, float)
        The search box of x (it brackets 1).
    weights : sequence of arrays, optional
        Per-record channel weights of the squared residuals.

    The fit fails (``success=False``, x still reported) when the free vibration is not
    out of the noise: ``snr < snr_noise`` (:class:`MassFit`).
    """
    records = list(records) if isinstance(records, (list, tuple)) else [records]
    if not 0 < bounds[0] < 1 < bounds[1]:
        raise InputError(f"bounds must bracket 1, got {bounds!r}")
    modes = bridge.modes(n_modes)
    om0 = modes.omega
    ratio = bridge.rayleigh.ratio
    segs = []
    for k, rec in enumerate(records):
        t_exit = max(p.axle_times_on(bridge.length)[-1, 1] for p in rec.passages)
        sel = rec.time > t_exit + 1.0 / rec.sampling_rate
        if rec.time[sel].size < 2:
            continue
        tau = rec.time[sel] - rec.time[sel][0]
        if tau[-1] * modes.frequencies[0] / np.sqrt(bounds[0]) < min_periods:
            continue
        sw = np.ones(rec.data.shape[1]) if weights is None else np.sqrt(weights[k])
        segs.append((tau, rec.data[sel] * sw, estimate_noise([rec])[0] * sw))
    if not segs:
        need = min_periods * np.sqrt(bounds[0])  # periods of the model's f1
        return MassFit(x=np.nan, fun=np.nan, frequencies=modes.frequencies, n_samples=0,
                       success=False, message=f"no free vibration after exit (record a tail "
                       f"of ≥ {need:.3g} periods of the first mode, "
                       f"{need / modes.frequencies[0]:.3g} s)")

    def residuals(s):
        om = om0 / np.sqrt(s)
        zeta = ratio(om)
        wd = om * np.sqrt(1 - np.minimum(zeta, 0.99) ** 2)
        out = []
        for tau, d, _ in segs:
            env = np.exp(-np.outer(tau, zeta * om))
            B = np.hstack([env * np.cos(np.outer(tau, wd)), env * np.sin(np.outer(tau, wd))])
            c = np.linalg.lstsq(B, d, rcond=None)[0]
            out.append(d - B @ c)
        return out

    def cost(s):
        return sum(float((r**2).sum()) for r in residuals(s))

    grid = np.exp(np.linspace(np.log(bounds[0]), np.log(bounds[1]), 241))
    vals = np.array([cost(s) for s in grid])
    i = int(np.argmin(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    r = so.minimize_scalar(cost, bounds=(lo, hi), method="bounded",
                           options={"xatol": 1e-6})
    n = sum(d.size for _, d, _ in segs)
    dof = n - sum(2 * om0.size * d.shape[1] for _, d, _ in segs) - 1
    h = 1e-3 * float(r.x)
    curvature = (cost(r.x + h) - 2 * float(r.fun) + cost(r.x - h)) / h**2
    se = (float(np.sqrt(2 * float(r.fun) / dof / curvature))
          if dof > 0 and curvature > 0 else float("nan"))
    snr, snr_noise = _free_snr(segs, residuals(r.x), modes.frequencies, bounds)
    success, message = bool(r.success), str(r.message)
    if success and snr < snr_noise:
        success, message = False, (
            f"the free vibration after exit is not out of the noise (snr {snr:.3g}, below "
            f"the {snr_noise:.3g} noise alone exceeds with probability "
            f"{FREE_FALSE_ALARM:g}): the fit's optimum would be the noise's")
    return MassFit(x=float(r.x), fun=float(r.fun), frequencies=om0 / np.sqrt(r.x) / 2 / np.pi,
                   n_samples=n, success=success, message=message, standard_error=se,
                   snr=snr, snr_noise=snr_noise)


def _free_snr(segs: list, residuals: list[np.ndarray], frequencies: np.ndarray,
              bounds: tuple[float, float]) -> tuple[float, float]:
    """``(snr, snr_noise)`` of :class:`MassFit` from the fitted tails ``segs`` (time, data,
    channel noise) and their residuals at the answer."""
    import scipy.stats

    sig = np.concatenate([sg for _, _, sg in segs])
    top = float(sig.max())
    if top <= 0:
        snr = float("inf")
    else:
        var = np.maximum(sig, 1e-3 * top) ** 2  # a noise-free channel: floored (noise_weights)
        explained = np.concatenate([(d**2).sum(axis=0) - (res**2).sum(axis=0)
                                    for (_, d, _), res in zip(segs, residuals, strict=True)])
        snr = float((explained / var).sum())
    tail = max(float(tau[-1]) for tau, _, _ in segs)
    trials = 1.0 + tail * float(frequencies[-1]) * (1 / np.sqrt(bounds[0])
                                                     - 1 / np.sqrt(bounds[1]))
    dof = 2 * frequencies.size * sig.size
    return snr, float(scipy.stats.chi2.isf(FREE_FALSE_ALARM / trials, dof))
