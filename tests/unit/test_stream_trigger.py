"""The trigger of continuous recordings (bwim.stream) on records built here: closed-form
half-sine pulses on a noisy, offset baseline.

Reference: a pulse ``A sin(π (t − t0) / D)`` on ``[t0, t0 + D]`` crosses ``c σ`` at
``t0 + D asin(c σ / A) / π`` and again at ``t0 + D − D asin(c σ / A) / π``; the noise moves
a crossing by about σ / slope = D / (π A / σ) (3 ms for A = 100 σ, D = 1 s), so the
crossings are checked to 10 ms.  The trigger's own windows are then exact in samples:
``pre`` before the opening, ``post`` after the closing.
"""

import dataclasses
import itertools
import math
from datetime import datetime, timedelta

import numpy as np
import pytest

from bwim import Record, Sensor
from bwim.errors import InputError
from bwim.stream import TriggerSettings, cut_events, cut_stream

FS = 512.0
SIGMA = 1.0  # noise σ of each of the three gauges: the sum's σ is √3


def _record(total: float, pulses=(), *, seed=0, clock=None, drift=0.0, step=None,
            spikes=()) -> Record:
    """Three gauges (offsets 40, −25, 7) and an axle detector; ``pulses`` (t0, D, A in
    units of the sum's σ) added to the sum, split 50/30/20 over the gauges; ``drift`` the
    sum's baseline slope (σ per s); ``step`` (t, height in σ) a lasting jump of the sum."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(total * FS)) / FS
    s_sigma = SIGMA * math.sqrt(3)
    shape = drift * s_sigma * t
    for t0, d, a in pulses:
        on = (t >= t0) & (t <= t0 + d)
        shape = shape + np.where(on, a * s_sigma * np.sin(math.pi * (t - t0) / d), 0.0)
    if step is not None:
        shape = shape + np.where(t >= step[0], step[1] * s_sigma, 0.0)
    for ts, a in spikes:
        k = round(ts * FS)
        shape[k:k + 3] += a * s_sigma
    gauges = np.outer(shape, [0.5, 0.3, 0.2]) + np.array([40.0, -25.0, 7.0])
    gauges += SIGMA * rng.standard_normal(gauges.shape)
    detector = rng.standard_normal(t.size)
    detector[::700] += 1e4                        # big axle-detector pulses: not summed
    sensors = [Sensor(name=f"g{j}") for j in range(3)] + [Sensor(name="ad",
                                                                 kind="axle_detector")]
    return Record(time=t, data=np.column_stack([gauges, detector]), sensors=sensors,
                  clock=clock)


def _crossings(t0, d, a, on, off):
    return (t0 + d * math.asin(on / a) / math.pi, t0 + d - d * math.asin(off / a) / math.pi)


def test_windows_where_the_pulses_were_put():
    pulses = [(5.0, 1.0, 100.0), (12.0, 0.8, 60.0), (20.0, 1.5, 200.0)]
    settings = TriggerSettings(pre=0.4, post=0.6)
    cut = cut_events(_record(30.0, pulses), settings)
    assert len(cut.events) == 3
    for ev, (t0, d, a) in zip(cut.events, pulses, strict=True):
        t_on, t_off = _crossings(t0, d, a, settings.on, settings.off)
        assert ev.on == pytest.approx(t_on, abs=0.01)
        assert ev.off == pytest.approx(t_off, abs=0.01)
        assert ev.start_index == round(ev.on * FS) - round(0.4 * FS)
        assert ev.stop_index == round(ev.off * FS) + round(0.6 * FS)
        assert ev.record.time.size == ev.n_samples
        assert ev.noise == pytest.approx(SIGMA * math.sqrt(3), rel=0.15)
        assert ev.baseline == pytest.approx(40.0 - 25.0 + 7.0, abs=1.0)
        assert ev.peak == pytest.approx(a, rel=0.05)
        assert ev.flags == ()


def test_no_event_on_noise_with_a_drifting_baseline():
    """Two minutes of noise whose sum drifts by 6 σ per minute: the baseline follows it
    (lagging by half its window, 0.5 σ; a baseline frozen at the start-up would be 6 σ off
    after a minute)."""
    cut = cut_events(_record(120.0, drift=0.1, seed=3))
    assert cut.events == ()
    assert cut.duration == pytest.approx(120.0)


def test_hysteresis_holds_the_trigger_between_the_thresholds():
    """A pulse followed by a 7 σ plateau (between off = 2 and on = 12; the noise reaches
    below 2 σ there with probability 3e-7 a sample) until 7.5 s: the trigger stays open
    across the plateau and closes when the sum falls back; with off = 9 it closes where
    the pulse falls to the plateau (near 6 s)."""
    rec = _record(20.0, [(5.0, 1.0, 100.0)])
    plateau = (rec.time > 5.97) & (rec.time < 7.5)
    data = rec.data.copy()
    data[plateau, 0] += 7.0 * SIGMA * math.sqrt(3)
    rec = Record(time=rec.time, data=data, sensors=rec.sensors)
    held = cut_events(rec, TriggerSettings(on=12.0, off=2.0)).events
    assert len(held) == 1 and held[0].off == pytest.approx(7.5, abs=2 / FS)
    dropped = cut_events(rec, TriggerSettings(on=12.0, off=9.0)).events
    assert len(dropped) == 1 and dropped[0].off == pytest.approx(6.0, abs=0.03)


def test_pre_and_post_trigger_and_the_record_edges():
    """``pre`` and ``post`` in samples; a pulse 0.1 s after the start keeps what there is
    (the window starts at the first sample)."""
    rec = _record(12.0, [(0.1, 1.0, 100.0), (8.0, 1.0, 100.0)])
    evs = cut_events(rec, TriggerSettings(pre=0.25, post=0.75, baseline=2.0)).events
    assert len(evs) == 2
    assert evs[0].start_index == 0 and evs[0].start == 0.0
    assert evs[1].start_index == round(evs[1].on * FS) - 128
    assert evs[1].stop_index == round(evs[1].off * FS) + 384
    assert evs[1].stop == pytest.approx(evs[1].off + 0.75 - 1 / FS, abs=1e-9)


def test_triggers_closer_than_the_gap_merge():
    """Two pulses 0.6 s apart (closing of one to opening of the next about 0.65 s): one
    event with the default gap (1 s), two with merge_gap 0.2 s and pre = post = 0.1 s."""
    pulses = [(10.0, 1.0, 100.0), (11.6, 1.0, 100.0)]
    rec = _record(20.0, pulses)
    merged = cut_events(rec).events
    assert len(merged) == 1
    t_on = _crossings(*pulses[0], 6.0, 3.0)[0]
    t_off = _crossings(*pulses[1], 6.0, 3.0)[1]
    assert merged[0].on == pytest.approx(t_on, abs=0.01)
    assert merged[0].off == pytest.approx(t_off, abs=0.01)
    apart = cut_events(rec, TriggerSettings(merge_gap=0.2, pre=0.1, post=0.1)).events
    assert len(apart) == 2
    assert apart[0].stop_index <= apart[1].start_index


def test_spikes_shorter_than_min_duration_are_dropped():
    rec = _record(15.0, spikes=[(6.0, 40.0)])
    assert cut_events(rec).events == ()
    kept = cut_events(rec, TriggerSettings(min_duration=0.0)).events
    assert len(kept) == 1 and kept[0].on == pytest.approx(6.0, abs=1 / FS)


def test_a_lasting_step_is_closed_at_max_duration_and_the_baseline_follows():
    rec = _record(60.0, step=(15.0, 50.0))
    evs = cut_events(rec, TriggerSettings(max_duration=12.0)).events
    assert len(evs) == 1
    assert evs[0].flags == ("max_duration",)
    assert evs[0].off == pytest.approx(15.0 + 12.0, abs=0.3)


def test_a_stream_that_begins_and_ends_inside_crossings():
    """The first pulse is under way at the first sample, the last one at the last: both
    events are kept, flagged, their windows clipped to the stream."""
    rec = _record(20.0, [(-0.3, 1.0, 100.0), (19.6, 1.0, 100.0)])
    evs = cut_events(rec, TriggerSettings(baseline=5.0)).events
    assert [e.flags for e in evs] == [("open_at_start",), ("open_at_end",)]
    assert evs[0].start_index == 0 and evs[0].on == 0.0
    assert evs[1].stop_index == rec.time.size and evs[1].off == pytest.approx(20.0)


def test_the_clock_of_each_event():
    clock = datetime(2026, 4, 17, 12, 0, 0)
    rec = _record(20.0, [(9.0, 1.0, 100.0)], clock=clock)
    ev = cut_events(rec).events[0]
    assert ev.record.time[0] == 0.0
    assert ev.clock == clock + timedelta(seconds=ev.start)
    assert ev.record.clock_at(ev.on - ev.start) == clock + timedelta(seconds=ev.on)
    np.testing.assert_array_equal(ev.record.data, rec.data[ev.start_index:ev.stop_index])
    # without a clock: a record time from 0 (the stream's is one) starts at 0 again, as
    # an event file of a clockless logger (it cannot be placed in the day: no_clock) ...
    clockless = cut_events(_record(20.0, [(9.0, 1.0, 100.0)])).events[0]
    assert clockless.record.clock is None and clockless.start > 8.0
    assert clockless.record.time[0] == 0.0 and not clockless.record.time_of_day
    np.testing.assert_allclose(clockless.record.time,
                               rec.time[clockless.start_index:clockless.stop_index]
                               - clockless.start, atol=1e-9)
    # (also when the logger counts from one sample step, or from 59 s: RECORD_TIME_SPAN)
    for t0 in (1.0 / FS, 59.0):
        late = _record(20.0, [(9.0, 1.0, 100.0)])
        late = dataclasses.replace(late, time=late.time + t0)
        ev = cut_events(late).events[0]
        assert ev.record.time[0] == 0.0 and not ev.record.time_of_day
    # ... and a clock time of day (a stream from 10:00) stays the stream's own
    morning = _record(20.0, [(9.0, 1.0, 100.0)])
    morning = dataclasses.replace(morning, time=morning.time + 36000.0)
    ev = cut_events(morning).events[0]
    assert ev.record.time[0] == ev.start > 36008.0 and ev.record.time_of_day
    # ... also past midnight, where the stream counts on (86400 s and more): the event
    # holds that day's clock time of day, as the logger's event file would (a stream
    # from 23:59:50, an event 80 s on: 70 s after midnight, past the first minute that a
    # record time may take)
    night = _record(100.0, [(80.0, 1.0, 100.0)])
    night = dataclasses.replace(night, time=night.time + 86390.0)
    ev = cut_events(night).events[0]
    assert ev.start > 86460.0 and ev.record.time_of_day
    np.testing.assert_allclose(ev.record.time,
                               night.time[ev.start_index:ev.stop_index] - 86400.0, atol=1e-9)
    assert ev.record.time[0] == pytest.approx(ev.start - 86400.0, abs=1e-9)


def test_the_stream_split_anywhere_gives_the_same_events():
    """The record cut whole and fed in pieces of 1000–9000 samples, one ending 10 samples
    before each opening: the same windows, openings, closings, peaks and data."""
    pulses = [(3.0, 1.0, 100.0), (9.3, 0.8, 60.0), (10.6, 1.0, 80.0), (25.0, 1.5, 200.0)]
    rec = _record(40.0, pulses, seed=5)
    whole = cut_events(rec).events
    rng = np.random.default_rng(1)
    edges = np.cumsum(rng.integers(1000, 9000, 40))
    near = [round(ev.on * FS) - 10 for ev in whole]  # a piece ends just before an opening
    edges = sorted({0, *edges[edges < rec.time.size - 2].tolist(), *near, rec.time.size})
    pieces = [Record(time=rec.time[a:b], data=rec.data[a:b], sensors=rec.sensors)
              for a, b in itertools.pairwise(edges)]
    streamed = list(cut_stream(pieces))
    assert len(whole) == len(streamed) == 3
    for w, s in zip(whole, streamed, strict=True):
        assert (w.start_index, w.stop_index, w.on, w.off, w.peak) == \
            (s.start_index, s.stop_index, s.on, s.off, s.peak)
        np.testing.assert_array_equal(w.record.data, s.record.data)


def test_a_stream_whose_pieces_do_not_follow_is_refused():
    rec = _record(10.0)
    a = Record(time=rec.time[:1000], data=rec.data[:1000], sensors=rec.sensors)
    b = Record(time=rec.time[1001:], data=rec.data[1001:], sensors=rec.sensors)
    with pytest.raises(InputError, match="one sample step"):
        list(cut_stream([a, b]))


@pytest.mark.parametrize(("kw", "match"), [
    ({"on": 3.0, "off": 3.0}, "off must be below on"),
    ({"pre": -1.0}, "pre must be >= 0 s"),
    ({"frame": 0.0}, "frame must be positive"),
    ({"baseline": 0.1}, "baseline must hold at least one frame"),
    ({"max_duration": 5.0}, "max_duration must exceed"),
    ({"channels": ["g0", "g0"]}, "channels must be distinct"),
])
def test_bad_settings(kw, match):
    with pytest.raises(InputError, match=match):
        TriggerSettings(**kw)


def test_unknown_channel_and_no_gauge():
    rec = _record(5.0)
    with pytest.raises(InputError, match="no channel 'x'"):
        cut_events(rec, TriggerSettings(channels=["x"]))
    with pytest.raises(InputError, match="no strain or deflection channel"):
        cut_events(rec.channels(["ad"]))
    warm = Record(time=rec.time, data=rec.data, sensors=[
        *rec.sensors[:3], Sensor(name="ad", kind="temperature")])
    with pytest.raises(InputError, match="'ad' is a temperature channel"):
        cut_events(warm, TriggerSettings(channels=["g0", "ad"]))


@pytest.mark.parametrize(("total", "flagged"), [(11.5, True), (13.5, False)])
def test_a_stream_that_ends_within_the_merge_gap_of_an_event(total, flagged):
    """A tractor's pulse (10 s, 1 s long) and a stream that ends 0.55 s after its trigger
    closes, less than the merge gap (the default join, max(merge_gap, pre + post) = 1 s):
    its trailer's pulse could have followed and been the same event, so the event is
    flagged ``open_at_end`` though its trigger closed; ending 2.55 s after, it is not."""
    rec = _record(total, [(10.0, 1.0, 100.0)])
    evs = cut_events(rec, TriggerSettings(baseline=5.0)).events
    assert len(evs) == 1
    assert ("open_at_end" in evs[0].flags) is flagged
    assert evs[0].off == pytest.approx(_crossings(10.0, 1.0, 100.0, 6.0, 3.0)[1], abs=0.01)


@pytest.mark.parametrize(("t0", "flagged"), [(0.4, True), (2.5, False)])
def test_a_stream_that_begins_within_the_merge_gap_of_an_event(t0, flagged):
    """A trailer's pulse whose trigger opens 0.4 s after the stream's first sample (less
    than the 1 s merge gap: its tractor's pulse could have come just before the stream
    began) is flagged ``open_at_start``; one opening 2.5 s in is not."""
    rec = _record(20.0, [(t0, 1.0, 100.0)])
    evs = cut_events(rec, TriggerSettings(baseline=5.0)).events
    assert len(evs) == 1
    assert ("open_at_start" in evs[0].flags) is flagged
