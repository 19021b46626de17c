"""Grid lines, node and degree-of-freedom numbering, and point location.

Contract
--------
* A plate mesh is a rectangular grid of ``nx × ny`` elements between grid lines
  ``x_lines`` (``nx + 1`` values from 0 to the length) and ``y_lines`` (``ny + 1`` values
  from 0 to the width).  Grid lines may be non-uniform so that sensor lines, girder lines
  and zone borders fall on node lines.
* Plate nodes carry 4 DOF in the order ``(w, w_x, w_y, w_xy)``; a beam mesh (``y_lines``
  is ``None``) has nodes with ``(w, w_x)``.
* Nodes are numbered across the **short** side first, which keeps the half-bandwidth of
  K near ``4 × (nodes across + 1)`` DOF.
* Element ``e = ix * ny + iy`` (plates) or ``e = ix`` (beams); ``ix`` counts along x.
* :meth:`Grid.locate` returns, for points on the deck, the element and the local
  coordinates ``ξ = (x − x_i) / a``, ``η = (y − y_j) / b`` in [0, 1].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bwim.errors import InputError

__all__ = ["Grid", "Location", "grid_lines"]

#: Relative tolerance (of the deck dimension) for "on a grid line" and "on the deck".
REL_TOL = 1e-9


def grid_lines(
    length: float, n: int, *, through: Sequence[float] = (), name: str = "grid"
) -> np.ndarray:
    """Grid lines from 0 to ``length`` in ``n`` elements passing through given coordinates.

    The coordinates in ``through`` (sensor lines, girder lines, zone borders) become grid
    lines; the remaining lines are spread so that elements are as even as possible.

    Parameters
    ----------
    length : float
        Dimension to divide, m (> 0).
    n : int
        Number of elements (>= number of distinct interior points + 1).
    through : sequence of float
        Interior coordinates (m) that must be grid lines.

    Returns
    -------
    ndarray, shape (n + 1,)
        Increasing grid-line coordinates, first 0 and last ``length``.
    """
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise InputError(f"{name}: number of elements must be a positive integer, got {n!r}")
    pts = sorted({float(t) for t in through if REL_TOL * length < t < length * (1 - REL_TOL)})
    for t in through:
        if not (0.0 <= float(t) <= length):
            raise InputError(f"{name}: line at {float(t):g} m lies outside [0, {length:g}] m")
    fixed = [0.0, *pts, float(length)]
    n_seg = len(fixed) - 1
    if n < n_seg:
        raise InputError(
            f"{name}: {n} elements cannot pass through {len(pts)} required lines; "
            f"use at least {n_seg}"
        )
    seg_len = np.diff(fixed)
    # Share the elements among segments in proportion to their length (largest remainder).
    counts = np.ones(n_seg, dtype=int)
    for _ in range(n - n_seg):
        counts[np.argmax(seg_len / counts)] += 1
    lines = [0.0]
    for a, b, c in zip(fixed[:-1], fixed[1:], counts, strict=True):
        lines.extend(np.linspace(a, b, c + 1)[1:].tolist())
    return np.asarray(lines)


def _check_lines(name: str, lines: np.ndarray) -> np.ndarray:
    lines = np.asarray(lines, dtype=float)
    if lines.ndim != 1 or lines.size < 2:
        raise InputError(f"{name} must be a 1-D sequence of at least two coordinates")
    if not np.all(np.isfinite(lines)):
        raise InputError(f"{name} must be finite, got {lines.tolist()}")
    if abs(lines[0]) > 0.0:
        raise InputError(f"{name} must start at 0, got {lines[0]:g}")
    if np.any(np.diff(lines) <= 0.0):
        raise InputError(f"{name} must be strictly increasing, got {lines.tolist()}")
    return lines


@dataclass(frozen=True, eq=False)
class Location:
    """Where points fall on the mesh (all arrays have the points' shape ``(n,)``)."""

    element: np.ndarray  #: element index
    ix: np.ndarray  #: element column along x
    iy: np.ndarray  #: element row across y (zeros for a beam)
    xi: np.ndarray  #: local coordinate along x in [0, 1]
    eta: np.ndarray  #: local coordinate across y in [0, 1] (zeros for a beam)


@dataclass(frozen=True, eq=False)
class Grid:
    """A rectangular plate grid, or a line of beam elements when ``y_lines`` is None."""

    x_lines: np.ndarray
    y_lines: np.ndarray | None = None
    across_first: bool = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "x_lines", _check_lines("x_lines", self.x_lines))
        if self.y_lines is not None:
            object.__setattr__(self, "y_lines", _check_lines("y_lines", self.y_lines))
        # Number nodes across the short side first (narrow band).
        object.__setattr__(self, "across_first", self.n_nodes_y <= self.n_nodes_x)

    # --- sizes -------------------------------------------------------------------------
    @property
    def is_plate(self) -> bool:
        return self.y_lines is not None

    @property
    def length(self) -> float:
        return float(self.x_lines[-1])

    @property
    def width(self) -> float:
        return float(self.y_lines[-1]) if self.y_lines is not None else 0.0

    @property
    def nx(self) -> int:
        return self.x_lines.size - 1

    @property
    def ny(self) -> int:
        return self.y_lines.size - 1 if self.y_lines is not None else 1

    @property
    def n_nodes_x(self) -> int:
        return self.x_lines.size

    @property
    def n_nodes_y(self) -> int:
        return self.y_lines.size if self.y_lines is not None else 1

    @property
    def n_nodes(self) -> int:
        return self.n_nodes_x * self.n_nodes_y

    @property
    def dof_per_node(self) -> int:
        return 4 if self.is_plate else 2

    @property
    def n_dof(self) -> int:
        return self.n_nodes * self.dof_per_node

    @property
    def n_elements(self) -> int:
        return self.nx * self.ny

    # --- numbering ---------------------------------------------------------------------
    def node(self, ix: np.ndarray | int, iy: np.ndarray | int = 0) -> np.ndarray:
        """Node number of grid node ``(ix, iy)`` (vectorised)."""
        ix = np.asarray(ix)
        iy = np.asarray(iy)
        if self.across_first:
            return ix * self.n_nodes_y + iy
        return iy * self.n_nodes_x + ix

    def element_index(self, ix: np.ndarray | int, iy: np.ndarray | int = 0) -> np.ndarray:
        return np.asarray(ix) * self.ny + np.asarray(iy)

    def element_ixiy(self) -> tuple[np.ndarray, np.ndarray]:
        """Element grid indices ``(ix, iy)`` of every element, in element order."""
        e = np.arange(self.n_elements)
        return e // self.ny, e % self.ny

    def element_sizes(self) -> tuple[np.ndarray, np.ndarray]:
        """Element dimensions ``(a, b)`` (m) in element order (b = 1 for beams)."""
        ix, iy = self.element_ixiy()
        a = np.diff(self.x_lines)[ix]
        b = np.diff(self.y_lines)[iy] if self.is_plate else np.ones_like(a)
        return a, b

    def element_centres(self) -> tuple[np.ndarray, np.ndarray]:
        ix, iy = self.element_ixiy()
        xc = 0.5 * (self.x_lines[ix] + self.x_lines[ix + 1])
        if not self.is_plate:
            return xc, np.zeros_like(xc)
        yc = 0.5 * (self.y_lines[iy] + self.y_lines[iy + 1])
        return xc, yc

    def element_dofs(self) -> np.ndarray:
        """Global DOF numbers of every element, in the local order of the element.

        Plates: local DOF ``4 * a + b`` with 1-D Hermite indices ``a`` (along x) and ``b``
        (across y), each in ``(value at 0, slope at 0, value at 1, slope at 1)``: the
        Kronecker order of :func:`bwim.fe.plate.bfs_unit_matrices`.  Beams: ``(w0, wx0,
        w1, wx1)``.  Shape ``(n_elements, 16)`` or ``(n_elements, 4)``.
        """
        ix, iy = self.element_ixiy()
        if not self.is_plate:
            n0 = self.node(ix)
            n1 = self.node(ix + 1)
            return np.stack([2 * n0, 2 * n0 + 1, 2 * n1, 2 * n1 + 1], axis=1)
        dofs = np.empty((self.n_elements, 16), dtype=np.int64)
        for a in range(4):
            i, dx = divmod(a, 2)
            for b in range(4):
                j, dy = divmod(b, 2)
                node = self.node(ix + i, iy + j)
                dofs[:, 4 * a + b] = 4 * node + dx + 2 * dy
        return dofs

    # --- location ----------------------------------------------------------------------
    def on_x_line(self, x: float) -> int | None:
        """Index of the x grid line at ``x`` (within tolerance) or None."""
        return _line_index(self.x_lines, x)

    def on_y_line(self, y: float) -> int | None:
        if self.y_lines is None:
            return None
        return _line_index(self.y_lines, y)

    def contains(self, x: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """True where the points lie on the deck (within a tiny tolerance)."""
        x = np.asarray(x, dtype=float)
        tx = REL_TOL * max(self.length, 1.0)
        ok = (x >= -tx) & (x <= self.length + tx)
        if self.is_plate and y is not None:
            y = np.asarray(y, dtype=float)
            ty = REL_TOL * max(self.width, 1.0)
            ok &= (y >= -ty) & (y <= self.width + ty)
        return ok

    def locate(self, x: np.ndarray, y: np.ndarray | None = None) -> Location:
        """Element and local coordinates of points (which must be on the deck)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        ix, xi = _locate_1d(self.x_lines, x)
        if self.is_plate:
            if y is None:
                raise InputError("a plate needs y coordinates to locate points")
            y = np.broadcast_to(np.asarray(y, dtype=float), x.shape)
            iy, eta = _locate_1d(self.y_lines, y)
        else:
            iy = np.zeros_like(ix)
            eta = np.zeros_like(xi)
        return Location(
            element=self.element_index(ix, iy), ix=ix, iy=iy, xi=xi, eta=eta
        )

    def elements_at(self, x: float, y: float = 0.0) -> list[tuple[int, float, float]]:
        """All elements touching a point, with local coordinates: ``[(e, ξ, η), ...]``.

        A point inside an element touches one; on an element edge two; on a node up to
        four.  Used to average discontinuous quantities (curvatures) at shared points.
        """
        cols = _touching(self.x_lines, x)
        rows = _touching(self.y_lines, y) if self.is_plate else [(0, 0.0)]
        return [
            (int(self.element_index(ix, iy)), xi, eta) for ix, xi in cols for iy, eta in rows
        ]


def _line_index(lines: np.ndarray, v: float) -> int | None:
    tol = REL_TOL * max(float(lines[-1]), 1.0)
    k = int(np.argmin(np.abs(lines - v)))
    return k if abs(lines[k] - v) <= tol else None


def _locate_1d(lines: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = lines.size - 1
    i = np.clip(np.searchsorted(lines, v, side="right") - 1, 0, n - 1)
    s = (v - lines[i]) / (lines[i + 1] - lines[i])
    return i, np.clip(s, 0.0, 1.0)


def _touching(lines: np.ndarray, v: float) -> list[tuple[int, float]]:
    n = lines.size - 1
    k = _line_index(lines, v)
    if k is None:
        (i,), (s,) = _locate_1d(lines, np.array([v]))
        return [(int(i), float(s))]
    out = []
    if k > 0:
        out.append((k - 1, 1.0))
    if k < n:
        out.append((k, 0.0))
    return out
