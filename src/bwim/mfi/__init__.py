"""First-order moving force identification (MFI)."""

from bwim.mfi.dp import solve_batch, solve_dp
from bwim.mfi.identify import ForceIdentification, identify_forces, record_band
from bwim.mfi.lcurve import LCurve
from bwim.mfi.metrics import ForceErrors, force_errors
from bwim.mfi.statespace import ForceUnknowns, MFIModel, Order, build_model

__all__ = [
    "ForceErrors",
    "ForceIdentification",
    "ForceUnknowns",
    "LCurve",
    "MFIModel",
    "Order",
    "build_model",
    "force_errors",
    "identify_forces",
    "record_band",
    "solve_batch",
    "solve_dp",
]
