"""The figure of a site model's self-check (:class:`bwim.site.SiteModel`).

Contract
--------
* :func:`plot_site_model`: each used calibration run's GVW error (%) when weighed by the
  model fitted without it, one bar per run (labelled by its position in the runs given,
  from 1), with the model's tolerance as a band (± ``tolerance``); a run that could not be
  weighed is marked with a cross at 0.  The title gives the verdict.  This is the plot to
  read first: a model that does not weigh its own truck is not used.
"""

from __future__ import annotations

import numpy as np

from bwim.plots import axes

__all__ = ["plot_site_model"]


def plot_site_model(model, *, ax=None):
    """Leave-one-out GVW error of each run against the tolerance (module docstring)."""
    ax = axes(ax, figsize=(6.0, 3.8))
    err = 100 * model.gvw_errors
    x = np.arange(err.size)
    weighed = np.isfinite(err)
    ax.bar(x[weighed], err[weighed], color="C0", label="GVW error, run left out")
    if (~weighed).any():
        ax.plot(x[~weighed], np.zeros(int((~weighed).sum())), "x", color="C3",
                label="not weighed")
    tol = 100 * model.tolerance
    ax.axhspan(-tol, tol, color="C2", alpha=0.12, label=f"tolerance ± {tol:.0f} %")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xticks(x, [f"run {r.index + 1}" for r in model.runs], fontsize="small")
    ax.set_ylabel("GVW error (%)")
    verdict = "accepted" if model.accepted else "not accepted"
    ax.set_title(f"Site model weighing its own runs: {verdict}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(alpha=0.3, axis="y")
    return ax.figure
