"""``calibrate``: the bridge FE model from strains under a truck of known weight.

Contract
--------
The paper's procedure (Dowling, OBrien & González 2012, §5.1 steps 3–4; THEORY §7):

1. **Stiffness, pseudo-static.**  ``E_x``, ``E_y`` per zone (and ``E_girder``) minimise the
   misfit between the measured strains and the *static* strains of the truck's static
   wheel loads at their positions (:class:`~bwim.calibration.problem.StaticObjective`).
2. **Mass, dynamic.**  With that stiffness, ``mu`` per zone (and ``mu_girder``) minimise
   the misfit between measured strains and the simulated dynamic strains of the crossing
   (vehicle–bridge interaction over the given road).

Beyond the paper, an optional third stage (``refine="lm"``, the default) polishes every
unknown together on the dynamic misfit by Levenberg–Marquardt from the two-stage answer:
the pseudo-static fit is biased by the dynamics in the measured strains (measured here:
about 0.5–5 % in E on the paper's crossing), the dynamic misfit is not.

``method`` chooses the optimiser of stages 1–2 through one interface: ``"ce"`` (the
paper's Cross-Entropy, sub-structured when there are several zones, with the neighbour map
from which zones touch which measurement points), ``"lm"`` (``scipy.optimize.
least_squares``; adjoint Jacobian for the stiffness, finite differences for the mass) or
``"cma"`` (CMA-ES from the ``cmaes`` package).  Populations are evaluated in parallel with
``n_jobs`` worker processes or on a dask ``client``.

Each parameter's ``uncertainty`` is the spread of its final elite set (CE), or the
standard error ``σ sqrt(diag((JᵀJ)⁻¹))`` of the last least-squares stage that moved it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from scipy.optimize import least_squares

from bwim.calibration.problem import (
    DynamicObjective,
    ParameterSpace,
    StaticObjective,
    neighbour_map,
)
from bwim.calibration.sensitivity import Identifiability, identifiability
from bwim.errors import InputError, parse_enum
from bwim.fe.bridge import Bridge
from bwim.fe.influence import static_sensitivities
from bwim.optimize import CrossEntropy
from bwim.optimize.parallel import evaluate
from bwim.records import Record
from bwim.road import RoadProfile

__all__ = ["Calibration", "Method", "Refine", "StageResult", "calibrate"]

STIFFNESS = ("E_x", "E_y", "E_girder")
MASS = ("mu", "mu_girder")


class Method(StrEnum):
    """Optimiser of the paper's two stages."""

    CE = "ce"
    LM = "lm"
    CMA = "cma"


class Refine(StrEnum):
    """Optional joint dynamic refinement after the two stages."""

    NONE = "none"
    LM = "lm"


@dataclass(frozen=True, kw_only=True, eq=False)
class StageResult:
    """One calibration stage.

    ``history`` is the optimiser's per-iteration record: a
    :class:`~bwim.optimize.ce.CEHistory` for CE, the best objective after each
    evaluation batch (ndarray) for LM and CMA-ES.
    """

    name: str
    labels: tuple[str, ...]
    start: np.ndarray
    x: np.ndarray
    fun: float
    nfev: int
    nit: int
    success: bool
    message: str
    uncertainty: np.ndarray
    history: object
    wall_time: float


@dataclass(frozen=True, kw_only=True, eq=False)
class Calibration:
    """A calibrated bridge model.

    Attributes
    ----------
    bridge : Bridge
        The calibrated model.
    params : dict of str to ndarray
        The calibrated parameter families.
    uncertainty : dict of str to ndarray
        Their uncertainty (see module docstring), same shapes.
    stages : tuple of StageResult
    nfev : int
        Objective evaluations over all stages.
    wall_time : float
        Seconds.
    identifiability : Identifiability
    """

    bridge: Bridge
    params: dict
    uncertainty: dict
    stages: tuple[StageResult, ...]
    nfev: int
    wall_time: float
    identifiability: Identifiability

    @property
    def history(self) -> tuple[object, ...]:
        return tuple(s.history for s in self.stages)


#: (mean, std) smoothing of sub-structured CE: without it the paper's settings stopped
#: above 1 % error in 1 of 12 runs of the 48-parameter NLC benchmark, with it in none
#: (tests/validation/test_cross_entropy.py, benchmarks/bench_optimize.py).
SUBSTRUCTURED_SMOOTHING = (1.0, 0.7)

#: Fewest elite trials per CE update: a spread needs several members (small populations
#: of the dynamic stage would otherwise keep one trial and collapse at once).
MIN_ELITE = 5


def _ce_stage(name, objective, space, *, seed, population, elite_fraction, convergences,
              max_evals, bounds, neighbours, n_jobs, client, callback, ce_options):
    x0 = space.vector()
    rho = min(1.0, max(elite_fraction, MIN_ELITE / population))
    opt = CrossEntropy(x0, population=population, elite_fraction=rho,
                       bounds=bounds, seed=seed, neighbours=neighbours,
                       convergences=convergences, max_evals=max_evals, **ce_options)
    while not opt.should_stop():
        X = opt.ask()
        V = evaluate(objective, X, n_jobs=n_jobs, client=client)
        opt.tell(X, V if neighbours is not None else V.sum(axis=1))
        if callback is not None:
            callback(name, opt.nit, opt.best_fun)
    res = opt.result
    unc = np.where(np.isfinite(res.elite_std), res.elite_std, 0.0)
    return res.x, res.fun, res.nfev, res.nit, res.success, res.message, unc, res.history


def _lm_stage(name, residuals, jac, space, *, bounds, max_evals, callback):
    x0 = space.vector()
    lo, hi = bounds
    trace = []

    def fun(u):
        r = residuals(u * x0)
        trace.append(float(np.sum(r**2)))
        if callback is not None:
            callback(name, len(trace), min(trace))
        return r / 1e-6

    jac_fn = "2-point" if jac is None else (lambda u: jac(u * x0) * x0[None, :] / 1e-6)
    res = least_squares(fun, np.ones_like(x0), jac=jac_fn, bounds=(lo / x0, hi / x0),
                        diff_step=1e-4, x_scale=1.0, max_nfev=max_evals, method="trf")
    dof = max(res.fun.size - x0.size, 1)
    sigma2 = 2 * res.cost / dof
    try:
        cov = np.linalg.pinv(res.jac.T @ res.jac) * sigma2
        unc = np.sqrt(np.clip(np.diag(cov), 0, None)) * np.abs(x0)
    except np.linalg.LinAlgError:
        unc = np.full(x0.size, np.nan)
    best = np.minimum.accumulate(np.asarray(trace)) * 1.0 if trace else np.zeros(0)
    return (res.x * x0, float(np.sum((res.fun * 1e-6) ** 2)), len(trace), res.nfev,
            bool(res.success), str(res.message), unc, best)


def _cma_stage(name, objective, space, *, seed, population, bounds, max_evals, n_jobs,
               client, callback):
    try:
        import cmaes
    except ImportError:  # pragma: no cover - depends on the installation
        raise InputError("method='cma' needs the cmaes package: pip install bwim[cma]") from None
    x0 = space.vector()
    lo, hi = bounds
    rng = np.random.default_rng(seed)
    cma = cmaes.CMA(mean=np.ones_like(x0), sigma=0.3, bounds=np.stack([lo / x0, hi / x0], 1),
                    seed=int(rng.integers(2**31 - 1)),
                    population_size=population)
    best_x, best_f, nfev, nit, trace = x0.copy(), np.inf, 0, 0, []
    budget = max_evals if max_evals is not None else 200 * cma.population_size
    while not cma.should_stop() and nfev + cma.population_size <= budget:
        U = np.array([cma.ask() for _ in range(cma.population_size)])
        V = evaluate(objective, U * x0, n_jobs=n_jobs, client=client).sum(axis=1)
        cma.tell(list(zip(U, V, strict=True)))
        nfev += U.shape[0]
        nit += 1
        k = int(np.argmin(V))
        if V[k] < best_f:
            best_f, best_x = float(V[k]), U[k] * x0
        trace.append(best_f)
        if callback is not None:
            callback(name, nit, best_f)
    unc = np.full(x0.size, np.nan)
    return best_x, best_f, nfev, nit, True, "CMA-ES stopped", unc, np.asarray(trace)


def calibrate(
    start_bridge: Bridge,
    records: Record | Sequence[Record],
    vehicle,
    *,
    road: RoadProfile | None = None,
    unknowns: Sequence[str] = ("E_x", "E_y", "mu"),
    seed: int | np.random.Generator | None = None,
    method: Method | str = Method.CE,
    refine: Refine | str = Refine.LM,
    approach: float = 100.0,
    population: int | tuple[int, int] | None = None,
    elite_fraction: float = 0.05,
    convergences: int = 3,
    max_evals: int | tuple[int, int] | None = None,
    bounds: tuple[float, float] = (0.2, 5.0),
    substructure: bool | None = None,
    shared_girders: bool = True,
    weights=None,
    n_modes: int | None = None,
    n_jobs: int = 1,
    client=None,
    callback: Callable[[str, int, float], None] | None = None,
    ce_options: dict | None = None,
) -> Calibration:
    """Calibrate a bridge model from crossings of a truck of known weight.

    Parameters
    ----------
    start_bridge : Bridge
        The starting model (its zones define the unknowns' layout; its parameter values
        are the starting means).
    records : Record or sequence of Record
        Strain records of the calibration truck (one passage each; several speeds, lanes
        or runs stack).
    vehicle
        The calibration truck (its static wheel loads, and its dynamic model for the mass
        stage).
    road : RoadProfile, optional
        The road the crossings were made on (default flat), for the dynamic stages.
    unknowns : sequence of str
        Parameter families to calibrate: stiffness ones (``E_x``, ``E_y``, ``E_girder``)
        in stage 1, mass ones (``mu``, ``mu_girder``) in stage 2.
    seed : int or Generator
        Randomness of the population methods.
    method : "ce", "lm" or "cma"
    refine : "lm" or "none"
        The joint dynamic refinement after the two stages (see module docstring).
    approach : float
        Run-up length of the crossings, m (the vehicle's dynamic state on entry).
    population : int or (int, int), optional
        CE/CMA population of the static and dynamic stages (default 200 and
        ``clip(10 × n_unknowns, 40, 100)``).
    elite_fraction, convergences : CE settings (paper: 5 %, but at least
        :data:`MIN_ELITE` trials; convergences with variance injection).
    max_evals : int or (int, int), optional
        Evaluation budget of the static and dynamic stages.
    bounds : (float, float)
        Search box as factors of the starting values.
    substructure : bool, optional
        Sub-structured CE (default: when the bridge has more than one zone).
    shared_girders : bool
        Calibrate one ``E_girder`` and one ``mu_girder`` for all girders (the paper's
        §5.4; identical girders), rather than one per girder.
    weights : sequence of arrays, optional
        Per-record, per-channel weights of the squared residuals (default 1, the paper's
        plain sum); :func:`~bwim.calibration.problem.peak_weights` gives the
        maximum-likelihood weights for noise proportional to each channel's peak.
    n_modes : int, optional
        Modes of the dynamic simulations (default: up to sampling_rate / 8).
    n_jobs, client
        Parallel evaluation of populations (joblib workers or a dask client).
    callback : callable, optional
        ``callback(stage, iteration, best_objective)`` after each iteration.
    ce_options : dict, optional
        Further :class:`~bwim.optimize.CrossEntropy` options (smoothing, tol, injection…).
    """
    t0 = time.perf_counter()
    method = parse_enum(Method, method, "method")
    refine = parse_enum(Refine, refine, "refine")
    if not isinstance(start_bridge, Bridge):
        raise InputError(f"start_bridge must be a bwim.Bridge, got {type(start_bridge).__name__}")
    records = [records] if isinstance(records, Record) else list(records)
    present = start_bridge.params
    unknowns = tuple(unknowns)
    for u in unknowns:
        if u not in present:
            raise InputError(f"unknown {u!r} is not a parameter of this bridge; it has "
                             f"{sorted(present)}")
    if not unknowns:
        raise InputError("unknowns must name at least one parameter family")
    lo_f, hi_f = bounds
    if not 0 < lo_f < 1 < hi_f:
        raise InputError(f"bounds must be factors (low < 1 < high), got {bounds}")
    pop_s, pop_d = population if isinstance(population, tuple) else (population, population)
    ev_s, ev_d = max_evals if isinstance(max_evals, tuple) else (max_evals, max_evals)
    rng = np.random.default_rng(seed)
    ce_options = dict(ce_options or {})
    stages: list[StageResult] = []
    current = start_bridge
    uncertainty: dict[str, np.ndarray] = {}

    def run(name, space, objective, residuals, jac, pop, budget, allow_sub):
        nonlocal current
        x0 = space.vector()
        box = (x0 * lo_f, x0 * hi_f)
        t = time.perf_counter()
        sub = allow_sub and (start_bridge.n_zones > 1 if substructure is None else substructure)
        if method is Method.CE:
            nb = neighbour_map(space, records[0].sensors) if sub else None
            opts = dict(ce_options)
            if sub:  # std smoothing makes sub-structured CE reliable on NLC problems
                opts.setdefault("smoothing", SUBSTRUCTURED_SMOOTHING)
            out = _ce_stage(name, objective, space, seed=rng, population=pop,
                            elite_fraction=elite_fraction, convergences=convergences,
                            max_evals=budget, bounds=box, neighbours=nb, n_jobs=n_jobs,
                            client=client, callback=callback, ce_options=opts)
        elif method is Method.LM:
            out = _lm_stage(name, residuals, jac, space, bounds=box, max_evals=budget,
                            callback=callback)
        else:
            out = _cma_stage(name, objective, space, seed=rng, population=pop, bounds=box,
                             max_evals=budget, n_jobs=n_jobs, client=client,
                             callback=callback)
        x, fun, nfev, nit, ok, msg, unc, hist = out
        current = space.bridge(x, current)
        stages.append(StageResult(name=name, labels=tuple(space.labels()), start=x0, x=x,
                                  fun=fun, nfev=nfev, nit=nit, success=ok, message=msg,
                                  uncertainty=unc, history=hist,
                                  wall_time=time.perf_counter() - t))
        uncertainty.update(space.split(unc))

    shared = frozenset({"E_girder", "mu_girder"} if shared_girders else ())
    stiff = tuple(u for u in unknowns if u in STIFFNESS)
    mass = tuple(u for u in unknowns if u in MASS)
    if stiff:
        space = ParameterSpace(current, stiff, shared)
        obj = StaticObjective(space, records, vehicle, base=current, weights=weights)
        n = space.n
        run("stiffness (static)", space, obj, obj.residuals,
            lambda th, o=obj: _static_jacobian(o, th), pop_s or 200, ev_s, True)
    if mass:
        space = ParameterSpace(current, mass, shared)
        obj = DynamicObjective(space, records, vehicle, road, current, approach=approach,
                               n_modes=n_modes, weights=weights)
        n = space.n
        run("mass (dynamic)", space, obj, obj.residuals, None,
            pop_d or int(np.clip(10 * n, 40, 100)), ev_d, True)
    if refine is Refine.LM:
        space = ParameterSpace(current, unknowns, shared)
        obj = DynamicObjective(space, records, vehicle, road, current, approach=approach,
                               n_modes=n_modes, weights=weights)
        x0 = space.vector()
        t = time.perf_counter()
        out = _lm_stage("joint refinement (dynamic)", obj.residuals, None, space,
                        bounds=(x0 * lo_f, x0 * hi_f), max_evals=ev_d, callback=callback)
        x, fun, nfev, nit, ok, msg, unc, hist = out
        current = space.bridge(x, current)
        stages.append(StageResult(name="joint refinement (dynamic)",
                                  labels=tuple(space.labels()), start=x0, x=x, fun=fun,
                                  nfev=nfev, nit=nit, success=ok, message=msg,
                                  uncertainty=unc, history=hist,
                                  wall_time=time.perf_counter() - t))
        if method is not Method.CE:
            uncertainty.update(space.split(unc))
    report = identifiability(current, records, vehicle, names=stiff or None)
    params = {u: current.params[u] for u in unknowns}
    unc = {u: uncertainty.get(u, np.full(params[u].shape, np.nan)) for u in unknowns}
    return Calibration(bridge=current, params=params, uncertainty=unc, stages=tuple(stages),
                       nfev=sum(s.nfev for s in stages),
                       wall_time=time.perf_counter() - t0, identifiability=report)


def _static_jacobian(obj: StaticObjective, theta: np.ndarray) -> np.ndarray:
    """∂(static residuals)/∂θ by the adjoint method, shape (n_residuals, n_params).

    A shared family's value drives all its zones or girders: its column is the sum of
    theirs (chain rule through the broadcast).
    """
    space = obj.space
    bridge = space.bridge(theta, obj.base)
    blocks = []
    for rec, w in zip(obj.records, obj.weights, strict=True):
        p = rec.passage
        x = p.wheel_x(rec.time)
        y = np.broadcast_to(p.wheel_y, x.shape) if bridge.is_plate else None
        sens = static_sensitivities(bridge, rec.sensors, x, y, obj.static_wheels[None, :],
                                    wrt=space.names)
        weighted = sens.values * np.sqrt(w)[None, :, None]  # rows as in residuals()
        vals = weighted.reshape(-1, sens.values.shape[2])
        names = np.asarray(sens.names)
        cols = [vals[:, names == n].sum(axis=1, keepdims=True) if n in space.shared
                else vals[:, names == n] for n in space.names]
        blocks.append(np.hstack(cols))
    return np.vstack(blocks)
