"""The compiled kernels of :mod:`bwim.detect.group_kernels` give numpy's own numbers.

References: the plain numpy computations each kernel replaces (the code of
:mod:`bwim.detect.groups` before it was compiled), run here on the same random arrays:
``np.sum``, ``np.correlate``, ``np.interp``, ``np.linalg.inv``/``solve``,
``scipy.signal.find_peaks``, and the numpy forms of the one-axle test, the evenly spaced
hypotheses, the count chosen per segment and the whole choice after the least squares.
Numbers compared bit for bit (the kernels call BLAS and LAPACK as numpy does: scipy's
OpenBLAS, numpy's own, the same kernels), choices exactly.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.signal import find_peaks

from bwim.detect import group_kernels as K
from bwim.detect.groups import (
    GROUP_AXLES,
    GROUP_DIP,
    GROUP_EXTENT,
    LEVEL_GAIN,
    PEAK_FLOOR,
    RARE_GROUP,
)
from bwim.detect.signals import last_axis_sum


def _equal(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    assert a.tobytes() == b.tobytes()


def _bump(n, width, scale=1.0):
    return scale * np.exp(-0.5 * ((np.arange(n) - n / 2) / width) ** 2)


# ---- numpy references (the code before the kernels) ------------------------------------

def _ref_segments(local, k0, k1, lag, margin, st):
    e = np.zeros(local[0].size)
    for c, k in enumerate((k0, k1)):
        z = np.maximum(local[c] * np.sign(k[int(np.argmax(np.abs(k)))]), 0.0)
        top = float(z.max())
        if top > 0:
            shift = lag if c else 0
            if shift < e.size:
                e[:e.size - shift] += z[shift:] / top
    if not e.max() > 0:
        return []
    floor = PEAK_FLOOR * float(e.max())
    peaks, _ = find_peaks(e, height=floor, prominence=floor)
    if peaks.size == 0:
        return []
    cuts = [0]
    for a, b in itertools.pairwise(peaks):
        m = a + int(np.argmin(e[a:b + 1]))
        if e[m] < GROUP_DIP * min(e[a], e[b]):
            cuts.append(m)
    cuts.append(e.size - 1)
    out = []
    for a, b in itertools.pairwise(cuts):
        part = e[a:b + 1]
        above = np.flatnonzero(part >= GROUP_EXTENT * float(part.max()))
        out.append((max(a + int(above[0]) - margin, a) // st,
                    min(a + int(above[-1]) + margin, b) // st))
    return out


def _ref_one_axle(resid, tpl, auto, st, n_grid, ratio, bound):
    b, tol = [], []
    for c, (j0, h) in enumerate(tpl):
        z = resid[c]
        full = np.full(n_grid, -np.inf)
        if z.size >= h.size:
            cc = np.correlate(z, h, mode="valid")
            q = st * np.arange(n_grid) + j0
            ok = (q >= 0) & (q < cc.size)
            full[ok] = cc[q[ok]]
        b.append(full)
        tol.append(1e-9 * float(np.abs(h).sum()) * float(np.abs(z).max(initial=0.0)) + 1e-300)
    pos = [b[c] > -tol[c] for c in range(2)]
    sure = (b[0] > 1e3 * tol[0]) & (b[1] > 1e3 * tol[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        a0 = np.where(sure, b[0], 1.0) / max(auto[0][0], 1e-300)
        a1 = np.where(sure, b[1], 1.0) / max(auto[1][0], 1e-300)
        lr = np.log(a1 / (ratio * a0))
        slack = 4.0 * (tol[0] / np.where(sure, b[0], 1.0) + tol[1] / np.where(sure, b[1], 1.0))
    maybe = pos[0] & pos[1] & (~sure | (np.abs(lr) <= bound + slack + 1e-12))
    return np.concatenate([[0], maybe.cumsum()])


def _ref_explained(hyp, corr, auto):
    k = hyp.shape[1]
    if k == 1:
        b = np.array([corr[0][hyp[:, 0]], corr[1][hyp[:, 0]]]).T
        a = b / np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
        return last_axis_sum(a * b), a[:, None, :]
    lag = np.abs(hyp[:, :, None] - hyp[:, None, :])
    b = np.array([corr[0][hyp], corr[1][hyp]])
    G = np.array([auto[c][lag] + 1e-12 * auto[c][0] * np.eye(k) for c in range(2)])
    a = np.linalg.solve(G, b[..., None])[..., 0]
    gained = last_axis_sum(a * b)
    return gained[0] + gained[1], a.transpose(1, 2, 0)


def _ref_evenly(lengths, k, s_min, s_max, corr, auto):
    spacings = np.arange(s_min, s_max + 1)
    owner_of = np.arange(lengths.size).repeat(lengths)
    offsets = lengths.cumsum() - lengths
    local = np.arange(owner_of.size) - offsets[owner_of]
    row, sp = (local[:, None] + (k - 1) * spacings[None, :]
               <= (lengths - 1)[owner_of][:, None]).nonzero()
    steps = spacings[sp][:, None] * np.arange(k)[None, :]
    hyp = local[row][:, None] + steps
    if hyp.shape[0] == 0:
        return hyp, np.zeros(0, dtype=int), np.zeros(0), np.zeros((0, k, 2))
    n_s = int(sp.max()) + 1
    lags = spacings[:n_s, None, None] * np.abs(np.arange(k)[:, None] - np.arange(k)[None, :])
    G = np.array([auto[c][lags] + 1e-12 * auto[c][0] * np.eye(k) for c in range(2)])
    at = row[:, None] + steps
    b = np.array([corr[0][at], corr[1][at]])
    a = (np.linalg.inv(G).take(sp, axis=1) @ b[..., None])[..., 0]
    gained = last_axis_sum(a * b)
    return hyp, owner_of[row], gained[0] + gained[1], a.transpose(1, 2, 0)


def _ref_counts(ratio, bound, corr, auto, lengths, outside, energies, limit, n_samples,
                s_min, s_max):
    n = lengths.size
    offsets = lengths.cumsum() - lengths
    b = np.array(corr).T
    one = np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
    amps = b / one
    gained = last_axis_sum(amps * b)
    positive = (amps[:, 0] > 0) & (amps[:, 1] > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.log(amps[:, 1] / (ratio * amps[:, 0]))
    score = np.where(positive & (np.abs(lr) <= bound), gained, -np.inf)
    best: list = [None] * n
    active = []
    for i in range(n):
        o = int(offsets[i])
        j = int(score[o:o + lengths[i]].argmax())
        if score[o + j] > -np.inf:
            best[i] = (float(gained[o + j]), np.array([j]))
            active.append(i)
    for k in range(2, GROUP_AXLES + 1):
        if not active:
            break
        sub = [corr[c][np.concatenate([np.arange(offsets[i], offsets[i] + lengths[i])
                                       for i in active])] for c in range(2)]
        hyp, owner, gained, amps = _ref_evenly(lengths[active], k, s_min, s_max, sub, auto)
        with np.errstate(divide="ignore", invalid="ignore"):
            lr = np.log(amps[..., 1] / (ratio * amps[..., 0]))
        valid = ((amps[..., 0] > 0) & (amps[..., 1] > 0) & (np.abs(lr) <= bound)).all(axis=1)
        score = np.where(valid, gained, -np.inf)
        bounds = owner.searchsorted(np.arange(len(active) + 1))
        rare = RARE_GROUP if k > 3 else 1.0
        still = []
        for q, i in enumerate(active):
            h0, h1 = int(bounds[q]), int(bounds[q + 1])
            if h0 == h1:
                continue
            j = h0 + int(score[h0:h1].argmax())
            if not score[j] > -np.inf:
                continue
            gain = gained[j] - best[i][0]
            level = (outside[i] + (energies[i] - best[i][0])) / n_samples
            if gain < limit or gain < LEVEL_GAIN * rare * level:
                continue
            best[i] = (float(gained[j]), hyp[j])
            still.append(i)
        active = still
    return best


def _ref_responses(grids, w, shift, v, fs):
    out = []
    for c, (u, k) in enumerate(grids):
        d = shift[c]
        j0 = int(np.ceil((u[0] + d) / v * fs))
        j1 = int(np.floor((u[-1] + d) / v * fs))
        out.append((j0, np.interp(v * np.arange(j0, j1 + 1) / fs - d, u, k) * w[c]))
    return out


def _ref_choice(t, lo, taus, y, rest, X, coef, grids, w, shift, v, fs, st, lag, margin,
                s_min, s_max, ratio, bound, limit):
    """choose_groups after its least squares, as numpy computed it."""
    n = taus.size
    local = (y - rest @ coef[:, n:])[..., 0]
    parts = X * coef[:, None, :n, 0]
    resid = local - last_axis_sum(parts)
    r_total = sum(float(r @ r) for r in resid)
    n_rows = local.shape[1]
    n_samples = 2 * n_rows
    tpl = _ref_responses(grids, w, shift, v, fs)
    at = ((taus - t[lo]) * fs / st).round().astype(int)
    n_grid = (n_rows - 1) // st + 1
    auto = []
    for _, h in tpl:
        r = np.correlate(h, h, mode="full")[h.size - 1:][::st]
        auto.append(np.concatenate([r, np.zeros(max(0, s_max * GROUP_AXLES - r.size + 1))]))
    parts_of = _ref_segments(local, grids[0][1], grids[1][1], lag, margin, st)
    bare = None
    chosen, corr_all = [], ([], [])
    for first, last in parts_of:
        i0 = int(np.searchsorted(at, first, "left"))
        i1 = int(np.searchsorted(at, last, "right"))
        if i0 == i1:
            if bare is None:
                bare = _ref_one_axle(resid, tpl, auto, st, n_grid, ratio, bound)
            if bare[last + 1] == bare[first]:
                continue
        g = np.arange(i0, i1)
        energy = r_inside = 0.0
        for c, (j0, h) in enumerate(tpl):
            a, b = max(first * st + j0, 0), min(last * st + j0 + h.size, n_rows)
            z = (resid[c][a:b] + last_axis_sum(parts[c][a:b].take(g, axis=1)) if g.size
                 else resid[c][a:b])
            energy += float(z @ z)
            r_inside += float(resid[c][a:b] @ resid[c][a:b])
            part = np.zeros(last - first + 1)
            q1 = min(last * st + j0, n_rows - h.size)
            if q1 >= a:
                cc = np.correlate(z[:q1 - a + h.size], h, mode="valid")
                m0 = max(first, -((j0 - a) // st))
                m1 = min(last, (q1 - j0) // st)
                if m1 >= m0:
                    part[m0 - first:m1 - first + 1] = cc[st * m0 + j0 - a:
                                                         st * m1 + j0 - a + 1:st]
            corr_all[c].append(part)
        chosen.append((first, last, g, energy, r_inside))
    counts = []
    if chosen:
        corr = [np.concatenate(corr_all[0]), np.concatenate(corr_all[1])]
        lengths = np.array([last - first + 1 for first, last, *_ in chosen])
        counts = _ref_counts(ratio, bound, corr, auto, lengths,
                             [r_total - r for *_, r in chosen], [e for *_, e, _ in chosen],
                             limit, n_samples, s_min, s_max)
    offsets = np.cumsum([0, *(last - first + 1 for first, last, *_ in chosen)])
    out, changed = [], False
    for (first, last, g, _, _), best, off in zip(chosen, counts, offsets, strict=False):
        if best is None:
            out.extend(taus[g])
            continue
        if best[1].size == g.size:
            mine = np.clip(at[g], first, last)[None, :] - first
            seg = [corr[0][off:off + last - first + 1], corr[1][off:off + last - first + 1]]
            if _ref_explained(mine, seg, auto)[0][0] > best[0] - limit:
                out.extend(taus[g])
                continue
        out.extend(t[lo + st * (best[1] + first)])
        changed = True
    changed |= not all(any(a <= m <= b for a, b in parts_of) for m in at)
    return np.sort(np.array(out, dtype=float)), changed, parts_of


# ---- the kernels against them ---------------------------------------------------------

def test_sums_are_numpys():
    rng = np.random.default_rng(1)
    for n in [*range(0, 140), 255, 1000, 4097]:
        x = rng.standard_normal(n + 2) * 10.0 ** rng.integers(-8, 9, n + 2)
        if n:
            _equal(K.short_sum(x[2:]), last_axis_sum(x[None, 2:])[0])


def test_correlations_and_autocorrelations_are_numpys():
    rng = np.random.default_rng(2)
    for m in (3, 11, 12, 59, 200):
        h = rng.standard_normal(m)
        z = rng.standard_normal(m + 40)
        ref = np.correlate(z, h, mode="valid")
        _equal(np.array([K.correlation_at(z, q, h) for q in range(ref.size)]), ref)
        for st in (1, 3, 7):
            r = np.correlate(h, h, mode="full")[m - 1:][::st]
            size = r.size + 5
            _equal(K.grid_autocorrelation(h, st, size), np.concatenate([r, np.zeros(5)]))


def test_responses_on_samples_are_numpys():
    rng = np.random.default_rng(3)
    u = np.linspace(-1.7, 1.9, 361)
    k = _bump(u.size, 40.0) + 0.01 * rng.standard_normal(u.size)
    for v, fs, d in ((8.0, 512.0, 0.0), (23.7, 512.0, 3.1), (31.0, 1024.0, 1.2)):
        ref = _ref_responses([(u, k)], [0.7], [d], v, fs)[0]
        j0, h = K.response_on_samples(u, k, 0.7, v, fs, d)
        assert j0 == ref[0]
        _equal(h, ref[1])


def test_segments_are_the_numpy_ones():
    rng = np.random.default_rng(4)
    k0, k1 = _bump(101, 12.0), -_bump(81, 10.0, 0.4)
    for trial in range(40):
        n = int(rng.integers(60, 700))
        local = np.array([np.convolve(rng.standard_normal(n), np.hanning(9), mode="same")
                          for _ in range(2)])
        if trial % 3 == 0:
            local = np.round(local, 1)  # plateaus and repeated values
        lag, margin, st = int(rng.integers(0, 80)), int(rng.integers(0, 9)), 1 + trial % 4
        got = K.segment_bounds(local, k0, k1, lag, margin, st, GROUP_DIP, GROUP_EXTENT,
                               PEAK_FLOOR)
        assert [tuple(x) for x in got.tolist()] == _ref_segments(local, k0, k1, lag, margin,
                                                                 st)


def _templates(rng):
    tpl = [(-3, _bump(41, 7.0)), (25, _bump(33, 6.0, 0.3))]
    st = 3
    auto = [K.grid_autocorrelation(h, st, 60) for _, h in tpl]
    return tpl, auto, st


def test_one_axle_test_is_the_numpy_one():
    rng = np.random.default_rng(5)
    tpl, auto, st = _templates(rng)
    n_rows = 300
    n_grid = (n_rows - 1) // st + 1
    passed = 0
    for bound in (0.3, 1.1, 3.0):
        for _ in range(5):
            resid = rng.standard_normal((2, n_rows)) * np.array([[1.0], [0.25]])
            ref = _ref_one_axle(resid, tpl, auto, st, n_grid, 0.25, bound)
            got = K.one_axle_points(resid, tpl[0][1], tpl[1][1], np.array([-3, 25]),
                                    auto[0][0], auto[1][0], st, n_grid, 0.25, bound)
            _equal(got, ref)
            passed += int(ref[-1])
    assert 0 < passed < 15 * n_grid


def _correlations(rng, tpl, lengths, axles):
    corr = ([], [])
    for n, n_axles in zip(lengths, axles, strict=True):
        spacing = int(rng.integers(10, 16))
        for c, (_, h) in enumerate(tpl):
            z = 0.02 * rng.standard_normal(n * 3 + h.size)
            for i in range(n_axles):
                m = 3 * (4 + i * spacing // 3)
                if m + h.size <= z.size:
                    z[m:m + h.size] += rng.uniform(0.6, 1.0) * h
            corr[c].append(np.correlate(z, h, mode="valid")[::3][:n])
    return [np.concatenate(corr[0]), np.concatenate(corr[1])]


def test_hypotheses_and_counts_are_the_numpy_ones():
    """explained_kernel, evenly_kernel and group_choices (with its cheap bound skipping
    hypotheses) against numpy's explained, evenly_explained and group_counts: the same
    numbers, the same choices, each count (none, 1 … 4) chosen."""
    rng = np.random.default_rng(6)
    tpl, _, st = _templates(rng)
    auto = [K.grid_autocorrelation(h, st, 80) for _, h in tpl]
    s_min, s_max = 3, 6
    chosen = set()
    for trial in range(30):
        lengths = np.array([int(rng.integers(20, 40)) if a else int(rng.integers(2, 30))
                            for a in (0, 1, 2, 3, 4, 2)])
        corr = _correlations(rng, tpl, lengths, (0, 1, 2, 3, 4, 2))
        for k in (1, 2, 3):
            hyp = rng.integers(0, lengths[0], (7, k))
            ref = _ref_explained(hyp, corr, auto)
            got = K.explained_kernel(hyp, corr[0], corr[1], auto[0], auto[1])
            _equal(got[0], ref[0])
            _equal(got[1], ref[1])
        for k in (2, 3, 4):
            ref = _ref_evenly(lengths, k, s_min, s_max, corr, auto)
            got = K.evenly_kernel(lengths, k, s_min, s_max, corr[0], corr[1], auto[0],
                                  auto[1], 1.0, np.inf)
            for a, b in zip(got[:4], ref, strict=True):
                _equal(a, np.asarray(b, dtype=a.dtype))
        ratio, bound = 0.3, (0.4, 3.0)[trial % 2]
        limit = (0.0, 0.05, 0.5, 1e3)[trial % 4]
        outside = rng.uniform(0.0, 2.0, lengths.size)
        energies = rng.uniform(5.0, 30.0, lengths.size)
        n_samples = float(int(np.exp(rng.uniform(np.log(100), np.log(5000)))))
        ref = _ref_counts(ratio, bound, corr, auto, lengths, outside, energies, limit,
                          n_samples, s_min, s_max)
        gained, counts, pos = K.group_choices(corr[0], corr[1], lengths, auto[0], auto[1],
                                              outside, energies, limit, n_samples, s_min,
                                              s_max, ratio, bound, GROUP_AXLES, LEVEL_GAIN,
                                              RARE_GROUP)
        for i, b in enumerate(ref):
            assert counts[i] == (0 if b is None else b[1].size)
            if b is not None:
                _equal(pos[i, :counts[i]], b[1].astype(np.int64))
                _equal(gained[i], np.float64(b[0]))
            chosen.add(int(counts[i]))
    assert chosen == {0, 1, 2, 3, 4}


def test_the_choice_in_a_window_is_the_numpy_one():
    """choose_in_window against numpy's choose_groups after its least squares, on
    synthetic windows of two detectors (axle groups of one to four, noise, gauges' rest
    columns or none): the same times and the same answer whether they changed."""
    rng = np.random.default_rng(7)
    fs, v, st = 512.0, 20.0, 3
    u = np.linspace(-1.2, 1.2, 241)
    grids = [(u, np.exp(-0.5 * (u / 0.45) ** 2)), (u, 0.8 * np.exp(-0.5 * (u / 0.4) ** 2))]
    shift, w = (0.0, 1.5), np.array([2.0, 3.0])
    t = np.arange(2000) / fs
    lag = round(shift[1] / v * fs)
    margin = round(0.3 / v * fs)
    s_min, s_max = max(1, math.ceil(0.9 / v * fs / st)), math.floor(2.2 / v * fs / st)
    outcomes = set()
    for trial in range(24):
        # a vehicle: groups of 1-3 axles, 1.2-1.5 m apart within a group
        taus, tau = [], 0.6 + 0.1 * rng.random()
        for size in rng.integers(1, 4, int(rng.integers(1, 4))):
            for _ in range(size):
                taus.append(tau)
                tau += rng.uniform(1.2, 1.5) / v
            tau += rng.uniform(3.0, 6.0) / v
        taus = np.array(taus)
        lo, hi = int(t.searchsorted(taus[0] - 2.0 / v)), int(t.searchsorted(taus[-1] + 3.5 / v))
        tt = t[lo:hi]
        amps = rng.uniform(0.5, 1.5, taus.size)
        y = np.empty((2, tt.size, 1))
        X = np.empty((2, tt.size, taus.size))
        for c, (gu, gk) in enumerate(grids):
            X[c] = np.interp(v * (tt[:, None] - taus[None, :]) - shift[c], gu, gk) * w[c]
            y[c, :, 0] = X[c] @ amps + 0.02 * rng.standard_normal(tt.size)
        # the pursuit's axles: one dropped or one moved now and then
        found = taus.copy()
        if trial % 3 == 1 and found.size > 1:
            found = np.delete(found, int(rng.integers(found.size)))
        if trial % 3 == 2:
            found[0] += 0.3 / v
        Xf = np.empty((2, tt.size, found.size))
        for c, (gu, gk) in enumerate(grids):
            Xf[c] = np.interp(v * (tt[:, None] - found[None, :]) - shift[c], gu, gk) * w[c]
        p = 3 if trial % 2 else 0
        rest = np.ascontiguousarray(np.stack([np.column_stack([np.ones(tt.size), tt - tt.mean(),
                                                               (tt - tt.mean()) ** 2])[:, :p]
                                              for _ in range(2)]))
        M = np.concatenate([Xf, rest], axis=2)
        coef = np.linalg.solve(M.transpose(0, 2, 1) @ M, M.transpose(0, 2, 1) @ y)
        ratio, bound, limit = 1.1, 1.1, (0.0, 1.0, 5.0)[trial % 3]
        ref_new, ref_changed, parts_of = _ref_choice(
            t, lo, found, y, rest, Xf, coef, grids, w, shift, v, fs, st, lag, margin, s_min,
            s_max, ratio, bound, limit)
        new, changed = K.choose_in_window(
            t, lo, found, y, rest, Xf, coef, grids[0][0], grids[0][1], grids[1][0],
            grids[1][1], w, shift[0], shift[1], v, fs, st, lag, margin, s_min, s_max, ratio,
            bound, limit, GROUP_AXLES, LEVEL_GAIN, RARE_GROUP, GROUP_DIP, GROUP_EXTENT,
            PEAK_FLOOR)
        assert changed == ref_changed
        _equal(new, ref_new)
        outcomes.add((changed, len(parts_of)))
    assert {c for c, _ in outcomes} == {False, True} and len(outcomes) >= 4
