"""How the trigger cuts events out of a continuous recording.

Contract
--------
:class:`TriggerSettings` holds the trigger's parameters (:mod:`bwim.stream.trigger`); every
time is in seconds, every threshold in multiples of the robust noise σ of the summed
signal (dimensionless).  Validated at construction with one-line
:class:`~bwim.errors.InputError` messages:

* ``on > off > 0`` (hysteresis: a trigger opens at ``|s − b| >= on σ`` and closes at the
  first sample with ``|s − b| < off σ``);
* ``pre, post >= 0``; ``min_duration >= 0``; ``merge_gap >= 0``;
* ``frame > 0``; ``baseline >= frame`` (the baseline window holds at least one frame);
  ``max_duration > min_duration`` and ``max_duration >= baseline``;
* ``noise`` None (estimated) or a positive σ in the summed channels' units;
* ``channels`` None (every structural channel: strain and deflection) or a non-empty
  sequence of distinct channel names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from bwim.errors import InputError, require_finite, require_positive

__all__ = ["TriggerSettings"]


def _non_negative(name: str, value: float) -> float:
    v = require_finite(name, value)
    if v < 0:
        raise InputError(f"{name} must be >= 0 s, got {v:g}")
    return v


@dataclass(frozen=True, kw_only=True)
class TriggerSettings:
    """Parameters of the event trigger (see :mod:`bwim.stream.trigger`).

    Parameters
    ----------
    on : float
        Threshold that opens a trigger, in noise σ (default 6).
    off : float
        Threshold below which an open trigger closes, in noise σ (default 3; < ``on``).
    pre : float
        Time kept before a trigger's opening, s (default 0.5).
    post : float
        Time kept after a trigger's closing, s (default 0.5).
    min_duration : float
        Triggers open for less than this are dropped (spikes), s (default 0.1).
    merge_gap : float
        Triggers whose gap (closing of one to opening of the next) is shorter than
        ``max(merge_gap, pre + post)`` are one event, s (default 1.0): events never share
        a sample.
    max_duration : float
        A trigger open this long is closed (flag ``max_duration``) and the baseline taken
        afresh from its last ``baseline`` seconds; an event is not merged past it, s
        (default 60): bounds the memory of a stream.
    baseline : float
        Window of quiet frames whose median level is the baseline, s (default 10).
    frame : float
        Length of the frames the baseline and noise are estimated on, s (default 0.25).
    noise : float, optional
        The summed signal's noise σ in the channels' units; None (default): estimated
        (the median over the baseline window of each quiet frame's 1.4826 × MAD).
    channels : sequence of str, optional
        Channels summed; None (default): every strain and deflection channel.
    """

    on: float = 6.0
    off: float = 3.0
    pre: float = 0.5
    post: float = 0.5
    min_duration: float = 0.1
    merge_gap: float = 1.0
    max_duration: float = 60.0
    baseline: float = 10.0
    frame: float = 0.25
    noise: float | None = None
    channels: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        on = require_positive("TriggerSettings.on", self.on)
        off = require_positive("TriggerSettings.off", self.off)
        if off >= on:
            raise InputError(f"TriggerSettings.off must be below on (hysteresis), got off = "
                             f"{off:g} and on = {on:g}")
        object.__setattr__(self, "on", on)
        object.__setattr__(self, "off", off)
        for name in ("pre", "post", "min_duration", "merge_gap"):
            object.__setattr__(self, name,
                               _non_negative(f"TriggerSettings.{name}", getattr(self, name)))
        frame = require_positive("TriggerSettings.frame", self.frame)
        baseline = require_positive("TriggerSettings.baseline", self.baseline)
        if baseline < frame:
            raise InputError(f"TriggerSettings.baseline must hold at least one frame "
                             f"({frame:g} s), got {baseline:g} s")
        longest = require_positive("TriggerSettings.max_duration", self.max_duration)
        if longest <= self.min_duration or longest < baseline:
            raise InputError(f"TriggerSettings.max_duration must exceed min_duration and be "
                             f"at least baseline ({baseline:g} s), got {longest:g} s")
        object.__setattr__(self, "frame", frame)
        object.__setattr__(self, "baseline", baseline)
        object.__setattr__(self, "max_duration", longest)
        if self.noise is not None:
            object.__setattr__(self, "noise",
                               require_positive("TriggerSettings.noise", self.noise))
        if self.channels is not None:
            ch = self.channels
            if isinstance(ch, str) or not isinstance(ch, Sequence) or not ch or \
                    not all(isinstance(c, str) and c for c in ch) or len(set(ch)) != len(ch):
                raise InputError(f"TriggerSettings.channels must be distinct channel names, "
                                 f"got {ch!r}")
            object.__setattr__(self, "channels", tuple(ch))

    @property
    def join(self) -> float:
        """Gap below which two triggers are one event, s: ``max(merge_gap, pre + post)``."""
        return max(self.merge_gap, self.pre + self.post)
