"""Lanes without detectors, by their centre line (a review of stop 33): the scenario's
``[[lanes]]`` tables reach the site setup, and a detector pair whose own centre line is
unknown keeps its vehicles' lane number (a vehicle is given another lane only when it
lies nearer that lane's centre than its own; without its own there is nothing to be
nearer than).  Reference: the same calibration without the traffic lanes (equivalence:
lanes without detectors only name vehicles found elsewhere), and the declared numbers.

Data: the shared small realistic site (tests/conftest.py, ``small_site``: an FE plate with
vehicle dynamics, gauge noise, offsets and drift).
"""

from __future__ import annotations

import dataclasses

import pytest

from bwim.errors import InputError
from bwim.scenario import build_site_setup, load_scenario, scenario_from_dict
from bwim.site import calibrate_site, weigh_event
from bwim.site.setup import DetectorLane, Lane, SiteSetup

LANES = (Lane(number=2, y=7.9, direction="+x"), Lane(number=4, y=13.35, direction="-x"))


def test_lanes_tables_reach_the_site_setup(small_site, tmp_path):
    """[[lanes]] (it raised a TypeError: the field ``number`` shadowed its checker)."""
    doc = {"lanes": [{"number": 2, "y": 7.9}, {"number": 4, "y": 13.35, "direction": "-x"}]}
    assert scenario_from_dict(doc).lanes[1].y == 13.35
    text = small_site.scenario.read_text() + "".join(
        f'\n[[lanes]]\nnumber = {ln.number}\ny = {ln.y}\ndirection = "{ln.direction}"\n'
        for ln in LANES)
    path = tmp_path / "with_lanes.toml"
    path.write_text(text)
    setup = build_site_setup(load_scenario(path))
    assert setup.traffic_lanes == LANES
    assert setup.lane_of(13.0, "-x") == 4 and setup.lane_of(7.5, "+x") == 2
    with pytest.raises(InputError, match=r"\[\[lanes\]\] entry 2 y: expected a number"):
        scenario_from_dict({"lanes": [{"number": 2, "y": 7.9}, {"number": 4, "y": "x"}]})


def test_a_traffic_lane_must_agree_with_the_detectors():
    pair = DetectorLane(channels=("a", "b"), distance=3.0, lane=1, direction="+x")
    kw = dict(calibration_loads=[50e3, 100e3], calibration_spacings=[4.0], lanes=[pair])
    with pytest.raises(InputError, match="lane 1 travels -x in traffic_lanes but \\+x at "
                                         "its axle detectors"):
        SiteSetup(**kw, traffic_lanes=[Lane(number=1, y=3.0, direction="-x")])
    with pytest.raises(InputError, match="a lane appears twice in traffic_lanes"):
        SiteSetup(**kw, traffic_lanes=[Lane(number=2, y=3.0), Lane(number=2, y=6.0)])
    SiteSetup(**kw, traffic_lanes=[Lane(number=1, y=3.0)])  # its centre line: fine


def test_a_pair_without_a_centre_line_keeps_its_vehicles(small_site_calibrated,
                                                         small_site_truck):
    """The pairs' y removed, lanes 2 and 4 declared by their centres: every calibration
    run used without them is used with them (it was none: each run's truck was renamed
    lane 2, the nearest centre known), and the lane-1 truck is weighed in lane 1."""
    _, _, records, site = small_site_calibrated
    _, truck = small_site_truck
    base = site.setup
    lanes = [dataclasses.replace(ln, y=None) for ln in base.lanes]
    setup = dataclasses.replace(base, lanes=lanes)
    without = calibrate_site(records, setup)
    with_lanes = calibrate_site(records, dataclasses.replace(setup, traffic_lanes=LANES))
    assert with_lanes.n_used == without.n_used > 0
    rows = weigh_event(truck, with_lanes).to_summary_rows("truck")
    assert [r.lane for r in rows if r.weighed] == [1]


def test_the_wrong_calibration_lane_says_so(small_site_calibrated, tmp_path):
    """The lane-3 pair marked as the calibration lane, the truck having driven lane 1:
    refused, and the message names lane 1's pair as the one to mark (review of stop 33:
    it spoke of the detectors' distance only).  The lane-3 pair learns a response from
    the runs' lane-3 vehicles (half the runs hold one, of the truck's kind) and then sees
    nothing in the other three, where lane 1's pair sees the truck."""
    day, _, records, _ = small_site_calibrated
    text = day.scenario.read_text().replace('lane = 3\n', 'lane = 3\ncalibration = true\n', 1)
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    setup = build_site_setup(load_scenario(path))
    assert setup.calibration_lane == 3
    with pytest.raises(InputError, match=r"lane 3's detectors .*lane 1's \(ad1, ad2\) saw one: "
                                         r"if the truck drove lane 1, mark that lane's pair "
                                         r"\(calibration = true"):
        calibrate_site(records, setup)


def test_a_dead_detector_of_the_calibration_pair_is_not_taken_for_another_lane(
        small_site_calibrated):
    """The runs with a lane-3 vehicle only, detector ad1 dead (constant) in each, detection
    by peaks: the lane-1 pair sees no vehicle in any run while the lane-3 pair sees one
    in each (read as 3, 4 and 7 axles), but the runs' reasons name ad1, and the refusal
    does not send the operator to mark lane 3 (review of stop 35: it did on a bench day,
    any vehicle of the other pair counting; now only one of about the truck's axle
    count, and no run whose calibration pair has a detector silent counts)."""
    _, _, records, site = small_site_calibrated
    dirty = [k for k, why in enumerate(site.reasons) if why.startswith("another vehicle")]
    assert len(dirty) >= 2
    k = [s.name for s in records[0].sensors].index("ad1")
    dead = []
    for j in dirty:
        data = records[j].data.copy()
        data[:, k] = data[0, k]
        dead.append(dataclasses.replace(records[j], data=data))
    peaks = dataclasses.replace(site.setup, detection="peaks")
    with pytest.raises(InputError, match="is ad1 working") as err:
        calibrate_site(dead, peaks)
    assert "mark that lane's pair" not in str(err.value)
