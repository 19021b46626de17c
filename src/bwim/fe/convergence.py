"""Mesh convergence at the sensors: is a model fine enough for what it is compared with?

Contract
--------
* :func:`refine` bisects every element of a bridge (nx, ny → 2 nx, 2 ny; a beam's
  elements likewise), keeping its supports, zones (each new element in its parent's
  zone), girders and parameters.
* :func:`check_mesh` computes the static readings of ``sensors`` under one or more load
  cases (:class:`~bwim.loads.PointLoad`, N down) on the model and on successive
  bisections, until the readings at **every** sensor change by less than ``tol``
  (relative) between the last two meshes, or ``max_levels`` meshes were solved.
  Relative changes are taken against ``max(|reading|, floor × peak)``: the peak |reading|
  over the sensors with the same unit and load case, ``floor`` = 5 % (a sensor near a
  zero of its influence line would otherwise never converge relatively).
* The discretisation error of each mesh (docs/theory.md §11) is estimated by Richardson
  extrapolation from the last three meshes with the **observed** order
  ``p = log2(‖Δ₁‖ / ‖Δ₂‖)`` (clipped to [0.5, 6]); ``error[k] = reading[k] −
  extrapolated``.  With only two meshes, the last change stands in for the error of the
  finer one (p unknown, NaN).
* Results are a frozen :class:`MeshConvergence`; readings are strains (dimensionless) or
  deflections (m), as the sensors read.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_range
from bwim.fe.bridge import Bridge
from bwim.loads import PointLoad
from bwim.sensors import Sensor

__all__ = ["MeshConvergence", "check_mesh", "refine"]

#: Floor of the relative-change scale, a fraction of the peak reading of the same unit.
FLOOR = 0.05


@dataclass(frozen=True, kw_only=True, eq=False)
class MeshConvergence:
    """Static readings at the sensors on successively bisected meshes.

    Attributes
    ----------
    sensors : tuple of str
        Sensor names, in the order of the last axis below.
    meshes : tuple of (int, int)
        ``(nx, ny)`` of each mesh solved (``ny`` = 0 for beams), coarsest (the given
        model) first.
    readings : ndarray, shape (n_meshes, n_cases, n_sensors)
    scale : ndarray, shape (n_cases, n_sensors)
        What relative changes and errors are divided by (see module docstring).
    change : ndarray, shape (n_sensors,)
        Largest relative change over the load cases between the last two meshes.
    converged : bool
        Every ``change`` below ``tol``.
    tol : float
    order : float
        Observed convergence order (NaN with fewer than three meshes).
    extrapolated : ndarray, shape (n_cases, n_sensors)
        Richardson estimate of the converged readings.
    error : ndarray, shape (n_meshes, n_cases, n_sensors)
        Estimated discretisation error of each mesh's readings (reading − extrapolated).
    """

    sensors: tuple[str, ...]
    meshes: tuple[tuple[int, int], ...]
    readings: np.ndarray
    scale: np.ndarray
    change: np.ndarray
    converged: bool
    tol: float
    order: float
    extrapolated: np.ndarray
    error: np.ndarray

    @property
    def relative_error(self) -> np.ndarray:
        """Largest relative discretisation error of each mesh at each sensor over the load
        cases, shape (n_meshes, n_sensors)."""
        return np.max(np.abs(self.error) / self.scale[None], axis=1)

    @property
    def model_error(self) -> dict[str, float]:
        """Relative discretisation error of the *given* model at each sensor, by name."""
        return dict(zip(self.sensors, self.relative_error[0].tolist(), strict=True))

    @property
    def adequate(self) -> tuple[int, int] | None:
        """The coarsest mesh whose estimated relative error is below ``tol`` at every
        sensor (None if none is)."""
        ok = np.flatnonzero(self.relative_error.max(axis=1) < self.tol)
        return self.meshes[int(ok[0])] if ok.size else None

    def summary(self) -> str:
        rel = self.relative_error
        worst = int(np.argmax(rel[0]))
        lines = [
            f"meshes {', '.join(f'{a}x{b}' if b else str(a) for a, b in self.meshes)}; "
            f"observed order {self.order:.2f}; "
            + ("converged" if self.converged else "NOT converged")
            + f" to {self.tol:.2%} at every sensor",
            f"given model: discretisation error up to {rel[0, worst]:.2%} "
            f"(sensor {self.sensors[worst]}), median {np.median(rel[0]):.2%}",
        ]
        ad = self.adequate
        lines.append("no mesh solved is within tol" if ad is None
                     else f"coarsest mesh within tol: {ad[0]}x{ad[1]}" if ad[1]
                     else f"coarsest mesh within tol: {ad[0]} elements")
        return "\n".join(lines)


def refine(bridge: Bridge) -> Bridge:
    """``bridge`` with every element bisected in each direction (see module docstring)."""
    if not isinstance(bridge, Bridge):
        raise InputError(f"bridge must be a bwim.Bridge, got {type(bridge).__name__}")
    m = bridge.model
    g = m.grid
    xl = _bisect(g.x_lines)
    if m.is_plate:
        zones = np.repeat(np.repeat(m.zone_of_element.reshape(g.nx, g.ny), 2, axis=0), 2,
                          axis=1)
        new = Bridge.plate(length=g.length, width=g.width, x_lines=xl,
                           y_lines=_bisect(g.y_lines), thickness=m.thickness,
                           poisson=m.poisson, E=1.0, mu=1.0,
                           damping_ratio=bridge.damping_ratio, supports=m.supports,
                           girders=m.girders, zones=zones)
    else:
        zones = np.repeat(m.zone_of_element, 2)
        new = Bridge.beam(length=g.length, x_lines=xl, E=1.0, I=m.inertia, mu=1.0,
                          z_bottom=m.z_bottom, damping_ratio=bridge.damping_ratio,
                          supports=m.supports, zones=zones)
    return new.with_params(**bridge.params)


def _bisect(lines: np.ndarray) -> np.ndarray:
    out = np.empty(2 * lines.size - 1)
    out[0::2] = lines
    out[1::2] = 0.5 * (lines[:-1] + lines[1:])
    return out


def _cases(loads) -> list[list[PointLoad]]:
    """Load cases from one sequence of PointLoad or a sequence of them."""
    loads = list(loads)
    if not loads:
        raise InputError("loads must hold at least one PointLoad")
    if all(isinstance(p, PointLoad) for p in loads):
        return [loads]
    cases = []
    for k, case in enumerate(loads):
        case = list(case) if isinstance(case, (list, tuple)) else None
        if not case or not all(isinstance(p, PointLoad) for p in case):
            raise InputError(f"loads[{k}] must be a PointLoad or a non-empty sequence of "
                             "PointLoad")
        cases.append(case)
    return cases


def check_mesh(
    model: Bridge | Callable[[int, int], Bridge],
    sensors: Sequence[Sensor],
    loads,
    *,
    tol: float = 0.01,
    max_levels: int = 4,
    start: tuple[int, int] | None = None,
) -> MeshConvergence:
    """Refine the mesh until the static readings at every sensor change by < ``tol``.

    Parameters
    ----------
    model : Bridge or callable
        The model to check (refined by :func:`refine`), or ``factory(nx, ny) -> Bridge``
        (then ``start`` is the first ``(nx, ny)``; beams ignore ``ny``).
    sensors : sequence of Sensor
    loads : sequence of PointLoad, or sequence of such sequences (load cases)
        Static loads, N down, e.g. a truck's static wheel loads where its strains peak.
    tol : float
        Relative change at which a sensor counts as converged (0 < tol < 1).
    max_levels : int
        Most meshes to solve, the given one included (>= 2).
    start : (int, int), optional
        The factory's first mesh.
    """
    tol = require_range("tol", tol, 0.0, 1.0)
    if not isinstance(max_levels, (int, np.integer)) or max_levels < 2:
        raise InputError(f"max_levels must be an integer >= 2, got {max_levels!r}")
    sensors = list(sensors)
    if not sensors or not all(isinstance(s, Sensor) for s in sensors):
        raise InputError("sensors must be a non-empty sequence of bwim.Sensor")
    cases = _cases(loads)
    if isinstance(model, Bridge):
        bridges = _refined(model)
    elif callable(model):
        if start is None:
            raise InputError("a mesh factory needs start=(nx, ny), its first mesh")
        try:
            nx, ny = (int(v) for v in start)
        except (TypeError, ValueError):
            raise InputError(f"start must be two integers (nx, ny), got {start!r}") from None
        if nx < 1 or ny < 1:
            raise InputError(f"start must be positive (nx, ny), got {start!r}")
        bridges = (model(nx * 2**k, ny * 2**k) for k in range(max_levels))
    else:
        raise InputError(f"model must be a Bridge or a factory(nx, ny), got "
                         f"{type(model).__name__}")
    units = np.array([s.kind.unit for s in sensors])
    readings, meshes = [], []
    converged, change = False, np.full(len(sensors), np.nan)
    scale = None
    # islice: the mesh after the last one solved is never built (a 4× larger model)
    for level, b in enumerate(itertools.islice(bridges, max_levels)):
        g = b.model.grid
        meshes.append((g.nx, g.ny if b.is_plate else 0))
        readings.append(np.stack([b.static(case, sensors) for case in cases]))
        scale = _scale(readings[-1], units)
        if level >= 1:
            change = np.max(np.abs(readings[-1] - readings[-2]) / scale, axis=0)
            converged = bool(np.all(change < tol))
            if converged and level >= 2:
                break
    R = np.asarray(readings)
    order, extrap = _richardson(R)
    return MeshConvergence(sensors=tuple(s.name for s in sensors), meshes=tuple(meshes),
                           readings=R, scale=scale, change=change, converged=converged,
                           tol=float(tol), order=order, extrapolated=extrap,
                           error=R - extrap[None])


def _refined(bridge: Bridge):
    b = bridge
    while True:
        yield b
        b = refine(b)


def _scale(values: np.ndarray, units: np.ndarray) -> np.ndarray:
    """``max(|value|, FLOOR × peak of the same unit)`` per load case and sensor."""
    out = np.abs(values).copy()
    for unit in set(units.tolist()):
        grp = units == unit
        peak = np.abs(values[:, grp]).max(axis=1, keepdims=True)
        out[:, grp] = np.maximum(out[:, grp], FLOOR * peak)
    return np.where(out > 0, out, 1.0)


def _richardson(R: np.ndarray) -> tuple[float, np.ndarray]:
    """Observed order and extrapolated readings from the last three meshes."""
    if R.shape[0] < 3:
        return float("nan"), R[-1] + (R[-1] - R[-2])  # the last change as the error
    d1 = np.linalg.norm(R[-2] - R[-3])
    d2 = np.linalg.norm(R[-1] - R[-2])
    if d2 == 0 or d1 == 0:
        return float("nan"), R[-1].copy()
    p = float(np.clip(np.log2(d1 / d2), 0.5, 6.0))
    return p, R[-1] + (R[-1] - R[-2]) / (2.0**p - 1.0)
