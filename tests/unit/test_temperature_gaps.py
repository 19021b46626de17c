"""A temperature probe with gaps (issue 20, the temperature drift): a logger's temperature
column may have empty or NaN fields where the probe dropped out.  The record is kept (its
strains are whole), the event's temperature is the median of the probe's readings, and an
event with no reading at all falls back to the time-of-day drift, flagged, or is refused
when the scenario asks for the temperature method only.  References: the written files
(the gaps are put there by the test) and the simulated day's truth.
"""

import dataclasses

import numpy as np
import pytest

from bwim.errors import InputError
from bwim.io import LoggerFormat, read_logger
from bwim.records import Record
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.sensors import Sensor, SensorKind
from bwim.site import calibrate_site, weigh_event
from bwim.site.calibrate import record_temperature
from bwim.synthetic import make_test_day
from bwim.synthetic.testday import WIM_GRADE_ROUGHNESS

FMT = LoggerFormat(columns=("time", "s1", "s2", "temp"), sampling_rate=100.0,
                   kinds={"temp": "temperature"})


def _write(path, temps, strain=None):
    n = len(temps)
    rows = ["time\ts1\ts2\ttemp"]
    for k in range(n):
        s1 = "" if strain == k else f"{1e-6 * np.sin(k / 7):.9f}"
        rows.append(f"{k / 100:.2f}\t{s1}\t{2e-6 * np.cos(k / 5):.9f}\t{temps[k]}")
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("vectorised", [True, False])
def test_gaps_in_the_temperature_column_read_as_nan(tmp_path, vectorised):
    """Empty and NaN fields of the temperature column are NaN; the strains are read exactly
    as written (closed form: the values the test wrote)."""
    temps = ["21.5", "", "21.7", "NaN", "nan", "21.6"] * 10
    rec = read_logger(_write(tmp_path / "r.txt", temps), FMT, vectorised=vectorised)
    t = rec.channels(["temp"]).data[:, 0]
    gap = np.array([v == "" or v.lower() == "nan" for v in temps])
    assert np.all(np.isnan(t[gap])) and np.all(np.isfinite(t[~gap]))
    assert t[~gap] == pytest.approx([float(v) for v in np.array(temps)[~gap]])
    k = np.arange(len(temps))
    written = 1e-6 * np.sin(k / 7)  # with 9 decimals
    assert rec.channels(["s1"]).data[:, 0] == pytest.approx(written, abs=6e-10)
    assert record_temperature(rec, "temp") == pytest.approx(21.6)


def test_a_gap_in_a_strain_column_is_still_refused(tmp_path):
    with pytest.raises(InputError, match=r"line 5, column 's1': empty field"):
        read_logger(_write(tmp_path / "r.txt", ["21.5"] * 20, strain=3), FMT)


def test_a_temperature_first_row_gap_is_data_not_a_header(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("0.00\t1e-6\t2e-6\t\n0.01\t1e-6\t2e-6\t20.0\n" * 1
                    + "".join(f"{0.02 + k / 100:.2f}\t1e-6\t2e-6\t20.0\n" for k in range(20)))
    rec = read_logger(path, FMT)
    assert rec.data.shape == (22, 3) and np.isnan(rec.channels(["temp"]).data[0, 0])


def test_record_keeps_nan_only_in_a_temperature_channel():
    t = np.arange(5) / 100.0
    data = np.ones((5, 2))
    data[2, 1] = np.nan
    temp = Sensor(name="T", kind=SensorKind.TEMPERATURE)
    gauge = Sensor(name="g", kind=SensorKind.STRAIN_X)
    rec = Record(time=t, data=data, sensors=(gauge, temp))
    assert record_temperature(rec, "T") == 1.0
    with pytest.raises(InputError, match=r"non-finite sample at t = 0\.02 s in channel 'g'"):
        Record(time=t, data=data[:, ::-1], sensors=(gauge, temp))
    data[:, 1] = np.inf
    with pytest.raises(InputError, match="channel 'T'"):
        Record(time=t, data=data, sensors=(gauge, temp))
    data[:, 1] = np.nan
    assert record_temperature(Record(time=t, data=data, sensors=(gauge, temp)), "T") is None


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """Eight calibration runs and one lane-1 truck on the realistic site, with the deck
    temperature channel (a 0.6 m mesh, WIM-grade roads: a few seconds)."""
    day = make_test_day(tmp_path_factory.mktemp("gaps") / "site", site="short-span-4-lane",
                        seed=4, n_calibration=8, n_traffic=1, n_calibration_day_traffic=0,
                        n_multiple=0, mesh=0.6, roughness=WIM_GRADE_ROUGHNESS,
                        temperature_channel=True)
    scenario = load_scenario(day.scenario)
    setup = build_site_setup(scenario)
    cal = calibrate_site([load_record(p, scenario) for p in day.calibration], setup)
    return day, scenario, cal


def _blank_temperature(src, dst, keep_every=0):
    """``src`` with its last (temperature) column emptied, except every ``keep_every``-th
    row when given."""
    lines = src.read_text().splitlines()
    out = []
    for k, line in enumerate(lines):
        fields = line.split("\t")
        if not (keep_every and k % keep_every == 0):
            fields[-1] = ""
        out.append("\t".join(fields))
    dst.write_text("\n".join(out) + "\n")
    return dst


def test_an_event_with_a_patchy_probe_keeps_the_temperature_drift(site, tmp_path):
    """One reading in 50 left: the drift is still the temperature's, within the probe's
    noise of the whole record's factor (σ 0.1 °C × a slope of about 0.017 per °C: 0.2 %)."""
    day, scenario, cal = site
    path = day.traffic[0]
    whole = weigh_event(load_record(path, scenario), cal)
    patchy = weigh_event(load_record(_blank_temperature(path, tmp_path / path.name, 50),
                                     scenario), cal)
    assert whole.drift_method == patchy.drift_method == "temperature"
    assert patchy.drift_factor == pytest.approx(whole.drift_factor, rel=0.002)


def test_an_event_without_a_reading_falls_back_to_the_time_of_day(site, tmp_path):
    """No reading: ``auto`` uses the time of day, flagged ``temperature_missing``;
    ``temperature`` alone refuses the vehicle with the reason."""
    day, scenario, cal = site
    path = day.traffic[0]
    rec = load_record(_blank_temperature(path, tmp_path / path.name), scenario)
    ev = weigh_event(rec, cal)
    assert ev.drift_method == "time_of_day"
    assert "temperature_missing" in ev.flags
    strict = dataclasses.replace(cal, setup=dataclasses.replace(
        cal.setup, drift=dataclasses.replace(cal.setup.drift, method="temperature")))
    ev = weigh_event(rec, strict)
    assert not ev.weighed and "has no reading" in ev.reason


def test_runs_without_a_reading_are_left_out_of_the_temperature_fit(site, tmp_path):
    """Blanking one used run's probe leaves the fit on the other used runs: its span is
    theirs (closed form: the medians of those files' temperature columns)."""
    day, scenario, cal = site
    used = [k for k, r in enumerate(cal.reasons) if not r]
    assert len(used) >= 4
    runs = []
    medians = []
    for k, p in enumerate(day.calibration):
        if k == used[0]:
            runs.append(load_record(_blank_temperature(p, tmp_path / p.name), scenario))
            continue
        runs.append(load_record(p, scenario))
        if k in used:
            medians.append(float(np.median(np.loadtxt(p)[:, -1])))
    fit = calibrate_site(runs, cal.setup)
    assert [not r for r in fit.reasons] == [not r for r in cal.reasons]
    assert fit.temperature is not None
    assert fit.temperature.span == pytest.approx((min(medians), max(medians)))
