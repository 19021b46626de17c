"""Outlier runs of a multi-run calibration: which run is the worst, and why.

Contract
--------
* A run is rejected when its misfit (:attr:`~bwim.wim.multirun.RunFit.misfit`, residual
  in units of the channels' residual standard deviation) or its scale factor's departure
  from the other runs' trend over clock time (:func:`~bwim.wim.scale_trend.
  robust_departures`) stands out of the kept runs by the limits of an
  :class:`OutlierRule` (docs/theory.md §14).  Statistics are robust: median and
  ``1.4826 × MAD`` (median absolute deviation), the standard deviation of normal data.
* :func:`worst_run` names one run, the one most beyond its limit, with the reason; the
  caller removes it and recalibrates (one at a time: an outlier inflates the others'
  misfits).
* Runs carrying an upstream flag of ``OutlierRule.reject_flags`` (e.g. multiple
  presence) are rejected before fitting (:func:`upstream_rejections`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_finite, require_positive
from bwim.wim.scale_trend import robust_departures

__all__ = ["DEFAULT_OUTLIER_RULE", "OutlierRule", "Rejection", "run_flag_tuples",
           "upstream_rejections", "worst_run"]


@dataclass(frozen=True, kw_only=True)
class OutlierRule:
    """When a calibration run is rejected (the worst first, then recalibrate).

    Robust statistics over the kept runs: median and ``1.4826 × MAD`` (median absolute
    deviation), the standard deviation of normal data.

    Attributes
    ----------
    misfit : float
        Reject a run whose misfit (:attr:`~bwim.wim.multirun.RunFit.misfit`) exceeds the
        median by more than ``misfit`` robust standard deviations ...
    misfit_floor : float
        ... and is more than ``misfit_floor`` × the median (so that very uniform runs do
        not reject good ones).  A second vehicle on the bridge or a wrong passage shows
        here.
    scale : float
        Reject a run whose factor departs from the trend of the other runs' factors over
        clock time (local-linear as :class:`~bwim.wim.scale_trend.ScaleTrend`, bandwidth
        ``trend_bandwidth`` or two median spacings of the runs' times, bisquare robustness
        weights) by more than ``scale`` robust standard deviations of those departures ...
    scale_floor : float
        ... and by more than this relative amount.  A truck loaded differently, a second
        vehicle or a wrong speed shows here.
    reject_flags : tuple of str
        Runs carrying any of these upstream flags are rejected before fitting.
    min_runs : int
        Never keep fewer runs than this.
    """

    misfit: float = 5.0
    misfit_floor: float = 1.5
    scale: float = 4.0
    scale_floor: float = 0.03
    reject_flags: tuple[str, ...] = ("multiple_presence",)
    min_runs: int = 3

    def __post_init__(self) -> None:
        for name in ("misfit", "misfit_floor", "scale"):
            require_positive(f"OutlierRule.{name}", getattr(self, name))
        if require_finite("OutlierRule.scale_floor", self.scale_floor) < 0:
            raise InputError("OutlierRule.scale_floor must be >= 0")
        object.__setattr__(self, "reject_flags", tuple(str(f) for f in self.reject_flags))
        if int(self.min_runs) < 1:
            raise InputError(f"OutlierRule.min_runs must be >= 1, got {self.min_runs!r}")


#: The default rule of :func:`~bwim.wim.calibrate_lines`.
DEFAULT_OUTLIER_RULE = OutlierRule()


@dataclass(frozen=True, kw_only=True)
class Rejection:
    """One run rejected by :func:`worst_run`.

    Attributes
    ----------
    index : int
        The run (its index among all the runs given to the calibration).
    reason : str
        Which limit it exceeded, with the numbers.
    """

    index: int
    reason: str


def run_flag_tuples(run_flags: Sequence[Sequence[str] | str] | None,
                    n: int) -> list[tuple[str, ...]]:
    """Each of ``n`` runs' upstream flags as a tuple of str (``run_flags`` None: none; an
    entry may be one string or a sequence of them); InputError unless one entry per run."""
    if run_flags is None:
        return [()] * n
    flags = list(run_flags)
    if len(flags) != n:
        raise InputError(f"run_flags needs one entry per record ({n}), got {len(flags)}")
    out = []
    for f in flags:
        out.append((f,) if isinstance(f, str) else tuple(str(x) for x in (f or ())))
    return out


def upstream_rejections(flags: Sequence[tuple[str, ...]],
                        rule: OutlierRule) -> dict[int, str]:
    """``{run: reason}`` of the runs carrying one of ``rule.reject_flags``."""
    reasons: dict[int, str] = {}
    reject = set(rule.reject_flags)
    for k, f in enumerate(flags):
        hit = [x for x in f if x in reject]
        if hit:
            reasons[k] = f"flagged upstream: {', '.join(hit)}"
    return reasons


def worst_run(kept: Sequence[int], misfit: np.ndarray, scales: np.ndarray | None,
              times: np.ndarray, rule: OutlierRule,
              bandwidth: float | None) -> Rejection | None:
    """The kept run most beyond the rule's limits, with the reason (None if none is).

    ``misfit``, ``scales`` (None: no factor test) and ``times`` (clock, s) are the kept
    runs' (same order as ``kept``); ``bandwidth`` is the factor trend's (s; None: two
    median spacings).  The factor test needs at least 3 kept runs.  A run's severity is
    the largest ratio of a statistic to its limit; the worst run is returned if it
    exceeds 1.
    """
    med = float(np.median(misfit))
    rsd = 1.4826 * float(np.median(np.abs(misfit - med)))
    limit = max(med + rule.misfit * rsd, rule.misfit_floor * med)
    severity = misfit / limit if limit > 0 else np.zeros_like(misfit)
    # the numbers are those of the fit that rejects the run: the lines fitted again
    # without it give it another factor and misfit (its RunFit's), which the reason says
    why = [f"misfit {m:.3g} > {limit:.3g} against the lines of the runs kept then (median "
           f"{med:.3g} + {rule.misfit:g} robust sd {rsd:.3g}, and > {rule.misfit_floor:g} x "
           "median)" for m in misfit]
    if scales is not None and len(kept) >= 3:
        dev = robust_departures(times, scales, bandwidth)
        sd = 1.4826 * float(np.median(np.abs(dev)))
        lim = max(rule.scale * sd, rule.scale_floor)
        for i in range(len(kept)):
            sev = abs(dev[i]) / lim
            if sev > severity[i]:
                severity[i] = sev
                why[i] = (f"scale factor {scales[i]:.4g}, fitted with the runs kept then, "
                          f"departs {100 * dev[i]:+.1f} % from the runs' robust trend "
                          f"(limit {100 * lim:.1f} %)")
    i = int(np.argmax(severity))
    if severity[i] <= 1.0:
        return None
    return Rejection(index=kept[i], reason=why[i])
