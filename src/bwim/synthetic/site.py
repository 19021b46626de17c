"""The simulated installation: a short-span slab, its gauges, axle detectors and drift.

Contract
--------
* The bridge is a solid, simply supported slab (``ss-free``): span :data:`SPAN` = 9.0 m,
  width :data:`WIDTH` = 10.0 m, thickness :data:`THICKNESS` = 0.55 m, E = 35 GPa,
  ν = 0.2, 2400 kg/m³ (μ = 1320 kg/m²), 3 % Rayleigh damping.  :func:`site_bridge` meshes
  it with square-ish BFS elements of about ``mesh`` m (the *data* mesh; 0.25 m by default,
  finer than any model used to weigh: influence lines are calibrated from data, and a
  moving-force identification would use a coarser plate, e.g. 0.75 m).
* Two lanes, both travelled in +x: centre lines at :data:`LANE_Y` = (3.0, 6.5) m from the
  right-hand edge (y = 0).
* Fourteen ``strain_x`` gauges ``s01 … s14`` on the soffit at mid-span (x = 4.5 m), evenly
  across the width from y = 0.5 m to y = 9.5 m (``s01`` nearest the right-hand edge).
* **Load spread through the thickness.**  A Kirchhoff plate under a point wheel load has a
  logarithmically singular soffit strain under the load, so a gauge under a wheel path
  would read a mesh-dependent spike (+13 % from a 0.5 m to a 0.1 m mesh, measured).  A real
  wheel acts on a tyre patch and the load spreads at about 45° to the mid-plane, over
  roughly (patch + h): :data:`SPREAD` = 0.75 m (x) × 0.85 m (y).  The plate is
  translation-invariant enough near mid-span that spreading the *load* over that area is
  the same as averaging the *gauge* over it (reciprocity; checked: within 0.6 % of a
  uniformly spread load at every wheel position, 0.25 m and 0.1 m meshes).  So each gauge
  reads the weighted mean of a 4 × 4 Gauss–Legendre grid of soffit points over the spread
  area (:func:`gauge_points`), and wheels stay single contacts with the usual tyre
  dynamics.  The patch reading converges with the mesh (10.9 µε at 0.25 m and 0.1 m
  meshes for 50 kN over a gauge) where the point reading does not (15.3 / 17.5 µε).
* Axle detectors ``ad1`` at x = 0 (the bridge's first support) and ``ad2`` at x = 3.0 m,
  across the whole width.  Each responds to every axle as
  ``gain × F_axle(t) / 1 kN × K(x_axle(t) − x_d)`` with the Hann kernel
  ``K(u) = cos²(π u / w)`` for ``|u| < w / 2`` (0 beyond), ``w`` = :data:`DETECTOR_WIDTH`
  = 0.3 m (:func:`detector_kernel`).
* :class:`Drift` is the bridge's strain-to-load factor over the day (temperature-like):
  ``1 + amplitude × s(t)``, ``s`` a smooth function of clock time normalised so that
  ``max |s| = 1`` over the day window :data:`DAY` (06:00–20:00): ``0.75`` of a 24 h
  sinusoid peaking at 15:00 plus ``0.25`` of three random sinusoids of 2–6 h periods.
  Clock time is seconds since midnight.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_positive
from bwim.fe.bridge import Bridge
from bwim.sensors import Sensor

__all__ = [
    "DAY",
    "DETECTOR_NAMES",
    "DETECTOR_WIDTH",
    "DETECTOR_X",
    "GAUGE_NAMES",
    "GAUGE_X",
    "GAUGE_Y",
    "LANE_Y",
    "SPAN",
    "SPREAD",
    "THICKNESS",
    "WIDTH",
    "Drift",
    "GaugeSpread",
    "detector_kernel",
    "gauge_points",
    "site_bridge",
]

SPAN = 9.0  #: m
WIDTH = 10.0  #: m
THICKNESS = 0.55  #: m
MODULUS = 35e9  #: Pa (concrete)
POISSON = 0.2
DENSITY = 2400.0  #: kg/m³ (μ = DENSITY × THICKNESS)
DAMPING_RATIO = 0.03

LANE_Y = (3.0, 6.5)  #: m, lane centre lines from the right-hand edge

GAUGE_X = SPAN / 2  #: m
GAUGE_Y = tuple(float(v) for v in np.linspace(0.5, 9.5, 14))  #: m
GAUGE_NAMES = tuple(f"s{k + 1:02d}" for k in range(14))
SPREAD = (0.75, 0.85)  #: m, (x, y) extent of the through-thickness load spread
SPREAD_POINTS = 4  #: Gauss points per direction

DETECTOR_NAMES = ("ad1", "ad2")
DETECTOR_X = (0.0, 3.0)  #: m
DETECTOR_WIDTH = 0.3  #: m, full width of the detector's response to an axle

DAY = (6 * 3600.0, 20 * 3600.0)  #: s, clock window of the test day


def site_bridge(mesh: float = 0.25) -> Bridge:
    """The slab on a uniform grid of elements about ``mesh`` m (at most ``mesh``) square."""
    mesh = require_positive("mesh", mesh)
    nx = max(int(np.ceil(SPAN / mesh - 1e-9)), 2)
    ny = max(int(np.ceil(WIDTH / mesh - 1e-9)), 2)
    return Bridge.plate(length=SPAN, width=WIDTH, nx=nx, ny=ny, thickness=THICKNESS,
                        mu=DENSITY * THICKNESS, E=MODULUS, poisson=POISSON,
                        damping_ratio=DAMPING_RATIO)


@dataclass(frozen=True, kw_only=True, eq=False)
class GaugeSpread:
    """The soffit points each gauge averages, and the averaging matrix.

    Attributes
    ----------
    points : tuple of Sensor
        ``14 × 16`` strain_x points, gauge by gauge.
    weights : ndarray, shape (14 × 16, 14)
        Gauge readings are ``point_readings @ weights`` (each column sums to 1).
    """

    points: tuple[Sensor, ...]
    weights: np.ndarray


def gauge_points() -> GaugeSpread:
    """The :class:`GaugeSpread` of the site's gauges (the load spread through the slab)."""
    q, w = np.polynomial.legendre.leggauss(SPREAD_POINTS)
    dx, dy = np.meshgrid(q * SPREAD[0] / 2, q * SPREAD[1] / 2, indexing="ij")
    ww = np.outer(w, w).ravel() / 4.0
    pts = []
    weights = np.zeros((len(GAUGE_Y) * ww.size, len(GAUGE_Y)))
    for j, (name, y) in enumerate(zip(GAUGE_NAMES, GAUGE_Y, strict=True)):
        for k, (a, b) in enumerate(zip(dx.ravel(), dy.ravel(), strict=True)):
            pts.append(Sensor(x=GAUGE_X + a, y=y + b, kind="strain_x", name=f"{name}.{k}"))
        weights[j * ww.size:(j + 1) * ww.size, j] = ww
    return GaugeSpread(points=tuple(pts), weights=weights)


def detector_kernel(u: np.ndarray) -> np.ndarray:
    """The detector's response to a unit axle at distance ``u`` (m) from it."""
    u = np.asarray(u, dtype=float)
    return np.where(np.abs(u) < DETECTOR_WIDTH / 2, np.cos(np.pi * u / DETECTOR_WIDTH) ** 2,
                    0.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class Drift:
    """The bridge's strain-to-load factor as a function of clock time (see module)."""

    amplitude: float
    periods: np.ndarray  #: s, of the random components
    phases: np.ndarray  #: rad
    weights: np.ndarray  #: relative amplitudes of the random components (sum 1)
    norm: float  #: max |raw shape| over :data:`DAY`

    @classmethod
    def random(cls, amplitude: float, rng: np.random.Generator) -> Drift:
        """A drift of the given amplitude (fraction, e.g. 0.08) with random components."""
        if not np.isfinite(amplitude) or not 0 <= amplitude < 1:
            raise InputError(f"drift must be a fraction in [0, 1), got {amplitude!r}")
        periods = rng.uniform(2.0, 6.0, 3) * 3600.0
        phases = rng.uniform(0.0, 2 * np.pi, 3)
        weights = rng.uniform(0.5, 1.0, 3)
        weights = weights / weights.sum()
        t = np.linspace(*DAY, 50401)  # 1 s steps
        raw = _shape(t, periods, phases, weights)
        return cls(amplitude=float(amplitude), periods=periods, phases=phases,
                   weights=weights, norm=float(np.abs(raw).max()))

    def factor(self, clock: np.ndarray | float) -> np.ndarray:
        """Strain factor at clock times (s since midnight)."""
        raw = _shape(np.asarray(clock, dtype=float), self.periods, self.phases, self.weights)
        return 1.0 + self.amplitude * raw / self.norm


def _shape(t, periods, phases, weights):
    daily = np.sin(2 * np.pi * (t - 9 * 3600.0) / 86400.0)  # peaks at 15:00
    rand = sum(w * np.sin(2 * np.pi * t / p + f)
               for p, f, w in zip(periods, phases, weights, strict=True))
    return 0.75 * daily + 0.25 * rand
