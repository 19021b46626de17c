"""The discrete state-space model of a bridge under moving forces (docs/theory.md §4).

Contract
--------
* Modal coordinates ``q`` (n_m mass-normalised modes), ``z = [q; q̇]``,
  ``ż = A z + B(t) f`` with ``A = [[0, I], [−Ω², −2ζΩ]]``, ``B(t) = [[0], [G(t)]]`` and
  ``G(t) = Φᵀ L(t)`` for the n_f unknown forces at their positions at time t.
* First-order hold of the moving load (derivation below): exact when the modal load
  ``u(t) = G(t) f(t)`` varies linearly over a step, O(Δt²) otherwise; the load is where the
  wheels are at both ends of the step, not held at its start.
* The forces join the state, ``X_k = [w_k; f_k]`` (``w_k`` the held modal state, below),
  and the unknowns are ``r_k``: first order ``f_{k+1} = f_k + Δt r_k`` (González, Rowley &
  OBrien 2008) or zeroth order ``f_{k+1} = r_k`` (Law & Fang).  ``X_{k+1} = H_k X_k + T r_k``
  with ``H_k = [[P, Γ_k], [0, I or 0]]`` as in docs/theory.md §4.
* Readings ``d_k = Q_k X_k`` with ``Q_k = [S Φ, 0, D_k]``; ``D_k`` holds the static
  correction (the truncated modes' quasi-static strain per unit force at the force
  positions, ``g_s(x) − S Φ Ω⁻² Φᵀ N(x)``, docs/theory.md §1.5; zero when disabled) plus
  the hold's feed-through ``S Φ Λ₁ G_k`` (below).
* The initial state is ``X_0 = [z0 f_0; f_0]`` (:attr:`MFIModel.x0_map`): the bridge at
  rest, ``z_0 = 0``.
* Everything is held in scaled units (strain / s_d, force / s_f, r Δt / s_f, modal
  coordinates by their static response to s_f), so that λ is a well-conditioned number;
  :attr:`MFIModel.lam_physical` converts it back.

Discretisation (first-order hold)
---------------------------------
docs/theory.md §4 discretises with a zero-order hold, ``z_{k+1} = P z_k + Γ_k f_k`` with
``Γ_k = A⁻¹(P − I) B(t_k)``: the load stays where it was at ``t_k`` for the whole step.  The
wheels have moved on by ``v Δt`` at ``t_{k+1}``, so the modelled response lags the load by
Δt/2 (slow modes) to Δt (modes with ω Δt ≫ 1), while the static correction ``D_k f_k`` is
read at ``t_k``; the identified weights shift towards the first axle in proportion to the
distance travelled per step.  Here ``u(t) = G(t) f(t)`` is instead taken linear over each
step, between ``u_k = G(t_k) f_k`` and ``u_{k+1} = G(t_{k+1}) f_{k+1}``.  Variation of
constants over ``[t_k, t_{k+1}]`` then gives exactly ::

    z_{k+1} = P z_k + Λ₀ u_k + Λ₁ u_{k+1},   P = e^{AΔt},
    Λ₀ = ∫₀^Δt e^{A(Δt−τ)} (1 − τ/Δt) dτ [0; I],   Λ₁ = ∫₀^Δt e^{A(Δt−τ)} (τ/Δt) dτ [0; I].

``u_{k+1}`` contains ``f_{k+1}``, which the recursion has not chosen yet.  The held state
``w_k = z_k − Λ₁ u_k`` removes it::

    w_{k+1} = z_{k+1} − Λ₁ u_{k+1} = P (w_k + Λ₁ u_k) + Λ₀ u_k = P w_k + Γ_k f_k,
    Γ_k = (P Λ₁ + Λ₀) G(t_k),

the transition of docs/theory.md §4 with another ``Γ_k``.  The readings at ``t_k`` follow
from ``q_k``, the first half of ``z_k = w_k + Λ₁ G(t_k) f_k``::

    d_k = S Φ q_k + D_k^s f_k = [S Φ, 0] w_k + (D_k^s + S Φ Λ₁^q G(t_k)) f_k,

(``D_k^s`` the static correction, ``Λ₁^q`` the displacement half of Λ₁) so ``Q_k`` keeps
its form with ``D_k = D_k^s + S Φ Λ₁^q G(t_k)``, and ``z_0 = 0`` becomes
``w_0 = −Λ₁ G(t_0) f_0``.  Both the modal part and the static correction see the
load at the reading instant, which keeps a model with few modes (most of the strain in
the correction) consistent.  ``Λ₀ + Λ₁`` is the zero-order hold's ``A⁻¹(P − I)[0; I]``;
per mode, ``expm(Δt [[A_m, e₂, 0], [0, 0, 1/Δt], [0, 0, 0]])`` (4 × 4) holds ``P_m`` in
its first two columns, ``Λ₀ + Λ₁`` in the third and ``Λ₁`` in the fourth (the response to
a unit step and to the ramp τ/Δt of the input).  In the quasi-static limit the held
model reproduces ``S Φ Ω⁻² G(t_k) f`` at every ``t_k`` (the lag is gone), as the
simulation's trapezoidal Newmark scheme does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from functools import cached_property

import numpy as np
import scipy.linalg as sla

from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.fe.modal import Modes
from bwim.records import Passage, Record

__all__ = ["ForceUnknowns", "MFIModel", "Order", "build_model"]


class Order(StrEnum):
    """Tikhonov regularisation order."""

    FIRST = "first"  # penalise the force rate (smooth histories)
    ZEROTH = "zeroth"  # penalise the force itself


class ForceUnknowns(StrEnum):
    """What the unknown forces are."""

    AUTO = "auto"  # wheels when the sensors resolve the transverse position, else axles
    WHEEL = "wheel"
    AXLE = "axle"


@dataclass(frozen=True, kw_only=True, eq=False)
class MFIModel:
    """The scaled discrete model of one record (see module docstring).

    Attributes
    ----------
    P : ndarray (2 n_m, 2 n_m)
    gamma : ndarray (N, 2 n_m, n_f)
    Qz : ndarray (n_s, 2 n_m)
    D : ndarray (N, n_s, n_f)
    order : Order
    dt : float
    d_scale, f_scale : float
        Strain and force scales.
    on : ndarray of bool (N, n_f)
        Whether each force is on the deck at each step.
    z0 : ndarray (2 n_m, n_f) or None
        The initial modal state per unit initial force, ``w_0 = z0 f_0`` (None: zero).
    """

    P: np.ndarray
    gamma: np.ndarray
    Qz: np.ndarray
    D: np.ndarray
    order: Order
    dt: float
    d_scale: float
    f_scale: float
    on: np.ndarray
    z0: np.ndarray | None = None

    @property
    def n_steps(self) -> int:
        return self.gamma.shape[0]

    @property
    def n_z(self) -> int:
        return self.P.shape[0]

    @property
    def n_f(self) -> int:
        return self.gamma.shape[2]

    @property
    def n_x(self) -> int:
        return self.n_z + self.n_f

    @property
    def n_s(self) -> int:
        return self.Qz.shape[0]

    @property
    def t_coef(self) -> float:
        """T = [[0], [t_coef I]] in scaled units (1 for both orders by the choice of s_r)."""
        return 1.0

    @property
    def f_carry(self) -> float:
        """H's lower-right block: I (first order) or 0 (zeroth order)."""
        return 1.0 if self.order is Order.FIRST else 0.0

    @cached_property
    def H_all(self) -> np.ndarray:
        """All transition matrices ``H_k``, shape (N, n_x, n_x) (built once)."""
        nz, nf = self.n_z, self.n_f
        H = np.zeros((self.n_steps, nz + nf, nz + nf))
        H[:, :nz, :nz] = self.P
        H[:, :nz, nz:] = self.gamma
        H[:, nz:, nz:] = self.f_carry * np.eye(nf)
        return H

    @property
    def x0_map(self) -> np.ndarray:
        """``E`` with ``X_0 = E f_0``, shape (n_x, n_f): ``[z0; I]``."""
        top = np.zeros((self.n_z, self.n_f)) if self.z0 is None else self.z0
        return np.vstack([top, np.eye(self.n_f)])

    def H(self, k: int) -> np.ndarray:
        return self.H_all[k]

    def Q(self, k: int) -> np.ndarray:
        return np.hstack([self.Qz, self.D[k]])

    def qwq(self, weights: np.ndarray) -> np.ndarray:
        """``Q_kᵀ W Q_k`` for every step, shape (N, n_x, n_x)."""
        nz = self.n_z
        out = np.empty((self.n_steps, self.n_x, self.n_x))
        WQz = weights[:, None] * self.Qz
        out[:, :nz, :nz] = self.Qz.T @ WQz
        cross = np.einsum("sz,ksf->kzf", WQz, self.D)
        out[:, :nz, nz:] = cross
        out[:, nz:, :nz] = cross.transpose(0, 2, 1)
        out[:, nz:, nz:] = np.einsum("ksf,s,ksg->kfg", self.D, weights, self.D)
        return out

    def qwd(self, weights: np.ndarray, d: np.ndarray) -> np.ndarray:
        """``Q_kᵀ W d_k`` for every step, shape (N, n_x)."""
        wd = weights * d
        return np.concatenate([wd @ self.Qz, np.einsum("ksf,ks->kf", self.D, wd)], axis=1)

    def lam_physical(self, lam_scaled: float) -> float:
        """λ for strains in m/m and force rates in N/s (first order) or forces in N."""
        unit = self.f_scale / self.dt if self.order is Order.FIRST else self.f_scale
        return lam_scaled * (self.d_scale / unit) ** 2

    def lam_scaled(self, lam_physical: float) -> float:
        return lam_physical / self.lam_physical(1.0)


def _mode_blocks(omega: np.ndarray, zeta: np.ndarray, dt: float):
    """Per mode: ``P_m = e^{A_m Δt}`` (2 × 2) and the first-order-hold input vectors
    ``h0_m = ∫₀^Δt e^{A_m(Δt−τ)} (1 − τ/Δt) dτ e₂`` and ``h1_m = ∫₀^Δt e^{A_m(Δt−τ)} (τ/Δt)
    dτ e₂`` (2,) each, from one 4 × 4 exponential per mode (module docstring)."""
    n = omega.size
    P = np.zeros((n, 2, 2))
    h0 = np.zeros((n, 2))
    h1 = np.zeros((n, 2))
    for m in range(n):
        aug = np.zeros((4, 4))
        aug[0, 1] = 1.0
        aug[1, 0] = -omega[m] ** 2
        aug[1, 2] = 1.0
        aug[1, 1] = -2 * zeta[m] * omega[m]
        aug[2, 3] = 1.0 / dt
        E = sla.expm(aug * dt)
        # E[:2, 2] = ∫₀^Δt e^{A s} ds e₂ (zero-order hold), E[:2, 3] = ∫₀^Δt e^{A(Δt−τ)} τ/Δt dτ e₂
        P[m], h1[m] = E[:2, :2], E[:2, 3]
        h0[m] = E[:2, 2] - h1[m]
    return P, h0, h1


def _rows_times(rows, shapes: np.ndarray) -> np.ndarray:
    """``N Φ`` for point rows ``N`` (p points, k entries each) as one sparse product,
    shape (p, n_m)."""
    import scipy.sparse as sp

    p, k = rows.vals.shape
    mat = sp.csr_matrix((rows.vals.ravel(), rows.dofs.ravel(), np.arange(0, p * k + 1, k)),
                        shape=(p, shapes.shape[0]))
    return np.asarray(mat @ shapes)


def force_layout(passages: Sequence[Passage], unknowns: ForceUnknowns):
    """Force positions: per force (n_f) its passage index, axle index and lateral list.

    Returns ``(passage_of, axle_of, ys_of)`` where ``ys_of[f]`` lists the wheel y
    positions sharing force f equally (one wheel, or both wheels of an axle).
    """
    passage_of, axle_of, ys_of = [], [], []
    for j, p in enumerate(passages):
        wy = p.wheel_y.reshape(p.n_axles, p.wheels_per_axle)
        for a in range(p.n_axles):
            if unknowns is ForceUnknowns.WHEEL:
                for y in wy[a]:
                    passage_of.append(j)
                    axle_of.append(a)
                    ys_of.append([float(y)])
            else:
                passage_of.append(j)
                axle_of.append(a)
                ys_of.append([float(y) for y in wy[a]])
    return np.array(passage_of, dtype=int), np.array(axle_of, dtype=int), ys_of


def build_model(
    bridge: Bridge,
    modes: Modes,
    record: Record,
    d_scale: float,
    *,
    unknowns: ForceUnknowns,
    order: Order,
    static_correction: bool = True,
) -> MFIModel:
    """The scaled discrete model of a record (its sensors, time axis and passages)."""
    sensors, passages, time = record.sensors, record.passages, record.time
    dt = 1.0 / record.sampling_rate
    n_t = time.size
    S = bridge.sensor_matrix(sensors)
    s_phi = S @ modes.shapes  # (n_s, n_m)
    zeta = bridge.rayleigh.ratio(modes.omega)
    passage_of, axle_of, ys_of = force_layout(passages, unknowns)
    n_f = axle_of.size
    n_m = modes.n
    # G(t_k): modal force per unit force f (each force shared by its wheels)
    G = np.zeros((n_t, n_m, n_f))
    Dphys = np.zeros((n_t, s_phi.shape[0], n_f))
    on = np.zeros((n_t, n_f), dtype=bool)
    inf = bridge.influence(sensors) if static_correction else None
    for f in range(n_f):
        x = passages[passage_of[f]].axle_x(time)[:, axle_of[f]]
        inside = (x >= 0.0) & (x <= bridge.length)
        on[:, f] = inside
        if not inside.any():
            continue
        share = 1.0 / len(ys_of[f])
        for y in ys_of[f]:
            yy = np.full(inside.sum(), y) if bridge.is_plate else None
            rows = bridge.model.point_rows(x[inside], yy)
            g = _rows_times(rows, modes.shapes) * share
            G[inside, :, f] += g
            if inf is not None:
                Dphys[inside, :, f] += share * inf.at(x[inside], yy) - g @ (
                    s_phi / modes.omega**2).T
    # scales: the force that gives the peak strain, modal coordinates by their static share
    static_per_force = np.matmul(s_phi / modes.omega**2, G) + Dphys
    peak = np.abs(static_per_force).max()
    if peak == 0.0:
        raise InputError("no force crosses the bridge during the record")
    f_scale = d_scale / peak
    q_scale = f_scale * np.abs(G).max(axis=(0, 2)) / modes.omega**2
    q_scale = np.where(q_scale > 0, q_scale, f_scale / modes.omega**2)
    z_scale = np.concatenate([q_scale, q_scale * modes.omega])  # [q; q̇] ordered per block
    Pm, h0, h1 = _mode_blocks(modes.omega, zeta, dt)
    nz = 2 * n_m
    P = np.zeros((nz, nz))
    idx_q, idx_v = np.arange(n_m), n_m + np.arange(n_m)
    P[idx_q, idx_q], P[idx_q, idx_v] = Pm[:, 0, 0], Pm[:, 0, 1]
    P[idx_v, idx_q], P[idx_v, idx_v] = Pm[:, 1, 0], Pm[:, 1, 1]
    # first-order hold (module docstring): w_{k+1} = P w_k + (P Λ₁ + Λ₀) G_k f_k,
    # d_k = S Φ (w_k + Λ₁ G_k f_k) + D_k f_k, w_0 = −Λ₁ G_0 f_0 (z_0 = 0)
    hg = np.einsum("mij,mj->mi", Pm, h1) + h0  # per mode P_m h1_m + h0_m
    gamma = np.concatenate([hg[:, 0][None, :, None] * G, hg[:, 1][None, :, None] * G], axis=1)
    lam1 = np.concatenate([h1[:, 0][None, :, None] * G, h1[:, 1][None, :, None] * G],
                          axis=1)  # Λ₁ G_k, (N, 2 n_m, n_f)
    Dphys += np.matmul(s_phi, lam1[:, :n_m])
    # scaling: X = Dx X̃ with Dx = diag(z_scale, f_scale)
    P_s = P * z_scale[None, :] / z_scale[:, None]
    gamma_s = gamma * f_scale / z_scale[None, :, None]
    z0_s = -lam1[0] * f_scale / z_scale[:, None]
    Qz = np.hstack([s_phi, np.zeros_like(s_phi)]) * z_scale[None, :] / d_scale
    D = Dphys * f_scale / d_scale
    return MFIModel(P=P_s, gamma=gamma_s, Qz=Qz, D=D, order=order, dt=dt, d_scale=d_scale,
                    f_scale=f_scale, on=on, z0=z0_s)
