"""``simulate``: vehicles crossing a bridge over a road, recorded by sensors.

Contract
--------
* Vehicle–bridge interaction as in docs/theory.md §3, integrated with Newmark-β (average
  acceleration, §2.3) at the sampling rate.  Time 0 is the instant the first axle of the
  first vehicle reaches x = 0; each vehicle starts ``approach`` metres (its first axle)
  before the bridge in static equilibrium on the road and the record ends ``tail``
  seconds after the last axle leaves.  The record holds t ≥ 0 only (before that the
  bridge is at rest).
* The bridge is modal by default: all modes up to ``max_frequency`` (default
  sampling_rate / 8) or ``n_modes`` of them, damped with the bridge's Rayleigh damping.
  ``full_system=True`` integrates the full FE system instead.
* Modal readings carry a static correction by default (mode-acceleration method,
  docs/theory.md §8): the quasi-static response of the truncated modes,
  ``Σ_c F_c (g_s(x_c) − S Φ Ω⁻² Φᵀ N_c)`` with ``g_s`` the sensors' influence surfaces,
  so strains under the wheels converge like the static solution rather than like the
  modal series.
* Several vehicles: pass sequences for ``vehicle``, ``speed``, ``lane`` and ``delay``
  (record time at which each first axle reaches x = 0).
* Defaults: :data:`DEFAULT_APPROACH` (100 m) of run-up and :data:`DEFAULT_SAMPLING_RATE`
  (1 kHz), kept here only.  The record carries the crossing's
  :class:`~bwim.records.SimulationSettings` (approach, tail) for later re-simulation.
* Positions follow :meth:`bwim.records.Passage.axle_x`; the modal truncation is
  :func:`bwim.fe.select_modes`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import StrEnum
from functools import cached_property

import numpy as np

from bwim.dynamics.newmark import Newmark
from bwim.dynamics.vbi import (
    Crossing,
    FullBridge,
    ModalBridge,
    approach_phase,
    solve_coupled,
    solve_iterative,
)
from bwim.errors import InputError, parse_enum, require_positive
from bwim.fe.bridge import Bridge, RayleighDamping
from bwim.fe.influence import InfluenceSurfaces
from bwim.fe.modal import Modes, check_sampling_rate, select_modes
from bwim.limits import check_memory
from bwim.records import Passage, Record, SimulationSettings, Truth, VBIConvergence
from bwim.road import RoadProfile
from bwim.sensors import Sensor
from bwim.vehicles.model import VehicleModel
from bwim.vehicles.types import Vehicle

__all__ = ["DEFAULT_APPROACH", "DEFAULT_SAMPLING_RATE", "PreparedCrossing", "VBIMethod",
           "prepare_crossing", "run_crossing", "simulate"]

#: Default run-up before the bridge, m (the vehicle's dynamic state on entry).
DEFAULT_APPROACH = 100.0

#: Default sampling rate, Hz (also the integration rate).
DEFAULT_SAMPLING_RATE = 1000.0

#: Fewest samples while an axle crosses the bridge (a coarser time grid is refused).
MIN_SAMPLES_ON_BRIDGE = 4


class VBIMethod(StrEnum):
    """How vehicle and bridge are solved together."""

    COUPLED = "coupled"
    ITERATIVE = "iterative"


def _as_list(name, value, n):
    if isinstance(value, (list, tuple, np.ndarray)):
        vals = list(value)
        if len(vals) != n:
            raise InputError(f"{name} needs one value per vehicle ({n}), got {len(vals)}")
        return vals
    return [value] * n


def _combine(models: list[VehicleModel]) -> VehicleModel:
    n_v = sum(m.n_dof for m in models)
    M = np.zeros((n_v, n_v))
    C = np.zeros_like(M)
    K = np.zeros_like(M)
    E = np.zeros((n_v, sum(m.n_contacts for m in models)))
    i = j = 0
    for m in models:
        a, b = m.n_dof, m.n_contacts
        M[i:i + a, i:i + a], C[i:i + a, i:i + a], K[i:i + a, i:i + a] = (
            m.mass, m.damping, m.stiffness)
        E[i:i + a, j:j + b] = m.contact
        i, j = i + a, j + b
    cat = np.concatenate
    return VehicleModel(
        mass=M, damping=C, stiffness=K, contact=E,
        tyre_stiffness=cat([m.tyre_stiffness for m in models]),
        tyre_damping=cat([m.tyre_damping for m in models]),
        static_forces=cat([m.static_forces for m in models]),
        contact_offset=cat([m.contact_offset for m in models]),
        contact_lateral=cat([m.contact_lateral for m in models]),
        contact_axle=cat([m.contact_axle for m in models]),
        axle_offsets=cat([m.axle_offsets for m in models]),
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class PreparedCrossing:
    """Everything about a crossing that does not depend on the bridge's parameters.

    Made by :func:`prepare_crossing` for one bridge *structure* (mesh, supports, zones,
    girders); :func:`run_crossing` then simulates it on any bridge that shares that
    structure (``bridge.model``), e.g. every trial of a calibration.  The vehicles' run-up
    on the approach, which no bridge parameter changes, is integrated once and reused.
    """

    structure: object
    crossing: Crossing
    time: np.ndarray
    keep: np.ndarray
    rows: object
    sensors: tuple[Sensor, ...]
    S: np.ndarray
    models: tuple[VehicleModel, ...]
    passages: tuple[Passage, ...]
    scheme: Newmark
    settings: SimulationSettings

    @cached_property
    def approach_state(self):
        """Vehicle states before the first wheel reaches the deck (coupled solver)."""
        # the states before the first kept step are not needed
        return approach_phase(self.crossing, self.scheme, first=int(np.argmax(self.keep)))

    @cached_property
    def _on_deck(self) -> dict:
        """Memo of the influence surfaces at the on-deck contacts, keyed by the
        :class:`InfluenceSurfaces` object (one entry: a calibration of the mass passes the
        same surfaces to every trial)."""
        return {}

    def influence_on_deck(self, inf: InfluenceSurfaces) -> np.ndarray:
        """``inf`` at every on-deck contact (the steps and contacts of ``crossing.on``
        in C order), shape (n_on, n_sensors); the last surfaces' values are kept."""
        last = self._on_deck.get("last")  # one (surfaces, values) pair, replaced whole
        if last is not None and last[0] is inf:
            return last[1]
        c = self.crossing
        yy = np.broadcast_to(c.y, c.x.shape)[c.on] if self.structure.is_plate else None
        g = inf.at(c.x[c.on], yy)
        self._on_deck["last"] = (inf, g)
        return g


def prepare_crossing(
    bridge: Bridge,
    vehicle: Vehicle | Sequence[Vehicle],
    *,
    speed,
    sensors: Sequence[Sensor],
    lane=None,
    road: RoadProfile | None = None,
    sampling_rate: float = DEFAULT_SAMPLING_RATE,
    approach: float = DEFAULT_APPROACH,
    tail: float = 0.0,
    delay=0.0,
) -> PreparedCrossing:
    """Validate a crossing and precompute its kinematics (see :func:`simulate`)."""
    if not isinstance(bridge, Bridge):
        raise InputError(f"bridge must be a bwim.Bridge, got {type(bridge).__name__}")
    if sensors is None or isinstance(sensors, (str, bytes)):
        raise InputError(f"sensors must be a sequence of bwim.Sensor, got {sensors!r}")
    fs = require_positive("sampling_rate", sampling_rate)
    settings = SimulationSettings(approach=approach, tail=tail)  # validates both
    approach, tail = settings.approach, settings.tail
    vehicles = list(vehicle) if isinstance(vehicle, (list, tuple)) else [vehicle]
    n_veh = len(vehicles)
    speeds = [require_positive("speed", v) for v in _as_list("speed", speed, n_veh)]
    if lane is None:
        if bridge.is_plate:
            raise InputError("lane (vehicle centre line, m from the right-hand edge) is "
                             "required on a plate bridge")
        lane = 0.0
    lanes = [float(v) for v in _as_list("lane", lane, n_veh)]
    delays = np.array(_as_list("delay", delay, n_veh), dtype=float)
    if np.any(delays < 0) or not np.all(np.isfinite(delays)):
        raise InputError(f"delay must be >= 0 s, got {delays.tolist()}")
    delays = delays - delays.min()
    _check_crossing_memory(bridge, vehicles, speeds, fs, approach, tail, delays, sensors)
    sensors = tuple(sensors)
    road = RoadProfile.flat() if road is None else road
    if not isinstance(road, RoadProfile):
        raise InputError(f"road must be a bwim.RoadProfile, got {type(road).__name__}")
    S = bridge.sensor_matrix(sensors)

    models = [v.model() for v in vehicles]
    passages = [v.passage(speed=s, lane=ln, delay=d)
                for v, s, ln, d in zip(vehicles, speeds, lanes, delays, strict=True)]
    veh = _combine(models)
    c_vehicle = np.repeat(np.arange(n_veh), [m.n_contacts for m in models])
    c_speed = np.array(speeds)[c_vehicle]
    c_y = np.array(lanes)[c_vehicle] + veh.contact_lateral
    if bridge.is_plate:
        off = (c_y < 0) | (c_y > bridge.width)
        if np.any(off):
            c = int(np.flatnonzero(off)[0])
            raise InputError(
                f"vehicle {c_vehicle[c]} wheel at y = {c_y[c]:g} m is off the deck (width "
                f"{bridge.width:g} m) for lane {lanes[c_vehicle[c]]:g} m"
            )

    # --- time grid ------------------------------------------------------------------
    dt = 1.0 / fs
    t_start = min(d - approach / v for d, v in zip(delays, speeds, strict=True))
    t_end = max(p.axle_times_on(bridge.length)[-1, 1] for p in passages) + tail
    k0 = int(np.floor(t_start / dt + 1e-9))
    k1 = int(np.ceil(t_end / dt - 1e-9))
    t = dt * np.arange(k0, k1 + 1)
    x = np.hstack([p.axle_x(t)[:, m.contact_axle] for p, m in zip(passages, models,
                                                                  strict=True)])
    lo, hi = float(x.min()), float(x.max())
    if not road.covers(lo, hi):
        raise InputError(
            f"road profile covers x = {road.extent[0]:g} … {road.extent[1]:g} m but the "
            f"crossing needs {lo:g} … {hi:g} m (approach + bridge + vehicle length); "
            "generate a longer profile or a shorter approach"
        )
    r = road.at(x, veh.contact_lateral)
    r_dot = np.gradient(r, dt, axis=0) if r.shape[0] > 1 else np.zeros_like(r)
    on = (x >= 0.0) & (x <= bridge.length)
    if not on.any():
        raise InputError("no wheel reaches the bridge")
    crossing = Crossing(vehicle=veh, x=x, y=c_y, speed=c_speed, on=on, r=r, r_dot=r_dot)
    return PreparedCrossing(
        structure=bridge.model, crossing=crossing, time=t, keep=t >= -1e-9 * dt,
        rows=_contact_rows(bridge, x, c_y, on), sensors=sensors, S=S, models=tuple(models),
        passages=tuple(passages), scheme=Newmark(dt),
        settings=settings,
    )


def run_crossing(
    prepared: PreparedCrossing,
    bridge: Bridge,
    *,
    method: VBIMethod | str = VBIMethod.COUPLED,
    n_modes: int | None = None,
    max_frequency: float | None = None,
    full_system: bool = False,
    static_correction: bool = True,
    tol: float = 1e-6,
    max_iter: int = 50,
    influence: InfluenceSurfaces | None = None,
    warn: bool = True,
    modes: Modes | None = None,
) -> Record:
    """Simulate a prepared crossing on ``bridge`` (same structure, any parameters).

    ``influence`` may pass the sensors' influence surfaces of this bridge's stiffness to
    save their computation (calibration of the mass keeps K fixed).  ``modes`` may pass
    this bridge's modes when they are known without solving (e.g.
    :func:`bwim.fe.modal.scaled_modes` of another trial with the same K); they replace the
    truncation of ``n_modes`` / ``max_frequency`` and are checked against the sampling
    rate.
    """
    method = parse_enum(VBIMethod, method, "method")
    if bridge.model is not prepared.structure:
        raise InputError("this crossing was prepared for a bridge of another structure")
    crossing, rows, scheme = prepared.crossing, prepared.rows, prepared.scheme
    c_speed = crossing.speed
    fs = 1.0 / scheme.dt
    if full_system:
        moving = replace(rows, slopes=rows.slopes * c_speed[None, :, None])  # v ∂N/∂x
        rep = FullBridge(M=bridge.mass_matrix(), C=bridge.damping_matrix(),
                         K=bridge.stiffness_matrix(), rows=moving)
        modes = None
    else:
        if modes is None:
            modes = select_modes(bridge, n_modes=n_modes, max_frequency=max_frequency,
                                 sampling_rate=fs)
            rayleigh = bridge.rayleigh
        else:
            if not isinstance(modes, Modes) or modes.shapes.shape[0] != bridge.n_free:
                raise InputError("modes must be a bwim.fe.modal.Modes of this bridge")
            check_sampling_rate(modes, fs)
            rayleigh = (RayleighDamping.fit(bridge.damping_ratio, *modes.omega[:2])
                        if modes.n >= 2 else bridge.rayleigh)
        psi, psi_x = _contact_modes(rows, crossing.on, modes.shapes, c_speed)
        rep = ModalBridge(omega=modes.omega, zeta=rayleigh.ratio(modes.omega),
                          psi=psi, psi_x=psi_x)

    veh = crossing.vehicle
    if method is VBIMethod.COUPLED:
        sol = solve_coupled(crossing, rep, scheme, approach=prepared.approach_state)
        conv = VBIConvergence(method=method.value)
    else:
        sol = solve_iterative(crossing, rep, scheme, tol=tol, max_iter=max_iter)
        converged = sol.change < tol or veh.n_dof == 0
        conv = VBIConvergence(method=method.value, iterations=sol.iterations,
                              change=sol.change, converged=converged)
        if not converged and warn:
            warnings.warn(f"iterative VBI did not converge in {max_iter} iterations "
                          f"(change {sol.change:.2e})", RuntimeWarning, stacklevel=2)

    # --- readings -------------------------------------------------------------------
    keep, t = prepared.keep, prepared.time
    F = sol.forces
    if full_system:
        data = sol.state.u @ prepared.S.T
    else:
        s_modal = prepared.S @ modes.shapes  # (n_s, n_m)
        data = sol.state.u @ s_modal.T
        if static_correction:
            inf = bridge.influence(prepared.sensors) if influence is None else influence
            data += _static_correction(prepared.influence_on_deck(inf), crossing.on, F, psi,
                                       s_modal, modes)
    time = t[keep] - t[keep][0] if abs(t[keep][0]) < 1e-9 else t[keep]
    truths = []
    j = 0
    for v_idx, m in enumerate(prepared.models):
        wf = F[keep, j:j + m.n_contacts]
        j += m.n_contacts
        axle = np.zeros((wf.shape[0], m.n_axles))
        for c in range(m.n_contacts):
            axle[:, m.contact_axle[c]] += wf[:, c]
        lost = (wf < 0).any(axis=0)
        if lost.any() and warn:
            warnings.warn(f"vehicle {v_idx}: wheel(s) {np.flatnonzero(lost).tolist()} lost "
                          "contact with the road (negative contact force)", RuntimeWarning,
                          stacklevel=2)
        truths.append(Truth(wheel_forces=wf, axle_forces=axle,
                            static_wheel_loads=m.static_forces.copy(),
                            static_axle_loads=m.static_axle_loads, contact_lost=lost))
    return Record(time=time, data=data[keep], sensors=prepared.sensors,
                  passages=prepared.passages, truths=tuple(truths), convergence=conv,
                  settings=prepared.settings)


def simulate(
    bridge: Bridge,
    vehicle: Vehicle | Sequence[Vehicle],
    *,
    speed,
    sensors: Sequence[Sensor],
    lane=None,
    road: RoadProfile | None = None,
    sampling_rate: float = DEFAULT_SAMPLING_RATE,
    method: VBIMethod | str = VBIMethod.COUPLED,
    approach: float = DEFAULT_APPROACH,
    tail: float = 0.0,
    delay=0.0,
    n_modes: int | None = None,
    max_frequency: float | None = None,
    full_system: bool = False,
    static_correction: bool = True,
    tol: float = 1e-6,
    max_iter: int = 50,
) -> Record:
    """Simulate vehicles crossing ``bridge`` and record ``sensors``.

    Parameters
    ----------
    bridge : Bridge
    vehicle : vehicle or sequence of vehicles
        Any of :mod:`bwim.vehicles` (``MovingForces``, ``SprungMass``, ``HalfCar``,
        ``Truck3D``, ``TractorSemitrailer``).
    speed : float or sequence
        m/s, each > 0.
    sensors : sequence of Sensor
    lane : float or sequence, optional
        Vehicle centre line, m from the right-hand edge (required on a plate; ignored on a
        beam).
    road : RoadProfile, optional
        Default flat.  Must cover every wheel from the start of the approach to the end.
    sampling_rate : float
        Hz; also the integration rate.
    method : "coupled" or "iterative"
    approach : float
        Run-up before the bridge, m (0: enter at rest in static equilibrium).
    tail : float
        Free vibration recorded after the last axle leaves, s.
    delay : float or sequence
        Record time at which each vehicle's first axle reaches x = 0, s.
    n_modes, max_frequency : optional
        Modal truncation (see :func:`select_modes`).
    full_system : bool
        Integrate the full FE system instead of modes.
    static_correction : bool
        Add the truncated modes' quasi-static response to modal readings.
    tol, max_iter
        Convergence of the iterative method (relative change of the deck deflection
        under the wheels).

    Returns
    -------
    Record
        Readings at t ≥ 0, passages, truths (wheel and axle forces), convergence and the
        simulation settings (approach, tail).
    """
    method = parse_enum(VBIMethod, method, "method")
    prepared = prepare_crossing(bridge, vehicle, speed=speed, sensors=sensors, lane=lane,
                                road=road, sampling_rate=sampling_rate, approach=approach,
                                tail=tail, delay=delay)
    return run_crossing(prepared, bridge, method=method, n_modes=n_modes,
                        max_frequency=max_frequency, full_system=full_system,
                        static_correction=static_correction, tol=tol, max_iter=max_iter)


def _contact_rows(bridge: Bridge, x, y, on):
    """Shape-function rows of every contact at every step (zeros off the deck)."""
    from bwim.fe.model import PointRows

    n_t, n_c = x.shape
    k = 16 if bridge.is_plate else 4
    dofs = np.zeros((n_t, n_c, k), dtype=np.int64)
    vals = np.zeros((n_t, n_c, k))
    slopes = np.zeros((n_t, n_c, k))
    if on.any():
        steps = np.flatnonzero(on.any(axis=1))
        win = slice(steps[0], steps[-1] + 1)  # the on-deck window: the rest stays zero
        on_w = on[win]
        yy = np.broadcast_to(y, on_w.shape)[on_w] if bridge.is_plate else None
        rows = bridge.model.point_rows(x[win][on_w], yy, slopes=True)
        dofs[win][on_w], vals[win][on_w], slopes[win][on_w] = rows.dofs, rows.vals, rows.slopes
    return PointRows(dofs=dofs, vals=vals, slopes=slopes)


def _contact_modes(rows, on, phi, c_speed):
    """``psi[k, :, c] = Φᵀ N`` and ``psi_x`` (with the speed) at every step, gathered only
    where the contact is on the deck (zeros elsewhere), on the steps of the on-deck
    window (zeros before and after).  The on-deck rows ``N`` (values, then slopes) are one
    sparse matrix: ``Φᵀ N`` of all of them is one sparse–dense product."""
    import scipy.sparse as sp

    n_t, n_c = on.shape
    n_m = phi.shape[1]
    psi = np.zeros((n_t, n_m, n_c))
    psi_x = np.zeros((n_t, n_m, n_c))
    if on.any():
        steps = np.flatnonzero(on.any(axis=1))
        win = slice(steps[0], steps[-1] + 1)
        on_w = on[win]
        k = rows.dofs.shape[-1]
        sel = np.flatnonzero(on_w.ravel())  # the on-deck (step, contact) pairs, C order
        n_on = sel.size
        dofs = np.take(rows.dofs[win].reshape(-1, k), sel, axis=0).ravel()
        ptr = np.arange(0, n_on * k + 1, k)
        k_on, c_on = np.divmod(sel, n_c)
        pw, pxw = psi[win], psi_x[win]
        for dst, src in ((pw, rows.vals), (pxw, rows.slopes)):
            data = np.take(src[win].reshape(-1, k), sel, axis=0).ravel()
            dst[k_on, :, c_on] = sp.csr_matrix((data, dofs, ptr),
                                               shape=(n_on, phi.shape[0])) @ phi
        pxw[k_on, :, c_on] *= c_speed[c_on][:, None]
    return psi, psi_x


def _static_correction(g, on, F, psi, s_modal, modes):
    """Quasi-static response of the truncated modes (mode-acceleration correction), built
    from the steps with the contact on the deck only (the force is zero elsewhere); ``g``
    is the influence surfaces at the on-deck contacts, (n_on, n_s)."""
    out = np.zeros((on.shape[0], s_modal.shape[0]))
    if not on.any():
        return out
    k_on, c_on = np.nonzero(on)
    modal_static = psi[k_on, :, c_on] @ (s_modal / modes.omega**2).T
    term = F[k_on, c_on][:, None] * (g - modal_static)
    for c in range(on.shape[1]):  # each step once per contact: contacts added in order
        sel = c_on == c
        out[k_on[sel]] += term[sel]
    return out


def _check_crossing_memory(bridge, vehicles, speeds, fs, approach, tail, delays, sensors):
    """Refuse a time grid too coarse for the bridge, or one whose (samples × (sensors +
    modes + vehicle DOF)) would exceed the memory limit, before it is built
    (``speed = 1e-6``, ``tail = 1e6``...)."""
    per_crossing = fs * bridge.length / max(speeds)
    if per_crossing < MIN_SAMPLES_ON_BRIDGE:
        raise InputError(
            f"sampling_rate = {fs:g} Hz gives {per_crossing:.3g} samples while an axle "
            f"crosses the {bridge.length:g} m bridge at {max(speeds):g} m/s; at least "
            f"{MIN_SAMPLES_ON_BRIDGE} are needed")
    longest = max(float(getattr(v, "length", 0.0) or 0.0) for v in vehicles)
    span = approach + bridge.length + longest
    n_t = fs * (span / min(speeds) + tail + float(np.max(delays)))
    n_channels = len(tuple(sensors)) + 64 + 16 * len(vehicles)
    check_memory(n_t * n_channels * 8.0 * 4,
                 f"a crossing of {n_t:.3g} time steps (approach {approach:g} m, tail "
                 f"{tail:g} s, sampling rate {fs:g} Hz)")
