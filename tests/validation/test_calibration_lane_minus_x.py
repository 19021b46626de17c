"""A calibration lane that travels the bridge's −x (review of stop 33: the lines' frame
is the calibration truck's own, where it travels +x, but each lane's detection was
mirrored by its absolute direction: with a "-x" calibration lane every vehicle's window
on the span was off by about 3 m of travel, 0.13-0.14 s here, in both directions, which
refused single trucks as multiple presence or truncated and threw out clean
calibration runs; nothing said so).

Data: the realistic preset (``short-span-4-lane``) seen from its other end (x → S − x,
y → W − y, every lane's direction reversed: the same bridge, the calibration lane now
"-x"), simulated by :func:`bwim.synthetic.make_test_day` on a 0.6 m mesh with vehicle
dynamics, gauge noise, offsets and drift.  Reference: the truth's crossing times and
the layout (closed form: the truth's time is the first axle at the gauge line; the
vehicle enters the span (its first axle reaches the support it meets first) ``d / v``
before, ``d`` the gauge line's distance from that support, and leaves ``(S + L) / v``
after entering).
Measured after the fix: medians within 0.006 s (the preset's own +x calibration lane:
0.0002-0.006 s).
"""

from __future__ import annotations

import csv
import dataclasses
from datetime import datetime

import numpy as np
import pytest

from bwim.scenario import build_site_setup, load_scenario, record_reader
from bwim.site import calibrate_site
from bwim.site.calibrate import gauge_names
from bwim.site.lanes import detect_lanes
from bwim.synthetic import make_test_day
from bwim.synthetic.layout import SHORT_SPAN_4_LANE as PRESET


def _seen_from_the_other_end(layout):
    w, s = layout.width, layout.span
    return dataclasses.replace(
        layout, name="short-span-4-lane, from the other end",
        lanes=tuple(dataclasses.replace(ln, y=round(w - ln.y, 6), direction=-ln.direction)
                    for ln in layout.lanes),
        gauges=tuple(dataclasses.replace(g, x=s - g.x, y=round(w - g.y, 6))
                     for g in layout.gauges),
        detectors=tuple(dataclasses.replace(d, x=s - d.x, y=round(w - d.y, 6))
                        for d in layout.detectors))


@pytest.fixture(scope="module")
def mirrored(tmp_path_factory):
    layout = _seen_from_the_other_end(PRESET)
    day = make_test_day(tmp_path_factory.mktemp("minus_x") / "day", site=layout, seed=4,
                        n_calibration=8, n_traffic=8, n_calibration_day_traffic=0, mesh=0.6)
    return layout, day


def test_the_calibration_lane_is_minus_x(mirrored):
    _, day = mirrored
    setup = build_site_setup(load_scenario(day.scenario))
    assert setup.calibration_pair.direction == "-x"
    assert {ln.direction for ln in setup.lanes} == {"-x", "+x"}


def test_windows_on_the_span_are_the_true_crossings(mirrored):
    """Each single vehicle's window on the span, in both directions, against the truth:
    the median error of its start and end within 0.02 s (it was -0.14 s)."""
    layout, day = mirrored
    scenario = load_scenario(day.scenario)
    setup = build_site_setup(scenario)
    read = record_reader(scenario)
    site = calibrate_site([read(p) for p in day.calibration], setup)
    span = site.lines.core_support or site.lines.support
    with open(day.truth, newline="") as f:
        truth = [t for t in csv.DictReader(f) if t["kind"] == "traffic"]
    errors: dict[str, list[tuple[float, float]]] = {}
    for path in day.traffic:
        (t, *more) = [t for t in truth if t["record"] == path.name] or [None]
        if t is None or more:
            continue
        lane = next(ln for ln in layout.lanes if ln.number == int(t["lane"]))
        if not any(d.lane == lane.number for d in layout.detectors):
            continue
        v = float(t["speed_m_s"])
        length = sum(float(a) for a in t["axle_spacings_m"].split(";"))
        gx = layout.gauges[0].x  # the gauge line
        d = gx if lane.direction > 0 else layout.span - gx
        first = (datetime.fromisoformat(t["time"])
                 - datetime.fromisoformat(t["event_start"])).total_seconds()
        entry = first - d / v
        leave = entry + (layout.span + length) / v
        rec = read(path)
        ev = detect_lanes(rec, setup, responses=site.responses, span=span,
                          gauges=gauge_names(rec), bending=site.bending)
        for lv in ev.vehicles:
            if lv.pair == lane.number:
                errors.setdefault(lv.direction, []).append(
                    (lv.window[0] - entry, lv.window[1] - leave))
    assert set(errors) == {"-x", "+x"}, errors
    for direction, e in errors.items():
        median = np.median(np.array(e), axis=0)
        assert np.all(np.abs(median) < 0.02), (direction, median)


def test_an_fe_model_asks_for_the_calibration_lane_to_travel_plus_x(mirrored):
    """The FE model's moving loads travel the model's +x: with a "-x" calibration lane the
    model calibration is refused with what to do (it would run the truck the wrong way
    over the model), not attempted."""
    from bwim.errors import InputError
    from bwim.site import calibrate_site_model

    _, day = mirrored
    scenario = load_scenario(day.scenario)
    read = record_reader(scenario)
    runs = [read(p) for p in day.calibration]
    site = calibrate_site(runs, build_site_setup(scenario))
    with pytest.raises(InputError, match="calibration lane travels -x: give the scenario's x "
                                         "from the other end"):
        calibrate_site_model(runs, site, None)
