"""Issue 22, the site API's bad arguments: each raises InputError with a one-line message
naming the argument (before: AttributeError, TypeError or ValueError from deep inside).
Data: the session's small realistic site."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bwim
from bwim.errors import InputError
from bwim.scenario import build_bridge, load_record
from bwim.site import calibrate_site, calibrate_site_model, weigh_event


@pytest.fixture(scope="module")
def setup(small_site_calibrated):
    day, scenario, records, site = small_site_calibrated
    return {"records": records, "setup": site.setup, "site": site,
            "bridge": build_bridge(scenario),
            "event": load_record(day.traffic[0], scenario)}


CASES = {
    "weigh_event record=None": (lambda s: weigh_event(None, s["site"]), "record"),
    "weigh_event calibration=None": (lambda s: weigh_event(s["event"], None), "calibration"),
    "weigh_event identify_options=3": (lambda s: weigh_event(
        s["event"], s["site"], bridge=s["bridge"], identify_options=3), "identify_options"),
    "calibrate_site setup=None": (lambda s: calibrate_site(s["records"], None), "setup"),
    "calibrate_site records=[None]": (lambda s: calibrate_site([None], s["setup"]),
                                      "records"),
    "site model calibration=None": (lambda s: calibrate_site_model(
        s["records"], None, s["bridge"]), "calibration"),
    "site model tolerance='a'": (lambda s: calibrate_site_model(
        s["records"], s["site"], s["bridge"], tolerance="a"), "tolerance"),
    "site model track_width=nan": (lambda s: calibrate_site_model(
        s["records"], s["site"], s["bridge"], track_width=math.nan), "track_width"),
    "site model records='abc'": (lambda s: calibrate_site_model(
        "abc", s["site"], s["bridge"]), "records"),
    "assess summary_rows=None": (lambda s: bwim.assess(None, []), "summary_rows"),
    "Record data='abc'": (lambda s: bwim.Record(time=np.arange(3.0), data="abc",
                                                sensors=()), "data"),
    "with_params E_y='a'": (lambda s: s["bridge"].with_params(E_y="a"), "E_y"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_bad_argument_is_an_input_error(setup, name):
    call, word = CASES[name]
    with pytest.raises(InputError) as info:
        call(setup)
    message = str(info.value)
    assert word in message and "\n" not in message, message
