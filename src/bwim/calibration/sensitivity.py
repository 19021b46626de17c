"""What the sensors can see: the conditioning of the calibration's sensitivity matrix.

Contract
--------
:func:`identifiability` (docs/theory.md §10) stacks the relative sensitivities
``p ∂ε/∂p / ‖d‖`` of the static readings of the calibration crossings to every stiffness
parameter (adjoint sensitivities, docs/theory.md §1.5) and reports their singular values
and condition number, the norm of each parameter's column, and the parameters the
sensors cannot see: a column norm below ``threshold`` × the largest, or a large share in a
singular direction whose singular value is below ``threshold`` × the largest.

:func:`road_sensitivity` says how much the road assumption matters: for each alternative
road (e.g. flat, or a measured profile with its error) the change of the calibrated
parameters had the dynamic misfit been computed on that road instead.  By default each
alternative is re-fitted (the joint least-squares refinement from the calibrated values
on that road: a least-squares fit with a finite-difference Jacobian on each).
``linear=True`` takes one Gauss–Newton step instead,
``Δθ = −(JᵀJ)⁻¹ Jᵀ [r(θ; road′) − r(θ; road)]`` with ``J`` by forward differences
(``n_params + 1 + n_alternatives`` re-simulations): cheaper, but only as good as the
misfit is quadratic over the change of road, which for road changes of millimetres it is
not; the two are compared by ``tests/validation/test_mismatch.py`` and
``benchmarks/bench_mismatch.py``.  Shifts are relative (fractions of the calibrated
value).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bwim.calibration.problem import DynamicObjective, ParameterSpace
from bwim.calibration.stages import Method, run_stage
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.fe.influence import static_sensitivities
from bwim.records import Record
from bwim.road import RoadProfile
from bwim.vehicles import Vehicle

__all__ = ["Identifiability", "RoadSensitivity", "identifiability", "road_sensitivity"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Identifiability:
    """Identifiability of the stiffness parameters from the calibration records."""

    labels: tuple[str, ...]
    column_norms: np.ndarray
    singular_values: np.ndarray
    condition: float
    unseen: tuple[str, ...]

    def summary(self) -> str:
        lines = [f"condition number {self.condition:.3g} ({len(self.labels)} stiffness "
                 "parameters)"]
        if self.unseen:
            lines.append("the sensors cannot see: " + ", ".join(self.unseen))
        else:
            lines.append("every stiffness parameter is seen by the sensors")
        return "\n".join(lines)


def identifiability(
    bridge: Bridge, records: Sequence[Record], vehicle: Vehicle, *,
    names: Sequence[str] | None = None, threshold: float = 1e-3,
) -> Identifiability:
    """The identifiability report (see module docstring)."""
    present = [n for n in bridge.STIFFNESS_FAMILIES if n in bridge.params]
    names = tuple(present if names is None else [n for n in names if n in present])
    static = vehicle.model().static_forces
    scale = np.concatenate([bridge.params[n] for n in names])
    blocks, norm2, labels = [], 0.0, ()
    for rec in records:
        p = rec.passage
        x = p.wheel_x(rec.time)
        y = np.broadcast_to(p.wheel_y, x.shape) if bridge.is_plate else None
        sens = static_sensitivities(bridge, rec.sensors, x, y, static[None, :], wrt=names)
        blocks.append(sens.values.reshape(-1, sens.values.shape[2]))
        norm2 += float(np.sum(rec.data**2))
        labels = tuple(f"{n}[{i}]" for n, i in zip(sens.names, sens.index, strict=True))
    J = np.vstack(blocks) * scale[None, :] / np.sqrt(max(norm2, 1e-300))
    cols = np.linalg.norm(J, axis=0)
    _, sv, vt = np.linalg.svd(J, full_matrices=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    weak = set(np.flatnonzero(cols < threshold * cols.max()))
    for k in np.flatnonzero(sv < threshold * sv[0]):
        weak |= set(np.flatnonzero(np.abs(vt[k]) > 0.5))
    return Identifiability(labels=labels, column_norms=cols, singular_values=sv,
                           condition=cond, unseen=tuple(labels[i] for i in sorted(weak)))


@dataclass(frozen=True, kw_only=True, eq=False)
class RoadSensitivity:
    """First-order change of the calibrated parameters with the road assumed.

    Attributes
    ----------
    labels : tuple of str
        The parameters (``"E_x[0]"``…).
    values : ndarray, shape (n_params,)
        The calibrated values the shifts are relative to.
    shifts : dict of str to ndarray
        For each alternative road, by name: the relative change of each parameter.
    linear : bool
        One Gauss–Newton step (True) or a re-fit (False).
    """

    labels: tuple[str, ...]
    values: np.ndarray
    shifts: dict
    linear: bool = False

    def summary(self) -> str:
        how = "first-order (one Gauss–Newton step)" if self.linear else "re-fitted"
        lines = [f"road assumption: change of the calibrated parameters on each other road, "
                 f"% ({how})"]
        for name, d in self.shifts.items():
            lines.append(f"  {name}: " + ", ".join(
                f"{lab} {v * 100:+.2f}" for lab, v in zip(self.labels, d, strict=True)))
        return "\n".join(lines)


def road_sensitivity(
    bridge: Bridge, records: Sequence[Record], vehicle: Vehicle, road: RoadProfile | None,
    alternatives: Mapping[str, RoadProfile | None], *,
    unknowns: Sequence[str] = ("E_x", "E_y", "mu"), approach: float | None = None,
    n_modes: int | None = None, weights=None, step: float = 1e-3, linear: bool = False,
) -> RoadSensitivity:
    """How much the calibrated ``bridge`` depends on the road (see module docstring).

    Parameters
    ----------
    bridge : Bridge
        The calibrated model (e.g. :attr:`Calibration.bridge`).
    records, vehicle, road, approach, n_modes, weights
        As given to :func:`~bwim.calibration.calibrate` (``weights`` as arrays or None).
    alternatives : mapping of name to RoadProfile or None
        The other roads (None: flat).
    unknowns : sequence of str
        The calibrated parameter families.
    step : float
        Relative finite-difference step of the Jacobian (``linear=True``).
    linear : bool
        One Gauss–Newton step instead of a re-fit (cheaper, first order only).
    """
    if not alternatives:
        raise InputError("alternatives must name at least one other road")
    if not 0 < step < 0.1:
        raise InputError(f"step must be a small relative step in (0, 0.1), got {step!r}")
    records = [records] if isinstance(records, Record) else list(records)
    space = ParameterSpace(bridge, tuple(u for u in unknowns if u in bridge.params))
    theta = space.vector()

    def objective(rd):
        return DynamicObjective(space, records, vehicle, rd, bridge, approach=approach,
                                n_modes=n_modes, weights=weights)

    if not linear:
        shifts = {str(name): run_stage(Method.LM, objective(alt), space).x / theta - 1.0
                  for name, alt in alternatives.items()}
        return RoadSensitivity(labels=tuple(space.labels()), values=theta, shifts=shifts)
    base = objective(road)
    r0 = base.residuals(theta)
    J = np.empty((r0.size, theta.size))
    for i in range(theta.size):
        t = theta.copy()
        t[i] *= 1 + step
        J[:, i] = (base.residuals(t) - r0) / (theta[i] * step)
    Js = J * theta[None, :]  # per relative change
    shifts = {}
    for name, alt in alternatives.items():
        dr = objective(alt).residuals(theta) - r0
        d, *_ = np.linalg.lstsq(Js, -dr, rcond=None)
        shifts[str(name)] = d
    return RoadSensitivity(labels=tuple(space.labels()), values=theta, shifts=shifts,
                           linear=True)
