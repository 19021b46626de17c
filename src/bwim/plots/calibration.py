"""Figures of a calibration: CE convergence (paper Fig. 6/18), calibrated against exact
MFI forces (Fig. 8/19) and zone errors (Fig. 13)."""

from __future__ import annotations

import numpy as np

from bwim.conventions import KILONEWTON
from bwim.optimize import CEHistory
from bwim.plots import axes
from bwim.tables import pct_change

__all__ = ["plot_ce_convergence", "plot_mfi_comparison", "plot_zone_errors"]


def plot_ce_convergence(stage, *, parameter: int = 0, scale: float = 1.0, ax=None,
                        label: str | None = None):
    """Mean ± std of one parameter's sampling distribution at each CE iteration, with the
    best-ever trial; injections show as jumps in the spread (paper Fig. 6 and 18).

    ``stage`` is a calibration stage (:class:`~bwim.calibration.stages.StageResult`,
    named, with parameter labels) or a :class:`~bwim.optimize.CEResult` (``x[i]``).
    """
    h = stage.history
    if not isinstance(h, CEHistory):
        raise ValueError("this stage was not run by Cross-Entropy")
    labels = getattr(stage, "labels", None)
    name = labels[parameter] if labels else f"x[{parameter}]"
    ax = axes(ax)
    it = np.arange(1, h.mean.shape[0] + 1)
    m, s = h.mean[:, parameter] / scale, h.std[:, parameter] / scale
    ax.errorbar(it, m, yerr=s, fmt="o", capsize=3, label="sampling mean ± std")
    ax.axhline(stage.x[parameter] / scale, color="C1", lw=1, ls="--", label="answer")
    for k in np.flatnonzero(h.converged):
        ax.axvline(it[k] + 0.5, color="0.7", lw=0.8)
    ax.set_xlabel("iteration")
    ax.set_ylabel(label or name)
    ax.set_title(f"{getattr(stage, 'name', 'Cross-Entropy')}: {name}")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return ax.figure


def plot_mfi_comparison(exact, calibrated, truth, *, ax=None):
    """Axle forces: true, MFI with the exact model and with the calibrated one, against
    the first axle's distance along the bridge (paper Fig. 8 and 19)."""
    ax = axes(ax)
    p = exact.passages[0]
    dist = p.axle_x(exact.time)[:, 0]
    for a in range(truth.axle_forces.shape[1]):
        c = f"C{a}"
        ax.plot(dist, truth.axle_forces[:, a] / KILONEWTON, color=c, lw=2, alpha=0.4,
                label=f"actual, axle {a + 1}")
        ax.plot(dist, exact.axle_forces[:, a] / KILONEWTON, color=c, ls="--", lw=1,
                label=f"MFI, exact M & K, axle {a + 1}")
        ax.plot(dist, calibrated.axle_forces[:, a] / KILONEWTON, color=c, ls=":", lw=1.5,
                label=f"MFI, calibrated, axle {a + 1}")
    ax.set_xlabel("first axle distance (m)")
    ax.set_ylabel("force (kN)")
    ax.legend(fontsize="x-small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3)
    return ax.figure


def plot_zone_errors(true_bridge, calibrated_bridge, *, family: str = "E_x", ax=None):
    """Map of each zone's calibration error % over the deck (paper Fig. 13a)."""
    ax = axes(ax)
    model = true_bridge.model
    g = model.grid
    err = pct_change(calibrated_bridge.params[family], true_bridge.params[family])
    per_element = err[model.zone_of_element].reshape(g.nx, g.ny).T
    lim = max(float(np.abs(err).max()), 1e-9)
    mesh = ax.pcolormesh(g.x_lines, g.y_lines, per_element, cmap="RdBu_r", vmin=-lim,
                         vmax=lim, shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=f"{family} error (%)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{family}: calibrated − true, per zone")
    return ax.figure
