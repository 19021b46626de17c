"""Longitudinal joints of a plate deck, each a zone of its own.

Why
---
A wide slab is often cast in parts, or carries a longitudinal construction joint between
its carriageways, that passes less bending across it than the monolithic slab would: the
transverse spread of a wheel's strain stops at the joint.  A one-zone plate cannot show
it (its transverse modulus is the deck's everywhere), so a calibration of such a deck
either drives ``E_y`` of the whole plate down or leaves a misfit across the gauges
(docs/theory.md §18).  Declaring the joint's line gives the model one more zone whose
transverse modulus the calibration fits: near the deck's when the joint is monolithic, far
below it when the joint behaves as a hinge.

Contract
--------
* A joint along ``y = y_j`` (m, the plate's frame) is the column of elements, along the
  whole span, whose y-interval holds ``y_j`` (on a grid line: the element on its
  ``+y`` side, the last one at the far edge).  Joint k is zone ``k + 1``; the rest of the
  deck is zone 0.  Two joints in one column are refused.
* :func:`with_joints` needs a one-zone plate; the joints' zones start with the deck's
  ``E_x``, ``mu`` and ``E_y`` × ``stiffness[k]`` (default 1: the joint as stiff as the
  deck).  Girders and supports are kept.
* :func:`joint_zones` is the zone label of every element, shape ``(nx, ny)``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.fe.mesh import Grid

__all__ = ["joint_zones", "with_joints"]


def joint_zones(grid: Grid, joints: Sequence[float]) -> np.ndarray:
    """Each element's zone label, shape (nx, ny): 0 for the deck, k + 1 for joint k."""
    if grid.y_lines is None:
        raise InputError("joints need a plate (a beam has no transverse direction)")
    ys = np.asarray(joints, dtype=float).ravel()
    lines = np.asarray(grid.y_lines, dtype=float)
    width = float(lines[-1])
    if ys.size == 0 or not np.all(np.isfinite(ys)):
        raise InputError(f"joints must be one or more finite y positions, m; got {joints!r}")
    if np.any((ys <= 0.0) | (ys >= width)):
        raise InputError(f"a joint must lie inside the deck's width (0, {width:g}) m; got "
                         f"{[float(v) for v in ys]}")
    cols = np.minimum(np.searchsorted(lines, ys, side="right") - 1, lines.size - 2)
    if np.unique(cols).size != cols.size:
        raise InputError("two joints fall in one column of elements: refine the mesh "
                         "across the deck (ny) or merge them")
    zones = np.zeros((grid.nx, lines.size - 1), dtype=int)
    for k, j in enumerate(cols):
        zones[:, j] = k + 1
    return zones


def with_joints(bridge: Bridge, joints: Sequence[float],
                stiffness: Sequence[float] | None = None) -> Bridge:
    """``bridge`` (a one-zone plate) with a zone per joint (module contract)."""
    if not isinstance(bridge, Bridge) or not bridge.is_plate:
        raise InputError("joints need a plate bridge")
    if bridge.model.n_zones != 1:
        raise InputError(f"joints need a one-zone plate, got {bridge.model.n_zones} zones")
    zones = joint_zones(bridge.model.grid, joints)
    n = int(zones.max()) + 1
    ratio = np.ones(n - 1) if stiffness is None else np.asarray(stiffness, dtype=float)
    if ratio.shape != (n - 1,) or not np.all(np.isfinite(ratio)) or np.any(ratio <= 0):
        raise InputError(f"stiffness must give one positive ratio per joint ({n - 1}), got "
                         f"{stiffness!r}")
    model = dataclasses.replace(bridge.model, zone_of_element=zones.ravel(), n_zones=n)
    E_y = float(bridge.E_y[0]) * np.concatenate([[1.0], ratio])
    return Bridge(model=model, E_x=np.full(n, float(bridge.E_x[0])), E_y=E_y,
                  mu=np.full(n, float(bridge.mu[0])), E_girder=bridge.E_girder,
                  mu_girder=bridge.mu_girder, damping_ratio=bridge.damping_ratio)
