"""Evaluate an objective over a population, serially or in parallel chunks.

Contract
--------
* :func:`evaluate` applies ``fun`` to every row of a population ``X`` (k, n_params) and
  returns the values in row order: shape (k,) for a scalar objective, (k, n_parts) for an
  objective that returns its parts.  The answer does not depend on how it was computed:
  serial, joblib processes or a dask cluster give the same numbers.
* Serial by default.  ``n_jobs != 1`` splits the rows into chunks and evaluates them in
  joblib's ``loky`` worker processes with one BLAS/OpenMP thread per worker (so that
  ``n_jobs`` workers use ``n_jobs`` cores).  ``client=`` (a ``dask.distributed.Client``)
  evaluates the chunks on that cluster with ``client.map`` / ``client.gather`` instead.
* ``fun`` (and ``args``) must be picklable for the parallel paths (joblib and dask use
  cloudpickle, so closures and lambdas work).  On a dask cluster the number of BLAS
  threads per worker is the cluster's setting (start its workers with
  ``OMP_NUM_THREADS=1`` and friends).
* The module holds no state; the worker pool is joblib's reusable executor.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from bwim.errors import InputError

__all__ = ["evaluate"]


def _eval_chunk(fun: Callable[..., Any], X: np.ndarray, vectorized: bool,
                args: Sequence[Any]) -> np.ndarray:
    """Values of one chunk of rows (runs in the worker)."""
    if vectorized:
        return np.asarray(fun(X, *args), dtype=float)
    values = [np.asarray(fun(x, *args), dtype=float) for x in X]
    shapes = sorted({v.shape for v in values})
    if len(shapes) > 1:
        raise InputError(f"the objective returned values of different shapes {shapes} for "
                         "different trials")
    return np.array(values) if values else np.zeros(0)


def _chunks(X: np.ndarray, chunk_size: int) -> list[np.ndarray]:
    return [X[i:i + chunk_size] for i in range(0, X.shape[0], chunk_size)]


def check_int(name: str, value: object, low: int) -> int:
    """Return ``value`` as an int, or raise :class:`InputError` unless it is an integer
    (not a bool, not a float) ``>= low``."""
    if isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name} must be an integer, got {value!r}")
    try:
        v = operator.index(value)
    except TypeError:
        raise InputError(f"{name} must be an integer, got {value!r}") from None
    if v < low:
        raise InputError(f"{name} must be an integer >= {low}, got {v}")
    return v


def evaluate(
    fun: Callable[..., Any],
    X: np.ndarray,
    *,
    n_jobs: int = 1,
    chunk_size: int | None = None,
    client: Any = None,
    vectorized: bool = False,
    args: Sequence[Any] = (),
) -> np.ndarray:
    """Objective values of every row of a population.

    Parameters
    ----------
    fun : callable
        ``fun(x, *args)`` for one trial x (n_params,) returns a float or a (n_parts,)
        array; with ``vectorized=True`` ``fun(X_chunk, *args)`` takes a (m, n_params)
        chunk and returns (m,) or (m, n_parts).
    X : array_like, shape (k, n_params)
        The population.
    n_jobs : int
        Worker processes for joblib (``loky`` backend, one BLAS thread each); 1 = serial
        in this process, -1 = all cores (joblib's convention).  Ignored when ``client``
        is given.
    chunk_size : int or None
        Rows per task (or per call of a vectorised ``fun`` when serial); default: the
        population split evenly over the workers (serial: one chunk).
    client : dask.distributed.Client or None
        Evaluate the chunks on this dask cluster (``client.map`` then ``client.gather``).
    vectorized : bool
        Whether ``fun`` takes a whole chunk at once.
    args : sequence
        Extra positional arguments of ``fun``.

    Returns
    -------
    numpy.ndarray of float, shape (k,) or (k, n_parts)
        Values in the order of the rows of ``X``.  NaN and inf are passed through
        unchanged (the optimiser ranks them last).
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 2:
        raise InputError(f"X must have shape (population, n_params), got shape {X.shape}")
    k = X.shape[0]
    args = tuple(args)
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, (int, np.integer)) or n_jobs == 0:
        raise InputError(f"n_jobs must be a non-zero integer, got {n_jobs!r}")
    if chunk_size is not None:
        chunk_size = check_int("chunk_size", chunk_size, 1)
    if k == 0:
        return np.zeros(0)

    if client is not None:
        if chunk_size is None:
            workers = max(1, sum(client.nthreads().values()))
            chunk_size = math.ceil(k / workers)
        chunks = _chunks(X, chunk_size)
        n = len(chunks)
        futures = client.map(_eval_chunk, [fun] * n, chunks, [vectorized] * n, [args] * n,
                             pure=False)
        parts = client.gather(futures)
    elif n_jobs == 1:
        parts = [_eval_chunk(fun, c, vectorized, args) for c in _chunks(X, chunk_size or k)]
    else:
        from joblib import Parallel, delayed, effective_n_jobs, parallel_config

        from bwim.orphans import die_with_parent

        # the workers end with this process, also when it is killed (issue 22)
        with parallel_config(backend="loky", inner_max_num_threads=1,
                             initializer=die_with_parent):
            workers = effective_n_jobs(n_jobs)
            if chunk_size is None:
                chunk_size = math.ceil(k / workers)
            parts = Parallel(n_jobs=n_jobs)(
                delayed(_eval_chunk)(fun, c, vectorized, args) for c in _chunks(X, chunk_size)
            )
    return _stack(parts, k)


def _stack(parts: Sequence[np.ndarray], k: int) -> np.ndarray:
    shapes = {p.shape[1:] for p in parts}
    if len(shapes) != 1 or any(p.ndim not in (1, 2) for p in parts):
        raise InputError(
            "the objective must return a float (or a (n_parts,) array) for every trial; "
            f"got results of shapes {sorted(p.shape for p in parts)}"
        )
    out = np.concatenate(parts, axis=0)
    if out.shape[0] != k:
        raise InputError(f"the objective returned {out.shape[0]} values for {k} trials")
    return out
