"""Figures of a day of traffic from summary rows (:class:`bwim.summary.SummaryRow`).

Contract
--------
* Weights in kN, speed in km/h (the operator's unit; the summary holds m/s), counts in
  vehicles.  Weight figures use the **weighed** rows only (a refused row has no weight);
  speed, class, lane and flow figures count every vehicle seen (weighed or not, failed
  records excluded: they are no vehicle), weighed and not weighed stacked where it helps.
* Each function draws on ``ax`` when given, else on a new figure, and returns the figure
  (:mod:`bwim.plots`).  A figure with nothing to draw says so in its axes instead of
  failing; the site report (:mod:`bwim.report.site`) leaves such figures out with a note.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from datetime import datetime, timedelta

import numpy as np

from bwim.conventions import KILONEWTON
from bwim.plots import axes
from bwim.records import day_origin, on_day_axis, seconds_of_day

__all__ = ["hourly_counts", "plot_axle_load_spectrum", "plot_counts", "plot_gvw_histogram",
           "plot_hourly_flow", "plot_speed_distribution", "seen"]

_SIZE = (6.0, 3.8)  # inches: two figures side by side on a report page

_KMH = 3.6
_WEIGHED, _NOT = "C0", "0.65"


def seen(rows: Sequence) -> list:
    """The rows that are vehicles (weighed or refused; a failed record is none)."""
    return [r for r in rows if r.status != "failed"]


def _bins(values: np.ndarray, width: float) -> np.ndarray:
    lo = width * np.floor(values.min() / width) if values.size else 0.0
    hi = width * (np.floor(values.max() / width) + 1.0) if values.size else width
    return np.arange(lo, hi + 0.5 * width, width)


def _empty(ax, text: str):
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes)
    return ax.figure


def _limit_line(ax, limit: float | None) -> None:
    """A weight ``limit`` (N), when given, as a red vertical line named beside the axes."""
    if limit is None:
        return
    ax.axvline(limit / KILONEWTON, color="C3", lw=1.5, label=f"limit {limit / KILONEWTON:.0f} kN")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")


def _weight_histogram(ax, values: np.ndarray, *, width: float, limit: float | None,
                      xlabel: str, ylabel: str, title: str, empty: str, log: bool = False):
    """Weights (kN) in bins ``width`` kN wide, a ``limit`` (N) as a red line."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if not values.size:
        return _empty(ax, empty)
    ax.hist(values, bins=_bins(values, width), color=_WEIGHED, edgecolor="white")
    if log:
        ax.set_yscale("log")
    _limit_line(ax, limit)
    ax.grid(alpha=0.3)
    return ax.figure


def plot_gvw_histogram(rows: Sequence, *, limit: float | None = None, width: float = 25.0,
                       ax=None):
    """Histogram of the weighed vehicles' gross weights (kN, bins ``width`` kN wide); a
    gross weight ``limit`` (N), when given, as a red line."""
    gvw = np.array([r.gvw for r in rows if r.weighed]) / KILONEWTON
    return _weight_histogram(axes(ax, figsize=_SIZE), gvw, width=width, limit=limit,
                             xlabel="gross vehicle weight (kN)", ylabel="vehicles",
                             title=f"Gross vehicle weight, {gvw.size} weighed vehicles",
                             empty="no weighed vehicle")


def plot_axle_load_spectrum(rows: Sequence, *, limit: float | None = None,
                            width: float = 10.0, ax=None):
    """The axle-load spectrum: every weighed axle's load in classes ``width`` kN wide,
    counts on a log scale (the heavy tail matters for fatigue and pavement damage); an
    axle ``limit`` (N), when given, as a red line."""
    loads = np.array([w for r in rows if r.weighed for w in r.axle_weights]) / KILONEWTON
    return _weight_histogram(axes(ax, figsize=_SIZE), loads, width=width, limit=limit,
                             xlabel="axle load (kN)", ylabel="axles",
                             title=f"Axle-load spectrum, {loads.size} axles",
                             empty="no weighed axle", log=True)


def plot_speed_distribution(rows: Sequence, *, width: float = 5.0, ax=None):
    """Histogram of the vehicles' speeds (km/h, bins ``width`` km/h wide), weighed and
    not weighed stacked."""
    ax = axes(ax, figsize=_SIZE)
    vs = seen(rows)
    w = np.array([r.speed for r in vs if r.speed is not None and r.weighed]) * _KMH
    n = np.array([r.speed for r in vs if r.speed is not None and not r.weighed]) * _KMH
    ax.set_xlabel("speed (km/h)")
    ax.set_ylabel("vehicles")
    ax.set_title(f"Speed, {w.size + n.size} vehicles")
    if not w.size + n.size:
        return _empty(ax, "no speed measured")
    bins = _bins(np.concatenate([w, n]), width)
    ax.hist([w, n], bins=bins, stacked=True, color=[_WEIGHED, _NOT], edgecolor="white",
            label=["weighed", "not weighed"])
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(alpha=0.3)
    return ax.figure


def _stacked_bars(ax, keys: list[str], rows: list, key_of) -> None:
    weighed = Counter(key_of(r) for r in rows if r.weighed)
    other = Counter(key_of(r) for r in rows if not r.weighed)
    x = np.arange(len(keys))
    a = np.array([weighed[k] for k in keys])
    b = np.array([other[k] for k in keys])
    ax.bar(x, a, color=_WEIGHED, label="weighed")
    ax.bar(x, b, bottom=a, color=_NOT, label="not weighed")
    ax.set_xticks(x, keys, rotation=45 if len(keys) > 8 else 0,
                  ha="right" if len(keys) > 8 else "center")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")


def plot_counts(rows: Sequence, *, by: str = "class", ax=None):
    """Vehicles per class (the axle-group code, :mod:`bwim.classify`) or per lane
    (``by="lane"``), weighed and not weighed stacked; ``"?"`` collects unknown ones."""
    if by not in ("class", "lane"):
        raise ValueError(f"by must be 'class' or 'lane', got {by!r}")
    ax = axes(ax, figsize=_SIZE)
    vs = seen(rows)

    def key_of(r) -> str:
        if by == "class":
            return r.vehicle_class or "?"
        return "?" if r.lane is None else str(r.lane)

    keys = sorted({key_of(r) for r in vs}, key=lambda k: (k == "?", len(k), k))
    ax.set_xlabel("class (axle groups, front to back)" if by == "class" else "lane")
    ax.set_ylabel("vehicles")
    ax.set_title(f"Vehicles by {by}, {len(vs)} vehicles")
    if not vs:
        return _empty(ax, "no vehicle")
    _stacked_bars(ax, keys, vs, key_of)
    ax.grid(alpha=0.3, axis="y")
    return ax.figure


def hourly_counts(rows: Sequence) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Vehicles per clock hour (every hour from the first to the last, empty ones too):
    the hours' labels (``"09:00"``, or ``"2015-10-01 09:00"`` when the rows span several
    dates), weighed and not-weighed counts.  Rows without a time are left out; with only
    clock times of day the hours are those of one day."""
    vs = [r for r in seen(rows) if r.time is not None]
    if not vs:
        return [], np.zeros(0, int), np.zeros(0, int)
    if all(isinstance(r.time, datetime) for r in vs):
        stamps = [r.time.replace(minute=0, second=0, microsecond=0, tzinfo=None)
                  for r in vs]
        first, last = min(stamps), max(stamps)
        hours = [first + timedelta(hours=k)
                 for k in range(int((last - first) / timedelta(hours=1)) + 1)]
        fmt = "%H:%M" if first.date() == last.date() else "%Y-%m-%d %H:%M"
        labels = [h.strftime(fmt) for h in hours]
        index = {h: k for k, h in enumerate(hours)}
        slot = [index[s] for s in stamps]
    else:  # clock times of day (a datetime among them counts by its clock hour), from
        # where their day starts (a night from 23:50 to 00:20 is three hours, not 24)
        tod = [seconds_of_day(r.time) for r in vs]
        origin = day_origin(tod)
        hrs = [int(on_day_axis(s, origin) // 3600.0) for s in tod]
        lo, hi = min(hrs), max(hrs)
        labels = [f"{h % 24:02d}:00" for h in range(lo, hi + 1)]
        slot = [h - lo for h in hrs]
    weighed = np.zeros(len(labels), int)
    other = np.zeros(len(labels), int)
    for r, k in zip(vs, slot, strict=True):
        (weighed if r.weighed else other)[k] += 1
    return labels, weighed, other


def plot_hourly_flow(rows: Sequence, *, ax=None):
    """Vehicles per clock hour (:func:`hourly_counts`), weighed and not weighed stacked;
    each bar starts at its hour."""
    ax = axes(ax, figsize=_SIZE)
    labels, a, b = hourly_counts(rows)
    ax.set_xlabel("hour starting")
    ax.set_ylabel("vehicles per hour")
    ax.set_title(f"Flow per hour, {int(a.sum() + b.sum())} vehicles with a time")
    if not labels:
        return _empty(ax, "no vehicle has a time")
    x = np.arange(len(labels))
    ax.bar(x, a, width=0.9, align="edge", color=_WEIGHED, label="weighed")
    ax.bar(x, b, width=0.9, align="edge", bottom=a, color=_NOT, label="not weighed")
    step = max(1, len(labels) // 12)
    ax.set_xticks(x[::step], labels[::step], rotation=45 if len(labels) > 6 else 0,
                  ha="right" if len(labels) > 6 else "left")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(alpha=0.3, axis="y")
    return ax.figure
