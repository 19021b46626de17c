"""A vehicle's lateral position from the transverse spread of the strain gauges.

Contract
--------
* The gauges of one section across the deck each see a vehicle most strongly near its
  wheel paths.  Each gauge gets a weight, its largest reading above its quiet level in
  the vehicle's time window (``weight="peak"``) or the area of its positive part
  (``"area"``, sensitive to drift), and the lateral position is the centroid of the
  weights less ``threshold`` × the largest weight (negative parts dropped; 0: plain
  centroid).  On a slab the transverse spread is wide: a plain centroid is pulled toward
  the deck's centre, and subtracting the common part removes most of that pull while
  staying continuous in the readings (measured in tests/validation/test_vehicle_detection.py).
  Readings symmetric about the load on gauges symmetric about it give the load's
  position exactly.
* In metres from the right-hand edge when every gauge has a ``y`` and they do not all
  share one; otherwise a dimensionless *lateral index*: the centroid in gauge-order units,
  1 = the first gauge as listed, n = the last (gauges evenly spread give
  ``y ≈ y_1 + (index − 1) × gauge pitch``).
* The quiet level of each gauge is its median over the ``quiet`` samples.
* Compiled: the quiet levels (:func:`bwim.detect.signals.column_medians`, numpy's
  medians) and each window's peak weights (:func:`bwim.detect.order_stats.window_peaks`:
  numpy's max, maximum and threshold, the same numbers); the centroid is numpy's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_range
from bwim.records import Record
from bwim.sensors import Sensor, SensorKind

from .order_stats import window_peaks
from .signals import channel_data, column_medians, median

__all__ = ["LateralPosition", "in_metres", "lateral_position", "lateral_positions",
           "section_gauges"]


def in_metres(gauges: Sequence[Sensor]) -> bool:
    """Whether the lateral position of ``gauges`` is in metres (module contract): two or
    more, every one with its ``y``, not all one (the sensors' y are finite,
    :class:`bwim.sensors.Sensor`: they differ when max > min)."""
    ys = [getattr(s, "y", None) for s in gauges]
    return len(ys) > 1 and all(y is not None for y in ys) and max(ys) > min(ys)


@dataclass(frozen=True, kw_only=True, eq=False)
class LateralPosition:
    """Load centroid across the deck.

    Attributes
    ----------
    value : float
        Metres from the right-hand edge (``unit == "m"``) or gauge index (1-based); NaN
        when no gauge responded.
    unit : str
        ``"m"`` or ``"gauge index"``.
    weights : ndarray, shape (n_gauges,)
        Each gauge's weight after the threshold was subtracted.
    gauges : tuple of str
        Gauge names, in the order of the index.
    """

    value: float
    unit: str
    weights: np.ndarray
    gauges: tuple[str, ...]


def section_gauges(record: Record, gauges: Sequence[str] | None = None,
                   exclude: Sequence[str] = ()) -> tuple[Sensor, ...]:
    """The gauges used for lateral position and strain activity: the named ones, or every
    longitudinal strain gauge (``strain_x``) of the record not in ``exclude``; when their
    ``x`` positions are known and differ, those of the section with most gauges (ties:
    nearest the middle of the instrumented sections)."""
    by_name = {s.name: s for s in record.sensors}
    if gauges is not None:
        out = []
        for g in gauges:
            if g not in by_name:
                raise InputError(f"gauges: no channel {g!r} in this record; channels: "
                                 f"{list(by_name)}")
            out.append(by_name[g])
        return tuple(out)
    chosen = [s for s in record.sensors
              if s.kind is SensorKind.STRAIN_X and s.name not in exclude]
    xs = [getattr(s, "x", None) for s in chosen]
    if not chosen or any(x is None for x in xs):
        return tuple(chosen)
    rounded = np.round(np.asarray(xs, dtype=float), 6)
    sections, counts = np.unique(rounded, return_counts=True)
    if sections.size == 1:
        return tuple(chosen)
    mid = 0.5 * (sections[0] + sections[-1])
    best = min(range(sections.size), key=lambda k: (-counts[k], abs(sections[k] - mid)))
    return tuple(s for s, x in zip(chosen, rounded, strict=True) if x == sections[best])


def lateral_position(
    record: Record,
    *,
    window: tuple[float, float] | None = None,
    quiet: np.ndarray | None = None,
    gauges: Sequence[str] | None = None,
    weight: str = "peak",
    threshold: float = 0.5,
) -> LateralPosition:
    """Load centroid across the deck of the vehicle on the span during ``window``.

    Parameters
    ----------
    record : Record
    window : (t_start, t_end), optional
        Record times of the vehicle's presence, s (default the whole record).
    quiet : bool array, shape (n_t,), optional
        Samples without traffic, for each gauge's quiet level (default: the samples
        outside ``window`` if they are at least 10 % of the record, else the first and
        last 10 % of it).
    gauges : sequence of str, optional
        Gauge names across one section, default :func:`section_gauges`.
    weight : "peak" or "area"
    threshold : float
        This fraction of the largest weight is subtracted from every weight (negative
        results count as zero), in [0, 1).

    Returns
    -------
    LateralPosition
    """
    if weight not in ("peak", "area"):
        raise InputError(f"unknown weight {weight!r}; expected 'peak' or 'area'")
    t = record.time
    if quiet is None and window is not None:
        inside = (t >= window[0]) & (t <= window[1])
        if inside.any():
            quiet = ~inside
            if quiet.sum() < 0.1 * t.size:
                edge = max(1, t.size // 10)
                quiet = np.zeros(t.size, dtype=bool)
                quiet[:edge] = quiet[-edge:] = True
    return lateral_positions(record, [window], quiet=quiet, gauges=gauges, weight=weight,
                             threshold=threshold)[0]


def lateral_positions(
    record: Record,
    windows: Sequence[tuple[float, float] | None],
    *,
    quiet: np.ndarray | None = None,
    gauges: Sequence[str] | None = None,
    weight: str = "peak",
    threshold: float = 0.5,
    readings: np.ndarray | None = None,
) -> list[LateralPosition]:
    """:func:`lateral_position` of each of ``windows`` with one ``quiet`` mask (given,
    or None only when every window is None: the whole record, the first and last 10 %
    quiet), the same numbers: the gauges are read, and their quiet levels taken, once.
    ``readings``: the gauges' readings, ``channel_data(record, gauges)``, if already
    read."""
    if weight not in ("peak", "area"):
        raise InputError(f"unknown weight {weight!r}; expected 'peak' or 'area'")
    thr = require_range("threshold", threshold, 0.0, 1.0, closed=False) if threshold else 0.0
    sens = section_gauges(record, gauges)
    names = tuple(s.name for s in sens)
    metres = in_metres(sens)
    unit = "m" if metres else "gauge index"
    if not sens:
        return [LateralPosition(value=float("nan"), unit=unit, weights=np.zeros(0),
                                gauges=()) for _ in windows]
    t = record.time
    data = channel_data(record, names) if readings is None else readings
    if quiet is None:
        edge = max(1, t.size // 10)
        quiet = np.zeros(t.size, dtype=bool)
        quiet[:edge] = quiet[-edge:] = True
    quiet = np.asarray(quiet, dtype=bool)
    coord = (np.asarray([s.y for s in sens], dtype=float) if metres
             else np.arange(1.0, len(sens) + 1.0))
    peaks = weight == "peak"
    if peaks:  # the kernel's arguments: float64, C-contiguous; the table's columns one
        # after the other (a record's columns, Fortran-ordered, without a copy)
        t = np.ascontiguousarray(t, dtype=float)
        cols = np.ascontiguousarray(np.asarray(data, dtype=float).T)
    out = []
    level = None
    for window in windows:
        lo, hi = (-np.inf, np.inf) if window is None else (float(window[0]),
                                                            float(window[1]))
        if level is None:
            if not _any_inside(t, lo, hi):
                out.append(_nowhere(unit, len(sens), names))
                continue
            if quiet.shape != t.shape or not quiet.any():
                raise InputError("quiet must be a boolean mask of the record's samples with "
                                 "at least one True")
            level = column_medians(data, quiet)  # those of data[quiet]
        if peaks:
            # the largest deviation: the largest reading less the level (a subtraction
            # rounds monotonically: the same number as the largest of the differences),
            # thresholded (bwim.detect.order_stats.window_peaks)
            status, w = window_peaks(t, cols, lo, hi, level, thr)
            if status < 2:
                out.append(_nowhere(unit, len(sens), names))
                continue
        else:
            inside = (t >= lo) & (t <= hi)
            if not inside.any():
                out.append(_nowhere(unit, len(sens), names))
                continue
            w = np.maximum(data[inside] - level, 0.0).sum(axis=0) * median(np.diff(t))
            if not (w > 0).any():
                out.append(_nowhere(unit, len(sens), names))
                continue
            w = np.maximum(w - thr * w.max(), 0.0)
        out.append(LateralPosition(value=float(w @ coord / w.sum()), unit=unit, weights=w,
                                   gauges=names))
    return out


def _any_inside(t: np.ndarray, lo: float, hi: float) -> bool:
    """Whether a sample's time (a record's: increasing) lies in ``[lo, hi]``: the first
    one from ``lo`` on is not beyond ``hi``."""
    i = int(t.searchsorted(lo))
    return i < t.size and bool(t[i] <= hi)


def _nowhere(unit: str, n: int, names: tuple[str, ...]) -> LateralPosition:
    """The position of a window without a sample or without a gauge that responded."""
    return LateralPosition(value=float("nan"), unit=unit, weights=np.zeros(n), gauges=names)
