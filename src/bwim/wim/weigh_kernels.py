"""The loops of one weighing (:mod:`bwim.wim.weigh`), compiled: the lines' readings of a
unit weight on each axle group, the normal equations' products of each channel, and the
fit's residual.

Contract
--------
* :func:`group_readings` gives, at every sample and for every axle group, each
  channel's line read under the group's axles and summed with their shares
  (``Σ_i share[i, g] I_c(x_ki)``, shape (n_t, n_groups, n_c)): each axle's reading is
  linear between the nodes ``x0 + j h``, j = 0 … n, with the interior ordinates ``ords``
  (n − 1, n_c) and zero at both ends and off the support; the numbers of
  ``share.T @ hat_design(pos.reshape(-1, 1), [1], x0, h, n) @ ords`` (the matrix
  method's design, :func:`bwim.wim.influence_line.hat_design`) to rounding: each axle's
  reading is the sparse product's, bit for bit, the group's sum runs over the axles in
  order.
* :func:`channel_products` gives the products of the normal equations of a centred
  design ``X`` (n_t, n_groups, n_c) and readings ``e`` (n_t, n_c): per channel
  ``G_c = Σ_k X[k, :, c] ⊗ X[k, :, c]`` and ``h_c = Σ_k X[k, :, c] e[k, c]``, and the same
  of the channels' sum (``X`` and ``e`` summed over the channels first).
* :func:`fit_residual` gives the fitted static readings ``s Σ_g X[k, g, c] w_g`` of a
  design (uncentred) and group weights, the channels' offsets (the mean of reading −
  fit over the samples, or the ones given), the offset-free readings, and the sums of
  squares of the readings, of the residual, and of the residual in units of each
  channel's expected deviation (or, for the channels' sum, of the summed residual in
  units of its own).
* :func:`on_support` gives the samples at which an axle lies strictly inside the lines'
  support ``(lo, hi)``: ``((pos > lo) & (pos < hi)).any(axis=1)``, the same booleans.
* :func:`column_centred` gives a C-contiguous array (e.g. the design ``X``, (n_t,
  n_groups, n_c)) or a Fortran-ordered table (the readings, a record's columns) less its
  mean over the first axis, bit for bit ``X - X.mean(axis=0)`` in the same layout:
  numpy's column sums of a C-ordered table (sample after sample, from 0; a single
  column, a contiguous vector, by numpy's pairwise sum:
  :func:`bwim.pairwise.pairwise_sum`), of a Fortran-ordered one each column's pairwise
  sum, divided by the count, then each difference.
* :func:`axle_positions` gives :meth:`bwim.records.Passage.axle_x`'s positions,
  ``speed (t − delay) − offsets``, the same numbers (each a difference, a product and a
  difference); :func:`nan_sum` is ``numpy.nansum`` of a vector (its NaN as 0, then
  numpy's pairwise sum: :func:`bwim.pairwise.pairwise_sum`).
* Sums run in plain order (sample after sample): the numbers of the numpy expressions
  they replace to rounding, not bit for bit (tests/unit/test_weigh_kernels.py holds them
  to those expressions within 1e-13 relative on random data, and the unit readings to the
  matrix method's bit for bit).  No fused multiply-add (compiled without ``fastmath``).
* Compiled with numba (``cache=True``: the first call in a process compiles them, or
  loads them from numba's cache); float64 arrays in, float64 out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from bwim.pairwise import pairwise_sum

__all__ = ["ChannelProducts", "FitResidual", "axle_positions", "channel_products",
           "column_centred", "fit_residual", "group_readings", "nan_sum", "on_support"]


@numba.njit(cache=True)
def _group_readings(pos, ords, x0, h, n, share):  # pragma: no cover - compiled
    n_t, n_a = pos.shape
    n_c = ords.shape[1]
    n_g = share.shape[1]
    out = np.zeros((n_t, n_g, n_c))
    row = np.empty(n_c)
    for k in range(n_t):
        for i in range(n_a):
            u = (pos[k, i] - x0) / h
            if not (u > 0.0 and u < n):
                continue  # off the support: a zero reading
            j = int(np.floor(u))
            f = u - j
            for c in range(n_c):  # the nodes j and j + 1 (the ends' ordinates zero)
                a = ords[j - 1, c] if j >= 1 else 0.0
                b = ords[j, c] if j <= n - 2 else 0.0
                row[c] = (0.0 + (1.0 - f) * a) + f * b
            for g in range(n_g):
                sh = share[i, g]
                if sh != 0.0:
                    for c in range(n_c):
                        out[k, g, c] += sh * row[c]
    return out


def group_readings(pos: np.ndarray, ords: np.ndarray, x0: float, h: float, n: int,
                   share: np.ndarray) -> np.ndarray:
    """Each axle group's unit readings (module docstring): ``pos`` (n_t, n_axles) axle
    positions, ``ords`` (n − 1, n_c), ``share`` (n_axles, n_groups)."""
    return _group_readings(np.ascontiguousarray(pos, dtype=float),
                           np.ascontiguousarray(ords, dtype=float), float(x0), float(h),
                           int(n), np.ascontiguousarray(share, dtype=float))


@numba.njit(cache=True)
def _axle_positions(t, speed, delay, offsets):  # pragma: no cover - compiled
    n_t, n_a = t.size, offsets.size
    out = np.empty((n_t, n_a))
    for k in range(n_t):
        x = speed * (t[k] - delay)
        for i in range(n_a):
            out[k, i] = x - offsets[i]
    return out


def axle_positions(time: np.ndarray, speed: float, delay: float, offsets: np.ndarray
                   ) -> np.ndarray:
    """Each axle's position at each time, m, (n_t, n_axles): ``speed (t − delay) −
    offsets`` (module docstring)."""
    return _axle_positions(np.ascontiguousarray(time, dtype=float).reshape(-1), float(speed),
                           float(delay), np.ascontiguousarray(offsets, dtype=float))


@numba.njit(cache=True)
def _nan_sum(a):  # pragma: no cover - compiled
    b = a.copy()
    for i in range(b.size):
        if b[i] != b[i]:
            b[i] = 0.0
    return pairwise_sum(b, 0, b.size)


def nan_sum(a: np.ndarray) -> float:
    """``numpy.nansum`` of a float vector (module docstring)."""
    return _nan_sum(np.ascontiguousarray(a, dtype=float).reshape(-1))


@numba.njit(cache=True)
def _on_support(pos, lo, hi):  # pragma: no cover - compiled
    n_t, n_a = pos.shape
    on = np.zeros(n_t, dtype=np.bool_)
    for k in range(n_t):
        for i in range(n_a):
            x = pos[k, i]
            if x > lo and x < hi:
                on[k] = True
                break
    return on


def on_support(pos: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Whether an axle lies strictly inside ``(lo, hi)`` at each sample (module
    docstring): ``pos`` (n_t, n_axles) axle positions, m."""
    return _on_support(np.ascontiguousarray(pos, dtype=float), float(lo), float(hi))


@numba.njit(cache=True, error_model="numpy")
def _column_means(a, out):  # pragma: no cover - compiled
    """numpy's ``a.mean(axis=0)`` of a C-ordered table (n, m) into ``out`` (m,): the sums
    sample after sample from 0, over the count (one column: a contiguous vector, numpy's
    pairwise sum)."""
    n, m = a.shape
    if m == 1:
        out[0] = pairwise_sum(a.reshape(-1), 0, n)
    else:
        for j in range(m):
            out[j] = 0.0
        for k in range(n):
            for j in range(m):
                out[j] += a[k, j]
    for j in range(m):
        out[j] /= n


@numba.njit(cache=True, error_model="numpy")
def _column_centred(X, out):  # pragma: no cover - compiled
    n = X.shape[0]
    flat = X.reshape(n, -1)
    flat_out = out.reshape(n, -1)
    m = np.empty(flat.shape[1])
    _column_means(flat, m)
    for k in range(n):
        for j in range(flat.shape[1]):
            flat_out[k, j] = flat[k, j] - m[j]


@numba.njit(cache=True, error_model="numpy")
def _rows_centred(Xt, out_t):  # pragma: no cover - compiled
    m, n = Xt.shape  # a Fortran-ordered table's columns one after the other
    for j in range(m):
        mean = pairwise_sum(Xt[j], 0, n) / n
        for k in range(n):
            out_t[j, k] = Xt[j, k] - mean


def column_centred(X: np.ndarray) -> np.ndarray:
    """``X - X.mean(axis=0)`` of a C-contiguous float64 array, or of a Fortran-ordered
    table (a record's columns), in the same layout (module docstring): the same numbers
    (numpy's for that layout: the sums in its order)."""
    if X.dtype != np.float64:
        raise ValueError("column_centred: a float64 array")
    if X.flags.c_contiguous:
        out = np.empty(X.shape)
        _column_centred(X, out)
    elif X.ndim == 2 and X.flags.f_contiguous:  # numpy sums each column pairwise
        out = np.empty(X.shape, order="F")
        _rows_centred(X.T, out.T)
    else:
        raise ValueError("column_centred: a C-contiguous array or a Fortran-ordered table")
    return out


@numba.njit(cache=True)
def _channel_products(X, e):  # pragma: no cover - compiled
    n_t, n_g, n_c = X.shape
    # the running sums with the channel last (the inner loops run along a sample's row):
    # acc[g, q, c] for q >= g (G_c is symmetric), acc[g, n_g, c] the rhs
    acc = np.zeros((n_g, n_g + 1, n_c))
    sums = np.zeros((n_g, n_g + 1))  # the same of the channels' sum
    xs = np.empty(n_g)
    for k in range(n_t):
        es = 0.0
        for c in range(n_c):
            es += e[k, c]
        for g in range(n_g):
            a = 0.0
            for c in range(n_c):
                a += X[k, g, c]
            xs[g] = a
        for g in range(n_g):
            for q in range(g, n_g):
                for c in range(n_c):
                    acc[g, q, c] += X[k, g, c] * X[k, q, c]
            for c in range(n_c):
                acc[g, n_g, c] += X[k, g, c] * e[k, c]
            for q in range(g, n_g):
                sums[g, q] += xs[g] * xs[q]
            sums[g, n_g] += xs[g] * es
    out = np.empty((n_c + 1, n_g, n_g + 1))  # [c, :, :n_g] G_c, [c, :, n_g] h_c; n_c: sum
    for g in range(n_g):
        for q in range(g, n_g):
            for c in range(n_c):
                out[c, g, q] = acc[g, q, c]
                out[c, q, g] = acc[g, q, c]
            out[n_c, g, q] = sums[g, q]
            out[n_c, q, g] = sums[g, q]
        for c in range(n_c):
            out[c, g, n_g] = acc[g, n_g, c]
        out[n_c, g, n_g] = sums[g, n_g]
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class ChannelProducts:
    """:func:`channel_products`' result (``gram`` C-contiguous)."""

    gram: np.ndarray  # (n_c, n_groups, n_groups)
    rhs: np.ndarray  # (n_c, n_groups)
    sum_gram: np.ndarray  # (n_groups, n_groups)
    sum_rhs: np.ndarray  # (n_groups,)


def channel_products(X: np.ndarray, e: np.ndarray) -> ChannelProducts:
    """The normal equations' products of each channel and of their sum (module
    docstring)."""
    out = _channel_products(np.ascontiguousarray(X, dtype=float),
                            np.ascontiguousarray(e, dtype=float))
    n_c, n_g = X.shape[2], X.shape[1]
    return ChannelProducts(gram=np.ascontiguousarray(out[:n_c, :, :n_g]), rhs=out[:n_c, :, n_g],
                           sum_gram=out[n_c, :, :n_g], sum_rhs=out[n_c, :, n_g])


@numba.njit(cache=True, error_model="numpy")
def _fit_residual(Et, X, w, s, fit_offsets, offsets, sd, summed, fitted, meas
                  ):  # pragma: no cover - compiled
    n_t, n_g, n_c = X.shape  # Et: the readings' channels one after the other
    acc = np.empty(n_c)
    for k in range(n_t):  # each sum over the groups in order, from 0 (channel last)
        for c in range(n_c):
            acc[c] = 0.0
        for g in range(n_g):
            for c in range(n_c):
                acc[c] += X[k, g, c] * w[g]
        for c in range(n_c):
            fitted[k, c] = s * acc[c]
    if fit_offsets:  # each channel's sum over the samples in order, from 0
        for c in range(n_c):
            e = Et[c]
            o = 0.0
            for k in range(n_t):
                o += e[k] - fitted[k, c]
            offsets[c] = o / n_t
    # per channel Σ meas², Σ residual², Σ (residual / deviation)² (each over the samples
    # in order), then summed over the channels
    sq = np.zeros((3, n_c))
    for c in range(n_c):
        e = Et[c]
        o = offsets[c]
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        for k in range(n_t):
            m = e[k] - o
            meas[k, c] = m
            r = m - fitted[k, c]
            s0 += m * m
            s1 += r * r
            if not summed:
                z = r / sd[c]
                s2 += z * z
        sq[0, c] = s0
        sq[1, c] = s1
        sq[2, c] = s2
    misfit = 0.0  # the channels' summed residual's
    if summed:
        for k in range(n_t):
            rs = 0.0
            for c in range(n_c):
                rs += meas[k, c] - fitted[k, c]
            z = rs / sd[0]
            misfit += z * z
    out = np.zeros(3)
    for c in range(n_c):
        out[0] += sq[0, c]
        out[1] += sq[1, c]
        out[2] += sq[2, c]
    if summed:
        out[2] = misfit
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class FitResidual:
    """:func:`fit_residual`'s result."""

    fitted: np.ndarray  # (n_t, n_c) fitted static readings
    offsets: np.ndarray  # (n_c,)
    measured: np.ndarray  # (n_t, n_c) offset-free readings
    sum_measured: float  # Σ measured²
    sum_residual: float  # Σ (measured − fitted)²
    sum_misfit: float  # Σ of the squared residuals in units of their deviation


def fit_residual(E: np.ndarray, X: np.ndarray, weights: np.ndarray, scale: float, *,
                 offsets: np.ndarray | None, deviation: np.ndarray | float,
                 summed: bool = False) -> FitResidual:
    """The fit of readings ``E`` (n_t, n_c) by the design ``X`` (n_t, n_groups, n_c)
    times ``scale`` and the group ``weights`` (finite): fitted readings, offsets (fitted
    as the residual's mean when ``offsets`` is None), offset-free readings and the sums of
    squares (module docstring); ``deviation``: each channel's expected residual deviation
    (n_c,), or with ``summed`` one number, that of the channels' summed residual."""
    # the channels one after the other (a record's Fortran-ordered columns: no copy)
    Et = np.ascontiguousarray(np.asarray(E, dtype=float).T)
    n_c, n_t = Et.shape
    off = np.zeros(n_c) if offsets is None else np.array(offsets, dtype=float)
    sd = np.atleast_1d(np.asarray(deviation, dtype=float))
    fitted, meas = np.empty((n_t, n_c)), np.empty((n_t, n_c))
    sums = _fit_residual(Et, np.ascontiguousarray(X, dtype=float),
                         np.ascontiguousarray(weights, dtype=float), float(scale),
                         offsets is None, off, sd, bool(summed), fitted, meas)
    return FitResidual(fitted=fitted, offsets=off, measured=meas,
                       sum_measured=float(sums[0]), sum_residual=float(sums[1]),
                       sum_misfit=float(sums[2]))
