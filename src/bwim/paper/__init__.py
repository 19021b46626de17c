"""The bridges, sensors and calibration-truck data of Dowling, OBrien & González (2012).

Every value the paper leaves unstated is *assumed* here, once, with the reason; the rest of
bwim (tests, benchmarks, the demo, the reproductions) takes them from this module.  The
cases, the assumed values beside the paper's and what "reproduced" means are in
``docs/paper_cases.md``.

The paper stands apart from the library: this package holds its data (this module), its
§5 experiments (:mod:`bwim.paper.reproduce`) and the demo (:mod:`bwim.paper.demo`).  The
library never imports the package's submodules, and ``import bwim`` loads only this one.

Contract
--------
Units follow :mod:`bwim.conventions`.  The paper prints its flexural parameters as
"EI = 35 × 10⁹ N m²"; they only fit its strains as the **moduli** E of a solid slab, which
is how they are used here.  Every function returns a new object (no shared state).
"""

from __future__ import annotations

import numpy as np

from bwim.dynamics.crossing import DEFAULT_APPROACH, DEFAULT_SAMPLING_RATE
from bwim.fe.bridge import Bridge
from bwim.fe.girder import Girder, composite_section
from bwim.fe.mesh import grid_lines
from bwim.road import RoadProfile
from bwim.sensors import Sensor
from bwim.vehicles.library import two_axle_truck
from bwim.vehicles.types import Truck3D

__all__ = [
    "AXLE_LOADS",
    "AXLE_SPACING",
    "LANE",
    "SPEED",
    "TRACK_WIDTH",
    "road",
    "sensors",
    "slab_bridge",
    "truck",
    "vransko_bridge",
    "vransko_sensors",
    "zoned_bridges",
]

# --- the 12 m × 8 m slab bridge (paper §5.1–5.3) ----------------------------------------
SLAB_LENGTH = 12.0  #: m (paper)
SLAB_WIDTH = 8.0  #: m (paper)
SLAB_E = 35e9  #: Pa, true E_x = E_y (paper, read as a modulus)
SLAB_MU = 1560.0  #: kg/m² (paper)
SLAB_THICKNESS = 0.65  #: m, *assumed*: μ / 2400 kg/m³ (concrete)
SLAB_POISSON = 0.2  #: *assumed*: concrete
DAMPING_RATIO = 0.03  #: *assumed*: 3 % at the first two modes

#: Sensor grid of §5.1: ¼, ½, ¾ span × 2, 4, 6 m from the right-hand edge (paper).
SENSOR_X = (3.0, 6.0, 9.0)
SENSOR_Y = (2.0, 4.0, 6.0)

# --- the calibration truck (paper §5.1) --------------------------------------------------
AXLE_LOADS = (59.5e3, 108.6e3)  #: N, static axle loads (paper)
AXLE_SPACING = 5.5  #: m (paper)
SPEED = 20.0  #: m/s (paper)
LANE = 2.0  #: m, vehicle centre line from the right-hand edge, *assumed*
TRACK_WIDTH = 2.0  #: m, *assumed*
SAMPLING_RATE = DEFAULT_SAMPLING_RATE  #: Hz, *assumed* (the library's default)

# --- the road (paper §2, §5.1) -----------------------------------------------------------
ROUGHNESS = 65e-6  #: m³/cycle, G_d(n₀) (paper; its "class C", ISO's class B mean)
APPROACH = DEFAULT_APPROACH  #: m of run-up before the bridge, *assumed* (the default)
TYRE_PATCH = 0.24  #: m, moving-average tyre contact length, *assumed* (usual value)

# --- the beam-and-slab bridge after Vransko (paper §5.4) ---------------------------------
VRANSKO_LENGTH = 24.8  #: m (paper)
VRANSKO_WIDTH = 12.07  #: m (paper)
VRANSKO_SLAB_E = 31.0e9  #: Pa (paper, Table 2)
VRANSKO_SLAB_MU = 576.0  #: kg/m² (paper, Table 2)
VRANSKO_SLAB_THICKNESS = 0.24  #: m, *assumed*: μ / 2400 kg/m³
VRANSKO_GIRDER_E = 35.0e9  #: Pa (paper, Table 2)
VRANSKO_GIRDER_MU = 1373.0  #: kg/m (paper, Table 2)
VRANSKO_GIRDER_SPACING = 2.5  #: m, *assumed*
VRANSKO_OVERHANG = 1.035  #: m, *assumed*: (12.07 − 4 × 2.5) / 2
#: Bare precast girder, *assumed*: area from μ_b at 2500 kg/m³ (prestressed concrete);
#: an I-section 1.2 m deep with its centroid 0.55 m above the soffit.
VRANSKO_GIRDER_AREA = VRANSKO_GIRDER_MU / 2500.0  #: m²
VRANSKO_GIRDER_DEPTH = 1.2  #: m, *assumed*
VRANSKO_GIRDER_INERTIA = 0.095  #: m⁴, *assumed*
VRANSKO_GIRDER_CENTROID = 0.55  #: m above the girder soffit, *assumed*
VRANSKO_GIRDER_TORSION = 0.015  #: m⁴ St-Venant constant, *assumed*
VRANSKO_SENSOR_X = (7.44, 12.4, 17.36)  #: m, 4th, 6th and 8th node lines (paper)


def slab_bridge(
    *,
    nx: int = 12,
    ny: int = 8,
    zones: tuple[int, int] = (1, 1),
    damping_ratio: float = DAMPING_RATIO,
) -> Bridge:
    """The 12 m × 8 m solid slab of §5.1–5.3 with its true properties.

    Simply supported at x = 0 and x = 12 m, free long edges, 1 m × 1 m BFS elements by
    default; ``zones=(4, 4)`` gives the 3 m × 2 m zones of §5.3.
    """
    return Bridge.plate(
        length=SLAB_LENGTH, width=SLAB_WIDTH, nx=nx, ny=ny, thickness=SLAB_THICKNESS,
        E=SLAB_E, mu=SLAB_MU, poisson=SLAB_POISSON, damping_ratio=damping_ratio,
        supports="ss-free", zones=zones,
    )


def truck() -> Truck3D:
    """The paper's 2-axle calibration truck (see :func:`bwim.vehicles.two_axle_truck`)."""
    return two_axle_truck()


def road(seed: int = 1, *, approach: float = APPROACH, length: float = 40.0) -> RoadProfile:
    """The paper's road: G_d(n₀) = 65 × 10⁻⁶ m³/cycle, carpet, smoothed over the tyre patch.

    It covers the approach, a ``length`` m span and a long vehicle (20 m) with a margin,
    so any of the paper's crossings (and the named vehicles) fit on it.
    """
    start = -(approach + 25.0)
    total = approach + 25.0 + length + 5.0
    return RoadProfile.iso8608(ROUGHNESS, length=total, start=start, seed=seed).smoothed(
        TYRE_PATCH)


def sensors() -> list[Sensor]:
    """The 18 channels of §5.1: longitudinal then transverse strain at 9 locations."""
    out = []
    for kind in ("strain_x", "strain_y"):
        for x in SENSOR_X:
            for y in SENSOR_Y:
                out.append(Sensor(x=x, y=y, kind=kind, name=f"{kind[-1]}{x:g}_{y:g}"))
    return out


def _vransko_girder_y() -> np.ndarray:
    return VRANSKO_OVERHANG + VRANSKO_GIRDER_SPACING * np.arange(5)


def vransko_bridge(*, damping_ratio: float = DAMPING_RATIO) -> Bridge:
    """The beam-and-slab bridge of §5.4: 10 × 10 plate elements and five girders.

    Elements are 2.48 m long; across, one element outside each outer girder and two between
    adjacent girders.  Each girder acts with a slab width equal to its tributary width;
    see :func:`bwim.fe.composite_section` (the slab's own bending stays in the plate).
    """
    gy = _vransko_girder_y()
    y_lines = grid_lines(VRANSKO_WIDTH, 10, through=gy.tolist(), name="ny")
    girders = []
    for k, y in enumerate(gy):
        left = VRANSKO_OVERHANG if k == 4 else VRANSKO_GIRDER_SPACING / 2
        right = VRANSKO_OVERHANG if k == 0 else VRANSKO_GIRDER_SPACING / 2
        sec = composite_section(
            girder_area=VRANSKO_GIRDER_AREA, girder_inertia=VRANSKO_GIRDER_INERTIA,
            girder_depth=VRANSKO_GIRDER_DEPTH, girder_centroid_height=VRANSKO_GIRDER_CENTROID,
            slab_width=left + right, slab_thickness=VRANSKO_SLAB_THICKNESS,
            modular_ratio=VRANSKO_SLAB_E / VRANSKO_GIRDER_E,
        )
        girders.append(Girder(y=float(y), I=sec.I, z_bottom=sec.z_bottom, E=VRANSKO_GIRDER_E,
                              mu=VRANSKO_GIRDER_MU, J=VRANSKO_GIRDER_TORSION))
    return Bridge.plate(
        length=VRANSKO_LENGTH, width=VRANSKO_WIDTH, nx=10, y_lines=y_lines,
        thickness=VRANSKO_SLAB_THICKNESS, E=VRANSKO_SLAB_E, mu=VRANSKO_SLAB_MU,
        poisson=SLAB_POISSON, damping_ratio=damping_ratio, girders=girders,
    )


def vransko_sensors() -> list[Sensor]:
    """The 27 longitudinal strain channels of §5.4: 3 sections × (5 girders + 4 slab
    mid-points between girders); a sensor on a girder line reads the girder soffit."""
    gy = _vransko_girder_y()
    ys = np.sort(np.concatenate([gy, 0.5 * (gy[:-1] + gy[1:])]))
    return [Sensor(x=x, y=float(y), kind="strain_x", name=f"x{x:g}_{float(y):g}")
            for x in VRANSKO_SENSOR_X for y in ys]


#: §5.3: standard deviations of the zone moduli of bridges #1–#6, as fractions of the mean.
ZONE_SPREADS = (0.0, 0.05, 0.10, 0.15, 0.20, 0.25)
ZONES = (4, 4)  #: §5.3: 3 m × 2 m zones


def zoned_bridges(seed: int = 0) -> list[Bridge]:
    """The six bridges of §5.3: 4 × 4 zones whose E_x and E_y are drawn independently from
    normal distributions with mean 35 GPa and standard deviation 0, 5, …, 25 % (bridges
    #1–#6), μ = 1560 kg/m² everywhere; 1 m elements, so the nine sensors sit on the
    interior zone corners.  Draws are clipped to ≥ 30 % of the mean (a modulus must stay
    positive; at 25 % spread this is 2.8 standard deviations).
    """
    rng = np.random.default_rng(seed)
    base = slab_bridge(zones=ZONES)
    out = []
    for spread in ZONE_SPREADS:
        ex = SLAB_E * np.maximum(1.0 + spread * rng.standard_normal(base.n_zones), 0.3)
        ey = SLAB_E * np.maximum(1.0 + spread * rng.standard_normal(base.n_zones), 0.3)
        out.append(base.with_params(E_x=ex, E_y=ey))
    return out
