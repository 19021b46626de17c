"""Figures of a site calibration's runs (:class:`bwim.report.runs.CalibrationRuns`).

Contract
--------
* :func:`plot_run_scales`: each run's scale factor (its strain-to-load ratio relative to
  the fitted lines, dimensionless, 1 = the lines) against its clock time when every run
  has one (hours since the first run's midnight, or of the day), else against the run's
  order; used runs filled, runs left out hollow.  A drift of the factor over the day is
  what the drift correction follows (``drift_factor`` of the summary).
* :func:`plot_run_residuals`: each run's relative residual, one bar per run, used runs
  coloured, runs left out grey.
"""

from __future__ import annotations

from datetime import datetime

import numpy as np

from bwim.plots import axes

__all__ = ["plot_run_residuals", "plot_run_scales", "run_hours"]

_SIZE = (6.0, 3.8)  # inches: two figures side by side on a report page


def run_hours(runs) -> np.ndarray | None:
    """The runs' clock times in hours (of the first run's date, or of the day for clock
    times); None unless every run has a time."""
    times = [r.time for r in runs.runs]
    if not times or any(t is None for t in times):
        return None
    if all(isinstance(t, datetime) for t in times):
        day = min(times).replace(hour=0, minute=0, second=0, microsecond=0)
        return np.array([(t - day).total_seconds() / 3600.0 for t in times])
    return np.array([t.hour + t.minute / 60 + (t.second + t.microsecond / 1e6) / 3600
                     for t in times])


def plot_run_scales(runs, *, ax=None):
    """Scale factor of each run over the day (see the module docstring)."""
    ax = axes(ax, figsize=_SIZE)
    hours = run_hours(runs)
    x = np.arange(1, len(runs.runs) + 1) if hours is None else hours
    scale = np.array([np.nan if r.scale is None else r.scale for r in runs.runs])
    used = np.array([r.used for r in runs.runs], bool)
    ax.plot(x[used], scale[used], "o", color="C0", label="used")
    if (~used).any():
        ax.plot(x[~used], scale[~used], "o", mfc="none", color="0.5", label="left out")
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.set_xlabel("run (in the table's order)" if hours is None else "clock time (h)")
    ax.set_ylabel("scale factor (1 = the lines)")
    ax.set_title(f"Calibration runs' scale factor, {int(used.sum())} of {used.size} used")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(alpha=0.3)
    return ax.figure


def plot_run_residuals(runs, *, ax=None):
    """Relative residual of each run's fit (see the module docstring)."""
    ax = axes(ax, figsize=_SIZE)
    res = np.array([np.nan if r.residual is None else r.residual for r in runs.runs])
    used = np.array([r.used for r in runs.runs], bool)
    x = np.arange(len(runs.runs))
    ax.bar(x, np.where(used, res, 0.0), color="C0", label="used")
    if (~used).any():
        ax.bar(x, np.where(used, 0.0, res), color="0.65", label="left out")
    names = [r.name for r in runs.runs]
    step = max(1, len(names) // 30)
    ax.set_xticks(x[::step], names[::step], rotation=90, fontsize="x-small")
    ax.set_ylabel("relative residual")
    ax.set_title("Residual of each calibration run's fit")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(alpha=0.3, axis="y")
    return ax.figure
