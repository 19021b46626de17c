"""Calibration when the model is not the truth (issue 12): finer-mesh data, gauge noise.

Targets (issue 12, "Paper cases with realistic errors"):

* data from a 24 × 16 mesh of the paper's slab with 2 % gauge noise (one σ = 2 % of the
  record's peak strain on every channel): the §5.1 parameters of the 12 × 8 model stay
  within 1 % of the 24 × 16 model's own calibration on the same data;
* §5.2 at 5 % gauge noise keeps every parameter within 1 %.

And how much the road assumption matters (exact, measured with 1 mm RMS error, flat),
beside the road-free calibration (bwim.calibration.calibrate_quasistatic) that needs none.

Every calibration here is the §5.1 setup (bwim.paper: the truck at 20 m/s in lane 2 m on
the paper's road, known exactly; start E_x × 0.8, E_y × 1.2, μ × 1.25) with least
squares for both stages (``method="lm"``; the stages' optimum, not the optimiser, is
what is measured) and a 20 m approach.  Beside it, the mesh check of the 12 × 8 model
(:func:`bwim.fe.convergence.check_mesh`), which explains the misses.

Last table (issue 12, "Weighing with a mismatched model"; :func:`mismatch_weighing`):
24 × 16 data, 2 % absolute gauge noise, the 12 × 8 and 18 × 12 models calibrated from two
crossings (15, 22 m/s) with the road measured to 1 mm RMS, with no road, and with the exact
road, then six other vehicles weighed by MFI; beside them the same models with the true
parameters, the data's own model, and the true forces averaged over MFI's windows (the
limit of a window-mean static weight).  The calibrations take ``calibrate``'s default mass
(``mass="auto"``: the free vibration of the 1 s tail); one row repeats the corrected chain
with the dynamic mass (``mass="dynamic"``, the paper's).  Below it, issue 23's target 3
(:func:`target_exact_model`): the corrected chain against the exact 24 × 16 model, GVW
within 0.5 points and every vehicle's largest axle error within 1 point.
"""

from __future__ import annotations

import time

import numpy as np

import bwim
from benchmarks._timing import print_table
from bwim import paper
from bwim.calibration import calibrate, calibrate_quasistatic, road_sensitivity
from bwim.fe.convergence import check_mesh, refine
from bwim.mfi import force_errors, identify_forces
from bwim.vehicles import three_axle_truck, tractor_semitrailer, two_axle_truck

APPROACH = 20.0
START = {"E_x": 0.8, "E_y": 1.2, "mu": 1.25}
KEYS = tuple(START)


def _record(nx: int, ny: int):
    truth = paper.slab_bridge(nx=nx, ny=ny)
    return truth, bwim.simulate(truth, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                                sensors=paper.sensors(),
                                road=paper.road(1, approach=APPROACH), approach=APPROACH)


def _calibrate(nx: int, ny: int, rec, *, seed: int = 0, weights=None, mesh_correction=0):
    b = paper.slab_bridge(nx=nx, ny=ny)
    b = b.with_params(**{k: b.params[k] * f for k, f in START.items()})
    return calibrate(b, [rec], paper.truck(), road=paper.road(1, approach=APPROACH),
                     approach=APPROACH, seed=seed, method="lm", weights=weights,
                     mesh_correction=mesh_correction)


def _pct(cal, truth, which="params"):
    src = cal.params if which == "params" else cal.two_stage
    return np.array([(src[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS])


def mesh_check():
    rec = _record(12, 8)[1]
    k = int(np.argmax(np.abs(rec.data).sum(axis=1)))
    p = rec.passage
    x = p.wheel_x(rec.time[k:k + 1])[0]
    f = paper.truck().model().static_forces
    loads = [bwim.PointLoad(x=float(a), y=float(b), P=float(c))
             for a, b, c in zip(x, p.wheel_y, f, strict=True) if 0 < a < paper.SLAB_LENGTH]
    t0 = time.perf_counter()
    mc = check_mesh(paper.slab_bridge(), paper.sensors(), loads, tol=0.01)
    dt = time.perf_counter() - t0
    rel = mc.relative_error
    rows = [[f"{nx}x{ny}", f"{rel[i, :9].max() * 100:.2f}", f"{rel[i, 9:].max() * 100:.2f}",
             mc.sensors[9 + int(np.argmax(rel[i, 9:]))]]
            for i, (nx, ny) in enumerate(mc.meshes)]
    return mc, dt, rows


#: (data mesh, model mesh, mesh_correction levels) of the §5.1 mismatch table.
MISMATCH_CASES = (((24, 16), (12, 8), 0), ((24, 16), (12, 8), 1), ((48, 32), (24, 16), 0),
                  ((48, 32), (12, 8), 0), ((48, 32), (12, 8), 1), ((48, 32), (12, 8), 2))


def mismatch(noise: float = 0.02, cases=MISMATCH_CASES):
    """§5.1 calibrated on each case's model from data of a finer mesh, against the data
    mesh's own calibration; ``levels`` > 0: with the mesh defect correction."""
    rows, numbers, data = [], {}, {}
    for data_mesh, model_mesh, levels in cases:
        if data_mesh not in data:
            truth, clean = _record(*data_mesh)
            rec = clean.with_noise(noise, seed=5)
            t0 = time.perf_counter()
            own = _calibrate(*data_mesh, rec)
            data[data_mesh] = (truth, rec, own, time.perf_counter() - t0)
            rows.append([f"{data_mesh[0]}x{data_mesh[1]}", "(own mesh)", "",
                         *(f"{v:+.2f}" for v in _pct(own, truth, "two")),
                         *(f"{v:+.2f}" for v in _pct(own, truth)),
                         f"{data[data_mesh][3]:.1f}", ""])
        truth, rec, own, _ = data[data_mesh]
        t0 = time.perf_counter()
        cal = _calibrate(*model_mesh, rec, mesh_correction=levels)
        dt = time.perf_counter() - t0
        diff = np.array([(cal.params[k][0] / own.params[k][0] - 1) * 100 for k in KEYS])
        numbers[(data_mesh, model_mesh, levels)] = diff
        corr = ("none" if not levels else
                f"{cal.mesh_correction.mesh[0]}x{cal.mesh_correction.mesh[1]}, "
                f"{cal.mesh_correction.passes} passes")
        rows.append([f"{data_mesh[0]}x{data_mesh[1]}", f"{model_mesh[0]}x{model_mesh[1]}", corr,
                     *(f"{v:+.2f}" for v in _pct(cal, truth, "two")),
                     *(f"{v:+.2f}" for v in _pct(cal, truth)), f"{dt:.1f}",
                     ("met" if np.abs(diff).max() <= 1.0 else "MISSED") + " ("
                     + ", ".join(f"{v:+.2f}" for v in diff) + ")"])
    return rows, numbers


def noise_5(seeds=range(12), weights="noise"):
    """§5.2 at 5 % gauge noise over ``seeds``: per model, the mean ± sample std of the
    errors, the least-squares standard errors, the largest error and the share of seeds
    whose every parameter is within 1 %.  The data's own 24x16 model is the reference: what
    it cannot reach, no model can (the standard error is an information limit of one
    crossing)."""
    truth, clean = _record(24, 16)
    rows = []
    for model_mesh, levels in (((12, 8), 0), ((12, 8), 1), ((24, 16), 0)):
        errs, ses = [], []
        for sd in seeds:
            rec = clean.with_noise(0.05, seed=1000 + sd)
            cal = _calibrate(*model_mesh, rec, seed=sd, weights=weights,
                             mesh_correction=levels)
            errs.append(_pct(cal, truth))
            ses.append([cal.uncertainty[k][0] / truth.params[k][0] * 100 for k in KEYS])
        e, se = np.array(errs), np.array(ses)
        rows.append([f"{model_mesh[0]}x{model_mesh[1]}" + (" corrected" if levels else ""),
                     len(e),
                     *(f"{m:+.2f} ± {s:.2f}" for m, s in zip(e.mean(0), e.std(0, ddof=1),
                                                             strict=True)),
                     *(f"{v:.2f}" for v in se.mean(0)),
                     f"{np.abs(e).max():.2f}",
                     f"{np.mean(np.all(np.abs(e) <= 1.0, axis=1)):.0%}"])
    return rows


def measured_road(road, rms: float = 1e-3, seed: int = 3):
    """``road`` as a profilometer might give it: plus an error of ``rms`` m RMS, white
    at the profile's spacing then averaged over the tyre patch (and rescaled to ``rms``)."""
    rng = np.random.default_rng(seed)
    noise = bwim.RoadProfile(x=road.x, elevation=rng.standard_normal(road.x.size))
    e = noise.smoothed(paper.TYRE_PATCH)
    err = np.interp(road.x, e.x, e.elevation)
    err *= rms / np.sqrt(np.mean(err**2))
    return bwim.RoadProfile(x=road.x, elevation=road.elevation + err)


def road_effect():
    truth, clean = _record(24, 16)
    rec = clean.with_noise(0.02, seed=5)
    road = paper.road(1, approach=APPROACH)
    cal = _calibrate(24, 16, rec)
    t0 = time.perf_counter()
    rs = road_sensitivity(cal.bridge, [rec], paper.truck(), road,
                          {"measured, 1 mm RMS error": measured_road(road), "flat": None},
                          approach=APPROACH)
    dt = time.perf_counter() - t0
    rows = [["exact (calibrated)", *(f"{v:+.2f}" for v in _pct(cal, truth))]]
    for name, d in rs.shifts.items():
        rows.append([name, *(f"{((1 + v) * cal.params[k][0] / truth.params[k][0] - 1) * 100:+.2f}"
                            for v, k in zip(d, KEYS, strict=True))])
    return rows, dt


def _start24():
    b = paper.slab_bridge(nx=24, ny=16)
    return b.with_params(**{k: b.params[k] * f for k, f in START.items()})


def roadfree_same_record():
    """calibrate_quasistatic on road_effect's record (20 m/s, no tail: no mass)."""
    truth, clean = _record(24, 16)
    rec = clean.with_noise(0.02, seed=5)
    t0 = time.perf_counter()
    c = calibrate_quasistatic(_start24(), [rec], paper.truck())
    dt = time.perf_counter() - t0
    e = [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in ("E_x", "E_y")]
    return ["NONE (road-free, quasi-static)", *(f"{v:+.2f}" for v in e),
            "n/a (no free vibration)"], dt


def roadfree(road_seeds=range(1, 7), variants=None):
    """Road-free calibration over ISO roads ``road_seeds`` (paper class): 24x16 data and
    model, 2 % gauge noise, 1 s tail recorded; one crossing (15 or 22 m/s) or both."""
    variants = variants or {
        "default (K=4, inertia 3 modes)": {},
        "no force nuisance (K=0)": {"n_basis": 0},
        "no inertia correction": {"inertia_modes": 0},
    }
    truth = paper.slab_bridge(nx=24, ny=16)
    errs, times = {}, {}
    for rs in road_seeds:
        recs = []
        for k, v in enumerate((15.0, 22.0)):
            r = bwim.simulate(truth, paper.truck(), speed=v, lane=paper.LANE,
                              sensors=paper.sensors(), road=paper.road(rs, approach=APPROACH),
                              approach=APPROACH, tail=1.0)
            recs.append(r.with_noise(0.02, seed=10 * rs + k))
        for name, kw in variants.items():
            for runs, sel in (("15 m/s", recs[:1]), ("22 m/s", recs[1:]), ("both", recs)):
                t0 = time.perf_counter()
                c = calibrate_quasistatic(_start24(), sel, paper.truck(), **kw)
                times.setdefault((name, runs), []).append(time.perf_counter() - t0)
                errs.setdefault((name, runs), []).append(
                    [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS])
    rows = []
    for (name, runs), e in errs.items():
        e = np.array(e)
        rows.append([name, runs, len(e),
                     *(f"{m:+.2f} / {r:.2f} / {x:.2f}" for m, r, x in
                       zip(e.mean(0), np.sqrt((e**2).mean(0)), np.abs(e).max(0),
                           strict=True)),
                     f"{np.mean(times[(name, runs)]):.1f}"])
    return rows, errs


def vransko_mismatch():
    """§5.4 (beam-and-slab, five parameters) on data from the model bisected once (20x20
    plate elements, girders on the same lines), 2 % gauge noise, road 2, 20 modes; the
    paper's 10x10 model from the reproduction's start, with and without the mesh
    correction.  Error % against the truth.  Measured: uncorrected E_x −24.6 %, μ +18.7 %;
    corrected E_x +1.1 %, E_y +0.2 %, E_girder −0.03 %, while μ and μ_girder split the
    mass −10.7 / +10.7 % (noise-free, corrected: within 0.4 %): one crossing at 2 % noise
    tells the total mass but hardly how slab and girders share it."""
    truth = paper.vransko_bridge()
    truck, road = paper.truck(), paper.road(2, approach=APPROACH)
    rec = bwim.simulate(refine(truth), truck, speed=paper.SPEED, lane=paper.LANE,
                        sensors=paper.vransko_sensors(), road=road, approach=APPROACH)
    rec = rec.with_noise(0.02, seed=3)
    p = truth.params
    start = truth.with_params(E_x=0.85 * p["E_x"], E_y=1.15 * p["E_y"], mu=1.2 * p["mu"],
                              E_girder=0.9 * p["E_girder"], mu_girder=0.85 * p["mu_girder"])
    names = ("E_x", "E_y", "mu", "E_girder", "mu_girder")
    rows = []
    for levels in (0, 1):
        t0 = time.perf_counter()
        c = calibrate(start, [rec], truck, road=road, approach=APPROACH, method="lm",
                      unknowns=names, n_modes=20, weights="noise", mesh_correction=levels)
        rows.append(["20x20 (bisected)" if levels else "none",
                     *(f"{(c.params[k][0] / p[k][0] - 1) * 100:+.2f}" for k in names),
                     f"{time.perf_counter() - t0:.1f}"])
    return rows


def truck_mismatch_data():
    """The calibration truck's model is not the data's truck: 24x16 data of the paper
    truck with suspension stiffness x1.3, damping x0.6, tyre stiffness x0.85 (a truck whose
    springs are known only nominally), two crossings (15 and 22 m/s, 1 s tail) on road 1,
    2 % gauge noise.  Returns (truth, road, records, the data's truck, the nominal truck)."""
    import dataclasses

    nominal = paper.truck()
    other = dataclasses.replace(nominal,
                                suspension_stiffness=1.3 * nominal.suspension_stiffness,
                                suspension_damping=0.6 * nominal.suspension_damping,
                                tyre_stiffness=0.85 * nominal.tyre_stiffness)
    truth = paper.slab_bridge(nx=24, ny=16)
    road = paper.road(1, approach=APPROACH)
    recs = [bwim.simulate(truth, other, speed=v, lane=paper.LANE, sensors=paper.sensors(),
                          road=road, approach=APPROACH, tail=1.0) for v in CAL_SPEEDS]
    sigma = 0.02 * max(float(np.abs(r.data).max()) for r in recs)
    recs = [r.with_noise(sigma=sigma, seed=40 + k) for k, r in enumerate(recs)]
    return truth, road, recs, other, nominal


def vehicle_mismatch():
    """:func:`truck_mismatch_data` on the 12x8 model from the weighing target's start,
    calibrated with the data's truck model or the nominal one, with and without the mesh
    correction, and road-free."""
    truth, road, recs, other, nominal = truck_mismatch_data()
    start = paper.slab_bridge().with_params(**WEIGH_START)
    rows = []
    for label, veh in (("the data's truck", other), ("nominal truck", nominal)):
        for levels in (0, 1):
            t0 = time.perf_counter()
            c = calibrate(start, recs, veh, road=road, approach=APPROACH, method="lm",
                          weights="noise", mesh_correction=levels)
            rows.append([label, "24x16" if levels else "none",
                         *(f"{(c.params[k][0] / truth.params[k][0] - 1) * 100:+.2f}"
                           for k in KEYS), f"{time.perf_counter() - t0:.1f}"])
    for levels in (0, 1):
        t0 = time.perf_counter()
        c = calibrate_quasistatic(start, recs, nominal, mesh_correction=levels)
        rows.append(["nominal truck, road-free", "24x16" if levels else "none",
                     *(f"{(c.params[k][0] / truth.params[k][0] - 1) * 100:+.2f}"
                       for k in KEYS), f"{time.perf_counter() - t0:.1f}"])
    return rows


# --- issue 12, first target: weighing with a mismatched model -----------------------------
#: The calibration start of the weighing target (issue 12): E_x, E_y in Pa, μ in kg/m².
WEIGH_START = {"E_x": 28e9, "E_y": 42e9, "mu": 1950.0}
CAL_SPEEDS = (15.0, 22.0)  #: m/s, the two calibration crossings
#: The six weighed vehicles: (label, vehicle factory, speed m/s, lane m, ISO road seed).
WEIGHED = (
    ("3-axle", three_axle_truck, 14.0, 2.0, 11),
    ("3-axle", three_axle_truck, 23.0, 6.0, 12),
    ("semi", tractor_semitrailer, 18.0, 2.0, 13),
    ("semi", tractor_semitrailer, 25.0, 6.0, 14),
    ("2-axle", two_axle_truck, 12.0, 6.0, 15),
    ("2-axle", two_axle_truck, 20.0, 2.0, 16),
)


def weighing_data(data_mesh=(24, 16), noise=0.02):
    """The target's data: 24 × 16 truth, paper truck at 15 and 22 m/s on ISO road 1 (1 s
    tail), six other vehicles on roads 11-16; one absolute σ for every record and gauge,
    ``noise`` × the peak strain of the calibration crossings."""
    truth = paper.slab_bridge(nx=data_mesh[0], ny=data_mesh[1])
    road = paper.road(1, approach=APPROACH)
    cal = [bwim.simulate(truth, paper.truck(), speed=v, lane=paper.LANE,
                         sensors=paper.sensors(), road=road, approach=APPROACH, tail=1.0)
           for v in CAL_SPEEDS]
    sigma = noise * max(float(np.abs(r.data).max()) for r in cal)
    cal = [r.with_noise(sigma=sigma, seed=40 + k) for k, r in enumerate(cal)]
    weigh = [bwim.simulate(truth, make(), speed=v, lane=lane, sensors=paper.sensors(),
                           road=paper.road(rs, approach=APPROACH), approach=APPROACH)
             .with_noise(sigma=sigma, seed=60 + k)
             for k, (_, make, v, lane, rs) in enumerate(WEIGHED)]
    return truth, road, cal, weigh, sigma


def weigh_all(bridge, records):
    """MFI (bwim.identify_forces, defaults) of each record on ``bridge``: per vehicle the
    GVW error % and the axle errors % (array)."""
    out = []
    for r in records:
        e = force_errors(identify_forces(bridge, r), r.truth)
        out.append((e.gvw_error * 100, e.weight_error * 100))
    return out


def window_mean_limit(bridge, records):
    """The best a static weight from the window mean can do: the *true* dynamic axle forces
    averaged over MFI's own windows, error % against the static loads (GVW, axles)."""
    out = []
    for r in records:
        ident = identify_forces(bridge, r)
        t, tr = ident.time, r.truth
        ax = np.array([tr.axle_forces[(t >= lo) & (t <= hi), a].mean()
                       for a, (lo, hi) in enumerate(ident.axle_windows)])
        out.append(((ax.sum() / tr.gvw - 1) * 100, (ax / tr.static_axle_loads - 1) * 100))
    return out


def mismatch_weighing(models=((12, 8), (18, 12))):
    """Issue 12's first target: calibrate each model (never the data's 24 × 16 mesh) from the
    two crossings with (a) the road measured with 1 mm RMS error, (b) no road
    (calibrate_quasistatic), (c) the exact road; then weigh the six vehicles by MFI."""
    truth, road, cal_recs, weigh_recs, sigma = weighing_data()
    roads = {"measured 1 mm": measured_road(road), "none (quasi-static)": None,
             "exact": road}
    rows, results = [], {}

    def row(model, label, errs, res, dt):
        gv = max(abs(g) for g, _ in res)
        ax = max(float(np.abs(a).max()) for _, a in res)
        rows.append([model, label, *errs,
                     *(f"{g:+.2f}/{float(np.abs(a).max()):.1f}" for g, a in res),
                     dt, "met" if gv <= 2.0 and ax <= 5.0 else
                     f"MISSED ({gv:.1f}/{ax:.1f})"])

    for nx, ny in models:
        model = f"{nx}x{ny}"
        start = paper.slab_bridge(nx=nx, ny=ny).with_params(**WEIGH_START)
        for label, rd in roads.items():
            t0 = time.perf_counter()
            if label.startswith("none"):
                c = calibrate_quasistatic(start, cal_recs, paper.truck())
            else:
                c = calibrate(start, cal_recs, paper.truck(), road=rd, approach=APPROACH,
                              method="lm", weights="noise", seed=0)
            dt = time.perf_counter() - t0
            errs = [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS]
            res = weigh_all(c.bridge, weigh_recs)
            results[(model, label)] = (errs, res)
            row(model, label, [f"{v:+.2f}" for v in errs], res, f"{dt:.1f}")
        res = weigh_all(paper.slab_bridge(nx=nx, ny=ny), weigh_recs)
        results[(model, "true parameters")] = ([0.0] * 3, res)
        row(model, "(true E, mu)", ["0"] * 3, res, "")
    # the 12x8 model with the mesh defect correction by its 24x16 bisection, measured road;
    # MFI on the 12x8 model with those parameters, and on its bisection
    start = paper.slab_bridge().with_params(**WEIGH_START)
    t0 = time.perf_counter()
    c = calibrate(start, cal_recs, paper.truck(), road=roads["measured 1 mm"],
                  approach=APPROACH, method="lm", weights="noise", seed=0, mesh_correction=1)
    dt = time.perf_counter() - t0
    errs = [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS]
    for model, bridge in (("12x8 corrected", c.bridge),
                          ("12x8 corrected, MFI 24x16", c.mesh_correction.bridge)):
        res = weigh_all(bridge, weigh_recs)
        results[(model, "measured 1 mm")] = (errs, res)
        row(model, "measured 1 mm", [f"{v:+.2f}" for v in errs], res, f"{dt:.1f}")
    t0 = time.perf_counter()
    c = calibrate(start, cal_recs, paper.truck(), road=roads["measured 1 mm"],
                  approach=APPROACH, method="lm", weights="noise", seed=0, mesh_correction=1,
                  mass="dynamic")
    dt = time.perf_counter() - t0
    errs = [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS]
    res = weigh_all(c.mesh_correction.bridge, weigh_recs)
    results[("12x8 corrected, MFI 24x16", "measured 1 mm, mass dynamic")] = (errs, res)
    row("12x8 corrected, MFI 24x16", "measured 1 mm, mass dynamic",
        [f"{v:+.2f}" for v in errs], res, f"{dt:.1f}")
    t0 = time.perf_counter()
    c = calibrate_quasistatic(start, cal_recs, paper.truck(), mesh_correction=1)
    dt = time.perf_counter() - t0
    errs = [(c.params[k][0] / truth.params[k][0] - 1) * 100 for k in KEYS]
    res = weigh_all(c.mesh_correction.bridge, weigh_recs)
    results[("12x8 corrected, MFI 24x16", "none (quasi-static)")] = (errs, res)
    row("12x8 corrected, MFI 24x16", "none (quasi-static)", [f"{v:+.2f}" for v in errs], res,
        f"{dt:.1f}")
    res = weigh_all(truth, weigh_recs)
    results[("24x16", "data model")] = ([0.0] * 3, res)
    row("24x16 (data)", "(inverse crime)", ["0"] * 3, res, "")
    res = window_mean_limit(truth, weigh_recs)
    results[("limit", "window mean")] = ([0.0] * 3, res)
    row("true forces", "window mean", ["", "", ""], res, "")
    return rows, results, sigma


def target_exact_model(results, chain=("12x8 corrected, MFI 24x16", "measured 1 mm")):
    """Issue 23, target 3, from :func:`mismatch_weighing`'s ``results``: per vehicle the
    chain's GVW error minus the exact 24 × 16 model's (points) and its largest |axle error|
    minus the exact model's; met when every GVW is within 0.5 points and no largest axle
    error exceeds the exact model's by more than 1 point."""
    got, exact = results[chain][1], results[("24x16", "data model")][1]
    dg = [g - g0 for (g, _), (g0, _) in zip(got, exact, strict=True)]
    da = [float(np.abs(a).max() - np.abs(a0).max())
          for (_, a), (_, a0) in zip(got, exact, strict=True)]
    met = max(abs(v) for v in dg) <= 0.5 and max(da) <= 1.0
    return [[f"{chain[0]}, road {chain[1]}", *(f"{g:+.2f}/{a:+.2f}" for g, a in
                                               zip(dg, da, strict=True)),
             "met" if met else "MISSED"]]


def corrected_chain(data=None):
    """The weighing target's calibration with the mesh correction: the 12x8 model from
    28/42 GPa, 1950 kg/m², the two crossings of :func:`weighing_data` (or ``data``, its
    result), the road measured with 1 mm RMS error, ``calibrate``'s default mass (the free
    vibration of the tail); returns the Calibration (its ``mesh_correction.bridge`` is
    the 24x16 model the parameters belong to, the one to weigh with)."""
    _, road, cal_recs, _, _ = weighing_data() if data is None else data
    return calibrate(paper.slab_bridge().with_params(**WEIGH_START), cal_recs, paper.truck(),
                     road=measured_road(road), approach=APPROACH, method="lm",
                     weights="noise", seed=0, mesh_correction=1)


def smooth_road_records(iso_class: str = "A", sigma: float | None = None,
                        data_mesh: tuple[int, int] = (24, 16)):
    """The six weighed vehicles of :data:`WEIGHED` on ISO ``iso_class`` roads (a WIM-grade
    approach: COST 323 asks for a smooth one) with the same seeds, data from the
    ``data_mesh`` slab and the same gauge noise as the target's (``sigma``, default
    :func:`weighing_data`'s)."""
    truth = paper.slab_bridge(nx=data_mesh[0], ny=data_mesh[1])
    sigma = weighing_data()[4] if sigma is None else sigma
    recs = []
    for k, (_, make, v, lane, rs) in enumerate(WEIGHED):
        rd = bwim.RoadProfile.iso8608(iso_class, length=APPROACH + 70.0,
                                      start=-(APPROACH + 25.0), seed=rs).smoothed(
            paper.TYRE_PATCH)
        recs.append(bwim.simulate(truth, make(), speed=v, lane=lane, sensors=paper.sensors(),
                                  road=rd, approach=APPROACH).with_noise(sigma=sigma,
                                                                         seed=60 + k))
    return truth, recs


def weighing_smooth_roads(iso_class: str = "A"):
    """:func:`smooth_road_records` weighed by the corrected chain, the 12x8 model with the
    true parameters, the data's own 24x16 model, and the window-mean limit.  Separates
    what the road's roughness costs (the window mean) from what the mesh costs."""
    data = weighing_data()
    truth, recs = smooth_road_records(iso_class, sigma=data[4])
    rows = []
    for label, res in (("12x8 calibrated (road 1 mm, corrected), MFI on 24x16",
                        weigh_all(corrected_chain(data).mesh_correction.bridge, recs)),
                       ("12x8, true E, mu", weigh_all(paper.slab_bridge(), recs)),
                       ("24x16 (the data's)", weigh_all(truth, recs)),
                       ("true forces, window mean", window_mean_limit(truth, recs))):
        gv = max(abs(g) for g, _ in res)
        ax = max(float(np.abs(a).max()) for _, a in res)
        rows.append([label, *(f"{g:+.2f}/{float(np.abs(a).max()):.1f}" for g, a in res),
                     "met" if gv <= 2.0 and ax <= 5.0 else f"MISSED ({gv:.1f}/{ax:.1f})"])
    return rows


def main() -> None:
    mc, dt, rows = mesh_check()
    print_table(f"Mesh check of the paper's 12x8 slab at its 18 sensors (static truck "
                f"loads where the strains peak; {dt:.1f} s; observed order {mc.order:.2f}): "
                "largest estimated discretisation error %",
                ["mesh", "strain_x", "strain_y", "worst strain_y sensor"], rows)
    rows, _ = mismatch()
    print_table("§5.1 with finer-mesh data and 2 % gauge noise: parameter error % against "
                "the true values, two stages then refined (then, with a mesh correction, "
                "its defect-correction passes by the given finer model); target: the "
                "coarse model within 1 % of the data mesh's own calibration (Δ % in "
                "brackets)",
                ["data", "model", "mesh correction", "E_x 2-st", "E_y 2-st", "mu 2-st", "E_x",
                 "E_y", "mu", "time (s)", "target"], rows)
    print_table("§5.2 at 5 % gauge noise (one σ = 5 % of the peak strain), data from a "
                "24x16 mesh, channels weighted by their estimated noise: refined error % "
                "(mean ± std over seeds) and the least-squares standard error %",
                ["model", "seeds", "E_x", "E_y", "mu", "se E_x", "se E_y", "se mu",
                 "max |err|", "seeds all ≤ 1 %"], noise_5())
    rows, dt = road_effect()
    print_table("Road assumption (bwim.calibration.road_sensitivity, re-fitted; "
                f"{dt:.1f} s): 24x16 data and model, 2 % gauge noise, the calibration's "
                "parameter error % when the dynamic misfit uses each road",
                ["road in the model", "E_x", "E_y", "mu"], [*rows, roadfree_same_record()[0]])
    print_table("§5.4 (Vransko beam-and-slab) on data from its 20x20 bisection, 2 % gauge "
                "noise, the paper's 10x10 model: error % against the truth",
                ["mesh correction", "E_x", "E_y", "mu", "E_girder", "mu_girder",
                 "time (s)"], vransko_mismatch())
    print_table("Calibration truck not the model of it (suspension x1.3, damping x0.6, tyres "
                "x0.85 in the data): 24x16 data, 2 crossings, 2 % gauge noise, the 12x8 "
                "model; error % against the truth",
                ["truck model in calibration", "mesh correction", "E_x", "E_y", "mu",
                 "time (s)"], vehicle_mismatch())
    rows, _ = roadfree()
    print_table("Road-free calibration (bwim.calibration.calibrate_quasistatic), no profile: "
                "24x16 data and model, 2 % gauge noise, ISO roads 1-6, start E_x x0.8, "
                "E_y x1.2, mu x1.25; error % as mean / RMS / max|.| over roads",
                ["variant", "runs", "roads", "E_x", "E_y", "mu", "time (s)"], rows)
    t0 = time.perf_counter()
    rows, weighing_results, sigma = mismatch_weighing()
    print_table("Weighing with a mismatched model (issue 12): 24x16 data, gauge noise "
                f"σ = {sigma:.2e} (2 % of the calibration peak) on every channel; models "
                "calibrated from 15 and 22 m/s crossings starting at 28/42 GPa, 1950 kg/m², "
                "then MFI of six vehicles on other roads (speed m/s @ lane m). Columns: "
                "calibration error %, then GVW error % / max |axle error| % per vehicle; "
                "target GVW ≤ 2 %, axles ≤ 5 % "
                f"({time.perf_counter() - t0:.0f} s)",
                ["model", "road in calibration", "E_x", "E_y", "mu",
                 *(f"{n} {v:g}@{lane:g}" for n, _, v, lane, _ in WEIGHED),
                 "cal time (s)", "target"], rows)
    print_table("Issue 23, target 3: the corrected chain against the exact 24x16 model "
                "(the data's, true parameters), per vehicle GVW error difference (points) / "
                "largest |axle error| difference (points); target ≤ 0.5 / ≤ 1",
                ["chain", *(f"{n} {v:g}@{lane:g}" for n, _, v, lane, _ in WEIGHED),
                 "target"],
                [*target_exact_model(weighing_results),
                 *target_exact_model(weighing_results,
                                     ("12x8 corrected, MFI 24x16",
                                      "measured 1 mm, mass dynamic"))])
    print_table("The same six vehicles on ISO class A roads (WIM-grade), same seeds and noise: "
                "GVW error % / max |axle error| %",
                ["model", *(f"{n} {v:g}@{lane:g}" for n, _, v, lane, _ in WEIGHED), "target"],
                weighing_smooth_roads())


if __name__ == "__main__":
    main()
