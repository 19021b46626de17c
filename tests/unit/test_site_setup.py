"""The site chain's edges: its setup refuses what cannot describe a truck, and a weigh
batch refuses two records that the summary could not tell apart."""

import math

import numpy as np
import pytest

from bwim.cli import main
from bwim.errors import InputError
from bwim.fe.convergence import check_mesh
from bwim.paper import sensors, slab_bridge
from bwim.site import SiteSetup


@pytest.mark.parametrize(("spacings", "match"), [
    ([3.8, math.nan], "calibration_spacings"), ([3.8, math.inf], "calibration_spacings"),
    ([3.8], "calibration_spacings"), ([3.8, -1.0], "calibration_spacings"),
])
def test_site_setup_refuses_bad_spacings(spacings, match):
    with pytest.raises(InputError, match=match):
        SiteSetup(calibration_loads=[50e3, 100e3, 100e3], calibration_spacings=spacings)


def test_site_setup_needs_the_detectors_distance():
    with pytest.raises(InputError, match="distance"):
        SiteSetup(calibration_loads=[50e3, 100e3], calibration_spacings=[4.0],
                  detectors=("ad1", "ad2"))
    s = SiteSetup(calibration_loads=[50e3, 100e3], calibration_spacings=[4.0],
                  detectors=("ad1", "ad2"), distance=3.0)
    np.testing.assert_array_equal(s.calibration_loads, [50e3, 100e3])


def test_a_setup_of_one_pair_given_by_its_detectors_can_be_replaced():
    """The one-pair shorthand (``detectors=``, ``distance=``, ``position=``) lives on in
    ``lanes``: ``dataclasses.replace`` of such a setup keeps its pair (it raised "give
    lanes or detectors, not both", also inside ``calibrate_site`` with lines linear in
    the lateral position)."""
    import dataclasses

    s = SiteSetup(calibration_loads=[50e3, 100e3], calibration_spacings=[4.0],
                  detectors=("ad1", "ad2"), distance=3.0, position=-2.5, max_spacing=9.0)
    assert s.detectors is None and s.distance is None
    linear = dataclasses.replace(s, lateral="linear")
    assert linear.lanes == s.lanes and linear.lateral == "linear"
    (pair,) = linear.lanes
    assert (pair.channels, pair.distance, pair.position, pair.max_spacing) == (
        ("ad1", "ad2"), 3.0, -2.5, 9.0)
    # the shorthand's fields replaced on their own would leave the pair as it was: refused
    # (review of stop 37: distance=4.0 read back 4.0 while the pair kept 3.0)
    for field, value in (("distance", 4.0), ("position", 1.0), ("max_spacing", 20.0)):
        with pytest.raises(InputError, match="go with detectors="):
            dataclasses.replace(s, **{field: value})
    again = dataclasses.replace(s, detectors=("ad1", "ad2"), distance=4.0, lanes=())
    assert again.lanes[0].distance == 4.0


def test_weigh_refuses_two_records_of_one_name(tmp_path, capsys):
    scenario = tmp_path / "site.toml"
    scenario.write_text('[logger]\ncolumns = ["time", "s01"]\n[[sensors]]\nname = ["s01"]\n'
                        '[vehicle]\naxle_spacings = [4.0]\naxle_loads = [5e4, 1e5]\n')
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "e1.txt").write_text("0,1\n0.01,1\n")
    code = main(["weigh", str(scenario), str(tmp_path / "a"), str(tmp_path / "b"),
                 "--calibration-records", str(tmp_path / "a"), "-o", str(tmp_path / "out")])
    assert code == 2
    assert "two records are named 'e1.txt'" in capsys.readouterr().err


@pytest.mark.parametrize(("kw", "match"), [({"tol": "a"}, "tol"), ({"tol": 2.0}, "tol")])
def test_check_mesh_arguments(kw, match):
    with pytest.raises(InputError, match=match):
        check_mesh(slab_bridge(), sensors(), [], **kw)
