"""The part of an event's record a vehicle has to itself.

Contract
--------
* :func:`own_part` cuts a record around one vehicle's time on the span (its ``window``:
  record times, s, at which its first axle enters and its last axle leaves) so that the
  vehicles that cross before or after it (``others``: their windows), and never share
  the span with it, are left out: the part starts halfway through the quiet time between
  the last other window that ends before ``window`` starts and ``window``, and ends
  halfway through the quiet time before the next other window that starts after
  ``window`` ends.  The record's start or end bounds it where there is no such window.
  Windows that overlap ``window`` (a vehicle on the span with it) do not cut: what to
  do with a vehicle sharing the span is the caller's decision.
* Why: a logger file may hold a vehicle that follows the weighed one in its lane, or one
  that crossed the other way before it.  A weighing fits the whole record it is given
  (the channels' offsets from every sample, the residual over every sample), so another
  vehicle's strain outside this one's window would be read as misfit; cut off, it is
  not.  The quiet half-gaps on each side keep samples off the span for the offsets.
* The part keeps the record's time values (so its clock, sensors and every time the
  detection gave stay valid) and drops the passages and truths of a simulated record.
  A window of None or a record with nothing to cut gives the record itself.
* Units: s.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

from bwim.records import Record

__all__ = ["own_part"]


def own_part(record: Record, window: tuple[float, float] | None,
             others: Iterable[tuple[float, float] | None]) -> Record:
    """``record`` cut to the part ``window``'s vehicle has to itself (module docstring)."""
    if window is None:
        return record
    start, end = float(window[0]), float(window[1])
    t = record.time
    lo, hi = float(t[0]), float(t[-1])
    for w in others:
        if w is None:
            continue
        a, b = float(w[0]), float(w[1])
        if b <= start:  # crossed before it: cut in the quiet time between
            lo = max(lo, 0.5 * (b + start))
        elif a >= end:  # crossed after it
            hi = min(hi, 0.5 * (end + a))
    if lo <= t[0] and hi >= t[-1]:
        return record
    keep = (t >= lo) & (t <= hi)
    return dataclasses.replace(record, time=t[keep], data=record.data[keep], passages=(),
                               truths=())
