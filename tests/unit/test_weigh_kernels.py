"""A weighing's compiled loops (bwim.wim.weigh_kernels) against the numpy expressions
bwim.wim.weigh used before them, on random data: the same numbers to rounding (1e-13
relative, against 1e-14 … 1e-13 measured here; the sums run in another order).  The unit
readings of single axles are held to the matrix method's bit for bit in
tests/unit/test_wim.py."""

import numpy as np
import pytest

from bwim.records import Passage
from bwim.wim.influence_line import hat_design
from bwim.wim.weigh_kernels import (
    axle_positions,
    channel_products,
    column_centred,
    fit_residual,
    group_readings,
    nan_sum,
    on_support,
)


def _close(got, ref, rtol=1e-13):
    scale = max(float(np.max(np.abs(ref))), 1e-300) if np.size(ref) else 1.0
    np.testing.assert_allclose(got, ref, rtol=rtol, atol=rtol * scale)


@pytest.mark.parametrize("seed", range(3))
def test_group_readings_are_the_shared_sum_of_the_axles_readings(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n, h, x0 = int(rng.integers(2, 40)), rng.uniform(0.05, 1.0), rng.uniform(-5, 5)
        n_t, n_ax, n_c = (int(rng.integers(1, 200)), int(rng.integers(1, 7)),
                          int(rng.integers(1, 13)))
        n_g = int(rng.integers(1, n_ax + 1))
        pos = x0 + rng.uniform(-2.0, n * h + 2.0, size=(n_t, n_ax))
        ords = rng.normal(size=(n - 1, n_c)) * 10.0 ** rng.uniform(-9, 3)
        groups = np.sort(np.concatenate([np.arange(n_g), rng.integers(0, n_g, n_ax - n_g)]))
        share = np.zeros((n_ax, n_g))
        share[np.arange(n_ax), groups] = 1.0 / np.bincount(groups)[groups]
        M = np.asarray(hat_design(pos.reshape(-1, 1), np.ones(1), x0, h, n) @ ords
                       ).reshape(n_t, n_ax, n_c)
        _close(group_readings(pos, ords, x0, h, n, share), np.matmul(share.T, M))


@pytest.mark.parametrize("seed", range(3))
def test_channel_products_are_the_normal_equations(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n_t, n_g, n_c = int(rng.integers(1, 700)), int(rng.integers(1, 6)), int(
            rng.integers(1, 13))
        X = rng.normal(size=(n_t, n_g, n_c)) * 10.0 ** rng.uniform(-10, -4, n_c)
        e = rng.normal(size=(n_t, n_c)) * 1e-5
        p = channel_products(X, e)
        _close(p.gram, np.einsum("kgc,khc->cgh", X, X))
        _close(p.rhs, np.einsum("kgc,kc->cg", X, e))
        Xs, es = X.sum(axis=2), e.sum(axis=1)
        _close(p.sum_gram, Xs.T @ Xs)
        _close(p.sum_rhs, Xs.T @ es)


@pytest.mark.parametrize("summed", [False, True])
@pytest.mark.parametrize("fitted_offsets", [False, True])
def test_fit_residual_is_the_numpy_fit(summed, fitted_offsets):
    rng = np.random.default_rng(11 + summed + 2 * fitted_offsets)
    for _ in range(60):
        n_t, n_g, n_c = int(rng.integers(1, 700)), int(rng.integers(1, 6)), int(
            rng.integers(1, 13))
        X = rng.normal(size=(n_t, n_g, n_c)) * 1e-9
        w = rng.uniform(1e4, 1e5, n_g)
        s = rng.uniform(0.8, 1.2)
        E = np.einsum("kgc,g->kc", X, w) * s + 1e-6 * rng.normal(size=(n_t, n_c)) + 3e-4
        given = None if fitted_offsets else rng.normal(size=n_c) * 1e-4
        sd = (np.float64(rng.uniform(1e-6, 1e-5)) if summed
              else rng.uniform(1e-6, 1e-5, n_c))
        r = fit_residual(E, X, w, s, offsets=given, deviation=sd, summed=summed)
        fitted = s * np.einsum("kgc,g->kc", X, w)
        offsets = (E - fitted).mean(axis=0) if given is None else given
        meas = E - offsets
        _close(r.fitted, fitted)
        _close(r.offsets, offsets)
        _close(r.measured, meas)
        assert r.sum_measured == pytest.approx(np.linalg.norm(meas) ** 2, rel=1e-13)
        assert r.sum_residual == pytest.approx(np.linalg.norm(meas - fitted) ** 2, rel=1e-13)
        z = ((meas - fitted).sum(axis=1) / sd) if summed else (meas - fitted) / sd
        assert r.sum_misfit == pytest.approx(np.sum(z ** 2), rel=1e-13)


def test_on_support_is_numpys():
    """Any axle strictly inside the support: the same booleans as numpy's expression
    (axles on the ends, NaN positions)."""
    rng = np.random.default_rng(5)
    for trial in range(300):
        n_t, n_ax = int(rng.integers(1, 200)), int(rng.integers(1, 7))
        lo, hi = sorted(rng.uniform(-5, 20, 2))
        pos = rng.uniform(lo - 3, hi + 3, size=(n_t, n_ax))
        pos[rng.random(pos.shape) < 0.1] = lo  # on the ends: not inside
        pos[rng.random(pos.shape) < 0.1] = hi
        if trial % 5 == 0:
            pos[rng.random(pos.shape) < 0.1] = np.nan
        ref = ((pos > lo) & (pos < hi)).any(axis=1)
        got = on_support(pos, lo, hi)
        assert got.dtype == bool and np.array_equal(got, ref)


def test_column_centred_is_numpys_bit_for_bit():
    """X - X.mean(axis=0) of C-ordered tables and designs (signed zeros, a row of one
    sample, magnitudes apart): equal bit for bit, the sign of every zero included."""
    rng = np.random.default_rng(9)
    for trial in range(400):
        shape = (int(rng.integers(1, 700)), *([int(rng.integers(1, 5))] if trial % 2 else []),
                 int(rng.integers(1, 13)) if trial % 4 else 1)  # one column: pairwise
        X = rng.normal(size=shape) * 10.0 ** rng.uniform(-10, 3)
        if trial % 3 == 0:
            X = np.round(X / np.abs(X).max() * 2) * -0.0 if trial % 9 == 0 else np.round(X)
        ref = X - X.mean(axis=0)
        got = column_centred(X)
        assert np.array_equal(got, ref, equal_nan=True)
        assert np.array_equal(np.signbit(got), np.signbit(ref))
        if X.ndim == 2:  # a record's columns, Fortran-ordered: numpy's pairwise sums
            F = np.asfortranarray(X)
            ref = F - F.mean(axis=0)
            got = column_centred(F)
            assert np.array_equal(got, ref, equal_nan=True)
            assert np.array_equal(np.signbit(got), np.signbit(ref))
            assert got.flags.f_contiguous == ref.flags.f_contiguous
    with pytest.raises(ValueError, match="C-contiguous"):
        column_centred(np.ones((6, 4))[::2])


def test_channel_products_gram_is_contiguous():
    """The grams are one C-ordered block (numpy.tensordot's product of them is then a
    plain dot of the same array)."""
    rng = np.random.default_rng(2)
    p = channel_products(rng.normal(size=(50, 3, 4)), rng.normal(size=(50, 4)))
    assert p.gram.flags.c_contiguous and p.gram.shape == (4, 3, 3)
    w = rng.random(4)
    assert np.array_equal(np.dot(w.reshape(1, 4), p.gram.reshape(4, -1)).reshape(3, 3),
                          np.tensordot(w, p.gram, 1))


def test_axle_positions_are_the_passages():
    """Passage.axle_x's positions bit for bit (record times from 0 and clock times of
    day, many axles and one)."""
    rng = np.random.default_rng(12)
    for trial in range(300):
        n_ax = int(rng.integers(1, 10))
        p = Passage(speed=rng.uniform(3, 40), axle_spacings=rng.uniform(0.9, 9.0, n_ax - 1),
                    delay=rng.uniform(-2, 5) + (30000.0 if trial % 2 else 0.0))
        t = p.delay + rng.uniform(-1, 0, 1) + np.arange(int(rng.integers(1, 900))) / 512.0
        got = axle_positions(t, p.speed, p.delay, p.axle_offsets)
        assert got.flags.c_contiguous and np.array_equal(got, p.axle_x(t))


def test_nan_sum_is_numpys():
    rng = np.random.default_rng(14)
    for trial in range(2000):
        a = rng.normal(size=int(rng.integers(0, 300))) * 10.0 ** rng.uniform(-5, 5)
        if a.size and trial % 3 == 0:
            a[rng.random(a.size) < 0.3] = np.nan
        if trial % 11 == 0:
            a = -0.0 * np.abs(a)  # zeros of one sign: numpy's sum starts from +0
        ref = np.nansum(a)
        got = nan_sum(a)
        assert got == ref and np.signbit(got) == np.signbit(ref), (trial, got, ref)
