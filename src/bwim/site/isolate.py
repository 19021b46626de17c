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
* :func:`detected_alone` applies it to detection: an event whose detector pair found
  vehicles that cross one after the other (never on the span together) has each of
  them detected again on its own part of the record (``detect``, the event's own
  detection called on the part), and the vehicle that detection finds in the same pair
  over the same window replaces it.  Why: a detection judges an axle against the
  record's strongest (the matching pursuit stops when the next axle lowers the misfit
  by less than a share of the strongest axle's fall), so a light truck's steering axle
  is lost beside a heavy truck in the same file that it never shares the span with.
  On its own part it is judged as in its own file.  A vehicle the part's detection does
  not find once, in the same pair over an overlapping window, is kept as first found.
  Multiple presence stays the event's: a replacement's ``others`` are the event's
  vehicles its window overlaps, not the part's (the part may cut a vehicle of the other
  direction off, or hold a trace the event's detection left out).
* Units: s.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable

from bwim.detect.presence import windows_overlap
from bwim.detect.result import FLAG_MULTIPLE_PRESENCE
from bwim.records import Record
from bwim.site.lanes import EventDetection, LaneVehicle

__all__ = ["detected_alone", "own_part"]


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
    return record.samples((t >= lo) & (t <= hi))


def _apart(a: tuple[float, float] | None, b: tuple[float, float] | None) -> bool:
    """Whether two windows are both known and do not overlap."""
    return a is not None and b is not None and not windows_overlap(a, b)


def detected_alone(record: Record, event: EventDetection,
                   detect: Callable[[Record], EventDetection]) -> EventDetection:
    """``event`` with each vehicle that its detector pair found beside another it never
    shares the span with detected again on its own part of ``record`` (module
    docstring)."""
    vehicles = list(event.vehicles)
    replaced: dict[int, LaneVehicle] = {}
    notes = [event.message] if event.message else []
    for k, lv in enumerate(event.vehicles):
        if not any(j != k and w.pair == lv.pair and _apart(w.window, lv.window)
                   for j, w in enumerate(event.vehicles)):
            continue
        part = own_part(record, lv.window,
                        [w.window for j, w in enumerate(event.vehicles) if j != k])
        if part is record:
            continue
        again = [w for w in detect(part).vehicles
                 if w.pair == lv.pair and windows_overlap(w.window, lv.window)]
        if len(again) == 1:
            vehicles[k] = again[0]
            replaced[k] = lv
            if again[0].vehicle.n_axles != lv.vehicle.n_axles:
                notes.append(f"lane {lv.pair}: a {lv.vehicle.n_axles}-axle vehicle detected "
                             f"again on its own part of the record: {again[0].vehicle.n_axles}"
                             " axles")
    if replaced:
        vehicles = _presence_again(vehicles, replaced)
    return dataclasses.replace(event, vehicles=tuple(vehicles), message="; ".join(notes))


def _lane(v: LaneVehicle) -> int:
    return v.lane if v.lane is not None else v.pair


def _presence_again(vehicles: list[LaneVehicle], replaced: dict[int, LaneVehicle]
                    ) -> list[LaneVehicle]:
    """The event's multiple presence after the replacements (``replaced``: index → the
    vehicle as first found), from the event's vehicles, not the parts': a replacement's
    ``others`` are the event's vehicles its window overlaps (the part may have cut one
    off, or seen one the event's detection left out), flagged ``multiple_presence`` for
    them or for what flagged it without another vehicle (gauge activity no detector saw,
    in the part or the whole record); every other vehicle keeps its own and gains a
    replacement that now overlaps it."""
    def overlapping(k: int) -> tuple[int, ...]:
        return tuple(_lane(w) for j, w in enumerate(vehicles)
                     if j != k and windows_overlap(vehicles[k].window, w.window))

    def flagged(veh, on: bool):
        has = FLAG_MULTIPLE_PRESENCE in veh.flags
        if on and not has:
            return dataclasses.replace(veh, flags=(*veh.flags, FLAG_MULTIPLE_PRESENCE))
        if has and not on:
            return dataclasses.replace(veh, flags=tuple(f for f in veh.flags
                                                        if f != FLAG_MULTIPLE_PRESENCE))
        return veh

    out = []
    for k, v in enumerate(vehicles):
        others = overlapping(k)
        if k in replaced:
            first = replaced[k]
            unseen = any(FLAG_MULTIPLE_PRESENCE in w.vehicle.flags and not w.others
                         for w in (v, first))
            out.append(dataclasses.replace(v, others=others, vehicle=flagged(
                v.vehicle, bool(others) or unseen)))
        else:
            more = tuple(dict.fromkeys([*v.others, *others]))
            out.append(v if more == v.others else dataclasses.replace(
                v, others=more, vehicle=flagged(v.vehicle, True)))
    return sorted(out, key=lambda w: (w.window or (float("inf"),))[0])
