"""Vehicle–bridge interaction: the iterative (paper) and the coupled solvers.

Contract
--------
The vehicle follows :mod:`bwim.vehicles.model`: DOF ``y`` (down), contacts ``Eᵀ y``,
tyres ``K_t``, ``C_t``.  Under contact c the ground moves down by
``g_c = w_c − r_c`` (deck deflection minus road elevation) at the rate
``ġ_c = ∂w/∂t + v ∂w/∂x − ṙ_c``, and the contact force on the deck is

    F = F_static + K_t (Eᵀ y − g) + C_t (Eᵀ ẏ − ġ).

The bridge is either modal (``q̈ + 2ζΩ q̇ + Ω² q = Ψ(t) F``, ``Ψ = Φᵀ L(t)``, ζ from the
bridge's Rayleigh damping) or the full FE system (``M ü + C u̇ + K u = L(t) F``).

* :func:`solve_coupled` advances bridge and vehicles together, one Newmark step of the
  monolithic system at a time (modal: a small dense solve; full: one banded factor and a
  rank-n_c Woodbury correction per step).
* :func:`solve_iterative` is the paper's procedure (docs/theory.md §3): vehicles on a
  rigid deck, the bridge under their forces, the deck deflection added to the profile,
  repeated until the deflection under the wheels changes by less than ``tol``
  (relative).  Its fixed point is the same discrete system, so the two agree to the
  tolerance.
* Both start with the bridge at rest and the vehicles in static equilibrium on the road.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from bwim.dynamics.newmark import Newmark, NewmarkResult, final_state, integrate
from bwim.fe.model import PointRows
from bwim.vehicles.model import VehicleModel

__all__ = [
    "ApproachState",
    "Crossing",
    "FullBridge",
    "ModalBridge",
    "Solution",
    "approach_phase",
    "solve_coupled",
    "solve_iterative",
]


@dataclass(frozen=True, kw_only=True, eq=False)
class Crossing:
    """All contacts of all vehicles on the integration time grid.

    Attributes
    ----------
    vehicle : VehicleModel
        The vehicles combined (block-diagonal), contacts concatenated.
    x : ndarray, shape (n_t, n_c)
        Contact positions along the bridge, m.
    y : ndarray, shape (n_c,)
        Contact positions across, m.
    speed : ndarray, shape (n_c,)
    on : ndarray of bool, shape (n_t, n_c)
        Contact on the deck.
    r, r_dot : ndarray, shape (n_t, n_c)
        Road elevation (m, up) under the contacts and its time derivative.
    """

    vehicle: VehicleModel
    x: np.ndarray
    y: np.ndarray
    speed: np.ndarray
    on: np.ndarray
    r: np.ndarray
    r_dot: np.ndarray

    @property
    def n_t(self) -> int:
        return self.x.shape[0]

    def window(self) -> tuple[int, int]:
        """First and last step with any contact on the deck (inclusive)."""
        any_on = np.flatnonzero(self.on.any(axis=1))
        return int(any_on[0]), int(any_on[-1])


@dataclass(frozen=True, kw_only=True, eq=False)
class Solution:
    """Bridge state, contact forces and deck deflection under the contacts."""

    state: NewmarkResult  # bridge (modal q or full u) over the time grid
    forces: np.ndarray  # (n_t, n_c)
    iterations: int = 1
    change: float = 0.0


# --- vehicles on a given ground ------------------------------------------------------------
def _vehicle_on_ground(veh: VehicleModel, g, g_dot, scheme, y0=None, v0=None, a0=None
                       ) -> NewmarkResult:
    f = (veh.contact @ (veh.tyre_stiffness * g + veh.tyre_damping * g_dot).T).T
    return integrate(veh.mass, veh.damping, veh.stiffness, f, scheme, u0=y0, v0=v0, a0=a0)


def _static_on_ground(veh: VehicleModel, g0) -> np.ndarray:
    return np.linalg.solve(veh.stiffness, veh.contact @ (veh.tyre_stiffness * g0))


def _forces(veh: VehicleModel, ys: NewmarkResult | None, g, g_dot) -> np.ndarray:
    F = veh.static_forces - veh.tyre_stiffness * g - veh.tyre_damping * g_dot
    if veh.n_dof:
        F = F + veh.tyre_stiffness * (ys.u @ veh.contact) + veh.tyre_damping * (ys.v @ veh.contact)
    return F


# --- bridge representations -------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True, eq=False)
class ModalBridge:
    """The bridge in modal coordinates, with contact mode shapes on the time grid.

    ``psi[k, :, c]`` is ``Φᵀ N`` at contact c at step k (zero off the deck) and
    ``psi_x`` the same for ``v ∂N/∂x``.
    """

    omega: np.ndarray
    zeta: np.ndarray
    psi: np.ndarray
    psi_x: np.ndarray

    @property
    def n(self) -> int:
        return self.omega.size

    def matrices(self):
        return np.ones(self.n), 2 * self.zeta * self.omega, self.omega**2

    def forced(self, F: np.ndarray, scheme: Newmark) -> NewmarkResult:
        M, C, K = self.matrices()
        return integrate(M, C, K, np.einsum("kmc,kc->km", self.psi, F), scheme)

    def under(self, st: NewmarkResult) -> tuple[np.ndarray, np.ndarray]:
        w = np.einsum("kmc,km->kc", self.psi, st.u)
        w_dot = np.einsum("kmc,km->kc", self.psi, st.v) + np.einsum("kmc,km->kc", self.psi_x,
                                                                       st.u)
        return w, w_dot


@dataclass(frozen=True, kw_only=True, eq=False)
class FullBridge:
    """The full FE system with contact rows on the time grid (free DOF).

    ``rows`` holds ``dofs``, ``vals``, ``slopes`` of shape (n_t, n_c, k); ``slopes``
    include the speed (``v ∂N/∂x``).
    """

    M: object
    C: object
    K: object
    rows: PointRows

    @property
    def n(self) -> int:
        return self.K.shape[0]

    def effective_factor(self, scheme: Newmark) -> tuple[np.ndarray, bool]:
        """Banded Cholesky factor of the effective stiffness ``K + a1 C + a0 M`` (for
        ``scipy.linalg.cho_solve_banded``)."""
        return _banded_cholesky(scheme.effective(self.M, self.C, self.K).tocsr())

    def _load(self, k: int, F_k: np.ndarray) -> np.ndarray:
        f = np.zeros(self.n)
        np.add.at(f, self.rows.dofs[k], self.rows.vals[k] * F_k[:, None])
        return f

    def forced(self, F: np.ndarray, scheme: Newmark, start: int = 0,
               u0=None, v0=None, a0=None) -> NewmarkResult:
        fac = self.effective_factor(scheme)
        n_t = F.shape[0]
        U = np.zeros((n_t, self.n))
        V = np.zeros_like(U)
        A = np.zeros_like(U)
        u = np.zeros(self.n) if u0 is None else u0
        v = np.zeros(self.n) if v0 is None else v0
        a = (_solve_mass(self.M, self._load(start, F[start]) - self.C @ v - self.K @ u)
             if a0 is None else a0)
        U[start], V[start], A[start] = u, v, a
        for k in range(start + 1, n_t):
            rhs = self._load(k, F[k]) + scheme.history(self.M, self.C, u, v, a)
            u_new = sla.cho_solve_banded(fac, rhs, check_finite=False)
            v, a = scheme.update(u_new, u, v, a)
            u = u_new
            U[k], V[k], A[k] = u, v, a
        return NewmarkResult(u=U, v=V, a=A)

    def under(self, st: NewmarkResult) -> tuple[np.ndarray, np.ndarray]:
        k = np.arange(st.u.shape[0])[:, None, None]
        rows = self.rows
        ud = st.u[k, rows.dofs]
        w = np.einsum("kcj,kcj->kc", rows.vals, ud)
        w_dot = (np.einsum("kcj,kcj->kc", rows.vals, st.v[k, rows.dofs])
                 + np.einsum("kcj,kcj->kc", rows.slopes, ud))
        return w, w_dot


def _solve_mass(M, rhs):
    import scipy.sparse.linalg as spla

    return spla.spsolve(M.tocsc(), rhs)


def _banded_cholesky(A) -> tuple[np.ndarray, bool]:
    coo = A.tocoo()
    low = coo.row >= coo.col
    bw = int((coo.row[low] - coo.col[low]).max())
    ab = np.zeros((bw + 1, A.shape[0]))
    ab[coo.row[low] - coo.col[low], coo.col[low]] = coo.data[low]
    return sla.cholesky_banded(ab, lower=True), True


# --- iterative ------------------------------------------------------------------------------
def solve_iterative(
    crossing: Crossing, bridge: ModalBridge | FullBridge, scheme: Newmark,
    *, tol: float = 1e-6, max_iter: int = 50,
) -> Solution:
    """The paper's iterative VBI procedure (see module docstring)."""
    veh = crossing.vehicle
    w = np.zeros_like(crossing.r)
    w_dot = np.zeros_like(crossing.r)
    change = np.inf
    it = 0
    state = None
    F = None
    # before the first contact reaches the deck the deflection under the contacts is 0 in
    # every iteration: the vehicles' approach is integrated once
    pre = approach_phase(crossing, scheme) if veh.n_dof else None

    def vehicle(g, g_dot):
        if pre is None or pre.start == 0:
            return _vehicle_on_ground(veh, g, g_dot, scheme, y0=_static_on_ground(veh, g[0]))
        s = pre.start
        rest = _vehicle_on_ground(veh, g[s:], g_dot[s:], scheme, y0=pre.Y[s], v0=pre.YV[s],
                                  a0=pre.YA[s])
        return NewmarkResult(u=np.concatenate([pre.Y[:s], rest.u]),
                             v=np.concatenate([pre.YV[:s], rest.v]),
                             a=np.concatenate([pre.YA[:s], rest.a]))

    for it in range(1, max_iter + 1):  # noqa: B007 - reported below
        g, g_dot = w - crossing.r, w_dot - crossing.r_dot
        ys = vehicle(g, g_dot) if veh.n_dof else None
        F = _forces(veh, ys, g, g_dot)
        state = bridge.forced(np.where(crossing.on, F, 0.0), scheme)
        w_new, w_dot_new = bridge.under(state)
        scale = max(np.abs(w_new).max(), np.finfo(float).tiny)
        change = float(np.abs(w_new - w).max() / scale)
        w, w_dot = w_new, w_dot_new
        if change < tol or veh.n_dof == 0:
            break
    # forces consistent with the final deflection
    g, g_dot = w - crossing.r, w_dot - crossing.r_dot
    ys = vehicle(g, g_dot) if veh.n_dof else None
    F = _forces(veh, ys, g, g_dot)
    return Solution(state=state, forces=F, iterations=it, change=0.0 if veh.n_dof == 0
                    else change)


# --- coupled ---------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True, eq=False)
class ApproachState:
    """Vehicle states on the road before the first wheel reaches the deck.

    ``Y``, ``YV``, ``YA`` hold the steps ``first … start``; the earlier steps were not
    asked for (their rows are dropped from the record) and are not computed.
    """

    start: int  # last step before any contact is on the deck
    Y: np.ndarray  # (start + 1 − first, n_v) displacements
    YV: np.ndarray
    YA: np.ndarray
    first: int = 0  # first step held


def approach_phase(crossing: Crossing, scheme: Newmark, *, first: int = 0) -> ApproachState:
    """Integrate the vehicles on the road up to the step before the deck is reached.

    Independent of the bridge, so a calibration computes it once for all trials.  Only the
    steps from ``first`` on are returned (``first`` is clamped to the last step before the
    deck, whose state starts the coupled solver); the state there comes from
    :func:`bwim.dynamics.newmark.final_state`, without stepping through the approach.
    """
    veh = crossing.vehicle
    k_in, _ = crossing.window()
    start = max(k_in - 1, 0)
    first = min(max(int(first), 0), start)
    g0, g0_dot = -crossing.r[: start + 1], -crossing.r_dot[: start + 1]
    if not veh.n_dof:
        z = np.zeros((start + 1 - first, 0))
        return ApproachState(start=start, Y=z, YV=z, YA=z, first=first)
    y0 = _static_on_ground(veh, g0[0])
    if first == 0:
        pre = _vehicle_on_ground(veh, g0, g0_dot, scheme, y0=y0)
        return ApproachState(start=start, Y=pre.u, YV=pre.v, YA=pre.a)
    f = (veh.contact @ (veh.tyre_stiffness * g0[:first + 1]
                        + veh.tyre_damping * g0_dot[:first + 1]).T).T
    s = final_state(veh.mass, veh.damping, veh.stiffness, f, scheme, u0=y0)
    pre = _vehicle_on_ground(veh, g0[first:], g0_dot[first:], scheme, y0=s.u, v0=s.v,
                             a0=s.a)
    return ApproachState(start=start, Y=pre.u, YV=pre.v, YA=pre.a, first=first)


def solve_coupled(crossing: Crossing, bridge: ModalBridge | FullBridge, scheme: Newmark,
                  *, approach: ApproachState | None = None) -> Solution:
    """Bridge and vehicles advanced together, step by step (see module docstring).

    ``approach`` may pass the precomputed :func:`approach_phase` of this crossing; the
    forces (and vehicle states) of the steps before its ``first`` are not computed: NaN.
    """
    veh = crossing.vehicle
    _, k_out = crossing.window()
    n_t = crossing.n_t
    pre = approach_phase(crossing, scheme) if approach is None else approach
    start, first = pre.start, pre.first
    Y = np.zeros((n_t, veh.n_dof))
    YV = np.zeros_like(Y)
    YA = np.zeros_like(Y)
    Y[first: start + 1], YV[first: start + 1], YA[first: start + 1] = pre.Y, pre.YV, pre.YA
    y_state = (Y[start].copy(), YV[start].copy(), YA[start].copy())
    stepper = _modal_steps if isinstance(bridge, ModalBridge) else _full_steps
    state, F = stepper(crossing, bridge, scheme, (first, start), k_out, y_state,
                       (Y, YV, YA))
    return Solution(state=state, forces=F)


def _finish(crossing, bridge, scheme, k_out, state, vstate, F, veh):
    """After the last contact leaves: bridge in free vibration, vehicles on the road."""
    n_t = crossing.n_t
    if k_out + 1 >= n_t:
        return
    Y, YV, YA = vstate
    sl = slice(k_out, n_t)
    u0, v0, a0 = state.u[k_out], state.v[k_out], state.a[k_out]
    if isinstance(bridge, ModalBridge):
        M, C, K = bridge.matrices()
        tail = integrate(M, C, K, np.zeros((n_t - k_out, bridge.n)), scheme,
                         u0=u0, v0=v0, a0=a0)
        state.u[sl], state.v[sl], state.a[sl] = tail.u, tail.v, tail.a
    else:
        tail = bridge.forced(np.zeros((n_t, crossing.r.shape[1])), scheme, start=k_out,
                             u0=u0, v0=v0, a0=a0)
        state.u[sl], state.v[sl], state.a[sl] = tail.u[sl], tail.v[sl], tail.a[sl]
    g, g_dot = -crossing.r[sl], -crossing.r_dot[sl]
    ys = None
    if veh.n_dof:
        ys = _vehicle_on_ground(veh, g, g_dot, scheme, y0=Y[k_out], v0=YV[k_out], a0=YA[k_out])
        Y[sl], YV[sl], YA[sl] = ys.u, ys.v, ys.a
    F[sl] = _forces(veh, ys, g, g_dot)


def _modal_steps(crossing, bridge: ModalBridge, scheme, span, k_out, y_state, vstate):
    first, start = span
    Y, YV, YA = vstate
    veh = crossing.vehicle
    n_t, n_m, n_v = crossing.n_t, bridge.n, veh.n_dof
    n = n_m + n_v
    kt, ct, E = veh.tyre_stiffness, veh.tyre_damping, veh.contact
    Mb, Cb, Kb = bridge.matrices()
    U = np.zeros((n_t, n_m))
    V = np.zeros_like(U)
    A = np.zeros_like(U)
    F = np.zeros((n_t, kt.size))
    y, yv, ya = y_state
    z = np.concatenate([np.zeros(n_m), y])
    zv = np.concatenate([np.zeros(n_m), yv])
    za = np.concatenate([np.zeros(n_m), ya])
    _approach_forces(crossing, veh, Y, YV, start, first, F)
    # the coupled system of the window: constant parts (bridge modes; vehicles without
    # their tyres) plus the tyres between the contact displacements δ = Lᵀ z,
    # L = [−Ψ; E] (rank n_c): C_k = C₀ + L c_t Lᵀ, K_k = K₀ + L (k_t Lᵀ + c_t Lxᵀ)
    win = slice(start + 1, k_out + 1)
    P, Px = bridge.psi[win], bridge.psi_x[win]  # (n_w, n_m, n_c)
    r, rd = crossing.r[win], crossing.r_dot[win]
    n_w, n_c = P.shape[0], kt.size
    M0, C0, K0 = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    idx = np.arange(n_m)
    M0[idx, idx], C0[idx, idx], K0[idx, idx] = Mb, Cb, Kb
    M0[n_m:, n_m:] = veh.mass
    C0[n_m:, n_m:] = veh.damping - (E * ct) @ E.T
    K0[n_m:, n_m:] = veh.stiffness - (E * kt) @ E.T
    Lt = np.empty((n_w, n_c, n))  # Lᵀ per step
    np.negative(P.transpose(0, 2, 1), out=Lt[:, :, :n_m])
    Lt[:, :, n_m:] = E.T
    Wt = np.zeros_like(Lt)  # k_t Lᵀ + c_t Lxᵀ, Lx = [−Ψx; 0]
    np.negative(Px.transpose(0, 2, 1), out=Wt[:, :, :n_m])
    Wt *= ct[:, None]
    Wt += kt[:, None] * Lt
    f = np.zeros((n_w, n))
    f[:, :n_m] = (P @ (veh.static_forces + kt * r + ct * rd)[:, :, None])[:, :, 0]
    if n_v:
        f[:, n_m:] = -(kt * r + ct * rd) @ E.T
    S = _stepped(scheme, M0, C0, K0, Lt, ct, Wt, f, np.concatenate([z, zv, za]))
    Z, ZV, ZA = S[:, :n], S[:, n:2 * n], S[:, 2 * n:]
    U[win], V[win], A[win] = Z[:, :n_m], ZV[:, :n_m], ZA[:, :n_m]
    q, qv = Z[:, :n_m], ZV[:, :n_m]
    delta = -np.einsum("wmc,wm->wc", P, q) + r
    delta_dot = (-np.einsum("wmc,wm->wc", P, qv) - np.einsum("wmc,wm->wc", Px, q) + rd)
    if n_v:
        Y[win], YV[win], YA[win] = Z[:, n_m:], ZV[:, n_m:], ZA[:, n_m:]
        delta += Z[:, n_m:] @ E
        delta_dot += ZV[:, n_m:] @ E
    F[win] = veh.static_forces + kt * delta + ct * delta_dot
    state = NewmarkResult(u=U, v=V, a=A)
    _finish(crossing, bridge, scheme, k_out, state, vstate, F, veh)
    return state, F


#: Steps whose step matrices are built at once by :func:`_stepped` (bounds its memory).
STEP_CHUNK = 64


def _stepped(scheme: Newmark, M, C0, K0, Lt, c, Wt, f, s0) -> np.ndarray:
    """Newmark steps of ``M ü + C_i u̇ + K_i u = f_i`` with ``C_i = C₀ + L_i c L_iᵀ`` and
    ``K_i = K₀ + L_i Wᵀ_i`` (``Lt``, ``Wt``: ``L_iᵀ``, ``Wᵀ_i`` of shape (n_w, r, n),
    ``c`` of shape (r,)) from the state ``s0 = [u; v; a]``; returns the states after each
    step, shape (n_w, 3 n).

    The effective stiffness is ``D + L_i Hᵀ_i`` with the constant ``D = K₀ + a1 C₀ + a0 M``
    and ``Hᵀ_i = Wᵀ_i + a1 c L_iᵀ``: its inverse is the Sherman–Morrison–Woodbury update
    ``D⁻¹ − D⁻¹L_i (I + Hᵀ_i D⁻¹ L_i)⁻¹ Hᵀ_i D⁻¹`` (one r × r inverse per step).
    The step ``s_{i+1} = T_i s_i + b_i`` (the same algebra as :func:`integrate`'s step
    operator: ``u_new = K_eff⁻¹ (f + M(a0 u + a2 v + a3 a) + C(a1 u + a4 v + a5 a))``, then
    ``a_new = a0 (u_new − u) − a2 v − a3 a`` and ``v_new = v + dt ((1 − γ) a + γ a_new)``)
    is built for a chunk of steps with batched products, so that the loop over time is
    one small matrix product per step.  With ``G_i = K_eff⁻¹ [a0 M + a1 C_i | a2 M + a4 C_i
    | a3 M + a5 C_i | f_i]`` the rows of ``T_i`` are ``G_i``, ``dt γ (a0 G_i + A) + V``
    and ``a0 G_i + A`` with constant ``A``, ``V``.  ``G_i`` is built from
    ``K_eff⁻¹ M`` and ``K_eff⁻¹ C_i = K_eff⁻¹ C₀ + (K_eff⁻¹ L_i) c L_iᵀ`` (products with
    the constant M, C₀ are one matrix product per chunk)."""
    n_w, n = f.shape
    r = Lt.shape[1]
    g, dt = scheme.gamma, scheme.dt
    a0, a1, a2, a3, a4, a5 = (scheme.a0, scheme.a1, scheme.a2, scheme.a3, scheme.a4,
                              scheme.a5)
    m = 3 * n + 1
    d_inv = np.linalg.inv(scheme.effective(M, C0, K0))
    # augmented state [s; 1]: the constant term rides in T's last column, one product
    # per step; A and V are diagonal blocks, added on their diagonals only
    i = np.arange(n)
    diag_a = ((i, i, -a0), (i, n + i, -a2), (i, 2 * n + i, -a3))
    diag_v = ((i, n + i, 1.0), (i, 2 * n + i, dt * (1 - g)))
    out = np.empty((n_w + 1, m))
    out[0, :-1], out[:, -1] = s0, 1.0
    chunk = max(min(STEP_CHUNK, n_w), 1)
    T = np.empty((chunk, m, m))
    T[:, -1, :-1], T[:, -1, -1] = 0.0, 1.0
    blocks = ((a0, a1), (a2, a4), (a3, a5))
    for lo in range(0, n_w, chunk):
        hi = min(lo + chunk, n_w)
        Lti, Wti, Tw = Lt[lo:hi], Wt[lo:hi], T[:hi - lo]
        Li = np.ascontiguousarray(Lti.transpose(0, 2, 1))
        Hti = Wti + (a1 * c)[:, None] * Lti
        Yi = d_inv @ Li
        X = Hti @ Yi  # I + Hᵀ D⁻¹ L; then K_eff⁻¹ L = D⁻¹ L X⁻¹
        X[:, np.arange(r), np.arange(r)] += 1.0
        KL = Yi @ np.linalg.inv(X)
        kinv = d_inv - KL @ (Hti @ d_inv)
        flat = kinv.reshape(-1, n)
        KM = (flat @ M).reshape(kinv.shape)
        KC = (flat @ C0).reshape(kinv.shape)  # K_eff⁻¹ C_i = K_eff⁻¹ C₀ + (K_eff⁻¹ L) c Lᵀ
        KC += KL @ (c[:, None] * Lti)
        G, Ta, Tv = Tw[:, :n], Tw[:, 2 * n:3 * n], Tw[:, n:2 * n]
        for j, (cm, cc) in enumerate(blocks):
            blk = G[:, :, j * n:(j + 1) * n]
            np.multiply(cm, KM, out=blk)
            if cc:
                blk += cc * KC
        np.matmul(kinv, f[lo:hi, :, None], out=G[:, :, -1:])
        np.multiply(a0, G, out=Ta)
        for rr, cc, val in diag_a:
            Ta[:, rr, cc] += val
        np.multiply(dt * g, Ta, out=Tv)
        for rr, cc, val in diag_v:
            Tv[:, rr, cc] += val
        rows = list(out[lo:hi + 1])  # views: the loop is one gemv per step
        for t_i, s_i, s_next in zip(Tw, rows, rows[1:], strict=False):
            np.dot(t_i, s_i, out=s_next)
    return out[1:, :-1]


def _approach_forces(crossing, veh, Y, YV, start, first, F):
    """Contact forces on the road before the deck, from step ``first`` (NaN before)."""
    sl = slice(first, start + 1)
    ys = NewmarkResult(u=Y[sl], v=YV[sl], a=YV[sl]) if veh.n_dof else None
    F[:first] = np.nan
    F[sl] = _forces(veh, ys, -crossing.r[sl], -crossing.r_dot[sl])


def _full_steps(crossing, bridge: FullBridge, scheme, span, k_out, y_state, vstate):
    first, start = span
    Y, YV, YA = vstate
    veh = crossing.vehicle
    n_t, n_b, n_v = crossing.n_t, bridge.n, veh.n_dof
    kt, ct, E = veh.tyre_stiffness, veh.tyre_damping, veh.contact
    n_c = kt.size
    fac = bridge.effective_factor(scheme)
    at = kt + scheme.a1 * ct
    if n_v:
        kv_eff = scheme.effective(veh.mass, veh.damping, veh.stiffness)
        kv_inv_E = np.linalg.solve(kv_eff, E)
        X = np.eye(n_c) - at[:, None] * (E.T @ kv_inv_E)
    U = np.zeros((n_t, n_b))
    V = np.zeros_like(U)
    A = np.zeros_like(U)
    F = np.zeros((n_t, n_c))
    u, uv, ua = np.zeros(n_b), np.zeros(n_b), np.zeros(n_b)
    y, yv, ya = y_state
    _approach_forces(crossing, veh, Y, YV, start, first, F)
    for k in range(start + 1, k_out + 1):
        dofs, vals, slopes = bridge.rows.dofs[k], bridge.rows.vals[k], bridge.rows.slopes[k]
        r, rd = crossing.r[k], crossing.r_dot[k]
        cu_b = scheme.damping_history(u, uv, ua)
        Lt_cu = np.einsum("cj,cj->c", vals, cu_b[dofs])
        hist_b = scheme.history(bridge.M, bridge.C, u, uv, ua)
        if n_v:
            cu_y = scheme.damping_history(y, yv, ya)
            coupling_b = ct * (Lt_cu - cu_y @ E)
            rv = (scheme.history(veh.mass, veh.damping, y, yv, ya) - E @ (ct * Lt_cu)
                  - E @ (kt * r + ct * rd))
        else:
            coupling_b = ct * Lt_cu
        rb = hist_b + _scatter(n_b, dofs, vals, veh.static_forces + kt * r + ct * rd
                               + coupling_b)
        if n_v:  # eliminate the vehicles: rb' = rb + L At Eᵀ Kv⁻¹ rv
            rb = rb + _scatter(n_b, dofs, vals, at * (kv_inv_E.T @ rv))
        s = sla.cho_solve_banded(fac, rb, check_finite=False)
        on = crossing.on[k]
        if n_v and np.any(on):
            Lmat = np.zeros((n_b, n_c))
            for c in np.flatnonzero(on):
                np.add.at(Lmat[:, c], dofs[c], vals[c])
            Z = sla.cho_solve_banded(fac, Lmat, check_finite=False)  # Kb⁻¹ L
            LtZ = np.einsum("cj,cjd->cd", vals, Z[dofs])
            LxtZ = np.einsum("cj,cjd->cd", slopes, Z[dofs])
            WZ = at[:, None] * LtZ + ct[:, None] * LxtZ
            Ws = at * np.einsum("cj,cj->c", vals, s[dofs]) + ct * np.einsum(
                "cj,cj->c", slopes, s[dofs])
            corr = np.linalg.solve(np.eye(n_c) + WZ @ X, Ws)
            u_new = s - Z @ (X @ corr)
        else:
            u_new = s
        uv, ua = scheme.update(u_new, u, uv, ua)
        u = u_new
        U[k], V[k], A[k] = u, uv, ua
        w_c = np.einsum("cj,cj->c", vals, u[dofs])
        w_c_dot = np.einsum("cj,cj->c", vals, uv[dofs]) + np.einsum("cj,cj->c", slopes, u[dofs])
        if n_v:
            Wu = at * w_c + ct * np.einsum("cj,cj->c", slopes, u[dofs])
            y_new = np.linalg.solve(kv_eff, rv + E @ Wu)
            yv, ya = scheme.update(y_new, y, yv, ya)
            y = y_new
            Y[k], YV[k], YA[k] = y, yv, ya
            delta = y @ E - w_c + r
            delta_dot = yv @ E - w_c_dot + rd
        else:
            delta = -w_c + r
            delta_dot = -w_c_dot + rd
        F[k] = veh.static_forces + kt * delta + ct * delta_dot
    state = NewmarkResult(u=U, v=V, a=A)
    _finish(crossing, bridge, scheme, k_out, state, vstate, F, veh)
    return state, F


def _scatter(n, dofs, vals, coef):
    f = np.zeros(n)
    np.add.at(f, dofs, vals * coef[:, None])
    return f
