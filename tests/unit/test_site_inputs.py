"""Bad input to the real-installation chain (issue 20, "Bad input"): a clock pattern that
does not match the file names, a lane with one detector, detector distances that
contradict the calibration runs' known spacings.  Each is a one-line reason and exit
2, with nothing written.  Data: a tiny realistic site (:mod:`bwim.synthetic`,
``short-span-4-lane``), edited the way a user's mistake would edit it."""

import pytest

from bwim.cli import main
from bwim.errors import InputError
from bwim.scenario import build_site_setup, load_record, load_scenario
from bwim.site import calibrate_site
from bwim.synthetic import make_test_day


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    return make_test_day(tmp_path_factory.mktemp("inputs") / "day", site="short-span-4-lane",
                         seed=4, n_calibration=3, n_traffic=2, n_calibration_day_traffic=0,
                         mesh=0.6)


def _edited(day, tmp_path, old: str, new: str):
    text = day.scenario.read_text()
    assert old in text
    path = tmp_path / "site.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def _weigh(day, scenario, out, capsys) -> tuple[int, str]:
    code = main(["weigh", str(scenario), str(day.traffic[0].parent), "--calibration-records",
                 str(day.calibration[0].parent), "-o", str(out)])
    err = capsys.readouterr().err.strip()
    return code, err


def test_clock_pattern_that_matches_no_file_name(day, tmp_path, capsys):
    scenario = _edited(day, tmp_path, "[logger]\n", '[logger]\nclock = "evt_%Y%m%d_%H%M%S"\n')
    code, err = _weigh(day, scenario, tmp_path / "out", capsys)
    assert code == 2
    assert len(err.splitlines()) == 1
    assert "the file name has no clock time in the pattern 'evt_%Y%m%d_%H%M%S'" in err
    assert not (tmp_path / "out" / "summary.csv").exists()


def test_lane_with_one_detector(day, tmp_path, capsys):
    scenario = _edited(day, tmp_path, 'channels = ["ad1", "ad2"]', 'channels = ["ad1"]')
    with pytest.raises(InputError, match=r"\[\[axle_detectors\]\] entry 1: channels must "
                                         "name two different logger channels"):
        load_scenario(scenario)
    code, err = _weigh(day, scenario, tmp_path / "out", capsys)
    assert code == 2 and len(err.splitlines()) == 1 and "entry 1: channels" in err
    assert not any((tmp_path / "out").glob("*"))


def test_detector_distance_that_contradicts_the_runs(day, tmp_path, capsys):
    """The lane-1 detectors declared 4 m apart (3 m in truth): the speeds from the truck's
    declared spacings disagree with those from the detectors' lag by a third, far beyond
    what detection explains; the runs give back the true distance."""
    scenario = _edited(day, tmp_path, "distance = 3.0", "distance = 4.0")
    sc = load_scenario(scenario)
    runs = [load_record(p, sc) for p in day.calibration]
    with pytest.raises(InputError, match="distance of 4 m contradicts") as info:
        calibrate_site(runs, build_site_setup(sc))
    given = float(str(info.value).split("they give ")[1].split(" m")[0])
    assert given == pytest.approx(3.0, abs=0.1)
    code, err = _weigh(day, scenario, tmp_path / "out", capsys)
    assert code == 2 and len(err.splitlines()) == 1 and "contradicts" in err
    assert not (tmp_path / "out" / "summary.csv").exists()
