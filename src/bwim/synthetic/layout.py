"""A simulated installation described as data: slab, lanes, gauges, axle detectors, logger.

Contract
--------
* :class:`SiteLayout` is a frozen description of one B-WIM installation on a solid,
  simply supported slab (``ss-free``: supported at x = 0 and x = ``span``, free edges at
  y = 0 and y = ``width``).  Bridge frame as everywhere in bwim: x (m) along the span from
  the first support in the direction of the ``+x`` lanes, y (m) across from the right-hand
  edge of that direction.  Nothing about a site is a constant in the simulation code: a
  new installation is another :class:`SiteLayout`.
* :class:`Lane`: a lane's number, centre line ``y`` (m), direction (``+1``: vehicles
  travel +x; ``-1``: -x) and its share of the heavy vehicles.
* :class:`Gauge`: a ``strain_x`` soffit gauge (name, x, y).  Each gauge reads the mean of
  the soffit strain over the load's spread through the slab (``load_spread``, m, x × y;
  4 × 4 Gauss–Legendre points), the idea of :mod:`bwim.synthetic.site`: a Kirchhoff
  plate under a point wheel has a log-singular soffit strain, the spread mean converges
  with the mesh.
* :class:`AxleDetector`: a logger channel (name) at (x, y) serving ``lane``; its
  response model is the layout's :class:`~bwim.synthetic.detector.DetectorResponse`.
* :class:`Joint`: a longitudinal joint along ``y`` (m): a strip ``width`` m wide over the
  whole span whose transverse modulus is the slab's × ``stiffness`` (a construction joint
  that passes less bending across it; :mod:`bwim.fe.joints`).  None by default.
* :class:`Continuity`: the slab continuous over both supports into side spans (e.g. a
  multi-span slab, or approach slabs and abutments that carry moment), None by default.
  A load beyond a support then bends the span the other way (the influence lines have
  a lobe of the opposite sign outside the span).  :class:`ContinuousSpan` gives its
  static influence surfaces by the flexibility method: the slab with its side spans,
  simply supported at the far ends, with the deflection of every node on the two inner
  support lines released to zero by point reactions (``I = E − wᵀ F⁻¹ E_s``: ``E`` the
  sensors' and ``w`` the support nodes' influence on the long slab, ``F`` the support
  nodes' flexibility, ``E_s`` the sensors' readings under a unit load on each support
  node).
* ``columns``: the logger file's columns in order (``"time"``, channel names, ``"-"`` for
  a column the weighing skips, e.g. a digital status).
* **Mirror frame.**  The slab and its supports are symmetric under x → span − x, so a
  vehicle travelling -x is simulated as a +x vehicle in the mirrored frame with every
  sensor at x' = span − x (:meth:`SiteLayout.gauge_points` with ``mirrored=True``);
  its readings are the real sensors' readings.

:data:`SHORT_SPAN_4_LANE` is the realistic preset (issue 20: the measured layout of a real
installation; lane centre lines assumed, see its ``note``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_positive
from bwim.fe.bridge import Bridge
from bwim.fe.joints import with_joints
from bwim.fe.mesh import grid_lines
from bwim.sensors import Sensor
from bwim.synthetic.detector import DetectorResponse

__all__ = ["SHORT_SPAN_4_LANE", "AxleDetector", "Continuity", "ContinuousSpan", "Gauge",
           "GaugePoints", "Lane", "SiteLayout"]

SPREAD_POINTS = 4  #: Gauss points per direction of a gauge's load-spread mean


@dataclass(frozen=True, kw_only=True)
class Lane:
    """A traffic lane: its number, centre line y (m), direction of travel (+1 / -1) and
    share of the site's heavy vehicles (the shares of a layout sum to 1)."""

    number: int
    y: float
    direction: int
    heavy_share: float

    @property
    def direction_name(self) -> str:
        return "+x" if self.direction > 0 else "-x"


@dataclass(frozen=True, kw_only=True)
class Gauge:
    """A longitudinal (``strain_x``) soffit gauge at (x, y), m."""

    name: str
    x: float
    y: float


@dataclass(frozen=True, kw_only=True)
class AxleDetector:
    """An axle-detector channel at (x, y), m, serving ``lane``."""

    name: str
    lane: int
    x: float
    y: float


@dataclass(frozen=True, kw_only=True)
class Joint:
    """A longitudinal joint: centre line ``y`` (m), strip ``width`` (m) and the strip's
    transverse modulus over the slab's (``stiffness``)."""

    y: float
    stiffness: float
    width: float = 0.3


@dataclass(frozen=True, kw_only=True)
class Continuity:
    """The slab continuous over both supports into side spans of ``side_span`` m (the same
    slab, simply supported at their far ends)."""

    side_span: float


@dataclass(frozen=True, kw_only=True, eq=False)
class ContinuousSpan:
    """Static influence surfaces of sensors on a span continuous over its two supports
    (see the module docstring): the span's frame, x from its first support."""

    surfaces: object  #: InfluenceSurfaces of the sensors then the support nodes' deflection
    offset: float  #: x of the span's first support on the long slab, m
    n_sensors: int
    release: np.ndarray  #: F⁻¹ E_s, shape (n_support_nodes, n_sensors)

    @classmethod
    def build(cls, long_slab: Bridge, sensors, *, offset: float, span: float
              ) -> ContinuousSpan:
        """The surfaces of ``sensors`` (placed on ``long_slab``, m) with the nodes of the
        lines x = ``offset`` and ``offset + span`` held at zero deflection."""
        grid = long_slab.model.grid
        xs = [x for x in (offset, offset + span)
              if np.min(np.abs(grid.x_lines - x)) > 1e-9]
        if xs:
            raise InputError(f"the support line x = {xs[0]:g} m is not a node line of the "
                             "long slab")
        ys = grid.y_lines if long_slab.is_plate else np.array([0.0])
        sx = np.repeat([offset, offset + span], ys.size)
        sy = np.tile(ys, 2)
        support = [Sensor(x=float(x), y=float(y) if long_slab.is_plate else None,
                          kind="deflection", name=f"support{k}")
                   for k, (x, y) in enumerate(zip(sx, sy, strict=True))]
        sensors = tuple(sensors)
        surfaces = long_slab.influence([*sensors, *support])
        at = surfaces.at(sx, sy if long_slab.is_plate else None)
        n = len(sensors)
        release = np.linalg.solve(at[:, n:], at[:, :n])  # F is symmetric (reciprocity)
        return cls(surfaces=surfaces, offset=float(offset), n_sensors=n, release=release)

    def at(self, x: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """Ordinates (reading per newton) at points ``x`` (the span's frame, m) and ``y``,
        shape (n_points, n_sensors); zero beyond the side spans."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        o = self.surfaces.at(x + self.offset, y)
        return o[:, :self.n_sensors] - o[:, self.n_sensors:] @ self.release


@dataclass(frozen=True, kw_only=True, eq=False)
class GaugePoints:
    """Soffit points that gauges average, and the averaging matrix.

    ``readings = point_readings @ weights``: ``weights`` has shape
    (n_points, n_gauges) and each column sums to 1.
    """

    points: tuple[Sensor, ...]
    weights: np.ndarray


@dataclass(frozen=True, kw_only=True)
class SiteLayout:
    """One installation (see the module docstring).  Lengths in m, E in Pa, kg/m³."""

    name: str
    span: float
    width: float
    thickness: float
    modulus: float
    poisson: float
    density: float
    damping_ratio: float
    lanes: tuple[Lane, ...]
    gauges: tuple[Gauge, ...]
    detectors: tuple[AxleDetector, ...]
    detector_response: DetectorResponse
    columns: tuple[str, ...]
    sampling_rate: float = 512.0
    load_spread: tuple[float, float] = (0.75, 0.85)
    joints: tuple[Joint, ...] = ()
    continuity: Continuity | None = None
    note: str = ""

    def __post_init__(self) -> None:
        for key in ("span", "width", "thickness", "modulus", "density", "sampling_rate"):
            require_positive(key, getattr(self, key))
        if not 0 <= self.damping_ratio < 1 or not 0 <= self.poisson < 0.5:
            raise InputError(f"layout {self.name}: damping ratio or Poisson ratio out of range")
        numbers = [ln.number for ln in self.lanes]
        if len(set(numbers)) != len(numbers) or not numbers:
            raise InputError(f"layout {self.name}: lane numbers must be unique, got {numbers}")
        for ln in self.lanes:
            if ln.direction not in (1, -1) or not 0 < ln.y < self.width:
                raise InputError(f"layout {self.name}: lane {ln.number} needs a direction "
                                 f"of +1 or -1 and 0 < y < {self.width:g}")
        shares = [ln.heavy_share for ln in self.lanes]
        if min(shares) < 0 or abs(sum(shares) - 1.0) > 1e-9:
            raise InputError(f"layout {self.name}: lane heavy shares must be >= 0 and sum "
                             f"to 1, got {shares}")
        for s in (*self.gauges, *self.detectors):
            if not (0 < s.x < self.span and 0 < s.y < self.width):
                raise InputError(f"layout {self.name}: {s.name} at ({s.x:g}, {s.y:g}) is off "
                                 "the deck")
        for d in self.detectors:
            if d.lane not in numbers:
                raise InputError(f"layout {self.name}: {d.name} serves unknown lane {d.lane}")
        for n in {d.lane for d in self.detectors}:
            if len(self.lane_detectors(n)) != 2:
                raise InputError(f"layout {self.name}: lane {n} needs two axle detectors")
        for j in self.joints:
            if not (j.width > 0 and j.stiffness > 0 and j.width / 2 < j.y < self.width
                    - j.width / 2):
                raise InputError(f"layout {self.name}: a joint needs a positive width and "
                                 f"stiffness and its strip on the deck, got {j}")
        if self.continuity is not None:
            if not self.continuity.side_span > 0:
                raise InputError(f"layout {self.name}: continuity needs side spans > 0 m, "
                                 f"got {self.continuity.side_span!r}")
            if self.joints:
                raise InputError(f"layout {self.name}: continuity with joints is not "
                                 "modelled")
        names = [*(g.name for g in self.gauges), *(d.name for d in self.detectors)]
        if len(set(names)) != len(names):
            raise InputError(f"layout {self.name}: channel names must be unique")
        if (self.columns.count("time") != 1 or self.columns[0] != "time"
                or sorted(c for c in self.columns if c not in ("time", "-")) != sorted(names)):
            raise InputError(f"layout {self.name}: columns must start with 'time' and name "
                             "every gauge and detector once ('-' for other columns)")

    # --- lanes and detectors ---------------------------------------------------------------
    def lane(self, number: int) -> Lane:
        for ln in self.lanes:
            if ln.number == number:
                return ln
        raise InputError(f"layout {self.name} has no lane {number}")

    def lane_detectors(self, number: int) -> tuple[AxleDetector, ...]:
        """The lane's detectors in the order its traffic meets them."""
        direction = self.lane(number).direction
        mine = [d for d in self.detectors if d.lane == number]
        return tuple(sorted(mine, key=lambda d: direction * d.x))

    @property
    def detector_lanes(self) -> tuple[int, ...]:
        """Lanes with axle detectors, in lane order."""
        return tuple(sorted({d.lane for d in self.detectors}))

    # --- finite elements -------------------------------------------------------------------
    def bridge(self, mesh: float) -> Bridge:
        """The slab on a grid of elements at most ``mesh`` m square (uniform; with joints,
        grid lines at each joint strip's edges and a zone per joint)."""
        mesh = require_positive("mesh", mesh)
        nx = max(int(np.ceil(self.span / mesh - 1e-9)), 2)
        ny = max(int(np.ceil(self.width / mesh - 1e-9)), 2)
        edges = sorted(y for j in self.joints for y in (j.y - j.width / 2, j.y + j.width / 2))
        y_lines = grid_lines(self.width, max(ny, len(edges) + 1), through=edges) if edges \
            else None
        plate = Bridge.plate(length=self.span, width=self.width, nx=nx,
                             ny=None if edges else ny, y_lines=y_lines,
                             thickness=self.thickness, mu=self.density * self.thickness,
                             E=self.modulus, poisson=self.poisson,
                             damping_ratio=self.damping_ratio)
        if not self.joints:
            return plate
        return with_joints(plate, [j.y for j in self.joints],
                           [j.stiffness for j in self.joints])

    def continuous_span(self, mesh: float, sensors) -> ContinuousSpan:
        """The static influence surfaces of ``sensors`` (real frame) with the slab
        continuous into its side spans (:attr:`continuity`), on elements of at most
        ``mesh`` m (node lines on both supports)."""
        if self.continuity is None:
            raise InputError(f"layout {self.name} has no continuity")
        mesh = require_positive("mesh", mesh)
        a = float(self.continuity.side_span)

        def piece(x0: float, length: float, first: bool) -> np.ndarray:
            n = max(int(np.ceil(length / mesh - 1e-9)), 1)
            return x0 + np.linspace(0.0, length, n + 1)[0 if first else 1:]

        x_lines = np.concatenate([piece(0.0, a, True), piece(a, self.span, False),
                                  piece(a + self.span, a, False)])
        ny = max(int(np.ceil(self.width / mesh - 1e-9)), 2)
        slab = Bridge.plate(length=self.span + 2 * a, width=self.width, ny=ny,
                            x_lines=x_lines, thickness=self.thickness,
                            mu=self.density * self.thickness, E=self.modulus,
                            poisson=self.poisson, damping_ratio=self.damping_ratio)
        moved = [Sensor(x=s.x + a, y=s.y, kind=s.kind, name=s.name) for s in sensors]
        return ContinuousSpan.build(slab, moved, offset=a, span=self.span)

    def spread_points(self, locations, *, mirrored: bool = False,
                      prefix: str = "p") -> GaugePoints:
        """Load-spread points of gauges at ``locations`` ((x, y) pairs, m) in the real
        frame, or in the mirrored frame (x' = span − x) when ``mirrored``."""
        q, w = np.polynomial.legendre.leggauss(SPREAD_POINTS)
        dx, dy = np.meshgrid(q * self.load_spread[0] / 2, q * self.load_spread[1] / 2,
                             indexing="ij")
        ww = np.outer(w, w).ravel() / 4.0
        locations = list(locations)
        pts = []
        weights = np.zeros((len(locations) * ww.size, len(locations)))
        for j, (x, y) in enumerate(locations):
            xc = self.span - x if mirrored else x
            for k, (a, b) in enumerate(zip(dx.ravel(), dy.ravel(), strict=True)):
                pts.append(Sensor(x=xc + a, y=y + b, kind="strain_x", name=f"{prefix}{j}.{k}"))
            weights[j * ww.size:(j + 1) * ww.size, j] = ww
        return GaugePoints(points=tuple(pts), weights=weights)

    def gauge_points(self, *, mirrored: bool = False) -> GaugePoints:
        """The gauges' load-spread points (real or mirrored frame)."""
        return self.spread_points([(g.x, g.y) for g in self.gauges], mirrored=mirrored,
                                  prefix="g")


_GAUGE_Y = (4.50, 5.18, 5.86, 6.55, 7.23, 7.91, 8.59, 9.27, 9.95, 10.64, 11.32, 12.00)

#: The realistic preset (issue 20's measured layout; see ``note``).
SHORT_SPAN_4_LANE = SiteLayout(
    name="short-span-4-lane",
    span=6.0, width=15.55, thickness=0.45, modulus=35e9, poisson=0.2, density=2400.0,
    damping_ratio=0.03,
    lanes=(Lane(number=1, y=5.2, direction=1, heavy_share=0.50),
           Lane(number=2, y=7.9, direction=1, heavy_share=0.08),
           Lane(number=3, y=10.64, direction=-1, heavy_share=0.35),
           Lane(number=4, y=13.35, direction=-1, heavy_share=0.07)),
    gauges=tuple(Gauge(name=f"s{k + 1:02d}", x=3.0, y=y) for k, y in enumerate(_GAUGE_Y)),
    detectors=(AxleDetector(name="ad1", lane=1, x=1.5, y=5.2),
               AxleDetector(name="ad2", lane=1, x=4.5, y=5.2),
               AxleDetector(name="ad3", lane=3, x=1.5, y=10.64),
               AxleDetector(name="ad4", lane=3, x=4.5, y=10.64)),
    detector_response=DetectorResponse(),
    columns=("time", "ad1", "ad2", *(f"s{k:02d}" for k in range(1, 13)), "ad3", "ad4",
             "-", "-"),
    note=("Measured facts (issue 20): span, width, thickness, gauge and detector positions, "
          "columns, 512 Hz.  Assumed: lane centre lines 1-4 at y = 5.2, 7.9, 10.64, 13.35 m "
          "(lanes 1 and 3 at their detectors' y), E = 35 GPa, 2400 kg/m3, 3 % damping; "
          "heavy vehicles 50/8/35/7 % in lanes 1-4 (lanes 1 and 3, the lanes with "
          "detectors, carry each direction's heavy traffic)."),
)
