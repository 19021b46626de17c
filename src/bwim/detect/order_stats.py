"""Compiled order statistics for the detection: medians, robust deviations, the
five-sample running median of :func:`bwim.detect.signals.despike`, the quiet level and
noise of :func:`bwim.detect.presence.unexplained_activity`.

Contract
--------
* Each kernel is a numba function (``njit(cache=True)``, no fastmath, no parallelism)
  that computes what :mod:`bwim.detect.signals` describes with numpy or scipy calls,
  the same numbers: an order statistic is one of the values (found by selection on a
  copy: quickselect with branchless partitions; a running median by minima and
  maxima), the mean of the two
  middle values of an even count is ``(a + b) / 2`` as
  :func:`bwim.detect.signals.median` makes it, and every other
  operation is the same single IEEE operation numpy applies element by element.
  Signed zeros may differ where the order of equal values does (equal as numbers).
* Inputs are float64 and C-contiguous (the callers in :mod:`bwim.detect.signals`
  convert), so each kernel has one compiled signature (numba types a read-only array
  apart: one would compile a second; the detection passes none).
* :func:`median_of` is the median of a 1-D array (NaN for none, NaN if any value is);
  :func:`mad_of` the median absolute deviation from the median (0 for none; NaN when a
  value is); :func:`column_medians_of` the median of each column of the chosen rows of
  a 2-D array (NaN for a column holding one), and whether one is zero (a zero's sign is numpy's only
  through numpy's own order of equal values).
* :func:`despike_columns` is :func:`~bwim.detect.signals.despike`'s arithmetic for
  finite readings (n_t ≥ 5, k): each column's five-sample running median with the ends
  extended by their edge values (``scipy.ndimage.median_filter(y, size=(5, 1),
  mode="nearest")``), the deviations from it, each column's robust σ of them (1.4826
  MAD) and the range of its running medians, and the spikes: deviations beyond
  ``sigmas`` × σ and ``share`` × that range.  It says when a reading is not finite
  (the caller then takes the numpy and scipy path, whose NaN handling it does not copy).
* :func:`window_peaks` is :func:`bwim.detect.lateral.lateral_positions`' arithmetic of
  one window with peak weights: over the samples whose time lies in ``[lo, hi]``, each
  column's largest reading (numpy's ``max(axis=0)``: NaN when one is), less its quiet
  level, floored at 0 (``numpy.maximum``), then, when one is positive, less
  ``threshold`` × the largest of them, floored at 0 again.  It says when no sample lies
  in the window, or no weight is positive.  It and :func:`row_medians_of` take a
  table's columns one after the other (its transpose, C-contiguous: a record's columns
  as :func:`~bwim.detect.signals.channel_data` gives them, Fortran-ordered, without a
  copy); :func:`column_medians_of` is :func:`row_medians_of` of a C-ordered table's
  transpose.
* :func:`outside_windows` is the samples outside every window widened by a margin
  (:func:`bwim.detect.assemble.assemble_detection`'s quiet samples), and
  :func:`end_excursion` :func:`bwim.detect.assemble.ends_loaded`'s means of a record's
  first, second and last stretch (numpy's pairwise sums,
  :func:`bwim.pairwise.pairwise_sum`) and its largest excursion from the first;
  :func:`signed_extremes` :func:`bwim.detect.faults.diagnose`'s largest excursions up
  and down from a level at rest.
* :func:`outside_activity` is :func:`bwim.detect.presence.unexplained_activity`'s
  arithmetic for a finite signal: the samples inside a window widened by ``margin``,
  the quiet level (median outside), the noise (1.4826 MAD of the first difference over
  √2), the limit (the larger of ``fraction`` × the largest departure inside and ``snr``
  × the noise, as Python's ``max`` takes it) and the samples outside beyond it; the
  noise may be given (the same number computed once for several calls).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from bwim.pairwise import pairwise_sum

__all__ = ["column_medians_of", "despike_columns", "end_excursion", "mad_of", "median_of",
           "outside_activity", "outside_windows", "row_medians_of", "signed_extremes",
           "window_peaks"]


@njit(cache=True)
def _below(buf, lo, hi, pivot):
    """Move the values of ``buf[lo:hi]`` below ``pivot`` to its front (their count from
    ``lo`` returned), without a branch on the values: every value is swapped into the
    front and the front grows only past those below (the others are swapped back out by
    the next one).  A quickselect's partitions over noisy readings mispredict half of
    their branches; these have none."""
    j = lo
    for i in range(lo, hi):
        x = buf[i]
        buf[i] = buf[j]
        buf[j] = x
        j += x < pivot
    return j


@njit(cache=True)
def _not_above(buf, lo, hi, pivot):
    """:func:`_below` for the values not above ``pivot``."""
    j = lo
    for i in range(lo, hi):
        x = buf[i]
        buf[i] = buf[j]
        buf[j] = x
        j += not (pivot < x)
    return j


@njit(cache=True)
def _select(buf, lo, hi, k):
    """Rearrange ``buf[lo:hi]`` so that ``buf[k]`` holds the value of rank ``k`` (sorted
    order) with no larger value before it and no smaller after it: quickselect, the
    pivot the median of the first, middle and last values, each step a branchless
    partition into the values below the pivot, those equal to it (a second partition of
    the rest: runs of equal values, common in quantised readings, end the search at
    once) and those above; below 17 values an insertion sort.  The values are finite or
    ±inf (no NaN)."""
    while hi - lo > 16:
        a, b, c = buf[lo], buf[(lo + hi) // 2], buf[hi - 1]
        pivot = max(min(a, b), min(max(a, b), c))  # the middle one of three
        j = _below(buf, lo, hi, pivot)  # the pivot's own value is not below it: j < hi
        if k < j:
            hi = j
            continue
        j = _not_above(buf, j, hi, pivot)  # the pivot's value is: the rest shrinks
        if k < j:  # buf[k] is the pivot's value
            return
        lo = j
    for i in range(lo + 1, hi):
        x = buf[i]
        j = i - 1
        while j >= lo and buf[j] > x:
            buf[j + 1] = buf[j]
            j -= 1
        buf[j + 1] = x


@njit(cache=True)
def _median_inplace(buf, n):
    """The median of ``buf[:n]`` (no NaN, n ≥ 1), rearranging it."""
    k = n // 2
    _select(buf, 0, n, k)
    if n % 2:
        return buf[k]
    below = buf[0]  # the largest value before rank k: rank k - 1
    for i in range(1, k):
        if buf[i] > below:
            below = buf[i]
    return (below + buf[k]) / 2


@njit(cache=True)
def _has_nan(v):
    """Whether any value of ``v`` (1-D) is NaN."""
    for i in range(v.size):
        if v[i] != v[i]:
            return True
    return False


@njit(cache=True)
def median_of(v):
    """The median of ``v`` (1-D, float64, C-contiguous); NaN for none or if any is."""
    n = v.size
    if n == 0 or _has_nan(v):
        return np.nan
    return _median_inplace(v.copy(), n)


@njit(cache=True)
def mad_of(v):
    """``median |v − median v|`` of ``v`` (1-D, float64, C-contiguous); 0 for none,
    NaN if any value is NaN."""
    n = v.size
    if n == 0:
        return 0.0
    if _has_nan(v):
        return np.nan
    buf = v.copy()
    m = _median_inplace(buf, n)
    for i in range(n):
        buf[i] = abs(v[i] - m)
    return _median_inplace(buf, n)


@njit(cache=True)
def row_medians_of(a, rows):
    """The median of each row of ``a[:, rows]`` (``a`` (k, n) float64, C-contiguous: a
    table's columns one after the other; ``rows`` bool (n,), at least one True), shape
    (k,), NaN for a row holding one; and whether a median is zero (its sign, numpy's,
    rests on the order of equal values: the caller then takes numpy's partial sort)."""
    k, n = a.shape
    out = np.empty(k)
    buf = np.empty(n)
    zero = False
    for c in range(k):
        nan = False
        m = 0
        for i in range(n):
            if rows[i]:
                x = a[c, i]
                if x != x:
                    nan = True
                    break
                buf[m] = x
                m += 1
        out[c] = np.nan if nan else _median_inplace(buf, m)
        if out[c] == 0.0:
            zero = True
    return out, zero


@njit(cache=True)
def column_medians_of(v, rows):
    """The median of each column of ``v[rows]`` (``v`` (n, k) float64, C-contiguous;
    ``rows`` bool (n,), at least one True), shape (k,), NaN for a column holding one;
    and whether a median is zero (:func:`row_medians_of` of its transpose)."""
    return row_medians_of(np.ascontiguousarray(v.T), rows)


@njit(cache=True)
def _middle_of_five(a, b, c, d, e):
    """The middle one of five values (no NaN), by minima and maxima only (no branch to
    mispredict on noisy readings): the middle of ``e``, the larger of the pairs'
    smaller values and the smaller of their larger ones."""
    f = max(min(a, b), min(c, d))
    g = min(max(a, b), max(c, d))
    return max(min(e, f), min(max(e, f), g))


@njit(cache=True)
def despike_columns(y, sigmas, share, mad_to_sigma):
    """``despike``'s arithmetic on ``y`` (n_t ≥ 5, k; float64, C-contiguous; see the
    module docstring; σ = ``mad_to_sigma`` × MAD): (running medians, spikes (bool),
    number of spikes, whether every reading is finite).  When one is not, the other
    outputs are not computed."""
    n, k = y.shape
    med = np.empty((n, k))
    spikes = np.zeros((n, k), dtype=np.bool_)
    for i in range(n):
        for c in range(k):
            x = y[i, c]
            if not (x - x == 0.0):  # NaN or ±inf
                return med, spikes, 0, False
    count = 0
    buf = np.empty(n)
    dev = np.empty(n)
    for c in range(k):
        top = -np.inf
        bottom = np.inf
        for i in range(n):
            # the ends extended by their edge values
            m = _middle_of_five(y[max(i - 2, 0), c], y[max(i - 1, 0), c], y[i, c],
                                y[min(i + 1, n - 1), c], y[min(i + 2, n - 1), c])
            med[i, c] = m
            if m > top:
                top = m
            if m < bottom:
                bottom = m
            dev[i] = y[i, c] - m
            buf[i] = dev[i]
        centre = _median_inplace(buf, n)
        for i in range(n):
            buf[i] = abs(dev[i] - centre)
        sigma = mad_to_sigma * _median_inplace(buf, n)
        limit_sigma = sigmas * sigma
        limit_share = share * (top - bottom)
        for i in range(n):
            ad = abs(dev[i])
            if ad > limit_sigma and ad > limit_share:
                spikes[i, c] = True
                count += 1
    return med, spikes, count, True


@njit(cache=True)
def outside_activity(t, s, windows, margin, fraction, snr, mad_to_sigma, noise):
    """:func:`~bwim.detect.presence.unexplained_activity`'s samples of activity (see the
    module docstring): ``t``, ``s`` (n,), ``windows`` (m, 2) (float64, C-contiguous);
    ``noise`` the signal's noise when known (1.4826 MAD of its first difference over √2,
    as computed here), NaN to compute it.  Returns (status, active): status 0 when
    nothing can be reported (quiet samples fewer than 10 % of the record, or none inside
    a window), 1 with ``active`` (bool, (n,)) the samples outside every widened window
    departing beyond the limit, 2 when a reading is not finite (nothing computed)."""
    n = t.size
    active = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        x = s[i]
        if not (x - x == 0.0):
            return 2, active
    inside = np.zeros(n, dtype=np.bool_)
    for j in range(windows.shape[0]):
        lo = windows[j, 0] - margin
        hi = windows[j, 1] + margin
        for i in range(n):
            if t[i] >= lo and t[i] <= hi:
                inside[i] = True
    n_out = 0
    for i in range(n):
        if not inside[i]:
            n_out += 1
    if n_out < 0.1 * n or n_out == n:
        return 0, active
    buf = np.empty(max(n_out, n - 1))
    k = 0
    for i in range(n):
        if not inside[i]:
            buf[k] = s[i]
            k += 1
    level = _median_inplace(buf, n_out)
    # the noise: 1.4826 MAD of the first difference, over √2
    if noise == noise:  # given
        pass
    elif n > 1:
        diff = np.empty(n - 1)
        for i in range(n - 1):
            diff[i] = s[i + 1] - s[i]
            buf[i] = diff[i]
        centre = _median_inplace(buf, n - 1)
        for i in range(n - 1):
            buf[i] = abs(diff[i] - centre)
        noise = mad_to_sigma * _median_inplace(buf, n - 1) / np.sqrt(2.0)
    else:
        noise = 0.0 / np.sqrt(2.0)
    top = -np.inf
    for i in range(n):
        if inside[i]:
            d = abs(s[i] - level)
            if d > top:
                top = d
    a = fraction * top
    b = snr * noise
    limit = b if b > a else a  # Python's max(a, b)
    for i in range(n):
        if not inside[i] and abs(s[i] - level) > limit:
            active[i] = True
    return 1, active


@njit(cache=True)
def _floored(x):
    """``numpy.maximum(x, 0.0)`` of one value (x itself when NaN)."""
    return x if (x >= 0.0 or x != x) else 0.0


@njit(cache=True)
def window_peaks(t, cols, lo, hi, level, threshold):
    """The peak weights of the window ``[lo, hi]`` (see the module docstring): ``t``
    (n,), ``cols`` (k, n) the table's columns one after the other (the transpose of a
    table (n, k)), ``level`` (k,) (float64, C-contiguous).  Returns (status, weights
    (k,)): status 0 when no sample lies in the window, 1 when no weight is positive (the
    weights then not thresholded), 2 with the thresholded weights."""
    k, n = cols.shape
    w = np.zeros(k)
    inside = np.empty(n, dtype=np.bool_)
    seen = False
    for i in range(n):
        inside[i] = t[i] >= lo and t[i] <= hi
        if inside[i]:
            seen = True
    if not seen:
        return 0, w
    positive = False
    for c in range(k):
        top = 0.0
        first = True
        for i in range(n):
            if inside[i]:
                x = cols[c, i]
                if first:
                    top = x
                    first = False
                elif x > top or x != x:  # numpy's max: a NaN stays
                    top = x
        w[c] = _floored(top - level[c])
        if w[c] > 0.0:
            positive = True
    if not positive:
        return 1, w
    largest = w[0]
    for c in range(1, k):
        if w[c] > largest or w[c] != w[c]:
            largest = w[c]
    cut = threshold * largest
    for c in range(k):
        w[c] = _floored(w[c] - cut)
    return 2, w


@njit(cache=True)
def outside_windows(t, windows, margin):
    """The samples outside every window widened by ``margin`` (``t`` (n,), ``windows``
    (m, 2), float64, C-contiguous): numpy's ``~inside`` of ``inside |= (t >= a - margin)
    & (t <= b + margin)`` over the windows, and their count."""
    n = t.size
    outside = np.ones(n, dtype=np.bool_)
    for j in range(windows.shape[0]):
        lo = windows[j, 0] - margin
        hi = windows[j, 1] + margin
        for i in range(n):
            if t[i] >= lo and t[i] <= hi:
                outside[i] = False
    count = 0
    for i in range(n):
        if outside[i]:
            count += 1
    return outside, count


@njit(cache=True)
def end_excursion(y, n):
    """:func:`bwim.detect.assemble.ends_loaded`'s numbers of ``y`` (float64,
    C-contiguous, at least 2 ``n`` values): the means of its first ``n``, its last
    ``n`` and its second ``n`` values (numpy's: the pairwise sum over the count), and
    the first index of the largest ``|y − first mean|`` (numpy's argmax: a NaN first)
    with that difference."""
    size = y.size
    start = pairwise_sum(y, 0, n) / n
    end = pairwise_sum(y, size - n, n) / n
    middle = pairwise_sum(y, n, n) / n
    k = 0
    best = abs(y[0] - start)
    if best == best:
        for i in range(1, size):
            a = abs(y[i] - start)
            if a != a:
                k = i
                break
            if a > best:
                best = a
                k = i
    return start, end, middle, k, y[k] - start


@njit(cache=True)
def signed_extremes(y, rest, signs):
    """:func:`bwim.detect.faults.diagnose`'s excursions: with ``z = (y − rest) × signs``
    (``y`` (n ≥ 1, k) float64 C-contiguous, ``rest`` and ``signs`` (k,)), each column's
    largest ``z`` and the negative of its smallest (numpy's ``max`` and ``min``: NaN
    when a value is)."""
    n, k = y.shape
    up = np.empty(k)
    down = np.empty(k)
    for c in range(k):
        hi = (y[0, c] - rest[c]) * signs[c]
        lo = hi
        for i in range(1, n):
            z = (y[i, c] - rest[c]) * signs[c]
            if z > hi or z != z:  # a NaN stays (hi NaN: no comparison holds)
                hi = z
            if z < lo or z != z:
                lo = z
        up[c] = hi
        down[c] = -lo
    return up, down
