"""numpy's pairwise summation, compiled: the number ``numpy.sum`` gives for a vector.

Contract
--------
* :func:`pairwise_sum` ``(a, lo, n)`` is numpy's sum of ``a[lo:lo + n]`` (a contiguous
  float64 vector), bit for bit: numpy's ``pairwise_sum`` (blocks of at most 128 values,
  summed one after the other below 8 terms, else by 8 running sums combined pairwise;
  beyond a block, the sum of its halves, the first a multiple of 8 terms), added to the
  reduction's identity 0 (so a sum of negative zeros is +0.0, as numpy's).  numpy's
  recursion is walked with a stack of its own: numba's cache does not load a recursive
  function.  :func:`numpy_sum` is the same for a whole vector, from Python.
* Used by the compiled kernels that must give numpy's numbers
  (:mod:`bwim.detect.group_kernels`, :mod:`bwim.detect.order_stats`,
  :mod:`bwim.site.health_kernels`, :mod:`bwim.wim.weigh_kernels`); tested against
  ``numpy.sum`` (tests/unit/test_pairwise.py).
* Compiled with numba (``cache=True``).  numba's cache of a kernel does not follow the
  kernels it calls in other modules: after editing this one, delete the numba cache files
  (``*.nbi``, ``*.nbc``) of its callers' ``__pycache__`` (an installed copy never changes).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["numpy_sum", "pairwise_sum"]


@njit(cache=True)
def _block_sum(a, lo, n):
    """numpy's sum of at most 128 values: one after the other below 8, else 8
    accumulators."""
    if n < 8:
        res = -0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    end = n - n % 8
    while i < end:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def pairwise_sum(a, lo, n):
    """numpy's sum of ``a[lo:lo + n]`` (its pairwise summation: blocks of at most 128
    values, halves beyond, the first a multiple of 8), the same number.  numpy's
    recursion as a loop over an explicit stack (numba's cache fails recursive functions)."""
    if n <= 128:
        return 0.0 + _block_sum(a, lo, n)  # numpy adds the sum to its identity, 0
    # post-order over the halves: each frame (start, count, stage, left half's sum)
    starts = np.empty(64, dtype=np.int64)
    counts = np.empty(64, dtype=np.int64)
    stages = np.zeros(64, dtype=np.int64)
    lefts = np.empty(64)
    starts[0], counts[0], stages[0] = lo, n, 0
    depth = 1
    value = 0.0
    while True:
        d = depth - 1
        m = counts[d]
        if m <= 128:
            value = _block_sum(a, starts[d], m)
            depth -= 1
            # hand the value to the frames waiting for it
            while depth > 0:
                d = depth - 1
                if stages[d] == 1:  # its left half: now the right
                    lefts[d] = value
                    stages[d] = 2
                    half = counts[d] // 2
                    half -= half % 8
                    starts[depth], counts[depth], stages[depth] = (starts[d] + half,
                                                                   counts[d] - half, 0)
                    depth += 1
                    break
                value = lefts[d] + value  # its right half: its sum
                depth -= 1
            if depth == 0:
                return 0.0 + value
        else:  # split: the left half first
            stages[d] = 1
            half = m // 2
            half -= half % 8
            starts[depth], counts[depth], stages[depth] = starts[d], half, 0
            depth += 1


def numpy_sum(a: np.ndarray) -> float:
    """``numpy.sum`` of a float vector, compiled (see the module docstring)."""
    v = np.ascontiguousarray(a, dtype=float).reshape(-1)
    return float(pairwise_sum(v, 0, v.size))
