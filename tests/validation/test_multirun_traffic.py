"""Multi-run influence lines and the weighing of unknown traffic on a simulated
installation (issue 11), without inverse crime.

The data come from ``benchmarks/bench_multirun.py``: a 9 m × 10 m slab (Kirchhoff plate
FE, 0.25 m elements), 14 mid-span gauges, a 3-D truck model coupled with the bridge
(Newmark, modal with static correction) over ISO 8608 class A roads, 512 Hz, absolute
gauge noise (0.5 µε, three gauges 3 µε), random offsets, a strain-to-load drift of 6 %
over the day and ±0.3 m lateral wander; passages from the simulation's truth.  The
inversion knows none of this: piecewise-linear lines on a 0.05 m grid, fitted to the
records.  References: the vehicles' static axle loads (their own equilibrium) and the
drift the records were scaled by.
"""

import dataclasses
import time

import numpy as np
import pytest
from benchmarks import bench_multirun as site

from bwim.vehicles import library
from bwim.wim.multirun import calibrate_lines
from bwim.wim.weigh import weigh

HOUR = 3600.0


def _calibrate(events, **kw):
    return calibrate_lines([e.record for e in events], [e.passage for e in events],
                           events[0].static_axle_loads, **kw)


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


@pytest.fixture(scope="module")
def installation():
    bridge, gauges = site.bridge(), site.sensors()
    return {
        "bridge": bridge, "gauges": gauges,
        "day": site.calibration_day(bridge, gauges),
        "flat_day": site.calibration_day(bridge, gauges, road_class="flat"),
        "traffic": site.traffic(bridge, gauges, n=40, seed=111),
        "flat_traffic": site.traffic(bridge, gauges, n=24, road_class="flat"),
    }


def test_scale_factors_follow_the_drift(installation):
    """Flat road (the bridge's own dynamics and noise only): the runs' factors recover the
    drift (normalised to mean 1) to within 1 % (measured max 0.59 %, RMS 0.28 %, with the
    lateral model; 1.35 % / 0.82 % without it, the lateral mismatch leaking into the
    factors), while the drift itself spans ±4 %.  On the class A road the truck's own
    dynamics add a per-run error of 2.4 % RMS (measured), which the trend's smoothing
    halves (0.93 % RMS)."""
    day = installation["flat_day"]
    cal = _calibrate(day, lateral="linear")
    truth = np.array([site.drift(e.clock) for e in day])
    truth /= truth.mean()
    err = cal.scale_factors / truth - 1
    assert np.abs(err).max() < 0.01
    assert np.abs(truth - 1).max() > 0.03  # without factors the error would be 4 %
    assert cal.success and not cal.rejected
    lo, hi = cal.support  # the true support is −1.5 … 7.5 m (detector frame)
    assert -1.6 < lo < -1.2 and 7.4 < hi < 7.9  # measured −1.32 … 7.58


def test_an_outlier_run_is_rejected_with_its_reason(installation):
    """A 13th run with a second truck in the other lane, not in its passage: rejected for
    its factor (measured +35 %, limit 16 %), or because detection flagged it; the other
    12 runs are kept and give the same lines as without it."""
    bridge, gauges, day = installation["bridge"], installation["gauges"], installation["day"]
    truck = site.calibration_truck()
    mp = site.event(bridge, gauges, truck, speed=20.0, lane=3.0, clock=12.5 * HOUR, seed=99,
                    others=[(library.two_axle_truck(), 22.0, 7.0, 0.25)])
    cal = _calibrate([*day, mp])
    assert [r.index for r in cal.rejected] == [12]
    assert "scale factor" in cal.runs[12].reason
    assert cal.runs[12].scale > 1.2
    flagged = _calibrate([*day, mp], run_flags=[()] * 12 + ["multiple_presence"])
    assert flagged.runs[12].reason == "flagged upstream: multiple_presence"
    np.testing.assert_allclose(flagged.line.ordinates, cal.line.ordinates)


def test_gls_beats_the_plain_sum_on_held_out_traffic(installation):
    """40 trucks (2-, 3- and 5-axle, 12–40 t) at other times, speeds, lanes and roads than
    the calibration: GVW RMS error with the per-gauge lines combined by GLS 2.45 %, with
    the plain sum of the gauges 2.52 % (measured; the same order over three calibration
    days, 2.92 / 2.99 % over all 120 trucks).  Most of the error is the vehicles' own
    dynamics, common to all gauges, which no combination removes."""
    cal = _calibrate(installation["day"])
    traffic = installation["traffic"]
    gls = site.errors(cal, traffic, combine="gls")
    plain = site.errors(cal, traffic, combine="sum")
    assert _rms(gls["gvw"]) < _rms(plain["gvw"])
    assert _rms(gls["group"]) < _rms(plain["group"])
    assert _rms(gls["gvw"]) < 3.0 and abs(gls["gvw"].mean()) < 1.0  # measured 2.45, +0.40


def test_tridem_group_weights(installation):
    """The 5-axle trucks' tridems (1.31 m spacing) weighed as groups: within 2 % on a flat
    road (measured max 1.54 %), within 6.6 % on the class A road (measured, 14 tridems:
    the trailer's dynamics)."""
    flat = _calibrate(installation["flat_day"])
    errs = []
    for e in installation["flat_traffic"]:
        if e.passage.n_axles == 5:
            w = weigh(e.record, e.passage, flat)
            assert w.groups[-1] == (2, 3, 4)
            errs.append(w.group_weights[-1] / e.static_axle_loads[2:].sum() - 1)
            np.testing.assert_allclose(w.axle_weights[2:], w.group_weights[-1] / 3)
    assert len(errs) >= 5 and np.abs(errs).max() < 0.02
    cal = _calibrate(installation["day"])
    rough = [weigh(e.record, e.passage, cal).group_weights[-1]
             / e.static_axle_loads[2:].sum() - 1
             for e in installation["traffic"] if e.passage.n_axles == 5]
    assert np.abs(rough).max() < 0.08


def test_flags_on_simulated_events(installation):
    """A second truck the passage does not describe raises the misfit above the limit; an
    event after the calibrated hours is flagged and corrected by the last factor; normal
    traffic is not flagged for its residual (measured 0 of 40; 1 of 60 on another day)."""
    bridge, gauges = installation["bridge"], installation["gauges"]
    cal = _calibrate(installation["day"])
    mp = site.event(bridge, gauges, library.tractor_semitrailer(), speed=20.0, lane=3.0,
                    clock=12 * HOUR, seed=73,
                    others=[(library.tractor_semitrailer(), 22.0, 7.0, 0.5)])
    w = weigh(mp.record, mp.passage, cal)
    assert "residual_high" in w.flags and w.quality == "reject"
    e = installation["traffic"][0]
    shift = 21 * HOUR - e.clock
    late = dataclasses.replace(e.record, time=e.record.time + shift)
    passage = dataclasses.replace(e.passage, delay=e.passage.delay + shift)
    w = weigh(late, passage, cal)
    assert "outside_calibration_time" in w.flags
    assert w.scale_factor == cal.scale_trend.factor[-1]
    flagged = [weigh(t.record, t.passage, cal).flags for t in installation["traffic"]]
    assert sum("residual_high" in f for f in flagged) <= 1
    assert not any({"truncated_start", "truncated_end", "no_baseline"} & set(f)
                   for f in flagged)


def test_weighing_throughput(installation):
    """Moses weighing of a 1.5 s, 512 Hz, 14-gauge event: at least 100 events per second
    on one core (measured 375–470 / s on the shared 2-core machine under load 7)."""
    cal = _calibrate(installation["day"])
    e = installation["traffic"][0]
    assert e.record.data.shape[1] == 14 and e.record.time.size >= 700
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(20):
            weigh(e.record, e.passage, cal)
        best = min(best, (time.perf_counter() - t0) / 20)
    assert 1.0 / best > 100.0
