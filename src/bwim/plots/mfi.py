"""Figures of moving force identification: forces against the truth, and the L-curve."""

from __future__ import annotations

import numpy as np

from bwim.conventions import KILONEWTON
from bwim.plots import axes

__all__ = ["plot_forces", "plot_lcurve"]


def plot_forces(ident, truth=None, *, by="axle", ax=None, label="MFI"):
    """Identified axle (or wheel) forces in kN against time, with the truth if given.

    The shaded band of each axle marks the window its static weight is averaged over.
    """
    ax = axes(ax)
    forces = ident.axle_forces if by == "axle" else ident.wheel_forces
    colors = [f"C{i}" for i in range(forces.shape[1])]
    for i in range(forces.shape[1]):
        ax.plot(ident.time, forces[:, i] / KILONEWTON, color=colors[i],
                label=f"{label} {by} {i + 1}")
        if truth is not None:
            ref = truth.axle_forces if by == "axle" else truth.wheel_forces
            if i < ref.shape[1]:
                ax.plot(ident.time, ref[:, i] / KILONEWTON, color=colors[i], ls="--", lw=1,
                        label=f"true {by} {i + 1}")
    if by == "axle":
        for i, (lo, hi) in enumerate(ident.axle_windows):
            ax.axvspan(lo, hi, color=colors[i % len(colors)], alpha=0.06)
            ax.hlines(ident.axle_weights[i] / KILONEWTON, lo, hi, colors=colors[i], lw=2.5,
                      alpha=0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("force (kN)")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3)
    return ax.figure


def plot_lcurve(ident, *, ax=None):
    """The L-curve (residual norm against solution seminorm, log–log) and its corner, of an
    identification or of an :class:`~bwim.mfi.lcurve.LCurve` itself."""
    curve = getattr(ident, "lcurve", ident)
    if curve is None:
        raise ValueError("this identification used a given λ: it has no L-curve")
    ax = axes(ax)
    ax.loglog(curve.residual_norm, curve.seminorm, "o-", ms=3)
    i = int(np.argmin(np.abs(np.log(curve.lam_scaled / curve.corner_scaled))))
    ax.loglog(curve.residual_norm[i], curve.seminorm[i], "r*", ms=12,
              label=f"corner λ = {curve.corner:.3g}")
    ax.set_xlabel("residual norm ‖d − Q X‖ (scaled)")
    ax.set_ylabel("seminorm ‖r‖ (scaled)")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    return ax.figure
