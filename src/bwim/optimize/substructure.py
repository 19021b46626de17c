"""Elite sets for plain and sub-structured Cross-Entropy.

Contract
--------
* A trial's objective (or part) value that is NaN or ±inf is a failed evaluation: it
  ranks after every finite value and never enters that objective's (or part's) elite
  set.  Ties keep the order of the trials (stable sort), so the elite set is a
  deterministic function of the values.
* :func:`elite_mask` marks the ⌈ρk⌉ best of k trials by one objective (fewer when fewer
  values are finite).
* :func:`parameter_elite_masks` is the sub-structured rule of Dowling, OBrien & González
  (2012) §4.1 (docs/theory.md §6) for "Near Linear Combination" problems
  ``O(x) = Σ_j O_j(x)``: each part j
  elects its own elite set by its sub-objective ``O_j``; the elite set of parameter i is the
  union of the elite sets of the parts that neighbour i; a parameter without a neighbouring
  part uses the global elite set, ranked by the total ``Σ_j O_j``.
* :func:`masked_mean_std` turns a (n_params, k) membership mask into each parameter's
  elite mean and standard deviation (maximum-likelihood, ddof = 0).

These functions are pure (no randomness, no state) and know nothing about bridges.
"""

from __future__ import annotations

import numpy as np

from bwim.errors import InputError

__all__ = [
    "check_neighbours",
    "elite_mask",
    "masked_mean_std",
    "parameter_elite_masks",
    "part_elite_masks",
]


def check_neighbours(neighbours: object, n_params: int) -> np.ndarray:
    """Validate a neighbour map and return it as a read-only bool array.

    Parameters
    ----------
    neighbours : array_like of bool or {0, 1}, shape (n_parts, n_params)
        ``neighbours[j, i]`` is True when sub-objective j depends strongly on parameter i.
    n_params : int
        Number of parameters of the problem.

    Returns
    -------
    numpy.ndarray of bool, shape (n_parts, n_params)
    """
    arr = np.asarray(neighbours)
    if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] != n_params:
        raise InputError(
            f"neighbours must be a bool array of shape (n_parts, n_params) = (n_parts, "
            f"{n_params}) with n_parts >= 1, got shape {arr.shape}"
        )
    if arr.dtype != bool:
        if not np.issubdtype(arr.dtype, np.number) or not np.all((arr == 0) | (arr == 1)):
            raise InputError(
                f"neighbours must hold booleans (or 0/1), got dtype {arr.dtype}"
            )
        arr = arr != 0
    out = np.array(arr, dtype=bool)
    out.flags.writeable = False
    return out


def _ranked_keys(values: np.ndarray) -> np.ndarray:
    """Values with every non-finite entry replaced by +inf (ranks last)."""
    return np.where(np.isfinite(values), values, np.inf)


def elite_mask(values: np.ndarray, n_elite: int) -> np.ndarray:
    """The ``n_elite`` lowest finite values of ``values`` (k,), as a (k,) bool mask."""
    values = np.asarray(values, dtype=float)
    order = np.argsort(_ranked_keys(values), kind="stable")[:n_elite]
    mask = np.zeros(values.shape[0], dtype=bool)
    mask[order[np.isfinite(values[order])]] = True
    return mask


def part_elite_masks(part_values: np.ndarray, n_elite: int) -> np.ndarray:
    """Each part's elite set: shape (n_parts, k) bool from values of shape (k, n_parts)."""
    part_values = np.asarray(part_values, dtype=float)
    k, n_parts = part_values.shape
    order = np.argsort(_ranked_keys(part_values), axis=0, kind="stable")[:n_elite]
    cols = np.broadcast_to(np.arange(n_parts), order.shape)
    finite = np.isfinite(part_values[order, cols])
    mask = np.zeros((n_parts, k), dtype=bool)
    mask[cols[finite], order[finite]] = True
    return mask


def parameter_elite_masks(
    part_values: np.ndarray, neighbours: np.ndarray, n_elite: int
) -> np.ndarray:
    """Sub-structured elite sets, one per parameter.

    Parameters
    ----------
    part_values : numpy.ndarray, shape (k, n_parts)
        Sub-objective values of k trials.
    neighbours : numpy.ndarray of bool, shape (n_parts, n_params)
        The neighbour map (see :func:`check_neighbours`).
    n_elite : int
        Size of each part's elite set, ⌈ρk⌉.

    Returns
    -------
    numpy.ndarray of bool, shape (n_params, k)
        ``mask[i, t]`` is True when trial t is in parameter i's elite set: the union of the
        elite sets of the parts neighbouring i, or the global elite set (ranked by the sum
        of the parts; a trial with any non-finite part is a failure) when i has no
        neighbouring part.
    """
    part_values = np.asarray(part_values, dtype=float)
    parts = part_elite_masks(part_values, n_elite).astype(np.int64)
    mask = (neighbours.T.astype(np.int64) @ parts) > 0
    orphans = ~neighbours.any(axis=0)
    if orphans.any():
        mask[orphans] = elite_mask(part_values.sum(axis=1), n_elite)
    return mask


def masked_mean_std(X: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                np.ndarray]:
    """Per-parameter mean and standard deviation of the trials selected by ``mask``.

    Parameters
    ----------
    X : numpy.ndarray, shape (k, n_params)
        Trial vectors.
    mask : numpy.ndarray of bool, shape (n_params, k)
        Elite membership of each trial for each parameter.

    Returns
    -------
    mean, std : numpy.ndarray, shape (n_params,)
        Elite mean and (ddof = 0) standard deviation; NaN where a parameter has no elite
        trial.
    count : numpy.ndarray of int, shape (n_params,)
        Number of elite trials of each parameter.
    """
    Xt = X.T
    count = mask.sum(axis=1)
    safe = np.maximum(count, 1)
    mean = np.where(mask, Xt, 0.0).sum(axis=1) / safe
    var = np.where(mask, (Xt - mean[:, None]) ** 2, 0.0).sum(axis=1) / safe
    empty = count == 0
    mean[empty] = np.nan
    var[empty] = np.nan
    return mean, np.sqrt(var), count
