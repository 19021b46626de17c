"""Figures of a WIM accuracy test: weighed against static reference weights.

Contract
--------
* Weights in N in, kN on the axes; errors in per cent, ``100 (W_wim − W_static) /
  W_static`` (:func:`bwim.accuracy.relative_errors`).
* The COST 323 tolerance δ (%) of the class reached (:mod:`bwim.accuracy`), when given,
  is drawn: the lines ``W_wim = (1 ± δ/100) W_static`` on the scatter, ``±δ`` on the
  error histogram.  δ is the half width of the interval that must hold the errors with
  the class's minimum level of confidence π₀ (:func:`bwim.accuracy.min_confidence`).
"""

from __future__ import annotations

import numpy as np

from bwim.conventions import KILONEWTON
from bwim.plots import axes

__all__ = ["plot_error_histogram", "plot_weighed_vs_reference"]

_SIZE = (6.0, 3.8)  # inches: two figures side by side on a report page


def _legend(ax) -> None:
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")


def plot_weighed_vs_reference(weighed, reference, *, tolerance: float | None = None,
                              class_name: str = "", what: str = "gross weight", ax=None):
    """Weighed (WIM) against static reference weights, N, with the 1:1 line and, for a
    ``tolerance`` δ (%), the lines ±δ about it."""
    ax = axes(ax, figsize=_SIZE)
    w = np.asarray(weighed, dtype=float) / KILONEWTON
    r = np.asarray(reference, dtype=float) / KILONEWTON
    ax.plot(r, w, "o", ms=4, color="C0", label=f"{w.size} vehicles")
    if w.size:
        hi = 1.05 * float(max(w.max(), r.max()))
        ref = np.array([0.0, hi])
        ax.plot(ref, ref, color="0.3", lw=1, label="weighed = static")
        if tolerance is not None:
            label = f"±{tolerance:g} %" + (f" (class {class_name})" if class_name else "")
            ax.plot(ref, ref * (1 + tolerance / 100), "--", color="C3", lw=1, label=label)
            ax.plot(ref, ref * (1 - tolerance / 100), "--", color="C3", lw=1)
        ax.set_xlim(0.0, hi)
        ax.set_ylim(0.0, hi)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"static {what} (kN)")
    ax.set_ylabel(f"weighed {what} (kN)")
    ax.set_title(f"Weighed against static {what}")
    ax.grid(alpha=0.3)
    _legend(ax)
    return ax.figure


def plot_error_histogram(errors_pct, *, tolerance: float | None = None,
                         class_name: str = "", what: str = "gross weight", ax=None):
    """Histogram of the relative errors (%), their mean, and ±δ of the class reached."""
    ax = axes(ax, figsize=_SIZE)
    e = np.asarray(errors_pct, dtype=float)
    ax.set_xlabel(f"{what} error (%)")
    ax.set_ylabel("vehicles")
    ax.set_title(f"Relative error of the {what}, {e.size} vehicles")
    if e.size:
        span = max(float(np.abs(e).max()), tolerance or 0.0) * 1.1 or 1.0
        bins = np.linspace(-span, span, 2 * max(5, min(25, e.size // 2)) + 1)
        ax.hist(e, bins=bins, color="C0", edgecolor="white", label="errors")
        ax.axvline(float(e.mean()), color="0.2", lw=1.5,
                   label=f"mean {e.mean():+.2f} %, std {e.std(ddof=1) if e.size > 1 else 0:.2f} %")
    if tolerance is not None:
        label = f"±{tolerance:g} %" + (f" (class {class_name})" if class_name else "")
        ax.axvline(-tolerance, color="C3", ls="--", lw=1.5, label=label)
        ax.axvline(tolerance, color="C3", ls="--", lw=1.5)
    ax.grid(alpha=0.3)
    _legend(ax)
    return ax.figure
