"""The result commands: accuracy (COST 323) and report (HTML)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from bwim.cli.common import (
    out_file,
    write_csv,
)
from bwim.errors import InputError

__all__ = ["accuracy_command", "report_command"]


# --- accuracy --------------------------------------------------------------------------------
def accuracy_command(args: argparse.Namespace) -> int:
    from bwim.accuracy import assess
    from bwim.io import read_reference, read_summary

    # the output checked before the work (docs/cli.md): an existing file or a wrong
    # suffix is refused before anything is printed
    target = (out_file(args.output, (".csv",), inputs=[args.summary, args.reference],
                       force=args.force) if args.output else None)
    summary = read_summary(args.summary)
    reference = read_reference(args.reference)
    result = assess(summary, reference, repeatability=args.repeatability,
                    environment=args.environment, strict=args.strict,
                    time_tolerance=_time_tolerance(args))
    print(result.render())
    if target is not None:
        table = result.table()
        write_csv(target, table.header, table.rows)
        print(f"table: {target}")
    return 0


def _time_tolerance(args: argparse.Namespace) -> float:
    """``--time-tolerance`` (s), refused unless positive and finite."""
    value = getattr(args, "time_tolerance", 5.0)
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"--time-tolerance must be a positive number of seconds, got "
                         f"{value:g}")
    return float(value)


# --- report ----------------------------------------------------------------------------------
def _limits(args: argparse.Namespace):
    """Overload limits from ``--gvw-limit`` / ``--axle-limit`` (kN; 0 switches one off)
    when the parser has them, else the defaults (:class:`bwim.report.OverloadLimits`)."""
    from bwim.report import OverloadLimits

    given = {}
    for key, attr in (("gvw", "gvw_limit"), ("axle", "axle_limit")):
        value = getattr(args, attr, None)
        if value is not None:
            if not (math.isfinite(value) and value >= 0.0):  # in the option's kN
                raise InputError(f"--{attr.replace('_', '-')} must be a load in kN, 0 or "
                                 f"more (0 switches it off), got {value:g}")
            given[key] = None if float(value) == 0.0 else float(value) * 1000.0
    return OverloadLimits(**given)


def report_command(args: argparse.Namespace) -> int:
    """``bwim report RESULTS... [--reference REF.csv] [--runs RUNS.csv] -o REPORT.html``:
    result files as sections; a weigh ``summary.csv`` as the operator's site report
    (:func:`bwim.report.site_sections`) with the COST 323 accuracy against
    ``--reference`` and the calibration runs (``--runs``, or a ``calibration_runs.csv``
    among the results)."""
    from bwim import report

    runs_arg = getattr(args, "runs", None)
    inputs = [*args.results, *([args.reference] if args.reference else []),
              *([runs_arg] if runs_arg else [])]
    out = out_file(args.output, (".html", ".htm"), force=args.force, inputs=inputs)
    limits = _limits(args)
    items = report.read_results(args.results)
    summaries = [obj for _, obj in items if isinstance(obj, report.TrafficSummary)]
    runs = [obj for _, obj in items if isinstance(obj, report.CalibrationRuns)]
    if runs_arg:
        runs.insert(0, report.read_calibration_runs(runs_arg))
    reference = None
    if args.reference:
        from bwim.io import read_reference

        if not summaries:
            raise InputError("--reference needs a weigh summary.csv among the results")
        reference = read_reference(args.reference)
    sections = []
    for k, summary in enumerate(summaries):
        sections += report.site_sections(
            summary, reference=reference, limits=limits,
            reference_name=Path(args.reference).name if args.reference else "",
            time_tolerance=_time_tolerance(args),
            runs=runs[0] if runs and k == 0 else None)
    for extra in runs[1:] if summaries else runs:
        sections.append(report.site.runs_section(extra))
    for name, obj in items:
        if not isinstance(obj, (report.TrafficSummary, report.CalibrationRuns)):
            sections.append(report.section(obj, name))
    report.write_report(out, sections, title=args.title)
    print(f"report of {len(items) + bool(runs_arg)} result(s): {out}")
    return 0
