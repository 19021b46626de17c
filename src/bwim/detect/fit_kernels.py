"""Compiled kernels (numba) of a vehicle's least squares, its refinement and the pursuit.

Contract
--------
* The equations of :mod:`bwim.detect.vehicle_fit` and :mod:`bwim.detect.pursuit`, whole
  loops at a time, on plain arrays (records are a few hundred samples: what the numpy
  versions spent was the calls, not the arithmetic).  Every kernel is ``njit(cache=True)``
  (no fastmath, no parallel): no operation is reordered by the compiler, so a kernel
  gives the same numbers on every call and from every caller, and the same numbers as the
  equations written out in the order the comments give; numpy's BLAS and LAPACK sum in
  orders of their own, so against the numpy versions the numbers agree to rounding only
  (an atom's value, element by element, is the same bytes: :func:`grid_atoms`).
* Response grids as the kernels read them (:class:`GridTable`): ``scalars`` (5, 2) per
  detector the grid's offset (``D_d + u_0``), ``1 / du``, last index less 1e-6 (the
  grids end in zeros), the channel's weight and weight / du; ``first`` (2,) each grid's
  first index in ``values``; ``values`` (2, N) both grids' ordinates end to end, then
  their differences (0 after each's last).
* The atoms' zero rows: a response is zero beyond its reach (its grid's first and last
  intervals whose ordinate and difference are both +0), so on most of a window's rows
  most atoms are zero.  Where the inputs allow it (:func:`zero_reach`: every value
  finite, the rows' times ascending), :func:`least_squares` and the refinement's trials
  evaluate an atom only on the rows it may reach (by bisection on its grid position,
  which rises with the row), write ``+0 × weight`` on the others (what :func:`_atom`
  gives there) and leave their terms out of the sums, as the Jacobian does
  (:func:`span_dots`): a term left out is a zero times a finite number, ±0, and a sum
  from +0 never becomes −0 (round to nearest), so adding ±0 leaves it as it is.  The
  numbers are those of every term summed in its order, byte for byte (the unit tests
  compare them with plain numpy).  :func:`grid_atoms` (an axle's times ascending) and the
  pursuit's trials in :func:`pursuit_loop` evaluate only the rows an atom may reach too
  (the trials' products with the readings of the axles already taken are kept from the
  trial that made them: the same rows, the same numbers).
* :func:`pursuit_loop` is the pursuit's whole loop (the matcher, the trials, the
  exclusions and the acceptance of :mod:`bwim.detect.pursuit`), the same steps as its
  Python classes take one by one (the unit tests compare them byte for byte): Python's
  ``max`` (the first unless a later one is larger), numpy's ``searchsorted``
  (:func:`search_sorted`) and column maximum (a NaN wins).
* Kernels write into arrays the caller made (their shapes are given); singular systems
  raise :class:`numpy.linalg.LinAlgError`, as numpy's solvers do.
* A least-squares inverse falls back to the pseudo-inverse (:func:`symmetric_pinv`) when
  an LU pivot is exactly zero (numpy's ``inv`` raising), as
  :class:`~bwim.detect.vehicle_fit.Solution` did (with the ridge, never seen).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["GridTable", "best_match", "grid_atoms", "grid_table", "jacobian", "least_squares",
           "levenberg_marquardt", "matcher_atom", "pursuit_loop", "pursuit_trial",
           "search_sorted", "sorted_copy", "span_dots", "symmetric_pinv", "zero_reach"]


@dataclass(frozen=True, eq=False)
class GridTable:
    """Both detectors' response grids as the kernels read them (see the contract)."""

    scalars: np.ndarray  # (5, 2)
    first: np.ndarray  # (2,) int64
    values: np.ndarray  # (2, N)


def grid_table(grids, steps, shift, w) -> GridTable:
    """The :class:`GridTable` of both detectors' ``grids`` (u, K, ...), their ``steps``
    (K's differences, 0 after the last), shifts ``D_d`` and weights ``w``."""
    u = [g[0] for g in grids]
    du = [ui[1] - ui[0] for ui in u]
    scalars = np.empty((5, 2))
    for c in range(2):
        scalars[:, c] = (shift[c] + u[c][0], 1.0 / du[c], u[c].size - 1.000001, float(w[c]),
                         w[c] / du[c])
    first = np.array([0, u[0].size], dtype=np.int64)
    n0 = u[0].size
    values = np.empty((2, n0 + u[1].size))
    values[0, :n0], values[0, n0:] = grids[0][1], grids[1][1]
    values[1, :n0], values[1, n0:] = steps[0], steps[1]
    return GridTable(scalars=scalars, first=first, values=values)


@njit(cache=True)
def _atom(v, dt, c, scalars, first, values):
    """Detector ``c``'s weighted atom and slope at ``dt`` (time less the axle's): K
    linear between its ordinates at ``x = (v dt − offset) / du``, clipped to the grid;
    NaN for a NaN ``dt`` (numpy would fail to index)."""
    x = (v * dt - scalars[0, c]) * scalars[1, c]
    if x < 0.0:
        x = 0.0
    if x > scalars[2, c]:
        x = scalars[2, c]
    if x != x:
        return np.nan, np.nan
    j = int(x)
    x -= j
    j += first[c]
    step = values[1, j]
    x *= step
    x += values[0, j]
    return x * scalars[3, c], step * scalars[4, c]


@njit(cache=True)
def grid_atoms(scalars, first, values, v, dt, out, slopes):
    """Both detectors' atoms ``out`` (2, n_rows, n) at ``dt`` (d, n_rows, n): d = 1 the
    same times at both, d = 2 each detector's own; ``slopes`` (2, n_rows, n) their
    slopes, or empty (0, 0, 0) for none.  Element by element the numbers of
    :meth:`~bwim.detect.vehicle_fit.Problem.both_atoms` in numpy (an axle's rows beyond
    its response's reach, its times ascending, written as +0 × weight without evaluating
    them: the same numbers, :func:`zero_reach`)."""
    want = slopes.size > 0
    flat = np.empty((2, 2), dtype=np.int64)
    fast = _grid_zeros(scalars, first, values, flat) and v > 0.0 and v - v == 0.0
    n_rows = dt.shape[1]
    # an axle's rows beyond its response's reach (its times ascending and finite): +0 ×
    # weight, what _atom gives there (zero_reach)
    sorted_col = np.zeros((dt.shape[0], dt.shape[2]), dtype=np.bool_)
    if fast:
        for d in range(dt.shape[0]):
            for j in range(dt.shape[2]):
                sorted_col[d, j] = _finite_ascending(dt[d, :, j])
    for c in range(2):
        d = c if dt.shape[0] > 1 else 0
        zero, zero_slope = 0.0 * scalars[3, c], 0.0 * scalars[4, c]
        for j in range(dt.shape[2]):
            col = dt[d, :, j]
            i0, i1 = 0, n_rows
            if sorted_col[d, j]:
                i0, i1 = _reach(v, col, c, scalars, flat)
            for i in range(i0):
                out[c, i, j] = zero
                if want:
                    slopes[c, i, j] = zero_slope
            for i in range(i0, i1):
                a, s = _atom(v, dt[d, i, j], c, scalars, first, values)
                out[c, i, j] = a
                if want:
                    slopes[c, i, j] = s
            for i in range(max(i0, i1), n_rows):
                out[c, i, j] = zero
                if want:
                    slopes[c, i, j] = zero_slope


@njit(cache=True)
def _lu(A, piv):
    """LU with partial pivoting of ``A`` in place (the first largest |pivot|, as
    LAPACK's getrf), row swaps in ``piv``; False if a pivot is exactly zero."""
    n = A.shape[0]
    ok = True
    for k in range(n):
        m = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                m = i
        piv[k] = m
        if m != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[m, j]
                A[m, j] = tmp
        d = A[k, k]
        if d == 0.0:
            ok = False
            continue
        for i in range(k + 1, n):
            f = A[i, k] / d
            A[i, k] = f
            for j in range(k + 1, n):
                A[i, j] -= f * A[k, j]
    return ok


@njit(cache=True)
def _lu_solve(LU, piv, b):
    """Solve in place ``b`` (n,) with :func:`_lu`'s factors."""
    n = LU.shape[0]
    for k in range(n):
        m = piv[k]
        if m != k:
            tmp = b[k]
            b[k] = b[m]
            b[m] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= LU[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * b[j]
        b[i] = s / LU[i, i]


@njit(cache=True)
def _inverse_columns(LU, piv, E):
    """``E`` (n, n) the inverse of :func:`_lu`'s factored matrix: :func:`_lu_solve` of
    each column of the identity, all columns at once (the identity's rows swapped as it
    swaps each right-hand side, then the forward and back substitutions row by row across
    the columns: each element gets its column's operations in their order, the same
    numbers, the loops over the columns independent)."""
    n = LU.shape[0]
    for i in range(n):
        _fill_with(E[i], 0.0)
        E[i, i] = 1.0
    for k in range(n):
        m = piv[k]
        if m != k:
            for col in range(n):
                tmp = E[k, col]
                E[k, col] = E[m, col]
                E[m, col] = tmp
    for i in range(n):
        ei = E[i]
        for j in range(i):
            lij = LU[i, j]
            ej = E[j]
            for col in range(n):
                ei[col] -= lij * ej[col]
    for i in range(n - 1, -1, -1):
        ei = E[i]
        for j in range(i + 1, n):
            uij = LU[i, j]
            ej = E[j]
            for col in range(n):
                ei[col] -= uij * ej[col]
        d = LU[i, i]
        for col in range(n):
            ei[col] = ei[col] / d


@njit(cache=True)
def _fill_with(x, value):
    """Every element of the 1-D ``x`` set to ``value`` (a loop: slice assignment costs
    seconds of compilation)."""
    for i in range(x.size):
        x[i] = value


@njit(cache=True)
def _copy(src, dst):
    """``src`` into ``dst`` (C-contiguous, the same size), element by element."""
    a = src.reshape(src.size)
    b = dst.reshape(dst.size)
    for i in range(a.size):
        b[i] = a[i]


@njit(cache=True)
def _ridge(G, p):
    """Raise the diagonal of ``G`` (p, p) by 1e-12 of its mean (+1e-300): the ridge of
    :func:`~bwim.detect.vehicle_fit.ridged_normal`."""
    s = 0.0
    for i in range(p):
        s += G[i, i]
    r = 1e-12 * (s / p + 1e-300)
    for i in range(p):
        G[i, i] += r


@njit(cache=True)
def _dots(A, na, b, out):
    """``out[i] = Σ_m A[i, m] b[m]`` for i < ``na``, each sum in the order of m (eight
    or four rows at a time: sums running side by side, each in that order)."""
    r = b.size
    i = 0
    while i + 8 <= na:
        a0, a1, a2, a3 = A[i], A[i + 1], A[i + 2], A[i + 3]
        a4, a5, a6, a7 = A[i + 4], A[i + 5], A[i + 6], A[i + 7]
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
        for m in range(r):
            bm = b[m]
            s0 += a0[m] * bm
            s1 += a1[m] * bm
            s2 += a2[m] * bm
            s3 += a3[m] * bm
            s4 += a4[m] * bm
            s5 += a5[m] * bm
            s6 += a6[m] * bm
            s7 += a7[m] * bm
        out[i], out[i + 1], out[i + 2], out[i + 3] = s0, s1, s2, s3
        out[i + 4], out[i + 5], out[i + 6], out[i + 7] = s4, s5, s6, s7
        i += 8
    while i + 4 <= na:
        a0, a1, a2, a3 = A[i], A[i + 1], A[i + 2], A[i + 3]
        s0 = s1 = s2 = s3 = 0.0
        for m in range(r):
            bm = b[m]
            s0 += a0[m] * bm
            s1 += a1[m] * bm
            s2 += a2[m] * bm
            s3 += a3[m] * bm
        out[i], out[i + 1], out[i + 2], out[i + 3] = s0, s1, s2, s3
        i += 4
    while i < na:
        a0 = A[i]
        s0 = 0.0
        for m in range(r):
            s0 += a0[m] * b[m]
        out[i] = s0
        i += 1


@njit(cache=True)
def _gram(A, n, G):
    """``G[i, j] = Σ_m A[i, m] A[j, m]`` for i, j < ``n``, each sum from 0 in the order
    of m (:func:`_dots`' numbers; symmetric: a product is the same number either way
    round): four rows by four at a time (sixteen sums side by side), the rows left over
    by :func:`_dots`."""
    r = A.shape[1]
    nb = n // 4 * 4
    for jb in range(0, nb, 4):
        b0, b1, b2, b3 = A[jb], A[jb + 1], A[jb + 2], A[jb + 3]
        for ib in range(0, jb + 4, 4):
            a0, a1, a2, a3 = A[ib], A[ib + 1], A[ib + 2], A[ib + 3]
            s00 = s01 = s02 = s03 = s10 = s11 = s12 = s13 = 0.0
            s20 = s21 = s22 = s23 = s30 = s31 = s32 = s33 = 0.0
            for m in range(r):
                x0, x1, x2, x3 = a0[m], a1[m], a2[m], a3[m]
                y0, y1, y2, y3 = b0[m], b1[m], b2[m], b3[m]
                s00 += x0 * y0
                s01 += x0 * y1
                s02 += x0 * y2
                s03 += x0 * y3
                s10 += x1 * y0
                s11 += x1 * y1
                s12 += x1 * y2
                s13 += x1 * y3
                s20 += x2 * y0
                s21 += x2 * y1
                s22 += x2 * y2
                s23 += x2 * y3
                s30 += x3 * y0
                s31 += x3 * y1
                s32 += x3 * y2
                s33 += x3 * y3
            G[jb, ib], G[jb + 1, ib], G[jb + 2, ib], G[jb + 3, ib] = s00, s01, s02, s03
            G[jb, ib + 1], G[jb + 1, ib + 1] = s10, s11
            G[jb + 2, ib + 1], G[jb + 3, ib + 1] = s12, s13
            G[jb, ib + 2], G[jb + 1, ib + 2] = s20, s21
            G[jb + 2, ib + 2], G[jb + 3, ib + 2] = s22, s23
            G[jb, ib + 3], G[jb + 1, ib + 3] = s30, s31
            G[jb + 2, ib + 3], G[jb + 3, ib + 3] = s32, s33
    for j in range(nb, n):
        _dots(A, j + 1, A[j], G[j])
    for j in range(n):
        for i in range(j):
            G[i, j] = G[j, i]


@njit(cache=True)
def symmetric_pinv(G, out):
    """The pseudo-inverse of the symmetric ``G`` (p, p) into ``out``: its eigenvalues
    and vectors by cyclic Jacobi rotations, ``V diag(1/λ) Vᵀ`` over the eigenvalues above
    1e-15 of the largest |λ| (numpy's ``pinv``: its singular values are the |λ|)."""
    p = G.shape[0]
    A = G.copy()
    V = np.eye(p)
    for _ in range(100):
        off = 0.0
        total = 0.0
        for i in range(p):
            for j in range(p):
                total += A[i, j] * A[i, j]
                if i != j:
                    off += A[i, j] * A[i, j]
        if not off > 1e-32 * total:
            break
        for i in range(p - 1):
            for j in range(i + 1, p):
                if A[i, j] == 0.0:
                    continue
                theta = (A[j, j] - A[i, i]) / (2.0 * A[i, j])
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(p):  # A J (columns i, j)
                    aki, akj = A[k, i], A[k, j]
                    A[k, i] = c * aki - s * akj
                    A[k, j] = s * aki + c * akj
                for k in range(p):  # Jᵀ (A J) (rows i, j)
                    aik, ajk = A[i, k], A[j, k]
                    A[i, k] = c * aik - s * ajk
                    A[j, k] = s * aik + c * ajk
                for k in range(p):
                    vki, vkj = V[k, i], V[k, j]
                    V[k, i] = c * vki - s * vkj
                    V[k, j] = s * vki + c * vkj
    top = 0.0
    for i in range(p):
        top = max(top, abs(A[i, i]))
    inv = np.zeros(p)
    for i in range(p):
        if abs(A[i, i]) > 1e-15 * top:
            inv[i] = 1.0 / A[i, i]
    for i in range(p):
        for j in range(p):
            s = 0.0
            for m in range(p):
                s += V[i, m] * inv[m] * V[j, m]
            out[i, j] = s


@njit(cache=True)
def _union(lo, hi, i0, i1):
    """The smallest span holding the spans of rows ``i0`` … ``i1 − 1`` (empty ones
    aside); (0, 0) when all are empty."""
    a = -1
    b = 0
    for i in range(i0, i1):
        if lo[i] < hi[i]:
            if a < 0 or lo[i] < a:
                a = lo[i]
            if hi[i] > b:
                b = hi[i]
    return max(a, 0), b


@njit(cache=True)
def span_dots(A, na, b, blo, bhi, lo, hi, out):
    """:func:`_dots` (``out[i] = Σ_m A[i, m] b[m]`` for i < ``na``, each sum from 0 in
    the order of m) over only the terms where both factors may be nonzero: ``b`` zero
    outside ``[blo, bhi)``, row ``i`` of ``A`` zero outside ``[lo[i], hi[i])``, every
    value of both finite.  The same numbers: a term left out is a zero times a finite
    number, ±0, and a sum from +0 is never −0 (round to nearest), so adding ±0 leaves it
    as it is.  Rows eight or four at a time (sums side by side, each in that order) over
    the union of their spans."""
    i = 0
    while i + 8 <= na:
        ulo, uhi = _union(lo, hi, i, i + 8)
        m0, m1 = max(blo, ulo), min(bhi, uhi)
        a0, a1, a2, a3 = A[i], A[i + 1], A[i + 2], A[i + 3]
        a4, a5, a6, a7 = A[i + 4], A[i + 5], A[i + 6], A[i + 7]
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
        for m in range(m0, m1):
            bm = b[m]
            s0 += a0[m] * bm
            s1 += a1[m] * bm
            s2 += a2[m] * bm
            s3 += a3[m] * bm
            s4 += a4[m] * bm
            s5 += a5[m] * bm
            s6 += a6[m] * bm
            s7 += a7[m] * bm
        out[i], out[i + 1], out[i + 2], out[i + 3] = s0, s1, s2, s3
        out[i + 4], out[i + 5], out[i + 6], out[i + 7] = s4, s5, s6, s7
        i += 8
    while i + 4 <= na:
        ulo, uhi = _union(lo, hi, i, i + 4)
        m0, m1 = max(blo, ulo), min(bhi, uhi)
        a0, a1, a2, a3 = A[i], A[i + 1], A[i + 2], A[i + 3]
        s0 = s1 = s2 = s3 = 0.0
        for m in range(m0, m1):
            bm = b[m]
            s0 += a0[m] * bm
            s1 += a1[m] * bm
            s2 += a2[m] * bm
            s3 += a3[m] * bm
        out[i], out[i + 1], out[i + 2], out[i + 3] = s0, s1, s2, s3
        i += 4
    while i < na:
        a0 = A[i]
        s0 = 0.0
        for m in range(max(blo, lo[i]), min(bhi, hi[i])):
            s0 += a0[m] * b[m]
        out[i] = s0
        i += 1


@njit(cache=True)
def _span_gram(A, n, lo, hi, G, split):
    """:func:`_gram` by :func:`span_dots` (the same numbers; ``lo``, ``hi`` the rows'
    spans, every value finite), the rows before ``split`` (the atoms) and from it (the
    rest: whole rows) in batches of their own (a batch runs over its rows' spans' union)."""
    for j in range(n):
        na = min(j + 1, split)
        span_dots(A, na, A[j], lo[j], hi[j], lo, hi, G[j])
        if j >= split:
            span_dots(A[split:], j + 1 - split, A[j], lo[j], hi[j], lo[split:],
                      hi[split:], G[j, split:])
    for j in range(n):
        for i in range(j):
            G[i, j] = G[j, i]


@njit(cache=True)
def _span_combination(A, n, coef, lo, hi, acc):
    """``acc = Σ_j A[j] coef[j]`` (each element's sum from 0 in the order of j), row j
    only over its span ``[lo[j], hi[j])`` when ``coef[j]`` is finite (else all of it;
    every value of ``A`` finite): the same numbers (a sum from +0 is never −0)."""
    _fill_with(acc, 0.0)
    r = acc.size
    for j in range(n):
        cj = coef[j]
        if cj - cj == 0.0:
            m0, m1 = lo[j], hi[j]
        else:
            m0, m1 = 0, r
        # over views from 0 (a loop from m0 is not vectorised: measured 4x slower)
        aj = A[j, m0:m1]
        out = acc[m0:m1]
        for i in range(m1 - m0):
            out[i] += aj[i] * cj


@njit(cache=True)
def _all_finite(x):
    """Whether every value of the C-contiguous ``x`` is finite."""
    f = x.reshape(x.size)
    bad = False
    for i in range(f.size):
        bad |= not f[i] - f[i] == 0.0
    return not bad


@njit(cache=True)
def _finite_ascending(x):
    """Whether every value of the 1-D ``x`` (any strides) is finite and none falls."""
    if x.size and not x[0] - x[0] == 0.0:
        return False
    for i in range(1, x.size):
        if not (x[i] >= x[i - 1] and x[i] - x[i] == 0.0):
            return False
    return True


@njit(cache=True)
def _positive_zero(x):
    return x == 0.0 and math.copysign(1.0, x) > 0.0


@njit(cache=True)
def _grid_zeros(scalars, first, values, flat):
    """Per detector ``c`` ``flat[c] = (zl, zt)``: the grid intervals ``j < zl`` and
    ``zt ≤ j`` (of those an atom reads, j ≤ N − 2) whose ordinate and difference are both
    +0, so an atom and its slope there are ``+0 × weight`` (:func:`_atom`'s operations).
    Returns whether the grids allow a bisection on them (:func:`_reach`): every value
    finite, each grid's ``1 / du`` positive."""
    ok = _all_finite(scalars) and _all_finite(values)
    for c in range(2):
        if not scalars[1, c] > 0.0:
            ok = False
        f = first[c]
        last = int(scalars[2, c])  # N − 2: the last interval an atom reads
        zl = 0
        while zl <= last and _positive_zero(values[0, f + zl]) and _positive_zero(
                values[1, f + zl]):
            zl += 1
        zt = last + 1
        while zt > zl and _positive_zero(values[0, f + zt - 1]) and _positive_zero(
                values[1, f + zt - 1]):
            zt -= 1
        flat[c, 0] = zl
        flat[c, 1] = zt
    return ok


@njit(cache=True)
def _ascending(t):
    """Whether ``t`` (1-D) never falls (a NaN breaks it)."""
    for i in range(1, t.size):
        if not t[i] >= t[i - 1]:
            return False
    return True


@njit(cache=True)
def zero_reach(scalars, first, values, t, y, rest, flat):
    """Where the atoms are surely zero, for :func:`least_squares` to leave out (the grids'
    flat +0 intervals ``flat``, :func:`_grid_zeros`).  Returns whether the rows may be
    left out: every value of the grids, ``t``, ``y`` and ``rest`` finite, ``t`` ascending
    and each grid's ``1 / du`` positive (the grid position of an atom, ``(v dt − offset)
    / du``, then rises with the row at a positive speed: its zero rows are the first and
    last of the window, found by bisection, :func:`_reach`)."""
    ok = _grid_zeros(scalars, first, values, flat)
    return (ok and _all_finite(t) and _all_finite(y) and _all_finite(rest)
            and _ascending(t))


@njit(cache=True)
def _nonzero(x, d):
    """The smallest span ``(lo, hi)`` outside which the rows ``x`` and ``d`` (1-D, the
    same size) are both 0; (0, 0) if they are everywhere."""
    r = x.size
    a = 0
    while a < r and x[a] == 0.0 and d[a] == 0.0:
        a += 1
    b = r
    while b > a and x[b - 1] == 0.0 and d[b - 1] == 0.0:
        b -= 1
    return (a, b) if a < b else (0, 0)


@njit(cache=True)
def _given_spans(Mt, dXt, dtt, n, lo, hi):
    """The spans ``lo``, ``hi`` (2, p; the whole window (0, r) on entry) of the atoms of
    a least squares given (:func:`_nonzero` of each atom's row and its slopes'), when
    every value of ``Mt``, ``dXt`` and ``dtt`` is finite (else left whole)."""
    if _all_finite(Mt) and _all_finite(dXt) and _all_finite(dtt):
        for c in range(2):
            for j in range(n):
                lo[c, j], hi[c, j] = _nonzero(Mt[c, j], dXt[c, j])


@njit(cache=True)
def _reach(v, dt, c, scalars, flat):
    """``(i0, i1)``: the rows ``dt`` (ascending) whose atom at detector ``c`` may differ
    from +0 × weight (:func:`zero_reach`: the grid intervals ``[zl, zt)``), by bisection
    on the grid position ``x = (v dt − offset) / du`` (:func:`_atom`'s operations; it
    rises with the row): the interval is ``int(clip(x))``, below zl where ``x < zl``,
    from zt on where ``x ≥ zt`` (zl ≥ 1, zt ≤ N − 2; none else)."""
    r = dt.size
    zl, zt = flat[c, 0], flat[c, 1]
    if zl >= zt:
        return 0, 0  # every interval zero
    off, inv = scalars[0, c], scalars[1, c]
    i0 = 0
    if zl >= 1:
        a, b = 0, r  # the first row with x ≥ zl
        while a < b:
            m = (a + b) // 2
            if (v * dt[m] - off) * inv >= zl:
                b = m
            else:
                a = m + 1
        i0 = a
    i1 = r
    if zt <= int(scalars[2, c]):
        a, b = i0, r  # the first row with x ≥ zt
        while a < b:
            m = (a + b) // 2
            if (v * dt[m] - off) * inv >= zt:
                b = m
            else:
                a = m + 1
        i1 = a
    return i0, i1


@njit(cache=True)
def _fill(scalars, first, values, t, y, rest, taus, v, k, dtt, Mt, dXt, Ginv, a, res, fast,
          flat, lo, hi):
    """One least squares (see :func:`least_squares`), written into the arrays given
    (``dXt`` empty for no slopes).  With ``fast`` (:func:`zero_reach`'s answer, ``flat``
    its intervals) each atom only where it may not be zero, its other rows +0 × weight
    (what :func:`_atom` gives there) and left out of the sums (:func:`span_dots`: the
    same numbers); ``lo``, ``hi`` (2, p) the rows' spans written (the whole window for
    the rest's rows, and for all without ``fast``)."""
    r, n, q = t.size, taus.size, rest.shape[1]
    p = n + q
    for j in range(n):
        for i in range(r):
            dtt[j, i] = t[i] - taus[j]
    want = dXt.size > 0
    G = np.empty((p, p))
    b = np.empty(p)
    piv = np.empty(p, dtype=np.int64)
    coef = np.empty(p)
    acc = np.empty(r)
    if fast:  # a positive, finite speed and finite times (the grid position rises)
        fast = v > 0.0 and v - v == 0.0
        for j in range(n):
            if not taus[j] - taus[j] == 0.0:
                fast = False
    for c in range(2):
        zero, zero_slope = 0.0 * scalars[3, c], 0.0 * scalars[4, c]
        for j in range(n):
            i0, i1 = _reach(v, dtt[j], c, scalars, flat) if fast else (0, r)
            m, d = Mt[c, j], dXt[c, j] if want else Mt[c, j]
            _fill_with(m[:i0], zero)
            for i in range(i0, i1):
                x, s = _atom(v, dtt[j, i], c, scalars, first, values)
                m[i] = x
                if want:
                    d[i] = s
            _fill_with(m[max(i1, i0):], zero)
            if want:
                _fill_with(d[:i0], zero_slope)
                _fill_with(d[max(i1, i0):], zero_slope)
            lo[c, j], hi[c, j] = (i0, i1) if i0 < i1 else (0, 0)
        for j in range(q):
            for i in range(r):
                Mt[c, n + j, i] = rest[c, j, i]
            lo[c, n + j], hi[c, n + j] = 0, r
        # G = MᵀM, b = Mᵀy, each sum in the rows' order (the terms of zeros left out)
        yc = y[c]
        _span_gram(Mt[c], p, lo[c], hi[c], G, n)
        span_dots(Mt[c], p, yc, 0, r, lo[c], hi[c], b)
        _ridge(G, p)
        if _lu(G, piv):  # (MᵀM)⁻¹ column by column
            _inverse_columns(G, piv, Ginv[c])
        else:  # an exact zero pivot (numpy's inv raising): the pseudo-inverse
            _span_gram(Mt[c], p, lo[c], hi[c], G, n)
            _ridge(G, p)
            symmetric_pinv(G, Ginv[c])
        for i in range(p):  # coef = (MᵀM)⁻¹ Mᵀy
            s = 0.0
            for j in range(p):
                s += Ginv[c, i, j] * b[j]
            coef[i] = s
        for j in range(n):
            a[c, j] = coef[j]
        # M coef (each sum in the columns' order)
        _span_combination(Mt[c], p, coef, lo[c], hi[c], acc)
        for i in range(r):  # residual y − M coef, scaled to all samples
            res[c * r + i] = (yc[i] - acc[i]) * k


@njit(cache=True)
def _removal_costs(a, Ginv, step, amps, gains):
    """``amps`` (n, 2) the amplitudes ``a`` (2, n) transposed; ``gains`` (n,) each
    axle's removal cost ``(a_0j² / max(Ginv_0jj, 1e-300) + a_1j² / max(Ginv_1jj,
    1e-300)) step`` (numpy's ``a**2`` is ``a × a``; its ``maximum`` keeps a NaN)."""
    for j in range(a.shape[1]):
        a0, a1 = a[0, j], a[1, j]
        amps[j, 0] = a0
        amps[j, 1] = a1
        d0, d1 = Ginv[0, j, j], Ginv[1, j, j]
        if not (d0 != d0 or d0 > 1e-300):
            d0 = 1e-300
        if not (d1 != d1 or d1 > 1e-300):
            d1 = 1e-300
        gains[j] = (a0 * a0 / d0 + a1 * a1 / d1) * step


@njit(cache=True)
def least_squares(scalars, first, values, t, y, rest, taus, v, k, step, dtt, Mt, dXt, Ginv, a,
                  res, amps, gains):
    """Both detectors' least squares of the axles ``taus`` (n,) at speed ``v`` on a
    window's rows: times ``t`` (r,), readings ``y`` (2, r), rest columns ``rest``
    (2, q, r; one per row).  Writes ``dtt`` (n, r) the rows' times less each axle's,
    ``Mt`` (2, p = n + q, r) the design matrix transposed (the atoms, then the rest),
    ``dXt`` (2, n, r) the atoms' slopes (or pass it empty (0, 0, 0): none), ``Ginv``
    (2, p, p) ``(MᵀM + ridge)⁻¹``, ``a`` (2, n) the axles' amplitudes and ``res``
    (2 r,) the residual ``y − M (MᵀM)⁻¹ Mᵀy``, both detectors end to end, times ``k``
    (√ of the sampling step ``step``: scaled to all samples), ``amps`` (n, 2) the
    amplitudes transposed and ``gains`` (n,) each axle's removal cost, scaled to all
    samples (:func:`_removal_costs`).  Each atom is evaluated, and summed, only over the
    rows where it may not be zero (:func:`zero_reach`): the same numbers as over all."""
    flat = np.empty((2, 2), dtype=np.int64)
    fast = zero_reach(scalars, first, values, t, y, rest, flat)
    p = Mt.shape[1]
    lo = np.empty((2, p), dtype=np.int64)
    hi = np.empty((2, p), dtype=np.int64)
    _fill(scalars, first, values, t, y, rest, taus, v, k, dtt, Mt, dXt, Ginv, a, res, fast,
          flat, lo, hi)
    _removal_costs(a, Ginv, step, amps, gains)


@njit(cache=True)
def _jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt, lo, hi):
    """:func:`jacobian`, the sums over only the rows' spans ``lo``, ``hi`` (2, p): each
    atom and its slope zero outside its own, every value of ``Mt``, ``dXt`` and ``dtt``
    finite, or the whole window (0, r) (:func:`_fill`'s); the same numbers."""
    p, r = Mt.shape[1], Mt.shape[2]
    n = a.shape[1]
    Dt = np.empty((n + 1, r))
    Et = np.empty((n + 1, p))
    F = np.empty(p)
    acc = np.empty(r)
    dlo = np.empty(n + 1, dtype=np.int64)
    dhi = np.empty(n + 1, dtype=np.int64)
    every_lo = np.zeros(p, dtype=np.int64)
    every_hi = np.full(p, r, dtype=np.int64)
    cols = np.empty(p, dtype=np.int64)
    for c in range(2):
        g_finite = _all_finite(Ginv[c])
        # spans of the atoms' rows and of D's columns (a zero slope times a finite
        # amplitude is ±0); all rows where an amplitude or the speed is not finite
        sparse = v - v == 0.0
        for j in range(n):
            if not a[c, j] - a[c, j] == 0.0:
                sparse = False
        mlo, mhi = (lo[c], hi[c]) if sparse else (every_lo, every_hi)
        for j in range(n):
            dlo[j], dhi[j] = mlo[j], mhi[j]
        dlo[n], dhi[n] = _union(mlo, mhi, 0, n)
        _fill_with(Dt[n], 0.0)
        for j in range(n):
            aj = a[c, j]
            dx = dXt[c, j]
            for i in range(r):
                Dt[j, i] = -v * dx[i] * aj  # ∂(X a)/∂τ_j
            m0, m1 = dlo[j], dhi[j]  # views from 0: vectorised
            dxs, djs, dvs = dx[m0:m1], dtt[j, m0:m1], Dt[n, m0:m1]
            for i in range(m1 - m0):
                dvs[i] += dxs[i] * djs[i] * aj  # ∂(X a)/∂v: Σ_j K'(…) dt_j A_j
        for j in range(n + 1):
            # Mᵀ D, each sum in the rows' order (the terms of zeros left out)
            span_dots(Mt[c], p, Dt[j], dlo[j], dhi[j], mlo, mhi, Et[j])
            # F = (MᵀM)⁻¹ Mᵀ D, each sum in the columns' order; Mᵀ D's zeros (rows out
            # of D's reach) left out when (MᵀM)⁻¹ is finite: the same numbers
            nz = 0
            for m in range(p):
                if not (g_finite and Et[j, m] == 0.0):
                    cols[nz] = m
                    nz += 1
            for i in range(p):
                s = 0.0
                for q_ in range(nz):
                    m = cols[q_]
                    s += Ginv[c, i, m] * Et[j, m]
                F[i] = s
            _span_combination(Mt[c], p, F, mlo, mhi, acc)  # M F (sums in the columns' order)
            for i in range(r):  # J = M (MᵀM)⁻¹ Mᵀ D − D
                Jt[j, c * r + i] = (acc[i] - Dt[j, i]) * k


@njit(cache=True)
def jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt):
    """The variable-projection Jacobian (Kaufman) of :func:`least_squares`' residual in
    (τ_1 … τ_n, v), transposed, written into ``Jt`` (n + 1, 2 r): with ``D`` the
    derivatives of the atoms times their amplitudes (∂/∂τ_i: ``−v K'(…) A_i``; ∂/∂v:
    ``Σ_i K'(…) dt_i A_i``), ``J = (M (MᵀM)⁻¹ Mᵀ D − D) k``."""
    p, r = Mt.shape[1], Mt.shape[2]
    lo = np.zeros((2, p), dtype=np.int64)
    hi = np.full((2, p), r, dtype=np.int64)
    _given_spans(Mt, dXt, dtt, a.shape[1], lo, hi)
    _jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt, lo, hi)


@njit(cache=True)
def sorted_copy(x):
    """``x`` (1-D, a few values) ascending, a copy (insertion sort: np.sort's values,
    quicker to compile)."""
    out = x.copy()
    for i in range(1, out.size):
        v = out[i]
        j = i - 1
        while j >= 0 and out[j] > v:
            out[j + 1] = out[j]
            j -= 1
        out[j + 1] = v
    return out


@njit(cache=True)
def levenberg_marquardt(scalars, first, values, t, y, rest, params, iterations, k, converged,
                        every, fresh, dtt, Mt, dXt, Ginv, a, res, amps, gains):
    """Levenberg–Marquardt on (τ, v) over the variable projection of
    :func:`least_squares` (:func:`~bwim.detect.vehicle_fit.refine`): ``params`` (n + 1,)
    the sorted times and the speed, ``dtt`` … ``res`` their least squares with slopes
    (as :func:`least_squares` writes them) on entry, or, with ``fresh``, made here
    first (with ``amps`` and ``gains``: :func:`least_squares`' numbers); on return the
    last accepted times and speed and their least squares, with their amplitudes
    ``amps`` and removal costs ``gains`` (left as they are when no trial was accepted;
    ``every`` the sampling step).  Returns the misfit ``Σ res²``.

    Per iteration: ``Js = J s`` (``s = 1 / v₀`` per column: metres), ``A = JsᵀJs``,
    ``g = Jsᵀ r``; up to 8 trials of ``(A + λ diag(diag(A) + 1e-12)) x = g``, step ``−x
    s``; a trial with a speed ≤ 0 or a misfit not below (or not finite) multiplies λ by
    10, an accepted one divides it by 3 (at least 1e-7).  Stops without an accepted
    trial, when the misfit fell by less than ``converged`` of itself, or the times moved
    by less than 5 mm of travel."""
    n = params.size - 1
    r = t.size
    q = rest.shape[1]
    p = n + q
    # where the atoms may not be zero (zero_reach): the entry's by a look at its rows
    # (or from _fill when made here), each trial's from _fill
    flat = np.empty((2, 2), dtype=np.int64)
    fast = zero_reach(scalars, first, values, t, y, rest, flat)
    cur_lo = np.zeros((2, p), dtype=np.int64)
    cur_hi = np.full((2, p), r, dtype=np.int64)
    if fresh:
        _fill(scalars, first, values, t, y, rest, params[:n], params[n], k, dtt, Mt, dXt,
              Ginv, a, res, fast, flat, cur_lo, cur_hi)
        _removal_costs(a, Ginv, every, amps, gains)
    else:
        _given_spans(Mt, dXt, dtt, n, cur_lo, cur_hi)
    cost = 0.0
    for i in range(2 * r):
        cost += res[i] * res[i]
    lam = 1e-3
    scale = 1.0 / params[n]  # τ in s, v in m/s: metres
    cur_dtt, cur_Mt, cur_dXt, cur_Ginv, cur_a, cur_res = dtt, Mt, dXt, Ginv, a, res
    accepted = 0
    Jt = np.empty((n + 1, 2 * r))
    A = np.empty((n + 1, n + 1))
    g = np.empty(n + 1)
    damped = np.empty((n + 1, n + 1))
    x = np.empty(n + 1)
    step = np.empty(n + 1)
    trial = np.empty(n + 1)
    piv = np.empty(n + 1, dtype=np.int64)
    rel = 0.0
    for _ in range(iterations):
        _jacobian(cur_Mt, cur_Ginv, cur_a, cur_dXt, cur_dtt, params[n], k, Jt, cur_lo,
                  cur_hi)
        for j in range(n + 1):
            for i in range(2 * r):
                Jt[j, i] *= scale
        _gram(Jt, n + 1, A)  # A = JsᵀJs, g = Jsᵀr
        _dots(Jt, n + 1, cur_res, g)
        improved = False
        for _ in range(8):
            for i in range(n + 1):
                for j in range(n + 1):
                    damped[i, j] = A[i, j]
                damped[i, i] += lam * (damped[i, i] + 1e-12)
                x[i] = g[i]
            if not _lu(damped, piv):
                raise np.linalg.LinAlgError("singular matrix")
            _lu_solve(damped, piv, x)
            for i in range(n + 1):
                step[i] = -x[i] * scale
                trial[i] = params[i] + step[i]
            tt = sorted_copy(trial[:n])
            vv = trial[n]
            if vv <= 0:
                lam *= 10.0
                continue
            t_dtt = np.empty((n, r))
            t_Mt = np.empty((2, p, r))
            t_dXt = np.empty((2, n, r))
            t_Ginv = np.empty((2, p, p))
            t_a = np.empty((2, n))
            t_res = np.empty(2 * r)
            t_lo = np.empty((2, p), dtype=np.int64)
            t_hi = np.empty((2, p), dtype=np.int64)
            _fill(scalars, first, values, t, y, rest, tt, vv, k, t_dtt, t_Mt, t_dXt, t_Ginv,
                  t_a, t_res, fast, flat, t_lo, t_hi)
            c2 = 0.0
            for i in range(2 * r):
                c2 += t_res[i] * t_res[i]
            # a step that moves an axle off the window leaves its column zero at a
            # detector: the fit is degenerate, its misfit not finite, the step rejected
            if math.isfinite(c2) and c2 < cost:
                rel = (cost - c2) / max(cost, 1e-300)
                cur_dtt, cur_Mt, cur_dXt, cur_Ginv, cur_a, cur_res = t_dtt, t_Mt, t_dXt, \
                    t_Ginv, t_a, t_res
                cur_lo, cur_hi = t_lo, t_hi
                accepted += 1
                for i in range(n):
                    params[i] = tt[i]
                params[n] = vv
                cost = c2
                lam = max(lam / 3.0, 1e-7)
                improved = True
                break
            lam *= 10.0
        moved = 0.0
        for i in range(n):
            moved = max(moved, abs(step[i]))
        if not improved or rel < converged or moved * params[n] < 5e-3:
            break
    if accepted:
        _copy(cur_dtt, dtt)
        _copy(cur_Mt, Mt)
        _copy(cur_dXt, dXt)
        _copy(cur_Ginv, Ginv)
        _copy(cur_a, a)
        _copy(cur_res, res)
        _removal_costs(a, Ginv, every, amps, gains)
    return cost


@njit(cache=True)
def pursuit_trial(scalars, first, values, t, tk, tk2, v, Qt, y, Xt, G, p, amps, res):
    """The pursuit's trial (:mod:`bwim.detect.pursuit` ``_Pursuit.trial``): the atoms of
    an axle at ``tk`` (detector 1) and ``tk2`` (detector 2) at speed ``v`` on the
    record's times ``t`` (n_t,), less their projection on the rest's orthonormal basis
    (``Qt`` (2, q, n_t): its columns, one per row), written as row ``p`` of ``Xt`` (2,
    ≥ p + 1, n_t) after the ``p`` accepted axles' rows; the Gram matrix ``G`` (2, ≥ p +
    1, ≥ p + 1) grows by its products (no ridge); the amplitudes ``amps`` (p + 1, 2)
    solve ``(G + ridge) a = Xᵀ y`` (``y`` (2, n_t) the readings less their projection,
    the ridge of :func:`~bwim.detect.vehicle_fit.ridged_normal`), ``res`` (n_t, 2) ``y
    − X a``.  Returns the misfit ``Σ res²``."""
    n_t = t.size
    flat = np.zeros((2, 2), dtype=np.int64)
    lo = np.zeros((2, p + 1), dtype=np.int64)
    hi = np.full((2, p + 1), n_t, dtype=np.int64)
    return _trial(scalars, first, values, t, tk, tk2, v, Qt, y, Xt, G, p, amps, res, False,
                  flat, lo, hi, np.empty((2, p + 1)), 0)


@njit(cache=True)
def _trial(scalars, first, values, t, tk, tk2, v, Qt, y, Xt, G, p, amps, res, fast, flat, lo,
           hi, xty, known):
    """:func:`pursuit_trial`; with ``fast`` (:func:`zero_reach` of the grids, ``t``,
    ``y`` and ``Qt``) the atoms only where they may not be zero (+0 × weight elsewhere)
    and the sums over the rows' spans ``lo``, ``hi`` (2, ≥ p + 1: the accepted rows',
    row p's written here; the whole record once projected on the rest): the same
    numbers (:func:`span_dots`).  ``xty`` (2, ≥ p + 1): the rows' products with ``y``,
    the first ``known`` as made by an earlier trial (the same rows: the same numbers),
    the others made here."""
    n_t, q = t.size, Qt.shape[1]
    x = np.empty(n_t)
    dt = np.empty(n_t)
    acc = np.empty(n_t)
    proj = np.empty(q)
    ridged = np.empty((p + 1, p + 1))
    b = np.empty(p + 1)
    gx = np.empty(p + 1)
    piv = np.empty(p + 1, dtype=np.int64)
    every_lo = np.zeros(q, dtype=np.int64)
    every_hi = np.full(q, n_t, dtype=np.int64)
    chi = 0.0
    fast = fast and v > 0.0 and v - v == 0.0 and tk - tk == 0.0 and tk2 - tk2 == 0.0
    for c in range(2):
        tc = tk if c == 0 else tk2
        for i in range(n_t):
            dt[i] = t[i] - tc
        i0, i1 = _reach(v, dt, c, scalars, flat) if fast else (0, n_t)
        _fill_with(x[:i0], 0.0 * scalars[3, c])  # beyond the response's reach
        for i in range(i0, i1):
            x[i] = _atom(v, dt[i], c, scalars, first, values)[0]
        _fill_with(x[max(i0, i1):], 0.0 * scalars[3, c])
        lo[c, p], hi[c, p] = (i0, i1) if i0 < i1 else (0, 0)
        if q:  # x − Q (Qᵀ x) (Qᵀ x over the atom's rows alone)
            span_dots(Qt[c], q, x, lo[c, p], hi[c, p], every_lo, every_hi, proj)
            _fill_with(acc, 0.0)
            for j in range(q):
                pj = proj[j]
                qj = Qt[c, j]
                for i in range(n_t):
                    acc[i] += qj[i] * pj
            for i in range(n_t):
                x[i] -= acc[i]
            lo[c, p], hi[c, p] = 0, n_t
        for i in range(n_t):
            Xt[c, p, i] = x[i]
        # the new response's products and Xᵀy (each sum in the samples' order)
        span_dots(Xt[c], p + 1, x, lo[c, p], hi[c, p], lo[c], hi[c], gx)
        if known < p + 1:
            span_dots(Xt[c, known:], p + 1 - known, y[c], 0, n_t, lo[c, known:],
                      hi[c, known:], xty[c, known:])
        for m in range(p + 1):
            b[m] = xty[c, m]
        for m in range(p + 1):
            G[c, m, p] = gx[m]
            G[c, p, m] = gx[m]
        for i in range(p + 1):
            for j in range(p + 1):
                ridged[i, j] = G[c, i, j]
        _ridge(ridged, p + 1)
        if not _lu(ridged, piv):
            raise np.linalg.LinAlgError("Singular matrix")
        _lu_solve(ridged, piv, b)
        for m in range(p + 1):
            amps[m, c] = b[m]
        _span_combination(Xt[c], p + 1, b, lo[c], hi[c], acc)  # X a (the axles' order)
        for i in range(n_t):
            e = y[c, i] - acc[i]
            res[i, c] = e
            chi += e * e
    return chi


@njit(cache=True)
def best_match(res, atoms, lo, length, pad, slack, energy, excluded, corr, picked):
    """The matcher's choice (:mod:`bwim.detect.pursuit` ``_Matcher.best``): per detector
    ``corr[c, m] = Σ_i res[c, pad + m + lo[c] + i] atoms[c, i]``, i < ``length[c]``
    (``res`` (2, pad + n + pad), zeros in the pads; ``atoms`` (2, ≥ length)); the score
    ``max(corr_1 + max(corr_2 within ±slack), 0)² / energy``, 0 where ``excluded``;
    writes ``picked`` (2,): its argmax ``m`` (the first of equals) and where the second
    detector's best within ±slack of ``m`` was (the first of equals)."""
    n = corr.shape[1]
    finite = _all_finite(res)
    for c in range(2):
        # each sum in the atom's order (the loop over the samples m innermost); the
        # atom's leading and trailing zeros left out when the residual is finite (a
        # zero times it is ±0, and a sum from +0 never becomes −0: the same numbers)
        out = corr[c]
        _fill_with(out, 0.0)
        L = length[c]
        i = 0
        if finite:
            while i < L and atoms[c, i] == 0.0:
                i += 1
            while L > i and atoms[c, L - 1] == 0.0:
                L -= 1
        while i < L:  # four terms a pass, added one after the other
            base = pad + lo[c] + i
            if i + 4 <= L:
                a0, a1, a2, a3 = atoms[c, i], atoms[c, i + 1], atoms[c, i + 2], atoms[c, i + 3]
                z0 = res[c, base:base + n]
                z1 = res[c, base + 1:base + 1 + n]
                z2 = res[c, base + 2:base + 2 + n]
                z3 = res[c, base + 3:base + 3 + n]
                for m in range(n):
                    o = out[m]
                    o += z0[m] * a0
                    o += z1[m] * a1
                    o += z2[m] * a2
                    o += z3[m] * a3
                    out[m] = o
                i += 4
            else:
                ai = atoms[c, i]
                z = res[c, base:base + n]
                for m in range(n):
                    out[m] += z[m] * ai
                i += 1
    best = -1.0
    at = 0
    for m in range(n):
        c2 = corr[1, m]
        for j in range(max(m - slack, 0), min(m + slack + 1, n)):
            if corr[1, j] > c2:
                c2 = corr[1, j]
        z = corr[0, m] + c2
        if z < 0.0:
            z = 0.0
        score = z * z / energy
        if excluded[m]:
            score = 0.0
        if score > best:
            best = score
            at = m
    picked[0] = at
    a = max(at - slack, 0)
    top = a
    for j in range(a, min(at + slack + 1, n)):
        if corr[1, j] > corr[1, top]:
            top = j
    picked[1] = top


@njit(cache=True)
def _before(a, b):
    """numpy's order of floats for sorting and searching: ``a < b``, NaN after all."""
    return a < b or (b != b and a == a)


@njit(cache=True)
def search_sorted(t, x, right):
    """``t.searchsorted(x, side="right" if right else "left")``: numpy's bisection with
    numpy's order (:func:`_before`), the same index."""
    lo, hi = 0, t.size
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        if (not _before(x, t[mid])) if right else _before(t[mid], x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _exclude_near(t, excluded, tk, gap):
    """The matcher's exclusion (:mod:`bwim.detect.pursuit` ``_Matcher.exclude``):
    ``excluded[a:b] |= |t[a:b] − tk| < gap`` with ``a = max(searchsorted(tk − gap) − 1,
    0)``, ``b = searchsorted(tk + gap, "right") + 1``."""
    a = max(search_sorted(t, tk - gap, False) - 1, 0)
    b = min(search_sorted(t, tk + gap, True) + 1, t.size)
    for i in range(a, b):
        if abs(t[i] - tk) < gap:
            excluded[i] = True


@njit(cache=True)
def _reaches(amps, p, min_height):
    """Whether the last axle (row ``p``) of ``amps`` (p + 1, 2) reaches ``min_height`` of
    the largest amplitude at both detectors (:mod:`bwim.detect.pursuit`
    ``_acceptable``): numpy's column maximum (NaN if one is), ``a / (top if top > 0 else
    1) >= min_height``."""
    for c in range(2):
        top = amps[0, c]
        nan = top != top
        for i in range(1, p + 1):
            x = amps[i, c]
            if x != x:
                nan = True
            elif x > top:
                top = x
        if nan:
            top = np.nan
        if not amps[p, c] / (top if top > 0 else 1.0) >= min_height:
            return False
    return True


@njit(cache=True)
def pursuit_loop(scalars, first, values, t, v, Qt, y, Xt, G, res, pad, atoms, lo, length,
                 slack, energy, excluded, corr, gap, chi, thr2, share, min_height, max_axles,
                 tries, taus, taus2, out):
    """The pursuit (:func:`bwim.detect.pursuit.pursue_axles`' loop), its steps those of
    :func:`best_match`, :func:`pursuit_trial`, :func:`_exclude_near` and
    :func:`_reaches` (``_Matcher.best``, ``_Pursuit.trial``, ``_Matcher.exclude``,
    ``_acceptable``, ``_Pursuit.accept``): up to ``tries`` times the best new axle for
    the residual ``res`` (2, pad + n_t + pad) and its trial; stop when it lowers the
    misfit ``chi`` by less than ``thr2`` and ``share`` of the strongest fall so far (as
    Python's ``max`` takes them) or ``max_axles`` are taken; else exclude its
    neighbourhood and, when its amplitudes reach ``min_height``, take it (its residual
    into ``res``, its times into ``taus``, ``taus2``).  Returns the number taken;
    ``out[0]`` the strongest fall, ``out[1]`` the misfit with the axles taken."""
    n_t = t.size
    picked = np.zeros(2, dtype=np.int64)
    flat = np.empty((2, 2), dtype=np.int64)
    fast = zero_reach(scalars, first, values, t, y, Qt, flat)
    row_lo = np.zeros((2, Xt.shape[1]), dtype=np.int64)  # the rows' spans (_trial)
    row_hi = np.full((2, Xt.shape[1]), n_t, dtype=np.int64)
    xty = np.empty((2, Xt.shape[1]))  # the accepted rows' products with y
    top = 0.0
    p = 0
    for _ in range(tries):
        best_match(res, atoms, lo, length, pad, slack, energy, excluded, corr, picked)
        tk, tk2 = t[picked[0]], t[picked[1]]
        amps = np.empty((p + 1, 2))
        trial_res = np.empty((n_t, 2))
        chi_new = _trial(scalars, first, values, t, tk, tk2, v, Qt, y, Xt, G, p, amps,
                         trial_res, fast, flat, row_lo, row_hi, xty, p)
        gain = chi - chi_new
        if gain > top:  # max(top, gain)
            top = gain
        bar = share * top
        if not bar > thr2:  # max(thr2, share × top)
            bar = thr2
        if gain < bar or p >= max_axles:
            break
        _exclude_near(t, excluded, tk, gap)  # taken, or not seen: not tried again
        if not _reaches(amps, p, min_height):
            continue
        for c in range(2):
            for i in range(n_t):
                res[c, pad + i] = trial_res[i, c]
        taus[p] = tk
        taus2[p] = tk2
        p += 1
        chi = chi_new
    out[0] = top
    out[1] = chi
    return p


@njit(cache=True)
def matcher_atom(u, k, scale, v, fs, d, m_lo, out):
    """The matcher's atom of one detector (:mod:`bwim.detect.pursuit` ``_Matcher``):
    ``out[i] = numpy.interp(v (m_lo + i) / fs − d, u, k, left=0, right=0) × scale``
    for every i < ``out.size``: numpy's operations (the sample's distance, then
    numpy.interp's interval, slope and value, written out as its C loop makes them,
    NaN retries included), the same numbers."""
    n = u.size
    j = 0
    for i in range(out.size):
        x = v * float(m_lo + i) / fs - d
        if x != x:
            y = x
        elif x < u[0]:
            y = 0.0
        elif x > u[n - 1]:
            y = 0.0
        else:
            if x < u[j]:
                j = 0
            while j < n - 1 and u[j + 1] <= x:
                j += 1
            if j == n - 1 or x == u[j]:
                y = k[j]
            else:
                slope = (k[j + 1] - k[j]) / (u[j + 1] - u[j])
                y = slope * (x - u[j]) + k[j]
                if math.isnan(y):
                    y = slope * (x - u[j + 1]) + k[j + 1]
                    if math.isnan(y) and k[j] == k[j + 1]:
                        y = k[j]
        out[i] = y * scale
