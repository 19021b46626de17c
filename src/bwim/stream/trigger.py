"""The trigger: events cut out of a continuous recording, record by record or streamed.

Contract
--------
* The trigger watches the **summed signal** ``s(t) = Σ_j x_j(t)`` of the structural
  channels (strain and deflection, in the record's units; or ``settings.channels``) against
  a **baseline** ``b`` and a **noise** ``σ``.  Both are robust statistics of *frames* of
  ``settings.frame`` seconds, counted from the stream's first sample: ``b`` is the median
  of the last ``settings.baseline`` seconds of quiet frames' medians, ``σ`` the median of
  their ``1.4826 × MAD`` (or ``settings.noise``).  A frame is quiet when no trigger was
  open at any of its samples.  The first ``baseline`` seconds of the stream (every frame,
  quiet or not: medians of medians) start them.  A frame's samples are judged with the
  ``b`` and ``σ`` of the frames before it.
* **Hysteresis**: a trigger opens at the first sample with ``|s − b| >= on σ`` and closes
  at the first later sample with ``|s − b| < off σ`` (``off < on``; both signs count).  A
  trigger open for less than ``min_duration`` is dropped (a spike); triggers whose gap is
  shorter than ``max(merge_gap, pre + post)`` are one event; an event keeps ``pre``
  seconds before its opening and ``post`` after its closing, within the stream (events
  never share a sample).  A trigger still open after ``max_duration`` is closed at the
  end of that frame (flag ``max_duration``) and the baseline and noise are then taken
  from the last ``baseline`` seconds of frames, quiet or not (a step of the baseline does
  not hold the trigger open for ever); an event is not merged past ``max_duration``.
* :func:`cut_stream` takes the stream as consecutive :class:`~bwim.Record` pieces (the
  same sensors and clock, each starting one sample step after the previous ended:
  :func:`bwim.stream.chunks.read_chunks`) and yields each :class:`~bwim.stream.events.
  StreamEvent` as soon as no later sample can change it; it holds only the samples an
  open or pending event or the next ``pre`` seconds may need (bounded by about
  ``2 max_duration + baseline`` of data whatever the stream's length).  The events do
  not depend on how the stream is split: :func:`cut_events` on the whole record gives
  the same windows.
* An event that the stream's start or end may have cut is flagged: ``open_at_start``
  when its trigger opens less than the merge gap after the stream's first sample (at it:
  the stream began inside a crossing), ``open_at_end`` when the stream ends with the
  trigger open or less than the merge gap after it closed (a later trigger, a trailer's
  axles after its tractor's, would have been the same event).
* Limits: the stream should begin at rest (a stream that begins inside a crossing has a
  wrong start-up baseline for its first frames); channels of opposite signs cancel in the
  sum (name the channels to sum); a quantised noise-free signal has ``σ = 0``: give
  ``settings.noise``.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError
from bwim.records import Record
from bwim.sensors import SensorKind
from bwim.stream.events import EventCut, StreamEvent
from bwim.stream.settings import TriggerSettings

__all__ = ["cut_events", "cut_stream"]

_MAD = 1.4826  #: σ of a normal distribution per median absolute deviation
_DAY = 86400.0  #: s in a day


@dataclass
class _Run:
    """A trigger, open (``off`` None) or closed; sample indices in the stream."""

    on: int
    baseline: float
    noise: float
    peak: float = 0.0
    off: int | None = None
    flags: tuple[str, ...] = ()


def _frame_stats(x: np.ndarray) -> tuple[float, float]:
    med = float(np.median(x))
    spread = _MAD * float(np.median(np.abs(x - med)))
    if spread == 0.0:
        spread = float(np.std(x))
    return med, spread


class _Trigger:
    """The trigger's state over one stream (see the module docstring)."""

    def __init__(self, settings: TriggerSettings | None) -> None:
        if settings is None:
            settings = TriggerSettings()
        elif not isinstance(settings, TriggerSettings):
            raise InputError(f"settings must be a bwim.stream.TriggerSettings, got "
                             f"{type(settings).__name__}")
        self.settings = settings
        self.template: Record | None = None
        self.n = 0                      # samples received
        self.pos = 0                    # next sample to judge
        self.buf0 = 0                   # stream index of the buffer's first sample
        self.history: deque = deque()
        self.recent: deque = deque()
        self.ready = False
        self.active: _Run | None = None
        self.pending: _Run | None = None
        self.last_stop = 0
        self.count = 0
        self.out: list[StreamEvent] = []

    # --- the stream's pieces ------------------------------------------------------------
    def _start(self, record: Record) -> None:
        s = self.settings
        names = [x.name for x in record.sensors]
        if s.channels is None:
            idx = [j for j, x in enumerate(record.sensors) if x.kind.is_structural]
            if not idx:
                raise InputError(f"the record has no strain or deflection channel to trigger "
                                 f"on (channels {names}); name the channels to sum")
        else:
            missing = [c for c in s.channels if c not in names]
            if missing:
                raise InputError(f"TriggerSettings.channels: no channel {missing[0]!r} in the "
                                 f"record; channels: {names}")
            idx = [names.index(c) for c in s.channels]
            gappy = [c for c, j in zip(s.channels, idx, strict=True)
                     if record.sensors[j].kind is SensorKind.TEMPERATURE]
            if gappy:
                raise InputError(f"TriggerSettings.channels: {gappy[0]!r} is a temperature "
                                 "channel (it may have gaps); sum readings of the bridge")
        self.idx = np.array(idx)
        self.template = record
        self.fs = record.sampling_rate
        self.step = 1.0 / self.fs
        # the largest difference of a step from the step within the records
        self.jitter = _jitter(record.time, self.step)
        fs = self.fs
        self.frame = max(2, round(s.frame * fs))
        self.n_frames = max(1, round(s.baseline / s.frame))
        self.history = deque(maxlen=self.n_frames)
        self.recent = deque(maxlen=self.n_frames)
        self.pre, self.post = round(s.pre * fs), round(s.post * fs)
        self.join = round(s.join * fs)
        self.shortest = round(s.min_duration * fs)
        self.longest = max(1, round(s.max_duration * fs))
        self.time = np.empty(0)
        self.data = np.empty((0, len(record.sensors)))
        self.signal = np.empty(0)

    def _check_next(self, record: Record) -> None:
        t = self.template
        if [x.name for x in record.sensors] != [x.name for x in t.sensors]:
            raise InputError("the stream's records must have the same channels: got "
                             f"{[x.name for x in record.sensors]} after "
                             f"{[x.name for x in t.sensors]}")
        if record.clock != t.clock:
            raise InputError(f"the stream's records must share one clock: got {record.clock} "
                             f"after {t.clock}")
        expected = self.last_time + self.step
        # a time column written rounded steps unevenly within each record: the step
        # between two records may be off by as much (and 1 % of a step otherwise)
        self.jitter = max(self.jitter, _jitter(record.time, self.step))
        allowed = max(0.01 * self.step, self.jitter) + 1e-9 * abs(expected)
        if abs(float(record.time[0]) - expected) > allowed:
            raise InputError(f"the stream's records must follow each other one sample step "
                             f"({self.step:g} s) apart: a record starts at "
                             f"{float(record.time[0]):.9g} s after one that ended at "
                             f"{self.last_time:.9g} s")

    def feed(self, record: Record) -> list[StreamEvent]:
        if not isinstance(record, Record):
            raise InputError(f"the stream must be bwim Records, got {type(record).__name__}")
        if self.template is None:
            self._start(record)
        else:
            self._check_next(record)
        self.last_time = float(record.time[-1])
        signal = record.data[:, self.idx].sum(axis=1)
        if self.time.size:
            self.time = np.concatenate([self.time, record.time])
            self.data = np.concatenate([self.data, record.data])
            self.signal = np.concatenate([self.signal, signal])
        else:                       # nothing held: the record's own arrays (never written)
            self.time, self.data, self.signal = record.time, record.data, signal
        self.n += record.time.size
        if not self.ready:
            if self.n < self.n_frames * self.frame:
                return []
            self._init()
        while self.pos + self.frame <= self.n:
            self._judge(self.pos, self.pos + self.frame)
        self._release()
        self._trim()
        return self._take()

    def close(self) -> list[StreamEvent]:
        if self.template is None:
            return []
        if not self.ready:
            self._init()
        while self.pos + self.frame <= self.n:
            self._judge(self.pos, self.pos + self.frame)
        if self.pos < self.n:
            self._judge(self.pos, self.n)
        if self.active is not None:
            self._end(self.n, ("open_at_end",))
        if self.pending is not None:
            p = self.pending
            if p.off + self.join > self.n and "open_at_end" not in p.flags:
                # the stream ended less than the merge gap after the trigger closed: a later
                # trigger (a trailer's axles after its tractor's) would have been this event
                p.flags = (*p.flags, "open_at_end")
            self._emit(p)
            self.pending = None
        return self._take()

    def _take(self) -> list[StreamEvent]:
        out, self.out = self.out, []
        return out

    # --- baseline and noise ---------------------------------------------------------------
    def _init(self) -> None:
        end = min(self.n, self.n_frames * self.frame)
        x = self.signal[:end]
        frames = [x[k:k + self.frame] for k in range(0, end - self.frame + 1, self.frame)]
        if not frames:
            frames = [x]
        self.history.extend(_frame_stats(f) for f in frames)
        self._update()
        self.ready = True

    def _update(self) -> None:
        stats = np.array(self.history)
        self.b = float(np.median(stats[:, 0]))
        if self.settings.noise is not None:
            self.sigma = self.settings.noise
        else:
            self.sigma = max(float(np.median(stats[:, 1])), 1e-12 * max(1.0, abs(self.b)))

    # --- judging a frame ------------------------------------------------------------------
    def _judge(self, a: int, e: int) -> None:
        s = self.settings
        x = self.signal[a - self.buf0:e - self.buf0]
        z = np.abs(x - self.b) / self.sigma
        quiet = self.active is None
        k, length = 0, e - a
        while k < length:
            if self.active is None:
                hits = np.flatnonzero(z[k:] >= s.on)
                if not hits.size:
                    break
                k += int(hits[0])
                # the stream began inside it, or less than the merge gap before it (a
                # trigger before the stream's start would have been the same event)
                self.active = _Run(on=a + k, baseline=self.b, noise=self.sigma,
                                   flags=("open_at_start",) if a + k < max(self.join, 1)
                                   else ())
                quiet = False
            else:
                below = np.flatnonzero(z[k:] < s.off)
                stop = length if not below.size else k + int(below[0])
                if stop > k:
                    self.active.peak = max(self.active.peak, float(z[k:stop].max()))
                if not below.size:
                    break
                self._end(a + stop)
                k = stop
        stats = _frame_stats(x)
        self.recent.append(stats)
        if quiet:
            self.history.append(stats)
            self._update()
        if self.active is not None and e - self.active.on >= self.longest:
            self._end(e, ("max_duration",))
            self.history = deque(self.recent, maxlen=self.n_frames)
            self._update()
        self.pos = e

    def _end(self, off: int, flags: tuple[str, ...] = ()) -> None:
        run, self.active = self.active, None
        run.off = off
        run.flags = (*run.flags, *flags)
        if off - run.on < self.shortest and "max_duration" not in flags:
            return                                  # a spike
        p = self.pending
        if p is not None and run.on - p.off < self.join and p.off - p.on < self.longest:
            p.off = run.off
            p.peak = max(p.peak, run.peak)
            p.flags = tuple(dict.fromkeys((*p.flags, *run.flags)))
            return
        if p is not None:
            self._emit(p, limit=run.on - self.pre)
        self.pending = run

    def _release(self) -> None:
        p = self.pending
        if p is None or self.pos < p.off + self.join:
            return
        if self.active is not None and self.active.on < p.off + self.join:
            return
        self._emit(p)
        self.pending = None

    def _trim(self) -> None:
        keep = self.pos - self.pre
        for run in (self.pending, self.active):
            if run is not None:
                keep = min(keep, run.on - self.pre)
        cut = max(0, keep - self.buf0)
        if cut:
            self.time = self.time[cut:]
            self.data = self.data[cut:]
            self.signal = self.signal[cut:]
            self.buf0 += cut

    # --- an event -------------------------------------------------------------------------
    def _t(self, i: int) -> float:
        j = i - self.buf0
        if j < self.time.size:
            return float(self.time[j])
        return float(self.time[-1]) + (j - self.time.size + 1) * self.step

    def _emit(self, run: _Run, limit: int | None = None) -> None:
        a = max(run.on - self.pre, self.last_stop, 0)
        e = min(run.off + self.post, self.n)
        if limit is not None:                       # the next event's window starts there
            e = max(min(e, limit), run.off)
        time = self.time[a - self.buf0:e - self.buf0].copy()
        data = self.data[a - self.buf0:e - self.buf0].copy()
        t = self.template
        clock = None if t.clock is None else t.clock_at(float(time[0]))
        if clock is not None or not t.time_of_day:  # from 0, as an event file (without a
            time = time - time[0]                   # clock: a record time, not a clock)
        elif time[0] >= _DAY:  # a clock time of day counted on past midnight: the clock
            time = time - _DAY * math.floor(time[0] / _DAY)  # time of that day, as its
            # logger's event file would hold it
        record = dataclasses.replace(t, time=time, data=data, passages=(), truths=(),
                                     clock=clock)
        self.out.append(StreamEvent(
            index=self.count, start_index=a, stop_index=e, start=self._t(a),
            stop=self._t(e - 1), on=self._t(run.on), off=self._t(run.off), peak=run.peak,
            baseline=run.baseline, noise=run.noise, flags=run.flags, record=record))
        self.count += 1
        self.last_stop = e


def _jitter(time: np.ndarray, step: float) -> float:
    """The largest difference of a record's steps from ``step``, s."""
    return float(np.max(np.abs(np.diff(time) - step))) if time.size > 1 else 0.0


def cut_stream(records: Iterable[Record], settings: TriggerSettings | None = None
               ) -> Iterator[StreamEvent]:
    """The events of a stream given as consecutive records, each yielded as soon as it is
    complete (see the module docstring).

    Raises
    ------
    InputError
        Bad settings; a record of other channels or clock than the first, or that does
        not start one sample step after the previous one ended; no channel to sum.
    """
    trigger = _Trigger(settings)
    for record in records:
        yield from trigger.feed(record)
    yield from trigger.close()


def cut_events(record: Record, settings: TriggerSettings | None = None) -> EventCut:
    """The events of one whole record (see the module docstring)."""
    if not isinstance(record, Record):
        raise InputError(f"record must be a bwim Record, got {type(record).__name__}")
    trigger = _Trigger(settings)
    events = [*trigger.feed(record), *trigger.close()]
    return EventCut(events=tuple(events), settings=trigger.settings,
                    n_samples=int(record.time.size), sampling_rate=record.sampling_rate)
