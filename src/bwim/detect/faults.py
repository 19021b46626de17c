"""Which axle detector of a pair is faulty, from one record's readings of the pair.

Contract
--------
* Input: the pair's two channels ``y`` (n_t, 2, reading units, in the responses' order)
  and their :class:`~bwim.detect.response.LearnedResponses`.  Each channel is taken
  from its level at rest (the median of the record's first :data:`REST_SHARE`) and
  turned by its learned response's sign, so that an axle reads positive; its largest
  excursions up (``p``, the axles' peaks) and down (``q``: the span's bending, or a
  reversed detector's peaks) are compared between the detectors in the learned gain
  ratio (the second's over ``gain_ratio``).
* A detector **sees a vehicle** when its peak stands :data:`SEEN` levels
  (:attr:`~bwim.detect.response.DetectorResponse.level`) above rest and above its dip.
  When exactly one does, the other is named: **reversed** when its dip is the size of
  the first's peak (within :data:`GAIN_FACTOR`) and larger than its own peak; **reads
  nothing** (dead, disconnected or only noise) when neither excursion reaches
  :data:`NOTHING` of the first's peak.  When their peaks differ by more than
  :data:`GAIN_FACTOR` from the learned ratio (both see it, or the other reads it, not
  reversed, too weakly to be seen), both are named (one of them changed gain: one record
  cannot tell which).  Otherwise nothing is said ("").
* The result is one line for a detection's message.
* Compiled: the excursions (:func:`bwim.detect.order_stats.signed_extremes`, numpy's max
  and min of ``(y − rest) × sign``); the rest is numpy's arithmetic on float64 scalars.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .order_stats import signed_extremes
from .response import LearnedResponses
from .signals import column_medians

__all__ = ["GAIN_FACTOR", "NOTHING", "REST_SHARE", "SEEN", "DetectorFault", "detector_faults",
           "diagnose"]

#: Share of the record (from its start) whose median is a channel's level at rest.
REST_SHARE = 0.1
#: A vehicle's peak stands this many levels above rest on a detector that sees it.
SEEN = 10.0
#: A detector whose excursions stay below this share of the other's peak (in the gain
#: ratio) reads nothing of the vehicle.
NOTHING = 0.25
#: Two detectors' peaks (in the gain ratio) further apart than this factor disagree.
GAIN_FACTOR = 2.0


@dataclass(frozen=True)
class DetectorFault:
    """What one record's readings say of the pair (:func:`diagnose`): ``kind`` is
    ``"gain"``, ``"reversed"``, ``"nothing"`` or "" (nothing said), ``message`` the
    sentence naming the detector(s) ("" when nothing is said)."""

    kind: str = ""
    message: str = ""


def detector_faults(y: np.ndarray, learned: LearnedResponses) -> str:
    """What the readings say of a faulty detector of the pair (see the module contract):
    a sentence naming it by its channel, or "" when they do not say."""
    return diagnose(y, learned).message


def diagnose(y: np.ndarray, learned: LearnedResponses) -> DetectorFault:
    """:func:`detector_faults` with the fault's kind."""
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[1] != 2 or y.shape[0] < 2:
        return DetectorFault()
    rest = column_medians(y[:max(1, int(REST_SHARE * y.shape[0]))])  # numpy.median's
    names = learned.channels
    # z = (y - rest) * signs; up, down = z.max(axis=0), -z.min(axis=0)
    # (bwim.detect.order_stats.signed_extremes: the same numbers); then each detector's
    # numbers as numpy float64 scalars (numpy's arithmetic, a division by 0 included)
    ups, downs = signed_extremes(np.ascontiguousarray(y), rest,
                                 np.array([float(r.sign) for r in learned.responses]))
    up, down = (ups[0], ups[1]), (downs[0], downs[1])
    scale = (np.float64(1.0), np.float64(learned.gain_ratio))
    level = [np.float64(max(r.level, 1e-300)) for r in learned.responses]
    peak = (up[0] / scale[0], up[1] / scale[1])  # in the first detector's units
    sees = [bool(up[c] >= SEEN * level[c]) and bool(up[c] > down[c]) for c in (0, 1)]

    def gain(ratio: float) -> DetectorFault:
        return DetectorFault(kind="gain", message=(
            f"{names[1]} reads the vehicle {ratio:.2g} × {names[0]} in their learned gain "
            f"ratio: {names[0]} or {names[1]} has changed gain"))

    if all(sees):
        ratio = peak[1] / peak[0]
        if ratio > GAIN_FACTOR or ratio < 1.0 / GAIN_FACTOR:
            return gain(ratio)
        return DetectorFault()
    if not any(sees):
        return DetectorFault()
    d = sees.index(True)  # the detector that sees it
    o = 1 - d
    dip = down[o] / scale[o]
    if down[o] > up[o] and peak[d] / GAIN_FACTOR <= dip <= peak[d] * GAIN_FACTOR:
        return DetectorFault(kind="reversed", message=(
            f"{names[o]} reads the vehicle {names[d]} sees reversed (its peaks have the "
            "opposite sign of its learned response)"))
    if max(up[o], down[o]) / scale[o] < NOTHING * peak[d]:
        return DetectorFault(kind="nothing", message=(
            f"{names[o]} reads nothing of the vehicle {names[d]} sees (dead, disconnected "
            "or only noise)"))
    if up[o] > down[o] and up[o] / scale[o] < peak[d] / GAIN_FACTOR:
        # it reads the vehicle, too weakly to be seen, in the learned gain ratio
        return gain(float(peak[1] / peak[0]))
    return DetectorFault()
