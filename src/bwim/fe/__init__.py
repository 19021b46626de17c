"""The bridge finite-element model: BFS orthotropic plates, girders and 1-D beams."""

from bwim.fe.bridge import Bridge, RayleighDamping
from bwim.fe.girder import CompositeSection, Girder, composite_section
from bwim.fe.influence import (
    InfluenceSurfaces,
    Sensitivities,
    influence_surfaces,
    static_sensitivities,
)
from bwim.fe.mesh import Grid, grid_lines
from bwim.fe.modal import Modes, select_modes
from bwim.fe.model import EdgeSupport, FEModel, Supports

__all__ = [
    "Bridge",
    "CompositeSection",
    "EdgeSupport",
    "FEModel",
    "Girder",
    "Grid",
    "InfluenceSurfaces",
    "Modes",
    "RayleighDamping",
    "Sensitivities",
    "Supports",
    "composite_section",
    "grid_lines",
    "influence_surfaces",
    "select_modes",
    "static_sensitivities",
]
