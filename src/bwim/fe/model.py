"""The discretised structure: mesh, supports, zones, girders and element sets.

Contract
--------
* :class:`FEModel` is everything about a bridge model that does **not** change during
  calibration: geometry, mesh, supports, zone map, girder geometry, unit element matrices
  and the assembly plan.  :class:`bwim.fe.bridge.Bridge` pairs one model with a parameter
  set; bridges that differ only in parameters share the model.
* Supports (docs/theory.md §1.1): a simply supported edge ``x = const`` fixes ``w`` and
  ``w_y``, an edge ``y = const`` fixes ``w`` and ``w_x``; a clamped edge fixes all four
  DOF of its nodes (on a beam: simple fixes ``w``, clamped ``w`` and ``w_x``); free fixes
  nothing.
* Zones group elements; each plate zone carries ``E_x, E_y, μ``, each beam zone
  ``E_x, μ``; each girder carries ``E_girder, μ_girder``.
* Rows that map free-DOF displacements to sensor readings and point loads to consistent
  nodal loads live here (:meth:`FEModel.sensor_matrix`, :meth:`FEModel.point_rows`).
  ``sensor_matrix`` is the one entry through which every FE computation (static,
  influence, simulate, calibration, MFI) meets sensors: it refuses a sensor without a
  position ``(x, y)`` and an axle detector with :class:`~bwim.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import scipy.sparse

from bwim.errors import InputError, parse_enum
from bwim.fe.assembly import Assembler, ElementSet
from bwim.fe.girder import Girder, beam_unit_matrices, girder_unit_matrices
from bwim.fe.mesh import Grid
from bwim.fe.plate import bfs_shape, bfs_unit_matrices, flexural_rigidity, hermite
from bwim.sensors import Sensor, SensorKind

__all__ = ["EdgeSupport", "FEModel", "PointRows", "Supports"]


def _require_fe_sensor(sensor: Sensor) -> None:
    """Refuse a sensor the model cannot observe: no position, or not a structural reading
    (an axle detector, a temperature channel)."""
    if not sensor.kind.is_structural:
        what = "an axle detector" if sensor.kind is SensorKind.AXLE_DETECTOR else (
            f"a {sensor.kind.value} channel")
        raise InputError(f"sensor {sensor.name!r} is {what}; an FE model has no reading for it")
    if not sensor.has_position:
        raise InputError(f"sensor {sensor.name!r} has no position (x, y); an FE model "
                         "needs one")


class EdgeSupport(StrEnum):
    """Boundary condition of one edge."""

    FREE = "free"
    SIMPLE = "simple"
    CLAMPED = "clamped"


_SUPPORT_PRESETS = {
    "ss-free": ("simple", "simple", "free", "free"),
    "ss": ("simple", "simple", "free", "free"),
    "ss-all": ("simple", "simple", "simple", "simple"),
    "clamped-free": ("clamped", "clamped", "free", "free"),
    "clamped": ("clamped", "clamped", "free", "free"),
}


@dataclass(frozen=True)
class Supports:
    """Support of each edge: ``x0`` (x = 0), ``x_end`` (x = length), ``y0`` (y = 0,
    right-hand edge) and ``y_end`` (y = width).  Beams use ``x0`` and ``x_end`` only."""

    x0: EdgeSupport = EdgeSupport.SIMPLE
    x_end: EdgeSupport = EdgeSupport.SIMPLE
    y0: EdgeSupport = EdgeSupport.FREE
    y_end: EdgeSupport = EdgeSupport.FREE

    def __post_init__(self) -> None:
        for name in ("x0", "x_end", "y0", "y_end"):
            object.__setattr__(self, name, parse_enum(EdgeSupport, getattr(self, name),
                                                      "support", context=f" for edge {name}"))

    @classmethod
    def parse(cls, value: Supports | str | Mapping[str, str]) -> Supports:
        """Supports from a preset name (``"ss-free"``, ``"ss-all"``, ``"ss"``,
        ``"clamped-free"``), a mapping of edge names to ``"free" | "simple" |
        "clamped"``, or a :class:`Supports`."""
        if isinstance(value, Supports):
            return value
        if isinstance(value, str):
            if value not in _SUPPORT_PRESETS:
                raise InputError(
                    f"unknown supports {value!r}; expected one of "
                    f"{', '.join(_SUPPORT_PRESETS)} or a mapping of edges"
                )
            return cls(*_SUPPORT_PRESETS[value])
        if isinstance(value, Mapping):
            unknown = set(value) - {"x0", "x_end", "y0", "y_end"}
            if unknown:
                raise InputError(
                    f"unknown support edge(s) {sorted(unknown)}; edges are x0, x_end, y0, y_end"
                )
            return cls(**dict(value))
        raise InputError(f"supports must be a name, a mapping or Supports, got {value!r}")


@dataclass(frozen=True, eq=False)
class PointRows:
    """Consistent-load rows of points: ``f[dofs[p]] += vals[p] * P_p``.

    ``dofs`` (n, k) are free-DOF indices (constrained DOF point at 0 with value 0).
    The same rows give the deflection at the points: ``w_p = vals[p] @ u[dofs[p]]``, and
    ``slopes`` (when asked for) the slope ``∂w/∂x = slopes[p] @ u[dofs[p]]``.
    """

    dofs: np.ndarray
    vals: np.ndarray
    slopes: np.ndarray | None = None

    def interpolate(self, fields: np.ndarray) -> np.ndarray:
        """``Σ_k vals[p, k] fields[dofs[p, k]]`` for every point ``p``, shape (n, m), of
        nodal ``fields`` (n_free, m): the deflection at the points of m displacement
        fields (mode shapes, influence surfaces).  As a sparse product: the numbers of
        ``einsum("pk,pkm->pm", vals, fields[dofs])`` (bit for bit with two fields or
        more, to rounding with one) without gathering an (n, k, m) array."""
        n, k = self.vals.shape
        rows = scipy.sparse.csr_matrix(
            (self.vals.ravel(), self.dofs.ravel(), np.arange(0, n * k + 1, k)),
            shape=(n, fields.shape[0]))
        return rows @ fields


@dataclass(frozen=True, eq=False, kw_only=True)
class FEModel:
    """A discretised bridge (see module docstring)."""

    grid: Grid
    supports: Supports
    zone_of_element: np.ndarray
    n_zones: int
    thickness: float | None = None  # plate
    poisson: float = 0.0  # plate
    inertia: float | None = None  # beam second moment, m⁴
    z_bottom: float | None = None  # beam soffit distance, m
    girders: tuple[Girder, ...] = ()
    assembler: Assembler = field(init=False, repr=False)
    girder_lines: tuple[int, ...] = field(init=False)
    # sensor rows already built (a sensor's row depends only on this model's geometry)
    _sensor_rows: dict = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        lines = []
        for k, g in enumerate(self.girders):
            iy = self.grid.on_y_line(g.y)
            if iy is None:
                raise InputError(
                    f"girders[{k}].y = {g.y:g} m is not on a node line; grid lines across "
                    f"are {np.round(self.grid.y_lines, 6).tolist()} "
                    "(pass y_lines=bwim.fe.grid_lines(width, ny, through=[...]))"
                )
            lines.append(iy)
        if len(set(lines)) != len(lines):
            raise InputError("two girders on the same node line")
        object.__setattr__(self, "girder_lines", tuple(lines))
        object.__setattr__(
            self,
            "assembler",
            Assembler(n_dof=self.grid.n_dof, fixed=self._fixed_dofs(), sets=self._sets()),
        )

    # --- construction ---------------------------------------------------------------
    @property
    def is_plate(self) -> bool:
        return self.grid.is_plate

    def _fixed_dofs(self) -> np.ndarray:
        g = self.grid
        fixed: list[np.ndarray] = []
        if not g.is_plate:
            for edge, ix in ((self.supports.x0, 0), (self.supports.x_end, g.nx)):
                node = int(g.node(ix))
                if edge is EdgeSupport.SIMPLE:
                    fixed.append(np.array([2 * node]))
                elif edge is EdgeSupport.CLAMPED:
                    fixed.append(np.array([2 * node, 2 * node + 1]))
            return np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, int)
        iy_all = np.arange(g.n_nodes_y)
        ix_all = np.arange(g.n_nodes_x)
        # (edge support, nodes on the edge, DOF fixed by a simple support)
        edges = (
            (self.supports.x0, g.node(0, iy_all), (0, 2)),
            (self.supports.x_end, g.node(g.nx, iy_all), (0, 2)),
            (self.supports.y0, g.node(ix_all, 0), (0, 1)),
            (self.supports.y_end, g.node(ix_all, g.ny), (0, 1)),
        )
        for edge, nodes, simple in edges:
            kinds = {EdgeSupport.SIMPLE: simple, EdgeSupport.CLAMPED: (0, 1, 2, 3)}.get(edge, ())
            for k in kinds:
                fixed.append(4 * nodes + k)
        return np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, int)

    def _sets(self) -> tuple[ElementSet, ...]:
        g = self.grid
        a, b = g.element_sizes()
        if g.is_plate:
            shapes, shape_id = np.unique(np.round(np.stack([a, b], 1), 12), axis=0,
                                         return_inverse=True)
            units = [bfs_unit_matrices(sa, sb, self.poisson) for sa, sb in shapes]
            plate = ElementSet(
                dofs=g.element_dofs(),
                stiffness_units=np.stack([np.stack(u[:3]) for u in units], axis=1),
                mass_units=np.stack([u[3] for u in units]),
                shape_id=shape_id.ravel(),
            )
            return (plate, *self._girder_sets())
        lengths, shape_id = np.unique(np.round(a, 12), return_inverse=True)
        units = [beam_unit_matrices(L) for L in lengths]
        beam = ElementSet(
            dofs=g.element_dofs(),
            stiffness_units=np.stack([u[0] for u in units])[None],
            mass_units=np.stack([u[1] for u in units]),
            shape_id=shape_id.ravel(),
        )
        return (beam,)

    def _girder_sets(self) -> list[ElementSet]:
        g = self.grid
        sets = []
        ix = np.arange(g.nx)
        lengths = np.diff(g.x_lines)
        for girder, iy in zip(self.girders, self.girder_lines, strict=True):
            n0 = g.node(ix, iy)
            n1 = g.node(ix + 1, iy)
            dofs = np.stack([4 * n0, 4 * n0 + 1, 4 * n0 + 2, 4 * n1, 4 * n1 + 1, 4 * n1 + 2], 1)
            uniq, sid = np.unique(np.round(lengths, 12), return_inverse=True)
            units = [girder_unit_matrices(L, girder.I, girder.J, girder.poisson) for L in uniq]
            sets.append(ElementSet(
                dofs=dofs,
                stiffness_units=np.stack([u[0] for u in units])[None],
                mass_units=np.stack([u[1] for u in units]),
                shape_id=sid.ravel(),
            ))
        return sets

    # --- coefficients ----------------------------------------------------------------
    def stiffness_coefficients(self, params: Mapping[str, np.ndarray]) -> list[np.ndarray]:
        """Per element set, the (n_parts, n_e) coefficients of the unit matrices."""
        z = self.zone_of_element
        if self.is_plate:
            dx = flexural_rigidity(params["E_x"][z], self.thickness, self.poisson)
            dy = flexural_rigidity(params["E_y"][z], self.thickness, self.poisson)
            out = [np.stack([dx, dy, np.sqrt(dx * dy)])]
            n_e = self.grid.nx
            out += [np.full((1, n_e), e) for e in params.get("E_girder", ())]
            return out
        return [(params["E_x"][z] * self.inertia)[None]]

    def mass_coefficients(self, params: Mapping[str, np.ndarray]) -> list[np.ndarray]:
        """Per element set, the (n_e,) mass coefficients (kg/m² or kg/m)."""
        out = [params["mu"][self.zone_of_element]]
        out += [np.full(self.grid.nx, m) for m in params.get("mu_girder", ())]
        return out

    def stiffness_derivatives(
        self, params: Mapping[str, np.ndarray], name: str
    ) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """∂(unit coefficients)/∂parameter for a stiffness parameter family.

        Returns a list of ``(set index, parameter index per element (n_e,), dcoef
        (n_parts, n_e))``: element ``e`` of that set depends on parameter
        ``name[param_index[e]]`` with ``∂c[:, e] = dcoef[:, e]``.
        """
        z = self.zone_of_element
        if name == "E_girder":
            if not self.is_plate:
                return []
            n_e = self.grid.nx
            return [(1 + k, np.full(n_e, k), np.ones((1, n_e))) for k in range(len(self.girders))]
        if not self.is_plate:
            if name != "E_x":
                raise InputError(f"a beam has no stiffness parameter {name!r}")
            return [(0, z, np.full((1, z.size), self.inertia))]
        c = flexural_rigidity(1.0, self.thickness, self.poisson)
        ex, ey = params["E_x"][z], params["E_y"][z]
        if name == "E_x":
            d = np.stack([np.full_like(ex, c), np.zeros_like(ex), 0.5 * c * np.sqrt(ey / ex)])
        elif name == "E_y":
            d = np.stack([np.zeros_like(ey), np.full_like(ey, c), 0.5 * c * np.sqrt(ex / ey)])
        else:
            raise InputError(f"no stiffness parameter {name!r}; use E_x, E_y or E_girder")
        return [(0, z, d)]

    # --- rows ------------------------------------------------------------------------
    def check_on_deck(self, what: str, x: np.ndarray, y: np.ndarray | None) -> None:
        ok = self.grid.contains(x, y)
        if not np.all(ok):
            k = int(np.flatnonzero(~np.atleast_1d(ok))[0])
            xs = np.atleast_1d(x)[k]
            where = f"x = {xs:g} m"
            if self.is_plate and y is not None:
                where += f", y = {np.atleast_1d(y)[k]:g} m"
            size = f"{self.grid.length:g} m"
            if self.is_plate:
                size += f" × {self.grid.width:g} m"
            raise InputError(f"{what} at {where} is off the deck ({size})")

    def point_rows(
        self, x: np.ndarray, y: np.ndarray | None = None, *, slopes: bool = False
    ) -> PointRows:
        """Consistent-load (and deflection, optionally slope) rows of points on the deck."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        loc = self.grid.locate(x, y)
        a, b = self.grid.element_sizes()
        e = loc.element
        if self.is_plate:
            hx, dhx, _ = hermite(loc.xi, a[e])
            hy, _, _ = hermite(loc.eta, b[e])
            n = np.einsum("pa,pb->pab", hx, hy).reshape(-1, 16)
            nx = np.einsum("pa,pb->pab", dhx, hy).reshape(-1, 16) if slopes else None
        else:
            n, nx, _ = hermite(loc.xi, a[e])
        dofs = self.assembler.free_of[self.assembler.sets[0].dofs[e]]
        free = dofs >= 0
        return PointRows(
            dofs=np.where(free, dofs, 0),
            vals=np.where(free, n, 0.0),
            slopes=np.where(free, nx, 0.0) if slopes else None,
        )

    def load_vector(self, x: np.ndarray, y: np.ndarray | None, P: np.ndarray) -> np.ndarray:
        """Consistent nodal load vector on the free DOF (sum of the point loads)."""
        rows = self.point_rows(x, y)
        f = np.zeros(self.assembler.n_free)
        np.add.at(f, rows.dofs, rows.vals * np.asarray(P, dtype=float)[:, None])
        return f

    def sensor_row(self, sensor: Sensor) -> np.ndarray:
        """Row ``s`` with ``reading = s @ u`` (u on the free DOF), shape (n_free,)."""
        _require_fe_sensor(sensor)
        g = self.grid
        kind = SensorKind(sensor.kind)
        if not g.is_plate:
            if kind is SensorKind.STRAIN_Y:
                raise InputError(f"sensor {sensor.name!r}: a beam bridge has no strain_y")
            if kind.is_strain and self.z_bottom is None:
                raise InputError(
                    f"sensor {sensor.name!r}: strain on a beam bridge needs z_bottom "
                    "(distance from the neutral axis to the soffit) in Bridge.beam"
                )
        touching = g.elements_at(sensor.x, sensor.y)
        a, b = g.element_sizes()
        dofs0 = self.assembler.sets[0].dofs
        row_full = np.zeros(g.n_dof)
        if kind is SensorKind.DEFLECTION:
            touching = touching[:1]
        for e, xi, eta in touching:
            if g.is_plate:
                n, n_xx, n_yy = bfs_shape(np.array([xi]), np.array([eta]), a[e], b[e])
            else:
                n, _, n_xx = hermite(np.array([xi]), a[e])
                n_yy = None
            if kind is SensorKind.DEFLECTION:
                r = n[0]
            elif kind is SensorKind.STRAIN_X:
                r = -self._strain_depth(sensor) * n_xx[0]
            else:
                r = -0.5 * self.thickness * n_yy[0]
            np.add.at(row_full, dofs0[e], r / len(touching))
        return row_full[self.assembler.free]

    def _strain_depth(self, sensor: Sensor) -> float:
        if not self.is_plate:
            return float(self.z_bottom)
        iy = self.grid.on_y_line(sensor.y)
        for girder, line in zip(self.girders, self.girder_lines, strict=True):
            if iy == line:
                return girder.z_bottom
        return 0.5 * self.thickness

    def sensor_matrix(self, sensors: Sequence[Sensor]) -> np.ndarray:
        """Stacked sensor rows, shape (n_sensors, n_free)."""
        sensors = list(sensors)
        if not sensors:
            raise InputError("at least one sensor is needed")
        rows = []
        for k, s in enumerate(sensors):
            if not isinstance(s, Sensor):
                raise InputError(f"sensors[{k}] must be a bwim.Sensor, got {type(s).__name__}")
            row = self._sensor_rows.get(s)
            if row is None:
                _require_fe_sensor(s)
                self.check_on_deck(f"sensor {s.name!r}", np.array([s.x]), np.array([s.y]))
                row = self.sensor_row(s)
                row.flags.writeable = False
                self._sensor_rows[s] = row
            rows.append(row)
        return np.stack(rows)

    @property
    def deflection_dofs(self) -> np.ndarray:
        """Free-DOF indices of the nodal deflections w."""
        per = self.grid.dof_per_node
        w = np.arange(0, self.grid.n_dof, per)
        f = self.assembler.free_of[w]
        return f[f >= 0]
