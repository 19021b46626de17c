"""Vehicle models (moving forces, sprung mass, half car, 3-D trucks) and named vehicles."""

from bwim.vehicles.library import (
    NAMED_VEHICLES,
    named,
    three_axle_truck,
    tractor_semitrailer,
    two_axle_truck,
)
from bwim.vehicles.model import VehicleModel
from bwim.vehicles.types import (
    HalfCar,
    MovingForces,
    SprungMass,
    TractorSemitrailer,
    Truck3D,
    Vehicle,
)

__all__ = [
    "NAMED_VEHICLES",
    "HalfCar",
    "MovingForces",
    "SprungMass",
    "TractorSemitrailer",
    "Truck3D",
    "Vehicle",
    "VehicleModel",
    "named",
    "three_axle_truck",
    "tractor_semitrailer",
    "two_axle_truck",
]
