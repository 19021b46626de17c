"""The ``bwim`` command line.

Contract
--------
``main(argv=None) -> int`` parses arguments, calls the library and prints; it holds no
numerics.  The subcommands are one declarative table, :data:`COMMANDS` (name, handler,
help, description, arguments), from which the parser is built; tables are printed with
:class:`bwim.tables.Table`.  Bad input (a scenario, record or model file, an option, an
output path) ends with a one-line message ``bwim: error: ...`` on stderr and exit code 2,
never a traceback, and leaves no partial output file (every writer is atomic, outputs are
checked before the work starts).  Progress goes to stderr: a bar (tqdm) on a terminal,
else plain lines every ten seconds or so (batches: count, total, rate and ETA; the
calibration: stage, iteration and best objective).  ``bwim --version`` prints the
version; every command takes its output as ``-o`` (also ``--out``, ``--output``).  When
stdout's reader goes away (``bwim weigh ... | head``), what is printed is dropped and the
command finishes its work and its files.

Subcommands:

``simulate SCENARIO [-o RECORD] [--bridge MODEL]``
    Simulate the scenario's crossing and write the record (``.h5`` or ``.csv``).
``calibrate SCENARIO RECORD... [-o MODEL] [--method] [--jobs] [--seed]``
    Calibrate the scenario's bridge (the starting model) from records of the scenario's
    vehicle; write the model (TOML) and print start → calibrated ± uncertainty.
``identify SCENARIO RECORD... [--bridge MODEL] [-o FOLDER|SUMMARY.csv] [--jobs|--scheduler]``
    Moving force identification on each record (folders expanded), in parallel on
    ``--jobs`` processes (this one and loky workers, each reading its records and
    writing their results) or on a dask.distributed scheduler; a CSV summary (one row
    per vehicle, one with the reason per failed record) and one HDF5 result per record,
    written as each record finishes (the summary and ``manifest.json`` at most every
    second or so).  A rerun skips the records done (``manifest.json``); ``--force``
    starts afresh.  Exit code 0: all records done; 1: some failed; 2: bad input.

Safety of outputs (:mod:`bwim.io.outputs`, ``docs/cli.md``): an output that is one of the
inputs is refused; every existing output file of a command (summary, manifest, each
record's result, lines, runs, report, figures) is refused unless ``--force``, before any
work; an output folder is locked (``.bwim.lock``) for the run; SIGTERM ends a run like
Ctrl-C (temporary files removed, worker processes stopped, exit code 130); worker
processes end with their parent, also on ``kill -9``.  ``bwim --memory-limit SIZE
COMMAND`` bounds the memory of each process of the run (:mod:`bwim.limits`); a
``BWIM_MEMORY_LIMIT`` that is not a size is refused before any work.
``weigh SCENARIO RECORD... (--calibration-records REC... | --influence IL.h5) [-o FOLDER]``
    Static weights by Moses' algorithm, the influence line calibrated from crossings of
    the scenario's vehicle (and written) or read from a file.
``accuracy SUMMARY.csv --reference REF.csv [--repeatability] [--environment]``
    The COST 323 accuracy class per criterion and overall.
``report RESULTS... -o REPORT.html``
    A single-file HTML report (tables, embedded figures) of result files and folders.
``demo [-o FOLDER] [--quick] [--force]``
    The whole chain on the paper's slab bridge: simulate a calibration crossing,
    calibrate, identify a second vehicle's forces with the calibrated model, weigh it by
    Moses; a table against the truth, figures and ``report.html``.
``reproduce {5.1,5.2,5.3,5.4,compare,all} [-o FOLDER] [--force]``
    The paper's experiments: tables with the paper's numbers beside ours, figures in
    ``-o`` (default ``bwim-out/reproduce``).
"""


from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from bwim.calibration import Method
from bwim.cli.batches import identify_command, weigh_command
from bwim.cli.models import (
    calibrate_command,
    demo_command,
    reproduce_command,
    simulate_command,
)
from bwim.cli.results import accuracy_command, report_command
from bwim.errors import BwimError

__all__ = ["COMMANDS", "build_parser", "main"]


# --- the parser: one declarative entry per command -------------------------------------------
@dataclass(frozen=True)
class Arg:
    """One argument: its names (flags or a positional name) and its add_argument options."""

    names: tuple[str, ...]
    options: dict = field(default_factory=dict)

    def updated(self, **options) -> Arg:
        """This argument with more (or other) add_argument options, e.g. a command's help."""
        return Arg(self.names, {**self.options, **options})


def arg(*names: str, **options) -> Arg:
    """An :class:`Arg`: ``arg("-o", "--output", default="x", help="...")``."""
    return Arg(names, options)


@dataclass(frozen=True)
class OneOf:
    """Mutually exclusive arguments (exactly one if ``required``)."""

    args: tuple[Arg, ...]
    required: bool = False


@dataclass(frozen=True)
class Command:
    """A subcommand: name, handler, one-line help, description and arguments.

    ``raw`` keeps the description's line breaks (its example line) in ``--help``.
    """

    name: str
    run: Callable[[argparse.Namespace], int]
    help: str
    description: str
    args: tuple[Arg | OneOf, ...]
    raw: bool = True


# Arguments several commands share, declared once; a command adds its own default and help.
_SCENARIO = arg("scenario", metavar="SCENARIO.toml")
_RECORDS = arg("records", nargs="+", metavar="RECORD")
_OUTPUT = arg("-o", "--output", "--out")
_BRIDGE = arg("--bridge", metavar="MODEL.toml")
_REFERENCE = arg("--reference", metavar="REF.csv")
_TIME_TOLERANCE = arg("--time-tolerance", type=float, default=5.0, metavar="S",
                      help="a reference vehicle given by time (no record) is the summary's "
                      "one vehicle within this many seconds (in its lane when given); "
                      "default 5")
_FORCE = arg("--force", action="store_true",
             help="overwrite existing outputs (an input is never overwritten)")
_PARALLEL = OneOf((arg("--jobs", type=int, default=1,
                       help="worker processes on this machine (-1: all cores); default 1"),
                   arg("--scheduler", metavar="ADDRESS",
                       help="address of a dask.distributed scheduler, e.g. "
                       "tcp://host:8786")))
_RESUME = arg("--resume", action="store_true",
              help="go on with the batch in OUT (its manifest.json): records done and "
              "unchanged are kept, failed ones are tried again, rows of records not given "
              "again are kept")
_PARQUET = arg("--parquet", action="store_true",
               help="also write the summary as summary.parquet (typed columns; needs "
               "pyarrow: pip install 'bwim[parquet]')")

COMMANDS: tuple[Command, ...] = (
    Command(
        "simulate", simulate_command,
        "simulate a scenario's vehicle crossing and write the strain record",
        "Simulate the scenario's vehicle crossing its bridge (vehicle-bridge interaction over "
        "the road profile) and write what the sensors read.\n\n"
        "  bwim simulate examples/paper_slab.toml -o crossing.h5",
        (_SCENARIO.updated(help="the scenario file"),
         _OUTPUT.updated(default="record.h5", metavar="RECORD",
             help="output record: .h5 (with positions, passage and true forces) or .csv "
             "(time and readings only); default record.h5"),
         _BRIDGE.updated(
             help="use this bridge model (e.g. a calibrated one) instead of the scenario's "
             "[bridge]"),
         _FORCE)),
    Command(
        "calibrate", calibrate_command,
        "calibrate the bridge model from crossings of a truck of known weight",
        "Calibrate the stiffness (E_x, E_y, …) and mass (mu) of the scenario's bridge from "
        "strain records of the scenario's vehicle, the calibration truck of known static axle "
        "loads.  The scenario's [bridge] is the starting model and its [calibrate] section "
        "gives the defaults; the records must be crossings at the scenario's [run] speed, "
        "lane and approach, over its [road].\n\n"
        "With a site's scenario ([logger], [[axle_detectors]], [vehicle], a [bridge] and the "
        "gauges' x, y) the records are the calibration truck's logger files: the runs are "
        "detected as bwim weigh detects them, runs with other traffic are left out, and the "
        "model's stiffness ratio, the logger's gain(s), offsets and the detectors' place on "
        "the deck are fitted without a road (docs/site_model.md).  The model is checked by "
        "weighing each run with the model fitted without it; one that cannot weigh its own "
        "runs within 10 % is written but not accepted (exit status 1), and bwim weigh "
        "refuses it.\n\n"
        "  bwim calibrate examples/paper_slab.toml crossing.h5 -o calibrated.toml\n"
        "  bwim calibrate site/scenario.toml site/calibration -o site_model.toml",
        (_SCENARIO,
         _RECORDS.updated(
             help="records of the calibration truck (.h5 or .csv; folders expanded)"),
         _OUTPUT.updated(default="calibrated.toml", metavar="MODEL.toml",
             help="the calibrated bridge model (default calibrated.toml)"),
         arg("--method", choices=[m.value for m in Method],
             help="optimiser: ce = Cross-Entropy (the paper's), lm = Levenberg-Marquardt, "
             "cma = CMA-ES (default: the scenario's, else ce)"),
         arg("--jobs", type=int, help="worker processes for the populations"),
         arg("--seed", type=int, help="random seed of the optimiser"),
         arg("--mesh-correction", metavar="N|auto",
             help="correct the model's discretisation error by a model bisected N times "
             "(1-3), or as often as its sensors need (auto); default: the scenario's, "
             "else none (a site's logger files: else auto)"),
         arg("--mass", choices=["auto", "free", "dynamic"],
             help="where the mass comes from: the free vibration after the truck leaves "
             "(free), the crossings' dynamic misfit (dynamic, the paper's), or free when the "
             "records hold a free vibration, else dynamic (auto); default: the scenario's, "
             "else auto"),
         arg("--gains", choices=["common", "per_channel"],
             help="a site's logger files: one logger scale for every gauge (common, the "
             "default) or a gain per gauge"),
         arg("--track-width", type=float, metavar="M",
             help="a site's logger files: the calibration truck's track, m (default 1.9)"),
         _FORCE)),
    Command(
        "identify", identify_command,
        "identify the moving axle forces and weights of vehicles (MFI)",
        "Moving force identification: the time history of each axle's force, its static "
        "weight and the gross vehicle weight, from each record and the bridge model (ideally "
        "a calibrated one).  Many records run in parallel on this machine (--jobs) or on a "
        "dask.distributed cluster (--scheduler).  Writes a CSV summary, one row per vehicle, "
        "and <record>_forces.h5 per record, each as its record finishes; a record that "
        "fails gets a summary row with its reason and the others go on; --resume goes on "
        "with an interrupted batch.  Exit code 0: all records done, 1: some failed, 2: bad "
        "input.\n\n"
        "  bwim identify examples/paper_slab.toml records/ --bridge calibrated.toml -o out/",
        (_SCENARIO.updated(
             help="the scenario (sensor positions; passage of CSV records)"),
         _RECORDS.updated(
             help="records (.h5 or .csv) or folders of them"),
         _BRIDGE.updated(
             help="bridge model (default: the scenario's [bridge])"),
         _OUTPUT.updated(default="bwim-out/identify", metavar="OUT",
             help="a results folder, or summary.csv (results beside it); default "
             "bwim-out/identify"),
         _PARALLEL,
         _RESUME,
         _PARQUET,
         _FORCE)),
    Command(
        "weigh", weigh_command,
        "static weights by Moses' algorithm from influence lines",
        "Static axle weights and GVW by Moses' algorithm, one summary.csv row per record "
        "(record, n_axles, speed_m_s, axle_spacings_m, axle_weights_kN, gvw_kN, flags, ...); "
        "a record that cannot be weighed gets a row with its reason, and the exit code is 1 "
        "if a record failed.  No weight is written without its plausibility checks.\n"
        "With a scenario that has [logger] (a real installation's logger files): each "
        "vehicle is detected (axle detectors, or the strain alone), every gauge's influence "
        "line is calibrated from the calibration truck's runs (speed, lateral position and "
        "drift of each run found from the data), and traffic is weighed with the gauges "
        "combined.  Otherwise the records carry their passages and one line is calibrated "
        "from crossings of the scenario's vehicle or read from a file.\n\n"
        "  bwim weigh site.toml events/ --calibration-records calibration/ -o out/\n"
        "  bwim weigh examples/paper_slab.toml truck.h5 --calibration-records crossing.h5",
        (_SCENARIO,
         _RECORDS.updated(
             help="records of the vehicles to weigh: logger files of any extension with a "
             "[logger] scenario, else .h5 or .csv; folders expanded"),
         OneOf((arg("--calibration-records", nargs="+", metavar="REC",
                    help="crossings of the scenario's vehicle to calibrate the influence "
                    "line from"),
                arg("--influence", metavar="IL.h5", help="a saved influence line")),
               required=True),
         _OUTPUT.updated(default="bwim-out/weigh", metavar="FOLDER",
             help="results folder (default bwim-out/weigh)"),
         _PARALLEL,
         _RESUME,
         _BRIDGE.updated(
             help="logger files only: weigh each detected vehicle by moving force "
             "identification with this (calibrated) bridge model instead of Moses; the "
             "gauges need x and y, and the first detector's position its x on the bridge"),
         _PARQUET,
         arg("--continuous", action="store_true",
             help="logger files only: each file is a continuous recording, cut into events "
             "by the trigger first (docs/streams.md); each event is written to "
             "FOLDER/events/FILE#k.h5 and named FILE#k in the summary"),
         _FORCE)),
    Command(
        "accuracy", accuracy_command,
        "COST 323 accuracy classes of weights against statically weighed references",
        "The COST 323 European WIM specification's accuracy class per criterion (gross "
        "weight, group of axles, single axle, axle of a group) and overall, from a weigh "
        "summary and a reference of the same vehicles' static weights (CSV with the columns "
        "record, n_axles, axle_spacings_m, axle_weights_kN, gvw_kN; lists ';'-separated; "
        "or, instead of record, time: when the vehicle crossed, matched to the summary's "
        "time within --time-tolerance).\n\n"
        "  bwim accuracy out/summary.csv --reference static_weights.csv",
        (arg("summary", metavar="SUMMARY.csv", help="a summary written by bwim weigh"),
         _REFERENCE.updated(required=True,
             help="static weights of the same vehicles (by record name)"),
         arg("--repeatability", choices=["r1", "r2", "RR1", "RR2"], default="RR2",
             help="test conditions: r1/r2 repeatability (one or a few vehicles passing many "
             "times), RR1/RR2 reproducibility (a few vehicles / a sample of traffic); "
             "default RR2"),
         arg("--environment", choices=["I", "II", "III"], default="I",
             help="environmental conditions: I repeatable (a day or so), II limited "
             "reproducibility, III full (seasons); default I"),
         arg("--strict", action="store_true",
             help="a reference record absent from the summary (or a vehicle given by "
             "time that more than one row could be) is an error"),
         _TIME_TOLERANCE,
         _OUTPUT.updated(metavar="TABLE.csv", help="also write the table as CSV"),
         _FORCE)),
    Command(
        "report", report_command,
        "a single-file HTML report of result files",
        "A self-contained HTML page (figures embedded) of result files: force "
        "identifications, static weights, influence lines, records (.h5), bridge models "
        "(.toml) and summaries (.csv); folders are expanded.  A weigh summary.csv gives "
        "the site report: traffic figures, overloads, flags in words, the COST 323 "
        "accuracy against --reference and the calibration runs (docs/report.md).\n\n"
        "  bwim report out/ -o report.html",
        (arg("results", nargs="+", metavar="RESULTS"),
         _OUTPUT.updated(default="report.html", metavar="REPORT.html",
             help="default report.html"),
         arg("--title", default="bwim report", help="the page title"),
         arg("--runs", metavar="RUNS.csv",
             help="calibration_runs.csv of bwim weigh: each run's scale factor and residual"),
         arg("--gvw-limit", type=float, metavar="KN",
             help="overload limit of the gross weight, kN (default 392.4 = 40 t; 0: none)"),
         arg("--axle-limit", type=float, metavar="KN",
             help="overload limit of an axle, kN (default 112.8 = 11.5 t; 0: none)"),
         _REFERENCE.updated(
             help="static weights of the weighed vehicles: adds the COST 323 accuracy "
             "classes of each weigh summary.csv among the results"),
         _TIME_TOLERANCE,
         _FORCE)),
    Command(
        "demo", demo_command,
        "the whole chain on the paper's slab bridge, in under a minute",
        "On the paper's 12 m × 8 m slab: simulate a calibration crossing, calibrate E_x, E_y "
        "and mu from a wrong start by Cross-Entropy, identify a second vehicle's axle forces "
        "with the calibrated model and weigh it by Moses; print the results against the truth "
        "and write figures and report.html to --out.",
        (arg("--modes", type=int, default=6, help="natural frequencies to print (default 6)"),
         arg("-o", "--out", "--output", dest="out", default="bwim-out",
             help="output folder (default bwim-out)"),
         arg("--seed", type=int, default=0, help="seed of the calibration"),
         arg("--jobs", type=int, default=1, help="worker processes for calibration"),
         arg("--quick", action="store_true",
             help="a smaller, faster calibration (for tests)"),
         _FORCE)),
    Command(
        "reproduce", reproduce_command,
        "the paper's experiments with its numbers side by side",
        "Reproduce Dowling, OBrien & González (2012) §5: 5.1 identical elements, 5.2 noise, "
        "5.3 sixteen zones, 5.4 beam-and-slab bridge, and a comparison of optimisers "
        "('compare').  Full runs take minutes (5.3 the longest); --quick runs small versions.",
        (arg("case", choices=["5.1", "5.2", "5.3", "5.4", "compare", "all"]),
         arg("--quick", action="store_true", help="small, fast versions"),
         arg("-o", "--out", "--output", dest="out", default="bwim-out/reproduce",
             help="folder for the figures"),
         arg("--jobs", type=int, default=1, help="worker processes for populations"),
         arg("--no-figures", action="store_true", help="tables only"),
         _FORCE),
        raw=False),
)


def _add(parser, item: Arg | OneOf) -> None:
    """Add ``item`` to ``parser`` (an ArgumentParser or a mutually exclusive group)."""
    if isinstance(item, OneOf):
        group = parser.add_mutually_exclusive_group(required=item.required)
        for a in item.args:
            _add(group, a)
    else:
        parser.add_argument(*item.names, **item.options)


def build_parser() -> argparse.ArgumentParser:
    """The ``bwim`` argument parser (built from :data:`COMMANDS`)."""
    p = argparse.ArgumentParser(
        prog="bwim",
        description="Calibrated, dynamic Bridge Weigh-in-Motion: simulate crossings, "
        "calibrate the bridge's FE model from a truck of known weight, identify the moving "
        "axle forces of other vehicles, weigh them statically (Moses), report.",
        epilog="Scenario files (TOML) describe the bridge, the sensors, the vehicle, the "
        "road and the run; see examples/paper_slab.toml.  Units are SI.",
    )
    p.add_argument("--version", action="version", version=f"bwim {_version()}")
    p.add_argument("--memory-limit", metavar="SIZE",
                   help="most memory a command may use (per process), e.g. 4G, 800M or "
                   "0.25 (a fraction of the machine's); default: the BWIM_MEMORY_LIMIT "
                   "environment variable, else half the machine's memory")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for c in COMMANDS:
        fmt = {"formatter_class": argparse.RawDescriptionHelpFormatter} if c.raw else {}
        s = sub.add_parser(c.name, help=c.help, description=c.description, **fmt)
        for item in c.args:
            _add(s, item)
        s.set_defaults(run=c.run)
    return p


def _version() -> str:
    from bwim import __version__

    return __version__


class _PipeSafe:
    """A text stream whose reader may go away (``bwim weigh ... | head``, also with
    ``2>&1``): once the pipe is broken, what is printed is dropped and the command goes on
    (its output files are still written whole); the exit code stays the command's."""

    def __init__(self, stream) -> None:
        self.stream = stream
        self.broken = False

    def _drop(self) -> None:
        self.broken = True
        with contextlib.suppress(AttributeError, ValueError, OSError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self.stream.fileno())  # the interpreter's last flush is quiet
            os.close(devnull)

    def write(self, text: str) -> int:
        if not self.broken:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self._drop()
        return len(text)

    def flush(self) -> None:
        if not self.broken:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._drop()

    def isatty(self) -> bool:
        return False if self.broken else self.stream.isatty()

    def __getattr__(self, name: str):
        return getattr(self.stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``bwim`` command; returns the exit code."""
    from bwim.io.outputs import signals_as_interrupt
    from bwim.limits import ENV_VAR, parse_size

    for stream in (sys.stdout, sys.stderr):  # file names that are not UTF-8 print too
        with contextlib.suppress(AttributeError, ValueError, OSError):
            stream.reconfigure(errors="backslashreplace")
    parser = build_parser()
    args = parser.parse_args(argv)
    saved = os.environ.get(ENV_VAR)
    stdout, stderr = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _PipeSafe(stdout), _PipeSafe(stderr)
    try:
        if args.memory_limit is not None:
            parse_size(args.memory_limit)  # a one-line error if it is not a size
            os.environ[ENV_VAR] = args.memory_limit
        elif (saved or "").strip():
            parse_size(saved)  # a garbage BWIM_MEMORY_LIMIT: refused before any work
        with signals_as_interrupt():
            return int(args.run(args))
    except BwimError as exc:
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"bwim: error: {message}", file=sys.stderr)
        return 2
    except RecursionError:  # e.g. a TOML file of thousands of nested arrays
        print("bwim: error: an input file is nested too deeply to be read (e.g. thousands of "
              "nested arrays or tables in a TOML file)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bwim: interrupted (the records finished so far are kept; rerun to go on)",
              file=sys.stderr)
        return 130
    finally:
        sys.stdout, sys.stderr = stdout, stderr
        if saved is None:
            os.environ.pop(ENV_VAR, None)
        else:
            os.environ[ENV_VAR] = saved
