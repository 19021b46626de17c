"""Accuracy class of a weigh-in-motion system by the COST 323 European specification.

The specification is COST 323, *European Specification on Weigh-in-Motion of Road
Vehicles* (draft 3.0, 1999; reprinted in Jacob, OBrien & Jehaes (eds.), *Weigh-in-Motion
of Road Vehicles: Final Report of the COST 323 Action*, LCPC Paris, 2002); the statistics
are those of Jacob (2000), "Assessment of the accuracy and classification of weigh-in-motion
systems, Part 1: Statistical background", Int. J. Heavy Vehicle Systems 7(2/3) 136–152.
The formulas below follow the COST 323 accuracy calculation sheet (its cell formulas are
quoted in the OpenWIM ``pywim`` project, ``notebooks/AccuracyCalculationCOST323.ipynb``).

Contract
--------
* Errors are relative, in per cent, of the WIM value against the static reference:
  ``e = 100 (W_wim − W_static) / W_static`` (:func:`relative_errors`).  A sample of ``n``
  errors has mean ``m`` and standard deviation ``s`` (``ddof = 1``), both in per cent.
* Criteria (:data:`CRITERIA`): ``gross_weight``, ``group_of_axles`` (the sum of a group's
  axles), ``single_axle`` and ``axle_of_group`` (each axle of a group).  Tolerances δ (%,
  half width of the confidence interval) per class (:data:`TOLERANCES`)::

      class             A(5)  B+(7)  B(10)  C(15)  D+(20)  D(25)
      gross weight        5     7     10     15     20      25
      group of axles      7    10     13     18     23      28
      single axle         8    11     15     20     25      30
      axle of a group    10    14     20     25     30      35

  Beyond D(25) the class is ``E(d)``, ``d`` = 30, 35, …, with the calculation sheet's
  extension of the table: δ = d (gross), 1.1 d (group), 1.2 d (single axle),
  1.2 d + 5 (axle of a group).
* Minimum level of confidence (:func:`min_confidence`), a probability in (0, 1)::

      π₀ = 2 Φ(u/k − t₀.₉₇₅,ₙ₋₁ / √n) − 1

  with Φ the standard normal CDF, t₀.₉₇₅,ₙ₋₁ Student's 97.5 % quantile with n − 1 degrees of
  freedom, u = 2.675 (r1, full repeatability), 2.36 (r2, extended repeatability),
  2.155 (RR1, limited reproducibility), 2.0 (RR2, full reproducibility) and k = 1, 1.05,
  1.1 for environment I (repeatability), II (limited reproducibility), III (full
  reproducibility).
* Level of confidence of the interval [−δ, δ] (:func:`confidence_level`)::

      π(δ) = 1 − T̄ₙ₋₁(δ/s − m/s − t₀.₉₇₅,ₙ₋₁/√n) − T̄ₙ₋₁(δ/s + m/s − t₀.₉₇₅,ₙ₋₁/√n)

  with T̄ₙ₋₁ the upper tail of Student's distribution with n − 1 degrees of freedom (the
  sheet's ``TDIST(x; n−1; 1)``; not the normal CDF).  π increases with δ; as n → ∞ it tends
  to P(|X| ≤ δ) for X ~ N(m, s²).
* Class of a criterion: the first class of the table whose δ gives π ≥ π₀ (the smallest
  δ); if none, ``E(d)`` with the smallest d whose δ passes.  ``delta_min`` is the exact δ
  at which π = π₀ (the sheet's "d_min").  At least 2 errors are needed, and enough for
  π₀ > 0 (e.g. 4 for RR2 in environment I): fewer are an InputError, the test being void.
* Overall class: the worst class of the criteria assessed (the sheet's "accepted" class is
  the largest class value).  Criteria with too few values (as above) are not assessed and
  are listed as skipped.
* :func:`assess` matches summary rows (WIM, :class:`bwim.summary.SummaryRow`: no file is
  needed) to reference rows (static) by record name (and vehicle), or, for a reference
  that gives a clock time instead of a record (a continuous recording's events are
  named by the trigger, not known beforehand), by time: the one summary row within
  ``time_tolerance`` s of it (in its lane when given; among several, those of its axle
  count), else none (see :func:`assess`),
  splits each vehicle's axles into single axles and groups with the REFERENCE spacings
  (consecutive axles closer than ``group_spacing``, :func:`bwim.wim.group_axles`) and
  classifies the four criteria.  Weights are in N (SI); only their ratios matter.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from datetime import time as dtime

import numpy as np

from bwim.errors import InputError, require_choice, require_finite, require_positive
from bwim.records import seconds_of_day
from bwim.summary import SummaryRow
from bwim.tables import Table
from bwim.wim.moses import group_axles

__all__ = [
    "CLASSES",
    "CRITERIA",
    "ENVIRONMENTS",
    "REPEATABILITIES",
    "TOLERANCES",
    "AccuracyResult",
        "CriterionResult",
    "ReferenceMatch",
    "ReferenceRow",
    "SummaryRow",
    "assess",
    "class_tolerance",
    "classify",
    "classify_statistics",
    "confidence_level",
    "match_references",
    "min_confidence",
    "relative_errors",
]

#: Accuracy classes of the table, best first, with their gross-weight tolerance (%).
CLASSES: tuple[tuple[str, float], ...] = (
    ("A", 5.0), ("B+", 7.0), ("B", 10.0), ("C", 15.0), ("D+", 20.0), ("D", 25.0),
)

#: Criteria in the specification's order, with the label printed in tables.
CRITERIA: dict[str, str] = {
    "gross_weight": "gross weight",
    "group_of_axles": "group of axles",
    "single_axle": "single axle",
    "axle_of_group": "axle of a group",
}

#: Tolerance δ (%) of each criterion for the classes of :data:`CLASSES`, in that order.
TOLERANCES: dict[str, tuple[float, ...]] = {
    "gross_weight": (5.0, 7.0, 10.0, 15.0, 20.0, 25.0),
    "group_of_axles": (7.0, 10.0, 13.0, 18.0, 23.0, 28.0),
    "single_axle": (8.0, 11.0, 15.0, 20.0, 25.0, 30.0),
    "axle_of_group": (10.0, 14.0, 20.0, 25.0, 30.0, 35.0),
}

#: u of each test condition (repeatability / reproducibility of the test plan).
REPEATABILITIES: dict[str, float] = {"r1": 2.675, "r2": 2.36, "RR1": 2.155, "RR2": 2.0}

#: k of each environmental condition.
ENVIRONMENTS: dict[str, float] = {"I": 1.0, "II": 1.05, "III": 1.1}

_E_START, _E_STEP = 30.0, 5.0
_E_MAX = 1.0e6  # a class value beyond this means the errors are meaningless
_MIN_N = 2


def _e_tolerance(criterion: str, d: float) -> float:
    """δ of a criterion in class E(d) (the calculation sheet's extension of the table)."""
    if criterion == "gross_weight":
        return d
    if criterion == "group_of_axles":
        return 1.1 * d
    if criterion == "single_axle":
        return 1.2 * d
    return 1.2 * d + 5.0


def _e_value(criterion: str, delta: float) -> float:
    """Inverse of :func:`_e_tolerance`: the class value d whose δ is ``delta``."""
    if criterion == "gross_weight":
        return delta
    if criterion == "group_of_axles":
        return delta / 1.1
    if criterion == "single_axle":
        return delta / 1.2
    return (delta - 5.0) / 1.2


def _class_name(value: float) -> str:
    for name, v in CLASSES:
        if value == v:
            return f"{name}({v:g})"
    return f"E({value:g})"


def _criterion(name: object) -> str:
    return require_choice("criterion", name, CRITERIA)


def _repeatability(name: object) -> str:
    if isinstance(name, str):
        for key in REPEATABILITIES:
            if name.strip().lower() == key.lower():
                return key
    return require_choice("repeatability", name, REPEATABILITIES)


def _environment(name: object) -> str:
    if isinstance(name, str) and name.strip().upper() in ENVIRONMENTS:
        return name.strip().upper()
    return require_choice("environment", name, ENVIRONMENTS)


def _sample_size(n: object) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer):
        raise InputError(f"n must be an integer, got {n!r}")
    if n < _MIN_N:
        raise InputError(f"n must be at least {_MIN_N} (a standard deviation needs two "
                         f"values), got {n}")
    return int(n)


def class_tolerance(criterion: str, class_name: str) -> float:
    """Tolerance δ (%) of ``criterion`` in a class: ``"B+"``, ``"B+(7)"``, ``"E(35)"`` …"""
    crit = _criterion(criterion)
    text = class_name.strip() if isinstance(class_name, str) else ""
    for (name, value), delta in zip(CLASSES, TOLERANCES[crit], strict=True):
        if text in (name, _class_name(value)):
            return delta
    if text.startswith("E(") and text.endswith(")"):
        try:
            d = float(text[2:-1])
        except ValueError:
            d = math.nan
        if _E_START <= d <= _E_MAX and d % _E_STEP == 0:
            return _e_tolerance(crit, d)
    names = ", ".join(name for name, _ in CLASSES)
    raise InputError(f"unknown class_name {class_name!r}; expected one of {names} or E(d) "
                     f"with d = 30, 35, …")


def relative_errors(measured, reference) -> np.ndarray:
    """Relative errors ``100 (measured − reference) / reference``, per cent.

    Parameters
    ----------
    measured, reference : array_like, same shape
        WIM and static values (any one unit); every reference value positive.
    """
    m = np.asarray(measured, dtype=float)
    r = np.asarray(reference, dtype=float)
    if m.shape != r.shape:
        raise InputError(f"measured and reference must have the same shape, got {m.shape} "
                         f"and {r.shape}")
    if not np.all(np.isfinite(m)):
        raise InputError("measured must be finite")
    if not np.all(np.isfinite(r)) or np.any(r <= 0.0):
        raise InputError("reference must be finite and positive")
    return 100.0 * (m - r) / r


def _t975(n: int) -> float:
    from scipy import stats  # here: importing scipy.stats takes most of a second

    return float(stats.t.ppf(0.975, n - 1))


def min_confidence(n: int, repeatability: str = "RR2", environment: str = "I") -> float:
    """π₀: minimum level of confidence required of ``n`` values (probability in (0, 1)).

    ``2 Φ(u/k − t₀.₉₇₅,ₙ₋₁/√n) − 1`` with u of ``repeatability`` (r1, r2, RR1, RR2) and k
    of ``environment`` (I, II, III).
    """
    n = _sample_size(n)
    u = REPEATABILITIES[_repeatability(repeatability)]
    k = ENVIRONMENTS[_environment(environment)]
    from scipy import stats

    return float(2.0 * stats.norm.cdf(u / k - _t975(n) / math.sqrt(n)) - 1.0)


def _ratio(num: float, den: float) -> float:
    if den > 0.0:
        return num / den
    return math.copysign(math.inf, num) if num != 0.0 else 0.0


def confidence_level(delta: float, mean: float, std: float, n: int) -> float:
    """π: level of confidence of the interval [−δ, δ] for n errors of mean m and std s.

    ``1 − T̄(δ/s − m/s − t/√n) − T̄(δ/s + m/s − t/√n)`` with T̄ the upper tail of Student's
    distribution with n − 1 degrees of freedom and t = t₀.₉₇₅,ₙ₋₁.  ``delta``, ``mean``
    and ``std`` in per cent; ``std`` ≥ 0 (0 gives the limit s → 0⁺).
    """
    n = _sample_size(n)
    d = require_finite("delta", delta)
    m = require_finite("mean", mean)
    s = require_finite("std", std)
    if d < 0.0 or s < 0.0:
        raise InputError(f"delta and std must be non-negative, got {d:g} and {s:g}")
    from scipy import stats

    c = _t975(n) / math.sqrt(n)
    dof = n - 1
    return float(1.0 - stats.t.sf(_ratio(d - m, s) - c, dof)
                 - stats.t.sf(_ratio(d + m, s) - c, dof))


def _delta_min(mean: float, std: float, n: int, pi0: float) -> float:
    """The δ at which π(δ) = π₀ (π increases with δ)."""

    def gap(delta: float) -> float:
        return confidence_level(delta, mean, std, n) - pi0

    if gap(0.0) >= 0.0:
        return 0.0
    hi = abs(mean) + 10.0 * std + 1.0
    while gap(hi) < 0.0:
        hi *= 2.0
        if hi > _E_MAX:
            raise InputError(f"errors too large to classify (mean {mean:g} %, std {std:g} %)")
    from scipy import optimize

    return float(optimize.brentq(gap, 0.0, hi, xtol=1e-10, rtol=1e-12))


@dataclass(frozen=True, kw_only=True)
class CriterionResult:
    """COST 323 test of one criterion.

    Attributes
    ----------
    name : str
        Criterion key (:data:`CRITERIA`).
    n : int
        Number of values (vehicles, groups or axles).
    mean, std : float
        Mean and standard deviation (ddof = 1) of the relative errors, %.
    pi0 : float
        Minimum level of confidence π₀ for n values (probability).
    delta_min : float
        Tolerance at which π = π₀ exactly, % (the best tolerance the data support).
    class_name : str
        ``"A(5)"`` … ``"D(25)"`` or ``"E(d)"``.
    class_value : float
        The class's gross-weight tolerance d, % (5, 7, 10, 15, 20, 25, 30, 35, …).
    delta : float
        This criterion's tolerance in that class, %.
    pi : float
        Level of confidence π of [−δ, δ] (≥ pi0).
    """

    name: str
    n: int
    mean: float
    std: float
    pi0: float
    delta_min: float
    class_name: str
    class_value: float
    delta: float
    pi: float

    @property
    def label(self) -> str:
        """The criterion as printed ("gross weight", …)."""
        return CRITERIA[self.name]


def classify_statistics(*, n: int, mean: float, std: float, criterion: str,
                        repeatability: str = "RR2", environment: str = "I") -> CriterionResult:
    """Class of one criterion from the number, mean and std (%) of its relative errors."""
    crit = _criterion(criterion)
    rep = _repeatability(repeatability)
    env = _environment(environment)
    n = _sample_size(n)
    m = require_finite("mean", mean)
    s = require_finite("std", std)
    if s < 0.0:
        raise InputError(f"std must be non-negative, got {s:g}")
    pi0 = min_confidence(n, rep, env)
    if pi0 <= 0.0:
        raise InputError(f"n = {n} values are too few for test {rep}, environment {env} "
                         f"(pi0 = {100 * pi0:.0f} % ≤ 0): no class can be given")
    dmin = _delta_min(m, s, n, pi0)
    passing = [(value, delta, confidence_level(delta, m, s, n))
               for (_, value), delta in zip(CLASSES, TOLERANCES[crit], strict=True)]
    passing = [c for c in passing if c[2] >= pi0]
    if passing:
        value, delta, pi = passing[0]
    else:  # class E: the smallest d = 30, 35, … whose tolerance passes
        value = max(_E_START, _E_STEP * math.ceil(_e_value(crit, dmin) / _E_STEP - 1e-9))
        while True:
            delta = _e_tolerance(crit, value)
            pi = confidence_level(delta, m, s, n)
            if pi >= pi0:
                break
            value += _E_STEP
            if value > _E_MAX:
                raise InputError(f"errors too large to classify (mean {m:g} %, std {s:g} %)")
    return CriterionResult(name=crit, n=n, mean=m, std=s, pi0=pi0, delta_min=dmin,
                           class_name=_class_name(value), class_value=float(value),
                           delta=float(delta), pi=pi)


def classify(errors_pct, criterion: str, repeatability: str = "RR2",
             environment: str = "I") -> CriterionResult:
    """Class of one criterion from its relative errors (%, e.g. :func:`relative_errors`)."""
    e = np.asarray(errors_pct, dtype=float)
    if e.ndim != 1:
        raise InputError(f"errors_pct must be one-dimensional, got shape {e.shape}")
    if not np.all(np.isfinite(e)):
        raise InputError("errors_pct must be finite")
    if e.size < _MIN_N:
        raise InputError(f"errors_pct needs at least {_MIN_N} values, got {e.size}")
    return classify_statistics(n=int(e.size), mean=float(e.mean()), std=float(e.std(ddof=1)),
                               criterion=criterion, repeatability=repeatability,
                               environment=environment)


# --- rows of the summary (WIM) and of the reference (static weighing) -----------------------


def _float_tuple(name: str, values, *, positive: bool) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a sequence of numbers, got {values!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise InputError(f"{name} must be finite, got {list(out)}")
    if positive and any(v <= 0.0 for v in out):
        raise InputError(f"{name} must be positive, got {list(out)}")
    return out


def _count(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _record_name(value) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InputError(f"record must be a non-empty name (or give the time), got {value!r}")
    return value.strip()


@dataclass(frozen=True, kw_only=True)
class ReferenceRow:
    """One statically weighed vehicle (a row of the reference file).

    Attributes
    ----------
    record : str
        The record (event file) in which the vehicle crossed; empty when ``time`` says
        when it crossed instead.
    gvw : float
        Static gross vehicle weight, N (> 0).
    axle_weights : tuple of float
        Static axle weights, N (> 0), one per axle; empty when only the gross weight is
        known.
    axle_spacings : tuple of float
        m (> 0), one fewer than the axles; empty when unknown (the axles are then grouped
        by the WIM system's measured spacings).
    speed : float or None
        m/s, when known.
    vehicle : int or None
        Which vehicle of the record (the summary's ``vehicle``, from 1); None: the
        record's one vehicle (see :func:`assess`).
    lane : int or None
        The vehicle's lane, when known (it picks the vehicle of a record with several).
    time : datetime, time or None
        When the vehicle crossed (the site's local time, as the summary's ``time``: a date
        and time, or a time of day; a UTC offset is dropped, the local time kept as
        written, as the loggers' clocks are read); with an empty ``record`` the vehicle
        is matched by it (see :func:`assess`).
    """

    record: str = ""
    gvw: float
    axle_weights: tuple[float, ...] = ()
    axle_spacings: tuple[float, ...] = ()
    speed: float | None = None
    vehicle: int | None = None
    lane: int | None = None
    time: datetime | dtime | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if self.time is not None:
            if not isinstance(self.time, datetime | dtime):
                raise InputError(f"time must be a datetime or a time, got {self.time!r}")
            if self.time.tzinfo is not None:  # the local time as written (as the clocks)
                set_(self, "time", self.time.replace(tzinfo=None))
        if self.time is None or (isinstance(self.record, str) and self.record.strip()):
            set_(self, "record", _record_name(self.record))
        elif not isinstance(self.record, str):
            raise InputError(f"record must be a name, got {self.record!r}")
        else:
            set_(self, "record", "")
            if self.vehicle is not None:
                raise InputError(f"vehicle {self.vehicle} needs a record (a vehicle matched "
                                 "by time has none)")
        set_(self, "gvw", require_positive("gvw", self.gvw))
        set_(self, "axle_weights", _float_tuple("axle_weights", self.axle_weights,
                                                positive=True))
        set_(self, "axle_spacings", _float_tuple("axle_spacings", self.axle_spacings,
                                                 positive=True))
        if not self.axle_weights and self.axle_spacings:
            raise InputError(f"{self._who}: axle spacings without axle weights")
        if self.axle_spacings and len(self.axle_spacings) != len(self.axle_weights) - 1:
            raise InputError(
                f"{self._who}: {len(self.axle_weights)} axle weights need "
                f"{len(self.axle_weights) - 1} axle spacings, got {len(self.axle_spacings)}")
        if self.speed is not None:
            set_(self, "speed", require_finite("speed", self.speed))
        if self.vehicle is not None:
            set_(self, "vehicle", _count("vehicle", self.vehicle))
        if self.lane is not None:
            set_(self, "lane", _count("lane", self.lane))

    @property
    def n_axles(self) -> int | None:
        """Axles (None when only the gross weight is known)."""
        return len(self.axle_weights) or None

    @property
    def _who(self) -> str:
        return f"record {self.record}" if self.record else f"the vehicle at {self.label}"

    @property
    def label(self) -> str:
        """How the notes name it: ``RECORD`` (``RECORD#VEHICLE``), or its time (and lane)
        when it has no record."""
        if self.record:
            return self.record if self.vehicle is None else f"{self.record}#{self.vehicle}"
        return _time_text(self.time) + ("" if self.lane is None else f" lane {self.lane}")


# --- result ----------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class AccuracyResult:
    """COST 323 accuracy assessment of a WIM test.

    Attributes
    ----------
    criteria : tuple of CriterionResult
        The criteria assessed, in the order of :data:`CRITERIA`.
    skipped : tuple of str
        Criteria not assessed: too few values for π₀ > 0 (e.g. no axle groups).
    overall_class : str or None
        The worst class of ``criteria`` (None when nothing was assessed).
    overall_value : float
        Its gross-weight tolerance, % (NaN when nothing was assessed).
    repeatability, environment : str
        Test conditions (``"RR2"``, ``"I"`` …).
    n_reference : int
        Reference rows (statically weighed vehicles).
    n_vehicles : int
        Reference vehicles the system weighed (values of the gross-weight criterion).
    missing : tuple of str
        Reference vehicles present in the summary without a gross weight (not weighed).
    unmatched : tuple of str
        Reference records absent from the summary (vehicles given by time: no summary row
        within the time tolerance).
    ambiguous : tuple of str
        Reference vehicles given by time that more than one summary row could be (within
        the time tolerance, in the lane and of the axle count given), or whose one row
        another reference also takes: not matched, not assessed.
    axle_mismatch : tuple of str
        Weighed vehicles whose axle count (or axle weights) disagree with the reference:
        in the gross-weight criterion, excluded from the axle criteria.
    n_unreferenced : int
        Summary records without a reference (traffic not statically weighed).
    group_spacing : float
        Spacing below which axles form a group, m.
    """

    criteria: tuple[CriterionResult, ...]
    skipped: tuple[str, ...]
    overall_class: str | None
    overall_value: float
    repeatability: str
    environment: str
    n_reference: int
    n_vehicles: int
    missing: tuple[str, ...]
    unmatched: tuple[str, ...]
    axle_mismatch: tuple[str, ...]
    n_unreferenced: int
    group_spacing: float
    ambiguous: tuple[str, ...] = ()

    @property
    def n_missing(self) -> int:
        """Reference vehicles in the summary but not weighed."""
        return len(self.missing)

    @property
    def identified(self) -> float:
        """Fraction of the reference vehicles found in the summary that were weighed."""
        seen = self.n_vehicles + self.n_missing
        return self.n_vehicles / seen if seen else math.nan

    def criterion(self, name: str) -> CriterionResult:
        """The result of one criterion (InputError if it was not assessed)."""
        for c in self.criteria:
            if c.name == name:
                return c
        raise InputError(f"criterion {name!r} was not assessed; assessed: "
                         f"{', '.join(c.name for c in self.criteria) or 'none'}")

    def table(self) -> Table:
        """One row per criterion (skipped ones too); :meth:`notes` tells what was left out."""
        header = ("criterion", "n", "mean %", "std %", "pi0 %", "delta_min %", "class",
                  "delta %", "pi %")
        rows = []
        for name, label in CRITERIA.items():
            c = next((c for c in self.criteria if c.name == name), None)
            if c is None:
                rows.append((label, "too few", *("-",) * 7))
            else:
                rows.append((label, str(c.n), f"{c.mean:.2f}", f"{c.std:.2f}",
                             f"{100 * c.pi0:.1f}", f"{c.delta_min:.2f}", c.class_name,
                             f"{c.delta:g}", f"{100 * c.pi:.1f}"))
        title = (f"COST 323 accuracy: overall class {self.overall_class or 'none'} "
                 f"(test {self.repeatability}, environment {self.environment})")
        if self.skipped and self.overall_class:  # a class of some criteria only: say so
            title += ", of " + ", ".join(CRITERIA[c.name] for c in self.criteria) + " only"
        return Table(title=title, header=header, rows=tuple(rows))

    def notes(self) -> tuple[str, ...]:
        """Lines on the vehicles weighed and the records left out of the criteria."""
        notes = [f"{self.n_vehicles} of {self.n_reference} reference vehicles weighed"]
        for what, names in (("not weighed", self.missing),
                            ("absent from the summary", self.unmatched),
                            ("more than one vehicle they may be, or one another reference "
                             "takes (give the lane, the vehicle, or a smaller time "
                             "tolerance): not assessed", self.ambiguous),
                            ("axle count differs (axle criteria exclude them)",
                             self.axle_mismatch)):
            if names:
                shown = ", ".join(names[:10]) + (", …" if len(names) > 10 else "")
                notes.append(f"{len(names)} {what}: {shown}")
        if self.n_unreferenced:
            notes.append(f"{self.n_unreferenced} summary records without a reference ignored")
        return tuple(notes)

    def render(self) -> str:
        """The table and its notes as text."""
        return "\n".join([self.table().render(), *self.notes()])


def _time_text(t: datetime | dtime | None) -> str:
    if t is None:
        return ""
    return t.isoformat(timespec="seconds" if t.microsecond == 0 else "milliseconds")


def _seconds_apart(a: datetime | dtime, b: datetime | dtime) -> float:
    """|a − b| in s: as instants when both have a date, else as times of day (the
    shorter way round midnight)."""
    if isinstance(a, datetime) and isinstance(b, datetime):
        return abs((a - b).total_seconds())  # both naive (SummaryRow, ReferenceRow)
    d = abs(seconds_of_day(a) - seconds_of_day(b)) % 86400.0
    return min(d, 86400.0 - d)


def _references(rows: Sequence[ReferenceRow]) -> dict[tuple[str, int | None], ReferenceRow]:
    out: dict[tuple[str, int | None], ReferenceRow] = {}
    for r in rows:
        if not isinstance(r, ReferenceRow):
            raise InputError(f"reference rows must be ReferenceRow, got {type(r).__name__}")
        key = (r.record, r.vehicle) if r.record else ("", (r.time, r.lane))
        if key in out:
            if not r.record:
                raise InputError(f"reference rows name the vehicle at {r.label} twice")
            which = "" if r.vehicle is None else f" vehicle {r.vehicle}"
            raise InputError(f"reference rows name record {r.record!r}{which} twice")
        out[key] = r
    return out


def _summaries(rows: Sequence[SummaryRow]) -> dict[str, list[SummaryRow]]:
    out: dict[str, list[SummaryRow]] = {}
    seen: set[tuple[str, int]] = set()
    for r in rows:
        if not isinstance(r, SummaryRow):
            raise InputError(f"summary rows must be SummaryRow, got {type(r).__name__}")
        if r.key in seen:
            raise InputError(f"summary rows name record {r.record!r} vehicle {r.vehicle} "
                             "twice")
        seen.add(r.key)
        out.setdefault(r.record, []).append(r)
    return out


def _match(ref: ReferenceRow, rows: list[SummaryRow] | None) -> list[SummaryRow]:
    """The summary rows of its record a reference vehicle may be (see :func:`assess`):
    its vehicle's when it names one; else those in its lane (rows without a lane
    included), and among several those of its axle count."""
    if not rows:
        return []
    if ref.vehicle is not None:
        return [r for r in rows if r.vehicle == ref.vehicle][:1]
    if ref.lane is not None:
        rows = [r for r in rows if r.lane is None or r.lane == ref.lane]
    if len(rows) > 1 and ref.n_axles is not None:
        return [r for r in rows if r.n_axles == ref.n_axles] or rows
    return rows


def _by_time(ref: ReferenceRow, rows: Sequence[SummaryRow], tolerance: float
             ) -> list[SummaryRow]:
    """The summary rows a reference given by time may be (see :func:`assess`)."""
    near = [r for r in rows if r.time is not None
            and (ref.lane is None or r.lane == ref.lane)
            and _seconds_apart(r.time, ref.time) <= tolerance]
    if len(near) > 1 and ref.n_axles is not None:
        return [r for r in near if r.n_axles == ref.n_axles] or near
    return near


def _matches(summary: dict[str, list[SummaryRow]], reference: dict, tolerance: float
             ) -> tuple[dict, list]:
    """Each reference's summary row (None: unmatched) and the keys of those given by time
    that are ambiguous."""
    timed = [r for rows in summary.values() for r in rows if r.time is not None]
    found: dict = {}
    ambiguous: list = []
    claims: dict[tuple[str, int], int] = {}
    named: dict[tuple[str, int], int] = {}  # the claims of references by record
    for key, ref in reference.items():
        near = (_match(ref, summary.get(ref.record)) if ref.record
                else _by_time(ref, timed, tolerance))
        found[key] = near[0] if len(near) == 1 else None
        if len(near) > 1:
            ambiguous.append(key)
        elif near:
            claims[near[0].key] = claims.get(near[0].key, 0) + 1
            if ref.record:
                named[near[0].key] = named.get(near[0].key, 0) + 1
    for key, ref in reference.items():  # one row, another reference's too: a record
        row = found[key]  # keeps it against references by time, not against another
        if row is not None and (named.get(row.key, 0) if ref.record
                                else claims[row.key]) > 1:
            found[key] = None
            ambiguous.append(key)
    return found, ambiguous


@dataclass(frozen=True, kw_only=True, eq=False)
class ReferenceMatch:
    """A reference vehicle and its summary row (see :func:`assess`).

    Attributes
    ----------
    reference : ReferenceRow
    row : SummaryRow or None
        None: no summary row is it (``ambiguous``: more than one could be).
    ambiguous : bool
        A reference that more than one summary row could be, or whose one row another
        reference also takes.
    """

    reference: ReferenceRow
    row: SummaryRow | None
    ambiguous: bool = False


def _rows_given(name: str, rows) -> None:
    if rows is None or isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise InputError(f"{name} must be a sequence of rows, got {type(rows).__name__}")


def match_references(summary_rows: Sequence[SummaryRow],
                     reference_rows: Sequence[ReferenceRow], *, time_tolerance: float = 5.0
                     ) -> tuple[ReferenceMatch, ...]:
    """Each reference vehicle with its summary row, in the reference's order, by the
    matching rule of :func:`assess` (the one rule the report's figures use too)."""
    tolerance = require_positive("time_tolerance", time_tolerance)
    _rows_given("summary_rows", summary_rows)
    _rows_given("reference_rows", reference_rows)
    reference = _references(reference_rows)
    found, unclear = _matches(_summaries(summary_rows), reference, tolerance)
    return tuple(ReferenceMatch(reference=ref, row=found[key], ambiguous=key in unclear)
                 for key, ref in reference.items())


def assess(summary_rows: Sequence[SummaryRow], reference_rows: Sequence[ReferenceRow], *,
           repeatability: str = "RR2", environment: str = "I", group_spacing: float = 2.0,
           strict: bool = False, time_tolerance: float = 5.0) -> AccuracyResult:
    """COST 323 class of a WIM system from its summary and a static reference.

    Parameters
    ----------
    summary_rows : sequence of SummaryRow
        What the system reported, one row per record.
    reference_rows : sequence of ReferenceRow
        Statically weighed vehicles, one per record.
    repeatability : {"r1", "r2", "RR1", "RR2"}
        Test conditions.  The default, RR2 (full reproducibility), is the condition of a
        sample of vehicles taken from the traffic, each crossing once.
    environment : {"I", "II", "III"}
        The default, I (environmental repeatability), is a test over a short period (a
        day) in unchanged conditions; II spans days to weeks, III a year.
    group_spacing : float
        Consecutive axles closer than this (the REFERENCE spacings, m, or the summary's
        when the reference has none) form a group.
    strict : bool
        If True, a reference record absent from the summary is an InputError (a typo or
        the wrong summary), and so is a reference given by time that is ambiguous; if
        False they are reported in ``unmatched`` and ``ambiguous``.
    time_tolerance : float
        s: how far the time of a reference given by time (no record) may lie from its
        summary row's ``time`` (the vehicle's first axle at the gauges).

    Notes
    -----
    Matching: a reference names a record and, optionally, a vehicle of it (the summary's
    ``vehicle``); without one it is the record's summary row in the reference's lane
    (when given; rows without a lane count as in it), among several the one of the
    reference's axle count.  A reference without a record gives the time the vehicle
    crossed instead (a continuous recording's events are named by the trigger): its row
    is the summary row whose ``time`` lies within ``time_tolerance`` of it (as instants
    when both have a date, else as times of day), in the reference's lane when given;
    among several, those of the reference's axle count.  Still several, or one row that
    another reference also takes, is ambiguous: not matched, listed in ``ambiguous``
    (never a guess: a refused truck beside a weighed car is not the car).  A summary row without
    a gross weight counts as not weighed (``missing``), never silently dropped.  A weighed
    vehicle whose axle count differs from the reference, or whose axle weights are
    unknown, stays in the gross-weight criterion and is left out of the three axle
    criteria (``axle_mismatch``).  Summary rows without a reference are counted
    (``n_unreferenced``) and otherwise ignored.
    """
    rep = _repeatability(repeatability)
    env = _environment(environment)
    spacing = require_positive("group_spacing", group_spacing)
    tolerance = require_positive("time_tolerance", time_tolerance)
    _rows_given("summary_rows", summary_rows)
    _rows_given("reference_rows", reference_rows)
    summary_rows, reference_rows = list(summary_rows), list(reference_rows)
    summary = _summaries(summary_rows)
    if not reference_rows:
        raise InputError("reference_rows is empty")
    matches = match_references(summary_rows, reference_rows, time_tolerance=tolerance)
    ambiguous = [m.reference.label for m in matches if m.ambiguous]
    unmatched = tuple(m.reference.label for m in matches if m.row is None and not m.ambiguous)
    if strict and ambiguous:
        shown = ", ".join(ambiguous[:5]) + (", …" if len(ambiguous) > 5 else "")
        raise InputError(f"{len(ambiguous)} reference vehicle(s) match more than one "
                         f"summary row (by record, or by time within {tolerance:g} s), or "
                         f"one another reference takes: {shown}")
    if strict and unmatched:
        shown = ", ".join(unmatched[:5]) + (", …" if len(unmatched) > 5 else "")
        raise InputError(f"reference names {len(unmatched)} record(s) (or times) absent "
                         f"from the summary: {shown}")

    errors: dict[str, list[float]] = {name: [] for name in CRITERIA}
    missing: list[str] = []
    mismatch: list[str] = []
    n_vehicles = 0
    matched: set[tuple[str, int]] = set()
    for m in matches:
        ref, name, row = m.reference, m.reference.label, m.row
        if row is None:
            continue
        matched.add(row.key)
        if row.gvw is None:
            missing.append(name)
            continue
        n_vehicles += 1
        errors["gross_weight"].append(100.0 * (row.gvw - ref.gvw) / ref.gvw)
        if ref.n_axles is None:  # a gross weight only: no axle criteria
            continue
        if row.n_axles not in (None, ref.n_axles) or len(row.axle_weights) != ref.n_axles:
            mismatch.append(name)
            continue
        spacings = ref.axle_spacings or row.axle_spacings
        if len(spacings) != ref.n_axles - 1:  # nothing to group the axles by
            mismatch.append(name)
            continue
        wim = np.array(row.axle_weights)
        static = np.array(ref.axle_weights)
        for group in group_axles(np.array(spacings), spacing):
            idx = list(group)
            if len(idx) == 1:
                errors["single_axle"].append(float(relative_errors(wim[idx], static[idx])[0]))
            else:
                errors["group_of_axles"].append(
                    100.0 * (wim[idx].sum() - static[idx].sum()) / static[idx].sum())
                errors["axle_of_group"].extend(relative_errors(wim[idx], static[idx]).tolist())

    results = []
    skipped = []
    for name in CRITERIA:
        if len(errors[name]) < _MIN_N or min_confidence(len(errors[name]), rep, env) <= 0.0:
            skipped.append(name)
        else:
            results.append(classify(errors[name], name, rep, env))
    worst = max(results, key=lambda c: c.class_value, default=None)
    return AccuracyResult(
        criteria=tuple(results), skipped=tuple(skipped),
        overall_class=None if worst is None else worst.class_name,
        overall_value=math.nan if worst is None else worst.class_value,
        repeatability=rep, environment=env, n_reference=len(matches),
        n_vehicles=n_vehicles, missing=tuple(missing), unmatched=unmatched,
        ambiguous=tuple(ambiguous),
        axle_mismatch=tuple(mismatch),
        n_unreferenced=sum(1 for rows in summary.values() for r in rows
                           if r.key not in matched),
        group_spacing=spacing)
