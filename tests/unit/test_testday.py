"""The simulated B-WIM test day (bwim.synthetic): files, truth and the injected effects.

A small day (4 calibration runs, 8 traffic events, 0.5 m data mesh) is generated once for
the module; the checks read its files back with numpy/csv/tomllib, as a consumer would.
"""

import csv
import os
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from bwim import Bridge, PointLoad, Sensor
from bwim.conventions import GRAVITY
from bwim.errors import InputError
from bwim.synthetic import COLUMNS, make_test_day, site
from bwim.vehicles import TractorSemitrailer

FS = 512.0
PRE = 154


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    return make_test_day(tmp_path_factory.mktemp("day") / "site", seed=3, n_calibration=4,
                         n_traffic=8, mesh=0.5)


def _read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _floats(text):
    return np.array([float(v) for v in text.split(";")])


def _load_event(path):
    with open(path) as f:
        header = f.readline().rstrip("\n").split("\t")
    return header, np.loadtxt(path, skiprows=1, delimiter="\t")


def _by_record(rows):
    out = {}
    for r in rows:
        out.setdefault(r["record"], []).append(r)
    return out


def test_files_parse_with_the_scenario_columns_and_uniform_512_hz_clock_time(day):
    """Every event file has the header of COLUMNS, 19 numeric columns and an exactly
    uniform 512 Hz clock-time axis; the first sample is the event start of the truth and
    sample 154 is when the first axle reaches ad1; the name carries the start's hhmmss.
    The scenario has ISSUE 11's shape and its column list matches the files."""
    scenario = tomllib.loads(day.scenario.read_text())
    assert set(scenario) == {"logger", "sensors", "axle_detectors", "vehicle"}
    cols = scenario["logger"]["columns"]
    assert cols == ["time", "ad1", "ad2", *[f"s{k:02d}" for k in range(1, 15)], "-", "-"]
    assert scenario["sensors"] == [{"name": cols[3:17], "kind": "strain_x"}]
    assert scenario["axle_detectors"] == {"channels": ["ad1", "ad2"], "distance": 3.0}
    assert scenario["vehicle"]["axle_spacings"] == [3.8, 6.0, 1.3, 1.3]

    truth = _by_record(_read_csv(day.truth))
    paths = day.calibration + day.traffic
    assert len(day.calibration) == 4 and len(day.traffic) == 8
    assert sorted(p.name for p in paths) == sorted(truth)
    for path in paths:
        header, data = _load_event(path)
        assert tuple(header) == COLUMNS and data.shape[1] == len(cols)
        t = data[:, 0]
        assert np.all(np.diff(t) == 1.0 / FS)  # exact: multiples of 2**-9 written exactly
        first = truth[path.name][0]
        assert t[0] == float(first["event_start_s"])
        assert t[PRE] == float(first["clock_time_s"])
        s = int(t[0])
        assert path.name.split("_")[2] == f"{s // 3600:02d}{s % 3600 // 60:02d}{s % 60:02d}.txt"
        assert 1.0 < t[-1] - t[0] < 2.5


def test_reference_weights_are_the_models_static_loads_and_sum_to_the_weight(day):
    """reference.csv lists every traffic truck with the static axle loads of its vehicle
    model (to the 1 N of the written kN with 3 decimals); their sum is the vehicle's weight
    m g (static equilibrium: the model's closed form).  The scenario's calibration loads
    are the calibration truck's, 40.0 t × g in total."""
    rows = _read_csv(day.reference)
    assert list(rows[0]) == ["record", "n_axles", "axle_spacings_m", "axle_weights_kN",
                             "gvw_kN", "speed_m_s"]
    expected = [(e.name, v) for e in day.events if e.kind == "traffic"
                and len(e.vehicles) == 1 for v in e.vehicles]
    assert [r["record"] for r in rows] == [name for name, _ in expected]
    for r, (_, v) in zip(rows, expected, strict=True):
        veh = v.vehicle
        loads = veh.model().static_axle_loads
        mass = 2 * np.sum(veh.wheel_mass) + (
            veh.tractor_mass + veh.trailer_mass if isinstance(veh, TractorSemitrailer)
            else veh.body_mass)
        assert int(r["n_axles"]) == veh.n_axles
        np.testing.assert_allclose(_floats(r["axle_weights_kN"]) * 1e3, loads, atol=0.5)
        assert abs(float(r["gvw_kN"]) * 1e3 - mass * GRAVITY) < 1.0
        np.testing.assert_allclose(_floats(r["axle_spacings_m"]), veh.axle_spacings,
                                   atol=5e-4)
        assert abs(float(r["speed_m_s"]) - v.speed) < 5e-4
        assert 10.0 <= mass / 1e3 <= 50.0
    cal = tomllib.loads(day.scenario.read_text())["vehicle"]["axle_loads"]
    np.testing.assert_allclose(cal, day.calibration_axle_loads, atol=0.05)
    assert abs(sum(cal) - 40.0e3 * GRAVITY) < 0.5


def test_detector_pulses_at_the_times_of_truth_speed_and_spacings(day):
    """Each axle's pulse on ad_k peaks at t0 + (x_k + offset_a) / v (closed form from
    truth.csv: clock time at ad1, speed, spacings; x = 0 and 3.0 m).  Peaks are located by
    parabolic interpolation; measured error ≤ 0.11 sample here, ≤ 0.34 sample over the full
    day (the dynamic axle force's slope shifts the peak of F·K by (F'/F) / (2 (π v/w)²)),
    so the tolerance is half a sample."""
    truth = _by_record(_read_csv(day.truth))
    n_pulses = 0
    for path in day.calibration + day.traffic:
        rows = truth[path.name]
        if len(rows) != 1:
            continue
        r = rows[0]
        _, data = _load_event(path)
        t = data[:, 0]
        offsets = np.concatenate([[0.0], np.cumsum(_floats(r["axle_spacings_m"]))])
        for k, x_d in enumerate(site.DETECTOR_X):
            a = data[:, 1 + k] - np.median(data[:, 1 + k])
            i = np.flatnonzero((a[1:-1] > 0.25 * a.max()) & (a[1:-1] >= a[:-2])
                               & (a[1:-1] > a[2:])) + 1
            delta = 0.5 * (a[i - 1] - a[i + 1]) / (a[i - 1] - 2 * a[i] + a[i + 1])
            peaks = t[i] + delta / FS
            expected = float(r["clock_time_s"]) + (x_d + offsets) / float(r["speed_m_s"])
            assert peaks.size == offsets.size, path.name
            assert np.max(np.abs(peaks - expected)) < 0.5 / FS, path.name
            n_pulses += peaks.size
    assert n_pulses > 40


def test_noise_sigma_is_the_absolute_sigma_on_the_pre_trigger(day):
    """On the 154 pre-trigger samples (bridge at rest) of every event, each gauge divided by
    its gain and detrended (linear, 2 dof) has the requested absolute σ = 2 % of the
    calibration truck's peak gauge strain: pooled within 3 standard errors
    (1/sqrt(2 n_dof)), every channel within 4."""
    gains = np.array(day.gauge_gains)
    sq = np.zeros(14)
    n = 0
    k = np.arange(PRE)
    for path in day.calibration + day.traffic:
        _, data = _load_event(path)
        pre = data[:PRE, 3:17] / gains * 1e-6
        coef = np.polynomial.polynomial.polyfit(k, pre, 1)
        res = pre - np.polynomial.polynomial.polyval(k, coef).T
        sq += (res**2).sum(axis=0)
        n += PRE - 2
    assert abs(day.noise_sigma / day.reference_strain - 0.02) < 1e-12
    assert 20e-6 < day.reference_strain < 60e-6
    pooled = np.sqrt(sq.sum() / (14 * n)) / day.noise_sigma
    assert abs(pooled - 1) < 3 / np.sqrt(2 * 14 * n)
    per_channel = np.sqrt(sq / n) / day.noise_sigma
    assert np.all(np.abs(per_channel - 1) < 4 / np.sqrt(2 * n))


def test_drift_range_and_it_scales_the_gauges_not_the_detectors(day, tmp_path):
    """The strain factor stays within ±8 % and reaches it over the day (the amplitude is
    the largest deviation over 06:00–20:00); truth's factors are the drift at each event.
    Two one-event days that differ only in ``drift`` (same seed, so the same noise, gains
    and dynamics) differ in the gauges by exactly (f − 1) × gain × strain, and not at all
    in the detector channels: the drift-free record less that strain is noise, offset and
    a linear baseline of the requested σ (within 3 standard errors; a factor wrong by 3 %
    would leave 3 % of the signal in it)."""
    grid = np.arange(site.DAY[0], site.DAY[1] + 1.0, 1.0)
    dev = np.abs(day.drift.factor(grid) - 1)
    assert dev.max() <= 0.08 + 1e-9 and dev.max() > 0.08 - 1e-6
    for e in day.events:
        assert abs(e.strain_factor - 1) <= 0.08 + 1e-9
        assert e.strain_factor == pytest.approx(float(day.drift.factor(e.start_time + PRE / FS)))

    kw = {"seed": 5, "n_calibration": 1, "n_traffic": 0, "mesh": 0.6}
    flat = make_test_day(tmp_path / "flat", drift=0.0, **kw)
    drifting = make_test_day(tmp_path / "drift", drift=0.08, **kw)
    _, a = _load_event(flat.calibration[0])
    _, b = _load_event(drifting.calibration[0])
    np.testing.assert_array_equal(a[:, :3], b[:, :3])  # time and detectors
    f = drifting.events[0].strain_factor
    assert abs(f - 1) > 0.01
    gains = np.array(flat.gauge_gains) / 1e-6
    clean = (b[:, 3:17] - a[:, 3:17]) / (f - 1) / gains  # the drift-free strain f = 1
    assert np.abs(clean).max() > 20 * flat.noise_sigma
    # what is left of the drift-free record: noise + offset + linear baseline, nothing else
    rest = a[:, 3:17] / gains - clean
    k = np.arange(rest.shape[0])
    coef = np.polynomial.polynomial.polyfit(k, rest, 1)
    res = rest - np.polynomial.polynomial.polyval(k, coef).T
    n_dof = res.size - 2 * 14
    assert abs(np.sqrt(np.sum(res**2) / n_dof) / flat.noise_sigma - 1) < 3 / np.sqrt(2 * n_dof)


def test_multiple_presence_events_are_marked_and_overlap_on_the_bridge(day):
    """The requested multiple-presence events hold two trucks, marked n_vehicles = 2 with a
    configuration in truth.csv and no reference row (a system must flag, not weigh, them);
    from truth's clock times, speeds and
    spacings both are on the 9 m span at once (closed form); single events have one."""
    truth = _by_record(_read_csv(day.truth))
    ref = _by_record(_read_csv(day.reference))
    multiple = [name for name, rows in truth.items() if len(rows) == 2]
    assert len(multiple) == 1
    for rows in truth.values():
        n = len(rows)
        assert all(int(r["n_vehicles"]) == n for r in rows)
        assert all((r["configuration"] == "single") == (n == 1) for r in rows)
    for name in multiple:
        assert name not in ref
        on = []
        for r in truth[name]:
            t0, v = float(r["clock_time_s"]), float(r["speed_m_s"])
            on.append((t0, t0 + (site.SPAN + _floats(r["axle_spacings_m"]).sum()) / v))
        assert max(a for a, _ in on) < min(b for _, b in on)


def test_gauge_load_spread_converges_with_the_mesh_unlike_a_point_gauge():
    """A 50 kN wheel over a gauge: the point reading grows with mesh refinement (the
    Kirchhoff point-load singularity, +10 % from 0.5 to 0.125 m measured) while the
    gauge averaged over the 0.75 × 0.85 m load spread changes by < 1 %; and that average
    equals the reading of the load spread uniformly over the same area (reciprocity in a
    nearly translation-invariant plate) within 1 %."""
    spread = site.gauge_points()
    points, weights = list(spread.points), spread.weights
    j = 2
    mine = slice(16 * j, 16 * (j + 1))
    y0 = site.GAUGE_Y[j]
    grid = np.linspace(-0.5, 0.5, 15)
    spread = [PointLoad(x=site.GAUGE_X + a * site.SPREAD[0], y=y0 + b * site.SPREAD[1],
                        P=50e3 / grid.size**2) for a in grid for b in grid]
    avg, point, uniform = [], [], []
    for mesh in (0.5, 0.125):
        bridge = site.site_bridge(mesh)
        assert isinstance(bridge, Bridge)
        wheel = [PointLoad(x=site.GAUGE_X, y=y0, P=50e3)]
        avg.append(bridge.static(wheel, points[mine]) @ weights[mine, j])
        point.append(bridge.static(wheel, [Sensor(x=site.GAUGE_X, y=y0)])[0])
        uniform.append(bridge.static(spread, [Sensor(x=site.GAUGE_X, y=y0)])[0])
    assert point[1] / point[0] > 1.05
    assert abs(avg[1] / avg[0] - 1) < 0.01
    assert abs(avg[1] / uniform[1] - 1) < 0.01


def test_refuses_a_non_empty_folder_and_bad_arguments(tmp_path):
    """Existing output is never overwritten; bad arguments are named."""
    (tmp_path / "x.txt").write_text("keep")
    with pytest.raises(InputError, match="not empty"):
        make_test_day(tmp_path)
    assert (tmp_path / "x.txt").read_text() == "keep"
    with pytest.raises(InputError, match="not a folder"):
        make_test_day(tmp_path / "x.txt")
    for kw, word in [({"n_calibration": 0}, "n_calibration"), ({"mesh": 0.75}, "mesh"),
                     ({"n_traffic": 2, "n_multiple": 3}, "n_multiple"),
                     ({"noise": -0.1}, "noise"), ({"drift": 1.5}, "drift")]:
        with pytest.raises(InputError, match=word):
            make_test_day(tmp_path / "new", **kw)


def test_trucks_are_reproducible_across_processes():
    """The same seed gives the same trucks in a fresh interpreter whatever its string-hash
    seed (no draw order may depend on set/dict hashing)."""
    code = ("import numpy as np; from bwim.synthetic import random_truck, TRUCK_KINDS; "
            "r = np.random.default_rng(7); "
            "print([random_truck(k, r).model().static_axle_loads.round(6).tolist() "
            "for k in TRUCK_KINDS])")
    outs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True, env={**os.environ, "PYTHONHASHSEED": h}).stdout
            for h in ("1", "2", "3")}
    assert len(outs) == 1


def test_basic_site_is_the_default_and_reports_progress(tmp_path):
    """``site="basic-2-lane"`` is the default (the same files, byte for byte), and
    progress(done, total) is called after every event file."""
    kw = {"seed": 5, "n_calibration": 1, "n_traffic": 1, "mesh": 0.6}
    calls = []
    a = make_test_day(tmp_path / "a", **kw)
    b = make_test_day(tmp_path / "b", site="basic-2-lane",
                      progress=lambda done, total: calls.append((done, total)), **kw)
    assert calls == [(1, 2), (2, 2)]
    for p in sorted(a.out_dir.rglob("*")):
        q = b.out_dir / p.relative_to(a.out_dir)
        assert p.is_dir() or p.read_bytes() == q.read_bytes()
