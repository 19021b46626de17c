"""The result commands: accuracy (COST 323) and report (HTML)."""

from __future__ import annotations

import argparse

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

    summary = read_summary(args.summary)
    reference = read_reference(args.reference)
    result = assess(summary, reference, repeatability=args.repeatability,
                    environment=args.environment, strict=args.strict)
    print(result.render())
    if args.output:
        target = out_file(args.output, (".csv",), inputs=[args.summary, args.reference],
                           force=args.force)
        table = result.table()
        write_csv(target, table.header, table.rows)
        print(f"table: {target}")
    return 0


# --- report ----------------------------------------------------------------------------------
def report_command(args: argparse.Namespace) -> int:
    from bwim import report

    out = out_file(args.output, (".html", ".htm"), force=args.force,
                    inputs=[*args.results, *([args.reference] if args.reference else [])])
    items = report.read_results(args.results)
    sections = [report.section(obj, name) for name, obj in items]
    if args.reference:  # COST 323 classes of every weigh summary among the results
        from bwim.accuracy import assess
        from bwim.io import read_reference, read_summary
        from bwim.io.summary import is_summary

        reference = read_reference(args.reference)
        summaries = [p for p in report.result_paths(args.results)
                     if p.suffix.lower() == ".csv" and is_summary(p)]
        if not summaries:
            raise InputError("--reference needs a weigh summary.csv among the results")
        for p in summaries:
            sections.append(report.section(assess(read_summary(p), reference), p.name))
    report.write_report(out, sections, title=args.title)
    print(f"report of {len(items)} result(s): {out}")
    return 0


