"""Compiled loops of :mod:`bwim.detect.groups` (numba): the same equations, the same numbers.

Contract
--------
* Each kernel computes what :mod:`bwim.detect.groups` documents, as loops compiled by
  numba (``cache=True``, no fastmath, no parallel) instead of numpy calls over tiny arrays
  (a vehicle's window holds a few hundred samples: numpy's cost was its calls).
* The numbers are numpy's, operation for operation, where numpy's order is known:
  sums of fewer than 8 terms one after the other from 0 (numpy's order:
  :func:`bwim.detect.signals.last_axis_sum`), longer ones pairwise as numpy's sum
  (:func:`pairwise_sum`); dot products and the correlations' inner products by BLAS
  ``ddot`` as numpy's (:func:`correlation_at`: numpy's own loop for kernels of at most 11
  values); the readings less the rest by BLAS ``gemv`` (as numpy's matmul);
  ``numpy.interp`` written out (its interval, slope and value); each evenly spaced
  system's inverse by LAPACK ``gesv`` on the identity (as ``numpy.linalg.inv``), applied
  by BLAS ``gemv`` (as numpy's matmul), a hypothesis's system by ``gesv`` (as
  ``numpy.linalg.solve``).  numba calls scipy's OpenBLAS, numpy its own: the same
  kernels, measured equal on this machine (the unit tests check it, bit for bit).
* Evenly spaced hypotheses: a hypothesis's BLAS product is made only where a cheap look
  (its plain products, and a bound on how far any order of their sums, BLAS's included,
  can be from them: ``k u Σ|terms|`` per sum, taken 4 times over) says it might be valid
  and might beat the best so far; a hypothesis skipped is surely invalid or surely not
  larger, so the choice (the first largest valid one, numpy's argmax) is the same.
* One exception: logarithms are the C library's, numpy's may be its own SIMD ones; the two
  can differ in the last bit, which changes a decision only where an axle's log gain
  ratio lies within that bit of the bound.
* The thresholds are arguments (constants of :mod:`bwim.detect.groups`), never globals
  (numba would freeze them into its cache).
* Arrays are float64 and int64, C order; grid points every ``st``-th sample of a window.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bwim.detect.fit_kernels import sorted_copy
from bwim.pairwise import pairwise_sum

__all__ = [
    "choose_in_window",
    "correlation_at",
    "evenly_kernel",
    "explained_kernel",
    "grid_autocorrelation",
    "group_choices",
    "one_axle_may_fit_at",
    "one_axle_points",
    "one_axle_tolerance",
    "response_on_samples",
    "segment_bounds",
    "short_sum",
]


@njit(cache=True)
def short_sum(a):
    """``last_axis_sum`` of one row ``a`` (numpy's ``sum``): from 0 one value after the
    other below 8 values (2 … 7), else numpy's pairwise sum."""
    k = a.size
    if 2 <= k < 8:
        s = a[0] + 0.0
        for i in range(1, k):
            s += a[i]
        return s
    return pairwise_sum(a, k - k, k)  # (not a literal 0: one compiled signature)


@njit(cache=True)
def correlation_at(z, q, h):
    """``numpy.correlate(z, h, "valid")[q]`` (``z.size >= h.size``), the same number:
    numpy's own loop for at most 11 values of ``h``, BLAS ``ddot`` beyond."""
    n = h.size
    if n <= 11:
        s = 0.0
        for j in range(n):
            s += z[q + j] * h[j]
        return s
    return np.dot(z[q:q + n], h)


@njit(cache=True)
def response_on_samples(u, k, w, v, fs, d):
    """:func:`bwim.detect.groups.responses` of one detector (grid ``u``, ordinates ``k``,
    weight ``w``, shift ``d``): the first sample and the weighted response on the samples
    (``numpy.interp``'s numbers: its interval, slope and value, written out)."""
    j0 = math.ceil((u[0] + d) / v * fs)
    j1 = math.floor((u[-1] + d) / v * fs)
    h = np.empty(max(j1 - j0 + 1, 0))
    n = u.size
    j = 0
    for i in range(h.size):
        x = v * float(j0 + i) / fs - d
        # numpy.interp: the interval u[j] <= x < u[j + 1], its slope and value
        if x < u[0]:
            y = k[0]
        elif x > u[n - 1]:
            y = k[n - 1]
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
        h[i] = y * w
    return j0, h


@njit(cache=True)
def grid_autocorrelation(h, st, size):
    """``numpy.correlate(h, h, "full")[h.size - 1:]`` every ``st``-th lag, zero beyond the
    response, ``size`` values at least (the same numbers: numpy's own loop for lag 0 of at
    most 11 values, BLAS ``ddot`` of ``h[k:]`` and ``h[:n - k]`` for the rest, as numpy)."""
    n = h.size
    n_lags = (n - 1) // st + 1 if n else 0
    out = np.zeros(max(n_lags, size))
    for m in range(n_lags):
        k = m * st
        if k == 0:
            out[m] = correlation_at(h, 0, h)
        else:
            out[m] = np.dot(h[k:], h[:n - k])
    return out


@njit(cache=True)
def _sign_of_peak(k):
    """``np.sign`` of the value of ``k`` largest in magnitude (the first such)."""
    j, top = 0, -1.0
    for i in range(k.size):
        x = abs(k[i])
        if x > top or (math.isnan(x) and not math.isnan(top)):
            j, top = i, x
            if math.isnan(x):
                break
    x = k[j]
    return 1.0 if x > 0 else (-1.0 if x < 0 else (0.0 if x == 0 else x))


@njit(cache=True)
def segment_bounds(local, k0, k1, lag, margin, st, dip, extent, peak_floor):
    """:func:`bwim.detect.groups.segments` on the window's local readings ``local`` (2,
    n) with the responses' ordinates ``k0``, ``k1`` (their sign): (n_seg, 2) first and
    last grid points (``scipy.signal.find_peaks``' local maxima, heights and prominences
    as scipy computes them)."""
    n = local.shape[1]
    e = np.zeros(n)
    for c in range(2):
        sg = _sign_of_peak(k0 if c == 0 else k1)
        z = np.empty(n)
        top = -np.inf
        for i in range(n):
            x = local[c, i] * sg
            x = x if (x >= 0.0 or math.isnan(x)) else 0.0  # np.maximum(x, 0.0)
            z[i] = x
            if x > top or math.isnan(x):
                top = x
                if math.isnan(x):
                    break
        if top <= 0:
            continue
        shift = lag if c else 0
        for i in range(n - shift):
            e[i] += z[i + shift] / top
    emax = -np.inf
    for i in range(n):
        if e[i] > emax or math.isnan(e[i]):
            emax = e[i]
            if math.isnan(emax):
                break
    empty = np.zeros((0, 2), dtype=np.int64)
    if not emax > 0:
        return empty
    floor = peak_floor * emax
    # scipy's _local_maxima_1d (plateaus: their middle, rounded down)
    peaks = np.empty(n // 2 + 1, dtype=np.int64)
    n_peaks = 0
    i, i_max = 1, n - 1
    while i < i_max:
        if e[i - 1] < e[i]:
            i_ahead = i + 1
            while i_ahead < i_max and e[i_ahead] == e[i]:
                i_ahead += 1
            if e[i_ahead] < e[i]:
                peak = (i + i_ahead - 1) // 2
                # height, then prominence (scipy's _peak_prominences, whole signal)
                if floor <= e[peak]:
                    left_min = e[peak]
                    j = peak
                    while 0 <= j and e[j] <= e[peak]:
                        if e[j] < left_min:
                            left_min = e[j]
                        j -= 1
                    right_min = e[peak]
                    j = peak
                    while j <= n - 1 and e[j] <= e[peak]:
                        if e[j] < right_min:
                            right_min = e[j]
                        j += 1
                    if floor <= e[peak] - max(left_min, right_min):
                        peaks[n_peaks] = peak
                        n_peaks += 1
                i = i_ahead
        i += 1
    if n_peaks == 0:
        return empty
    # cuts: between neighbouring peaks a and b the first lowest sample of a … b - 1,
    # where it dips below ``dip`` of the lower peak
    cuts = np.empty(n_peaks + 1, dtype=np.int64)
    cuts[0] = 0
    n_cuts = 1
    for p in range(n_peaks - 1):
        a, b = peaks[p], peaks[p + 1]
        m = a
        for j in range(a + 1, b):
            if e[j] < e[m]:
                m = j
        if e[m] < dip * min(e[a], e[b]):
            cuts[n_cuts] = m
            n_cuts += 1
    out = np.empty((n_cuts, 2), dtype=np.int64)
    for p in range(n_cuts):
        a = cuts[p]
        b = cuts[p + 1] if p + 1 < n_cuts else n - 1
        high = -np.inf
        for j in range(a, b + 1):
            if e[j] > high or math.isnan(e[j]):
                high = e[j]
                if math.isnan(high):
                    break
        high = extent * high
        first, last = -1, -1
        for j in range(a, b + 1):
            if e[j] >= high:
                if first < 0:
                    first = j
                last = j
        out[p, 0] = max(first - margin, a) // st
        out[p, 1] = min(last + margin, b) // st
    return out


@njit(cache=True)
def one_axle_tolerance(resid, h0, h1):
    """The bound on the rounding of the one-axle test's correlations, per detector:
    ``1e-9 Σ|h| max|z| + 1e-300`` (numpy's sum and max, the same numbers)."""
    tol = np.empty(2)
    for c in range(2):
        h = h0 if c == 0 else h1
        zmax = 0.0
        for i in range(resid.shape[1]):
            x = abs(resid[c, i])
            if x > zmax or math.isnan(x):
                zmax = x
                if math.isnan(x):
                    break
        tol[c] = 1e-9 * pairwise_sum(np.abs(h), h.size - h.size, h.size) * zmax + 1e-300
    return tol


@njit(cache=True)
def one_axle_may_fit_at(resid, h0, h1, j0, auto00, auto10, st, m, tol, ratio, bound):
    """Whether one axle might fit the residual ``resid`` (2, n_rows) at grid point ``m``
    (see :func:`one_axle_points`; ``tol``: :func:`one_axle_tolerance`)."""
    n_rows = resid.shape[1]
    b0 = b1 = -np.inf  # no correlation: the response leaves the window
    for c in range(2):
        h = h0 if c == 0 else h1
        q = st * m + j0[c]
        if n_rows >= h.size and 0 <= q < n_rows - h.size + 1:
            if c == 0:
                b0 = correlation_at(resid[0], q, h)
            else:
                b1 = correlation_at(resid[1], q, h)
    if not (b0 > -tol[0] and b1 > -tol[1]):
        return False
    if not (b0 > 1e3 * tol[0] and b1 > 1e3 * tol[1]):
        return True  # near zero: let the exact test decide
    lr = math.log((b1 / max(auto10, 1e-300)) / (ratio * (b0 / max(auto00, 1e-300))))
    slack = 4.0 * (tol[0] / b0 + tol[1] / b1)
    return abs(lr) <= bound + slack + 1e-12


@njit(cache=True)
def one_axle_points(resid, h0, h1, j0, auto00, auto10, st, n_grid, ratio, bound):
    """:func:`bwim.detect.groups.one_axle_may_fit`: cumulative count (``n_grid + 1``)
    of the grid points where one axle might fit the residual ``resid`` (2, n_rows);
    ``h0``, ``h1`` the responses starting at samples ``j0`` (2,), ``auto00``, ``auto10``
    their autocorrelations at lag 0 (:func:`one_axle_may_fit_at` at every point)."""
    tol = one_axle_tolerance(resid, h0, h1)
    out = np.zeros(n_grid + 1, dtype=np.int64)
    for m in range(n_grid):
        ok = one_axle_may_fit_at(resid, h0, h1, j0, auto00, auto10, st, m, tol, ratio, bound)
        out[m + 1] = out[m] + (1 if ok else 0)
    return out


@njit(cache=True)
def _seen(a0, a1, ratio, bound):
    """An axle's amplitudes positive at both detectors and in their gain ratio."""
    return a0 > 0 and a1 > 0 and abs(math.log(a1 / (ratio * a0))) <= bound


@njit(cache=True)
def _better(score, best):
    """numpy's argmax order: the first NaN, else the first largest."""
    if math.isnan(best):
        return False
    return math.isnan(score) or score > best


@njit(cache=True)
def _inverse(auto, s, k):
    """``numpy.linalg.inv`` of the system of ``k`` axles ``s`` grid points apart
    (``auto`` at multiples of ``s``, a ridge of 1e-12 of its zero lag): LAPACK gesv on
    the identity, as numpy."""
    G = np.empty((k, k))
    ridge = 1e-12 * auto[0]
    for i in range(k):
        for j in range(k):
            G[i, j] = auto[s * abs(i - j)] + ridge * (1.0 if i == j else 0.0)
    eye = np.zeros((k, k))
    for i in range(k):
        eye[i, i] = 1.0
    return np.linalg.solve(G, eye)


@njit(cache=True)
def _even(c0, c1, off, start, s, k, inv0, inv1, b0, b1, a0, a1, ratio, bound):
    """One hypothesis of ``k`` axles ``s`` grid points apart from ``start`` (of the
    correlations ``c0``, ``c1`` from ``off``): its amplitudes into ``a0``, ``a1``, the
    misfit it removes and whether every axle is seen by both detectors."""
    for j in range(k):
        b0[j] = c0[off + start + s * j]
        b1[j] = c1[off + start + s * j]
    np.dot(inv0, b0, a0)
    np.dot(inv1, b1, a1)
    g0 = a0[0] * b0[0] + 0.0
    g1 = a1[0] * b1[0] + 0.0
    for j in range(1, k):
        g0 += a0[j] * b0[j]
        g1 += a1[j] * b1[j]
    valid = True
    for j in range(k):
        if not _seen(a0[j], a1[j], ratio, bound):
            valid = False
            break
    return g0 + g1, valid


#: The unit roundoff of float64.
_U = 2.0**-53


@njit(cache=True)
def _even_bound(c0, c1, off, start, s, k, inv0, inv1, b0, b1, lo_x, hi_x, ratio):
    """A cheap look at one hypothesis (see :func:`_even`) without BLAS: False where it is
    surely not valid (an axle's amplitude surely not positive, or its gain ratio surely
    beyond ``lo_x`` … ``hi_x``, the bound's exponentials), and an upper bound on the
    misfit :func:`_even` gives it (its plain products' sum plus a bound on both sums'
    rounding: any order of a k-term sum is within ``k u Σ|terms|`` of the exact one)."""
    for j in range(k):
        b0[j] = c0[off + start + s * j]
        b1[j] = c1[off + start + s * j]
    g = 0.0
    err = 1e-300
    maybe = True
    for i in range(k):
        x0 = x1 = 0.0
        m0 = m1 = 0.0
        for j in range(k):
            p0 = inv0[i, j] * b0[j]
            p1 = inv1[i, j] * b1[j]
            x0 += p0
            x1 += p1
            m0 += abs(p0)
            m1 += abs(p1)
        e0 = 8.0 * k * _U * m0 + 1e-300  # bounds |x - BLAS's amplitude| (2 k u Σ|p| at most)
        e1 = 8.0 * k * _U * m1 + 1e-300
        g += x0 * b0[i] + x1 * b1[i]
        err += (e0 * abs(b0[i]) + e1 * abs(b1[i])
                + 8.0 * k * _U * ((abs(x0) + e0) * abs(b0[i]) + (abs(x1) + e1) * abs(b1[i])))
        if maybe:
            if x0 + e0 <= 0.0 or x1 + e1 <= 0.0:
                maybe = False  # surely not positive at a detector
            elif x0 - e0 > 0.0 and x1 - e1 > 0.0:
                r = x1 / (ratio * x0)
                m = 2.0 * (e0 / (x0 - e0) + e1 / (x1 - e1)) + 1e-12
                if r < lo_x * (1.0 - m) or r > hi_x * (1.0 + m):
                    maybe = False  # surely not seen by both
    return maybe, g + err + 8.0 * _U * abs(g)


@njit(cache=True)
def _inverses(auto0, auto1, k, s_min, n_sp):
    """Each spacing's inverses (n_sp, 2, k, k)."""
    inv = np.empty((n_sp, 2, k, k))
    for i in range(n_sp):
        inv[i, 0] = _inverse(auto0, s_min + i, k)
        inv[i, 1] = _inverse(auto1, s_min + i, k)
    return inv


@njit(cache=True)
def evenly_kernel(lengths, k, s_min, s_max, c0, c1, auto0, auto1, ratio, bound):
    """:func:`bwim.detect.groups.evenly_explained`: ``(hyp, owner, gained, amps)`` of
    every segment's hypotheses of ``k`` (≥ 2) evenly spaced axles (segments' correlations
    end to end), each spacing's system inverted once; and whether each hypothesis's axles
    are all seen by both detectors (``ratio``, ``bound``)."""
    n_seg = lengths.size
    n_hyp = 0
    longest = 0
    for i in range(n_seg):
        L = lengths[i]
        longest = max(longest, L)
        for start in range(L):
            for s in range(s_min, s_max + 1):
                if start + (k - 1) * s <= L - 1:
                    n_hyp += 1
    hyp = np.empty((n_hyp, k), dtype=np.int64)
    owner = np.empty(n_hyp, dtype=np.int64)
    gained = np.empty(n_hyp)
    amps = np.empty((n_hyp, k, 2))
    valid = np.empty(n_hyp, dtype=np.bool_)
    if n_hyp == 0:
        return hyp, owner, gained, amps, valid
    n_sp = min(s_max - s_min + 1, (longest - 1) // (k - 1) - s_min + 1)
    inv = _inverses(auto0, auto1, k, s_min, n_sp)
    b0, b1, a0, a1 = np.empty(k), np.empty(k), np.empty(k), np.empty(k)
    h, off = 0, 0
    for i in range(n_seg):
        L = lengths[i]
        for start in range(L):
            for s in range(s_min, s_max + 1):
                if start + (k - 1) * s > L - 1:
                    break
                g, ok = _even(c0, c1, off, start, s, k, inv[s - s_min, 0],
                              inv[s - s_min, 1], b0, b1, a0, a1, ratio, bound)
                for j in range(k):
                    hyp[h, j] = start + s * j
                    amps[h, j, 0] = a0[j]
                    amps[h, j, 1] = a1[j]
                owner[h] = i
                gained[h] = g
                valid[h] = ok
                h += 1
        off += L
    return hyp, owner, gained, amps, valid


@njit(cache=True)
def _choice(c0, c1, off, L, auto0, auto1, outside, energy, limit, n_samples, s_min, s_max,
            ratio, bound, group_axles, level_gain, rare_group, invs, done, pos):
    """One segment's choice of its ``L`` grid points' correlations from ``off`` (see
    :func:`group_choices`): the misfit removed and the count, its grid points into
    ``pos``.  ``invs`` (count - 2, n_sp, 2, k, k at most) and ``done`` (count - 2, n_sp):
    the spacings' inverses made so far, filled on demand."""
    one0, one1 = max(auto0[0], 1e-300), max(auto1[0], 1e-300)
    best_g, best_j = -np.inf, -1
    for j in range(L):
        b0, b1 = c0[off + j], c1[off + j]
        a0, a1 = b0 / one0, b1 / one1
        g = a0 * b0 + 0.0
        g += a1 * b1
        sc = g if _seen(a0, a1, ratio, bound) else -np.inf
        if best_j < 0 or _better(sc, best_g):
            best_g, best_j = sc, j
    if best_j < 0 or not best_g > -np.inf:
        return 0.0, 0
    best, count = best_g, 1
    pos[0] = best_j
    lo_x, hi_x = math.exp(-bound), math.exp(bound)
    for k in range(2, group_axles + 1):
        b0, b1, a0, a1 = np.empty(k), np.empty(k), np.empty(k), np.empty(k)
        A0, A1 = np.empty((k, k)), np.empty((k, k))  # an inverse in C order, for BLAS
        top_g, top_s, top_start = -np.inf, -1, -1
        for start in range(L):
            for s in range(s_min, s_max + 1):
                if start + (k - 1) * s > L - 1:
                    break
                i = s - s_min
                if not done[k - 2, i]:
                    invs[k - 2, i, 0, :k, :k] = _inverse(auto0, s, k)
                    invs[k - 2, i, 1, :k, :k] = _inverse(auto1, s, k)
                    done[k - 2, i] = True
                inv0, inv1 = invs[k - 2, i, 0], invs[k - 2, i, 1]
                # numpy's numbers (BLAS) only where the hypothesis might be valid and
                # might beat the best so far (the bound: see _even_bound)
                maybe, most = _even_bound(c0, c1, off, start, s, k, inv0, inv1, b0, b1,
                                          lo_x, hi_x, ratio)
                if not maybe:
                    continue  # its score is -inf: it changes no choice
                if top_s >= 0 and (math.isnan(top_g) or most < top_g):
                    continue  # it cannot be the first largest
                A0[:, :] = inv0[:k, :k]
                A1[:, :] = inv1[:k, :k]
                g, ok = _even(c0, c1, off, start, s, k, A0, A1, b0, b1, a0, a1, ratio, bound)
                sc = g if ok else -np.inf
                if top_s < 0 or _better(sc, top_g):
                    top_g, top_s, top_start = sc, s, start
        if top_s < 0 or not top_g > -np.inf:
            break
        gain = top_g - best
        level = (outside + (energy - best)) / n_samples
        rare = rare_group if k > 3 else 1.0
        if gain < limit or gain < level_gain * rare * level:
            break
        best, count = top_g, k
        for j in range(k):
            pos[j] = top_start + top_s * j
    return best, count


@njit(cache=True)
def group_choices(c0, c1, lengths, auto0, auto1, outside, energies, limit, n_samples, s_min,
                  s_max, ratio, bound, group_axles, level_gain, rare_group):
    """:func:`bwim.detect.groups.group_counts`: each segment's (``lengths`` grid points,
    correlations ``c0``, ``c1`` end to end) misfit removed, count (0: no single axle is
    valid) and grid points (n_seg, group_axles), one segment after the other; each
    spacing's inverses made once, when first asked for."""
    n_seg = lengths.size
    n_sp = max(s_max - s_min + 1, 0)
    invs = np.empty((max(group_axles - 1, 0), n_sp, 2, group_axles, group_axles))
    done = np.zeros((max(group_axles - 1, 0), n_sp), dtype=np.bool_)
    gained = np.zeros(n_seg)
    counts = np.zeros(n_seg, dtype=np.int64)
    pos = np.zeros((n_seg, group_axles), dtype=np.int64)
    off = 0
    for i in range(n_seg):
        gained[i], counts[i] = _choice(c0, c1, off, lengths[i], auto0, auto1, outside[i],
                                       energies[i], limit, n_samples, s_min, s_max, ratio,
                                       bound, group_axles, level_gain, rare_group, invs,
                                       done, pos[i])
        off += lengths[i]
    return gained, counts, pos


@njit(cache=True)
def explained_kernel(hyp, c0, c1, auto0, auto1):
    """:func:`bwim.detect.groups.explained`: the misfit each hypothesis (n_hyp, k) removes
    and its amplitudes (n_hyp, k, 2); each system solved by LAPACK gesv (as
    ``numpy.linalg.solve``)."""
    n_hyp, k = hyp.shape
    gained = np.empty(n_hyp)
    amps = np.empty((n_hyp, k, 2))
    if k == 1:
        one0, one1 = max(auto0[0], 1e-300), max(auto1[0], 1e-300)
        for h in range(n_hyp):
            b0, b1 = c0[hyp[h, 0]], c1[hyp[h, 0]]
            a0, a1 = b0 / one0, b1 / one1
            g = a0 * b0 + 0.0
            gained[h] = g + a1 * b1
            amps[h, 0, 0] = a0
            amps[h, 0, 1] = a1
        return gained, amps
    G = np.empty((k, k))
    b = np.empty((k, 1))  # one column: gesv's one signature with the inverses'
    p = np.empty(k)
    for h in range(n_hyp):
        total = 0.0
        for c in range(2):
            auto = auto0 if c == 0 else auto1
            corr = c0 if c == 0 else c1
            ridge = 1e-12 * auto[0]
            for i in range(k):
                b[i, 0] = corr[hyp[h, i]]
                for j in range(k):
                    lag = abs(hyp[h, i] - hyp[h, j])
                    if lag >= auto.size:
                        raise IndexError("lag beyond the autocorrelation")
                    G[i, j] = auto[lag] + ridge * (1.0 if i == j else 0.0)
            finite = True
            for i in range(k):
                finite = finite and math.isfinite(b[i, 0])
            if finite:
                a = np.linalg.solve(G, b)
            else:  # numba's solve refuses what LAPACK would carry through: NaN, as numpy
                a = np.full((k, 1), np.nan)
            for i in range(k):
                p[i] = a[i, 0] * b[i, 0]
                amps[h, i, c] = a[i, 0]
            if c == 0:
                total = short_sum(p)
            else:
                total = total + short_sum(p)
        gained[h] = total
    return gained, amps


@njit(cache=True)
def choose_in_window(t, lo, taus, y, rest, X, coef, u0, k0, u1, k1, w, shift0, shift1, v, fs,
                     st, lag, margin, s_min, s_max, ratio, bound, limit, group_axles,
                     level_gain, rare_group, dip, extent, peak_floor):
    """:func:`bwim.detect.groups.choose_groups` after the vehicle's least squares on its
    window (samples ``lo`` … of ``t``): ``taus`` (sorted), the window's readings ``y``
    (2, n_rows, 1), rest columns ``rest`` (2, n_rows, p), atoms ``X`` (2, n_rows, n) and
    the least-squares coefficients ``coef`` (2, n + p, 1); the responses' grids ``u0``,
    ``k0``, ``u1``, ``k1``, weights ``w`` and shifts.  The responses on the samples
    (:func:`response_on_samples`) and their autocorrelations every ``st``-th sample
    (:func:`grid_autocorrelation`, at least to the widest group's lag) are made here.
    The new times (sorted) and whether they changed."""
    n = taus.size
    n_rows = y.shape[1]
    n_grid = (n_rows - 1) // st + 1
    j00, h0 = response_on_samples(u0, k0, w[0], v, fs, shift0)
    j01, h1 = response_on_samples(u1, k1, w[1], v, fs, shift1)
    j0 = np.array([j00, j01])
    auto0 = grid_autocorrelation(h0, st, s_max * group_axles + 1)
    auto1 = grid_autocorrelation(h1, st, s_max * group_axles + 1)
    # the readings less the rest (BLAS gemv, as numpy's matmul), each axle's fitted part,
    # the residual (numpy's sum of the parts)
    local = np.empty((2, n_rows))
    parts = np.empty((2, n_rows, n))
    resid = np.empty((2, n_rows))
    p = rest.shape[2]
    for c in range(2):
        r = np.dot(rest[c], coef[c, n:, 0].copy()) if p > 0 else np.zeros(n_rows)
        for i in range(n_rows):
            local[c, i] = y[c, i, 0] - r[i]
            for g in range(n):
                parts[c, i, g] = X[c, i, g] * coef[c, g, 0]
            resid[c, i] = local[c, i] - short_sum(parts[c, i])
    # the axles' grid points (numpy's round: half to even)
    at = np.empty(n, dtype=np.int64)
    for g in range(n):
        at[g] = np.int64(np.rint((taus[g] - t[lo]) * fs / st))
    segs = segment_bounds(local, k0, k1, lag, margin, st, dip, extent, peak_floor)
    r_total = np.dot(resid[0], resid[0]) + np.dot(resid[1], resid[1])
    n_samples = 2 * n_rows
    n_seg = segs.shape[0]
    # the segments worth a choice: their correlations end to end
    corr = np.zeros((2, n_grid * max(n_seg, 1)))
    keep = np.empty((n_seg, 5), dtype=np.int64)  # first, last, i0, i1, offset
    energies = np.empty(n_seg)
    inside = np.empty(n_seg)
    tol = np.zeros(0)  # the one-axle test's bound on rounding, made when first asked
    n_chosen, off = 0, 0
    for p in range(n_seg):
        first, last = segs[p, 0], segs[p, 1]
        i0 = i1 = 0  # the axles at first … last (at is ascending)
        while i0 < n and at[i0] < first:
            i0 += 1
        while i1 < n and at[i1] <= last:
            i1 += 1
        if i0 == i1:
            if tol.size == 0:
                tol = one_axle_tolerance(resid, h0, h1)
            fits = False  # the window's one-axle test, on this segment's points alone
            for m in range(first, last + 1):
                if one_axle_may_fit_at(resid, h0, h1, j0, auto0[0], auto1[0], st, m, tol,
                                       ratio, bound):
                    fits = True
                    break
            if not fits:
                continue  # no axle of the vehicle here and no one axle fits: noise
        first, last = max(first, 0), min(last, n_grid - 1)
        energy = r_inside = 0.0
        for c in range(2):
            h = h0 if c == 0 else h1
            jc = j0[c]
            a = max(first * st + jc, 0)
            b = min(last * st + jc + h.size, n_rows)
            z = resid[c, a:b].copy()
            if i1 > i0:  # the readings less the other groups' axles
                row = np.empty(i1 - i0)
                for r in range(a, b):
                    for g in range(i0, i1):
                        row[g - i0] = parts[c, r, g]
                    z[r - a] += short_sum(row)
            energy += np.dot(z, z)
            r_inside += np.dot(resid[c, a:b], resid[c, a:b])
            q1 = min(last * st + jc, n_rows - h.size)
            if q1 >= a:
                m0 = max(first, -((jc - a) // st))
                m1 = min(last, (q1 - jc) // st)
                for m in range(m0, m1 + 1):
                    corr[c, off + m - first] = correlation_at(z, st * m + jc - a, h)
        keep[n_chosen, 0] = first
        keep[n_chosen, 1] = last
        keep[n_chosen, 2] = i0
        keep[n_chosen, 3] = i1
        keep[n_chosen, 4] = off
        energies[n_chosen] = energy
        inside[n_chosen] = r_inside
        n_chosen += 1
        off += last - first + 1
    c0, c1 = corr[0], corr[1]
    lengths = keep[:n_chosen, 1] - keep[:n_chosen, 0] + 1
    gained, counts, pos = group_choices(c0, c1, lengths, auto0, auto1,
                                        r_total - inside[:n_chosen], energies[:n_chosen],
                                        limit, float(n_samples), s_min, s_max, ratio, bound,
                                        group_axles, level_gain, rare_group)
    out = np.empty(taus.size + group_axles * n_chosen)
    n_out = 0
    changed = False
    for p in range(n_chosen):
        first, last, i0, i1, o = keep[p, 0], keep[p, 1], keep[p, 2], keep[p, 3], keep[p, 4]
        L = last - first + 1
        best, count = gained[p], counts[p]
        stands = count == 0
        if count > 0 and count == i1 - i0:
            # the count stands: the refined times stay unless they fit worse by more
            # than the threshold
            mine = np.empty((1, count), dtype=np.int64)
            for g in range(i0, i1):
                mine[0, g - i0] = min(max(at[g], first), last) - first
            mine_g = explained_kernel(mine, c0[o:o + L], c1[o:o + L], auto0, auto1)[0][0]
            stands = mine_g > best - limit
        if stands:
            for g in range(i0, i1):
                out[n_out] = taus[g]
                n_out += 1
            continue
        for j in range(count):
            out[n_out] = t[lo + st * (pos[p, j] + first)]
            n_out += 1
        changed = True
    # axles outside every segment: noise the pursuit took
    for g in range(at.size):
        inside_any = False
        for p in range(n_seg):
            if segs[p, 0] <= at[g] <= segs[p, 1]:
                inside_any = True
                break
        if not inside_any:
            changed = True
    return sorted_copy(out[:n_out]), changed  # a few times
