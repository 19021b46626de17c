"""The result vocabulary of :mod:`scipy.optimize`, shared by bwim's minimisers and fits.

Contract
--------
* :class:`OptimizeResult` holds ``x, fun, nfev, nit, success, message`` with scipy's
  meanings.  A result of a bwim minimiser or fit inherits it (frozen, keyword-only, so the
  fields are given by name) and adds its own fields; its docstring states what its ``x``
  and ``fun`` are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, kw_only=True, eq=False)
class OptimizeResult:
    """What a minimisation found and why it stopped (:func:`scipy.optimize.minimize`'s
    vocabulary).

    Attributes
    ----------
    x : numpy.ndarray
        The best point found.
    fun : float
        The objective at ``x``.
    nfev : int
        Objective evaluations.
    nit : int
        Iterations of the minimiser.
    success : bool
        Whether it stopped normally (a spent budget is not a success).
    message : str
        A sentence saying why it stopped.
    """

    x: np.ndarray
    fun: float
    nfev: int
    nit: int
    success: bool
    message: str
