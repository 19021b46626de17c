"""Deck temperature over a day, and the strain-to-load factor it drives.

Contract
--------
* :class:`DeckTemperature` is one day's deck temperature (°C) against clock time (s
  since midnight): the usual two-half-cosine diurnal curve — from its minimum
  ``t_min`` it rises as a half cosine to its maximum ``t_max`` (``t_min + amplitude``),
  then falls as a half cosine over the remaining ``24 h − (t_max − t_min)`` to the next
  day's minimum (smooth, slope zero at both extremes).  Times outside one day wrap.
* :class:`ThermalDrift` is the bridge's strain-to-load factor (what multiplies every
  simulated strain):

  ``f(t) = 1 + coefficient × (T(t) − t_ref) + nonthermal × sin(2π t / period + phase)``

  — linear in the deck temperature (the surfacing's stiffness and the bearings' restraint
  change with it), plus a small non-thermal component (one slow sinusoid per day).  The
  coefficient and reference temperature belong to the bridge (the same on every day); the
  temperature curve and the non-thermal term belong to each day.
* :func:`draw_days` draws a calibration day and a traffic day that differ: the traffic
  day is cooler or warmer, its curve a little shifted in time and scaled in amplitude
  against the calibration day's.  The ranges (see its docstring) make the factor rise
  steadily through a working day, with a half-range over 09:00–16:00 of roughly 12–18 %
  (issue 20: a real site's calibration runs rose from 0.86 at 09:28 to 1.13 at 15:52,
  steadily; the traffic day two days later ran a few per cent below that at the same
  clock time: −15 % at 09:45 and +9 % at 15:34 against the runs' mean).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError

__all__ = ["DAY_SECONDS", "DeckTemperature", "ThermalDrift", "draw_days"]

DAY_SECONDS = 86400.0
HOUR = 3600.0


@dataclass(frozen=True, kw_only=True)
class DeckTemperature:
    """One day's deck temperature (see the module docstring); times in s since midnight."""

    t_min: float
    t_max: float
    minimum: float  #: °C at t_min
    amplitude: float  #: °C, maximum − minimum

    def __post_init__(self) -> None:
        if not 0 <= self.t_min < self.t_max < self.t_min + DAY_SECONDS:
            raise InputError("DeckTemperature needs 0 <= t_min < t_max < t_min + 24 h")
        if not self.amplitude >= 0:
            raise InputError("DeckTemperature.amplitude must be >= 0")

    def at(self, clock) -> np.ndarray:
        """Temperature, °C, at clock times (s since midnight)."""
        t = np.mod(np.asarray(clock, dtype=float) - self.t_min, DAY_SECONDS)
        rise = self.t_max - self.t_min
        up = 0.5 * (1.0 - np.cos(np.pi * t / rise))
        down = 0.5 * (1.0 + np.cos(np.pi * (t - rise) / (DAY_SECONDS - rise)))
        return self.minimum + self.amplitude * np.where(t <= rise, up, down)


@dataclass(frozen=True, kw_only=True)
class ThermalDrift:
    """The strain-to-load factor of one day (see the module docstring)."""

    temperature: DeckTemperature
    coefficient: float  #: 1/°C
    t_ref: float  #: °C
    nonthermal: float  #: amplitude of the non-thermal term (fraction)
    period: float  #: s
    phase: float  #: rad

    def factor(self, clock) -> np.ndarray:
        """Strain factor at clock times (s since midnight)."""
        t = np.asarray(clock, dtype=float)
        return (1.0 + self.coefficient * (self.temperature.at(t) - self.t_ref)
                + self.nonthermal * np.sin(2 * np.pi * t / self.period + self.phase))


def draw_days(rng: np.random.Generator) -> tuple[ThermalDrift, ThermalDrift]:
    """The calibration day's and the traffic day's drift.

    Bridge: coefficient uniform in 0.023–0.027 /°C, reference temperature 20 °C.
    Calibration day: minimum at 04:30–06:00, maximum at 19:00–20:30 (a slab under its
    surfacing warms through the working day and peaks in the evening), minimum
    temperature 9–13 °C, daily swing 16–19 °C: the factor rises about 0.27 from 09:30 to
    16:00, steadily (its rate in the last hour 0.7 of the first's or more on 95 % of
    the draws, 0.58 at the least).
    Traffic day: the same bridge on a day 0.8–1.6 °C cooler or warmer, its curve shifted
    by up to 0.4 h either way and its swing within 1 °C of the calibration day's: at the
    same clock time its factor differs from the calibration day's by a few per cent,
    steadily, as on the real site (issue 20).  Each day: non-thermal amplitude 0.3–0.6 %,
    period 3–8 h, random phase.
    """
    coefficient = float(rng.uniform(0.023, 0.027))
    t_min = float(rng.uniform(4.5, 6.0)) * HOUR
    t_max = float(rng.uniform(19.0, 20.5)) * HOUR
    cal = DeckTemperature(t_min=t_min, t_max=t_max, minimum=float(rng.uniform(9.0, 13.0)),
                          amplitude=float(rng.uniform(16.0, 19.0)))
    sign = float(rng.choice([-1.0, 1.0]))  # cooler (-1) or warmer (+1)
    shift = float(rng.uniform(-0.4, 0.4)) * HOUR
    traffic = DeckTemperature(
        t_min=t_min + shift, t_max=t_max + shift,
        minimum=cal.minimum + sign * float(rng.uniform(0.8, 1.6)),
        amplitude=cal.amplitude + float(rng.uniform(-1.0, 1.0)))
    days = []
    for temp in (cal, traffic):
        days.append(ThermalDrift(temperature=temp, coefficient=coefficient, t_ref=20.0,
                                 nonthermal=float(rng.uniform(0.003, 0.006)),
                                 period=float(rng.uniform(3.0, 8.0)) * HOUR,
                                 phase=float(rng.uniform(0.0, 2 * np.pi))))
    return days[0], days[1]
