"""The realistic simulated site (bwim.synthetic, short-span-4-lane): its files as a real
installation's (issue 20), read back with numpy/csv/tomllib and bwim.io.read_logger.

One small site (4 calibration runs, 12 + 4 traffic events, 0.5 m data mesh, with the
temperature channel) is generated for the module.
"""

import csv
import datetime as dt
import re
import tomllib

import numpy as np
import pytest

from bwim.conventions import GRAVITY
from bwim.errors import InputError
from bwim.fe.modal import select_modes
from bwim.io.logger import LoggerFormat, read_logger
from bwim.scenario import load_record, load_scenario
from bwim.sensors import SensorKind
from bwim.synthetic import SHORT_SPAN_4_LANE, make_test_day
from bwim.synthetic.layout import AxleDetector, Lane, SiteLayout
from bwim.synthetic.sitedays import make_site_days

FS = 512.0
PRE = 154
LAYOUT = SHORT_SPAN_4_LANE
STAMP = r"(\d{4})-(\d\d)-(\d\d)-(\d\d)-(\d\d)-(\d\d)-(\d{3})"


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    calls = []
    d = make_test_day(tmp_path_factory.mktemp("site") / "site", site="short-span-4-lane",
                      seed=2, n_calibration=4, n_traffic=12, n_calibration_day_traffic=4,
                      n_multiple=3, mesh=0.5, temperature_channel=True,
                      progress=lambda done, total: calls.append((done, total)))
    return d, calls


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _by_record(rows):
    out = {}
    for r in rows:
        out.setdefault(r["record"], []).append(r)
    return out


def _clock(name):
    y, mo, d, h, mi, s, ms = (int(v) for v in re.search(STAMP, name).groups())
    return dt.datetime(y, mo, d, h, mi, s, ms * 1000)


def test_scenario_has_the_schema_of_issue_20(day):
    """scenario.toml: [logger] columns (19 + temp_C) and 512 Hz; the gauges as one
    [[sensors]] table with their x (one line, mid-span) and y; temp_C a temperature
    sensor; [bridge] the measured geometry with nominal concrete (not the simulation's
    35 GPa and 2400 kg/m³) on a 0.75 m mesh; one [[axle_detectors]]
    per lane with detectors, channels in the order the lane's traffic meets them (lane 3
    travels -x: ad4 at x = 4.5 m first), 3.0 m apart; [vehicle] the calibration truck,
    whose loads sum to its 40 t × g."""
    d, _ = day
    sc = tomllib.loads(d.scenario.read_text())
    assert set(sc) == {"bridge", "logger", "sensors", "axle_detectors", "vehicle"}
    assert sc["bridge"] == {"kind": "plate", "length": 6.0, "width": 15.55, "nx": 8,
                            "ny": 21, "thickness": 0.45, "E": 30e9, "mu": 2500 * 0.45,
                            "poisson": 0.2, "damping_ratio": 0.03, "supports": "ss-free"}
    gauges = [f"s{k:02d}" for k in range(1, 13)]
    assert sc["logger"] == {"columns": ["time", "ad1", "ad2", *gauges, "ad3", "ad4", "-", "-",
                                        "temp_C"], "sampling_rate": 512.0}
    assert sc["sensors"] == [
        {"name": gauges, "kind": "strain_x", "x": 3.0,
         "y": [4.50, 5.18, 5.86, 6.55, 7.23, 7.91, 8.59, 9.27, 9.95, 10.64, 11.32, 12.00]},
        {"name": "temp_C", "kind": "temperature"}]
    assert sc["axle_detectors"] == [
        {"lane": 1, "direction": "+x", "channels": ["ad1", "ad2"], "distance": 3.0, "y": 5.2},
        {"lane": 3, "direction": "-x", "channels": ["ad4", "ad3"], "distance": 3.0,
         "y": 10.64}]
    assert sc["vehicle"]["axle_spacings"] == [3.8, 6.0, 1.3, 1.3]
    assert abs(sum(sc["vehicle"]["axle_loads"]) - 40.0e3 * GRAVITY) < 0.5


def test_files_have_20_columns_time_from_zero_and_the_clock_in_the_name(day):
    """Every event file: no header, 19 columns + temp_C, time exactly k / 512 from 0, two
    digital status columns of 0/1 text; the name is ``YYYY-MM-DD-HH-MM-SS-mmm.txt``
    (calibration) or ``PL<lane>_...`` (traffic) with the clock of the first sample, which
    is truth's event start; the calibration and traffic dates are two days apart, and
    the clock time at the gauge line is event start + the first axle's travel (truth)."""
    d, _ = day
    truth = _by_record(_rows(d.truth))
    paths = d.calibration + d.calibration_day_traffic + d.traffic
    assert len(d.calibration) == 4 and len(d.calibration_day_traffic) == 4
    assert len(d.traffic) == 12
    assert sorted(p.name for p in paths) == sorted(truth)
    assert d.traffic_date - d.calibration_date == dt.timedelta(days=2)
    for path in paths:
        lines = path.read_text().splitlines()
        fields = [ln.split("\t") for ln in lines]
        assert {len(f) for f in fields} == {20}
        assert {f[17] for f in fields} == {"1"} and {f[18] for f in fields} == {"0"}
        data = np.array([[float(v) for v in f] for f in fields])
        np.testing.assert_array_equal(data[:, 0], np.arange(len(lines)) / FS)
        rows = truth[path.name]
        start = dt.datetime.fromisoformat(rows[0]["event_start"])
        assert _clock(path.name) == start
        if path in d.calibration:
            assert re.fullmatch(STAMP + r"\.txt", path.name)
            assert start.date() == d.calibration_date
        else:
            trig = next(r for r in rows if r["trigger"] == "true")
            assert path.name == f"PL{trig['lane']}_{start:%Y-%m-%d-%H-%M-%S}-" \
                                f"{start.microsecond // 1000:03d}.txt"
            date = d.traffic_date if path in d.traffic else d.calibration_date
            assert start.date() == date
        # the first axle enters the deck 154 samples after the first sample (for the
        # earliest vehicle) and reaches the gauge line (x = 3 m) 3 m later; truth's
        # times are written to 1 µs and speeds to 1 mm/s (3 m / v off by ≤ 4 µs)
        first = min((dt.datetime.fromisoformat(r["time"]) - start).total_seconds()
                    - 3.0 / float(r["speed_m_s"]) for r in rows)
        assert first == pytest.approx(PRE / FS, abs=5e-6)


def test_logger_reader_reads_every_file_with_the_scenario_columns(day):
    """bwim.io.read_logger with the scenario's columns reads each file: 17 channels
    (12 gauges, 4 detectors, temp_C), time from 0 at 512 Hz."""
    d, _ = day
    sc = tomllib.loads(d.scenario.read_text())
    kinds = {f"ad{k}": "axle_detector" for k in range(1, 5)} | {"temp_C": "temperature"}
    fmt = LoggerFormat(columns=tuple(sc["logger"]["columns"]), kinds=kinds,
                       sampling_rate=sc["logger"]["sampling_rate"])
    for path in d.calibration + d.traffic[:3]:
        rec = read_logger(path, fmt)
        assert rec.data.shape[1] == 17 and rec.time[0] == 0.0
        assert rec.sampling_rate == pytest.approx(FS, rel=1e-12)


def test_the_written_scenario_loads_its_files_with_the_temperature(day):
    """The scenario as written (temperature channel declared as a plain name) builds its
    sensors and loads a record through bwim.scenario: temp_C arrives as a temperature
    channel, the gauges with their y in metres."""
    d, _ = day
    scenario = load_scenario(d.scenario)
    rec = load_record(d.traffic[0], scenario)
    kinds = {s.name: s.kind for s in rec.sensors}
    assert kinds["temp_C"] is SensorKind.TEMPERATURE
    assert [s.y for s in rec.sensors if s.name == "s01"] == [4.5]


def test_opposite_traffic_in_half_of_the_calibration_runs(day):
    """round(n / 2) calibration runs have a second vehicle of 4–7 axles in lane 3 (-x)
    on the bridge with the truck (their deck times overlap: closed form from truth's
    gauge-line times, speeds and lengths); the other runs have the truck alone."""
    d, _ = day
    truth = _by_record(_rows(d.truth))
    with_other = 0
    for path in d.calibration:
        rows = truth[path.name]
        assert rows[0]["vehicle_type"] == "calibration" and rows[0]["lane"] == "1"
        if len(rows) == 1:
            assert rows[0]["configuration"] == "single"
            continue
        with_other += 1
        other = rows[1]
        assert other["lane"] == "3" and other["direction"] == "-x"
        assert 4 <= int(other["n_axles"]) <= 7
        assert all(r["configuration"] == "opposite" and r["n_vehicles"] == "2" for r in rows)
        on = []
        for r in rows:
            v = float(r["speed_m_s"])
            length = sum(float(s) for s in r["axle_spacings_m"].split(";"))
            t_in = dt.datetime.fromisoformat(r["time"]).timestamp() - 3.0 / v
            on.append((t_in, t_in + (6.0 + length) / v))
        assert max(a for a, _ in on) < min(b for _, b in on)
    assert with_other == 2


def test_reference_lists_single_vehicles_of_detector_lanes_on_the_traffic_date(day):
    """reference.csv: one row per single-vehicle traffic-date event whose vehicle is in
    lane 1 or 3, with the columns of issue 20; the weights are truth's static loads and
    the gross weight their sum; multiple-presence events are in truth.csv only."""
    d, _ = day
    rows = _rows(d.reference)
    assert list(rows[0]) == ["record", "n_axles", "axle_spacings_m", "axle_weights_kN",
                             "gvw_kN", "speed_m_s", "time", "lane", "direction"]
    truth = _by_record(_rows(d.truth))
    expected = [p.name for p in d.traffic if len(truth[p.name]) == 1
                and truth[p.name][0]["lane"] in ("1", "3")]
    assert [r["record"] for r in rows] == expected
    for r in rows:
        t = truth[r["record"]][0]
        for key in ("n_axles", "axle_spacings_m", "axle_weights_kN", "gvw_kN", "speed_m_s",
                    "time", "lane", "direction"):
            assert r[key] == t[key]
        loads = [float(v) for v in r["axle_weights_kN"].split(";")]
        assert abs(sum(loads) - float(r["gvw_kN"])) < 0.01
    assert any(len(rs) > 1 for rs in truth.values())


def test_events_in_every_lane_both_directions_and_the_trigger_first(day):
    """Traffic runs in both directions (lanes 1-2 +x, 3-4 -x); each event has one trigger
    vehicle, listed first; n_multiple = 3 events per date have a second vehicle."""
    d, _ = day
    truth = _by_record(_rows(d.truth))
    for rows in truth.values():
        assert [r["trigger"] for r in rows] == ["true"] + ["false"] * (len(rows) - 1)
        for r in rows:
            assert r["direction"] == ("+x" if r["lane"] in ("1", "2") else "-x")
    for paths in (d.calibration_day_traffic, d.traffic):
        assert sum(len(truth[p.name]) > 1 for p in paths) == 3


def test_progress_is_called_once_per_event(day):
    """progress(done, total) after every event file, done = 1 … total."""
    d, calls = day
    n = len(d.events)
    assert calls == [(k, n) for k in range(1, n + 1)]


def test_refuses_bad_arguments_with_a_named_reason(tmp_path):
    """Unknown site, an option the site lacks, and bad values are InputErrors naming them;
    the basic site is still the default and refuses the realistic site's options."""
    with pytest.raises(InputError, match="unknown site"):
        make_test_day(tmp_path / "a", site="nowhere")
    with pytest.raises(InputError, match="temperature_channel"):
        make_test_day(tmp_path / "b", temperature_channel=True)
    with pytest.raises(InputError, match="drift"):
        make_test_day(tmp_path / "c", site="short-span-4-lane", drift=0.1)
    for kw, word in [({"n_calibration": 0}, "n_calibration"), ({"mesh": 0.05}, "mesh"),
                     ({"n_calibration_day_traffic": -1}, "n_calibration_day_traffic"),
                     ({"temperature_channel": 1}, "temperature_channel"),
                     ({"progress": 3}, "progress"), ({"n_traffic": 5000}, "do not fit")]:
        with pytest.raises(InputError, match=word):
            make_site_days(tmp_path / "d", **kw)
    assert not (tmp_path / "d").exists() or not any((tmp_path / "d").iterdir())


def test_layout_is_validated():
    """A layout with a detector off the deck, a lane with one detector or lane shares
    that do not sum to 1 is refused."""
    good = SHORT_SPAN_4_LANE
    kw = {f: getattr(good, f) for f in good.__dataclass_fields__}
    with pytest.raises(InputError, match="off the deck"):
        SiteLayout(**kw | {"detectors": (*good.detectors[:3],
                                         AxleDetector(name="ad4", lane=3, x=7.0, y=10.64))})
    with pytest.raises(InputError, match="two axle detectors"):
        SiteLayout(**kw | {"detectors": good.detectors[:3],
                           "columns": tuple(c for c in good.columns if c != "ad4")})
    with pytest.raises(InputError, match="sum"):
        SiteLayout(**kw | {"lanes": (*good.lanes[:3],
                                     Lane(number=4, y=13.35, direction=-1, heavy_share=0.5))})


def test_slab_first_frequency_is_the_plate_strips_22_hz():
    """The preset's slab (6 m span, 0.45 m, 35 GPa, ν = 0.2, 2400 kg/m³): first natural
    frequency within 1 % of the simply supported plate strip's closed form
    f₁ = π / (2 L²) √(D / ρh), D = E h³ / (12 (1 − ν²)) = 22.09 Hz (free edges lower it
    slightly; the FE gives 22.0 Hz)."""
    lay = LAYOUT
    d = lay.modulus * lay.thickness**3 / (12 * (1 - lay.poisson**2))
    f1 = np.pi / (2 * lay.span**2) * np.sqrt(d / (lay.density * lay.thickness))
    modes = select_modes(lay.bridge(0.5), n_modes=1, sampling_rate=1024.0)
    assert abs(modes.omega[0] / (2 * np.pi) / f1 - 1) < 0.01
    assert 21.5 < f1 < 22.5
