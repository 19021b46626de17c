"""Figures: matplotlib functions that take a result (and ``ax=None``) and return the figure.

Contract
--------
* Every plotting function has the form ``plot_something(result, ..., ax=None) -> Figure``:
  it draws on ``ax`` if given, otherwise on a new figure, and never calls ``show()``.
* Plots show strain in µε and forces in kN (:mod:`bwim.conventions`); readings in a
  logger's uncalibrated units are labelled "reading units", never µε
  (:func:`bwim.plots.wim.reading_units`).  Legends stand beside the axes, or a colour bar
  tells many channels apart, so that no legend covers the curves.
* The site report's figures: :mod:`bwim.plots.traffic` (weights, speeds, counts, flow),
  :mod:`bwim.plots.accuracy` (against a static reference), :mod:`bwim.plots.runs`
  (calibration runs).
* Nothing in the core imports this package at import time; it imports matplotlib lazily
  through :func:`axes`, so ``import bwim`` stays free of matplotlib.  Each result with a
  figure has a thin ``.plot(ax=None, **kw)`` method that imports its function here when
  called: :class:`~bwim.Record`, :class:`~bwim.InfluenceLine`,
  :class:`~bwim.StaticWeights`, :class:`~bwim.ForceIdentification`,
  :class:`~bwim.mfi.lcurve.LCurve`, :class:`~bwim.calibration.stages.StageResult`,
  :class:`~bwim.Calibration` and :class:`~bwim.optimize.CEResult`;
  :meth:`bwim.paper.reproduce.CaseReport.figures` gives a case's named figures.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["axes"]


def axes(ax: Axes | None = None, **subplot_kw) -> Axes:
    """``ax`` itself, or the axes of a new figure (Agg-safe, no pyplot state kept)."""
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=subplot_kw.pop("figsize", (7.0, 4.0)), layout="constrained")
    return fig.add_subplot(**subplot_kw)
