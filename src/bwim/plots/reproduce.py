"""Figures of the reproduced experiments (see :mod:`bwim.paper.reproduce`)."""

from __future__ import annotations

from bwim.optimize import CEHistory
from bwim.plots.calibration import plot_ce_convergence, plot_mfi_comparison, plot_zone_errors

__all__ = ["report_figures"]


def report_figures(report) -> dict:
    """Named figures of a case report: CE convergence (Fig. 6/18), MFI with the calibrated
    and exact models (Fig. 8/19), zone error maps (Fig. 13)."""
    out = {}
    art = report.artefacts
    if "calibration" in art:
        cal = art["calibration"]
        for st in cal.stages:
            if isinstance(st.history, CEHistory):
                key = "ce_" + st.name.split()[0]
                for i, lab in enumerate(st.labels[:3]):
                    scale = 1e9 if lab.startswith("E") else 1.0
                    unit = " (GPa)" if scale == 1e9 else ""
                    out[f"{key}_{lab.replace('[', '').replace(']', '')}"] = \
                        plot_ce_convergence(st, parameter=i, scale=scale, label=lab + unit)
        out["mfi_forces"] = plot_mfi_comparison(art["exact"], art["calibrated"],
                                                art["record"].truth)
    for b, item in art.items():
        if isinstance(item, dict) and "cal48" in item:
            out[f"zones_bridge{b}_E_x"] = plot_zone_errors(item["truth"], item["cal48"].bridge)
    return out
