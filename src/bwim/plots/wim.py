"""Figures of static Bridge WIM: influence lines and Moses' fit.

Strain in µε, forces in kN (:mod:`bwim.conventions`); ordinates per kN of axle load.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from bwim.conventions import KILONEWTON, MICROSTRAIN
from bwim.plots import axes
from bwim.sensors import SensorKind
from bwim.tables import format_kn, format_kn_each

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from bwim.records import Record
    from bwim.wim import InfluenceLine, StaticWeights

__all__ = ["plot_influence_line", "plot_static_fit"]


def _unit(kind: SensorKind) -> tuple[float, str]:
    """Scale from SI reading to the plotted unit, and the unit's name."""
    if kind is SensorKind.DEFLECTION:
        return 1e3, "mm"
    return 1.0 / MICROSTRAIN, "µε"


def plot_influence_line(
    il: InfluenceLine, *, reference: InfluenceLine | None = None, ax: Axes | None = None
) -> Figure:
    """The influence line of each channel (per kN of axle load) against position, with a
    reference line (typically the FE model's, :func:`bwim.wim.model_influence_line`)
    dashed beside it."""
    ax = axes(ax)
    colours = [f"C{k % 10}" for k in range(len(il.channels))]
    units = set()
    for k, ch in enumerate(il.channels):
        scale, unit = _unit(ch.kind)
        units.add(unit)
        ax.plot(il.x, il.ordinates[:, k] * scale * KILONEWTON, color=colours[k],
                label=f"{ch.name} ({il.source or 'influence line'})")
    if reference is not None:
        names = reference.channel_names
        for k, ch in enumerate(il.channels):
            if ch.name not in names:
                continue
            j = names.index(ch.name)
            scale, _ = _unit(ch.kind)
            ax.plot(reference.x, reference.ordinates[:, j] * scale * KILONEWTON, "--",
                    color=colours[k], alpha=0.8,
                    label=f"{ch.name} ({reference.source or 'reference'})")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("axle position x (m)")
    ax.set_ylabel(f"reading per kN ({'/'.join(sorted(units))} per kN)")
    track = "centre line" if il.track_width is None else f"track {il.track_width:g} m"
    ax.set_title(f"Influence line, lane {il.lane:g} m, {track}")
    ax.legend(fontsize="small")
    return ax.figure


def plot_static_fit(
    weights: StaticWeights, *, record: Record | None = None, ax: Axes | None = None
) -> Figure:
    """Measured readings and Moses' static fit over the weighing window; the weights (and,
    for a simulated ``record``, the true static weights) in the legend."""
    ax = axes(ax)
    for k, ch in enumerate(weights.channels):
        scale, _ = _unit(ch.kind)
        ax.plot(weights.time, weights.measured[:, k] * scale, color=f"C{k % 10}", lw=1.0,
                label=f"{ch.name} measured")
        ax.plot(weights.time, weights.fitted[:, k] * scale, "--", color=f"C{k % 10}",
                label=f"{ch.name} static fit")
    kn = ", ".join(format_kn_each(weights.axle_weights))
    text = f"Moses: {kn} kN, GVW {format_kn(weights.gvw)} kN"
    if record is not None and record.truths:
        true = record.truth.static_axle_loads
        text += (f"\ntrue: {', '.join(format_kn_each(true))} kN, "
                 f"GVW {format_kn(np.sum(true))} kN")
    ax.set_title(text, fontsize="small")
    ax.set_xlabel("time (s)")
    units = {_unit(ch.kind)[1] for ch in weights.channels}
    ax.set_ylabel(f"reading ({'/'.join(sorted(units))})")
    ax.legend(fontsize="small")
    return ax.figure
