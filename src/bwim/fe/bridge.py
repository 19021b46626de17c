"""The bridge: a discretised structure with a set of material parameters.

Contract
--------
* :class:`Bridge` pairs an immutable :class:`~bwim.fe.model.FEModel` (mesh, supports,
  zones, girders, unit element matrices) with the parameters the calibration estimates:

  ======================  ==============  ===========================================
  name                    shape           meaning
  ======================  ==============  ===========================================
  ``E_x``                 (n_zones,)      longitudinal modulus of each zone, Pa
  ``E_y``                 (n_zones,)      transverse modulus of each zone, Pa (plates)
  ``mu``                  (n_zones,)      mass per area, kg/m² (beams: per length, kg/m)
  ``E_girder``            (n_girders,)    girder modulus, Pa (plates with girders)
  ``mu_girder``           (n_girders,)    girder mass per length, kg/m
  ======================  ==============  ===========================================

  ``with_params`` returns a new bridge sharing the model: nothing is re-integrated.
* Damping is Rayleigh, ``C = α M + β K``, fitted to ``damping_ratio`` at the first two
  modes (docs/theory.md §1.4); modal damping ratios follow from α and β.
* Everything returned is on the model's **free** DOF (constrained DOF removed).
* Derived quantities (K, its factor, M, modes) are computed once per bridge and cached.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from bwim.errors import (
    InputError,
    NumericalError,
    as_floats,
    require_finite,
    require_positive,
    require_range,
)
from bwim.fe.girder import Girder
from bwim.fe.mesh import Grid, grid_lines
from bwim.fe.modal import Modes, lowest_modes
from bwim.fe.model import FEModel, Supports
from bwim.limits import check_memory
from bwim.loads import PointLoad
from bwim.sensors import Sensor

__all__ = ["Bridge", "RayleighDamping"]


@dataclass(frozen=True)
class RayleighDamping:
    """``C = alpha M + beta K``; modal ratio ``ζ(ω) = alpha / (2ω) + beta ω / 2``."""

    alpha: float
    beta: float

    def ratio(self, omega: np.ndarray) -> np.ndarray:
        omega = np.asarray(omega, dtype=float)
        return self.alpha / (2.0 * omega) + 0.5 * self.beta * omega

    @classmethod
    def fit(cls, damping_ratio: float, omega_1: float, omega_2: float) -> RayleighDamping:
        """The coefficients giving ``damping_ratio`` at ``omega_1`` and ``omega_2`` (rad/s)."""
        z = damping_ratio
        if z == 0.0:
            return cls(0.0, 0.0)
        return cls(2 * z * omega_1 * omega_2 / (omega_1 + omega_2), 2 * z / (omega_1 + omega_2))


def _zone_map_plate(grid: Grid, zones: Any) -> tuple[np.ndarray, int]:
    if isinstance(zones, np.ndarray) or (
        isinstance(zones, (list, tuple)) and zones and isinstance(zones[0], (list, tuple))
    ):
        arr = np.asarray(zones)
        if arr.shape != (grid.nx, grid.ny) or not np.issubdtype(arr.dtype, np.integer):
            raise InputError(
                f"zones as an array must be integers of shape (nx, ny) = "
                f"{(grid.nx, grid.ny)}, got shape {arr.shape}"
            )
        labels, inv = np.unique(arr.ravel(), return_inverse=True)
        return inv.ravel(), labels.size
    try:
        nzx, nzy = (int(v) for v in zones)
    except (TypeError, ValueError):
        raise InputError(f"zones must be (nzx, nzy) or an (nx, ny) array, got {zones!r}") from None
    if nzx < 1 or nzy < 1 or nzx > grid.nx or nzy > grid.ny:
        raise InputError(
            f"zones = {(nzx, nzy)} must be at least (1, 1) and at most the element grid "
            f"{(grid.nx, grid.ny)}"
        )
    xc, yc = grid.element_centres()
    zx = np.minimum((xc / grid.length * nzx).astype(int), nzx - 1)
    zy = np.minimum((yc / grid.width * nzy).astype(int), nzy - 1)
    return zx * nzy + zy, nzx * nzy


def _zone_map_beam(grid: Grid, zones: Any) -> tuple[np.ndarray, int]:
    if isinstance(zones, (int, np.integer)):
        if not 1 <= zones <= grid.nx:
            raise InputError(f"zones must be in [1, {grid.nx}], got {zones}")
        xc, _ = grid.element_centres()
        return np.minimum((xc / grid.length * zones).astype(int), zones - 1), int(zones)
    arr = np.asarray(zones)
    if arr.shape != (grid.nx,) or not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"zones for a beam must be an int or {grid.nx} integer labels")
    labels, inv = np.unique(arr, return_inverse=True)
    return inv.ravel(), labels.size


def _structure(grid: Grid, supports: Any, zone_map: tuple[np.ndarray, int], **section: Any
               ) -> FEModel:
    """The FE model of a mesh: ``supports`` parsed, the elements' parameter zones from
    ``zone_map`` (:func:`_zone_map_plate` or :func:`_zone_map_beam`), and the section
    constants (``thickness``, ``poisson``, ``girders`` of a plate; ``inertia``,
    ``z_bottom`` of a beam)."""
    zone_of, n_zones = zone_map
    return FEModel(grid=grid, supports=Supports.parse(supports), zone_of_element=zone_of,
                   n_zones=n_zones, **section)


#: Bounds on a zone's modulus over its mass (Pa per kg/m², or per kg/m for a beam): a
#: concrete slab has about 1e7, a steel beam 1e8; beyond these bounds the eigenvalues
#: (∝ the ratio) over- or underflow double precision in the modal solver.
STIFFNESS_MASS_RANGE = (1e-30, 1e30)


def _param_array(name: str, value: Any, n: int) -> np.ndarray:
    arr = as_floats(name, value, ndmin=1).copy()  # the bridge owns its parameters
    if arr.size == 1 and n != 1:
        arr = np.full(n, arr.item())
    if arr.shape != (n,):
        raise InputError(f"{name} must be a scalar or have shape ({n},), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        bad = arr[~(np.isfinite(arr) & (arr > 0))][0]
        raise InputError(f"{name} must be positive, got {bad:g}")
    return arr


@dataclass(frozen=True, eq=False, kw_only=True)
class Bridge:
    """A bridge finite-element model with its material parameters.

    Build one with :meth:`Bridge.plate` or :meth:`Bridge.beam`; change parameters with
    :meth:`with_params`.  The parameter families' names are the class constants below
    (the module docstring's table).
    """

    #: Every parameter family, in the order of :attr:`params`.
    PARAM_FAMILIES: ClassVar[tuple[str, ...]] = ("E_x", "E_y", "mu", "E_girder", "mu_girder")
    #: The stiffness families (moduli, Pa).
    STIFFNESS_FAMILIES: ClassVar[tuple[str, ...]] = ("E_x", "E_y", "E_girder")
    #: The mass families (kg/m² or kg/m).
    MASS_FAMILIES: ClassVar[tuple[str, ...]] = ("mu", "mu_girder")
    #: The families with one value per girder (the others have one per zone).
    GIRDER_FAMILIES: ClassVar[tuple[str, ...]] = ("E_girder", "mu_girder")

    model: FEModel
    E_x: np.ndarray
    E_y: np.ndarray | None = None
    mu: np.ndarray
    E_girder: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mu_girder: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping_ratio: float = 0.0
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        m = self.model
        set_ = object.__setattr__
        set_(self, "E_x", _param_array("E_x", self.E_x, m.n_zones))
        set_(self, "mu", _param_array("mu", self.mu, m.n_zones))
        if m.is_plate:
            set_(self, "E_y", _param_array("E_y", self.E_y, m.n_zones))
        elif self.E_y is not None:
            raise InputError("a beam bridge has no E_y")
        ng = len(m.girders)
        set_(self, "E_girder", _param_array("E_girder", self.E_girder, ng) if ng else np.zeros(0))
        set_(self, "mu_girder",
             _param_array("mu_girder", self.mu_girder, ng) if ng else np.zeros(0))
        require_range("damping_ratio", self.damping_ratio, 0.0, 1.0, closed=True)
        pairs = [("E_x", self.E_x, "mu", self.mu)]
        if m.is_plate:
            pairs.append(("E_y", self.E_y, "mu", self.mu))
        if ng:
            pairs.append(("E_girder", self.E_girder, "mu_girder", self.mu_girder))
        for e_name, e, m_name, mass in pairs:
            with np.errstate(over="ignore"):
                ratio = e / mass
            bad = ~((ratio > STIFFNESS_MASS_RANGE[0]) & (ratio < STIFFNESS_MASS_RANGE[1]))
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise InputError(
                    f"{e_name} / {m_name} = {ratio[k]:.3g} is outside "
                    f"{STIFFNESS_MASS_RANGE[0]:g} … {STIFFNESS_MASS_RANGE[1]:g}: the natural "
                    f"frequencies would leave floating point (units? E in Pa, mass in kg/m² "
                    "or kg/m)")
        set_(self, "_cache", {})

    # --- constructors ----------------------------------------------------------------
    @classmethod
    def plate(
        cls,
        *,
        length: float,
        width: float,
        nx: int | None = None,
        ny: int | None = None,
        thickness: float,
        mu: float | Sequence[float],
        E: float | None = None,
        E_x: float | Sequence[float] | None = None,
        E_y: float | Sequence[float] | None = None,
        poisson: float = 0.2,
        damping_ratio: float = 0.03,
        supports: Supports | str | Mapping[str, str] = "ss-free",
        girders: Sequence[Girder] = (),
        zones: Any = (1, 1),
        x_lines: Sequence[float] | None = None,
        y_lines: Sequence[float] | None = None,
    ) -> Bridge:
        """An orthotropic Kirchhoff slab deck (BFS elements), optionally on girders.

        Parameters
        ----------
        length, width : float
            Span (x) and deck width (y), m.
        nx, ny : int
            Elements along and across (uniform grid) unless ``x_lines``/``y_lines`` given.
        thickness : float
            Slab thickness h, m (strains are read at h/2 below the mid-plane).
        mu : float or array (n_zones,)
            Mass per unit area, kg/m².
        E : float, optional
            Isotropic modulus, Pa; or give ``E_x`` and ``E_y`` (scalars or per zone).
        poisson : float
            Poisson ratio ν in [0, 0.5).
        damping_ratio : float
            Rayleigh damping ratio at the first two modes.
        supports : str, mapping or Supports
            ``"ss-free"`` (simply supported at x = 0 and x = length, free long edges;
            default), ``"ss-all"``, ``"clamped-free"`` or a mapping per edge.
        girders : sequence of Girder
            Girders along node lines (``y`` must be a grid line).
        zones : (nzx, nzy) or int array (nx, ny)
            Parameter zones: a grid of ``nzx × nzy`` equal zones (by element centre), or an
            explicit zone label per element.  Default one zone.
        x_lines, y_lines : sequence of float, optional
            Explicit (non-uniform) grid lines from 0 to length / width; see
            :func:`bwim.fe.grid_lines`.
        """
        length = require_positive("length", length)
        width = require_positive("width", width)
        thickness = require_positive("thickness", thickness)
        poisson = require_finite("poisson", poisson)
        if not 0.0 <= poisson < 0.5:
            raise InputError(f"poisson must lie in [0, 0.5), got {poisson:g}")
        _check_mesh_memory(_n_elements("nx", nx, x_lines), _n_elements("ny", ny, y_lines))
        xl = _lines("x_lines", "nx", length, nx, x_lines)
        yl = _lines("y_lines", "ny", width, ny, y_lines)
        if E is not None:
            if E_x is not None or E_y is not None:
                raise InputError("give either E or E_x/E_y, not both")
            E_x = E_y = E
        if E_x is None or E_y is None:
            raise InputError("a plate needs E, or both E_x and E_y")
        grid = Grid(xl, yl)
        zone_map = _zone_map_plate(grid, zones)
        girders = tuple(girders)
        for k, gd in enumerate(girders):
            if not isinstance(gd, Girder):
                raise InputError(f"girders[{k}] must be a bwim.Girder, got {type(gd).__name__}")
            if not 0.0 <= gd.y <= width:
                raise InputError(f"girders[{k}].y = {gd.y:g} m is off the deck (width {width:g})")
        model = _structure(grid, supports, zone_map, thickness=thickness, poisson=poisson,
                           girders=girders)
        return cls(
            model=model,
            E_x=E_x,
            E_y=E_y,
            mu=mu,
            E_girder=[gd.E for gd in girders],
            mu_girder=[gd.mu for gd in girders],
            damping_ratio=damping_ratio,
        )

    @classmethod
    def beam(
        cls,
        *,
        length: float,
        n_elements: int | None = None,
        E: float | Sequence[float],
        I: float,
        mu: float | Sequence[float],
        z_bottom: float | None = None,
        damping_ratio: float = 0.03,
        supports: Supports | str | Mapping[str, str] = "ss",
        zones: Any = 1,
        x_lines: Sequence[float] | None = None,
    ) -> Bridge:
        """A 1-D Euler–Bernoulli beam bridge (sensors and wheels ignore y).

        Parameters
        ----------
        length : float
            Span, m.
        n_elements : int
            Number of beam elements (uniform) unless ``x_lines`` given.
        E : float or array (n_zones,)
            Modulus, Pa (the parameter ``E_x``).
        I : float
            Second moment of area, m⁴.
        mu : float or array (n_zones,)
            Mass per unit length, kg/m.
        z_bottom : float, optional
            Distance from the neutral axis to the soffit, m; needed for strain sensors.
        supports : str, mapping or Supports
            ``"ss"`` (simply supported both ends; default), ``"clamped"`` or a mapping with
            edges ``x0`` and ``x_end``.
        zones : int or int array (n_elements,)
            Parameter zones along the span (default one).
        """
        length = require_positive("length", length)
        inertia = require_positive("I", I)
        zb = None if z_bottom is None else require_positive("z_bottom", z_bottom)
        _check_mesh_memory(_n_elements("n_elements", n_elements, x_lines), None)
        grid = Grid(_lines("x_lines", "n_elements", length, n_elements, x_lines))
        model = _structure(grid, supports, _zone_map_beam(grid, zones), inertia=inertia,
                           z_bottom=zb)
        return cls(model=model, E_x=E, mu=mu, damping_ratio=damping_ratio)

    # --- parameters ------------------------------------------------------------------
    @property
    def params(self) -> dict[str, np.ndarray]:
        """The calibratable parameters present on this bridge (copies), in the order of
        :attr:`PARAM_FAMILIES` (``E_y`` on plates only, the girder families with girders)."""
        out = {}
        for name in self.PARAM_FAMILIES:
            value = getattr(self, name)
            if value is not None and value.size:
                out[name] = value.copy()
        return out

    def with_params(self, **params: Any) -> Bridge:
        """A new bridge with some parameters replaced (scalars broadcast over zones)."""
        present = self.params
        unknown = set(params) - set(present)
        if unknown:
            raise InputError(
                f"unknown parameter(s) {sorted(unknown)}; this bridge has {sorted(present)}"
            )
        return dataclasses.replace(self, **params)

    def with_damping(self, damping_ratio: float) -> Bridge:
        return dataclasses.replace(self, damping_ratio=damping_ratio)

    # --- geometry shortcuts ------------------------------------------------------------
    @property
    def is_plate(self) -> bool:
        return self.model.is_plate

    @property
    def length(self) -> float:
        return self.model.grid.length

    @property
    def width(self) -> float:
        return self.model.grid.width

    @property
    def n_zones(self) -> int:
        return self.model.n_zones

    @property
    def n_free(self) -> int:
        return self.model.assembler.n_free

    def _cached(self, key: Any, make: Callable[[], Any]) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # --- matrices ----------------------------------------------------------------------
    def stiffness_banded(self) -> np.ndarray:
        """K on the free DOF in LAPACK lower-banded storage."""
        return self._cached("K_band", lambda: self.model.assembler.stiffness_banded(
            self.model.stiffness_coefficients(self.params)))

    def stiffness_factor(self) -> np.ndarray:
        """Lower banded Cholesky factor of K (for ``scipy.linalg.cho_solve_banded``)."""
        def make() -> np.ndarray:
            try:
                return sla.cholesky_banded(self.stiffness_banded(), lower=True)
            except np.linalg.LinAlgError:
                raise NumericalError(
                    "the stiffness matrix is not positive definite: the supports leave the "
                    "bridge free to move as a mechanism"
                ) from None
        return self._cached("K_factor", make)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``K⁻¹ rhs`` on the free DOF (rhs shape (n_free,) or (n_free, k))."""
        return sla.cho_solve_banded((self.stiffness_factor(), True), rhs, check_finite=False)

    def stiffness_matrix(self) -> sp.csr_matrix:
        """K on the free DOF (CSR)."""
        return self._cached("K", lambda: self.model.assembler.stiffness_csr(
            self.model.stiffness_coefficients(self.params)))

    def mass_matrix(self) -> sp.csr_matrix:
        """M on the free DOF (CSR)."""
        return self._cached("M", lambda: self.model.assembler.mass_csr(
            self.model.mass_coefficients(self.params)))

    def mass_banded(self) -> np.ndarray:
        return self._cached("M_band", lambda: self.model.assembler.mass_banded(
            self.model.mass_coefficients(self.params)))

    @property
    def rayleigh(self) -> RayleighDamping:
        """Rayleigh coefficients fitted to ``damping_ratio`` at the first two modes."""
        def make() -> RayleighDamping:
            if self.damping_ratio == 0.0:
                return RayleighDamping(0.0, 0.0)
            w1, w2 = self.modes(2).omega
            return RayleighDamping.fit(self.damping_ratio, w1, w2)
        return self._cached("rayleigh", make)

    def damping_matrix(self) -> sp.csr_matrix:
        """Rayleigh C on the free DOF (CSR)."""
        r = self.rayleigh
        return (r.alpha * self.mass_matrix() + r.beta * self.stiffness_matrix()).tocsr()

    # --- analyses ----------------------------------------------------------------------
    def modes(self, n: int = 6) -> Modes:
        """The ``n`` lowest natural modes (mass-normalised, Hz ascending)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise InputError(f"n (number of modes) must be a positive integer, got {n!r}")
        if n > self.n_free:
            raise InputError(f"n = {n} modes is more than the model's {self.n_free} degrees "
                             "of freedom")
        n = int(n)
        def make() -> Modes:
            return lowest_modes(
                n, self.stiffness_factor(), self.stiffness_matrix(), self.mass_matrix(),
                self.model.deflection_dofs,
            )
        cached = [k for k in self._cache if isinstance(k, tuple) and k[0] == "modes"
                  and k[1] >= n]
        if cached:
            m = self._cache[min(cached)]
            return Modes(omega=m.omega[:n], shapes=m.shapes[:, :n])
        return self._cached(("modes", n), make)

    def load_vector(self, loads: Sequence[PointLoad]) -> np.ndarray:
        """Consistent nodal load vector of point loads, shape (n_free,)."""
        loads = list(loads)
        for k, ld in enumerate(loads):
            if not isinstance(ld, PointLoad):
                raise InputError(f"loads[{k}] must be a bwim.PointLoad, got {type(ld).__name__}")
        if not loads:
            return np.zeros(self.n_free)
        x = np.array([ld.x for ld in loads])
        y = np.array([ld.y for ld in loads]) if self.is_plate else None
        self.model.check_on_deck("load", x, y)
        return self.model.load_vector(x, y, np.array([ld.P for ld in loads]))

    def static_displacements(self, loads: Sequence[PointLoad]) -> np.ndarray:
        """Static displacements on the free DOF under point loads, shape (n_free,)."""
        return self.solve(self.load_vector(loads))

    def sensor_matrix(self, sensors: Sequence[Sensor]) -> np.ndarray:
        """Rows mapping free-DOF displacements to sensor readings, (n_sensors, n_free)."""
        return self.model.sensor_matrix(sensors)

    def static(self, loads: Sequence[PointLoad], sensors: Sequence[Sensor]) -> np.ndarray:
        """Static sensor readings under point loads, shape (n_sensors,).

        Strains are dimensionless (tension positive), deflections in m (down positive).
        """
        return self.sensor_matrix(sensors) @ self.static_displacements(loads)

    def influence(self, sensors: Sequence[Sensor]):
        """Static influence surfaces of the sensors by reciprocity (docs/theory.md §1.5)."""
        from bwim.fe.influence import influence_surfaces

        return influence_surfaces(self, sensors)


def _n_elements(name: str, n: Any, lines: Any) -> int:
    """Elements along one axis from ``n`` or explicit grid ``lines`` (validated later)."""
    if lines is not None:
        try:
            return max(len(lines) - 1, 1)
        except TypeError:
            raise InputError(f"{name}: the grid lines must be a sequence of numbers") from None
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"{name} must be a positive integer, got {n!r}")
    return int(n)


def _check_mesh_memory(n_x: int, n_y: int | None) -> None:
    """Refuse a mesh whose banded matrices (stiffness, mass, factor) exceed the memory
    limit, before the grid is built: DOF × band × 8 bytes × 4 arrays."""
    if n_y is None:  # beam: 2 DOF per node, half-band 4
        n_dof, band = 2.0 * (n_x + 1), 4.0
        what = f"a beam of {n_x} elements"
    else:  # BFS plate: 4 DOF per node; nodes numbered across the shorter side
        n_dof = 4.0 * (n_x + 1) * (n_y + 1)
        band = 4.0 * (min(n_x, n_y) + 2)
        what = f"a {n_x} × {n_y} element plate"
    check_memory(n_dof * (2 * band + 1) * 8.0 * 4, what)


def _lines(
    lines_name: str, name: str, size: float, n: int | None, lines: Sequence[float] | None
) -> np.ndarray:
    if lines is not None:
        arr = np.asarray(lines, dtype=float)
        if arr.ndim != 1 or arr.size < 2:
            raise InputError(f"{lines_name} must have at least two values")
        if abs(arr[-1] - size) > 1e-9 * size or abs(arr[0]) > 1e-9 * size:
            raise InputError(
                f"{lines_name} must run from 0 to {size:g} m, got {arr[0]:g} … {arr[-1]:g}"
            )
        if n is not None and n != arr.size - 1:
            raise InputError(f"{name} = {n} disagrees with {arr.size - 1} elements in "
                             f"{lines_name}")
        return arr
    if n is None or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"{name} must be a positive integer, got {n!r}")
    return grid_lines(size, int(n), name=name)
