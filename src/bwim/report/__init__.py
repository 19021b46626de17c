"""A single-file HTML report of bwim results: tables and embedded figures.

Contract
--------
* :func:`section` (:mod:`bwim.report.results`) turns one result object into a
  :class:`Section`; :func:`read_results` reads result files (folders expanded).
* :func:`site_sections` (:mod:`bwim.report.site`) is the operator's site report of a
  weighed day (``summary.csv``): traffic figures, overloads, flags in words, COST 323
  accuracy against a static reference and the calibration runs when given.
* :func:`render_html` makes the page (figures as base64 PNG, nothing linked; tables never
  wider than the page: :mod:`bwim.report.page`); :func:`write_report` writes it
  atomically; :func:`figure_files` names the figures for writing them as image files.
* Tables are :class:`bwim.tables.Table` (re-exported here as :class:`Table`).
* This package is above the core and may import matplotlib (through :mod:`bwim.plots`,
  lazily); the core never imports it.
"""

from __future__ import annotations

from bwim.report.overloads import OverloadLimits
from bwim.report.page import Section, figure_files, render_html, write_report
from bwim.report.results import RESULT_SUFFIXES, read_results, result_paths, section
from bwim.report.runs import CalibrationRuns, read_calibration_runs
from bwim.report.site import TrafficSummary, site_sections
from bwim.tables import Table

__all__ = ["RESULT_SUFFIXES", "CalibrationRuns", "OverloadLimits", "Section", "Table",
           "TrafficSummary", "figure_files", "read_calibration_runs", "read_results",
           "render_html", "result_paths", "section", "site_sections", "write_report"]
