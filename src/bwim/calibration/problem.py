"""Calibration objectives: parameter vectors, the static and dynamic misfits, neighbours.

Contract
--------
* A :class:`ParameterSpace` maps a flat vector ``θ`` to bridge parameters: the families
  being calibrated (e.g. ``("E_x", "E_y")`` then ``("mu",)``) times their zones (or
  girders), in that order.  :meth:`ParameterSpace.bridge` builds the trial bridge.
* :class:`StaticObjective` (docs/theory.md §7 step 1) is the pseudo-static misfit: for a trial
  stiffness, the static strains of the calibration truck's static wheel loads at their
  positions, through influence surfaces (one banded factorisation and one solve per
  sensor, docs/theory.md §1.5), against the measured (dynamic) strains.
* :class:`DynamicObjective` (step 2) simulates the calibration crossing on the trial
  bridge (vehicle–bridge interaction over the given road) and compares total strains.
  A trial whose stiffness equals a recent trial's and whose masses are all that trial's
  times one factor c (e.g. a single μ zone) reuses its modes, scaled exactly
  (:func:`bwim.fe.modal.scaled_modes`: ω × c^(−½), shapes × c^(−½)); otherwise the
  modes are solved for.
* :meth:`StaticObjective.jacobian` is the residuals' Jacobian by the adjoint method
  (docs/theory.md §1.5).
* Both return, per trial, the squared misfit of each **part**: the channels of one
  measurement point (the sub-objectives of sub-structured CE, paper §4.1;
  docs/theory.md §6).  Their sum is the objective.  :func:`neighbour_map` says which
  parameters neighbour which part: the zones of the elements that touch the point, and
  girders within one element of it.
* Channel weights: unweighted by default (the paper's plain sum);
  :func:`noise_weights` estimates each channel's noise from the data itself (no noise
  model assumed); :func:`peak_weights` is the paper's §5.2 model (noise ∝ channel peak).
* Objectives are picklable, so populations can be evaluated in worker processes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from bwim.dynamics.crossing import DEFAULT_APPROACH, prepare_crossing, run_crossing
from bwim.errors import InputError, NumericalError
from bwim.fe.bridge import Bridge
from bwim.fe.influence import static_sensitivities
from bwim.fe.modal import Modes, scaled_modes, select_modes
from bwim.records import Record, SimulationSettings
from bwim.road import RoadProfile
from bwim.vehicles import Vehicle

__all__ = [
    "DynamicObjective",
    "ParameterSpace",
    "StaticObjective",
    "estimate_noise",
    "measurement_points",
    "neighbour_map",
    "noise_weights",
    "peak_weights",
]


@dataclass(frozen=True, eq=False)
class ParameterSpace:
    """The calibrated parameters of a bridge as a flat vector.

    Attributes
    ----------
    start : Bridge
        The starting model; parameters not calibrated keep its values.
    names : tuple of str
        Parameter families, in vector order.
    shared : frozenset of str
        Families calibrated as one value for all their zones or girders (e.g. identical
        girders); the vector holds their mean.
    """

    start: Bridge
    names: tuple[str, ...]
    shared: frozenset = frozenset()
    sizes: tuple[int, ...] = field(init=False)

    def __post_init__(self) -> None:
        present = self.start.params
        for n in self.names:
            if n not in present:
                raise InputError(f"unknown parameter {n!r}; this bridge has {sorted(present)}")
        object.__setattr__(self, "shared", frozenset(self.shared) & set(self.names))
        object.__setattr__(self, "sizes", tuple(
            1 if n in self.shared else present[n].size for n in self.names))

    @property
    def n(self) -> int:
        return sum(self.sizes)

    def labels(self) -> list[str]:
        return [f"{n}[{i}]" for n, k in zip(self.names, self.sizes, strict=True)
                for i in range(k)]

    def vector(self, bridge: Bridge | None = None) -> np.ndarray:
        params = (self.start if bridge is None else bridge).params
        return np.concatenate([params[n].mean(keepdims=True) if n in self.shared
                               else params[n] for n in self.names])

    def split(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """Families' values for a vector (shared families broadcast to all entries)."""
        theta = np.asarray(theta, dtype=float)
        full = self.start.params
        out, i = {}, 0
        for n, k in zip(self.names, self.sizes, strict=True):
            part = theta[i:i + k]
            out[n] = np.full(full[n].size, part[0]) if n in self.shared else part
            i += k
        return out

    def bridge(self, theta: np.ndarray, base: Bridge | None = None) -> Bridge:
        return (self.start if base is None else base).with_params(**self.split(theta))

    def family_index(self) -> list[tuple[str, int | None]]:
        """(family, zone/girder index) of every vector entry (None: all, shared)."""
        return [(n, None if n in self.shared else i)
                for n, k in zip(self.names, self.sizes, strict=True) for i in range(k)]


def measurement_points(sensors) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Group channels by measurement point: (part index of each channel, the points)."""
    points: list[tuple[float, float]] = []
    part = np.empty(len(sensors), dtype=int)
    for c, s in enumerate(sensors):
        key = (round(s.x, 9), round(s.y, 9))
        if key not in points:
            points.append(key)
        part[c] = points.index(key)
    return part, points


def neighbour_map(space: ParameterSpace, sensors) -> np.ndarray:
    """Which parameters neighbour which measurement point, bool (n_parts, n_params)."""
    model = space.start.model
    grid = model.grid
    _, points = measurement_points(sensors)
    nb = np.zeros((len(points), space.n), dtype=bool)
    fam = space.family_index()
    for j, (x, y) in enumerate(points):
        zones = {int(model.zone_of_element[e]) for e, _, _ in grid.elements_at(x, y)}
        near_girders = set()
        if grid.is_plate:
            iy = np.searchsorted(grid.y_lines, y)
            for g, line in enumerate(model.girder_lines):
                if abs(line - iy) <= 1:
                    near_girders.add(g)
        for p, (name, idx) in enumerate(fam):
            if idx is None:  # shared by all zones or girders
                nb[j, p] = True
            elif name in Bridge.GIRDER_FAMILIES:
                nb[j, p] = idx in near_girders
            else:
                nb[j, p] = idx in zones
    return nb


def _check_records(records: Sequence[Record], vehicle: Vehicle) -> list[Record]:
    records = list(records) if isinstance(records, (list, tuple)) else [records]
    if not records:
        raise InputError("calibration needs at least one record of the calibration truck")
    for k, r in enumerate(records):
        if not isinstance(r, Record):
            raise InputError(f"records[{k}] must be a bwim.Record, got {type(r).__name__}")
        if len(r.passages) != 1:
            raise InputError(f"records[{k}] must hold exactly one passage (the calibration "
                             f"truck), got {len(r.passages)}")
        if r.passage.n_axles != vehicle.n_axles:
            raise InputError(f"records[{k}] has {r.passage.n_axles} axles but the calibration "
                             f"vehicle has {vehicle.n_axles}")
    return records


def peak_weights(records: Sequence[Record]) -> list[np.ndarray]:
    """Channel weights ``1 / peak²`` of each record: the maximum-likelihood weighting when
    each channel's noise is proportional to its peak reading (the paper's §5.2 model)."""
    out = []
    for rec in records:
        peak = np.abs(rec.data).max(axis=0)
        out.append(1.0 / np.where(peak > 0, peak, 1.0) ** 2)
    return out


def estimate_noise(records: Sequence[Record]) -> list[np.ndarray]:
    """Each channel's noise standard deviation as estimated from the data, per record.

    σ̂ is the robust spread of the channel's second differences (``1.4826 × MAD / √6``,
    exact for white noise): a strain signal sampled far above its bandwidth is smooth
    from one sample to the next, its noise is not.  No noise model is assumed.
    """
    out = []
    for rec in records:
        d2 = np.diff(np.asarray(rec.data, dtype=float), n=2, axis=0)
        mad = np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0)
        out.append(1.4826 * mad / np.sqrt(6.0))
    return out


def noise_weights(records: Sequence[Record], *,
                  model_error: np.ndarray | None = None) -> list[np.ndarray]:
    """Channel weights ``1 / (σ̂² + e²)`` from the data's own noise (:func:`estimate_noise`)
    and, optionally, the model's error ``e`` at each channel (same units, e.g. the
    discretisation error of :func:`bwim.fe.convergence.check_mesh`).

    Under gauge noise the weights come out equal, under noise proportional to each
    channel's peak ``∝ 1 / peak²``; a channel the model cannot reproduce weighs less.
    Weights are normalised to a mean of 1 over all channels of all records (residuals
    stay strain-sized); a σ̂ below 10⁻³ of the largest one is floored there (noise-free
    channels do not take all the weight).
    """
    sig = estimate_noise(records)
    top = max((float(s.max()) for s in sig if s.size), default=0.0)
    var = [np.maximum(s, 1e-3 * top) ** 2 for s in sig]
    if model_error is not None:
        e = np.asarray(model_error, dtype=float)
        var = [v + e**2 for v in var]
    if max(float(v.max()) for v in var) <= 0:
        return [np.ones(r.data.shape[1]) for r in records]
    mean_inv = float(np.mean(np.concatenate([1.0 / v for v in var])))
    return [1.0 / v / mean_inv for v in var]


def _channel_weights(weights, records) -> list[np.ndarray]:
    if weights is None:
        return [np.ones(r.data.shape[1]) for r in records]
    weights = list(weights)
    if len(weights) != len(records):
        raise InputError(f"channel weights needed for {len(records)} record(s), got "
                         f"{len(weights)}")
    out = []
    for k, (w, r) in enumerate(zip(weights, records, strict=True)):
        w = np.asarray(w, dtype=float)
        if w.shape != (r.data.shape[1],) or np.any(w < 0) or not np.all(np.isfinite(w)):
            raise InputError(f"channel weights of record {k} must be {r.data.shape[1]} "
                             "non-negative numbers")
        out.append(w)
    return out


def _factored_loads(dofs, vals, t_idx, shape) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The load matrix ``L`` (rows: time steps; a wheel at step ``t_idx[p]`` loads
    ``dofs[p]`` with ``vals[p]``) as ``A @ R``, fewer non-zeros for the same product.

    The wheels that load the same DOF set (one element, one wheel line) have shape-function
    rows in a space of low dimension (a wheel line crosses a bicubic element along a
    cubic); an SVD of each such group gives ``R``'s rows and ``A``'s coefficients,
    exact to round-off (singular values below ``k ε σ₁`` are dropped: checked).  ``L @ g``
    then costs the non-zeros of ``A`` and ``R`` instead of those of ``L``.
    """
    k = dofs.shape[1]
    L = sp.csr_matrix((vals.ravel(), (np.repeat(t_idx, k), dofs.ravel())), shape=shape)
    if t_idx.size == 0:
        return sp.identity(shape[0], format="csr"), L
    uniq, inv = np.unique(dofs, axis=0, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    bounds = np.searchsorted(inv[order], np.arange(uniq.shape[0] + 1))
    a_r, a_c, a_v, r_r, r_c, r_v = [], [], [], [], [], []
    n_r = 0
    for g in range(uniq.shape[0]):
        sel = order[bounds[g]:bounds[g + 1]]
        u, sv, vt = np.linalg.svd(vals[sel], full_matrices=False)
        r = max(int(np.count_nonzero(sv > k * np.finfo(float).eps * sv[0])), 1)
        a_r.append(np.repeat(t_idx[sel], r))
        a_c.append(np.tile(np.arange(n_r, n_r + r), sel.size))
        a_v.append((u[:, :r] * sv[:r]).ravel())
        r_r.append(np.repeat(np.arange(n_r, n_r + r), k))
        r_c.append(np.tile(uniq[g], r))
        r_v.append(vt[:r].ravel())
        n_r += r
    cat = np.concatenate
    A = sp.csr_matrix((cat(a_v), (cat(a_r), cat(a_c))), shape=(shape[0], n_r))
    R = sp.csr_matrix((cat(r_v), (cat(r_r), cat(r_c))), shape=(n_r, shape[1]))
    scale = max(abs(L).max(), np.finfo(float).tiny)
    if A.nnz + R.nnz >= L.nnz or abs(A @ R - L).max() > 1e-12 * scale:
        return sp.identity(shape[0], format="csr"), L
    return A, R


def _stiffness_units(bridge: Bridge) -> tuple[np.ndarray, np.ndarray] | None:
    """Banded K as a combination of a few constant matrices: the stiffness coefficients
    (set, part, element) that are equal for every parameter value (e.g. the elements of
    one zone) form a group G, and ``K = Σ_G c_G K_G`` with ``K_G`` assembled once.

    Groups are the coefficient entries equal at the start and at two random draws of
    every stiffness parameter; a third draw checks ``Σ_G c_G K_G`` against the assembler
    (relative 1e-12), else None (assemble every trial).  Returns (one entry index per
    group, the stacked ``K_G``).
    """
    model = bridge.model
    p0 = bridge.params
    rng = np.random.default_rng(0)

    def draw():
        return {**p0, **{n: v * rng.uniform(0.5, 2.0, v.shape) for n, v in p0.items()
                         if n in Bridge.STIFFNESS_FAMILIES}}

    def flat(params):
        return np.concatenate([c.ravel() for c in model.stiffness_coefficients(params)])

    samples = np.stack([flat(p0), flat(draw()), flat(draw())], axis=1)
    _, first, inv = np.unique(samples, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    if first.size > 64:
        return None
    shapes = [c.shape for c in model.stiffness_coefficients(p0)]
    units = []
    for g in range(first.size):
        ind = (inv == g).astype(float)
        parts, i = [], 0
        for shp in shapes:
            k = int(np.prod(shp))
            parts.append(ind[i:i + k].reshape(shp))
            i += k
        units.append(model.assembler.stiffness_banded(parts))
    units = np.stack(units)
    check = draw()
    ref = model.assembler.stiffness_banded(model.stiffness_coefficients(check))
    got = np.tensordot(flat(check)[first], units, 1)
    if np.abs(got - ref).max() > 1e-12 * np.abs(ref).max():
        return None
    return first, units


class StaticObjective:
    """Pseudo-static misfit of trial stiffness parameters (see module docstring).

    ``weights`` (one array per record, one weight per channel) weight the squared
    residuals; default 1 (the paper's plain sum).
    """

    def __init__(self, space: ParameterSpace, records: Sequence[Record], vehicle: Vehicle,
                 base: Bridge | None = None, weights=None):
        self.space = space
        self.base = space.start if base is None else base
        self.records = _check_records(records, vehicle)
        self.weights = _channel_weights(weights, self.records)
        model = self.base.model
        self._sensor_rows = []
        self._loads = []
        self._data = []
        self._parts = []
        static_wheels = vehicle.model().static_forces
        self.static_wheels = static_wheels
        for rec in self.records:
            p = rec.passage
            if p.wheels_per_axle * p.n_axles != static_wheels.size:
                raise InputError("the record's wheel layout does not match the vehicle")
            S = self.base.sensor_matrix(rec.sensors)
            x = p.wheel_x(rec.time)
            y = np.broadcast_to(p.wheel_y, x.shape) if self.base.is_plate else None
            on = model.grid.contains(x.ravel(), None if y is None else y.ravel())
            t_idx = np.repeat(np.arange(x.shape[0]), x.shape[1])[on]
            P = np.tile(static_wheels, x.shape[0])[on]
            rows = model.point_rows(x.ravel()[on], None if y is None else y.ravel()[on])
            self._sensor_rows.append(S)
            self._loads.append(_factored_loads(rows.dofs, rows.vals * P[:, None], t_idx,
                                               (x.shape[0], self.base.n_free)))
            self._data.append(rec.data)
            self._parts.append(measurement_points(rec.sensors)[0])
        self.n_parts = max(int(p.max()) for p in self._parts) + 1
        self._params0 = self.base.params
        self._units = _stiffness_units(self.base)

    def _stiffness_banded(self, theta: np.ndarray) -> np.ndarray:
        """Lower-banded K of a trial: ``Σ_G c_G K_G`` over the coefficient groups when
        :func:`_stiffness_units` found them, else the assembler's."""
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (self.space.n,) or not (np.all(np.isfinite(theta))
                                                  and np.all(theta > 0)):
            self.space.bridge(theta, self.base)  # raises the bridge's own InputError
        model = self.base.model
        coefs = model.stiffness_coefficients({**self._params0, **self.space.split(theta)})
        if self._units is None:
            return model.assembler.stiffness_banded(coefs)
        first, units = self._units
        flat = np.concatenate([c.ravel() for c in coefs])[first]
        return (flat @ units.reshape(first.size, -1)).reshape(units.shape[1:])

    def predicted(self, theta: np.ndarray) -> list[np.ndarray]:
        """Static readings of the trial model for each record, each (n_t, n_s)."""
        ab = self._stiffness_banded(theta)
        try:
            c = sla.cholesky_banded(ab, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            raise NumericalError("trial stiffness is not positive definite") from None
        out = []
        for S, (A, R) in zip(self._sensor_rows, self._loads, strict=True):
            g = sla.cho_solve_banded((c, True), S.T, check_finite=False)
            out.append(A @ (R @ g))
        return out

    def parts(self, theta: np.ndarray) -> np.ndarray:
        """Weighted squared misfit of each measurement point, shape (n_parts,)."""
        out = np.zeros(self.n_parts)
        for pred, d, part, w in zip(self.predicted(theta), self._data, self._parts,
                                    self.weights, strict=True):
            r = pred - d
            out += np.bincount(part, weights=w * np.einsum("ts,ts->s", r, r),
                               minlength=self.n_parts)
        return out

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([((p - d) * np.sqrt(w)).ravel() for p, d, w in
                               zip(self.predicted(theta), self._data, self.weights,
                                   strict=True)])

    def jacobian(self, theta: np.ndarray) -> np.ndarray:
        """∂(residuals)/∂θ by the adjoint method, shape (n_residuals, n_params).

        A shared family's value drives all its zones or girders: its column is the sum of
        theirs (chain rule through the broadcast).
        """
        space = self.space
        bridge = space.bridge(theta, self.base)
        blocks = []
        for rec, w in zip(self.records, self.weights, strict=True):
            p = rec.passage
            x = p.wheel_x(rec.time)
            y = np.broadcast_to(p.wheel_y, x.shape) if bridge.is_plate else None
            sens = static_sensitivities(bridge, rec.sensors, x, y,
                                        self.static_wheels[None, :], wrt=space.names)
            weighted = sens.values * np.sqrt(w)[None, :, None]  # rows as in residuals()
            vals = weighted.reshape(-1, sens.values.shape[2])
            names = np.asarray(sens.names)
            cols = [vals[:, names == n].sum(axis=1, keepdims=True) if n in space.shared
                    else vals[:, names == n] for n in space.names]
            blocks.append(np.hstack(cols))
        return np.vstack(blocks)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        return self.parts(theta)


#: Stiffnesses whose modes a :class:`DynamicObjective` remembers for mass-only trials.
MODE_CACHE = 4


class DynamicObjective:
    """Dynamic misfit of trial parameters: the calibration crossings re-simulated
    (channel ``weights`` as in :class:`StaticObjective`).

    Each crossing is re-simulated with its record's :class:`~bwim.records.
    SimulationSettings` (run-up and tail); ``approach`` (m), when given, overrides the
    run-up of every record.  A record without settings runs up
    :data:`~bwim.dynamics.DEFAULT_APPROACH` and is simulated to its end.
    """

    def __init__(self, space: ParameterSpace, records: Sequence[Record], vehicle: Vehicle,
                 road: RoadProfile | None, base: Bridge, *, approach: float | None = None,
                 n_modes: int | None = None, weights=None):
        self.space = space
        self.base = base
        self.records = _check_records(records, vehicle)
        self.weights = _channel_weights(weights, self.records)
        self._prepared = []
        self._parts = []
        for rec in self.records:
            p = rec.passage
            settings = rec.settings
            if settings is None:
                settings = SimulationSettings(approach=DEFAULT_APPROACH,
                                              tail=rec.time_after_exit(base.length))
            prep = prepare_crossing(base, vehicle, speed=p.speed, sensors=rec.sensors,
                                    lane=p.lane if base.is_plate else None, road=road,
                                    sampling_rate=rec.sampling_rate,
                                    approach=settings.approach if approach is None else approach,
                                    tail=settings.tail)
            self._prepared.append(prep)
            self._parts.append(measurement_points(rec.sensors)[0])
        self.n_parts = max(int(p.max()) for p in self._parts) + 1
        if n_modes is None:
            n_modes = select_modes(base, sampling_rate=self.records[0].sampling_rate).n
        self.n_modes = n_modes
        stiff = set(self.space.names) & set(Bridge.STIFFNESS_FAMILIES)
        # K fixed (mass stage): the influence surfaces are computed once
        self._influence = (None if stiff else
                           [base.influence(rec.sensors) for rec in self.records])
        self._modes: list[tuple[np.ndarray, np.ndarray, Modes]] = []

    def modes(self, bridge: Bridge) -> Modes:
        """The trial's ``n_modes`` modes: a recent trial's scaled when only a uniform mass
        factor separates them (see module docstring), else solved (and remembered)."""
        params = bridge.params
        k = np.concatenate([params[n] for n in Bridge.STIFFNESS_FAMILIES if n in params])
        m = np.concatenate([params[n] for n in Bridge.MASS_FAMILIES if n in params])
        for i, (k_ref, m_ref, modes) in enumerate(self._modes):
            if np.array_equal(k, k_ref):
                c = float(m[0] / m_ref[0])
                if np.allclose(m, c * m_ref, rtol=4 * np.finfo(float).eps, atol=0.0):
                    self._modes.insert(0, self._modes.pop(i))
                    return modes if c == 1.0 else scaled_modes(modes, c)
        modes = bridge.modes(self.n_modes)
        self._modes = [(k, m, modes), *self._modes[:MODE_CACHE - 1]]
        return modes

    def predicted(self, theta: np.ndarray) -> list[np.ndarray]:
        bridge = self.space.bridge(theta, self.base)
        modes = self.modes(bridge)
        out = []
        for k, (prep, rec) in enumerate(zip(self._prepared, self.records, strict=True)):
            inf = None if self._influence is None else self._influence[k]
            sim = run_crossing(prep, bridge, modes=modes, influence=inf, warn=False)
            out.append(_on_times(sim, rec.time))
        return out

    def parts(self, theta: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n_parts)
        for pred, rec, part, w in zip(self.predicted(theta), self.records, self._parts,
                                      self.weights, strict=True):
            np.add.at(out, part, w * ((pred - rec.data) ** 2).sum(axis=0))
        return out

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([((p - r.data) * np.sqrt(w)).ravel() for p, r, w in
                               zip(self.predicted(theta), self.records, self.weights,
                                   strict=True)])

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        return self.parts(theta)


def _on_times(sim: Record, times: np.ndarray) -> np.ndarray:
    """Simulated readings at the measured record's times (linear interpolation)."""
    if sim.time.size == times.size and np.allclose(sim.time, times):
        return sim.data
    return np.stack([np.interp(times, sim.time, sim.data[:, c], left=0.0, right=0.0)
                     for c in range(sim.data.shape[1])], axis=1)
