"""The model commands: simulate, calibrate, demo, reproduce."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bwim.cli.common import (
    CalibrationProgress,
    Progress,
    bridge_of,
    check_jobs,
    load_records,
    locked,
    out_file,
    out_folder,
    record_paths,
    refuse_existing_outputs,
    site_provenance,
)
from bwim.errors import InputError
from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values

__all__ = ["calibrate_command", "demo_command", "reproduce_command", "simulate_command"]


# --- simulate --------------------------------------------------------------------------------
def simulate_command(args: argparse.Namespace) -> int:
    from bwim.io import write_csv_record, write_record
    from bwim.scenario import load_scenario, simulate_scenario

    out = out_file(args.output, (".h5", ".hdf5", ".hdf", ".csv"),
                    inputs=[args.scenario, *([args.bridge] if args.bridge else [])],
                    force=args.force)
    scenario = load_scenario(args.scenario)
    bridge = bridge_of(args, scenario) if args.bridge else None
    t0 = time.perf_counter()
    record = simulate_scenario(scenario, bridge=bridge)
    if out.suffix.lower() == ".csv":
        write_csv_record(record, out)
    else:
        write_record(record, out)
    p = record.passage
    print(f"simulated {scenario.title or scenario.source}: {p.n_axles}-axle vehicle at "
          f"{p.speed:g} m/s in lane {p.lane:g} m, {len(record.sensors)} channels × "
          f"{record.time.size} samples at {record.sampling_rate:g} Hz "
          f"({time.perf_counter() - t0:.1f} s)")
    if record.truths:
        print("true static axle loads (kN): "
              f"{', '.join(format_kn_each(record.truth.static_axle_loads))}; "
              f"GVW {format_kn(record.truth.gvw)} kN")
    print(f"record: {out}")
    return 0


# --- calibrate -------------------------------------------------------------------------------
def calibrate_command(args: argparse.Namespace) -> int:
    from bwim.calibration import MassSource, calibrate
    from bwim.io.outputs import refuse_output_in_inputs
    from bwim.scenario import build_bridge, build_road, build_vehicle, load_scenario, save_bridge

    check_jobs(args.jobs)
    scenario = load_scenario(args.scenario)
    paths = record_paths(args.records, any_suffix=scenario.logger is not None)
    out = out_file(args.output, (".toml",), inputs=[args.scenario, *paths],
                    force=args.force)
    if scenario.logger is not None:
        # (a logger's records folder takes any file: a model saved there is read as a run
        # next time, and the model then refused as made from other runs)
        refuse_output_in_inputs(out.parent, args.records)
        return _site_model(args, scenario, paths, out)
    for key in ("gains", "track_width"):
        if getattr(args, key, None) is not None:
            raise InputError(f"--{key.replace('_', '-')} is for a site's logger files "
                             "(a scenario with [logger])")
    start = build_bridge(scenario)
    vehicle = build_vehicle(scenario)
    road = build_road(scenario)
    records = load_records(paths, scenario)
    kwargs = scenario.calibrate.kwargs() if scenario.calibrate is not None else {}
    for key in ("method", "seed", "mass"):
        if getattr(args, key, None) is not None:
            kwargs[key] = getattr(args, key)
    if args.jobs is not None:
        kwargs["n_jobs"] = args.jobs
    if args.mesh_correction is not None:
        mc = args.mesh_correction.strip().lower()
        kwargs["mesh_correction"] = int(mc) if mc.isdigit() else mc
    progress = CalibrationProgress()
    try:
        cal = calibrate(start, records, vehicle, road=road, callback=progress, **kwargs)
    finally:
        progress.close()
    # with the mesh correction the parameters are the finer model's: save that model
    saved = cal.bridge if cal.mesh_correction is None else cal.mesh_correction.bridge
    save_bridge(saved, out, title=f"calibrated from {len(records)} record(s) of "
                f"{scenario.title or scenario.source}")
    rows = [(name, f"{s0:.5g}", f"{v:.5g}", f"± {u:.3g}", format_pct(v, s0))
            for name, v, s0, u in param_values(cal.params, start.params, cal.uncertainty)]
    print(Table(f"Calibrated parameters (SI: Pa, kg/m²), {len(records)} record(s):",
                ("parameter", "start", "calibrated", "uncertainty", "change %"),
                rows).render())
    print()
    print(Table("", ("stage", "unknowns", "evaluations", "time (s)"),
                [(s.name, ", ".join(s.labels), s.nfev, f"{s.wall_time:.1f}")
                 for s in cal.stages]).render())
    print(f"\nidentifiability: {cal.identifiability.summary().replace(chr(10), '; ')}")
    if cal.mesh_correction is not None:
        nx, ny = cal.mesh_correction.mesh
        print(f"{cal.mesh_correction.summary()}\nthe calibrated model is saved on the "
              f"{nx}x{ny} mesh the corrected parameters belong to")
    if cal.mass is not None:
        print(f"mass from the free vibration after exit: x {cal.mass.x:.4f} "
              f"± {cal.mass.standard_error:.2g} of the stages' masses" if cal.mass.success
              else f"mass: the stages' (the free-vibration fit failed: {cal.mass.message})")
    if cal.discretisation is not None:
        print(f"mesh check: {cal.discretisation.summary().replace(chr(10), '; ')}")
    print(f"{cal.nfev} evaluations, wall time {cal.wall_time:.1f} s")
    print(f"calibrated model: {out}")
    # the mass was required from the free vibration (mass="free") and could not be fitted
    if kwargs.get("mass") == MassSource.FREE and cal.mass is not None and not cal.mass.success:
        why = " ".join(cal.message.split())
        print(f"bwim: the calibration did not succeed: {why} (the model is written for "
              "inspection)", file=sys.stderr)
        return 1
    return 0


def _site_model(args: argparse.Namespace, scenario, paths, out: Path) -> int:
    """``bwim calibrate`` on a site's logger files: the FE model from the calibration runs
    (:func:`bwim.site.calibrate_site_model`), saved with its gains and self-check."""
    from bwim.scenario import build_bridge, build_site_setup, load_record, save_site_model
    from bwim.site import calibrate_site, calibrate_site_model

    if scenario.bridge is None:
        raise InputError("calibrating a site's model needs a [bridge] in the scenario (the "
                         "deck's geometry, a nominal E and mu) and every gauge's x and y")
    for key in ("method", "seed"):
        if getattr(args, key) is not None:
            raise InputError(f"--{key.replace('_', '-')} is not used for a site's logger "
                             "files (the road-free fit has no optimiser choice)")
    if getattr(args, "mass", None) is not None:
        raise InputError("--mass is not used for a site's logger files (the road-free fit "
                         "takes the mass from the free vibration when it stands out of the "
                         "noise)")
    # of [calibrate], the road-free fit reads mesh_correction only: no key is ignored
    unused = sorted(k for k in (scenario.calibrate.kwargs() if scenario.calibrate is not None
                                else {}) if k != "mesh_correction")
    if unused:
        raise InputError(f"{scenario.source}: [calibrate] {', '.join(unused)}: not used for "
                         "a site's logger files (the road-free fit reads mesh_correction "
                         "only; its mass comes from the free vibration when it stands out "
                         "of the noise)")
    start = build_bridge(scenario)
    records = []
    for p in paths:
        records.append(load_record(p, scenario))
    site = calibrate_site(records, build_site_setup(scenario))
    print(f"calibrating the model from {site.n_used} of {len(records)} run(s) "
          "(each model fitted again without each run to check it) ...", flush=True)
    # the weighing scale and the self-check weigh as bwim weigh will: its [identify] options
    options = scenario.identify.kwargs() if scenario.identify is not None else None
    given = scenario.calibrate.mesh_correction if scenario.calibrate is not None else None
    mc = str(args.mesh_correction or ("auto" if given is None else given)).strip().lower()
    joints = range(1, len(scenario.bridge.joints or ()) + 1)  # bwim.fe.joints' zones
    with Progress(1 + site.n_used, "calibrating the model (the fit, then one fold a run)"
                  ) as bar:
        bar(0)
        model = calibrate_site_model(records, site, start, gains=args.gains or "common",
                                     track_width=args.track_width, identify_options=options,
                                     mesh_correction=int(mc) if mc.isdigit() else mc,
                                     joints=tuple(joints),
                                     progress=lambda done, total: bar(done))
    model = dataclasses.replace(model, provenance=site_provenance(paths, scenario))
    save_site_model(model, out, title=f"calibrated from {site.n_used} run(s) of "
                    f"{scenario.title or scenario.source}")
    fit = model.fit
    rows = [(name, f"{v:.5g}", f"± {fit.uncertainty[name]:.2g}") for name, v in
            fit.params.items()]
    rows.append(("gain (logger units per strain)",
                 " … ".join(f"{g:.5g}" for g in sorted({min(model.gains.values()),
                                                        max(model.gains.values())})), ""))
    print(Table("Calibrated (E_x is the scale reference; SI units):",
                ("parameter", "value", "uncertainty"), rows).render())
    checks = {r.index: r for r in model.runs}
    runs = []
    for k, (p, why) in enumerate(zip(paths, site.reasons, strict=True)):
        c = checks.get(k)
        runs.append((p.name, why or "used",
                     "" if c is None else f"{100 * c.explained:.1f}",
                     "" if c is None or not np.isfinite(c.gvw_error)
                     else f"{100 * c.gvw_error:+.1f}"))
    print()
    print(Table("Calibration runs (explained: share of the filtered response; GVW: the run "
                "weighed by the model fitted without it):",
                ("run", "use", "explained %", "GVW error %"), runs).render())
    print(f"\n{fit.mass_message}")
    if fit.mesh_correction is not None:
        print(f"{fit.mesh_correction.summary()}; the model is saved on that mesh")
    else:
        print("mesh: the start's mesh is fine enough at the gauges (no correction)"
              if mc == "auto" else "mesh: not corrected (--mesh-correction 0)")
    print(f"{fit.nfev} evaluations")
    print(f"model: {out}")
    if not model.accepted:
        print(f"bwim: the model is not accepted: {model.reason}; bwim weigh refuses to "
              "weigh with it", file=sys.stderr)
        return 1
    print(f"accepted: every run weighed within {100 * model.tolerance:.0f} % by the model "
          "fitted without it")
    return 0


# --- demo ------------------------------------------------------------------------------------
def write_figures(figures: dict, folder: Path, *, prefix: str = "", dpi: int) -> list[Path]:
    """Each named figure as ``folder/<prefix><name>.png`` (atomically); the paths."""
    from bwim.io import atomic_output

    paths = []
    for name, fig in figures.items():
        target = folder / f"{prefix}{name}.png"
        with atomic_output(target) as tmp:
            fig.savefig(tmp, format="png", dpi=dpi)
        paths.append(target)
    return paths


#: The files ``bwim demo`` writes whatever the run (its figures are named after them).
DEMO_FILES = ("calibrated_bridge.toml", "calibration_crossing.h5", "second_vehicle.h5",
              "second_vehicle_forces.h5", "second_vehicle_static.h5", "influence_line.h5",
              "report.html")


def demo_command(args: argparse.Namespace) -> int:
    from bwim.paper.demo import MAX_MODES

    if not 1 <= args.modes <= MAX_MODES:
        raise InputError(f"--modes must be between 1 and {MAX_MODES}, got {args.modes}")
    check_jobs(args.jobs)
    out = out_folder(args.out)
    with locked(out):
        refuse_existing_outputs([out / name for name in DEMO_FILES], force=args.force)
        return _demo_run(args, out)


def _demo_run(args: argparse.Namespace, out: Path) -> int:
    from bwim.io import (
        write_identification,
        write_influence_line,
        write_record,
        write_static_weights,
    )
    from bwim.paper.demo import REPORT_INTRO, REPORT_TITLE, run_demo
    from bwim.report import figure_files, write_report
    from bwim.scenario import save_bridge

    t0 = time.perf_counter()
    progress = CalibrationProgress()
    try:
        demo = run_demo(quick=args.quick, seed=args.seed, n_jobs=args.jobs, n_modes=args.modes,
                        callback=progress, echo=lambda text: print(text, flush=True))
    finally:
        progress.close()
    sections = demo.sections()
    figures = figure_files(sections)
    refuse_existing_outputs([out / f"{name}.png" for name in figures], force=args.force)
    save_bridge(demo.calibration.bridge, out / "calibrated_bridge.toml",
                title="bwim demo: calibrated")
    write_record(demo.calibration_record, out / "calibration_crossing.h5")
    write_record(demo.second_record, out / "second_vehicle.h5")
    write_identification(demo.identified, out / "second_vehicle_forces.h5")
    write_static_weights(demo.moses, out / "second_vehicle_static.h5")
    write_influence_line(demo.influence_line, out / "influence_line.h5")
    write_figures(figures, out, dpi=100)
    page = write_report(out / "report.html", sections, title=REPORT_TITLE, intro=REPORT_INTRO)
    print(f"\nfiles in {out}: calibrated_bridge.toml, records, results (.h5), figures (.png)")
    print(f"report: {page}")
    print(f"demo took {time.perf_counter() - t0:.1f} s")
    return 0


# --- reproduce -------------------------------------------------------------------------------
def reproduce_command(args: argparse.Namespace) -> int:
    from bwim.io import check_writable
    from bwim.paper import reproduce

    names = list(reproduce.CASES) if args.case == "all" else [args.case]
    check_jobs(args.jobs)
    out = out_folder(args.out)
    check_writable(out / ".probe")
    with locked(out):
        if not args.no_figures:  # a case's figures share its prefix (5_1_..., compare_...)
            refuse_existing_outputs(sorted(p for name in names for p in out.glob(
                f"{_prefix(name)}*.png")), force=args.force)
        _reproduce_cases(args, names, out)
    return 0


def _prefix(case: str) -> str:
    return f"{case.replace('.', '_')}_"


def _reproduce_cases(args: argparse.Namespace, names: Sequence[str], out: Path) -> None:
    from bwim.paper import reproduce

    t0 = time.perf_counter()
    for name in names:
        print(f"== reproducing {name}{' (quick)' if args.quick else ''} ==", flush=True)
        kwargs = {"quick": args.quick}
        if name != "compare":
            kwargs["n_jobs"] = args.jobs
        report = reproduce.CASES[name](**kwargs)
        print(report.render(), flush=True)
        if not args.no_figures:
            figures = report.figures()
            refuse_existing_outputs([out / f"{_prefix(name)}{k}.png" for k in figures],
                                    force=args.force)
            for target in write_figures(figures, out, prefix=_prefix(name), dpi=110):
                print(f"  figure: {target}")
        print()
    print(f"total {time.perf_counter() - t0:.1f} s")


