"""General-purpose optimisation: Cross-Entropy with variance injection and sub-structuring.

This package knows nothing about bridges; :mod:`bwim.calibration` drives it.  The method
and its settings are in docs/theory.md §6.

* :class:`CrossEntropy` — ask/tell minimiser over whole populations (plain or
  sub-structured); :attr:`CrossEntropy.result` is a :class:`CEResult`.
* :func:`minimize_ce` — the loop for a function, serial or parallel, with checkpoints.
* :func:`evaluate` — a population's objective values, serial, joblib or dask.
* :class:`OptimizeResult` — ``x, fun, nfev, nit, success, message`` in scipy's
  vocabulary, the base of every minimiser's result here and in :mod:`bwim.calibration`.
"""

from bwim.optimize.ce import (
    DEFAULT_INJECTION,
    CEHistory,
    CEResult,
    CrossEntropy,
    StopReason,
    load_checkpoint,
    minimize_ce,
    save_checkpoint,
)
from bwim.optimize.parallel import evaluate
from bwim.optimize.result import OptimizeResult
from bwim.optimize.substructure import parameter_elite_masks

__all__ = [
    "DEFAULT_INJECTION",
    "CEHistory",
    "CEResult",
    "CrossEntropy",
    "OptimizeResult",
    "StopReason",
    "evaluate",
    "load_checkpoint",
    "minimize_ce",
    "parameter_elite_masks",
    "save_checkpoint",
]
