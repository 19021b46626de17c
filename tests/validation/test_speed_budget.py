"""What sets the detected speed's error on the realistic site (issue 20's target: speed
within 0.5 %, spacings within 0.1 m): the trucks' dynamic tyre forces, not the detection.

Data: :func:`bwim.synthetic.make_test_day` with the ``short-span-4-lane`` layout, seed 5,
12 calibration runs, 40 traffic events, a 0.6 m mesh, the detectors' white noise off,
twice: on the preset's roads (``bwim.synthetic.sitedays.ROUGHNESS``) and on smooth roads
(G_d(n₀) 10⁻¹² m³: static tyre forces).  Nothing else differs.  Reference: the simulated
speeds and spacings (``reference.csv``).  The full study (four variants, 240 events, two
seeds) is ``benchmarks/bench_speed_budget.py``.
"""

import csv
import dataclasses
from functools import partial

import numpy as np
import pytest

from bwim.batch import weigh_events
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site
from bwim.synthetic import make_test_day
from bwim.synthetic.layout import SHORT_SPAN_4_LANE

SMOOTH = (1e-12, 1.1e-12)  # m³, G_d(n₀)
QUIET = dataclasses.replace(SHORT_SPAN_4_LANE, detector_response=dataclasses.replace(
    SHORT_SPAN_4_LANE.detector_response, noise=0.0))


def _errors(folder, **options):
    """Speed errors (%) and spacing errors (m) of the day's lane-1 reference trucks, each
    asserted detected alone with its axle count."""
    day = make_test_day(folder, site=QUIET, seed=5, n_calibration=12, n_traffic=40,
                        n_calibration_day_traffic=0, mesh=0.6, **options)
    scenario = load_scenario(day.scenario)
    site = calibrate_site([load_record(p, scenario) for p in day.calibration],
                          build_site_setup(scenario))
    with open(day.reference, newline="") as f:
        ref = {r["record"]: r for r in csv.DictReader(f) if r["lane"] == "1"}
    read = partial(load_record, scenario=scenario)
    rows = [r for o in weigh_events([p for p in day.traffic if p.name in ref], site, read=read)
            for r in o.rows if r.lane == 1]
    assert sorted(r.record for r in rows) == sorted(ref)
    speed, spacing = [], []
    for r in rows:
        truth = ref[r.record]
        assert r.n_axles == int(truth["n_axles"]), r.record
        speed.append(100.0 * (r.speed / float(truth["speed_m_s"]) - 1.0))
        spacing.extend(np.asarray(r.axle_spacings)
                       - np.array([float(x) for x in truth["axle_spacings_m"].split(";")]))
    return np.array(speed), np.array(spacing)


@pytest.fixture(scope="module")
def errors(tmp_path_factory):
    base = tmp_path_factory.mktemp("speed")
    return {"smooth": _errors(base / "smooth", roughness=SMOOTH),
            "preset": _errors(base / "preset")}


def test_on_smooth_roads_every_speed_is_within_half_a_percent(errors):
    """With static tyre forces the detection meets the issue's targets on every truck
    (15 lane-1 trucks; measured: speed error at most 0.34 %, mean -0.12 %; spacings at
    most 0.020 m)."""
    speed, spacing = errors["smooth"]
    assert speed.size >= 10
    assert np.abs(speed).max() < 0.5
    assert np.abs(spacing).max() < 0.03


def test_the_roads_dynamics_set_the_speeds_scatter(errors):
    """The same trucks on the preset's roads: the speed's scatter grows more than five-fold
    (measured: standard deviation 1.23 % against 0.12 %, 10×; spacings 0.056 m against
    0.007 m).  A tyre force that changes while the tyre crosses a detector's 1 m wide
    response moves the response's centre, differently at the two detectors
    (docs/realistic_site.md)."""
    smooth, preset = errors["smooth"][0], errors["preset"][0]
    assert preset.std() > 5.0 * smooth.std()
    assert errors["preset"][1].std() > 5.0 * errors["smooth"][1].std()
