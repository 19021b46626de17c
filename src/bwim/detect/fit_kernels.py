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
           "levenberg_marquardt", "pursuit_trial", "sorted_copy", "symmetric_pinv"]


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
    scalars = np.array([[shift[c] + u[c][0] for c in range(2)],
                        [1.0 / d for d in du],
                        [ui.size - 1.000001 for ui in u],
                        [float(w[c]) for c in range(2)],
                        [w[c] / du[c] for c in range(2)]], dtype=float)
    first = np.array([0, u[0].size], dtype=np.int64)
    values = np.array([np.concatenate([g[1] for g in grids]), np.concatenate(steps)],
                      dtype=float)
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
    :meth:`~bwim.detect.vehicle_fit.Problem.both_atoms` in numpy."""
    want = slopes.size > 0
    for c in range(2):
        d = c if dt.shape[0] > 1 else 0
        for i in range(dt.shape[1]):
            for j in range(dt.shape[2]):
                a, s = _atom(v, dt[d, i, j], c, scalars, first, values)
                out[c, i, j] = a
                if want:
                    slopes[c, i, j] = s


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
    """``G[i, j] = Σ_m A[i, m] A[j, m]`` for i, j < ``n`` (:func:`_dots`; symmetric:
    a product is the same number either way round)."""
    for j in range(n):
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
def _fill(scalars, first, values, t, y, rest, taus, v, k, dtt, Mt, dXt, Ginv, a, res):
    """One least squares (see :func:`least_squares`), written into the arrays given
    (``dXt`` empty for no slopes)."""
    r, n, q = t.size, taus.size, rest.shape[1]
    p = n + q
    for j in range(n):
        for i in range(r):
            dtt[j, i] = t[i] - taus[j]
    want = dXt.size > 0
    G = np.empty((p, p))
    b = np.empty(p)
    e = np.empty(p)
    piv = np.empty(p, dtype=np.int64)
    coef = np.empty(p)
    acc = np.empty(r)
    for c in range(2):
        for j in range(n):
            for i in range(r):
                x, s = _atom(v, dtt[j, i], c, scalars, first, values)
                Mt[c, j, i] = x
                if want:
                    dXt[c, j, i] = s
        for j in range(q):
            for i in range(r):
                Mt[c, n + j, i] = rest[c, j, i]
        _gram(Mt[c], p, G)  # G = MᵀM, b = Mᵀy, each sum in the rows' order
        _dots(Mt[c], p, y[c], b)
        _ridge(G, p)
        if _lu(G, piv):  # (MᵀM)⁻¹ column by column
            for j in range(p):
                _fill_with(e, 0.0)
                e[j] = 1.0
                _lu_solve(G, piv, e)
                for i in range(p):
                    Ginv[c, i, j] = e[i]
        else:  # an exact zero pivot (numpy's inv raising): the pseudo-inverse
            _gram(Mt[c], p, G)
            _ridge(G, p)
            symmetric_pinv(G, Ginv[c])
        for i in range(p):  # coef = (MᵀM)⁻¹ Mᵀy
            s = 0.0
            for j in range(p):
                s += Ginv[c, i, j] * b[j]
            coef[i] = s
        for j in range(n):
            a[c, j] = coef[j]
        _fill_with(acc, 0.0)  # M coef (each sum in the columns' order)
        for j in range(p):
            cj = coef[j]
            mj = Mt[c, j]
            for i in range(r):
                acc[i] += mj[i] * cj
        yc = y[c]
        for i in range(r):  # residual y − M coef, scaled to all samples
            res[c * r + i] = (yc[i] - acc[i]) * k


@njit(cache=True)
def least_squares(scalars, first, values, t, y, rest, taus, v, k, dtt, Mt, dXt, Ginv, a, res):
    """Both detectors' least squares of the axles ``taus`` (n,) at speed ``v`` on a
    window's rows: times ``t`` (r,), readings ``y`` (2, r), rest columns ``rest``
    (2, q, r; one per row).  Writes ``dtt`` (n, r) the rows' times less each axle's,
    ``Mt`` (2, p = n + q, r) the design matrix transposed (the atoms, then the rest),
    ``dXt`` (2, n, r) the atoms' slopes (or pass it empty (0, 0, 0): none), ``Ginv``
    (2, p, p) ``(MᵀM + ridge)⁻¹``, ``a`` (2, n) the axles' amplitudes and ``res``
    (2 r,) the residual ``y − M (MᵀM)⁻¹ Mᵀy``, both detectors end to end, times ``k``
    (√ of the sampling step: scaled to all samples)."""
    _fill(scalars, first, values, t, y, rest, taus, v, k, dtt, Mt, dXt, Ginv, a, res)


@njit(cache=True)
def _jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt):
    p, r = Mt.shape[1], Mt.shape[2]
    n = a.shape[1]
    Dt = np.empty((n + 1, r))
    Et = np.empty((n + 1, p))
    F = np.empty(p)
    acc = np.empty(r)
    for c in range(2):
        _fill_with(Dt[n], 0.0)
        for j in range(n):
            aj = a[c, j]
            dx = dXt[c, j]
            dj = dtt[j]
            for i in range(r):
                Dt[j, i] = -v * dx[i] * aj  # ∂(X a)/∂τ_j
                Dt[n, i] += dx[i] * dj[i] * aj  # ∂(X a)/∂v: Σ_j K'(…) dt_j A_j
        for j in range(n + 1):
            _dots(Mt[c], p, Dt[j], Et[j])  # Mᵀ D, each sum in the rows' order
            for i in range(p):  # F = (MᵀM)⁻¹ Mᵀ D
                s = 0.0
                for m in range(p):
                    s += Ginv[c, i, m] * Et[j, m]
                F[i] = s
            _fill_with(acc, 0.0)  # M F (each sum in the columns' order)
            for m in range(p):
                fm = F[m]
                mm = Mt[c, m]
                for i in range(r):
                    acc[i] += mm[i] * fm
            for i in range(r):  # J = M (MᵀM)⁻¹ Mᵀ D − D
                Jt[j, c * r + i] = (acc[i] - Dt[j, i]) * k


@njit(cache=True)
def jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt):
    """The variable-projection Jacobian (Kaufman) of :func:`least_squares`' residual in
    (τ_1 … τ_n, v), transposed, written into ``Jt`` (n + 1, 2 r): with ``D`` the
    derivatives of the atoms times their amplitudes (∂/∂τ_i: ``−v K'(…) A_i``; ∂/∂v:
    ``Σ_i K'(…) dt_i A_i``), ``J = (M (MᵀM)⁻¹ Mᵀ D − D) k``."""
    _jacobian(Mt, Ginv, a, dXt, dtt, v, k, Jt)


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
                        dtt, Mt, dXt, Ginv, a, res):
    """Levenberg–Marquardt on (τ, v) over the variable projection of
    :func:`least_squares` (:func:`~bwim.detect.vehicle_fit.refine`): ``params`` (n + 1,)
    the sorted times and the speed, ``dtt`` … ``res`` their least squares with slopes
    (as :func:`least_squares` writes them) on entry; on return the last accepted times
    and speed and their least squares.  Returns the misfit ``Σ res²``.

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
        _jacobian(cur_Mt, cur_Ginv, cur_a, cur_dXt, cur_dtt, params[n], k, Jt)
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
            _fill(scalars, first, values, t, y, rest, tt, vv, k, t_dtt, t_Mt, t_dXt, t_Ginv,
                  t_a, t_res)
            c2 = 0.0
            for i in range(2 * r):
                c2 += t_res[i] * t_res[i]
            # a step that moves an axle off the window leaves its column zero at a
            # detector: the fit is degenerate, its misfit not finite, the step rejected
            if math.isfinite(c2) and c2 < cost:
                rel = (cost - c2) / max(cost, 1e-300)
                cur_dtt, cur_Mt, cur_dXt, cur_Ginv, cur_a, cur_res = t_dtt, t_Mt, t_dXt, \
                    t_Ginv, t_a, t_res
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
    n_t, q = t.size, Qt.shape[1]
    x = np.empty(n_t)
    acc = np.empty(n_t)
    proj = np.empty(q)
    ridged = np.empty((p + 1, p + 1))
    b = np.empty(p + 1)
    gx = np.empty(p + 1)
    piv = np.empty(p + 1, dtype=np.int64)
    chi = 0.0
    for c in range(2):
        tc = tk if c == 0 else tk2
        for i in range(n_t):
            x[i] = _atom(v, t[i] - tc, c, scalars, first, values)[0]
        if q:  # x − Q (Qᵀ x)
            _dots(Qt[c], q, x, proj)
            _fill_with(acc, 0.0)
            for j in range(q):
                pj = proj[j]
                qj = Qt[c, j]
                for i in range(n_t):
                    acc[i] += qj[i] * pj
            for i in range(n_t):
                x[i] -= acc[i]
        for i in range(n_t):
            Xt[c, p, i] = x[i]
        # the new response's products and Xᵀy (each sum in the samples' order)
        _dots(Xt[c], p + 1, x, gx)
        _dots(Xt[c], p + 1, y[c], b)
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
        _fill_with(acc, 0.0)  # X a (each sum in the axles' order)
        for m in range(p + 1):
            amps[m, c] = b[m]
            bm = b[m]
            xm = Xt[c, m]
            for i in range(n_t):
                acc[i] += xm[i] * bm
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
    for c in range(2):
        # each sum in the atom's order (the loop over the samples m innermost)
        out = corr[c]
        _fill_with(out, 0.0)
        L = length[c]
        i = 0
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
