"""What the sensors can see: the conditioning of the calibration's sensitivity matrix.

Contract
--------
:func:`identifiability` stacks the relative sensitivities ``p ∂ε/∂p / ‖d‖`` of the static
readings of the calibration crossings to every stiffness parameter (adjoint sensitivities,
THEORY §1.5) and reports their singular values and condition number, the norm of each
parameter's column, and the parameters the sensors cannot see: a column norm below
``threshold`` × the largest, or a large share in a singular direction whose singular value
is below ``threshold`` × the largest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.fe.bridge import Bridge
from bwim.fe.influence import static_sensitivities
from bwim.records import Record
from bwim.vehicles import Vehicle

__all__ = ["Identifiability", "identifiability"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Identifiability:
    """Identifiability of the stiffness parameters from the calibration records."""

    labels: tuple[str, ...]
    column_norms: np.ndarray
    singular_values: np.ndarray
    condition: float
    unseen: tuple[str, ...]

    def summary(self) -> str:
        lines = [f"condition number {self.condition:.3g} ({len(self.labels)} stiffness "
                 "parameters)"]
        if self.unseen:
            lines.append("the sensors cannot see: " + ", ".join(self.unseen))
        else:
            lines.append("every stiffness parameter is seen by the sensors")
        return "\n".join(lines)


def identifiability(
    bridge: Bridge, records: Sequence[Record], vehicle: Vehicle, *,
    names: Sequence[str] | None = None, threshold: float = 1e-3,
) -> Identifiability:
    """The identifiability report (see module docstring)."""
    present = [n for n in bridge.STIFFNESS_FAMILIES if n in bridge.params]
    names = tuple(present if names is None else [n for n in names if n in present])
    static = vehicle.model().static_forces
    scale = np.concatenate([bridge.params[n] for n in names])
    blocks, norm2, labels = [], 0.0, ()
    for rec in records:
        p = rec.passage
        x = p.wheel_x(rec.time)
        y = np.broadcast_to(p.wheel_y, x.shape) if bridge.is_plate else None
        sens = static_sensitivities(bridge, rec.sensors, x, y, static[None, :], wrt=names)
        blocks.append(sens.values.reshape(-1, sens.values.shape[2]))
        norm2 += float(np.sum(rec.data**2))
        labels = tuple(f"{n}[{i}]" for n, i in zip(sens.names, sens.index, strict=True))
    J = np.vstack(blocks) * scale[None, :] / np.sqrt(max(norm2, 1e-300))
    cols = np.linalg.norm(J, axis=0)
    _, sv, vt = np.linalg.svd(J, full_matrices=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    weak = set(np.flatnonzero(cols < threshold * cols.max()))
    for k in np.flatnonzero(sv < threshold * sv[0]):
        weak |= set(np.flatnonzero(np.abs(vt[k]) > 0.5))
    return Identifiability(labels=labels, column_norms=cols, singular_values=sv,
                           condition=cond, unseen=tuple(labels[i] for i in sorted(weak)))
