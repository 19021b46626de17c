"""bwim on the realistic simulated site (docs/realistic_site.md; issue 20): the calibration
day's runs with another vehicle on the bridge are rejected, and the drift correction is
what keeps the traffic date's weights together.

Data: :func:`bwim.synthetic.make_test_day` with the ``short-span-4-lane`` preset (12
calibration runs, half with a vehicle crossing the other way in lane 3; 40 traffic events
in four lanes two days later, a different drift curve; strain-type axle detectors, gauge
noise, offsets and gains; 3-D trucks over WIM-grade roads; a 0.6 m mesh).  The weighing
knows nothing of it but the scenario.  References: ``truth.csv`` and ``reference.csv``.
The full-size study is ``benchmarks/bench_realsite.py``.
"""

import csv
import dataclasses
from functools import partial

import numpy as np
import pytest

from bwim.accuracy import assess
from bwim.batch import weigh_events
from bwim.io import read_reference
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site, weigh_event
from bwim.site.calibrate import gauge_names
from bwim.synthetic import make_test_day


@pytest.fixture(scope="module", params=[5, 6])
def site(request, tmp_path_factory):
    day = make_test_day(tmp_path_factory.mktemp("realistic") / "day",
                        site="short-span-4-lane", seed=request.param, n_calibration=12,
                        n_traffic=40, n_calibration_day_traffic=0, mesh=0.6)
    scenario = load_scenario(day.scenario)
    cal = calibrate_site([load_record(p, scenario) for p in day.calibration],
                         build_site_setup(scenario))
    return day, scenario, cal


def _truth(day):
    out = {}
    with open(day.truth, newline="") as f:
        for r in csv.DictReader(f):
            out.setdefault(r["record"], []).append(r)
    return out


def test_runs_with_another_vehicle_rejected_and_the_others_used(site):
    """Every run with a lane-3 vehicle crossing at the same time is rejected with that
    reason; every run of the truck alone is used (measured: 6 of 6 and 6 of 6 on both
    seeds here and on the benchmark's two)."""
    day, _, cal = site
    truth = _truth(day)
    for path, reason in zip(day.calibration, cal.reasons, strict=True):
        if len(truth[path.name]) > 1:
            assert reason.startswith("another vehicle on the bridge"), path.name
        else:
            assert reason == "", (path.name, reason)


def test_drift_correction_halves_the_traffic_dates_scatter(site):
    """The traffic date's lane-1 reference trucks: the calibration day's factor at the
    same time of day (the default without a temperature channel or traffic enough for the
    traffic's own drift) against no correction.  GVW error sd measured 6.1 against
    13.6 % (seed 5) and 6.1 against 16.4 % (seed 6): at least a quarter less is asked.
    Switching the correction off fails this test."""
    day, scenario, cal = site
    reference = [r for r in read_reference(day.reference) if r.lane == 1]
    paths = [day.traffic[0].parent / r.record for r in reference]
    read = partial(load_record, scenario=scenario)

    def gvw_sd(calibration):
        rows = [r for o in weigh_events(paths, calibration, read=read) for r in o.rows]
        res = assess(rows, reference)
        assert res.n_vehicles >= 0.9 * len(reference)
        return next(c for c in res.criteria if c.name == "gross_weight").std

    off = dataclasses.replace(cal, setup=dataclasses.replace(
        cal.setup, drift=dataclasses.replace(cal.setup.drift, method="none")))
    corrected, uncorrected = gvw_sd(cal), gvw_sd(off)
    assert corrected < 0.75 * uncorrected, (corrected, uncorrected)
    assert np.isfinite(corrected)


def _moved_aside(record, k):
    """``record`` with its strain field moved ``k`` gauges up the section (towards
    lane 2): gauge j reads what gauge j - k read, the k lowest their own first reading
    (unloaded).  The axle detectors are untouched: the lane-1 pair still sees the
    truck."""
    all_names = [s.name for s in record.sensors]
    cols = [all_names.index(n) for n in gauge_names(record)]  # across the deck, in order
    data = record.data.copy()
    for j, c in enumerate(cols):
        data[:, c] = (record.data[:, cols[j - k]] if j >= k else record.data[0, c])
    return dataclasses.replace(record, data=data)


def test_a_vehicle_outside_the_runs_lateral_reach_is_not_weighed(site):
    """A vehicle the lane-1 detectors see while the gauges place it about 1.4 m or more
    from the calibration runs' mean lateral position, where the lines are not calibrated
    (on bench_realsite's days lane-2 trucks seen by the lane-1 pair were weighed at +10 …
    +33 %, and a truck in lane 1 with one beside it in lane 2 at nearly twice its
    weight), is refused with the reason; no single lane-1 truck is (on the benchmark's
    days they lie within 0.56 m of the runs' mean; 1.0 m is allowed).  The case is made
    from each lane-1 truck's own record, its strain field moved three gauges (2.04 m)
    towards lane 2 (:func:`_moved_aside`; measured 1.70-2.43 m from the runs' mean, the
    trucks' own -0.35 … +0.39 m, seeds 5 and 6); a lane-2 truck alone is never weighed as a
    lane-1 one (with the detectors' dips of the real range, stop 35, the lane-1 pair no
    longer sees seed 6's lane-2 trucks, which it did before)."""
    day, scenario, cal = site
    truth = _truth(day)
    read = partial(load_record, scenario=scenario)
    rows = [r for o in weigh_events(list(day.traffic), cal, read=read) for r in o.rows
            if r.lane == 1 and len(truth[r.record]) == 1]
    lane2 = [r for r in rows if truth[r.record][0]["lane"] == "2"]
    lane1 = [r for r in rows if truth[r.record][0]["lane"] == "1"]
    assert len(lane1) >= 10
    assert all(not r.weighed for r in lane2), [(r.record, r.reason) for r in lane2]
    assert not any("lateral position" in r.reason for r in lane1)
    weighed = [r.record for r in lane1 if r.weighed]
    moved = [weigh_event(_moved_aside(read(day.traffic[0].parent / name), 3), cal)
             for name in weighed]
    ones = [v for w in moved for v in w.vehicles if v.lane == 1]
    assert len(ones) == len(weighed)
    assert all(not v.weighed and "lateral position" in v.reason for v in ones), [
        v.reason or v.gvw for v in ones if v.weighed or "lateral position" not in v.reason]


def test_a_gauge_off_by_a_factor_0_6_in_one_run_leaves_that_run_out(site):
    """Gauge s02 at 0.6 × its gain in the first run used (of six clean runs): that run is
    left out with the gauge named, the others used.  Each gauge's gain is measured
    against the lines under the truck's known loads (review of stop 34: against a
    weighing's free loads, which take up part of one gauge's change, × 0.6 was kept and
    moved every weight of the day by about 4 %; × 1.5 is still read as less than the
    1.3 allowed, the lines holding the run themselves)."""
    day, scenario, cal = site
    records = [load_record(p, scenario) for p in day.calibration]
    first = cal.reasons.index("")
    rec = records[first]
    k = [s.name for s in rec.sensors].index("s02")
    data = rec.data.copy()
    data[:, k] = data[0, k] + 0.6 * (data[:, k] - data[0, k])
    records[first] = dataclasses.replace(rec, data=data)
    again = calibrate_site(records, cal.setup)
    assert again.reasons[first].startswith("gauge s02 at "), again.reasons[first]
    assert again.n_used == cal.n_used - 1

