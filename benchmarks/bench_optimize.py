"""Cross-Entropy against CMA-ES: evaluations to a target accuracy (issue 6).

For each test problem, each method is run from the same start with several seeds and
stops at the target or at the evaluation budget; the table gives the median number of
objective evaluations to the target (over the seeds that reached it), how many seeds
reached it, and the median wall time of a run.

Methods: plain CE and sub-structured CE (:class:`bwim.optimize.CrossEntropy`, population
200, elite fraction 0.05, variance injection) and CMA-ES (``cmaes.CMA``, its default
population 4 + ⌊3 ln n⌋).  Sub-structured CE needs an objective that is a sum of parts and
a neighbour map; for the 2-D Rosenbrock function (one part) it is plain CE.

Problems (the validation tests use the same definitions):
* ``sphere``: f = Σ (x_i − c_i)², n = 10, c_i = 1 … 2 (optimum x = c, f = 0); parts: the
  terms (a Linear Combination problem);
* ``rosenbrock``: f = Σ 100 (x_{i+1} − x_i²)² + (1 − x_i)² (Rosenbrock 1960; optimum at
  (1, …, 1), f = 0), n = 2 from (−1.2, 1) and n = 10 from 0; parts: the n − 1 terms,
  neighbours x_i and x_{i+1};
* ``rastrigin``: separable, multimodal; f = Σ 10 + y_i² − 10 cos 2π y_i, y = x − c
  (optimum x = c, f = 0; local minima near every integer offset);
* ``nlc``: the 48-parameter Near-Linear-Combination problem of :func:`nlc_problem`
  (a 4 × 4 grid of zones, 3 parameters per zone, 9 "sensors" at the interior corners;
  Dowling, OBrien & González 2012 §4.1 and §5.3); target: every parameter within 1 %.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from benchmarks._timing import print_table
from bwim.optimize import CrossEntropy


@dataclass(frozen=True, kw_only=True, eq=False)
class Problem:
    """A vectorised test problem.

    ``parts(X)`` maps trials (k, n) to sub-objective values (k, n_parts); the objective is
    their sum.  ``neighbours`` (n_parts, n) is the map for sub-structured CE.
    """

    name: str
    x0: np.ndarray
    std: float | np.ndarray | None
    parts: Callable[[np.ndarray], np.ndarray]
    neighbours: np.ndarray
    x_opt: np.ndarray
    target: str
    reached: Callable[[np.ndarray, float], bool]
    bounds: tuple[float, float] | None = None
    ce_options: dict = field(default_factory=dict)
    cma_sigma: float = 0.3

    def fun(self, X: np.ndarray) -> np.ndarray:
        """Objective values of trials X (k, n) or of one trial (n,)."""
        return self.parts(X).sum(axis=-1)


def sphere_problem(n: int = 10) -> Problem:
    """Shifted sphere Σ (x_i − c_i)², c = linspace(1, 2, n); optimum x = c, f = 0."""
    c = np.linspace(1.0, 2.0, n)
    return Problem(
        name=f"sphere {n}-D", x0=np.full(n, 1.5), std=None,
        parts=lambda X: (X - c) ** 2, neighbours=np.eye(n, dtype=bool), x_opt=c,
        target="f ≤ 1e-10", reached=lambda x, f: f <= 1e-10, cma_sigma=0.45,
    )


def rosenbrock(X: np.ndarray) -> np.ndarray:
    """The Rosenbrock terms 100 (x_{i+1} − x_i²)² + (1 − x_i)², shape (..., n − 1)."""
    X = np.asarray(X, dtype=float)
    return 100.0 * (X[..., 1:] - X[..., :-1] ** 2) ** 2 + (1.0 - X[..., :-1]) ** 2


def rosenbrock_problem(n: int) -> Problem:
    """Rosenbrock's function in n dimensions; optimum (1, …, 1), f = 0.

    Start (−1.2, 1) for n = 2 (Rosenbrock 1960), 0 otherwise (std 0.5).  The path to the
    optimum crosses zero, where injection relative to |m_i| would vanish, so CE injects
    relative to 1 (``injection_scale``) with a constant small factor and stops only at
    the target or the budget.
    """
    neighbours = np.zeros((n - 1, n), dtype=bool)
    idx = np.arange(n - 1)
    neighbours[idx, idx] = neighbours[idx, idx + 1] = True
    x0 = np.array([-1.2, 1.0]) if n == 2 else np.zeros(n)
    return Problem(
        name=f"Rosenbrock {n}-D", x0=x0, std=0.5, parts=rosenbrock, neighbours=neighbours,
        x_opt=np.ones(n), target="f ≤ 1e-6", reached=lambda x, f: f <= 1e-6,
        ce_options=dict(injection=(0.03,), injection_scale=1.0), cma_sigma=0.5,
    )


def rastrigin_problem(n: int = 5) -> Problem:
    """Shifted Rastrigin Σ 10 + y_i² − 10 cos 2π y_i, y = x − c; optimum x = c, f = 0.

    Start 2.6 away from the optimum in every coordinate, std 2, bounds [−2, 9].
    """
    c = np.linspace(1.5, 3.5, n)

    def parts(X):
        Y = np.asarray(X, dtype=float) - c
        return 10.0 + Y**2 - 10.0 * np.cos(2.0 * np.pi * Y)

    return Problem(
        name=f"Rastrigin {n}-D", x0=c + 2.6, std=2.0, parts=parts,
        neighbours=np.eye(n, dtype=bool), x_opt=c, target="‖x − x*‖∞ ≤ 1e-3",
        reached=lambda x, f: bool(np.max(np.abs(x - c)) <= 1e-3), bounds=(-2.0, 9.0),
        cma_sigma=2.0,
    )


def nlc_problem(seed: int = 0, *, readings: int = 16, weak: float = 0.05,
                spread: float = 0.1) -> Problem:
    """A 48-parameter Near-Linear-Combination problem modelled on the paper's §5.3.

    A 4 × 4 grid of zones, each with 3 parameters p (stiffness-like: E_x, E_y and a
    mass-like one, relative sensitivities 1, 0.7 and 0.4); 9 sensors at the interior
    corners of the grid, each giving ``readings`` values
    ``y_s = Σ_z w_sz A_sz (1 / p_z)`` (a strain is proportional to a compliance), with
    ``w_sz = 1`` for the four zones touching sensor s and ``weak`` for all others, the
    random matrices A fixed by ``seed`` and scaled by the sensor's amplitude (0.7 near
    the edges, 1 at the centre, like strains across a simply supported deck).  True
    parameters 1 + ``spread``·N(0, 1); start at 1.  Part s is the squared misfit of
    sensor s, unnormalised (as the paper's sum of squared strain differences).  The
    neighbour map links each sensor to the 12 parameters of its four zones.  CE smooths
    the standard deviations (β = 0.7), which keeps both CE variants from collapsing
    early on this problem.
    """
    rng = np.random.default_rng(seed)
    nz, per_zone = 4, 3
    n = nz * nz * per_zone
    sensitivity = np.array([1.0, 0.7, 0.4])
    amplitude = np.array([0.7, 1.0, 0.7])
    sensors = [(i, j) for i in (1, 2, 3) for j in (1, 2, 3)]
    neighbours = np.zeros((len(sensors), n), dtype=bool)
    G = np.zeros((len(sensors), readings, n))
    for s, (i, j) in enumerate(sensors):
        for zx in range(nz):
            for zy in range(nz):
                near = zx in (i - 1, i) and zy in (j - 1, j)
                cols = slice(per_zone * (zx * nz + zy), per_zone * (zx * nz + zy + 1))
                neighbours[s, cols] = near
                G[s][:, cols] = (rng.standard_normal((readings, per_zone)) * sensitivity
                                 * (1.0 if near else weak))
        G[s] *= amplitude[i - 1] * amplitude[j - 1]
    p_true = 1.0 + spread * rng.standard_normal(n)
    y_true = np.einsum("srn,n->sr", G, 1.0 / p_true)
    scale = np.sum(y_true**2) / len(sensors)

    def parts(X):
        X = np.asarray(X, dtype=float)
        Y = np.einsum("srn,...n->...sr", G, 1.0 / X)
        return np.sum((Y - y_true) ** 2, axis=-1) / scale

    return Problem(
        name="NLC 48-D", x0=np.ones(n), std=None, parts=parts, neighbours=neighbours,
        x_opt=p_true, target="all |x/x* − 1| ≤ 1 %",
        reached=lambda x, f: bool(np.max(np.abs(x / p_true - 1.0)) <= 0.01),
        bounds=(0.2, 5.0), ce_options=dict(smoothing=(1.0, 0.7)), cma_sigma=0.3,
    )


def problems() -> list[Problem]:
    """The benchmark's problems."""
    return [sphere_problem(), rosenbrock_problem(2), rosenbrock_problem(10),
            rastrigin_problem(), nlc_problem()]


def ce_evals_to_target(problem: Problem, *, substructured: bool, seed: int,
                       budget: int) -> tuple[int | None, CrossEntropy]:
    """Run CE until the problem's target or the budget; evaluations to the target."""
    options = dict(seed=seed, max_evals=budget, max_iter=None, convergences=10**9,
                   bounds=problem.bounds, **problem.ce_options)
    opt = CrossEntropy(problem.x0, problem.std,
                       neighbours=problem.neighbours if substructured else None, **options)
    while not opt.should_stop():
        X = opt.ask()
        values = problem.parts(X)
        opt.tell(X, values if substructured else values.sum(axis=1))
        if problem.reached(opt.best_x, opt.best_fun):
            return opt.nfev, opt
    return None, opt


def cma_evals_to_target(problem: Problem, *, seed: int, budget: int) -> int | None:
    """Run CMA-ES (``cmaes.CMA``, default population) until the target or the budget."""
    from cmaes import CMA

    n = problem.x0.size
    bounds = None if problem.bounds is None else np.tile(problem.bounds, (n, 1))
    opt = CMA(mean=problem.x0.astype(float), sigma=problem.cma_sigma, bounds=bounds,
              seed=seed)
    nfev = 0
    while nfev + opt.population_size <= budget and not opt.should_stop():
        X = np.array([opt.ask() for _ in range(opt.population_size)])
        values = problem.fun(X)
        nfev += X.shape[0]
        opt.tell(list(zip(X, values, strict=True)))
        i = int(np.argmin(values))
        if problem.reached(X[i], float(values[i])):
            return nfev
    return None


def _summary(evals: Sequence[int | None], times: Sequence[float]) -> list[object]:
    hits = [e for e in evals if e is not None]
    median = f"{int(np.median(hits)):,}" if hits else "—"
    return [median, f"{len(hits)}/{len(evals)}", f"{np.median(times):.2f}"]


METHODS = ("CE", "CE sub-structured", "CMA-ES")


def run(chosen: Sequence[Problem] | None = None, *, seeds: Sequence[int] = (0, 1, 2),
        budget: int = 1_000_000, methods: Sequence[str] = METHODS) -> list[list[object]]:
    """Evaluations to target for every problem and method; returns the table rows.

    Each row: problem, target, method, median evaluations to the target over the seeds
    that reached it ("—" if none), seeds that reached it, median wall time of a run (s).
    Sub-structured CE is skipped for one-part problems (where it is plain CE).
    """
    runners: dict[str, Callable[[Problem, int], int | None]] = {
        "CE": lambda p, s: ce_evals_to_target(p, substructured=False, seed=s,
                                              budget=budget)[0],
        "CE sub-structured": lambda p, s: ce_evals_to_target(p, substructured=True, seed=s,
                                                             budget=budget)[0],
        "CMA-ES": lambda p, s: cma_evals_to_target(p, seed=s, budget=budget),
    }
    rows = []
    for problem in chosen if chosen is not None else problems():
        for label in methods:
            if label == "CE sub-structured" and problem.neighbours.shape[0] == 1:
                continue
            method = runners[label]
            evals, times = [], []
            for seed in seeds:
                t0 = time.perf_counter()
                evals.append(method(problem, seed))
                times.append(time.perf_counter() - t0)
            rows.append([problem.name, problem.target, label, *_summary(evals, times)])
    return rows


def main() -> None:
    rows = run()
    print_table("Optimisers: objective evaluations to the target (median over 3 seeds; "
                "budget 1,000,000)",
                ["problem", "target", "method", "evaluations", "reached", "time (s)"], rows)


if __name__ == "__main__":
    main()
