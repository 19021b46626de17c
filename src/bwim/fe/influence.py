"""Static influence surfaces by reciprocity, and parameter sensitivities.

Contract
--------
* For a sensor row ``s`` (``reading = s u``), ``g = K⁻¹ sᵀ`` is the sensor's influence
  surface in nodal form: a unit downward load at ``(x, y)`` gives the reading
  ``g · N(x, y)ᵀ`` (docs/theory.md §1.5).  One banded solve per **sensor**, not per load
  position.
* :meth:`InfluenceSurfaces.at` evaluates ordinates (reading per newton) at any points;
  points off the deck give zero (a wheel not yet on the bridge).
  :meth:`InfluenceSurfaces.response` sums wheel loads for many load cases at once.
* :func:`static_sensitivities` gives ``∂(reading)/∂p = −gᵀ (∂K/∂p) u`` for the stiffness
  parameters ``E_x``, ``E_y`` (per zone) and ``E_girder`` (per girder), element by element,
  for many load cases.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bwim.errors import InputError
from bwim.sensors import Sensor

if TYPE_CHECKING:
    from bwim.fe.bridge import Bridge

__all__ = ["InfluenceSurfaces", "Sensitivities", "influence_surfaces", "static_sensitivities"]


@dataclass(frozen=True, eq=False, kw_only=True)
class InfluenceSurfaces:
    """Influence surfaces of a set of sensors on one bridge.

    Attributes
    ----------
    sensors : tuple of Sensor
    g : ndarray, shape (n_free, n_sensors)
        ``K⁻¹ Sᵀ``: reading of sensor j under nodal load vector f is ``f @ g[:, j]``.
    """

    bridge: Bridge
    sensors: tuple[Sensor, ...]
    g: np.ndarray

    def at(self, x: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """Ordinates (reading per newton, downward) at points, shape (n_points, n_sensors).

        Points off the deck (before entry, after exit) give 0.
        """
        x = np.atleast_1d(np.asarray(x, dtype=float))
        model = self.bridge.model
        if model.is_plate:
            if y is None:
                raise InputError("influence surfaces of a plate need y")
            y = np.broadcast_to(np.asarray(y, dtype=float), x.shape)
        on = model.grid.contains(x, y)
        out = np.zeros((x.size, self.g.shape[1]))
        if np.any(on):
            rows = model.point_rows(x[on], None if y is None else y[on])
            out[on] = rows.interpolate(self.g)
        return out

    def response(self, x: np.ndarray, y: np.ndarray | None, P: np.ndarray) -> np.ndarray:
        """Static readings for many load cases.

        Parameters
        ----------
        x, y, P : array_like, shape (n_cases, n_loads)
            Load positions (m) and forces (N, down); broadcastable to a common shape.

        Returns
        -------
        ndarray, shape (n_cases, n_sensors)
        """
        y_arr = None if y is None else np.asarray(y, dtype=float)
        shape = np.broadcast_shapes(np.shape(x), np.shape(P), () if y is None else y_arr.shape)
        if len(shape) != 2:
            raise InputError("x, y, P must broadcast to (n_cases, n_loads)")
        xb = np.broadcast_to(x, shape).ravel()
        yb = None if y is None else np.broadcast_to(y_arr, shape).ravel()
        ordin = self.at(xb, yb).reshape(*shape, -1)
        return np.einsum("cl,cls->cs", np.broadcast_to(P, shape), ordin)


def influence_surfaces(bridge: Bridge, sensors: Sequence[Sensor]) -> InfluenceSurfaces:
    """Influence surfaces of ``sensors`` on ``bridge``: one banded solve per sensor."""
    S = bridge.sensor_matrix(sensors)
    return InfluenceSurfaces(bridge=bridge, sensors=tuple(sensors), g=bridge.solve(S.T))


@dataclass(frozen=True, eq=False, kw_only=True)
class Sensitivities:
    """Derivatives of static readings with respect to stiffness parameters.

    Attributes
    ----------
    values : ndarray, shape (n_cases, n_sensors, n_params)
        ``∂ reading / ∂ p`` (reading units per Pa).
    names : tuple of str
        Parameter family of each column (``"E_x"``, ``"E_y"``, ``"E_girder"``).
    index : ndarray of int, shape (n_params,)
        Zone (or girder) index of each column.
    """

    values: np.ndarray
    names: tuple[str, ...]
    index: np.ndarray


def static_sensitivities(
    bridge: Bridge,
    sensors: Sequence[Sensor],
    x: np.ndarray,
    y: np.ndarray | None,
    P: np.ndarray,
    wrt: Sequence[str] | None = None,
    *,
    chunk: int = 256,
) -> Sensitivities:
    """Sensitivities of static readings to the stiffness parameters (docs/theory.md §1.5).

    Parameters
    ----------
    bridge : Bridge
    sensors : sequence of Sensor
    x, y, P : array_like, shape (n_cases, n_loads)
        Load cases as in :meth:`InfluenceSurfaces.response`.
    wrt : sequence of str, optional
        Parameter families; default all stiffness families of the bridge.

    Returns
    -------
    Sensitivities
    """
    model = bridge.model
    present = [n for n in bridge.STIFFNESS_FAMILIES if n in bridge.params]
    wrt = tuple(present if wrt is None else wrt)
    for n in wrt:
        if n not in present:
            raise InputError(f"no stiffness parameter {n!r} on this bridge; have {present}")
    inf = influence_surfaces(bridge, sensors)
    params = bridge.params
    xa = np.atleast_2d(np.asarray(x, dtype=float))
    shape = np.broadcast_shapes(xa.shape, np.shape(np.atleast_2d(P)),
                                () if y is None else np.shape(np.atleast_2d(y)))
    xb = np.broadcast_to(xa, shape)
    yb = None if y is None else np.broadcast_to(np.atleast_2d(y), shape)
    Pb = np.broadcast_to(np.atleast_2d(P), shape)
    n_cases, n_loads = shape
    # displacements of every load case
    U = np.zeros((bridge.n_free, n_cases))
    on = model.grid.contains(xb.ravel(), None if yb is None else yb.ravel())
    if np.any(on):
        rows = model.point_rows(xb.ravel()[on], None if yb is None else yb.ravel()[on])
        case = np.repeat(np.arange(n_cases), n_loads)[on]
        F = np.zeros((bridge.n_free, n_cases))
        np.add.at(F, (rows.dofs, case[:, None]), rows.vals * Pb.ravel()[on][:, None])
        U = bridge.solve(F)
    asm = model.assembler
    columns: list[np.ndarray] = []
    names: list[str] = []
    index: list[int] = []
    for name in wrt:
        n_par = params[name].size
        block = np.zeros((n_cases, len(inf.sensors), n_par))
        for set_i, p_idx, dcoef in model.stiffness_derivatives(params, name):
            es = asm.sets[set_i]
            fdofs = asm.element_free_dofs(set_i)
            mask = fdofs >= 0
            safe = np.where(mask, fdofs, 0)
            units = es.stiffness_units[:, es.shape_id]  # (n_parts, n_e, nd, nd)
            dK = np.einsum("pe,peij->eij", dcoef, units)
            g_e = np.where(mask[:, :, None], inf.g[safe], 0.0)  # (n_e, nd, n_s)
            zone = np.zeros((p_idx.size, n_par))
            zone[np.arange(p_idx.size), p_idx] = 1.0
            for c0 in range(0, n_cases, chunk):
                u_e = np.where(mask[:, :, None], U[safe, c0:c0 + chunk], 0.0)  # (n_e, nd, c)
                t = -np.einsum("eis,eij,ejc->ecs", g_e, dK, u_e, optimize=True)
                block[c0:c0 + chunk] += np.einsum("ecs,ep->csp", t, zone)
        columns.append(block)
        names += [name] * n_par
        index += list(range(n_par))
    return Sensitivities(
        values=np.concatenate(columns, axis=2), names=tuple(names), index=np.asarray(index)
    )
