"""Influence lines with a lobe of the opposite sign beyond the supports (issue 20 item 5).

A slab continuous over its supports (or on abutments that carry moment) reads a load
beyond the span with the opposite sign.  Reference: the mid-span bending moment of the
centre span of a three-span continuous beam (spans a, L, a), by the three-moment
equation (Clapeyron; e.g. Timoshenko & Young, "Theory of Structures", 2nd ed., 1965,
§ 9.3), checked against the tabulated coefficients of three equal spans (a point load at
the centre of the middle span: 0.175 PL at mid-span, −0.075 PL over the supports; e.g.
Reynolds & Steedman, "Reinforced Concrete Designer's Handbook", table of continuous beam
coefficients) and the clamped-clamped limit (PL/8 at mid-span).
"""

from __future__ import annotations

import numpy as np
import pytest

from bwim.records import Passage, Record
from bwim.sensors import Sensor
from bwim.wim import calibrate_lines, weigh
from bwim.wim.support import Grid, trimmed_support

from tests.continuous_beam import centre_moment


def test_closed_form_matches_the_tables():
    """Three equal spans, unit load at mid-span of the centre: 0.175 L (tables); end
    spans of vanishing length: the clamped-clamped beam, L / 8."""
    assert centre_moment(np.array([3.0]), 6.0, 6.0)[0] == pytest.approx(0.175 * 6.0, rel=1e-12)
    assert centre_moment(np.array([3.0]), 6.0, 1e-9)[0] == pytest.approx(6.0 / 8, rel=1e-6)
    # a load on an end span lifts the centre (the opposite sign), symmetric
    side = centre_moment(np.array([-2.0, 8.0]), 6.0, 6.0)
    assert side[0] < 0 and side[0] == pytest.approx(side[1], rel=1e-12)


def test_a_significant_lobe_beyond_the_zero_is_kept_and_vibration_is_not():
    """trimmed_support with keep_lobes walks past the zero of the line into an opposite
    lobe above the threshold (here 22 % of the peak: full continuity over equal spans),
    and still stops at the zero before a lobe below it (2 %: a first pass's free
    vibration); without it the line ends at the first zero, as before."""
    grid = Grid(x0=-8.0, h=0.05, n=440)  # -8 ... 14 m
    interior = grid.x[1:-1]
    line = centre_moment(interior, 6.0, 6.0)
    lo, hi = trimmed_support(line[:, None], grid, 0.05, keep_lobes=True)
    assert lo < -4.0 and hi > 10.0  # the lobes reach 6 m beyond each support
    lo, hi = trimmed_support(line[:, None], grid, 0.05)
    assert -0.3 <= lo <= 0.0 and 6.0 <= hi <= 6.3
    ripple = np.where((interior > 6.0) & (interior < 9.0), -0.02 * line.max()
                      * np.sin(np.pi * (interior - 6.0) / 3.0), 0.0)
    simple = np.where((interior >= 0) & (interior <= 6.0),
                      np.minimum(interior, 6.0 - interior) / 2, 0.0) + ripple
    lo, hi = trimmed_support(simple[:, None], grid, 0.05, keep_lobes=True)
    assert -0.2 <= lo <= 0.0 and 6.0 <= hi <= 6.2


def _record(line_x, line, offsets, loads, speed, fs=512.0, noise=0.0, rng=None):
    """Static readings of one channel as the closed-form line (reading = moment)."""
    t0 = 0.3
    t = np.arange(0.0, t0 + (line_x[-1] - line_x[0] + offsets[-1]) / speed + 0.2, 1 / fs)
    x_first = line_x[0] + speed * (t - t0)
    e = sum(w * np.interp(x_first - a, line_x, line, left=0.0, right=0.0)
            for a, w in zip(offsets, loads, strict=True))
    if noise:
        e = e + noise * rng.standard_normal(t.size)
    p = Passage(speed=speed, lane=0.0, axle_spacings=np.diff(offsets),
                delay=t0 - line_x[0] / speed)
    return Record(time=t, data=e[:, None], sensors=(Sensor(x=3.0, y=0.0, kind="strain_x",
                                                           name="g"),),
                  passages=(p,))


def test_single_axles_right_on_a_slab_continuous_over_its_supports():
    """A 6 m span continuous over 6 m end spans (a lobe of −22 % of the peak beyond
    each support): calibrated from a 5-axle truck, a 2+3 truck of another load
    distribution is weighed with its single axles right.  With the lobes cut off at the
    zero (``support_lobes=False``, the default) the steering axle came out +15.9 %, the
    drive axle −18.9 %, each tridem axle +6.8 % (measured); now every axle within 0.1 %
    (measured 0.02 %; the data are the closed form's with a tiny noise, the line
    piecewise linear: an algebra check of the support rule, not of the dynamics)."""
    span, side = 6.0, 6.0
    xs = np.linspace(-side, span + side, 2401)
    line = centre_moment(xs, span, side)
    cal_offsets = np.array([0.0, 3.8, 9.8, 11.1, 12.4])
    cal_loads = np.array([53e3, 110e3, 76e3, 76e3, 77e3])
    rng = np.random.default_rng(3)
    runs = [_record(xs, line, cal_offsets, cal_loads, v, noise=1e-4 * line.max() * 1e5,
                    rng=rng) for v in (20.0, 21.5, 23.0, 24.5)]
    lines = calibrate_lines(runs, None, cal_loads, per_run_scale=False, support_lobes=True)
    assert lines.support[0] < -4.0 and lines.support[1] > 10.0
    offsets = np.array([0.0, 3.6, 9.6, 10.95, 12.3])
    loads = np.array([50e3, 95e3, 58e3, 58e3, 58e3])
    w = weigh(_record(xs, line, offsets, loads, 22.0), None, lines, scale_correction=False)
    err = w.axle_weights / loads - 1
    assert np.all(np.abs(err) < 0.001)
    assert abs(w.gvw / loads.sum() - 1) < 0.001


def test_a_record_may_end_on_the_lobe_but_not_on_the_span():
    """With the lobes kept the lines know the support without them (``core_support``):
    a record that ends while the last axle is on the far lobe is weighed (the lobe's
    reading beyond the record is simply not observed), one that ends while it is still
    on the span is truncated, as before.  Same continuous beam as above: the data are
    the closed form's and the lines are fitted to it, so this checks the support rule's
    algebra, not the dynamics (the continuous site's bench_realsite does that)."""
    span, side = 6.0, 6.0
    xs = np.linspace(-side, span + side, 2401)
    line = centre_moment(xs, span, side)
    cal_offsets = np.array([0.0, 3.8, 9.8, 11.1, 12.4])
    cal_loads = np.array([53e3, 110e3, 76e3, 76e3, 77e3])
    runs = [_record(xs, line, cal_offsets, cal_loads, v) for v in (20.0, 22.0, 24.0)]
    lines = calibrate_lines(runs, None, cal_loads, per_run_scale=False, support_lobes=True)
    lo, hi = lines.core_support
    assert lines.support[0] < lo - 3.0 and hi + 3.0 < lines.support[1]  # lobes kept
    assert -0.3 <= lo <= 0.0 and 6.0 <= hi <= 6.3  # the span, as without lobes
    offsets = np.array([0.0, 3.6, 9.6, 10.95, 12.3])
    loads = np.array([50e3, 95e3, 58e3, 58e3, 58e3])
    whole = _record(xs, line, offsets, loads, 22.0)
    p = whole.passages[0]
    last_x = p.axle_x(whole.time)[:, -1]  # the last axle's position at each sample
    on_lobe = int(np.argmax(last_x > hi + 2.0))  # the last axle 2 m beyond the span
    on_span = int(np.argmax(last_x > 0.5 * (lo + hi)))  # still on the span
    for end, truncated in ((on_lobe, False), (on_span, True)):
        rec = Record(time=whole.time[:end], data=whole.data[:end], sensors=whole.sensors,
                     passages=whole.passages)
        w = weigh(rec, None, lines, scale_correction=False)
        assert ("truncated_end" in w.flags) is truncated, (end, w.flags)
        if not truncated:  # measured: every axle within 0.023 %
            assert np.all(np.abs(w.axle_weights / loads - 1) < 0.001)
    # the lines without lobes have no core of their own
    assert calibrate_lines(runs, None, cal_loads, per_run_scale=False).core_support is None


def test_a_lobe_of_the_same_sign_is_not_kept():
    """Only a lobe of the opposite sign is a continuous slab's adjacent span: the same
    lobe with its sign flipped (as a first pass whose signal spreads under wrong loads
    can show) ends the line at the zero before it; so does a second lobe beyond."""
    grid = Grid(x0=-8.0, h=0.05, n=440)
    interior = grid.x[1:-1]
    line = centre_moment(interior, 6.0, 6.0)
    same = np.where((interior < 0) | (interior > 6.0), np.abs(line), line)
    lo, hi = trimmed_support(same[:, None], grid, 0.05, keep_lobes=True)
    assert -0.3 <= lo <= 0.0 and 6.0 <= hi <= 6.3
    # two channels: the sign is judged on the channels together (their scalar product)
    both = np.column_stack([line, 0.5 * line])
    lo, hi = trimmed_support(both, grid, 0.05, keep_lobes=True)
    assert lo < -4.0 and hi > 10.0
