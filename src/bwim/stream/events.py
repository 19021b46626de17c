"""The events a trigger cut out of a continuous recording.

Contract
--------
* :class:`StreamEvent` is one event: its window ``[start_index, stop_index)`` in the
  stream's samples (counted from the stream's first sample), the record times of its first
  and last samples (``start``, ``stop``, s, on the stream's time axis), of the trigger's
  opening and closing (``on``, ``off``: the first sample at or above the on-threshold and
  the first sample back below the off-threshold, s), its ``peak`` (the largest
  ``|s − b| / σ``), the ``baseline`` ``b`` and noise ``σ`` in effect when it opened (the
  summed channels' units), ``flags`` and its ``record``.
* ``record`` is the window's :class:`~bwim.Record`, every channel, no passages or truths.
  With a clock, its time starts at 0 at its first sample and its ``clock`` is the clock of
  that sample (as a logger that writes one file per event: the clock time of every sample
  is the stream's); without one, its time is the stream's own when that is the clock time
  of day (:attr:`bwim.Record.time_of_day` of the stream's first piece; an event that
  starts after midnight, where the stream counts on past 86400 s, has that day's clock
  time of day, as its logger's event file would: the stream's less 86400 s per day
  passed), else it starts at 0 too (a record time says nothing of the day; ``start``
  places it in the stream).
* Flags: ``open_at_start`` (the stream began inside the event, or less than the merge
  gap before its trigger opened), ``open_at_end`` (the stream ended before the trigger
  closed, or less than the merge gap after), ``max_duration`` (a trigger was closed at
  :attr:`~bwim.stream.settings.TriggerSettings.max_duration` with the signal still up).
  An event with any of them may hold part of a vehicle only: ``bwim weigh --continuous``
  refuses its rows.
* :class:`EventCut` is a whole record's cut: its events in time order, the settings, the
  number of samples and the sampling rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from bwim.records import Record
from bwim.stream.settings import TriggerSettings

__all__ = ["FLAGS", "EventCut", "StreamEvent"]

#: Every flag an event may carry.
FLAGS = ("open_at_start", "open_at_end", "max_duration")


@dataclass(frozen=True, kw_only=True, eq=False)
class StreamEvent:
    """One event of a stream (see the module docstring)."""

    index: int
    start_index: int
    stop_index: int
    start: float
    stop: float
    on: float
    off: float
    peak: float
    baseline: float
    noise: float
    flags: tuple[str, ...]
    record: Record

    @property
    def n_samples(self) -> int:
        return self.stop_index - self.start_index

    @property
    def duration(self) -> float:
        """Time from the trigger's opening to its closing, s."""
        return self.off - self.on

    @property
    def clock(self) -> datetime | None:
        """Wall-clock time of the event's first sample (None without a clock)."""
        return self.record.clock_at()

    def __repr__(self) -> str:
        return (f"StreamEvent(index={self.index}, start={self.start:.3f} s, "
                f"stop={self.stop:.3f} s, peak={self.peak:.1f} σ, flags={self.flags})")


@dataclass(frozen=True, kw_only=True, eq=False)
class EventCut:
    """The events of one record, in time order."""

    events: tuple[StreamEvent, ...]
    settings: TriggerSettings
    n_samples: int
    sampling_rate: float

    @property
    def duration(self) -> float:
        """Length of the cut record, s."""
        return self.n_samples / self.sampling_rate

    def __len__(self) -> int:
        return len(self.events)

    def __repr__(self) -> str:
        return (f"EventCut({len(self.events)} events in {self.duration:.1f} s at "
                f"{self.sampling_rate:g} Hz)")
