"""Figures of strain (and deflection) records.

Contract
--------
``plot_record(record, ax=None, ...)`` draws each channel of a :class:`~bwim.Record`
against time, strain in µε and deflection in mm (two y-axes when a record holds both),
shades the time each vehicle's first to last axle is on the deck when the record knows
its passages and ``length`` is given, and returns the figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

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
    """
    if channels is not None:
        record = record.channels(list(channels))
    ax = axes(ax)
    strain = [k for k, s in enumerate(record.sensors) if s.kind is not SensorKind.DEFLECTION]
    deflection = [k for k, s in enumerate(record.sensors) if s.kind is SensorKind.DEFLECTION]
    legend = len(record.sensors) <= MAX_LEGEND
    ax_d = ax
    if strain:
        for k in strain:
            ax.plot(record.time, record.data[:, k] / MICROSTRAIN, lw=1.0,
                    color=f"C{k % 10}", label=record.sensors[k].name if legend else None)
        ax.set_ylabel("strain (µε)")
        if deflection:
            ax_d = ax.twinx()
    if deflection:
        for k in deflection:
            ax_d.plot(record.time, record.data[:, k] * 1e3, lw=1.0, ls="--",
                      color=f"C{k % 10}", label=record.sensors[k].name if legend else None)
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
    if handles:
        ax.legend(handles, labels, fontsize="x-small", ncols=3)
    return ax.figure
