"""One vehicle as a WIM system reports it: the row type of every summary.

Contract
--------
* :class:`SummaryRow` is what ``bwim weigh`` and ``bwim identify`` write per vehicle (one
  row of ``summary.csv``, :mod:`bwim.io.summary`) and what the COST 323 assessment reads
  (:func:`bwim.accuracy.assess`).  The site chain makes them with
  :meth:`bwim.site.EventWeighing.to_summary_row`, moving force identification with
  :meth:`bwim.mfi.ForceIdentification.to_summary_rows`, a batch with a failed record
  with :func:`failed_row`.  No file is needed between weighing and assessing.
* Units are SI: weights in N, spacings in m, speed in m/s.  The CSV file writes kN.
* ``status`` says what the row is: ``"weighed"`` (weights that passed every plausibility
  check), ``"refused"`` (the vehicle was seen but not weighed: ``reason`` says why, e.g.
  two vehicles on the bridge, an implausible fit) or ``"failed"`` (the record could not be
  read or processed: ``reason`` says why; a batch retries such records on resume).
* **A refused or doubtful weight is never a weight**: a row that is not ``"weighed"``
  carries no axle, group or gross weight, and a ``"weighed"`` row has a positive gross
  weight, no negative axle or group weight, no reason, a quality other than ``"reject"``
  and no hard flag (:data:`bwim.plausibility.HARD_FLAGS`).  With ``n_axles``, a row's
  axle weights (when any) are ``n_axles`` and its spacings ``n_axles − 1``.  The
  constructor refuses anything else, so no writer can emit one.
* ``vehicle`` numbers the vehicles of one record from 1 (in order of arrival); the pair
  ``(record, vehicle)`` is a row's key.  ``time`` is the wall-clock time of the vehicle's
  first axle at the gauges' reference (a :class:`datetime.datetime`, or a
  :class:`datetime.time` when the logger gives a clock time of day without a date),
  naive: the site's local time (a UTC offset given is dropped, the time as written).
  ``lateral`` is the centre of the vehicle's strain across the gauges (not its wheel
  path: the slab spreads the strain, which pulls the centre toward the gauges' middle;
  docs/flags.md), in metres from the right-hand edge when ``lateral_unit == "m"``, in
  gauge-order units (1 = the first gauge) when ``"gauge index"`` (see
  :mod:`bwim.detect.result`).  ``direction`` is ``"+x"`` or
  ``"-x"`` (the bridge frame, :mod:`bwim.conventions`), ``""`` when unknown.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from datetime import datetime
from datetime import time as dtime

from bwim.errors import InputError
from bwim.plausibility import HARD_FLAGS

__all__ = ["DIRECTIONS", "LATERAL_UNITS", "METHODS", "QUALITIES", "STATUSES", "SummaryRow",
           "failed_row"]

#: What a row is (see the module docstring).
STATUSES = ("weighed", "refused", "failed")
#: Quality of a weighing (:func:`bwim.plausibility.quality_of`); "" when not weighed.
QUALITIES = ("ok", "warning", "reject", "")
#: How it was weighed: influence lines (Moses' algorithm) or moving force identification.
METHODS = ("moses", "mfi", "")
#: Travel direction in the bridge frame.
DIRECTIONS = ("+x", "-x", "")
#: Unit of ``lateral``.
LATERAL_UNITS = ("m", "gauge index", "")


def _record_name(value: object) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InputError(f"record must be a non-empty name, got {value!r}")
    return value


def _floats(name: str, values: object) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a sequence of numbers, got {values!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise InputError(f"{name} must be finite, got {list(out)}")
    return out


def _optional_float(name: str, value: object) -> float | None:
    if value is None:
        return None
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number or None, got {value!r}") from None
    return v if math.isfinite(v) else None


def _choice(name: str, value: object, options: tuple[str, ...]) -> str:
    if value not in options:
        raise InputError(f"{name} must be one of {', '.join(repr(o) for o in options)}, "
                         f"got {value!r}")
    return str(value)


@dataclass(frozen=True, kw_only=True)
class SummaryRow:
    """One vehicle as the WIM system reported it (see the module docstring).

    Attributes
    ----------
    record : str
        Record (event file) name.
    vehicle : int
        The vehicle's number within the record, from 1.
    status : str or None
        ``"weighed"``, ``"refused"`` or ``"failed"``; None: ``"weighed"`` when a gross
        weight is given, else ``"refused"``.
    time : datetime, time or None
        Wall-clock time of the vehicle (see the module docstring).
    lane : int or None
        Lane number, as the scenario numbers its lanes.
    direction : str
        ``"+x"``, ``"-x"`` or ``""``.
    vehicle_class : str
        The vehicle's class (:mod:`bwim.classify`; the ``class`` column), ``""`` unknown.
    n_axles : int or None
        Axles detected.
    speed : float or None
        m/s.
    axle_spacings, axle_weights, group_weights : tuple of float
        m, N, N; the weights empty unless weighed.
    gvw : float or None
        Gross vehicle weight, N; None unless weighed.
    flags : tuple of str
        The flags of detection and weighing (:mod:`bwim.plausibility`, docs/flags.md).
    lateral : float or None
        Lateral position (see ``lateral_unit``).
    lateral_unit : str
        ``"m"``, ``"gauge index"`` or ``""``.
    group_laterals : tuple of float
        Lateral position of each axle group, in ``lateral_unit``
        (:func:`bwim.site.wheelpath.group_laterals`); empty when not measured.
    confidence : float or None
        Detection confidence in [0, 1].
    residual : float or None
        Relative residual of the weighing's fit.
    quality : str
        ``"ok"``, ``"warning"``, ``"reject"`` or ``""``.
    method : str
        ``"moses"``, ``"mfi"`` or ``""``.
    drift_factor : float or None
        The strain-to-load factor the weights were divided by (1 = the calibration's).
    drift_method : str
        Where that factor came from (:mod:`bwim.site`), ``""`` when none was applied.
    lam : float or None
        MFI's regularisation parameter (the ``lambda`` column).
    reason : str
        Why the vehicle was not weighed (default ``"not weighed"``), or why the record
        failed (required); ``""`` when weighed.
    """

    record: str
    vehicle: int = 1
    status: str | None = None
    time: datetime | dtime | None = None
    lane: int | None = None
    direction: str = ""
    vehicle_class: str = ""
    n_axles: int | None = None
    speed: float | None = None
    axle_spacings: tuple[float, ...] = ()
    axle_weights: tuple[float, ...] = ()
    gvw: float | None = None
    group_weights: tuple[float, ...] = ()
    flags: tuple[str, ...] = ()
    lateral: float | None = None
    lateral_unit: str = ""
    group_laterals: tuple[float, ...] = ()
    confidence: float | None = None
    residual: float | None = None
    quality: str = ""
    method: str = ""
    drift_factor: float | None = None
    drift_method: str = ""
    lam: float | None = None
    reason: str = field(default="")

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "record", _record_name(self.record))
        if isinstance(self.vehicle, bool) or not isinstance(self.vehicle, int) \
                or self.vehicle < 1:
            raise InputError(f"vehicle must be a positive integer, got {self.vehicle!r}")
        if self.gvw is not None:
            gvw = _optional_float("gvw", self.gvw)
            if gvw is None:
                raise InputError(f"gvw must be finite, got {self.gvw!r}")
            set_(self, "gvw", gvw)
        status = self.status
        if status is None:
            status = "weighed" if self.gvw is not None else "refused"
        set_(self, "status", _choice("status", status, STATUSES))
        if self.time is not None and not isinstance(self.time, (datetime, dtime)):
            raise InputError(f"time must be a datetime or a time, got {self.time!r}")
        if self.time is not None and self.time.tzinfo is not None:  # naive, as the clocks
            set_(self, "time", self.time.replace(tzinfo=None))
        if self.lane is not None and (isinstance(self.lane, bool)
                                      or not isinstance(self.lane, int)):
            raise InputError(f"lane must be an integer, got {self.lane!r}")
        set_(self, "direction", _choice("direction", self.direction, DIRECTIONS))
        set_(self, "vehicle_class", str(self.vehicle_class))
        if self.n_axles is not None and (isinstance(self.n_axles, bool) or not isinstance(
                self.n_axles, int) or self.n_axles < 1):
            raise InputError(f"n_axles must be a positive integer, got {self.n_axles!r}")
        for name in ("axle_spacings", "axle_weights", "group_weights", "group_laterals"):
            set_(self, name, _floats(name, getattr(self, name)))
        for name in ("speed", "lateral", "confidence", "residual", "drift_factor", "lam"):
            set_(self, name, _optional_float(name, getattr(self, name)))
        if isinstance(self.flags, str):
            raise InputError(f"flags must be a sequence of flags, got the text {self.flags!r}")
        set_(self, "flags", tuple(str(f) for f in self.flags))
        if self.n_axles is not None:  # one weight per axle, one spacing between two
            for name, n in (("axle_weights", self.n_axles),
                            ("axle_spacings", self.n_axles - 1)):
                values = getattr(self, name)
                if values and len(values) != n:
                    raise InputError(f"{self.record}: {len(values)} {name} for "
                                     f"n_axles = {self.n_axles}")
        set_(self, "lateral_unit", _choice("lateral_unit", self.lateral_unit, LATERAL_UNITS))
        set_(self, "quality", _choice("quality", self.quality, QUALITIES))
        set_(self, "method", _choice("method", self.method, METHODS))
        set_(self, "drift_method", str(self.drift_method))
        set_(self, "reason", " ".join(str(self.reason).split()))
        self._check_weights()

    def _check_weights(self) -> None:
        """A refused or doubtful weight is never a weight (the module docstring)."""
        if self.status == "weighed":
            if self.gvw is None:
                raise InputError(f"{self.record}: a weighed row needs its gross weight")
            if self.gvw <= 0 or any(w < 0 for w in (*self.axle_weights, *self.group_weights)):
                raise InputError(f"{self.record}: a weighed row's weights are positive "
                                 f"(gvw {self.gvw!r})")
            hard = [f for f in self.flags if f in HARD_FLAGS]
            if self.quality == "reject" or hard:
                raise InputError(f"{self.record}: a weighing of quality 'reject' is not a "
                                 "weight; its row must be refused with the reason"
                                 + (f" (hard flags: {', '.join(hard)})" if hard else ""))
            if self.reason:
                raise InputError(f"{self.record}: a weighed row has no reason, got "
                                 f"{self.reason!r}")
            return
        if self.gvw is not None or self.axle_weights or self.group_weights:
            raise InputError(f"{self.record}: a {self.status} row carries no weights")
        if not self.reason:
            if self.status == "failed":
                raise InputError(f"{self.record}: a failed row needs its reason")
            object.__setattr__(self, "reason", "not weighed")

    @property
    def weighed(self) -> bool:
        """True when the row holds weights."""
        return self.status == "weighed"

    @property
    def key(self) -> tuple[str, int]:
        """``(record, vehicle)``: a row's identity in a summary."""
        return self.record, self.vehicle

    def refused(self, reason: str, *flags: str) -> SummaryRow:
        """The row not weighed: its weights dropped, ``flags`` added (after its own, once
        each), quality ``"reject"`` and ``reason``; everything else kept (a day-level
        check's refusal of a row one event weighed)."""
        return dataclasses.replace(
            self, status="refused", axle_weights=(), group_weights=(), gvw=None,
            flags=tuple(dict.fromkeys([*self.flags, *flags])), quality="reject",
            reason=reason)


def failed_row(record: str, reason: str) -> SummaryRow:
    """The row of a record that could not be read or processed."""
    return SummaryRow(record=record, status="failed", reason=reason or "failed")
