"""How well identified forces match the truth (simulated records).

Contract
--------
:func:`force_errors` compares a :class:`~bwim.mfi.identify.ForceIdentification` with the
:class:`~bwim.records.Truth` of the same record over the central fraction of each axle's
time on the deck (the paper scores the central 80 %):

* ``weight_error``: (identified static axle weight − true static axle load) / true, per axle;
* ``gvw_error``: the same for the gross weight;
* ``rms_error``: RMS of (identified − true axle force) over the window, divided by the
  axle's static load, per axle;
* ``wheel_rms_error``: the same per wheel, divided by the wheel's static load;
* ``sum_sq``: Σ (identified − true wheel force)² over the window, kN² (the paper's Table 1
  measure, "sum of the squares of the differences", whose units the paper does not state).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.mfi.identify import ForceIdentification
from bwim.records import Truth

__all__ = ["ForceErrors", "force_errors"]


@dataclass(frozen=True, kw_only=True, eq=False)
class ForceErrors:
    """Errors of one identification against the truth (see module docstring)."""

    weight_error: np.ndarray
    gvw_error: float
    rms_error: np.ndarray
    wheel_rms_error: np.ndarray
    sum_sq: np.ndarray


def force_errors(ident: ForceIdentification, truth: Truth, vehicle: int = 0) -> ForceErrors:
    """Errors for one vehicle of the record (index ``vehicle``)."""
    if len(ident.passages) <= vehicle:
        raise InputError(f"no vehicle {vehicle} in this identification")
    p = ident.passages[vehicle]
    a0 = sum(q.n_axles for q in ident.passages[:vehicle])
    w0 = sum(q.n_axles * q.wheels_per_axle for q in ident.passages[:vehicle])
    n_w = p.wheels_per_axle
    if truth.axle_forces.shape != (ident.time.size, p.n_axles):
        raise InputError("truth and identification do not share a time axis and axle layout")
    t = ident.time
    weight_err = np.empty(p.n_axles)
    rms = np.empty(p.n_axles)
    wheel_rms = np.empty(p.n_axles * n_w)
    sum_sq = np.empty(p.n_axles * n_w)
    for a in range(p.n_axles):
        lo, hi = ident.axle_windows[a0 + a]
        inside = (t >= lo) & (t <= hi)
        static = truth.static_axle_loads[a]
        weight_err[a] = ident.axle_weights[a0 + a] / static - 1.0
        diff = ident.axle_forces[inside, a0 + a] - truth.axle_forces[inside, a]
        rms[a] = np.sqrt(np.mean(diff**2)) / static
        for k in range(n_w):
            c = a * n_w + k
            dw = ident.wheel_forces[inside, w0 + c] - truth.wheel_forces[inside, c]
            wheel_rms[c] = np.sqrt(np.mean(dw**2)) / truth.static_wheel_loads[c]
            sum_sq[c] = np.sum((dw / 1e3) ** 2)
    gvw_err = ident.gvw[vehicle] / truth.gvw - 1.0
    return ForceErrors(weight_error=weight_err, gvw_error=float(gvw_err), rms_error=rms,
                       wheel_rms_error=wheel_rms, sum_sq=sum_sq)
