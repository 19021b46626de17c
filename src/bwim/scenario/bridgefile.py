"""A bridge model on disk: TOML that rebuilds it exactly (for example a calibrated one).

Contract
--------
* :func:`save_bridge` writes a scenario file holding only a ``[bridge]`` section that
  states the bridge completely: explicit grid lines, the support of every edge, the zones
  (as ``[nzx, nzy]`` / ``n`` when the zone grid reproduces the labels, else an explicit
  ``zone_map``), the current parameters per zone (``E_x``, ``E_y``, ``mu``), the damping
  ratio and every girder with its current ``E_girder`` / ``mu_girder`` as ``E`` / ``mu``.
  Floats are written with :func:`repr`, which reads back bit for bit.
* :func:`load_bridge` reads such a file, or any scenario file, and builds its bridge:
  the loaded bridge has the same ``params``, damping ratio and grid, hence the same
  stiffness and mass matrices.  So ``bwim calibrate`` and ``bwim identify`` can run as
  two invocations.
* :func:`bridge_spec` gives the :class:`~bwim.scenario.BridgeSpec` of a bridge.
"""

from __future__ import annotations

import os
from importlib.metadata import PackageNotFoundError, version
from types import MappingProxyType

import numpy as np

from bwim.fe.bridge import Bridge
from bwim.scenario.build import build_bridge
from bwim.scenario.parse import dump_scenario, load_scenario
from bwim.scenario.specs import BridgeSpec, GirderSpec, Scenario

__all__ = ["bridge_spec", "load_bridge", "save_bridge"]


def _values(a: np.ndarray) -> float | tuple[float, ...]:
    a = np.asarray(a, dtype=float)
    return float(a[0]) if a.size == 1 else tuple(float(v) for v in a)


def _divisor_pairs(n: int, nx: int, ny: int) -> list[tuple[int, int]]:
    return [(a, n // a) for a in range(1, n + 1) if n % a == 0 and a <= nx and n // a <= ny]


def _zones(bridge: Bridge) -> dict:
    """``zones`` when a zone grid gives the bridge's labels, else ``zone_map``."""
    m = bridge.model
    g = m.grid
    if m.n_zones == 1:
        return {}
    labels = np.asarray(m.zone_of_element)
    if bridge.is_plate:
        for pair in _divisor_pairs(m.n_zones, g.nx, g.ny):
            trial = Bridge.plate(length=g.length, width=g.width, x_lines=g.x_lines,
                                 y_lines=g.y_lines, thickness=1.0, E=1.0, mu=1.0, zones=pair)
            if np.array_equal(trial.model.zone_of_element, labels):
                return {"zones": pair}
        zmap = tuple(tuple(int(v) for v in row) for row in labels.reshape(g.nx, g.ny))
    else:
        trial = Bridge.beam(length=g.length, x_lines=g.x_lines, E=1.0, I=1.0, mu=1.0,
                            zones=m.n_zones)
        if np.array_equal(trial.model.zone_of_element, labels):
            return {"zones": m.n_zones}
        zmap = tuple(int(v) for v in labels)
    out: dict = {"zone_map": zmap}
    if int(labels.max()) + 1 != m.n_zones:
        out["n_zones"] = m.n_zones
    return out


def bridge_spec(bridge: Bridge) -> BridgeSpec:
    """The ``[bridge]`` spec that rebuilds ``bridge`` exactly (see the module docstring)."""
    m = bridge.model
    g = m.grid
    edges = ("x0", "x_end", "y0", "y_end") if bridge.is_plate else ("x0", "x_end")
    supports = MappingProxyType({e: getattr(m.supports, e).value for e in edges})
    common = dict(length=g.length, x_lines=tuple(float(v) for v in g.x_lines),
                  mu=_values(bridge.mu), damping_ratio=float(bridge.damping_ratio),
                  supports=supports, **_zones(bridge))
    if not bridge.is_plate:
        return BridgeSpec(kind="beam", E=_values(bridge.E_x), I=float(m.inertia),
                          z_bottom=None if m.z_bottom is None else float(m.z_bottom), **common)
    girders = tuple(
        GirderSpec(y=float(gd.y), E=float(bridge.E_girder[k]), mu=float(bridge.mu_girder[k]),
                   I=float(gd.I), z_bottom=float(gd.z_bottom), J=float(gd.J),
                   poisson=float(gd.poisson))
        for k, gd in enumerate(m.girders)
    )
    return BridgeSpec(kind="plate", width=g.width, thickness=float(m.thickness),
                      y_lines=tuple(float(v) for v in g.y_lines), E_x=_values(bridge.E_x),
                      E_y=_values(bridge.E_y), poisson=float(m.poisson), girders=girders,
                      **common)


def save_bridge(bridge: Bridge, path: str | os.PathLike, *, title: str = "") -> None:
    """Write a bridge model as TOML that :func:`load_bridge` rebuilds exactly.

    Parameters
    ----------
    bridge : Bridge
    path : str or path
        Output file (written atomically).
    title : str
        Optional description stored as the file's ``title``.
    """
    try:
        release = version("bwim")
    except PackageNotFoundError:  # pragma: no cover - a source tree without installation
        release = "unknown version"
    header = (f"bwim bridge model (bwim {release}): parameters per zone, exact.\n"
              "Load with bwim.scenario.load_bridge(path); any [bridge] scenario key may be edited.")
    dump_scenario(Scenario(bridge=bridge_spec(bridge), title=title), path, header=header)


def load_bridge(path: str | os.PathLike) -> Bridge:
    """The bridge of a file written by :func:`save_bridge` (or of any scenario file)."""
    return build_bridge(load_scenario(path))
