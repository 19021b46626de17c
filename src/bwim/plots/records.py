"""Figures of strain (and deflection) records.

Contract
--------
``plot_record(record, ax=None, ...)`` draws each channel of a :class:`~bwim.Record`
against time, strain in µε and deflection in mm (two y-axes when a record holds both),
shades the time each vehicle's first to last axle is on the deck when the record knows
its passages and ``length`` is given, and returns the figure.  A record in a logger's own
units (read with ``scale = 1``: a reading beyond :data:`bwim.plots.wim.PLAUSIBLE_READING`
of strain) is labelled "reading (logger units)", never µε.  Channel names are in a legend
beside the axes; beyond :data:`MAX_LEGEND` channels the curves are coloured by channel
order with a colour bar naming them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from bwim.conventions import MICROSTRAIN
from bwim.plots import axes
from bwim.sensors import SensorKind

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from bwim.records import Record

__all__ = ["plot_record"]

#: More channels than this are drawn without a legend entry each.
MAX_LEGEND = 12


def plot_record(
    record: Record,
    ax: Axes | None = None,
    *,
    channels: Sequence[str] | None = None,
    length: float | None = None,
    title: str | None = None,
    units: str = "auto",
) -> Figure:
    """Each channel of ``record`` against time (strain in µε, deflection in mm).

    Parameters
    ----------
    record : Record
    ax : matplotlib Axes, optional
    channels : sequence of str, optional
        Channel names to draw (default all).
    length : float, optional
        Span, m: with it, the time each vehicle is on the deck is shaded.
    title : str, optional
    units : {"auto", "si", "reading"}
        Strain in µε and deflection in mm (``"si"``), or the file's numbers as they are
        (``"reading"``); ``"auto"``: the latter when a strain reading is implausible.
    """
    from bwim.plots.wim import PLAUSIBLE_READING

    if units not in ("auto", "si", "reading"):
        raise ValueError(f"units must be 'auto', 'si' or 'reading', got {units!r}")
    if channels is not None:
        record = record.channels(list(channels))
    ax = axes(ax)
    strain = [k for k, s in enumerate(record.sensors) if s.kind is not SensorKind.DEFLECTION]
    deflection = [k for k, s in enumerate(record.sensors) if s.kind is SensorKind.DEFLECTION]
    n = len(record.sensors)
    legend = n <= MAX_LEGEND
    if legend:
        colours = [f"C{k % 10}" for k in range(n)]
    else:
        from matplotlib import colormaps

        cmap = colormaps["viridis"]
        colours = [cmap(k / max(1, n - 1)) for k in range(n)]
    raw = units == "reading" or (units == "auto" and bool(strain) and bool(
        np.nanmax(np.abs(record.data[:, strain]), initial=0.0) > PLAUSIBLE_READING))
    ax_d = ax
    if strain:
        for k in strain:
            ax.plot(record.time, record.data[:, k] * (1.0 if raw else 1.0 / MICROSTRAIN),
                    lw=1.0, color=colours[k], label=record.sensors[k].name if legend else None)
        ax.set_ylabel("reading (logger units)" if raw else "strain (µε)")
        if deflection:
            ax_d = ax.twinx()
    if deflection:
        for k in deflection:
            ax_d.plot(record.time, record.data[:, k] * 1e3, lw=1.0, ls="--",
                      color=colours[k], label=record.sensors[k].name if legend else None)
        ax_d.set_ylabel("deflection (mm)")
    if length is not None:
        for i, p in enumerate(record.passages):
            t = p.axle_times_on(length)
            ax.axvspan(float(t.min()), float(t.max()), color="0.5", alpha=0.08,
                       label="vehicle on the deck" if i == 0 else None)
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title)
    handles, labels = ax.get_legend_handles_labels()
    if ax_d is not ax:
        h2, l2 = ax_d.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    if not legend:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        bar = ax.figure.colorbar(ScalarMappable(Normalize(0, n - 1), cmap=cmap), ax=ax_d,
                                 pad=0.1 if ax_d is not ax else 0.02)
        ticks = np.arange(0, n, max(1, n // 12))
        bar.set_ticks(ticks, labels=[record.sensors[k].name for k in ticks])
        bar.ax.tick_params(labelsize="x-small")
        bar.set_label("channel")
    if handles:
        ax.legend(handles, labels, fontsize="x-small", loc="upper left",
                  bbox_to_anchor=(1.12 if ax_d is not ax else 1.01, 1.0))
    return ax.figure
