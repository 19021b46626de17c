"""What the user declares is checked against the data (issue 22 item 2): the calibration
truck's axle loads against what a truck weighs (loads in kg instead of N refused with a
hint about units), its spacings against the spacings the axle detectors measure in every
used run.

Data: a tiny realistic site (:mod:`bwim.synthetic`, ``short-span-4-lane``: detectors
with noise, offsets and their own gains on an FE plate; the truck's true spacings 3.8,
6.0, 1.3, 1.3 m), with the scenario's ``[vehicle]`` edited the way a user's mistake
would edit it.  Expected outcomes are the issue's (refused, with the reason), not the
code's output.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from bwim.cli import main
from bwim.errors import InputError
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site
from bwim.site.calibrate import MIN_TRUCK_WEIGHT, SPACING_BIAS
from bwim.synthetic import make_test_day

LOADS = "axle_loads = [52842.7, 110182.5, 75657.0, 76458.3, 77259.5]"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    day = make_test_day(tmp_path_factory.mktemp("declared") / "day", site="short-span-4-lane",
                        seed=4, n_calibration=6, n_traffic=1, n_calibration_day_traffic=0,
                        mesh=0.6)
    scenario = load_scenario(day.scenario)
    runs = [load_record(p, scenario) for p in day.calibration]
    return day, build_site_setup(scenario), runs


def _loads(text: str, factor: float) -> str:
    values = [float(v) * factor for v in LOADS.split("[")[1].rstrip("]").split(",")]
    return text.replace(LOADS, "axle_loads = [" + ", ".join(f"{v:.1f}" for v in values) + "]")


@pytest.mark.parametrize(("factor", "why"), [
    (1.0 / 9.81, r"5 axles weighing 40\.0 kN \(4\.1 t\) in all \(under 10 t\)"),
    (1e-3, r"an axle of 0\.05 kN \(under 5 kN\)"),
])
def test_loads_not_in_newtons_are_refused(site, tmp_path, capsys, factor, why):
    """The 40 t truck's loads declared in kg (4.1 t) or in kN: refused by the API and by
    ``bwim weigh`` (one line, exit 2, nothing written), with the hint about units."""
    day, _, runs = site
    text = day.scenario.read_text()
    assert LOADS in text
    path = tmp_path / "site.toml"
    path.write_text(_loads(text, factor))
    with pytest.raises(InputError, match=why + r"; give the static axle loads in N, not kg"):
        calibrate_site(runs, build_site_setup(load_scenario(path)))
    code = main(["weigh", str(path), str(day.traffic[0].parent), "--calibration-records",
                 str(day.calibration[0].parent), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "not kg or kN" in err, err
    assert not (tmp_path / "out" / "summary.csv").exists()


def test_the_weight_limit_is_ten_tonnes_for_five_axles(site):
    """The same runs with the loads scaled to 5 % above and below 10 t: above is
    calibrated (the loads only scale the lines), below is refused; a light 2-axle truck
    is not refused for its loads (its runs are refused for their axle count)."""
    _, setup, runs = site
    loads = setup.calibration_loads
    above = dataclasses.replace(setup, calibration_loads=loads * 1.05 * MIN_TRUCK_WEIGHT
                                / loads.sum())
    assert calibrate_site(runs, above).n_used >= 2
    below = dataclasses.replace(setup, calibration_loads=loads * 0.95 * MIN_TRUCK_WEIGHT
                                / loads.sum())
    with pytest.raises(InputError, match="under 10 t"):
        calibrate_site(runs, below)
    two = dataclasses.replace(setup, calibration_loads=np.array([20e3, 30e3]),
                              calibration_spacings=np.array([3.8]))
    with pytest.raises(InputError) as info:
        calibrate_site(runs, two)
    assert "implausible" not in str(info.value) and "usable calibration run" in str(info.value)


def test_the_true_declaration_is_accepted(site):
    """The truck as it is: calibrated; every used run's detected spacings lie within
    0.1 m of the declared (measured: 0.077 m at most, signs mixed: the detection's own
    scatter under dynamic tyre forces), which the rule, 0.05 m on the same side in every
    run, leaves room for."""
    _, setup, runs = site
    cal = calibrate_site(runs, setup)
    dev = np.array([d.vehicles[0].passage.axle_spacings - setup.calibration_spacings
                    for d, why in zip(cal.detections, cal.reasons, strict=True) if not why])
    assert dev.shape[0] >= 2
    assert np.abs(dev).max() < 0.1
    assert SPACING_BIAS == 0.05


@pytest.mark.parametrize(("delta", "named"), [
    ([0.1, 0.1, 0.1, 0.1], [3, 4]),
    ([-0.1, -0.1, -0.1, -0.1], [3, 4]),
    ([0.0, 0.2, 0.0, 0.0], [2]),
    ([0.0, 0.0, 0.0, -0.2], [4]),
])
def test_spacings_every_run_contradicts_are_refused(site, delta, named):
    """Spacings declared 0.1 m or 0.2 m off, inside the runs' own 0.3 m acceptance (the
    issue's spacings 0.2 m long gave -8.3 % on every weight): refused, naming the spacing
    and what the runs detect, within 0.05 m of the truth (measured: 0.02 m at most, the
    tridem's 1.3 m read 1.28-1.32 m).  (All four 0.1 m off: one run of three reads the
    first two spacings within 0.05 m of the wrong declaration, so only the tridem's are
    named.)"""
    _, setup, runs = site
    truth = setup.calibration_spacings.copy()
    wrong = dataclasses.replace(setup, calibration_spacings=truth + np.array(delta))
    with pytest.raises(InputError, match="declared axle spacings contradict all 3 used runs"
                       ) as info:
        calibrate_site(runs, wrong)
    message = str(info.value)
    found = {int(k): float(v) for k, v in
             re.findall(r"spacing (\d) declared [\d.]+ m, detected ([\d.]+) m", message)}
    assert sorted(found) == named, message
    for k, detected in found.items():
        assert detected == pytest.approx(truth[k - 1], abs=0.05)


def test_runs_of_trucks_of_other_weights_are_refused(site):
    """Half the runs' strains halved (trucks of half the declared weight: what traffic
    given as calibration records looks like; the issue measured +43.8 ± 24 % on every
    weight): their scale factors span about ×2, beyond RUN_SCALE_RANGE: refused, naming
    the range.  The runs as they are pass (the test above)."""
    from bwim.site.calibrate import RUN_SCALE_RANGE

    _, setup, runs = site
    halved = []
    for k, rec in enumerate(runs):
        if k % 2:
            gauges = np.array([s.kind.is_structural for s in rec.sensors])
            data = rec.data.copy()
            data[:, gauges] *= 0.5
            rec = dataclasses.replace(rec, data=data)
        halved.append(rec)
    assert 2.0 > RUN_SCALE_RANGE
    with pytest.raises(InputError, match=r"scale factors range from 0\.\d\d to 1\.\d\d"):
        calibrate_site(halved, setup)


def _gauge_zeroed(rec, name):
    k = [s.name for s in rec.sensors].index(name)
    data = rec.data.copy()
    data[:, k] = 0.0
    return dataclasses.replace(rec, data=data)


def test_a_run_with_a_dead_gauge_is_left_out(site):
    """A gauge dead in one run (issue 22: sensor health on the calibration runs too): that
    run is rejected naming the gauge; the others are used as without it."""
    _, setup, runs = site
    clean = calibrate_site(runs, setup)
    used = [k for k, r in enumerate(clean.reasons) if not r]
    broken = list(runs)
    broken[used[0]] = _gauge_zeroed(runs[used[0]], "s05")
    cal = calibrate_site(broken, setup)
    assert "'s05' reads flat" in cal.reasons[used[0]]
    assert [k for k, r in enumerate(cal.reasons) if not r] == used[1:]


def test_a_gauge_dead_in_every_run_is_refused(site):
    _, setup, runs = site
    with pytest.raises(InputError, match=r"gauge 's05' reads flat \(dead or stuck\) in 6 of "
                                         r"6 calibration runs: leave it out"):
        calibrate_site([_gauge_zeroed(r, "s05") for r in runs], setup)


def test_two_runs_a_few_centimetres_off_the_same_way_are_no_contradiction(seed31_site):
    """Two runs of the truck alone (seed 31's runs 3 and 10) whose 6 m spacing both read
    0.06-0.1 m short: the detection's own scatter (over 77 used runs of 13 days that
    spacing read more than 0.05 m short in 15.6 % of the runs), which two runs share
    one time in forty.  Refused before as a declaration every run contradicts (stop 35's
    review: a false refusal with two runs); two runs now count only beyond 0.1 m, and a
    spacing declared 0.2 m off is still refused with them."""
    scenario = load_scenario(seed31_site.scenario)
    setup = build_site_setup(scenario)
    runs = [load_record(seed31_site.calibration[k], scenario) for k in (2, 9)]
    cal = calibrate_site(runs, setup)
    assert cal.reasons == ("", "")
    dev = [d.vehicles[0].passage.axle_spacings[1] - 6.0 for d in cal.detections]
    assert all(-0.1 < d < -0.05 for d in dev), dev
    wrong = dataclasses.replace(setup, calibration_spacings=setup.calibration_spacings
                                + np.array([0.0, 0.2, 0.0, 0.0]))
    with pytest.raises(InputError, match=r"contradict all 2 used runs: spacing 2 .* "
                                         r"\(every run more than 0.1 m the same way\)"):
        calibrate_site(runs, wrong)
