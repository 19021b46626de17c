"""The paper's experiments (Dowling, OBrien & González 2012, §5), reproduced.

Contract
--------
Each ``case_*`` function runs one experiment of ``docs/paper_cases.md`` and returns a
:class:`CaseReport`: printable tables with the paper's numbers beside ours, the measured
numbers (for tests and the note), the objects figures are drawn from
(:meth:`CaseReport.figures`), and the wall time.
``quick=True`` runs a smaller version (shorter approach, smaller populations, fewer
seeds) for the test suite; the full runs are ``bwim reproduce`` / ``make reproduce``.

Every assumed input is in :mod:`bwim.paper`.  The calibrations start from values within
±30 % of the truth, as the paper did (§5.1 step 2): E_x × 0.8, E_y × 1.2, μ × 1.25.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bwim import paper
from bwim.calibration import Calibration, Method, calibrate, run_stage
from bwim.dynamics.crossing import simulate
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.mfi import ForceIdentification, force_errors, identify_forces
from bwim.records import Record
from bwim.tables import Table, format_pct, pct_change

__all__ = ["CASES", "CaseReport", "Table", "case_5_1", "case_5_2", "case_5_3", "case_5_4",
           "compare_methods"]

#: The paper's published numbers.
PAPER = {
    "5.1": {"E_x": -0.60, "E_y": -0.17, "mu": -0.54},
    "5.3_48": [6.5, 12.1, 4.8, 9.1, 6.5, 14.4],
    "5.3_3": [5.0, 24.7, 19.8, 40.8, 70.5, 109.4],
    "5.3_bridge2_Ex": 1.0,
    "5.4": {"E_x": (31.0e9, 31.3e9), "E_y": (31.0e9, 30.9e9), "mu": (576.0, 577.0),
            "E_girder": (35e9, 34.8e9), "mu_girder": (1373.0, 1358.0)},
}
START = {"E_x": 0.8, "E_y": 1.2, "mu": 1.25, "E_girder": 0.9, "mu_girder": 0.85}


@dataclass(frozen=True, kw_only=True, eq=False)
class CaseReport:
    """One reproduced experiment."""

    case: str
    tables: tuple[Table, ...]
    numbers: dict
    wall_time: float
    artefacts: dict = field(default_factory=dict)

    def render(self) -> str:
        """The tables as text, then the wall time."""
        body = "\n\n".join(t.render() for t in self.tables)
        return f"{body}\n\n(case {self.case}: {self.wall_time:.1f} s)"

    def figures(self) -> dict:
        """Named figures of the case (:func:`bwim.plots.reproduce.report_figures`); imports
        matplotlib."""
        from bwim.plots.reproduce import report_figures

        return report_figures(self)


def _start(bridge: Bridge, unknowns: Sequence[str]) -> Bridge:
    p = bridge.params
    return bridge.with_params(**{u: p[u] * START[u] for u in unknowns})


def _crossing(bridge, sensors, *, seed, approach, speed=paper.SPEED, lane=paper.LANE,
              noise=0.0, noise_seed=0) -> Record:
    rec = simulate(bridge, paper.truck(), speed=speed, lane=lane, sensors=sensors,
                   road=paper.road(seed, approach=approach), approach=approach)
    return rec.with_noise(noise, seed=noise_seed) if noise else rec


def _mfi(bridge: Bridge, rec: Record) -> ForceIdentification:
    """MFI as in the paper: longitudinal strains only, λ at the L-curve's corner."""
    long = rec.channels([s for s in rec.sensors if s.kind.value == "strain_x"])
    return identify_forces(bridge, long)


def _settings(quick: bool, **overrides) -> dict:
    """Run sizes: the full run, the quick one, and any ``overrides`` that are not None
    (the tests' still smaller runs)."""
    s = ({"approach": 20.0, "population": (100, 24), "convergences": 2} if quick
         else {"approach": paper.APPROACH, "population": (200, 40), "convergences": 3})
    s.update({k: v for k, v in overrides.items() if v is not None})
    return s


def case_5_1(*, quick: bool = False, seed: int = 0, method: str = "ce", n_jobs: int = 1,
             callback=None) -> CaseReport:
    """§5.1: identical elements, 3 unknowns; then MFI with the calibrated model."""
    t0 = time.perf_counter()
    s = _settings(quick)
    truth = paper.slab_bridge()
    rec = _crossing(truth, paper.sensors(), seed=1, approach=s["approach"])
    cal = calibrate(_start(truth, ("E_x", "E_y", "mu")), [rec], paper.truck(),
                    road=paper.road(1, approach=s["approach"]), approach=s["approach"],
                    seed=seed, method=method, population=s["population"],
                    convergences=s["convergences"], n_jobs=n_jobs, callback=callback,
                    mesh_check=0.01)
    two = _two_stage_params(cal, truth)
    rows = []
    for k in ("E_x", "E_y", "mu"):
        t = truth.params[k][0]
        rows.append((k, f"{PAPER['5.1'][k]:+.2f}", format_pct(two[k][0], t, 3),
                     format_pct(cal.params[k][0], t, 5),
                     f"{cal.uncertainty[k][0] / t * 100:.3f}"))
    exact, calibrated = _mfi(truth, rec), _mfi(cal.bridge, rec)
    e_exact, e_cal = force_errors(exact, rec.truth), force_errors(calibrated, rec.truth)
    mfi_rows = [
        ("exact M, K", *(f"{v * 100:+.2f}" for v in e_exact.weight_error),
         *(f"{v * 100:.2f}" for v in e_exact.rms_error), f"{exact.lam:.3g}"),
        ("calibrated M, K", *(f"{v * 100:+.2f}" for v in e_cal.weight_error),
         *(f"{v * 100:.2f}" for v in e_cal.rms_error), f"{calibrated.lam:.3g}"),
    ]
    tables = (
        Table("§5.1 calibrated parameters: error % (paper beside ours)",
              ("parameter", "paper", "two stages", "refined", "uncertainty %"), tuple(rows)),
        Table("§5.1 MFI (longitudinal strains, L-curve λ): static axle weight error % and "
              "force RMS error % of the static load, central 80 % (paper: 'almost "
              "identical'; its λ ≈ 2e-18)",
              ("model", "axle 1 weight", "axle 2 weight", "axle 1 RMS", "axle 2 RMS", "λ"),
              tuple(mfi_rows)),
        _stage_table(cal),
        _discretisation_table(cal),
    )
    numbers = {
        "errors": {k: float(pct_change(cal.params[k], truth.params[k])[0]) for k in cal.params},
        "discretisation_error": cal.discretisation.model_error,
        "two_stage_errors": {k: float(pct_change(two[k], truth.params[k])[0]) for k in two},
        "mfi_weight_error": e_cal.weight_error.tolist(), "mfi_rms_error": e_cal.rms_error.tolist(),
        "mfi_exact_rms_error": e_exact.rms_error.tolist(), "nfev": cal.nfev,
    }
    return CaseReport(case="5.1", tables=tables, numbers=numbers,
                      wall_time=time.perf_counter() - t0,
                      artefacts={"calibration": cal, "record": rec, "exact": exact,
                                 "calibrated": calibrated})


def _two_stage_params(cal: Calibration, truth: Bridge) -> dict:
    """Parameters after the paper's two stages (before any refinement)."""
    return {k: np.asarray(v) for k, v in cal.two_stage.items()}


def _discretisation_table(cal: Calibration) -> Table:
    """The calibrated model's estimated discretisation error at each sensor (the data here
    come from the same mesh, so the calibration cannot see it)."""
    mc = cal.discretisation
    rows = tuple((name, f"{e * 100:.2f}") for name, e in mc.model_error.items())
    return Table(f"Discretisation error of the calibrated model at the sensors, % (Richardson "
                 f"over meshes {', '.join(f'{a}x{b}' for a, b in mc.meshes)}, observed order "
                 f"{mc.order:.2f}; the data come from the same mesh, so the parameters "
                 "above cannot show it)", ("sensor", "error %"), rows)


def _stage_table(cal: Calibration) -> Table:
    rows = tuple((st.name, str(len(st.labels)), str(st.nit), str(st.nfev),
                  f"{st.wall_time:.1f}", st.message[:60]) for st in cal.stages)
    return Table("Calibration stages", ("stage", "unknowns", "iterations", "evaluations",
                                        "time (s)", "stopped because"), rows)


def case_5_2(*, quick: bool = False, levels: Sequence[float] | None = None,
             seeds: Sequence[int] | None = None, method: str = "ce", n_jobs: int = 1,
             weighted: bool = True, noise: str = "paper",
             population: tuple[int, int] | None = None) -> CaseReport:
    """§5.2: measurement noise of p %; parameter errors over noise seeds, the paper's two
    stages beside the refined answer.

    ``noise="paper"`` is the paper's definition: σ = p % of *each channel's* peak
    (``Record.with_noise(..., per_channel=True)``); ``noise="gauge"`` is gauge noise, one
    σ = p % of the record's overall peak strain on every channel (a real gauge's noise
    does not scale with its signal).  ``weighted`` (beyond the paper) weights each
    channel by ``1 / σ̂²`` with its noise estimated from the data
    (:func:`~bwim.calibration.noise_weights`: no noise model assumed; under the paper's
    noise it comes out ∝ 1/peak²); otherwise the paper's plain sum, where the large
    longitudinal channels swamp the transverse ones that set E_y.
    """
    if noise not in ("paper", "gauge"):
        raise InputError(f"noise must be 'paper' or 'gauge', got {noise!r}")
    t0 = time.perf_counter()
    s = _settings(quick, population=population)
    levels = (1, 5, 20) if quick and levels is None else (levels or (1, 2, 3, 4, 5, 10, 15, 20))
    seeds = (0,) if quick and seeds is None else (seeds or (0, 1, 2))
    truth = paper.slab_bridge()
    clean = _crossing(truth, paper.sensors(), seed=1, approach=s["approach"])
    keys = ("E_x", "E_y", "mu")
    rows, numbers = [], {}
    for p in levels:
        errs, twos = [], []
        for sd in seeds:
            rec = clean.with_noise(p / 100.0, seed=1000 + sd, per_channel=noise == "paper")
            cal = calibrate(_start(truth, keys), [rec], paper.truck(),
                            road=paper.road(1, approach=s["approach"]), approach=s["approach"],
                            seed=sd, method=method, population=s["population"],
                            convergences=s["convergences"], n_jobs=n_jobs,
                            weights="noise" if weighted else None)
            errs.append([pct_change(cal.params[k], truth.params[k])[0] for k in keys])
            twos.append([pct_change(cal.two_stage[k], truth.params[k])[0] for k in keys])
        e, e2 = np.array(errs), np.array(twos)
        numbers[p] = {"mean_abs": np.abs(e).mean(0).tolist(), "max_abs": np.abs(e).max(0).tolist(),
                      "two_stage_mean_abs": np.abs(e2).mean(0).tolist(),
                      "two_stage_max_abs": np.abs(e2).max(0).tolist()}
        paper_note = "< 1" if p <= 5 else ("μ 42" if p == 20 else "> 1")
        rows.append((f"{p:g}",
                     *(f"{m:+.2f} ± {sdv:.2f}" for m, sdv in
                       zip(e2.mean(0), e2.std(0), strict=True)),
                     *(f"{m:+.2f} ± {sdv:.2f}" for m, sdv in
                       zip(e.mean(0), e.std(0), strict=True)),
                     f"{np.abs(e2).max():.2f}", f"{np.abs(e).max():.2f}", paper_note))
    how = ("channels weighted by their noise estimated from the data" if weighted
           else "plain sum, as the paper")
    what = ("σ = p % of each channel's peak, as the paper" if noise == "paper"
            else "gauge noise: one σ = p % of the overall peak strain")
    table = Table(f"§5.2 noise ({what}): parameter error %, mean ± std over {len(seeds)} "
                  f"noise seeds, the paper's two stages beside the refined answer ({how})",
                  ("noise %", "E_x two-stage", "E_y two-stage", "mu two-stage",
                   "E_x refined", "E_y refined", "mu refined", "max |err| two-stage",
                   "max |err| refined", "paper"), tuple(rows))
    return CaseReport(case="5.2", tables=(table,), numbers=numbers,
                      wall_time=time.perf_counter() - t0)


def case_5_4(*, quick: bool = False, seed: int = 0, method: str = "ce", n_jobs: int = 1,
             callback=None) -> CaseReport:
    """§5.4: the beam-and-slab bridge after Vransko, five unknowns."""
    t0 = time.perf_counter()
    s = _settings(quick)
    truth = paper.vransko_bridge()
    unknowns = Bridge.PARAM_FAMILIES
    rec = _crossing(truth, paper.vransko_sensors(), seed=2, approach=s["approach"])
    cal = calibrate(_start(truth, unknowns), [rec], paper.truck(),
                    road=paper.road(2, approach=s["approach"]), approach=s["approach"],
                    unknowns=unknowns, seed=seed, method=method, population=s["population"],
                    convergences=s["convergences"], n_jobs=n_jobs, callback=callback,
                    n_modes=20 if quick else None)
    rows = []
    for k in unknowns:
        t_paper, ce_paper = PAPER["5.4"][k]
        ours = float(cal.params[k].mean())
        two = float(cal.two_stage[k].mean())
        scale = 1e9 if k.startswith("E") else 1.0
        rows.append((k, f"{t_paper / scale:g}", f"{ce_paper / scale:g}",
                     f"{(ce_paper / t_paper - 1) * 100:+.2f}", f"{two / scale:.4g}",
                     format_pct(two, truth.params[k].mean(), 3), f"{ours / scale:.4g}",
                     format_pct(ours, truth.params[k].mean(), 3)))
    exact, calibrated = identify_forces(truth, rec), identify_forces(cal.bridge, rec)
    e_cal = force_errors(calibrated, rec.truth)
    tables = (
        Table("§5.4 Table 2: true → CE (paper) beside ours, two stages and refined (E in GPa)",
              ("parameter", "true", "paper CE", "paper error %", "two stages",
               "two-stage error %", "refined", "refined error %"),
              tuple(rows)),
        Table("§5.4 MFI with the calibrated model: weight error %, force RMS %",
              ("axle", "weight", "RMS"),
              tuple((str(i + 1), f"{w * 100:+.2f}", f"{r * 100:.2f}")
                    for i, (w, r) in enumerate(zip(e_cal.weight_error, e_cal.rms_error,
                                                   strict=True)))),
        _stage_table(cal),
    )
    numbers = {"errors": {k: float(pct_change(cal.params[k].mean(), truth.params[k].mean()))
                          for k in unknowns},
               "two_stage_errors": {k: float(pct_change(cal.two_stage[k].mean(),
                                                        truth.params[k].mean()))
                                    for k in unknowns},
               "mfi_weight_error": e_cal.weight_error.tolist(),
               "mfi_rms_error": e_cal.rms_error.tolist()}
    return CaseReport(case="5.4", tables=tables, numbers=numbers,
                      wall_time=time.perf_counter() - t0,
                      artefacts={"calibration": cal, "record": rec, "exact": exact,
                                 "calibrated": calibrated})


def case_5_3(*, quick: bool = False, seed: int = 0, bridges: Sequence[int] | None = None,
             n_jobs: int = 1, callback=None, budgets: tuple[int, int] | None = None,
             population: tuple[int, int] | None = None, refine: str = "lm",
             method: str = "ce") -> CaseReport:
    """§5.3: six zoned bridges; 48 unknowns (sub-structured CE) against one zone (3).

    Calibrated from two crossings of the paper truck (20 and 24 m/s; the paper: 20–25),
    then MFI of the calibration truck with each calibrated model.  The force error is the
    paper's Table 1 measure, Σ (identified − true wheel force)² over the central 80 %
    (kN², units not stated by the paper), averaged over the four wheels, with the RMS %
    beside it.  ``budgets`` (evaluations of the two stages) and ``population`` override the
    run sizes, ``refine="none"`` skips the joint refinement and ``method`` chooses the
    optimiser of the two stages (:func:`~bwim.calibration.calibrate`'s; ``"lm"`` makes
    small runs).
    """
    t0 = time.perf_counter()
    s = _settings(quick, population=population)
    approach = s["approach"]
    truths = paper.zoned_bridges(seed)
    which = list(range(6)) if bridges is None else list(bridges)
    if quick and bridges is None:
        which = [1]
    rows, numbers, zone_tables = [], {"48": {}, "3": {}, "bridge_Ex_error": {}}, []
    budgets = budgets or ((8000, 600) if quick else (40000, 1500))
    artefacts = {}
    for b in which:
        truth = truths[b]
        road_seed = 10 + b  # both crossings on one road, at two speeds
        recs = [_crossing(truth, paper.sensors(), seed=road_seed, approach=approach, speed=v)
                for v in (20.0, 24.0)]
        cal48 = _calibrate_runs(truth, recs, (4, 4), approach, road_seed, seed, s, budgets,
                                n_jobs, callback, population, refine, method)
        cal3 = _calibrate_runs(truth, recs, (1, 1), approach, road_seed, seed, s, budgets,
                               n_jobs, callback, population, refine, method)
        row = [f"#{b + 1}", f"{paper.ZONE_SPREADS[b] * 100:g}"]
        for label, cal in (("48", cal48), ("3", cal3)):
            ident = _mfi(cal.bridge, recs[0])
            err = force_errors(ident, recs[0].truth)
            numbers[label][b + 1] = {"sum_sq": float(err.sum_sq.mean()),
                                     "rms": float(err.wheel_rms_error.mean())}
            row += [f"{err.sum_sq.mean():.1f}", f"{err.wheel_rms_error.mean() * 100:.1f}"]
        ex_err = np.abs(pct_change(cal48.bridge.E_x, truth.E_x))
        ex_two = np.abs(pct_change(cal48.two_stage["E_x"], truth.E_x))
        numbers["bridge_Ex_error"][b + 1] = float(ex_err.mean())
        numbers.setdefault("bridge_Ex_error_two_stage", {})[b + 1] = float(ex_two.mean())
        row += [f"{ex_two.mean():.2f}", f"{ex_err.mean():.2f}", f"{PAPER['5.3_48'][b]:g}",
                f"{PAPER['5.3_3'][b]:g}"]
        rows.append(tuple(row))
        artefacts[b + 1] = {"truth": truth, "cal48": cal48, "cal3": cal3, "record": recs[0]}
        zone_tables.append(Table(
            f"§5.3 bridge #{b + 1}: E_x per zone, GPa (true → calibrated, error %)",
            ("zone", "true", "calibrated", "error %"),
            tuple((str(z + 1), f"{truth.E_x[z] / 1e9:.2f}", f"{cal48.bridge.E_x[z] / 1e9:.2f}",
                   format_pct(cal48.bridge.E_x[z], truth.E_x[z]))
                  for z in range(truth.n_zones))))
    table = Table(
        "§5.3 Table 1: MFI force error of the calibration truck with each calibrated model "
        "(Σ squared error, kN², mean over wheels; RMS % of the static wheel load), and the "
        "mean |E_x error| % of the 16 zones after the paper's two stages and refined "
        "(paper, bridge #2: 1.0 %)",
        ("bridge", "spread %", "48: Σ²", "48: RMS %", "3: Σ²", "3: RMS %",
         "|E_x err| two-stage %", "|E_x err| refined %",
         "paper 48", "paper 3"), tuple(rows))
    return CaseReport(case="5.3", tables=(table, *zone_tables), numbers=numbers,
                      wall_time=time.perf_counter() - t0, artefacts=artefacts)


def _calibrate_runs(truth, recs, zones, approach, road_seed, seed, s, budgets, n_jobs,
                    callback, population=None, refine="lm", method="ce") -> Calibration:
    nzx, nzy = zones
    start = paper.slab_bridge(zones=zones)
    start = _start(start, ("E_x", "E_y", "mu"))
    return calibrate(start, recs, paper.truck(),
                     road=paper.road(road_seed, approach=approach), approach=approach,
                     seed=seed, population=population or (
                         s["population"][0],
                         min(100, 10 * nzx * nzy) if nzx * nzy > 1 else s["population"][1]),
                     convergences=s["convergences"], max_evals=budgets, n_jobs=n_jobs,
                     callback=callback, refine=refine, method=method)


def compare_methods(*, quick: bool = False, seed: int = 0, budget: int | None = None,
                    budgets: tuple[int, int] | None = None,
                    population: tuple[int, int] | None = None,
                    methods: Sequence[str] = ("CE", "CE sub-structured", "CMA-ES",
                                              "least squares"),
                    refine: str = "lm") -> CaseReport:
    """Plain CE, sub-structured CE, CMA-ES and least squares, measured in one run.

    * §5.1 stiffness stage (2 unknowns): evaluations and wall time until every parameter
      is within 1 % of the stage's optimum θ* (found first by least squares to full
      precision; here θ* is within the dynamics' bias of the truth).
    * §5.3 bridge #2 (48 unknowns): the whole calibration with each method for the
      paper's two stages (the same least-squares refinement after), scored against the
      true zone moduli.  The pseudo-static optimum of 32 zone moduli is itself far from
      the truth (the dynamics' bias grows along the objective's weak directions), so a
      race to it would compare methods on reaching a wrong point
      (``docs/paper_cases.md``, "Beyond the paper").

    ``budget`` (the race's evaluations), ``budgets`` (the two stages' evaluations in the
    48-unknown runs) and ``population`` override the run sizes; ``methods`` chooses the
    48-unknown runs and ``refine="none"`` skips their refinement (smaller runs).
    """
    from bwim.calibration.problem import ParameterSpace, StaticObjective, neighbour_map
    from bwim.calibration.stages import SUBSTRUCTURED_SMOOTHING

    t0 = time.perf_counter()
    approach = 20.0 if quick else paper.APPROACH
    budget = budget or (20000 if quick else 200000)
    rows, numbers = [], {}
    truth = paper.slab_bridge()
    rec = _crossing(truth, paper.sensors(), seed=11, approach=approach)
    start = _start(truth, ("E_x", "E_y"))
    space = ParameterSpace(start, ("E_x", "E_y"))
    obj = StaticObjective(space, [rec], paper.truck())
    star = _stage_optimum(obj, space)

    def close(x):
        return bool(np.all(np.abs(np.asarray(x) / star - 1) <= 0.01))

    for name in ("CE", "CMA-ES", "least squares"):
        t = time.perf_counter()
        n, used, final = _race(name, obj, space, close, seed=seed, budget=budget,
                               neighbours=neighbour_map(space, rec.sensors),
                               smoothing=SUBSTRUCTURED_SMOOTHING)
        dev = float(np.abs(final / star - 1).max() * 100)
        numbers[("5.1", name)] = (n, time.perf_counter() - t, used, dev)
        rows.append(("§5.1 stiffness stage", name, "not reached" if n is None else f"{n:,}",
                     f"{time.perf_counter() - t:.2f}", f"{dev:.3g}"))
    rows.append(("§5.1 stiffness stage", "CE sub-structured", "n/a (one zone)", "—", "—"))
    table1 = Table("§5.1: evaluations and wall time until both stiffness parameters are "
                   "within 1 % of the static stage's optimum (and the final deviation %)",
                   ("problem", "method", "evaluations", "time (s)", "final dev %"),
                   tuple(rows))

    s = _settings(quick, population=population)
    truth3 = paper.zoned_bridges(0)[1]
    recs = [_crossing(truth3, paper.sensors(), seed=11, approach=approach, speed=v)
            for v in (20.0, 24.0)]
    start3 = _start(paper.slab_bridge(zones=(4, 4)), ("E_x", "E_y", "mu"))
    budgets = budgets or ((8000, 600) if quick else (40000, 1500))
    rows3 = []
    for name, kw in (("CE", {"method": "ce", "substructure": False}),
                     ("CE sub-structured", {"method": "ce", "substructure": True}),
                     ("CMA-ES", {"method": "cma"}),
                     ("least squares", {"method": "lm"})):
        if name not in methods:
            continue
        t = time.perf_counter()
        cal = calibrate(start3, recs, paper.truck(), road=paper.road(11, approach=approach),
                        approach=approach, seed=seed, max_evals=budgets,
                        population=population or (s["population"][0], 100),
                        convergences=s["convergences"], refine=refine, **kw)
        e = np.abs(np.concatenate([pct_change(cal.params[k], truth3.params[k])
                                   for k in ("E_x", "E_y")]))
        numbers[("5.3", name)] = {"nfev": cal.nfev, "time": time.perf_counter() - t,
                                  "mean": float(e.mean()), "max": float(e.max())}
        rows3.append(("§5.3 bridge #2, 48 unknowns", name,
                      f"{cal.stages[0].nfev:,} + {cal.stages[1].nfev:,}",
                      f"{cal.stages[-1].nfev:,}", f"{time.perf_counter() - t:.1f}",
                      f"{e.mean():.2f}", f"{e.max():.2f}"))
    table2 = Table("§5.3 bridge #2: the whole calibration with each method for the two "
                   "stages (then the same least-squares refinement): evaluations (stiffness + "
                   "mass, refinement), wall time, and |E_x, E_y error| % against the truth",
                   ("problem", "method", "stage evaluations", "refinement", "time (s)",
                    "mean err %", "max err %"), tuple(rows3))
    return CaseReport(case="compare", tables=(table1, table2), numbers=numbers,
                      wall_time=time.perf_counter() - t0)


def _stage_optimum(obj, space):
    """The stiffness stage's optimum to full precision (bounded least squares with the
    adjoint Jacobian)."""
    return run_stage(Method.LM, obj, space, options={"xtol": 1e-12, "ftol": 1e-12}).x


class _Counted:
    """An objective that counts its residual and Jacobian evaluations and notes the first
    residual evaluation at a point satisfying ``close``."""

    def __init__(self, objective, close):
        self.objective, self.close = objective, close
        self.calls, self.first = 0, None

    def __call__(self, theta):
        return self.objective(theta)

    def residuals(self, theta):
        self.calls += 1
        if self.first is None and self.close(theta):
            self.first = self.calls
        return self.objective.residuals(theta)

    def jacobian(self, theta):
        self.calls += 1
        return self.objective.jacobian(theta)


def _race(name, obj, space, close, *, seed, budget, neighbours, smoothing):
    """(evaluations until ``close(best)`` or None, evaluations used, final best x).

    The population methods stop at the target, at their own stopping rule, or at the
    budget; least squares runs to its own convergence (its evaluations count the
    Jacobian's).
    """
    if name == "least squares":
        counted = _Counted(obj, close)
        res = run_stage(Method.LM, counted, space)
        return counted.first, counted.calls, res.x
    if name.startswith("CE"):
        sub = name.endswith("structured")
        res = run_stage(Method.CE, obj, space, seed=seed, population=200, convergences=50,
                        max_evals=budget, neighbours=neighbours if sub else None,
                        options={"smoothing": smoothing} if sub else None, stop=close)
    else:
        res = run_stage(Method.CMA, obj, space, seed=seed, max_evals=budget, stop=close)
    return (res.nfev if close(res.x) else None), res.nfev, res.x


#: The reproducible cases, by the names the command line uses.
CASES = {"5.1": case_5_1, "5.2": case_5_2, "5.3": case_5_3, "5.4": case_5_4,
         "compare": compare_methods}
