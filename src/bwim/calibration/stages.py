"""``run_stage``: one calibration stage, by any of the three optimisers, with one result.

Contract
--------
* :func:`run_stage` minimises a calibration objective (:class:`~bwim.calibration.problem.
  StaticObjective` or :class:`~bwim.calibration.problem.DynamicObjective`) over the
  parameter vector of a :class:`~bwim.calibration.problem.ParameterSpace`, from the
  space's starting values inside a box of ``bounds`` factors of them, with

  - ``"ce"``: Cross-Entropy (:class:`~bwim.optimize.CrossEntropy`; sub-structured when
    given the ``neighbours`` map, on the objective's per-part misfits),
  - ``"lm"``: bounded least squares (``scipy.optimize.least_squares``, trust-region
    reflective) on the objective's residuals, with the objective's adjoint
    ``jacobian`` when it has one (the static objective) and finite differences otherwise,
  - ``"cma"``: CMA-ES (the ``cmaes`` package) on the summed misfit, in variables scaled
    by the starting values (initial step 0.3).

* Every method returns a frozen :class:`StageResult` in ``scipy.optimize`` vocabulary:
  ``x`` (parameters, SI), ``fun`` (the summed squared misfit at ``x``), ``nfev``
  (objective evaluations), ``nit`` (iterations; least squares: its own evaluation count,
  scipy's ``nfev``), ``success`` and ``message`` saying truthfully why it stopped: a
  spent evaluation budget is ``success=False``.
* ``uncertainty`` (same shape as ``x``) is the spread of the final elite set (CE), the
  standard error ``σ sqrt(diag((JᵀJ)⁻¹))`` (least squares), or NaN (CMA-ES, none).
* ``stop(x)`` (population methods) ends the stage after the first iteration whose best
  trial satisfies it (``success=True``).  ``seed`` is an int or a shared
  ``numpy.random.Generator``: CE draws from it, CMA-ES is seeded with the int itself or
  with one integer drawn from the Generator.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from enum import StrEnum

import numpy as np
from scipy.optimize import least_squares

from bwim.calibration.problem import ParameterSpace
from bwim.errors import InputError, parse_enum
from bwim.optimize import CrossEntropy, OptimizeResult
from bwim.optimize.parallel import evaluate

__all__ = ["MIN_ELITE", "SUBSTRUCTURED_SMOOTHING", "Method", "StageResult", "run_stage"]

#: (mean, std) smoothing of sub-structured CE (docs/theory.md §6): damping the spread's
#: update keeps the paper's settings from stopping early on the 48-parameter
#: near-linear-combination problem; measured by benchmarks/bench_optimize.py and guarded
#: by tests/validation/test_cross_entropy.py.
SUBSTRUCTURED_SMOOTHING = (1.0, 0.7)

#: Fewest elite trials per CE update: a spread needs several members (small populations
#: of the dynamic stage would otherwise keep one trial and collapse at once).
MIN_ELITE = 5

#: Residuals are divided by this (strain-sized) unit inside least squares.
_RESIDUAL_UNIT = 1e-6

_BUDGET_SPENT = "The evaluation budget (max_evals) is spent."
_STOP_MET = "The stop condition was met."


class Method(StrEnum):
    """Optimiser of a calibration stage."""

    CE = "ce"
    LM = "lm"
    CMA = "cma"


@dataclass(frozen=True, kw_only=True, eq=False)
class _Outcome(OptimizeResult):
    """What an optimiser's loop returns to :func:`run_stage` (which adds the stage's name,
    labels, start and wall time: :class:`StageResult`)."""

    uncertainty: np.ndarray
    history: object


@dataclass(frozen=True, kw_only=True, eq=False)
class StageResult(_Outcome):
    """One calibration stage (see module docstring): the optimiser's ``x, fun, nfev, nit,
    success, message, uncertainty, history`` and the stage's ``name, labels, start,
    wall_time``.

    ``history`` is the optimiser's per-iteration record: a
    :class:`~bwim.optimize.ce.CEHistory` for CE, the best objective after each
    evaluation (LM) or generation (CMA-ES) as an ndarray.
    """

    name: str
    labels: tuple[str, ...]
    start: np.ndarray
    wall_time: float

    def plot(self, ax=None, **kw):
        """CE convergence of one parameter (a CE stage only;
        :func:`bwim.plots.calibration.plot_ce_convergence`; ``kw``: parameter, scale,
        label); returns the figure."""
        from bwim.plots.calibration import plot_ce_convergence

        return plot_ce_convergence(self, ax=ax, **kw)


def run_stage(
    method: Method | str,
    objective,
    space: ParameterSpace,
    *,
    name: str = "stage",
    bounds: tuple[float, float] = (0.2, 5.0),
    seed: int | np.random.Generator | None = None,
    population: int | None = None,
    elite_fraction: float = 0.05,
    convergences: int = 3,
    max_evals: int | None = None,
    neighbours: np.ndarray | None = None,
    n_jobs: int = 1,
    client=None,
    callback: Callable[[str, int, float], None] | None = None,
    stop: Callable[[np.ndarray], bool] | None = None,
    options: dict | None = None,
) -> StageResult:
    """Minimise ``objective`` over ``space`` with one optimiser (see module docstring).

    Parameters
    ----------
    method : "ce", "lm" or "cma"
    objective : StaticObjective or DynamicObjective
        Called with a parameter vector: ``objective(θ)`` gives the per-part squared
        misfits, ``objective.residuals(θ)`` the weighted residuals and, when present,
        ``objective.jacobian(θ)`` their Jacobian.
    space : ParameterSpace
        The parameters; its starting values are the start (and the scale) of the search.
    name : str
        The stage's name (in the result and the callback).
    bounds : (float, float)
        Search box as factors of the starting values (low < 1 < high).
    seed : int or Generator, optional
        Randomness of the population methods.
    population : int, optional
        CE (default 200) or CMA-ES (default: cmaes' own) population.
    elite_fraction, convergences
        CE settings (elite fraction, at least :data:`MIN_ELITE` trials).
    max_evals : int, optional
        Evaluation budget (CE, CMA-ES: at least one population; LM: scipy's ``max_nfev``;
        CMA-ES default 200 populations).
    neighbours : bool array (n_parts, n_params), optional
        Sub-structured CE's neighbour map (:func:`~bwim.calibration.problem.
        neighbour_map`); None: plain CE on the summed misfit.
    n_jobs, client
        Parallel evaluation of populations (joblib workers or a dask client).
    callback : callable, optional
        ``callback(name, iteration, best_objective)`` after each iteration (LM: each
        evaluation).
    stop : callable, optional
        ``stop(best_x) -> bool``: end a population method early (not for LM).
    options : dict, optional
        Further options of the optimiser: :class:`~bwim.optimize.CrossEntropy` (CE),
        ``scipy.optimize.least_squares`` (LM) or ``cmaes.CMA`` (CMA-ES).
    """
    method = parse_enum(Method, method, "method")
    if not isinstance(space, ParameterSpace):
        raise InputError(f"space must be a ParameterSpace, got {type(space).__name__}")
    lo_f, hi_f = bounds
    if not 0 < lo_f < 1 < hi_f:
        raise InputError(f"bounds must be factors (low < 1 < high), got {bounds}")
    if stop is not None and method is Method.LM:
        raise InputError("stop ends a population method (ce, cma) early; least squares "
                         "runs to its own convergence")
    x0 = space.vector()
    box = (x0 * lo_f, x0 * hi_f)
    options = dict(options or {})
    t = time.perf_counter()
    if method is Method.CE:
        out = _ce(name, objective, x0, box, seed=seed, population=population or 200,
                  elite_fraction=elite_fraction, convergences=convergences,
                  max_evals=max_evals, neighbours=neighbours, n_jobs=n_jobs, client=client,
                  callback=callback, stop=stop, options=options)
    elif method is Method.LM:
        out = _lm(name, objective, x0, box, max_evals=max_evals, callback=callback,
                  options=options)
    else:
        out = _cma(name, objective, x0, box, seed=seed, population=population,
                   max_evals=max_evals, n_jobs=n_jobs, client=client, callback=callback,
                   stop=stop, options=options)
    return StageResult(name=name, labels=tuple(space.labels()), start=x0,
                       wall_time=time.perf_counter() - t,
                       **{f.name: getattr(out, f.name) for f in fields(_Outcome)})


def _ce(name, objective, x0, box, *, seed, population, elite_fraction, convergences,
        max_evals, neighbours, n_jobs, client, callback, stop, options) -> _Outcome:
    rho = min(1.0, max(elite_fraction, MIN_ELITE / population))
    opt = CrossEntropy(x0, population=population, elite_fraction=rho, bounds=box, seed=seed,
                       neighbours=neighbours, convergences=convergences,
                       max_evals=max_evals, **options)
    stopped = False
    while not opt.should_stop():
        X = opt.ask()
        V = evaluate(objective, X, n_jobs=n_jobs, client=client)
        opt.tell(X, V if neighbours is not None else V.sum(axis=1))
        if callback is not None:
            callback(name, opt.nit, opt.best_fun)
        if stop is not None and stop(opt.best_x):
            stopped = True
            break
    res = opt.result
    unc = np.where(np.isfinite(res.elite_std), res.elite_std, 0.0)
    return _Outcome(x=res.x, fun=res.fun, nfev=res.nfev, nit=res.nit,
                    success=True if stopped else res.success,
                    message=_STOP_MET if stopped else res.message, uncertainty=unc,
                    history=res.history)


def _lm(name, objective, x0, box, *, max_evals, callback, options) -> _Outcome:
    lo, hi = box
    trace: list[float] = []

    def fun(u):
        r = objective.residuals(u * x0)
        trace.append(float(np.sum(r**2)))
        if callback is not None:
            callback(name, len(trace), min(trace))
        return r / _RESIDUAL_UNIT

    jacobian = getattr(objective, "jacobian", None)
    jac = ("2-point" if jacobian is None
           else (lambda u: jacobian(u * x0) * x0[None, :] / _RESIDUAL_UNIT))
    settings = {"diff_step": 1e-4, "x_scale": 1.0, "method": "trf", **options}
    res = least_squares(fun, np.ones_like(x0), jac=jac, bounds=(lo / x0, hi / x0),
                        max_nfev=max_evals, **settings)
    dof = max(res.fun.size - x0.size, 1)
    sigma2 = 2 * res.cost / dof
    try:
        cov = np.linalg.pinv(res.jac.T @ res.jac) * sigma2
        unc = np.sqrt(np.clip(np.diag(cov), 0, None)) * np.abs(x0)
    except np.linalg.LinAlgError:
        unc = np.full(x0.size, np.nan)
    best = np.minimum.accumulate(np.asarray(trace)) * 1.0 if trace else np.zeros(0)
    return _Outcome(x=res.x * x0, fun=float(np.sum((res.fun * _RESIDUAL_UNIT) ** 2)),
                    nfev=len(trace), nit=res.nfev, success=bool(res.success),
                    message=str(res.message), uncertainty=unc, history=best)


def _cma(name, objective, x0, box, *, seed, population, max_evals, n_jobs, client,
         callback, stop, options) -> _Outcome:
    try:
        import cmaes
    except ImportError:  # pragma: no cover - depends on the installation
        raise InputError("method='cma' needs the cmaes package: pip install bwim[cma]") from None
    lo, hi = box
    if isinstance(seed, (int, np.integer)):
        cma_seed = int(seed)
    else:
        cma_seed = int(np.random.default_rng(seed).integers(2**31 - 1))
    cma = cmaes.CMA(mean=np.ones_like(x0), sigma=0.3, bounds=np.stack([lo / x0, hi / x0], 1),
                    seed=cma_seed, population_size=population, **options)
    pop = cma.population_size
    budget = max_evals if max_evals is not None else 200 * pop
    if budget < pop:
        raise InputError(f"max_evals = {budget} must allow one CMA-ES population ({pop})")
    best_x, best_f, nfev, nit, trace = x0.copy(), np.inf, 0, 0, []
    success, message = False, _BUDGET_SPENT
    while nfev + pop <= budget:
        U = np.array([cma.ask() for _ in range(pop)])
        V = evaluate(objective, U * x0, n_jobs=n_jobs, client=client).sum(axis=1)
        cma.tell(list(zip(U, V, strict=True)))
        nfev += pop
        nit += 1
        k = int(np.argmin(V))
        if V[k] < best_f:
            best_f, best_x = float(V[k]), U[k] * x0
        trace.append(best_f)
        if callback is not None:
            callback(name, nit, best_f)
        if stop is not None and stop(best_x):
            success, message = True, _STOP_MET
            break
        if cma.should_stop():
            success, message = True, ("CMA-ES converged (cmaes' stopping rules: the "
                                      "objective's or the step's tolerance).")
            break
    return _Outcome(x=best_x, fun=best_f, nfev=nfev, nit=nit, success=success,
                    message=message, uncertainty=np.full(x0.size, np.nan),
                    history=np.asarray(trace))
