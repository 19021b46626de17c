"""Strain records of vehicle crossings: what a logger recorded, and what was true.

Contract
--------
* :class:`Passage` is what a B-WIM system knows (or measures with axle detectors) about a
  vehicle crossing: speed, lane, axle spacings, track width and the time ``delay`` at which
  its first axle reached x = 0 (record time).  Wheel ``k`` of axle ``i`` is at
  ``x = speed (t − delay) − axle_offsets[i]`` and ``y = lane ∓ track_width / 2`` (right
  wheel first); with ``track_width=None`` each axle is one force on the lane centre line.
* :class:`Truth` holds a simulated vehicle's true wheel and axle forces (N, downward) on the
  record's time axis, its static loads, and whether a wheel lost contact.
* :class:`Record` is a time series of sensor readings (strain dimensionless, deflection m)
  with its sensors, passages and, for simulated records, truths.  Time 0 is the instant
  the first axle of the first vehicle reaches x = 0.  ``Record.clock`` is the wall-clock
  date and time at record time 0 when the file gave one (a logger's time column often
  starts at 0 in every file and the clock is in the file name); :meth:`Record.clock_seconds`
  puts every record on one clock axis (s).
* :meth:`Record.samples` is the record of some of its samples (its clock and sensors
  kept, its passages and truths dropped): a part of a valid record, not checked again.
* :class:`SimulationSettings` is how a crossing was simulated (run-up ``approach`` in m,
  free vibration ``tail`` in s): what re-simulating it needs (calibration's dynamic
  stages).  :func:`bwim.simulate` sets it on its records; measured records may carry the
  settings their model should use.
* :meth:`Record.with_noise` adds Gaussian noise; by default **gauge noise**: one σ for
  every channel of a kind (strain, deflection), absolute or a fraction of the record's
  overall peak of that kind.  The paper's per-channel model (σ ∝ each channel's peak) is
  ``per_channel=True``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from datetime import time as dtime
from itertools import accumulate

import numpy as np

from bwim.errors import InputError, require_axis, require_columns, require_finite, require_positive
from bwim.sensors import Sensor, SensorKind

__all__ = ["RECORD_TIME_SPAN", "AxleLayout", "Passage", "Record", "SimulationSettings", "Truth",
           "VBIConvergence", "axle_offsets", "clock_key", "day_origin", "local_seconds",
           "noise_sigma", "on_day_axis", "record_list", "seconds_of_day"]


_EPOCH = datetime(1970, 1, 1)
#: s: a record without a clock whose time column starts earlier is a record time (from 0
#: or a sample step), not the clock time of day (:attr:`Record.time_of_day`).
RECORD_TIME_SPAN = 60.0


def seconds_of_day(t: datetime | dtime) -> float:
    """Seconds since midnight of a clock time (a datetime's, or a time of day)."""
    return t.hour * 3600.0 + t.minute * 60.0 + t.second + t.microsecond * 1e-6


def day_origin(times_of_day: Sequence[float]) -> float:
    """Where a day that holds ``times_of_day`` (s since midnight) best starts, s since
    midnight: 0 when they do not straddle midnight, else the middle of the longest gap
    between them (times from 23:20 to 01:00: 12:10), so that they run in order from it."""
    tod = np.sort(np.mod(np.asarray(times_of_day, dtype=float), 86400.0))
    if tod.size < 2:
        return 0.0
    gaps = np.diff(np.concatenate([tod, [tod[0] + 86400.0]]))
    k = int(gaps.argmax())
    return 0.0 if k == tod.size - 1 else float(tod[k] + 0.5 * gaps[k])


def on_day_axis(time_of_day: float, origin: float) -> float:
    """A time of day (s since midnight) on the day that starts at ``origin``
    (:func:`day_origin`): from ``origin`` to ``origin`` + 86400 s."""
    t = float(time_of_day) % 86400.0
    return t + 86400.0 if t < origin else t


def clock_key(times: Sequence[datetime | dtime]) -> Callable[[datetime | dtime], tuple]:
    """A sort key of clock times: dated ones first, by instant; then times of day from
    where the day of those among ``times`` starts (:func:`day_origin`: a night from 23:50
    to 00:20 runs in order)."""
    origin = day_origin([seconds_of_day(t) for t in times if not isinstance(t, datetime)])

    def key(t: datetime | dtime) -> tuple:
        if isinstance(t, datetime):
            return (0, local_seconds(t))
        return (1, on_day_axis(seconds_of_day(t), origin))

    return key


def local_seconds(t: datetime) -> float:
    """Seconds since 1970-01-01 00:00 of a clock's own (naive: the site's local) time: the
    wall-clock arithmetic of the site, whatever the time zone of the machine (a naive
    datetime's ``timestamp()`` reads it in that zone: an hour lost or gained on the
    nights the clocks change); an aware datetime's offset is dropped, as bwim's clocks
    drop it."""
    return (t.replace(tzinfo=None) - _EPOCH).total_seconds()


def axle_offsets(spacings: np.ndarray) -> np.ndarray:
    """Distance of each axle behind the first, m, from the axle spacings: 0, then their
    running sums (``numpy.cumsum``'s, one after the other; a float vector's summed as
    Python floats, the same numbers without numpy's calls)."""
    if isinstance(spacings, np.ndarray) and spacings.dtype == np.float64 \
            and spacings.ndim == 1:
        return np.array([0.0, *accumulate(spacings.tolist())])
    return np.concatenate([[0.0], np.cumsum(spacings)])


class AxleLayout:
    """The axle count and offsets of anything with ``axle_spacings`` (m, shape
    (n_axles − 1,)): a :class:`Passage` and every vehicle model."""

    axle_spacings: np.ndarray

    @property
    def n_axles(self) -> int:
        return self.axle_spacings.size + 1

    @property
    def axle_offsets(self) -> np.ndarray:
        """Distance of each axle behind the first, m, shape (n_axles,)."""
        return axle_offsets(self.axle_spacings)


@dataclass(frozen=True, kw_only=True, eq=False)
class Passage(AxleLayout):
    """A vehicle's crossing as a B-WIM system sees it.

    Parameters
    ----------
    speed : float
        Constant speed, m/s (> 0).
    lane : float
        Transverse position of the vehicle's centre line, m from the right-hand edge.
    axle_spacings : sequence of float
        Distances between consecutive axles, m (length n_axles − 1).
    track_width : float or None
        Distance between the wheels of an axle, m; None: one force per axle on the
        centre line (1-D bridges, quarter cars).
    delay : float
        Record time at which the first axle reaches x = 0, s.
    """

    speed: float
    lane: float = 0.0
    axle_spacings: np.ndarray = field(default_factory=lambda: np.zeros(0))
    track_width: float | None = None
    delay: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed", require_positive("speed", self.speed))
        object.__setattr__(self, "lane", require_finite("lane", self.lane))
        sp = np.array(self.axle_spacings, dtype=float, ndmin=1)
        # finite and positive (NaN fails both comparisons)
        if sp.ndim != 1 or not all(0.0 < x < math.inf for x in sp.tolist()):
            raise InputError(f"axle_spacings must be positive distances, got {sp.tolist()}")
        object.__setattr__(self, "axle_spacings", sp)
        if self.track_width is not None:
            object.__setattr__(self, "track_width",
                               require_positive("track_width", self.track_width))
        object.__setattr__(self, "delay", require_finite("delay", self.delay))

    @property
    def wheels_per_axle(self) -> int:
        return 1 if self.track_width is None else 2

    @property
    def wheel_axle(self) -> np.ndarray:
        """Axle index of each wheel, shape (n_wheels,)."""
        return np.repeat(np.arange(self.n_axles), self.wheels_per_axle)

    @property
    def wheel_y(self) -> np.ndarray:
        """Transverse position of each wheel, m, shape (n_wheels,)."""
        if self.track_width is None:
            return np.full(self.n_axles, self.lane)
        half = self.track_width / 2
        return np.tile([self.lane - half, self.lane + half], self.n_axles)

    def axle_x(self, time: np.ndarray) -> np.ndarray:
        """Longitudinal axle positions at record times, m, shape (n_t, n_axles):
        ``speed (t − delay) − axle_offsets``."""
        t = np.asarray(time, dtype=float).reshape(-1)
        return self.speed * (t[:, None] - self.delay) - self.axle_offsets[None, :]

    def wheel_x(self, time: np.ndarray) -> np.ndarray:
        """Longitudinal wheel positions at record times, m, shape (n_t, n_wheels)."""
        return self.axle_x(time)[:, self.wheel_axle]

    def axle_times_on(self, length: float) -> np.ndarray:
        """Entry and exit time of each axle on a span of ``length``, shape (n_axles, 2)."""
        t_in = self.delay + self.axle_offsets / self.speed
        return np.stack([t_in, t_in + length / self.speed], axis=1)


@dataclass(frozen=True, kw_only=True, eq=False)
class Truth:
    """True forces of one simulated vehicle on the record's time axis.

    Attributes
    ----------
    wheel_forces : ndarray, shape (n_t, n_wheels)
        Contact forces, N (downward), in the wheel order of :class:`Passage`.
    axle_forces : ndarray, shape (n_t, n_axles)
        Sum of each axle's wheel forces, N.
    static_wheel_loads : ndarray, shape (n_wheels,)
    static_axle_loads : ndarray, shape (n_axles,)
    contact_lost : ndarray of bool, shape (n_wheels,)
        True where a wheel's contact force fell below zero at some instant (the linear
        model then pulls on the road: its forces are not physical there).
    """

    wheel_forces: np.ndarray
    axle_forces: np.ndarray
    static_wheel_loads: np.ndarray
    static_axle_loads: np.ndarray
    contact_lost: np.ndarray

    @property
    def gvw(self) -> float:
        """Gross vehicle weight (static), N."""
        return float(self.static_axle_loads.sum())


@dataclass(frozen=True, kw_only=True)
class VBIConvergence:
    """How the vehicle–bridge interaction solution was reached."""

    method: str
    iterations: int = 1
    change: float = 0.0
    """Final relative change of the deck displacement under the wheels (iterative)."""
    converged: bool = True


@dataclass(frozen=True, kw_only=True)
class SimulationSettings:
    """How a crossing was simulated (see module docstring).

    Attributes
    ----------
    approach : float
        Run-up of each vehicle before the bridge, m (>= 0).
    tail : float
        Free vibration recorded after the last axle leaves, s (>= 0).
    """

    approach: float
    tail: float = 0.0

    def __post_init__(self) -> None:
        for name in ("approach", "tail"):
            v = require_finite(name, getattr(self, name))
            if v < 0:
                unit = "m" if name == "approach" else "s"
                raise InputError(f"{name} must be >= 0 {unit}, got {v:g}")
            object.__setattr__(self, name, v)


@dataclass(frozen=True, kw_only=True, eq=False)
class Record:
    """Sensor readings of one event (one or more vehicles crossing).

    Attributes
    ----------
    time : ndarray, shape (n_t,)
        Sample times, s, uniformly spaced.
    data : ndarray, shape (n_t, n_sensors)
        Readings: strain (m/m) or deflection (m); finite, except that a ``temperature``
        channel (°C) may have gaps (NaN).
    sensors : tuple of Sensor
    passages : tuple of Passage
    truths : tuple of Truth
        Empty for measured records.
    convergence : VBIConvergence or None
        For simulated records.
    settings : SimulationSettings or None
        How the crossing was simulated (simulated records), or the settings a model of
        it should use.
    clock : datetime or None
        Wall-clock date and time at record time 0 (naive: the site's local time; a UTC
        offset given is dropped, the time kept as written), None when unknown (then
        ``time`` itself may be a clock time of day, as some loggers write it).
    """

    time: np.ndarray
    data: np.ndarray
    sensors: tuple[Sensor, ...]
    passages: tuple[Passage, ...] = ()
    truths: tuple[Truth, ...] = ()
    convergence: VBIConvergence | None = None
    settings: SimulationSettings | None = None
    clock: datetime | None = None

    def __post_init__(self) -> None:
        t = require_axis("time", self.time)
        d = require_columns("data", self.data, (t.size, len(self.sensors)), "(n_t, n_sensors)")
        # a temperature channel may have gaps (NaN); every other sample is finite
        gappy = np.array([s.kind is SensorKind.TEMPERATURE for s in self.sensors], dtype=bool)
        bad = ~np.isfinite(d)
        bad[:, gappy] = np.isinf(d[:, gappy])
        if bad.any():
            bad = np.argwhere(bad)[0]
            raise InputError(
                f"data has a non-finite sample at t = {t[bad[0]]:g} s in channel "
                f"{self.sensors[bad[1]].name!r}"
            )
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "data", d)
        object.__setattr__(self, "sensors", tuple(self.sensors))
        object.__setattr__(self, "passages", tuple(self.passages))
        object.__setattr__(self, "truths", tuple(self.truths))
        if self.settings is not None and not isinstance(self.settings, SimulationSettings):
            raise InputError(f"settings must be a SimulationSettings, got "
                             f"{type(self.settings).__name__}")
        if self.clock is not None and not isinstance(self.clock, datetime):
            raise InputError(f"clock must be a datetime, got {type(self.clock).__name__}")
        if self.clock is not None and self.clock.tzinfo is not None:
            # naive: the local time as written (a logger's offset, if any, is not a zone)
            object.__setattr__(self, "clock", self.clock.replace(tzinfo=None))

    @property
    def time_of_day(self) -> bool:
        """Whether the time column is the clock time of day (s since midnight): the record
        has no :attr:`clock` and its first sample lies within the day, after its first
        :data:`RECORD_TIME_SPAN` s (older loggers write the clock so; a record time starts
        at 0 or a sample step, and a record in the first minute after midnight is taken
        for one: placed in no day rather than placed wrongly)."""
        return self.clock is None and RECORD_TIME_SPAN <= float(self.time[0]) < 86400.0

    def clock_seconds(self, t: float | None = None) -> float:
        """Clock time of record time ``t`` (default: the first sample), s.

        With :attr:`clock`: seconds since 1970-01-01 00:00 of the site's local time (one
        axis across days).  Without: ``t`` itself (a logger's time column that holds the
        clock time of day, or a record time).
        """
        t = float(self.time[0]) if t is None else float(t)
        if self.clock is None:
            return t
        return local_seconds(self.clock) + t

    def clock_at(self, t: float | None = None) -> datetime | None:
        """The wall-clock date and time of record time ``t`` (default: the first sample);
        None when :attr:`clock` is unknown."""
        if self.clock is None:
            return None
        from datetime import timedelta

        t = float(self.time[0]) if t is None else float(t)
        return self.clock + timedelta(seconds=t)

    @property
    def sampling_rate(self) -> float:
        """Samples per second (from the median time step)."""
        return float(1.0 / np.median(np.diff(self.time)))

    def time_after_exit(self, length: float) -> float:
        """Record time after the last axle of every passage has left a span of ``length``
        m, s (0 if the record ends earlier)."""
        if not self.passages:
            raise InputError("this record has no passage: the axles' exit is unknown")
        exit_time = max(p.axle_times_on(length)[-1, 1] for p in self.passages)
        return max(0.0, float(self.time[-1] - exit_time))

    @property
    def passage(self) -> Passage:
        """The passage of a single-vehicle record."""
        if len(self.passages) != 1:
            raise InputError(f"this record has {len(self.passages)} vehicles; use .passages")
        return self.passages[0]

    @property
    def truth(self) -> Truth:
        """The truth of a single-vehicle simulated record."""
        if len(self.truths) != 1:
            raise InputError(
                "this record has no simulated truth" if not self.truths
                else f"this record has {len(self.truths)} vehicles; use .truths"
            )
        return self.truths[0]

    def channel_indices(self, sensors: Sequence[str | Sensor]) -> list[int]:
        """The columns of the channels ``sensors`` (by name or Sensor), in that order;
        InputError for a channel the record does not have."""
        names = [s.name for s in self.sensors]
        idx = []
        for s in sensors:
            key = s.name if isinstance(s, Sensor) else s
            if key not in names:
                raise InputError(f"no channel {key!r} in this record; channels: {names}")
            idx.append(names.index(key))
        return idx

    def samples(self, keep: np.ndarray) -> Record:
        """The record of the samples ``keep`` (a boolean mask of its samples), its clock,
        sensors, settings and convergence kept, its passages and truths dropped.  Two or
        more samples of a valid record make a valid record: they are not checked again
        (as ``dataclasses.replace`` would)."""
        time, data = self.time[keep], self.data[keep]
        if time.size < 2:  # the checks name what is wrong
            return dataclasses.replace(self, time=time, data=data, passages=(), truths=())
        part = object.__new__(type(self))
        for f in dataclasses.fields(self):
            object.__setattr__(part, f.name, getattr(self, f.name))
        object.__setattr__(part, "time", time)
        object.__setattr__(part, "data", data)
        object.__setattr__(part, "passages", ())
        object.__setattr__(part, "truths", ())
        return part

    def channels(self, sensors: Sequence[str | Sensor]) -> Record:
        """A record with a subset of the channels (by name or Sensor), in that order."""
        idx = self.channel_indices(sensors)
        return dataclasses.replace(
            self, data=self.data[:, idx], sensors=tuple(self.sensors[i] for i in idx)
        )

    def plot(self, ax=None, **kw):
        """Each channel against time (:func:`bwim.plots.records.plot_record`; ``kw``:
        channels, length, title); returns the figure."""
        from bwim.plots.records import plot_record

        return plot_record(self, ax, **kw)

    def with_noise(self, fraction: float | None = None, *,
                   seed: int | np.random.Generator | None, sigma: float | None = None,
                   per_channel: bool = False) -> Record:
        """A copy with Gaussian measurement noise (see :func:`noise_sigma`).

        Gauge noise is the default: one standard deviation for every channel of a kind of
        reading (all strain gauges share one σ in strain, all deflection channels one in
        m), given either absolutely (``sigma``) or as a ``fraction`` of the record's
        overall peak reading of that kind.  ``per_channel=True`` is the paper's §5.2
        model instead: each channel's σ is ``fraction`` × its own peak (a real gauge's
        noise does not scale with its signal; keep it to reproduce the paper).
        """
        scale = noise_sigma(self, fraction, sigma=sigma, per_channel=per_channel)
        rng = np.random.default_rng(seed)
        return dataclasses.replace(self, data=self.data + rng.standard_normal(self.data.shape)
                                   * scale)


def noise_sigma(record: Record, fraction: float | None = None, *, sigma: float | None = None,
                per_channel: bool = False) -> np.ndarray:
    """Noise standard deviation of each channel, shape (n_sensors,), in reading units.

    Exactly one of ``fraction`` and ``sigma``: ``sigma`` is absolute (every channel);
    ``fraction`` × the peak |reading| over all channels with the same unit (strain,
    deflection…; absolute gauge noise scaled to the event), or, with
    ``per_channel=True`` (the paper's §5.2 definition), × each channel's own peak.
    """
    if (fraction is None) == (sigma is None):
        raise InputError("noise fraction or sigma: give exactly one (fraction of the peak "
                         "reading, or sigma absolute)")
    peak = np.abs(record.data).max(axis=0)
    if sigma is not None:
        if per_channel:
            raise InputError("per_channel scales a fraction of each channel's peak; an "
                             "absolute sigma is the same on every channel")
        if isinstance(sigma, bool) or not isinstance(sigma, (int, float, np.number)) \
                or not np.isfinite(sigma) or sigma < 0:
            raise InputError(f"sigma must be a number >= 0 (reading units), got {sigma!r}")
        return np.full(peak.shape, float(sigma))
    if isinstance(fraction, bool) or not isinstance(fraction, (int, float, np.number)):
        raise InputError(f"noise fraction must be a number in [0, 1], got {fraction!r}")
    if not np.isfinite(fraction) or not 0.0 <= fraction <= 1.0:
        raise InputError(f"noise fraction must lie in [0, 1] (a share of the peak reading), "
                         f"got {fraction!r}")
    if per_channel:
        return fraction * peak
    units = np.array([s.kind.unit for s in record.sensors])
    out = np.empty_like(peak)
    for unit in set(units.tolist()):
        group = units == unit
        out[group] = fraction * peak[group].max()
    return out


def record_list(records: Record | Sequence[Record], *, needs: str) -> list[Record]:
    """A record or a sequence of records as a list; raises :class:`InputError` unless it is
    a non-empty sequence of :class:`Record` (``needs``: why it cannot be empty, for the
    message, e.g. ``"calibration needs at least one run"``)."""
    if isinstance(records, Record):
        records = [records]
    try:
        recs = list(records)
    except TypeError:
        raise InputError(f"records must be a sequence of Record, got "
                         f"{type(records).__name__}") from None
    if not recs:
        raise InputError(f"records is empty: {needs}")
    for k, r in enumerate(recs):
        if not isinstance(r, Record):
            raise InputError(f"records[{k}] is a {type(r).__name__}, not a bwim Record")
    return recs
