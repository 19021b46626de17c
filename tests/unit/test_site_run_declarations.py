"""What a site's calibration says of the runs it is given (review of stop 34, helper-40):
a run given twice is refused (one run's lines would pass the two-run minimum), and one
run alone says that two are needed."""

import dataclasses
from datetime import timedelta

import pytest

from bwim.errors import InputError
from bwim.site import calibrate_site


def test_a_run_given_twice_is_refused(small_site_calibrated):
    _, _, records, site = small_site_calibrated
    with pytest.raises(InputError, match=r"^calibration runs 1 and 2 are the same run "
                                         r"\(the same readings\): give each run once$"):
        calibrate_site([records[0], records[0], records[1]], site.setup)
    # the same clock with other readings (a file copied and edited) is refused too
    start = records[0].clock_at() - timedelta(seconds=float(records[1].time[0]))
    twin = dataclasses.replace(records[1], data=records[1].data * 1.01, clock=start)
    with pytest.raises(InputError, match=r"the same clock \(\d{4}-\d\d-\d\d "):
        calibrate_site([records[0], twin, *records[2:]], site.setup)


def test_one_run_says_two_are_needed(small_site_calibrated):
    _, _, records, site = small_site_calibrated
    with pytest.raises(InputError, match=r"^only [01] usable calibration run\(s\) of 1 "
                                         r"\(the lines need at least two\)($|: run 1: )"):
        calibrate_site([records[0]], site.setup)


def test_a_run_cut_mid_crossing_says_so(small_site_calibrated):
    """The first run used, cut where its truck is on the bridge (at 80 % of the record):
    refused as truncated (review of stop 34: "another vehicle on the bridge: gauge
    activity no axle detector saw", or a wrong axle count)."""
    _, _, records, site = small_site_calibrated
    first = site.reasons.index("")
    rec = records[first]
    keep = rec.time <= rec.time[0] + 0.8 * (rec.time[-1] - rec.time[0])
    runs = list(records)
    runs[first] = dataclasses.replace(rec, time=rec.time[keep], data=rec.data[keep])
    again = calibrate_site(runs, site.setup)
    assert again.reasons[first] == ("the record starts or ends while the truck is on the "
                                    "bridge (truncated)")
