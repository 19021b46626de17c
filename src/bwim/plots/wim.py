"""Figures of static Bridge WIM: influence lines and Moses' fit.

Strain in µε, forces in kN (:mod:`bwim.conventions`); ordinates per kN of axle load.  A
line in a logger's uncalibrated units is labelled "reading units per kN", never µε
(:func:`reading_units`); a lateral position is given a unit only when it is known.
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

__all__ = ["MAX_LEGEND_CHANNELS", "PLAUSIBLE_PER_KN", "PLAUSIBLE_READING",
           "plot_influence_line", "plot_static_fit", "reading_units"]


#: Largest plausible influence ordinate per kN of axle load, in SI units: 1000 µε (1e-3
#: strain) or 1 mm of deflection per kN would put a 100 kN axle far beyond any bridge's
#: yield; larger ordinates are uncalibrated logger units, not strain.
PLAUSIBLE_PER_KN = 1e-3
#: Largest plausible reading in SI units (strain 1e-2 = 10 000 µε, or 10 mm): above it a
#: record is in a logger's own units.
PLAUSIBLE_READING = 1e-2
#: Above this many channels the lines are told apart by a colour bar, not a legend.
MAX_LEGEND_CHANNELS = 8


def _unit(kind: SensorKind) -> tuple[float, str]:
    """Scale from SI reading to the plotted unit, and the unit's name."""
    if kind is SensorKind.DEFLECTION:
        return 1e3, "mm"
    return 1.0 / MICROSTRAIN, "µε"


def reading_units(il: InfluenceLine, units: str = "auto") -> bool:
    """Whether ``il`` is drawn in the logger's own units ("reading units") rather than
    µε or mm: ``units="reading"`` or ``"si"`` decide; ``"auto"`` takes reading units when
    an ordinate exceeds :data:`PLAUSIBLE_PER_KN` per kN (a logger file read with
    ``scale = 1``, :mod:`bwim.io.logger`, holds its own units, not strain)."""
    if units not in ("auto", "si", "reading"):
        raise ValueError(f"units must be 'auto', 'si' or 'reading', got {units!r}")
    if units != "auto":
        return units == "reading"
    return bool(np.nanmax(np.abs(il.ordinates), initial=0.0) * KILONEWTON > PLAUSIBLE_PER_KN)


def _lateral_text(il: InfluenceLine, lateral_unit: str | None) -> str:
    unit = "m" if il.source == "FE model" and lateral_unit is None else lateral_unit
    if unit == "m":
        return f"lane {il.lane:g} m"
    if unit:
        return f"lateral {il.lane:g} ({unit})"
    return f"lateral position {il.lane:g}"


def plot_influence_line(
    il: InfluenceLine, *, reference: InfluenceLine | None = None, units: str = "auto",
    lateral_unit: str | None = None, ax: Axes | None = None
) -> Figure:
    """The influence line of each channel (per kN of axle load) against position, with a
    reference line (typically the FE model's, :func:`bwim.wim.model_influence_line`)
    dashed beside it.

    ``units``: ``"auto"``, ``"si"`` (µε or mm per kN) or ``"reading"`` (the logger's
    units per kN), see :func:`reading_units`.  ``lateral_unit``: the unit of
    ``il.lane`` (``"m"``, ``"gauge index"``; None: metres for an FE model's line, no unit
    claimed otherwise).  Up to :data:`MAX_LEGEND_CHANNELS` channels get a legend beside
    the axes; more are coloured by channel order with a colour bar."""
    ax = axes(ax)
    raw = reading_units(il, units)
    many = len(il.channels) > MAX_LEGEND_CHANNELS
    if many:
        from matplotlib import colormaps

        cmap = colormaps["viridis"]
        colours = [cmap(k / max(1, len(il.channels) - 1)) for k in range(len(il.channels))]
    else:
        colours = [f"C{k % 10}" for k in range(len(il.channels))]
    found = set()

    def scale_of(ch) -> float:
        if raw:
            found.add("reading units")
            return 1.0
        scale, unit = _unit(ch.kind)
        found.add(unit)
        return scale

    for k, ch in enumerate(il.channels):
        ax.plot(il.x, il.ordinates[:, k] * scale_of(ch) * KILONEWTON, color=colours[k],
                label=f"{ch.name} ({il.source or 'influence line'})")
    if reference is not None:
        names = reference.channel_names
        for k, ch in enumerate(il.channels):
            if ch.name not in names:
                continue
            j = names.index(ch.name)
            scale = 1.0 if reading_units(reference, units) else _unit(ch.kind)[0]
            ax.plot(reference.x, reference.ordinates[:, j] * scale * KILONEWTON, "--",
                    color=colours[k], alpha=0.8,
                    label=f"{ch.name} ({reference.source or 'reference'})")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("axle position x (m)")
    ax.set_ylabel(f"reading per kN of axle load ({'/'.join(sorted(found))} per kN)")
    track = "centre line" if il.track_width is None else f"track {il.track_width:g} m"
    ax.set_title(f"Influence line, {_lateral_text(il, lateral_unit)}, {track}")
    if many:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize
        from matplotlib.lines import Line2D

        bar = ax.figure.colorbar(ScalarMappable(Normalize(1, len(il.channels)), cmap=cmap),
                                 ax=ax)
        bar.set_label("channel (order in the line)")
        styles = [Line2D([], [], color="0.3", label=il.source or "influence line")]
        if reference is not None:
            styles.append(Line2D([], [], color="0.3", ls="--",
                                 label=reference.source or "reference"))
        ax.legend(handles=styles, fontsize="small", loc="upper left",
                  bbox_to_anchor=(0.0, -0.15), ncols=2)
    else:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax.figure


def plot_static_fit(
    weights: StaticWeights, *, record: Record | None = None, units: str = "auto",
    ax: Axes | None = None
) -> Figure:
    """Measured readings and Moses' static fit over the weighing window; the weights (and,
    for a simulated ``record``, the true static weights) in the title.  ``units`` as in
    :func:`plot_influence_line`; ``"auto"`` takes the logger's units when a reading
    exceeds :data:`PLAUSIBLE_READING`."""
    if units not in ("auto", "si", "reading"):
        raise ValueError(f"units must be 'auto', 'si' or 'reading', got {units!r}")
    raw = units == "reading" or (units == "auto" and bool(
        np.nanmax(np.abs(weights.measured), initial=0.0) > PLAUSIBLE_READING))
    ax = axes(ax)
    for k, ch in enumerate(weights.channels):
        scale = 1.0 if raw else _unit(ch.kind)[0]
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
    units_ = {"reading units"} if raw else {_unit(ch.kind)[1] for ch in weights.channels}
    ax.set_ylabel(f"reading ({'/'.join(sorted(units_))})")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax.figure
