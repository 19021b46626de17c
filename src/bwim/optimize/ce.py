"""Cross-Entropy minimisation with variance injection and sub-structuring.

Contract
--------
* :class:`CrossEntropy` minimises an objective over ℝⁿ through an ask/tell interface over
  whole populations (docs/theory.md §6; Dowling, OBrien & González 2012, §4).  The sampling
  distribution is independent normals N(m_i, σ_i²); each iteration draws ``population``
  trials, the caller evaluates them, and the mean and standard deviation of each
  parameter's elite trials become the next m_i, σ_i (optionally smoothed with the old
  ones).  The elite set is the ⌈ρk⌉ best trials, ρ = ``elite_fraction``, k = ``population``.
* Bounds are respected by truncated sampling (inverse-CDF of the normal truncated to
  [lo, hi]): no trial ever leaves the bounds, so the objective is never evaluated outside
  them.
* Convergence: the best objective of an iteration's population differs from the previous
  iteration's by at most ``tol·|previous| + atol``.  After each convergence but the last,
  variance is injected (Botev & Kroese): σ_i ← c_j·|m_i|, c_j = ``injection[j-1]`` for
  the j-th convergence (the last entry repeats; |m_i| is floored at the initial σ_i so
  that a mean near zero still gets variance); the comparison then restarts.  The run
  stops at the requested number of convergences, or at a stop criterion (evaluation
  budget, iteration limit, target value, collapsed spread); :meth:`CrossEntropy.should_stop`
  says so and :attr:`CrossEntropy.result` lists every reason that holds.
* The answer is the best trial ever evaluated (by the total objective), not the last mean.
* Sub-structured mode (``neighbours`` given, bool (n_parts, n_params)): ``tell`` takes the
  sub-objective values (k, n_parts); the total is their sum; each parameter's elite set is
  the union of the elite sets of its neighbouring parts (see
  :mod:`bwim.optimize.substructure`).
* NaN or ±inf objective values are failed evaluations: they rank last, never enter an
  elite set and never become the best trial (sub-structured: a non-finite part value is
  ranked last for that part, and a trial with any non-finite part has a non-finite
  total).  A parameter without a finite elite trial keeps its mean and σ.
* Randomness comes only from the ``seed`` (a NumPy Generator kept inside the object): the
  same seed gives the same run, and an optimiser pickled at any point and unpickled
  continues bit for bit as the uninterrupted run would (:func:`save_checkpoint`,
  :func:`load_checkpoint`).
* :func:`minimize_ce` runs the loop for a function, serially or in parallel
  (:func:`bwim.optimize.parallel.evaluate`), optionally checkpointing every iteration.

This module knows nothing about bridges.
"""

from __future__ import annotations

import math
import operator
import os
import pickle
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import ndtr, ndtri

from bwim.atomic import atomic_output
from bwim.errors import InputError, require_finite
from bwim.optimize.parallel import check_int, evaluate
from bwim.optimize.result import OptimizeResult
from bwim.optimize.substructure import (
    check_neighbours,
    elite_mask,
    masked_mean_std,
    parameter_elite_masks,
)

# The public names are listed once, in bwim.optimize.__all__ (which re-exports them).

#: Default variance-injection schedule c_1, c_2, …: σ_i ← c_j |m_i| after the j-th
#: convergence (the paper starts at 0.3 and decreases over successive convergences).
DEFAULT_INJECTION = (0.3, 0.1, 0.03, 0.01, 0.003, 0.001)


class StopReason(StrEnum):
    """Why a Cross-Entropy run stopped (several may hold at once)."""

    CONVERGED = "converged"
    """The requested number of convergences was reached."""
    TARGET = "target"
    """The best objective reached ``target``."""
    MAX_EVALS = "max_evals"
    """Another population would exceed the evaluation budget ``max_evals``."""
    MAX_ITER = "max_iter"
    """``max_iter`` iterations were done."""
    STD_COLLAPSED = "std_collapsed"
    """Every σ_i ≤ ``std_tol``·|m_i|: the distribution has collapsed to a point."""

    @property
    def success(self) -> bool:
        """Whether this reason is a normal end (converged, target reached or the
        distribution collapsed to a point, like ``xtol`` in SciPy) rather than a limit."""
        return self in (StopReason.CONVERGED, StopReason.TARGET, StopReason.STD_COLLAPSED)


_MESSAGES = {
    StopReason.CONVERGED: "the requested number of convergences was reached",
    StopReason.TARGET: "the objective reached the target",
    StopReason.MAX_EVALS: "the evaluation budget (max_evals) is spent",
    StopReason.MAX_ITER: "the iteration limit (max_iter) was reached",
    StopReason.STD_COLLAPSED: "the sampling distribution collapsed (std <= std_tol·|mean|)",
}


@dataclass(frozen=True, kw_only=True, eq=False)
class CEHistory:
    """Per-iteration record of a Cross-Entropy run (nit rows).

    Attributes
    ----------
    mean, std : numpy.ndarray, shape (nit, n_params)
        The distribution each iteration's population was drawn from (so an injection
        shows in the row after the convergence that triggered it).
    best : numpy.ndarray, shape (nit,)
        Best total objective of the iteration's population (inf if none was finite).
    best_ever : numpy.ndarray, shape (nit,)
        Best total objective of all trials up to and including the iteration.
    nfev : numpy.ndarray of int, shape (nit,)
        Cumulative number of evaluated trials after the iteration.
    converged : numpy.ndarray of bool, shape (nit,)
        Whether the iteration completed a convergence.
    """

    mean: np.ndarray
    std: np.ndarray
    best: np.ndarray
    best_ever: np.ndarray
    nfev: np.ndarray
    converged: np.ndarray


@dataclass(frozen=True, kw_only=True, eq=False)
class CEResult(OptimizeResult):
    """The state of a Cross-Entropy run, in :func:`scipy.optimize.minimize` vocabulary.

    Attributes
    ----------
    x : numpy.ndarray, shape (n_params,)
        Best trial evaluated so far (the initial mean before any evaluation).
    fun : float
        Its total objective (inf before any finite evaluation).
    fun_parts : numpy.ndarray, shape (n_parts,), or None
        Its sub-objective values (sub-structured runs only).
    nfev, nit : int
        Trials evaluated and iterations (populations) done.
    success : bool
        Whether the run stopped normally: it converged the requested number of times,
        reached the target, or its distribution collapsed to a point (not merely a
        budget or iteration limit).
    message : str
        A sentence saying why the run stopped (or that it is running).
    stop_reasons : tuple of StopReason
        Every stop criterion that holds (empty while the run goes on).
    history : CEHistory
        Per-iteration arrays.
    mean, std : numpy.ndarray, shape (n_params,)
        The current sampling distribution (after the last update and any injection).
    elite_std : numpy.ndarray, shape (n_params,)
        Spread (standard deviation) of each parameter over its last elite set, a measure
        of how well the parameter is determined; NaN before the first update.
    convergences : int
        Number of convergences so far.
    convergence_iterations : tuple of int
        The iterations (1-based) at which they happened.
    """

    fun_parts: np.ndarray | None
    stop_reasons: tuple[StopReason, ...]
    history: CEHistory
    mean: np.ndarray
    std: np.ndarray
    elite_std: np.ndarray
    convergences: int
    convergence_iterations: tuple[int, ...]

    def plot(self, ax=None, **kw):
        """Mean ± std of one parameter's sampling distribution per iteration
        (:func:`bwim.plots.calibration.plot_ce_convergence`; ``kw``: parameter, scale,
        label); returns the figure."""
        from bwim.plots.calibration import plot_ce_convergence

        return plot_ce_convergence(self, ax=ax, **kw)


def _vector(name: str, value: object, n: int) -> np.ndarray:
    """A float (n,) array from a scalar or an (n,) array_like."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number or an array of shape ({n},), "
                         f"got {value!r}") from None
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise InputError(f"{name} must be a number or an array of shape ({n},), "
                         f"got shape {arr.shape}")
    return arr.copy()


def _read_only(attr: str, doc: str) -> property:
    """A read-only property returning ``self.<attr>`` as it is (no copy)."""
    return property(operator.attrgetter(attr), doc=doc)


def _sample_truncated(rng: np.random.Generator, mean: np.ndarray, std: np.ndarray,
                      lo: np.ndarray, hi: np.ndarray, k: int) -> np.ndarray:
    """k draws of independent N(mean, std²) truncated to [lo, hi], shape (k, n).

    Inverse-CDF sampling, one uniform per entry; ``lo <= mean <= hi`` holds, so the
    truncation interval always contains the mode and Φ(a) ≤ ½ ≤ Φ(b).  Where the
    interval is narrower than 1e-3 σ the truncated density is uniform to within 1e-6 and
    is sampled as such (Φ cannot resolve it).  Entries with std = 0 are the mean.  The
    result is clipped to the bounds against rounding.
    """
    positive = std > 0
    s = np.where(positive, std, 1.0)
    a = (lo - mean) / s
    b = (hi - mean) / s
    pa, pb = ndtr(a), ndtr(b)
    # rng.random is in [0, 1) on a grid of 2**-53; the half-step shift makes it (0, 1)
    u = rng.random((k, mean.size)) + 2.0**-54
    narrow = (b - a) < 1e-3
    with np.errstate(invalid="ignore"):  # inf − inf in the unbounded, unused branch
        z = np.where(narrow, a + u * (b - a), ndtri(pa + u * (pb - pa)))
    z = np.clip(z, a, b)
    x = np.where(positive, mean + s * z, mean)
    return np.clip(x, lo, hi)


class CrossEntropy:
    """Cross-Entropy minimiser with an ask/tell interface over whole populations.

    Parameters
    ----------
    mean : array_like, shape (n_params,)
        Initial mean m (the starting guess).
    std : float or array_like, shape (n_params,), optional
        Initial standard deviations σ (> 0); default 0.3·|mean| (the paper's choice), which
        needs every mean non-zero.
    population : int
        Trials per iteration, k (≥ 2).
    elite_fraction : float
        ρ in (0, 1]; the elite set is the ⌈ρk⌉ best trials (per part when sub-structured).
    bounds : (lo, hi) or None
        Lower and upper bounds, each a number or an (n_params,) array, lo < hi (±inf
        allowed); the initial mean must lie within them.  Trials never leave them.
    seed : int, numpy.random.SeedSequence, numpy.random.Generator or None
        Source of randomness (``numpy.random.default_rng(seed)``).  A Generator is used
        and advanced as given.
    neighbours : array_like of bool, shape (n_parts, n_params), or None
        Sub-structured mode: ``neighbours[j, i]`` is True when part j of the objective
        depends strongly on parameter i.  Then :meth:`tell` takes (k, n_parts) values.
    smoothing : float or (float, float)
        Weights (α, β) in (0, 1] of the new elite statistics:
        m ← α m_elite + (1−α) m, σ ← β σ_elite + (1−β) σ.  A single number is used for
        both; 1 (the default, as in the paper) means no smoothing.
    tol, atol : float
        Convergence when the iteration's best objective b_t satisfies
        ``|b_t − b_{t−1}| <= tol·|b_{t−1}| + atol`` (both iterations after the last
        injection).  Default: 2.5 % relative, as in the paper.
    convergences : int
        Number of convergences after which the run stops (≥ 1).
    injection : sequence of float
        Variance-injection schedule (c_1, c_2, …), each > 0: after the j-th convergence
        (j < ``convergences``) σ_i ← c_j·max(|m_i|, σ⁰_i), σ⁰ the initial ``std`` (the
        paper's c_j·|m_i| for any parameter that has not shrunk below its initial spread;
        the floor keeps variance in a parameter whose mean passes near zero).  When there
        are more convergences than entries the last entry repeats.  Default
        ``(0.3, 0.1, 0.03, 0.01, 0.003, 0.001)``.
    injection_scale : float or array_like, shape (n_params,), optional
        Reference magnitude of each parameter for injection (> 0), replacing
        max(|m_i|, σ⁰_i): σ_i ← c_j·``injection_scale``.
    max_evals : int or None
        Evaluation budget: the run stops when another population would exceed it, so
        ``nfev <= max_evals`` (≥ ``population``).
    max_iter : int or None
        Maximum number of iterations (default 1000).
    target : float or None
        Stop as soon as the best objective is ≤ ``target``.
    std_tol : float
        The run stops when every σ_i ≤ ``std_tol``·|m_i| after the update and any
        injection (default 1e-12).

    Notes
    -----
    One iteration: ``X = opt.ask()``; evaluate every row; ``opt.tell(X, values)``.  Values
    that are NaN or ±inf count as failures (ranked last).  ``ask`` and ``tell`` raise
    :class:`~bwim.errors.InputError` once :meth:`should_stop` is True.

    References
    ----------
    Dowling, J., OBrien, E. J. & González, A. (2012). Adaptation of Cross Entropy
    optimisation to a dynamic Bridge WIM calibration problem. *Engineering Structures* 44,
    13–22, §4 and §4.1.  Botev, Z. & Kroese, D. P. (2004). Global likelihood optimization
    via the cross-entropy method with an application to mixture models.  Proc. Winter
    Simulation Conference (variance injection).
    """

    def __init__(
        self,
        mean: object,
        std: object = None,
        *,
        population: int = 200,
        elite_fraction: float = 0.05,
        bounds: tuple[object, object] | None = None,
        seed: object = None,
        neighbours: object = None,
        smoothing: float | tuple[float, float] = 1.0,
        tol: float = 0.025,
        atol: float = 0.0,
        convergences: int = 5,
        injection: Sequence[float] = DEFAULT_INJECTION,
        injection_scale: object = None,
        max_evals: int | None = None,
        max_iter: int | None = 1000,
        target: float | None = None,
        std_tol: float = 1e-12,
    ) -> None:
        m = np.asarray(mean, dtype=float) if _is_numeric(mean) else None
        if m is None or m.ndim != 1 or m.size == 0:
            raise InputError(f"mean must be a non-empty 1-D array of numbers, got {mean!r}")
        if not np.all(np.isfinite(m)):
            raise InputError(f"mean must be finite, got {m.tolist()}")
        n = m.size
        if std is None:
            if np.any(m == 0):
                i = int(np.flatnonzero(m == 0)[0])
                raise InputError("std must be given when mean has zero entries (the default "
                                 f"0.3·|mean| would be 0 at index {i})")
            # docs/theory.md §6 step 1; Dowling et al. (2012) §4: σ = 0.3 × mean
            s = 0.3 * np.abs(m)
        else:
            s = _vector("std", std, n)
            if not np.all(np.isfinite(s) & (s > 0)):
                raise InputError(f"std must be finite and > 0, got {_show(std)}")
        self._population = check_int("population", population, 2)
        self._rho = _unit_weight("elite_fraction", elite_fraction)
        # docs/theory.md §6 step 4: the elite set is the ⌈ρk⌉ best trials (Dowling et al.
        # (2012) §4: ρ = 0.05), forgiving the rounding of ρ (0.05·200 is 10.000000000000002)
        self._n_elite = max(1, math.ceil(self._rho * self._population * (1.0 - 1e-12)))
        if bounds is None:
            lo, hi = np.full(n, -np.inf), np.full(n, np.inf)
        else:
            try:
                lo_in, hi_in = bounds
            except (TypeError, ValueError):
                raise InputError(f"bounds must be a pair (lo, hi), got {bounds!r}") from None
            lo, hi = _vector("bounds lo", lo_in, n), _vector("bounds hi", hi_in, n)
            if np.any(np.isnan(lo)) or np.any(np.isnan(hi)):
                raise InputError("bounds must not contain NaN")
            bad = np.flatnonzero(~(lo < hi))
            if bad.size:
                i = int(bad[0])
                raise InputError(f"bounds need lo < hi, got lo[{i}] = {lo[i]:g} >= "
                                 f"hi[{i}] = {hi[i]:g}")
            out = np.flatnonzero((m < lo) | (m > hi))
            if out.size:
                i = int(out[0])
                raise InputError(f"mean[{i}] = {m[i]:g} lies outside bounds "
                                 f"[{lo[i]:g}, {hi[i]:g}]")
        self._lo, self._hi = lo, hi
        if neighbours is None:
            self._neighbours = None
        else:
            self._neighbours = check_neighbours(neighbours, n)
        if np.ndim(smoothing) == 0:
            alpha = beta = smoothing
        else:
            try:
                alpha, beta = smoothing  # type: ignore[misc]
            except (TypeError, ValueError):
                raise InputError(f"smoothing must be a number or a pair (alpha, beta), "
                                 f"got {smoothing!r}") from None
        self._alpha = _unit_weight("smoothing alpha", alpha)
        self._beta = _unit_weight("smoothing beta", beta)
        self._tol = require_finite("tol", tol)
        self._atol = require_finite("atol", atol)
        if self._tol < 0 or self._atol < 0:
            raise InputError(f"tol and atol must be >= 0, got tol={tol!r}, atol={atol!r}")
        self._convergences = check_int("convergences", convergences, 1)
        try:
            inj = np.asarray(injection, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"injection must be a sequence of numbers, got {injection!r}") \
                from None
        if inj.ndim != 1 or inj.size == 0 or not np.all(np.isfinite(inj) & (inj > 0)):
            raise InputError(f"injection must be a non-empty sequence of factors > 0, "
                             f"got {_show(injection)}")
        self._injection = tuple(float(c) for c in inj)
        if injection_scale is None:
            self._injection_scale = None
        else:
            sc = _vector("injection_scale", injection_scale, n)
            if not np.all(np.isfinite(sc) & (sc > 0)):
                raise InputError(f"injection_scale must be finite and > 0, "
                                 f"got {_show(injection_scale)}")
            self._injection_scale = sc
        self._max_evals = None if max_evals is None else check_int(
            "max_evals", max_evals, self._population)
        self._max_iter = None if max_iter is None else check_int("max_iter", max_iter, 1)
        self._target = None if target is None else require_finite("target", target)
        self._std_tol = require_finite("std_tol", std_tol)
        if self._std_tol < 0:
            raise InputError(f"std_tol must be >= 0, got {std_tol!r}")

        if isinstance(seed, np.random.Generator):
            self._rng = seed
        else:
            try:
                self._rng = np.random.default_rng(seed)  # type: ignore[arg-type]
            except (TypeError, ValueError):
                raise InputError(f"seed must be None, an integer >= 0, a SeedSequence or a "
                                 f"Generator, got {seed!r}") from None
        self._mean = m.copy()
        self._std = s
        self._std0 = s.copy()
        self._x0 = m.copy()
        self._nfev = 0
        self._nit = 0
        self._best_x: np.ndarray | None = None
        self._best_fun = math.inf
        self._best_parts: np.ndarray | None = None
        self._elite_std = np.full(n, np.nan)
        self._previous: float | None = None
        self._conv_iters: list[int] = []
        self._stop: tuple[StopReason, ...] = ()
        self._h_mean: list[np.ndarray] = []
        self._h_std: list[np.ndarray] = []
        self._h_best: list[float] = []
        self._h_best_ever: list[float] = []
        self._h_nfev: list[int] = []
        self._h_converged: list[bool] = []

    # -- read-only properties --------------------------------------------------------
    population = _read_only("_population", "Trials per iteration, k.")
    n_elite = _read_only("_n_elite", "Elite set size ⌈ρk⌉ (per part when sub-structured).")
    neighbours = _read_only("_neighbours", "The neighbour map (n_parts, n_params), or None.")
    nfev = _read_only("_nfev", "Trials evaluated so far.")
    nit = _read_only("_nit", "Iterations (told populations) so far.")
    best_fun = _read_only("_best_fun",
                          "Total objective of :attr:`best_x` (inf before any finite evaluation).")

    @property
    def n_params(self) -> int:
        """Number of parameters."""
        return self._mean.size

    @property
    def n_parts(self) -> int | None:
        """Number of sub-objectives (None unless sub-structured)."""
        return None if self._neighbours is None else self._neighbours.shape[0]

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds, each (n_params,) (±inf where unbounded)."""
        return self._lo.copy(), self._hi.copy()

    @property
    def best_x(self) -> np.ndarray:
        """Best trial so far, (n_params,) (the initial mean before any evaluation); cheaper
        than ``result.x``."""
        return (self._x0 if self._best_x is None else self._best_x).copy()

    @property
    def mean(self) -> np.ndarray:
        """Current sampling mean, (n_params,)."""
        return self._mean.copy()

    @property
    def std(self) -> np.ndarray:
        """Current sampling standard deviations, (n_params,)."""
        return self._std.copy()

    # -- the loop --------------------------------------------------------------------
    def should_stop(self) -> bool:
        """Whether a stop criterion holds (see :attr:`result` ``.stop_reasons``)."""
        return bool(self._stop)

    def ask(self) -> np.ndarray:
        """Draw the next population from the current distribution.

        Returns
        -------
        numpy.ndarray, shape (population, n_params)
            Trials, each inside the bounds.
        """
        self._check_running("ask")
        # docs/theory.md §6 step 2: k trials from N(m_i, σ_i²), kept inside the bounds
        return _sample_truncated(self._rng, self._mean, self._std, self._lo, self._hi,
                                 self._population)

    def tell(self, X: object, values: object) -> None:
        """Update the distribution from an evaluated population.

        Parameters
        ----------
        X : array_like, shape (population, n_params)
            The trials (normally those returned by :meth:`ask`); finite and inside the
            bounds.
        values : array_like, shape (population,) or (population, n_parts)
            Objective values of the trials; (population, n_parts) sub-objective values in
            sub-structured mode (the total is their sum).  NaN/±inf mark failed trials.
        """
        self._check_running("tell")
        X, values = self._check_told(X, values)
        k = self._population
        if self._neighbours is None:
            totals = values
        else:
            with np.errstate(over="ignore", invalid="ignore"):
                totals = values.sum(axis=1)
        finite = np.isfinite(totals)
        self._h_mean.append(self._mean.copy())
        self._h_std.append(self._std.copy())
        self._nfev += k
        self._nit += 1

        best = math.inf
        if finite.any():
            i = int(np.argmin(np.where(finite, totals, np.inf)))
            best = float(totals[i])
            if best < self._best_fun:  # docs/theory.md §6 step 6: best trial of the run
                self._best_fun = best
                self._best_x = X[i].copy()
                self._best_parts = None if self._neighbours is None else values[i].copy()

        if self._neighbours is None:  # docs/theory.md §6 step 4: one elite set for all
            mask = np.broadcast_to(elite_mask(totals, self._n_elite), (self.n_params, k))
        else:
            # docs/theory.md §6, sub-structured CE; Dowling et al. (2012) §4.1 (Figure 3):
            # each parameter's elite set is the union of its neighbouring parts' elites
            mask = parameter_elite_masks(values, self._neighbours, self._n_elite)
        m_el, s_el, count = masked_mean_std(X, mask)
        have = count > 0
        self._elite_std = np.where(have, s_el, self._elite_std)
        # docs/theory.md §6 step 5: elite mean and standard deviation (optionally smoothed)
        new_m = self._alpha * m_el + (1.0 - self._alpha) * self._mean
        new_s = self._beta * s_el + (1.0 - self._beta) * self._std
        # a convex combination of points inside the bounds is inside; clip against rounding
        self._mean = np.where(have, np.clip(new_m, self._lo, self._hi), self._mean)
        self._std = np.where(have, new_s, self._std)

        converged = False
        if math.isfinite(best):
            prev = self._previous
            # docs/theory.md §6 step 7; Dowling et al. (2012) §4: the best objective changed
            # by less than the tolerance (2.5 %) since the previous iteration
            if prev is not None and abs(best - prev) <= self._tol * abs(prev) + self._atol:
                converged = True
                self._conv_iters.append(self._nit)
                self._previous = None
                if len(self._conv_iters) < self._convergences:
                    self._inject()
            else:
                self._previous = best
        else:
            self._previous = None

        self._h_best.append(best)
        self._h_best_ever.append(self._best_fun)
        self._h_nfev.append(self._nfev)
        self._h_converged.append(converged)
        self._stop = self._stop_reasons()

    def _inject(self) -> None:
        # docs/theory.md §6 step 7; Dowling et al. (2012) §4 (Botev & Kroese): variance
        # injection after the j-th convergence, σ_i = c_j |m_i| with c_j decreasing from 0.3
        j = min(len(self._conv_iters), len(self._injection)) - 1
        if self._injection_scale is None:
            scale = np.maximum(np.abs(self._mean), self._std0)
        else:
            scale = self._injection_scale
        self._std = self._injection[j] * scale

    def _stop_reasons(self) -> tuple[StopReason, ...]:
        reasons = []
        if len(self._conv_iters) >= self._convergences:
            reasons.append(StopReason.CONVERGED)
        if self._target is not None and self._best_fun <= self._target:
            reasons.append(StopReason.TARGET)
        if self._max_evals is not None and self._nfev + self._population > self._max_evals:
            reasons.append(StopReason.MAX_EVALS)
        if self._max_iter is not None and self._nit >= self._max_iter:
            reasons.append(StopReason.MAX_ITER)
        if np.all(self._std <= self._std_tol * np.abs(self._mean)):
            reasons.append(StopReason.STD_COLLAPSED)
        return tuple(reasons)

    def _check_running(self, what: str) -> None:
        if self._stop:
            names = ", ".join(r.value for r in self._stop)
            raise InputError(f"{what}() called after the optimiser stopped ({names}); "
                             "read .result, or start a new CrossEntropy")

    def _check_told(self, X: object, values: object) -> tuple[np.ndarray, np.ndarray]:
        k, n = self._population, self.n_params
        try:
            X = np.asarray(X, dtype=float)
            values = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise InputError("tell needs numeric arrays X and values") from None
        if X.shape != (k, n):
            raise InputError(f"X must have shape (population, n_params) = ({k}, {n}), "
                             f"got {X.shape}")
        if not np.all(np.isfinite(X)):
            raise InputError("X must be finite")
        out = np.flatnonzero(np.any((X < self._lo) | (X > self._hi), axis=0))
        if out.size:
            raise InputError(f"X leaves the bounds in parameter {int(out[0])}")
        want = (k,) if self._neighbours is None else (k, self._neighbours.shape[0])
        if values.shape != want:
            what = "(population,)" if self._neighbours is None else "(population, n_parts)"
            raise InputError(f"values must have shape {what} = {want}, got {values.shape}")
        return X.copy(), values.copy()

    # -- results ---------------------------------------------------------------------
    @property
    def history(self) -> CEHistory:
        """Per-iteration arrays of the run so far."""
        n = self.n_params
        return CEHistory(
            mean=np.array(self._h_mean).reshape(-1, n),
            std=np.array(self._h_std).reshape(-1, n),
            best=np.array(self._h_best, dtype=float),
            best_ever=np.array(self._h_best_ever, dtype=float),
            nfev=np.array(self._h_nfev, dtype=np.int64),
            converged=np.array(self._h_converged, dtype=bool),
        )

    @property
    def result(self) -> CEResult:
        """The best trial so far and the state of the run (readable at any time)."""
        reasons = self._stop
        if reasons:
            message = "; ".join(_MESSAGES[r] for r in reasons)
            message = message[0].upper() + message[1:] + "."
        elif self._nit == 0:
            message = "No population evaluated yet."
        else:
            message = "Running."
        x = self._x0 if self._best_x is None else self._best_x
        return CEResult(
            x=x.copy(),
            fun=self._best_fun,
            fun_parts=None if self._best_parts is None else self._best_parts.copy(),
            nfev=self._nfev,
            nit=self._nit,
            success=any(r.success for r in reasons),
            message=message,
            stop_reasons=reasons,
            history=self.history,
            mean=self._mean.copy(),
            std=self._std.copy(),
            elite_std=self._elite_std.copy(),
            convergences=len(self._conv_iters),
            convergence_iterations=tuple(self._conv_iters),
        )

    def __repr__(self) -> str:
        mode = "plain" if self._neighbours is None else f"{self.n_parts} parts"
        return (f"CrossEntropy(n_params={self.n_params}, population={self._population}, "
                f"{mode}, nit={self._nit}, nfev={self._nfev}, fun={self._best_fun:g})")


def _is_numeric(value: object) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


def _show(value: object) -> str:
    arr = np.asarray(value, dtype=float) if _is_numeric(value) else None
    return repr(value) if arr is None else str(arr.tolist())


def _unit_weight(name: str, value: object) -> float:
    v = require_finite(name, value)  # type: ignore[arg-type]
    if not 0.0 < v <= 1.0:
        raise InputError(f"{name} must lie in (0, 1], got {v:g}")
    return v


# -- checkpoints -----------------------------------------------------------------------
def save_checkpoint(opt: CrossEntropy, path: str | os.PathLike[str]) -> None:
    """Pickle an optimiser to ``path`` atomically.

    The state is written through :func:`bwim.atomic.atomic_output` (a temporary file in
    the same folder, flushed to disk and renamed over ``path``), so ``path`` always holds
    a complete checkpoint, the previous one or none, even if the process dies mid-write;
    an unwritable path is an :class:`~bwim.errors.InputError` naming it.
    """
    if not isinstance(opt, CrossEntropy):
        raise InputError(f"save_checkpoint needs a CrossEntropy, got {type(opt).__name__}")
    with atomic_output(path) as tmp, open(tmp, "wb") as f:
        pickle.dump(opt, f, protocol=pickle.HIGHEST_PROTOCOL)


def load_checkpoint(path: str | os.PathLike[str]) -> CrossEntropy:
    """Load an optimiser written by :func:`save_checkpoint`.

    Unpickling runs code from the file: load only checkpoints you wrote yourself.
    """
    with open(path, "rb") as f:
        opt = pickle.load(f)  # the caller's own checkpoint, see the docstring
    if not isinstance(opt, CrossEntropy):
        raise InputError(f"{os.fspath(path)!r} does not hold a CrossEntropy checkpoint")
    return opt


# -- the driver ------------------------------------------------------------------------
def minimize_ce(
    fun: Callable[..., Any],
    x0: object,
    std: object = None,
    *,
    args: Sequence[Any] = (),
    parts: bool = False,
    neighbours: object = None,
    vectorized: bool = False,
    n_jobs: int = 1,
    chunk_size: int | None = None,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
    callback: Callable[[CEResult], object] | None = None,
    **options: Any,
) -> CEResult:
    """Minimise ``fun`` by Cross-Entropy from ``x0``.

    Parameters
    ----------
    fun : callable
        ``fun(x, *args)`` → float for x (n_params,); with ``parts=True`` it returns the
        sub-objective values (n_parts,) whose sum is the objective.  With
        ``vectorized=True`` it takes a (m, n_params) chunk and returns (m,) or (m, n_parts).
    x0 : array_like, shape (n_params,)
        Initial mean.
    std : float or array_like, optional
        Initial standard deviations (default 0.3·|x0|).
    args : sequence
        Extra positional arguments of ``fun``.
    parts : bool
        Whether ``fun`` returns sub-objective values.  With ``neighbours`` the run is
        sub-structured; without, plain CE on their sum.
    neighbours : array_like of bool, shape (n_parts, n_params), optional
        Neighbour map for sub-structured CE (needs ``parts=True``).
    vectorized : bool
        Whether ``fun`` evaluates a chunk of trials at once.
    n_jobs, chunk_size, client
        Parallel evaluation, see :func:`bwim.optimize.parallel.evaluate` (serial by
        default; ``client`` is a ``dask.distributed.Client``).
    checkpoint : path, optional
        After every iteration the optimiser is saved here (atomically, see
        :func:`save_checkpoint`).  If the file exists when the call starts, the run
        resumes from it: its saved state and options govern, and a finished checkpoint
        returns its result at once.
    callback : callable, optional
        ``callback(result)`` after every iteration (e.g. a progress display); its return
        value is ignored.
    **options
        Further keyword arguments of :class:`CrossEntropy` (``population``,
        ``elite_fraction``, ``bounds``, ``seed``, ``smoothing``, ``tol``, ``convergences``,
        ``injection``, ``max_evals``, ``max_iter``, ``target``, …).

    Returns
    -------
    CEResult
    """
    if neighbours is not None and not parts:
        raise InputError("neighbours needs parts=True: sub-structured CE ranks trials by "
                         "each part of the objective")
    n_params = np.size(x0)
    opt: CrossEntropy | None = None
    if checkpoint is not None and Path(checkpoint).exists():
        opt = load_checkpoint(checkpoint)
        if opt.n_params != n_params or (opt.neighbours is None) != (neighbours is None):
            raise InputError(
                f"checkpoint {os.fspath(checkpoint)!r} holds a run with {opt.n_params} "
                f"parameters ({'plain' if opt.neighbours is None else 'sub-structured'}), "
                f"not this problem's {n_params} "
                f"({'plain' if neighbours is None else 'sub-structured'})"
            )
    if opt is None:
        opt = CrossEntropy(x0, std, neighbours=neighbours, **options)
    while not opt.should_stop():
        X = opt.ask()
        values = evaluate(fun, X, n_jobs=n_jobs, chunk_size=chunk_size, client=client,
                          vectorized=vectorized, args=args)
        if parts:
            if values.ndim != 2:
                raise InputError(f"with parts=True the objective must return (n_parts,) "
                                 f"values per trial, got values of shape {values.shape}")
            if neighbours is None:
                with np.errstate(over="ignore", invalid="ignore"):
                    values = values.sum(axis=1)
        opt.tell(X, values)
        if checkpoint is not None:
            save_checkpoint(opt, checkpoint)
        if callback is not None:
            callback(opt.result)
    return opt.result
