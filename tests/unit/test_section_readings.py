"""A record's section gauges read once for every detector pair (bwim.detect.assemble's
section_readings, taken by detect_axles, assemble_detection and detect_lanes): the
detection is the same as reading them in each, bit for bit.

Reference: :func:`bwim.detect.detect_axles` of each pair without ``section`` (every pair
reads its gauges, sums them, takes the sum's noise and the time step itself).  Data: the
small realistic site's calibration and its four traffic events (learned responses, two
detector pairs, twelve gauges).
"""

from __future__ import annotations

import numpy as np
import pytest

from bwim.detect import detect_axles
from bwim.detect.assemble import SectionReadings, section_readings
from bwim.detect.presence import signal_noise
from bwim.detect.signals import channel_data, median
from bwim.errors import InputError
from bwim.scenario import load_record
from bwim.site.calibrate import gauge_names


def _same_detection(a, b) -> None:
    assert (a.flags, a.message, a.method, a.fault) == (b.flags, b.message, b.method, b.fault)
    assert len(a.vehicles) == len(b.vehicles)
    for v, w in zip(a.vehicles, b.vehicles, strict=True):
        for name in ("confidence", "flags", "lateral", "lateral_unit", "window", "snr",
                     "speed_spread", "spacing_disagreement", "residual"):
            x, y = getattr(v, name), getattr(w, name)
            assert x == y or (x != x and y != y), name
        for name in ("axle_times", "axle_amplitudes", "detector_times"):
            assert np.array_equal(getattr(v, name), getattr(w, name), equal_nan=True), name
        p, q = v.passage, w.passage
        assert (p.speed, p.lane, p.delay) == (q.speed, q.lane, q.delay)
        assert np.array_equal(p.axle_spacings, q.axle_spacings)


@pytest.fixture(scope="module")
def events(small_site_calibrated):
    day, scenario, _, site = small_site_calibrated
    return site, [load_record(p, scenario) for p in day.traffic]


def test_section_readings_are_the_gauges_read(events):
    _, records = events
    for record in records:
        names = gauge_names(record)
        s = section_readings(record, names)
        data = channel_data(record, names)
        assert s.gauges == tuple(names)
        assert np.array_equal(s.readings, data) and s.readings.strides == data.strides
        assert np.array_equal(s.total, data.sum(axis=1))
        assert s.noise == signal_noise(data.sum(axis=1))
        assert s.step == median(np.diff(record.time))


def test_detection_with_the_section_read_once_is_the_same(events):
    """Every pair of every event: the same detection with the section given."""
    site, records = events
    lines = site.lines
    span = lines.core_support or lines.support
    n = 0
    for record in records:
        names = gauge_names(record)
        section = section_readings(record, names)
        for pair in site.setup.lanes:
            position = float(pair.position or 0.0)
            lane_span = span
            if pair.direction != site.setup.calibration_pair.direction:
                position, lane_span = -position, (-span[1], -span[0])
            kw = {"position": position, "span": lane_span, "gauges": list(names),
                  "responses": site.responses.get(pair.lane)}
            ref = detect_axles(record, pair.channels, pair.distance, **kw)
            got = detect_axles(record, pair.channels, pair.distance, section=section, **kw)
            _same_detection(got, ref)
            n += len(ref.vehicles)
    assert n >= 4


def test_a_section_of_other_gauges_is_refused(events):
    site, records = events
    record = records[0]
    names = gauge_names(record)
    pair = site.setup.lanes[0]
    other = section_readings(record, names[:-1])
    with pytest.raises(InputError, match="section: the readings of"):
        detect_axles(record, pair.channels, pair.distance, gauges=list(names),
                     responses=site.responses.get(pair.lane), section=other)
    with pytest.raises(InputError, match="section must be SectionReadings"):
        detect_axles(record, pair.channels, pair.distance, gauges=list(names),
                     section=object())
    assert isinstance(other, SectionReadings)
