"""Continuous recordings: events cut out of long logger files by a trigger, in bounded
memory.

Contract
--------
* :mod:`bwim.stream.settings`: :class:`TriggerSettings` (thresholds in noise σ, times in s).
* :mod:`bwim.stream.trigger`: :func:`cut_events` (a whole :class:`~bwim.Record`) and
  :func:`cut_stream` (consecutive records, events yielded as they complete); the same
  windows however the stream is split.
* :mod:`bwim.stream.events`: the results, :class:`StreamEvent` (a window and its record,
  on the stream's clock) and :class:`EventCut`.
* :mod:`bwim.stream.chunks`: :func:`read_chunks` reads a long logger file block by block
  (:func:`bwim.io.read_logger` on each block) and :func:`cut_file` cuts it.

Documented in docs/streams.md.
"""

from bwim.stream.chunks import ROWS, cut_file, read_chunks
from bwim.stream.events import FLAGS, EventCut, StreamEvent
from bwim.stream.settings import TriggerSettings
from bwim.stream.trigger import cut_events, cut_stream

__all__ = ["FLAGS", "ROWS", "EventCut", "StreamEvent", "TriggerSettings", "cut_events",
           "cut_file", "cut_stream", "read_chunks"]
