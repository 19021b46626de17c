"""Without axle detectors, the calibration truck's loads declared in reverse order are
refused as with them (issue 22 item 2; tests/unit/test_site_load_order.py is the
detector mode's test).

Data: the session's small realistic site (tests/conftest.py, ``small_site``: an FE plate
with vehicle dynamics, gauge noise, offsets and drift; the 40 t 5-axle truck, loads
52.8, 110.2, 75.7, 76.5, 77.3 kN from the first axle), its three runs of the truck
alone, read without the axle detectors (``SiteSetup.lanes`` empty: the truck is found
from the strain).  The expected outcome is the issue's (refused).  Measured: the truck
found and fitted with the true order leaves a relative residual 0.130, with the
declared reverse order 0.240 (REVERSED_FIT = 0.75 needs under 0.180); the true order
is accepted by tests/validation/test_site_strain_only.py (another site, its true loads).
"""

import dataclasses
import re

import pytest

from bwim.errors import InputError
from bwim.site import calibrate_site
from bwim.site.calibrate import REVERSED_FIT


def test_loads_in_reverse_order_are_refused_without_detectors(small_site_calibrated):
    _, _, records, site = small_site_calibrated
    runs = [r for r, why in zip(records, site.reasons, strict=True) if not why]
    setup = dataclasses.replace(site.setup, lanes=(),
                                calibration_loads=site.setup.calibration_loads[::-1])
    assert len(runs) == 3 and not setup.lanes
    with pytest.raises(InputError, match="fit markedly better with the declared axle loads "
                       "in reverse order") as info:
        calibrate_site(runs, setup, strain_passes=0)
    message = str(info.value)
    assert "\n" not in message and "first axle to the last" in message
    better, declared = (float(v) for v in re.findall(r"\d\.\d{3}", message))
    assert better < REVERSED_FIT * declared
