"""The shared input checks (``records.record_list``, ``errors.require_instance``) at the
public entry points that use them.

Reference: the InputError contract of ``bwim.errors`` (one line naming the argument and
what it got), the wording each entry point had before the checks were shared.
"""

import pytest

from bwim.errors import InputError, require_instance
from bwim.records import Record, record_list
from bwim.sensors import Sensor
from bwim.wim import calibrate_influence_line, calibrate_lines, weigh_static

LOADS = [60e3, 90e3]


@pytest.mark.parametrize(
    ("call", "needs"),
    [
        (lambda r: calibrate_influence_line(r, LOADS), "at least one crossing"),
        (lambda r: calibrate_lines(r, None, LOADS), "at least one run"),
    ],
)
def test_record_lists_are_checked_at_the_entry_points(call, needs):
    with pytest.raises(InputError, match=f"records is empty: calibration needs {needs}"):
        call([])
    with pytest.raises(InputError, match=r"records must be a sequence of Record, got int"):
        call(3)
    with pytest.raises(InputError, match=r"records\[0\] is a str, not a bwim Record"):
        call(["run.csv"])


def test_record_list_wraps_a_single_record():
    rec = Record(time=[0.0, 0.1], data=[[0.0], [1.0]],
                 sensors=(Sensor(x=6.0, y=4.0, kind="strain_x", name="a"),))
    assert record_list(rec, needs="x") == [rec]
    assert record_list((rec, rec), needs="x") == [rec, rec]


def test_require_instance_returns_the_value_or_names_the_argument():
    assert require_instance("n", 3, int) == 3
    with pytest.raises(InputError, match=r"^record must be a bwim Record, got dict$"):
        weigh_static({}, None)
