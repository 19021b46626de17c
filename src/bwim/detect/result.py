"""What vehicle detection found in a record: one :class:`VehicleDetection` per vehicle.

Contract
--------
* A :class:`Detection` holds the vehicles found in one record (in order of arrival), the
  record-level ``flags`` and a one-line ``message`` that explains an empty or flagged
  result.  Detection never raises on a record it can read: a record without axles gives
  a Detection with no vehicles, flag ``"no_axles"`` and the reason in ``message``, so a
  batch of records survives one bad event.
* A :class:`VehicleDetection` carries the estimated :class:`~bwim.records.Passage`
  (speed m/s, axle spacings m, ``delay`` s = record time at which the first axle is at
  x = 0 of the influence-line frame, ``lane`` = ``lateral``), the time each axle passes
  x = 0 (s, shape (n_axles,)), a confidence in [0, 1] whose meaning is documented by the
  function that made it, and flags (strings, the ``FLAG_*`` constants below).
* ``lateral`` is in metres from the right-hand edge when ``lateral_unit == "m"``; with
  ``lateral_unit == "gauge index"`` it is a dimensionless load centroid in gauge-order
  units (1 = the first gauge, n = the last); NaN when no gauges were available.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from bwim.errors import InputError, require_instance
from bwim.records import Passage, Record

# The public names are listed once, in bwim.detect.__all__ (which re-exports them).

#: The two axle detectors saw different numbers of axles (a missed or spurious peak).
FLAG_COUNT_MISMATCH = "axle_count_mismatch"
#: The pair's readings say one of its detectors is faulty (changed gain, reversed, reads
#: nothing): the layout it gives cannot be trusted (bwim.detect.faults).
FLAG_DETECTOR_FAULT = "detector_fault"
#: Isolated spikes (one or two samples far off their neighbours) were taken out of a
#: detector's readings before the detection (bwim.detect.signals.despike).
FLAG_DETECTOR_SPIKE = "detector_spike"
#: Two vehicles were on the instrumented span at the same time.
FLAG_MULTIPLE_PRESENCE = "multiple_presence"
#: No axle was found (record level).
FLAG_NO_AXLES = "no_axles"
#: A "vehicle" of one axle: an isolated peak, or a vehicle split by a long gap.
FLAG_SINGLE_AXLE = "single_axle"
#: The per-axle speeds of one vehicle differ by more than the stated tolerance.
FLAG_SPEED_VARIES = "speed_varies"
#: The vehicle's fitted speed lies outside the detection's speed range.
FLAG_SPEED_RANGE = "speed_out_of_range"
#: Found from the strain gauges alone (no axle detectors): lower confidence.
FLAG_STRAIN_ONLY = "strain_only"
#: The vehicle's time on the span starts before or ends after the record.
FLAG_TRUNCATED = "truncated"
#: Strain activity outside the time on the span of every detected vehicle (record level):
#: e.g. a vehicle in a lane the axle detectors do not cover.
FLAG_UNEXPLAINED_STRAIN = "unexplained_strain"


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleDetection:
    """One vehicle found in a record.

    Attributes
    ----------
    passage : Passage
        Speed, lane (= ``lateral``), axle spacings and delay (record time at which the
        first axle is at x = 0 of the influence-line frame).
    confidence : float
        In [0, 1]; how it is made is documented by the detecting function.
    flags : tuple of str
        ``FLAG_*`` values that apply to this vehicle.
    axle_times : ndarray, shape (n_axles,)
        Record time at which each axle passes x = 0, s (``delay + offsets / speed``).
    axle_amplitudes : ndarray, shape (n_axles,)
        Relative size of each axle's signal (detector peak or deconvolved load), in the
        units of the detecting method; a rough load ratio, not a weight.
    lateral : float
        Load centroid across the deck (see ``lateral_unit``), NaN if unknown.
    lateral_unit : str
        ``"m"`` (from the right-hand edge) or ``"gauge index"`` (1 = first gauge).
    window : tuple of float or None
        Record times (s) at which the first axle enters and the last axle leaves the
        span, or None when no span was given.
    snr : float
        Smallest axle peak over the noise (detectors) or signal-to-residual ratio (strain).
    speed_spread : float
        Relative standard deviation of the per-axle speeds (detectors; 0 otherwise).
    spacing_disagreement : float
        RMS difference, m, between the axle spacings seen by each detector (NaN if fewer
        than two axles were seen by both).
    residual : float
        Strain path: relative residual of the fitted static response (NaN otherwise).
    detector_times : ndarray, shape (n_axles, 2)
        Peak time of each axle at each detector, s (NaN where a detector missed it);
        empty for the strain path.
    """

    passage: Passage
    confidence: float
    flags: tuple[str, ...] = ()
    axle_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    axle_amplitudes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    lateral: float = float("nan")
    lateral_unit: str = "m"
    window: tuple[float, float] | None = None
    snr: float = float("nan")
    speed_spread: float = 0.0
    spacing_disagreement: float = float("nan")
    residual: float = float("nan")
    detector_times: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def __post_init__(self) -> None:
        require_instance("passage", self.passage, Passage)
        c = float(self.confidence)
        if not 0.0 <= c <= 1.0:
            raise InputError(f"confidence must lie in [0, 1], got {c!r}")
        object.__setattr__(self, "confidence", c)
        object.__setattr__(self, "flags", tuple(self.flags))
        object.__setattr__(self, "axle_times", np.asarray(self.axle_times, dtype=float))
        object.__setattr__(self, "axle_amplitudes",
                           np.asarray(self.axle_amplitudes, dtype=float))
        if self.lateral_unit not in ("m", "gauge index"):
            raise InputError(f"lateral_unit must be 'm' or 'gauge index', got "
                             f"{self.lateral_unit!r}")

    @property
    def n_axles(self) -> int:
        return self.passage.n_axles

    @property
    def speed(self) -> float:
        """m/s."""
        return self.passage.speed

    @property
    def axle_spacings(self) -> np.ndarray:
        """m, shape (n_axles − 1,)."""
        return self.passage.axle_spacings


@dataclass(frozen=True, kw_only=True, eq=False)
class Detection:
    """The vehicles found in one record.

    Attributes
    ----------
    vehicles : tuple of VehicleDetection
        In order of arrival (empty when none was found: see ``message``).
    flags : tuple of str
        Record-level flags: every vehicle's flags plus ``"no_axles"`` and
        ``"unexplained_strain"`` (sorted, each once).
    message : str
        One line: why nothing was found, or what the flags mean here; "" if all is well.
    method : str
        ``"axle detectors"`` or ``"strain"``.
    fault : str
        One line naming a faulty axle detector of the pair when its readings show one
        (:func:`bwim.detect.faults.detector_faults`; its vehicles then carry
        ``"detector_fault"``), else "".
    """

    vehicles: tuple[VehicleDetection, ...] = ()
    flags: tuple[str, ...] = ()
    message: str = ""
    method: str = ""
    fault: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "vehicles", tuple(self.vehicles))
        object.__setattr__(self, "flags", tuple(self.flags))

    @property
    def n_vehicles(self) -> int:
        return len(self.vehicles)

    @property
    def passages(self) -> tuple[Passage, ...]:
        """The vehicles' passages, in order of arrival."""
        return tuple(v.passage for v in self.vehicles)

    @property
    def single(self) -> VehicleDetection:
        """The one vehicle of a single-vehicle record; InputError (naming the flags and
        the message) if there is not exactly one."""
        if len(self.vehicles) != 1:
            why = f" ({self.message})" if self.message else ""
            flags = f"; flags: {', '.join(self.flags)}" if self.flags else ""
            raise InputError(f"detection found {len(self.vehicles)} vehicles, not one"
                             f"{why}{flags}")
        return self.vehicles[0]

    def annotate(self, record: Record) -> Record:
        """A copy of ``record`` whose passages are the detected ones."""
        require_instance("record", record, Record)
        return dataclasses.replace(record, passages=self.passages)
