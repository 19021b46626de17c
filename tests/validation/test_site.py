"""A real installation end to end, on a small simulated test day (:mod:`bwim.synthetic`).

The day's data come from a 0.5 m plate mesh with 3-D trucks over ISO roads, 2 % absolute
gauge noise, offsets, baseline drift, per-gauge gains, a drift of the strain-to-load ratio
over the day and detector pulses of a shape the detection never assumes; the weighing
knows none of that (no FE model at all: lines calibrated from the calibration truck's
runs).  References: the simulation's truth (``truth.csv``, ``reference.csv``).
Targets from issue 11: axle count right, speed within 0.5 %, spacings within 0.1 m.
"""

import csv
import dataclasses
import shutil
from datetime import time
from functools import partial

import numpy as np
import pytest

from bwim.accuracy import assess
from bwim.batch import weigh_events
from bwim.cli import main
from bwim.io import read_reference
from bwim.io.summary import COLUMNS
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import SiteSetup, calibrate_site, weigh_event
from bwim.synthetic import make_test_day
from bwim.synthetic.testday import WIM_GRADE_ROUGHNESS


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    return make_test_day(tmp_path_factory.mktemp("site") / "day", seed=3, n_calibration=6,
                         n_traffic=10, n_multiple=1, mesh=0.5)


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _floats(text):
    return np.array([float(v) for v in text.split(";")]) if text else np.zeros(0)


@pytest.fixture(scope="module")
def site(day):
    scenario = load_scenario(day.scenario)
    truck_loads = [float(v) for v in scenario.vehicle.params["axle_loads"]]
    setup = SiteSetup(calibration_loads=truck_loads,
                      calibration_spacings=scenario.vehicle.params["axle_spacings"],
                      detectors=("ad1", "ad2"),
                      distance=scenario.axle_detectors[0].distance)
    runs = [load_record(p, scenario) for p in day.calibration]
    return scenario, calibrate_site(runs, setup)


def test_calibration_runs_are_detected_and_track_the_days_drift(day, site):
    """Every run is used; the runs' scale factors follow the simulated strain-to-load
    ratio of the day (truth.csv, sd 3.3 %) up to the truck's own dynamics on these class
    A–B roads, which scatter each run's factor by about 5 % RMS (measured: 5.3 % on this
    day, correlation 0.60; 4.5 % and 0.73 on the full 12-run day)."""
    _, cal = site
    assert cal.n_used == len(day.calibration)
    truth = {r["record"]: float(r["strain_factor"]) for r in _rows(day.truth)}
    true = np.array([truth[p.name] for p in day.calibration])
    fitted = np.array([f.scale for f in cal.fits])
    true = true / true.mean()
    assert np.corrcoef(true, fitted)[0, 1] > 0.35
    assert np.sqrt(np.mean((fitted - true) ** 2)) < 0.075


def test_traffic_detected_and_weighed_against_the_truth(day, site):
    """Single trucks: axle count right, speed within 0.5 %, spacings within 0.1 m (the
    issue's targets), GVW within 12 % (the class A–B roads of this day give ±5 % sd on
    the full day; 12 % is 2.3 sd); the two-truck event is flagged, not weighed."""
    scenario, cal = site
    truth = {}
    for r in _rows(day.truth):
        truth.setdefault(r["record"], []).append(r)
    n_single = n_weighed = 0
    for path in day.traffic:
        ev = weigh_event(load_record(path, scenario), cal)
        t = truth[path.name]
        if len(t) > 1:
            assert not ev.weighed and "multiple presence" in ev.reason
            continue
        t = t[0]
        n_single += 1
        p = ev.passage
        assert p is not None and p.n_axles == int(t["n_axles"]), path.name
        assert abs(p.speed / float(t["speed_m_s"]) - 1) < 0.005
        assert np.max(np.abs(p.axle_spacings - _floats(t["axle_spacings_m"]))) < 0.1
        if t["lane"] != "1" and not ev.weighed:
            # the calibration truck never drove lane 2: the lines are extrapolated there,
            # and a fit much worse than the calibration's is refused, not written
            assert "lateral_extrapolated" in ev.flags and "residual_high" in ev.flags
            continue
        assert ev.weighed, (path.name, ev.reason)
        n_weighed += 1
        assert abs(ev.gvw / 1e3 / float(t["gvw_kN"]) - 1) < 0.12, path.name
    assert n_single == 9 and n_weighed >= 7


def _weigh(day, out, *extra):
    return main(["weigh", str(day.scenario), str(day.traffic[0].parent),
                 "--calibration-records", str(day.calibration[0].parent), "-o", str(out),
                 *extra])


def test_weigh_command_writes_the_contract_summary(day, tmp_path, capsys):
    out = tmp_path / "out"
    assert _weigh(day, out) == 0
    rows = _rows(out / "summary.csv")
    assert tuple(rows[0]) == COLUMNS
    assert list(dict.fromkeys(r["record"] for r in rows)) == [p.name for p in day.traffic]
    ref = {r["record"]: r for r in _rows(day.reference)}
    for r in rows:
        if r["record"] not in ref:  # the two-truck event: a reason, no weights
            assert r["gvw_kN"] == "" and "multiple_presence" in r["flags"]
            assert r["status"] == "refused" and r["reason"]
            continue
        if r["gvw_kN"] == "":  # refused (see the test above): flags and a reason
            assert r["status"] == "refused" and r["quality"] == "reject"
            assert r["flags"] and r["reason"] and r["axle_weights_kN"] == ""
            continue
        w = _floats(r["axle_weights_kN"])
        assert w.size == int(r["n_axles"]) == int(ref[r["record"]]["n_axles"])
        assert float(r["gvw_kN"]) == pytest.approx(w.sum(), abs=0.02)
    assert (out / "influence_lines.h5").exists()
    runs = _rows(out / "calibration_runs.csv")
    # this day's gauges have no y: the lateral position is their index, and says so
    assert "lateral (gauge index)" in runs[0] and float(runs[0]["lateral (gauge index)"]) > 0
    # each run's start: this day's time column is the clock of day (truth: event start)
    starts = {r["record"]: r["event_start_s"] for r in _rows(day.truth)}
    assert [r["run"] for r in runs] == [p.name for p in day.calibration]
    for r in runs:
        clock = time.fromisoformat(r["time"])
        seconds = clock.hour * 3600 + clock.minute * 60 + clock.second + clock.microsecond / 1e6
        assert seconds == pytest.approx(float(starts[r["run"]]), abs=1e-3)
    capsys.readouterr()
    assert main(["accuracy", str(out / "summary.csv"), "--reference", str(day.reference)]) == 0
    assert "gross weight" in capsys.readouterr().out
    html = tmp_path / "report.html"
    assert main(["report", str(out / "summary.csv"), "--reference", str(day.reference),
                 "-o", str(html)]) == 0
    text = html.read_text()
    assert f"COST 323 accuracy of {out.name}/summary.csv" in text and "axle of a group" in text


# --- the day's COST 323 class, in Python, without a file -----------------------------------
@pytest.fixture(scope="module")
def graded_day(tmp_path_factory):
    """A small WIM-grade day (12 runs, 30 trucks, ±8 % drift of the strain-to-load ratio
    over the day, 0.5 m data mesh)."""
    return make_test_day(tmp_path_factory.mktemp("graded") / "day", seed=5, n_calibration=12,
                         n_traffic=30, n_multiple=1, mesh=0.5, roughness=WIM_GRADE_ROUGHNESS)


def _assessed(day, drift):
    scenario = load_scenario(day.scenario)
    setup = dataclasses.replace(build_site_setup(scenario), drift=drift)
    cal = calibrate_site([load_record(p, scenario) for p in day.calibration], setup)
    rows = [r for out in weigh_events(day.traffic, cal,
                                      read=partial(load_record, scenario=scenario))
            for r in out.rows]
    reference = read_reference(day.reference)
    ref = {r.record: r for r in reference}
    errors = np.array([100 * (r.gvw / ref[r.record].gvw - 1) for r in rows
                       if r.weighed and r.record in ref])
    return assess(rows, reference), errors


def test_the_days_cost323_class_needs_the_drift_correction(graded_day):
    """bwim.batch.weigh_events → rows → bwim.accuracy.assess, no file.  With the runs'
    drift trend the gross weight is B+(7) (measured: −0.13 ± 2.81 %, largest 6.0 %, 28
    trucks); without it the day's ±8 % drift leaves B(10) (−0.75 ± 4.11 %): the
    correction must take the scatter down by a fifth at least (measured 0.68)."""
    with_trend, err = _assessed(graded_day, "trend")
    without, err_off = _assessed(graded_day, "none")
    gross = with_trend.criterion("gross_weight")
    assert gross.class_value <= 7.0, gross.class_name
    assert without.criterion("gross_weight").class_value > gross.class_value
    assert err.std(ddof=1) < 0.8 * err_off.std(ddof=1)
    assert np.abs(err).max() < 8.0  # measured 6.0 %
    assert err.size >= 27 and with_trend.overall_value <= 10.0


def _corrupt(src, dst, how):
    lines = src.read_text().splitlines()
    if how == "missing_column":
        lines[40] = "\t".join(lines[40].split("\t")[:-2])
    elif how == "nan":
        fields = lines[60].split("\t")
        fields[5] = "nan"
        lines[60] = "\t".join(fields)
    elif how == "backwards_time":
        lines[70], lines[71] = lines[71], lines[70]
    elif how == "no_axles":  # detectors silent: nothing crosses them
        for k in range(1, len(lines)):
            f = lines[k].split("\t")
            f[1] = f[2] = "0.0"
            lines[k] = "\t".join(f)
    dst.write_text("\n".join(lines) + "\n")


def test_a_batch_survives_bad_records(day, tmp_path):
    """Each bad record gets a summary row with a one-line reason; the good ones are
    weighed; the exit code says some failed (1)."""
    traffic = tmp_path / "traffic"
    shutil.copytree(day.traffic[0].parent, traffic)
    good = day.traffic[1]
    for how in ("missing_column", "nan", "backwards_time", "no_axles"):
        _corrupt(good, traffic / f"bad_{how}.txt", how)
    shutil.copy(good, traffic / "same_as_good.dat")  # any extension is a logger file
    out = tmp_path / "out"
    code = main(["weigh", str(day.scenario), str(traffic), "--calibration-records",
                 str(day.calibration[0].parent), "-o", str(out)])
    assert code == 1
    rows = {r["record"]: r for r in _rows(out / "summary.csv")}
    for how, needle in (("missing_column", "field"), ("nan", "nan"),
                        ("backwards_time", "time"), ("no_axles", "axle")):
        r = rows[f"bad_{how}.txt"]
        assert r["gvw_kN"] == "" and needle in r["reason"].lower(), (how, r["reason"])
        assert "\n" not in r["reason"]
    # the copy under another name and extension is read (any extension is a logger
    # file) and holds the same axles at the same clock as the good file: one vehicle in
    # two records, never weighed (nor counted) twice (bwim.site.split)
    for name, other in ((good.name, "same_as_good.dat"), ("same_as_good.dat", good.name)):
        r = rows[name]
        assert r["gvw_kN"] == "" and "split_across_records" in r["flags"], r
        assert other in r["reason"]
    assert sum(1 for n, r in rows.items() if r["gvw_kN"]) >= 5  # the others weighed


def test_resume_keeps_what_was_weighed(day, tmp_path):
    out = tmp_path / "out"
    assert _weigh(day, out) == 0
    first = (out / "summary.csv").read_text()
    assert _weigh(day, out, "--resume") == 0
    assert (out / "summary.csv").read_text() == first


def test_weighing_by_mfi_with_an_fe_model(day, site):
    """With a bridge model (the site's slab on a 0.75 m mesh: coarser than the 0.5 m data
    mesh, gauges as points where the data average a load spread, gauge gains unknown),
    each detected truck within the calibration runs' lateral reach is weighed by MFI: GVW
    within 12 % of the truth (measured −2.6 … +7.9 % on this day: the model is not
    calibrated to the data), and each beyond it is refused.  Without gauge positions MFI
    is refused with its reason, not attempted."""
    from bwim.scenario import read_toml, scenario_from_dict
    from bwim.synthetic import site as layout

    scenario, cal = site
    doc = read_toml(day.scenario)
    doc["sensors"][0]["x"] = layout.GAUGE_X
    doc["sensors"][0]["y"] = list(layout.GAUGE_Y)
    doc["logger"]["scale"] = 1e-6  # the logger writes microstrain × an unknown gain
    placed = scenario_from_dict(doc, source="site.toml")
    # runs and traffic read with one scenario: the learned detector responses and their
    # noise are in the readings' units
    placed_cal = calibrate_site([load_record(p, placed) for p in day.calibration], cal.setup)
    bridge = layout.site_bridge(0.75)
    truth = {r["record"]: r for r in _rows(day.truth)}
    weighed, beyond = 0, 0
    for path in day.traffic:
        if truth[path.name]["n_vehicles"] != "1":
            continue
        ev = weigh_event(load_record(path, placed), placed_cal, bridge=bridge,
                         identify_options={"n_modes": 12})
        if truth[path.name]["lane"] != "1":
            # a lane-2 truck, 3.7 m from the runs' lane: beyond their lateral reach,
            # refused by MFI too (its readings cannot tell a truck in another lane from
            # two beside each other; review of stop 33)
            assert not ev.weighed and "from the calibration runs'" in ev.reason, ev.reason
            beyond += 1
            continue
        assert ev.method == "mfi" and ev.weighed, (path.name, ev.reason)
        assert abs(ev.gvw / 1e3 / float(truth[path.name]["gvw_kN"]) - 1) < 0.12
        weighed += 1
    assert (weighed, beyond) == (6, 3)  # the day's single trucks: 6 in lane 1, 3 in lane 2
    ev = weigh_event(load_record(day.traffic[0], scenario), cal, bridge=bridge)
    assert not ev.weighed and "position" in ev.reason


def test_mfi_lcurve_keeps_the_upper_of_two_corners(day, site, monkeypatch):
    """The day's third truck (evt_0003, the 0.75 m model of 0.5 m data, as in the test
    above): its L-curve has two corners (reference: the corner rule on a dense grid of 73
    λ over the search's range, eight per decade, on the same model: a local curvature
    maximum at log10 λ ≈ 1.1 and the largest curvature at ≈ 2.9, clipped to the top of
    the fine grid, 2.43, by the search).  The search must keep the upper one: a sparser
    fine grid (8 coarse + 4 fine λ) found the lower one and weighed the truck at +12.6 %
    instead of +5.9 % (issue 23 item 2).  Measured: log10 λ 2.43, 1.3 decades above the
    lower corner, 0.4 below the upper one; GVW +5.9 %."""
    import bwim.site.event as event
    from bwim.mfi import build_model
    from bwim.mfi.dp import sweep
    from bwim.mfi.lcurve import _corner, _lowest_admissible
    from bwim.mfi.statespace import force_layout
    from bwim.scenario import read_toml, scenario_from_dict
    from bwim.synthetic import site as layout

    _, cal = site
    doc = read_toml(day.scenario)
    doc["sensors"][0]["x"] = layout.GAUGE_X
    doc["sensors"][0]["y"] = list(layout.GAUGE_Y)
    doc["logger"]["scale"] = 1e-6
    placed = scenario_from_dict(doc, source="site.toml")
    placed_cal = calibrate_site([load_record(p, placed) for p in day.calibration], cal.setup)
    bridge = layout.site_bridge(0.75)
    seen = []
    inner = event.identify_forces

    def spy(bridge, rec, **options):
        seen.append((rec, inner(bridge, rec, **options)))
        return seen[-1][1]

    monkeypatch.setattr(event, "identify_forces", spy)
    path = day.traffic[2]
    ev = weigh_event(load_record(path, placed), placed_cal, bridge=bridge,
                     identify_options={"n_modes": 12})
    assert ev.weighed and len(seen) == 1
    rec, ident = seen[0]
    # the reference: the corner rule on a dense grid of the same model, among the λ whose
    # forces stay compressive where they are weighed (as the search's rule)
    scale = float(np.abs(rec.data).max())
    model = build_model(bridge, bridge.modes(ident.n_modes), rec, scale,
                        unknowns=ident.unknowns, order=ident.order)
    t = np.linspace(np.log(1e-6), np.log(1e3), 73)
    sw = sweep(model, rec.data / scale, np.exp(t), keep_forces=True)
    passage_of, axle_of, _ = force_layout(rec.passages, ident.unknowns)
    assert np.all(passage_of == 0)
    lo_hi = ident.axle_windows[axle_of]
    weighed = (rec.time[:, None] >= lo_hi[:, 0]) & (rec.time[:, None] <= lo_hi[:, 1])
    ok = np.all((sw.forces > 0) | ~weighed[None], axis=(1, 2))
    lo = _lowest_admissible(t, ok)
    kappa, upper = _corner(t, sw.residual_norm, sw.seminorm, lo)
    inside = (kappa[1:-1] > kappa[:-2]) & (kappa[1:-1] > kappa[2:]) & (t[1:-1] >= lo)
    lower = t[1:-1][inside].min() / np.log(10)
    upper /= np.log(10)
    assert upper - lower > 1.0  # two corners, more than a decade apart
    chosen = np.log10(ident.lam_scaled)
    assert abs(chosen - upper) < abs(chosen - lower)
    truth = float({r["record"]: r for r in _rows(day.truth)}[path.name]["gvw_kN"])
    assert abs(ident.gvw[0] / 1e3 / truth - 1) < 0.09  # the lower corner: +12.6 %
