"""A vehicle's axle groups chosen again among evenly spaced axles (model selection).

Contract
--------
* Input: a :class:`~bwim.detect.vehicle_fit.Problem`, a vehicle's axle times and speed
  (refined), the misfit threshold an axle must pass and the smallest spacing.
* The rest and the axles are fitted on the vehicle's span and the rest taken off: what
  is left of both detectors' readings (the second's moved back by the lag, each over its
  largest) is cut into **axle groups** where it dips below :data:`GROUP_DIP` of the lower
  neighbouring peak (:func:`segments`); a group may lie where its readings exceed
  :data:`GROUP_EXTENT` of its peak, :data:`SEGMENT_MARGIN` m more each side.  An axle the
  pursuit missed is found here; axles outside every group are dropped.
* Each group, the other groups' axles taken off too, is chosen among 1 …
  :data:`GROUP_AXLES` **evenly spaced** axles (spacings from the smallest to
  :data:`GROUP_SPACING`, positions on the window's sampling grid): the most axles such
  that each more lowers the misfit by the threshold and by :data:`LEVEL_GAIN` times the
  vehicle's residual per sample (:data:`RARE_GROUP` times more for a fourth: dynamic tyre
  forces beyond the calibration truck's make spurious splits cheaper), with every
  axle's amplitudes positive and seen by both detectors.  Fast: a hypothesis's misfit
  needs only the readings' correlation with one axle's response and that response's
  autocorrelation (:func:`explained`; evenly spaced axles' systems depend on their
  spacing alone: one inverse per spacing, every segment's hypotheses of one count at
  once, :func:`evenly_explained`, :func:`group_counts`).  A group whose count stands
  keeps its refined times unless they fit worse by the threshold.  A segment that holds none of the
  vehicle's axles and where no single axle could fit (:func:`one_axle_may_fit`: the
  one-axle test made once over the window, widened by a bound on its rounding) is noise
  and skipped without changing any choice.
* Misfits in level variances (see :mod:`bwim.detect.vehicle_fit`); times in s, distances
  in m, speeds in m/s.
"""

from __future__ import annotations

import bisect

import numpy as np
from scipy.signal import find_peaks

from .signals import last_axis_sum
from .vehicle_fit import REACH, Problem, Rows, ridged_normal

__all__ = ["GROUP_AXLES", "GROUP_DIP", "GROUP_EXTENT", "GROUP_SPACING", "LEVEL_GAIN",
           "PEAK_FLOOR", "RARE_GROUP", "SEGMENT_MARGIN", "choose_groups", "evenly_explained",
           "explained", "group_counts", "hypotheses", "one_axle_may_fit", "segments",
           "templates"]

#: Largest spacing within an axle group (tandem, tridem) whose count is chosen again, m.
GROUP_SPACING = 2.2
#: Axle groups are cut where the detectors' readings dip below this share of the lower
#: neighbouring peak (under a response 1.2 m wide at half height: axles 1.3 m apart dip
#: to about 0.8, 2 m apart to about 0.3, 2.5 m apart to about 0.1).
GROUP_DIP = 0.25
#: An axle group spans where the readings exceed this share of its highest peak (an
#: axle's response falls to it about 0.65 m away) ...
GROUP_EXTENT = 0.3
#: ... and this much more each side, m.
SEGMENT_MARGIN = 0.3
#: Peaks of the readings lower than this share of the highest, or rising less above
#: their surroundings, do not start a group.
PEAK_FLOOR = 0.1
#: Most axles of a group.
GROUP_AXLES = 4
#: One more axle in a group must lower the misfit by this many times the vehicle's
#: residual per sample (the dynamic force of its tyres, beyond what the calibration
#: truck showed) ...
LEVEL_GAIN = 180.0
#: ... times this for a fourth axle in a group (groups of four are rare; a tridem's
#: dynamic forces make a fourth axle cheaper).
RARE_GROUP = 1.5


def templates(pb: Problem, v: float) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Per detector the weighted response of an axle passing detector 1 at sample 0, on
    the samples where it is not zero: (first sample offset, values, autocorrelation)."""
    out = []
    for c, (u, k, _) in enumerate(pb.grids):
        d = pb.shift[c]
        j0 = int(np.ceil((u[0] + d) / v * pb.fs))
        j1 = int(np.floor((u[-1] + d) / v * pb.fs))
        h = np.interp(v * np.arange(j0, j1 + 1) / pb.fs - d, u, k) * pb.w[c]
        out.append((j0, h, np.correlate(h, h, mode="full")[h.size - 1:]))
    return out


def choose_groups(pb: Problem, taus: np.ndarray, v: float, limit: float, min_sp: float,
                  span: tuple[float, float]) -> np.ndarray | None:
    """Each axle group of the vehicle (where the detectors' readings, with the rest and
    the other groups' axles fitted and taken off, stand out between dips: see
    :func:`segments`) chosen again among 1 … GROUP_AXLES evenly spaced axles at the
    vehicle's speed: the most axles such that each more lowers the misfit by ``limit``
    and both detectors see every axle.  Fast: with the other axles and the rest fitted and
    taken off, a group's misfit needs only the readings' correlation with one axle's
    response and that response's autocorrelation (on the window's sampling grid).  The new
    times, or None."""
    taus = np.sort(taus)
    n = taus.size
    lo = int(pb.t.searchsorted(span[0] - REACH / v))
    hi = int(pb.t.searchsorted(span[1] + (pb.shift[1] + REACH) / v, side="right"))
    w = Rows(pb, np.arange(lo, hi), slice(lo, hi))
    rows = w.rows
    # both detectors' least squares as one stack of two (the same numbers as two)
    X = pb.both_atoms(v, w.t[:, None] - taus[None, :])[0]
    Mt, G = ridged_normal(np.concatenate([X, w.rest], axis=2))
    coef = np.linalg.solve(G, Mt @ w.y)
    local = (w.y - w.rest @ coef[:, n:])[..., 0]  # (2, n_rows)
    parts = X * coef[:, None, :n, 0]  # (2, n_rows, n)
    fitted = last_axis_sum(parts)
    resid = local - fitted
    r_total = sum(float(r @ r) for r in resid)
    n_samples = 2 * rows.size
    tpl = templates(pb, v)
    st = pb.step  # hypotheses on every st-th sample
    at = ((taus - pb.t[lo]) * pb.fs / st).round().astype(int)  # axles' grid points
    margin = round(SEGMENT_MARGIN / v * pb.fs)
    s_min = max(1, int(np.ceil(min_sp / v * pb.fs / st)))
    s_max = int(np.floor(GROUP_SPACING / v * pb.fs / st))
    n_grid = (rows.size - 1) // st + 1
    # the responses' autocorrelation on the grid (zero beyond the response)
    auto = [np.concatenate([r[::st], np.zeros(max(0, s_max * GROUP_AXLES - r[::st].size + 1))])
            for _, _, r in tpl]
    out, changed = [], False
    parts_of = segments(pb, local, v, margin, st)
    bare = None  # one_axle_may_fit, made when a segment without axles asks (read one by one)
    at_list = at.tolist()
    # the segments worth a choice: their grid points' correlations with one axle end to
    # end (both detectors), the vehicle's axles in each, its readings' and residual's
    # energies where its axles act
    chosen, corr_all = [], ([], [])
    for first, last in parts_of:
        i0, i1 = bisect.bisect_left(at_list, first), bisect.bisect_right(at_list, last)
        if i0 == i1:
            if bare is None:
                bare = one_axle_may_fit(pb, resid, tpl, auto, st, n_grid).tolist()
            if bare[last + 1] == bare[first]:
                continue  # no axle of the vehicle here and no one axle fits: noise
        g = np.arange(i0, i1)
        first, last = max(first, 0), min(last, n_grid - 1)
        energy = r_inside = 0.0
        for c, (j0, h, _) in enumerate(tpl):
            # the readings less the others' axles, where this group's act
            a, b = max(first * st + j0, 0), min(last * st + j0 + h.size, rows.size)
            z = (resid[c][a:b] + last_axis_sum(parts[c][a:b].take(g, axis=1)) if g.size
                 else resid[c][a:b])
            energy += float(z @ z)
            r_inside += float(resid[c][a:b] @ resid[c][a:b])
            # correlation with an axle at grid point m (sample st m), on the segment:
            # Σ_j z[st m + j0 + j] h[j], zero where the response leaves the window
            part = np.zeros(last - first + 1)
            q1 = min(last * st + j0, rows.size - h.size)
            if q1 >= a:  # grid points whose sample q = st m + j0 lies in a … q1
                cc = np.correlate(z[:q1 - a + h.size], h, mode="valid")  # q = a … q1
                m0 = max(first, -((j0 - a) // st))
                m1 = min(last, (q1 - j0) // st)
                if m1 >= m0:
                    part[m0 - first:m1 - first + 1] = cc[st * m0 + j0 - a:
                                                         st * m1 + j0 - a + 1:st]
            corr_all[c].append(part)
        chosen.append((first, last, g, energy, r_inside))
    if not chosen:
        counts = []
    else:
        corr = [np.concatenate(corr_all[0]), np.concatenate(corr_all[1])]
        lengths = np.array([last - first + 1 for first, last, *_ in chosen])
        # the vehicle's residual outside each segment, and the segment's readings' energy
        outside = [r_total - r_inside for *_, r_inside in chosen]
        energies = [energy for *_, energy, _ in chosen]
        counts = group_counts(pb, corr, auto, lengths, outside, energies, limit, n_samples,
                         s_min, s_max)
    offsets = np.cumsum([0, *(last - first + 1 for first, last, *_ in chosen)])
    for (first, last, g, _, _), best, off in zip(chosen, counts, offsets, strict=False):
        if best is None:
            out.extend(taus[g])
            continue
        if best[1].size == g.size:
            # the count stands: the refined times stay unless they fit worse by more
            # than the threshold (two of a tridem's axles on one merged peak)
            mine = np.clip(at[g], first, last)[None, :] - first
            seg = [corr[0][off:off + last - first + 1], corr[1][off:off + last - first + 1]]
            if explained(mine, seg, auto)[0][0] > best[0] - limit:
                out.extend(taus[g])
                continue
        out.extend(pb.t[lo + st * (best[1] + first)])
        changed = True
    # axles outside every segment: noise the pursuit took
    changed |= not all(any(a <= m <= b for a, b in parts_of) for m in at)
    return np.sort(np.array(out)) if changed else None


def one_axle_may_fit(pb: Problem, resid, tpl, auto, st: int, n_grid: int) -> np.ndarray:
    """Cumulative count over the grid points (``n_grid + 1``, from 0) of those where one
    axle might fit the vehicle's residual ``resid`` (per detector, on the window's rows)
    with amplitudes positive at both detectors in their gain ratio, as
    :func:`choose_groups` tests it on a segment holding none of the vehicle's axles
    (``tpl``: the :func:`templates`; ``auto``: their autocorrelations every ``st``-th
    sample).  A segment without such a point is skipped.  Computed once over the window,
    so with rounding of its own: the test is widened by a bound on that rounding and only
    ever lets more segments through to the exact test."""
    b, tol = [], []
    for c, (j0, h, _) in enumerate(tpl):
        z = resid[c]
        full = np.full(n_grid, -np.inf)  # no correlation: the response leaves the window
        if z.size >= h.size:
            cc = np.correlate(z, h, mode="valid")  # sample q = 0 … z.size - h.size
            m = np.arange(n_grid)
            q = st * m + j0
            ok = (q >= 0) & (q < cc.size)
            full[ok] = cc[q[ok]]
        b.append(full)
        # a dot product's rounding: far below this (n eps Σ|z h| at most)
        tol.append(1e-9 * float(np.abs(h).sum()) * float(np.abs(z).max(initial=0.0)) + 1e-300)
    pos = [b[c] > -tol[c] for c in range(2)]
    sure = (b[0] > 1e3 * tol[0]) & (b[1] > 1e3 * tol[1])  # well away from zero
    with np.errstate(divide="ignore", invalid="ignore"):
        a0 = np.where(sure, b[0], 1.0) / max(auto[0][0], 1e-300)
        a1 = np.where(sure, b[1], 1.0) / max(auto[1][0], 1e-300)
        lr = np.log(a1 / (pb.ratio * a0))
        slack = 4.0 * (tol[0] / np.where(sure, b[0], 1.0) + tol[1] / np.where(sure, b[1], 1.0))
    maybe = pos[0] & pos[1] & (~sure | (np.abs(lr) <= pb.bound + slack + 1e-12))
    return np.concatenate([[0], maybe.cumsum()])


def segments(pb: Problem, local, v: float, margin: int, st: int) -> list[tuple[int, int]]:
    """The vehicle's axle groups in its window: (first, last) grid points where a group's
    axles may be.  Both detectors' local readings (the second's moved back by the lag,
    each over its largest) are added; groups are cut where their sum dips below GROUP_DIP
    of the lower of the two peaks beside, and span where the sum exceeds GROUP_EXTENT of
    their highest, ``margin`` samples more each side (not past a cut)."""
    lag = round(pb.shift[1] / v * pb.fs)
    e = np.zeros(local[0].size)
    for c, r in enumerate(pb.grids):
        z = local[c] * np.sign(r[1][int(np.argmax(np.abs(r[1])))])
        z = np.maximum(z, 0.0)
        top = float(z.max())
        if top <= 0:
            continue
        shift = lag if c else 0
        if shift < e.size:  # a window shorter than the lag: the second adds nothing
            e[:e.size - shift] += z[shift:] / top
    if not e.max() > 0:
        return []
    floor = PEAK_FLOOR * float(e.max())
    peaks, _ = find_peaks(e, height=floor, prominence=floor)
    if peaks.size == 0:
        return []
    cuts = np.zeros(0, dtype=int)
    if peaks.size > 1:
        # between two neighbouring peaks a and b, the first lowest sample (b, a peak, is
        # higher than a sample between: the lowest of a … b lies in a … b - 1)
        lows = np.minimum.reduceat(e[:peaks[-1]], peaks[:-1])
        equal = (e[peaks[0]:peaks[-1]] == lows.repeat(peaks[1:] - peaks[:-1])).nonzero()[0]
        where = peaks[0] + equal[equal.searchsorted(peaks[:-1] - peaks[0])]
        cuts = where[lows < GROUP_DIP * np.minimum(e[peaks[:-1]], e[peaks[1:]])]
    cuts = np.concatenate([[0], cuts, [e.size - 1]])
    # each part a … b (both ends in it): where it exceeds GROUP_EXTENT of its highest
    a, b = cuts[:-1], cuts[1:]
    size = b - a + 1
    starts = size.cumsum() - size
    idx = np.arange(int(size.sum())) - (starts - a).repeat(size)
    vals = e[idx]
    high = GROUP_EXTENT * np.maximum.reduceat(vals, starts)
    above = (vals >= high.repeat(size)).nonzero()[0]
    lo = np.maximum(idx[above[above.searchsorted(starts)]] - margin, a)
    hi = np.minimum(idx[above[above.searchsorted(starts + size) - 1]] + margin, b)
    return list(zip((lo // st).tolist(), (hi // st).tolist(), strict=True))


def hypotheses(first: int, last: int, k: int, s_min: int, s_max: int) -> np.ndarray:
    """Sample indices (n_hyp, k) of k evenly spaced axles between ``first`` and ``last``
    (spacings s_min … s_max samples)."""
    if k == 1:
        return np.arange(first, last + 1)[:, None]
    start, sp = np.nonzero(np.arange(first, last + 1)[:, None]
                           + (k - 1) * np.arange(s_min, s_max + 1)[None, :] <= last)
    return (first + start)[:, None] + (s_min + sp)[:, None] * np.arange(k)[None, :]


def evenly_explained(lengths: np.ndarray, k: int, s_min: int, s_max: int, corr, auto
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`hypotheses` ``(0, L - 1, k, s_min, s_max)`` (k ≥ 2) of every segment of
    ``lengths`` grid points, whose correlations ``corr`` (per detector) lie end to end,
    and what :func:`explained` gives for each: ``(hyp, owner, gained, amps)``, ``hyp`` in
    each segment's own grid points, ``owner`` its segment (ascending; in a segment the
    order of :func:`hypotheses`).  Evenly spaced axles' systems depend on their spacing
    alone (the autocorrelation at multiples of it), so each spacing's is inverted once
    and applied to every start of every segment (the numbers of solving each, to
    rounding)."""
    lengths = np.asarray(lengths, dtype=int)
    spacings = np.arange(s_min, s_max + 1)
    owner_of = np.arange(lengths.size).repeat(lengths)  # each grid point's segment
    offsets = lengths.cumsum() - lengths
    local = np.arange(owner_of.size) - offsets[owner_of]
    row, sp = (local[:, None] + (k - 1) * spacings[None, :]
                <= (lengths - 1)[owner_of][:, None]).nonzero()
    steps = spacings[sp][:, None] * np.arange(k)[None, :]
    hyp = local[row][:, None] + steps
    if hyp.shape[0] == 0:
        return hyp, np.zeros(0, dtype=int), np.zeros(0), np.zeros((0, k, 2))
    n_s = int(sp.max()) + 1  # the spacings used
    lags = spacings[:n_s, None, None] * np.abs(np.arange(k)[:, None] - np.arange(k)[None, :])
    eye = np.eye(k)
    G = np.array([auto[c][lags] + 1e-12 * auto[c][0] * eye for c in range(2)])
    at = row[:, None] + steps  # in the correlations end to end
    b = np.array([corr[0][at], corr[1][at]])  # (2, n_hyp, k)
    # each hypothesis's inverse (np.take: the indexing's numbers, without its slow path)
    a = (np.linalg.inv(G).take(sp, axis=1) @ b[..., None])[..., 0]
    gained = last_axis_sum(a * b)
    return hyp, owner_of[row], gained[0] + gained[1], a.transpose(1, 2, 0)


def group_counts(pb: Problem, corr, auto, lengths: np.ndarray, outside, energies,
                 limit: float, n_samples: int, s_min: int, s_max: int) -> list:
    """Each segment's choice (:func:`choose_groups`): ``(misfit removed, grid points)``
    of the most evenly spaced axles such that each more lowers the misfit by ``limit``
    and by LEVEL_GAIN times the residual per sample with one axle fewer (``(outside +
    (energy - removed)) / n_samples``: the vehicle's residual outside the segment, the
    segment's readings' energy), every axle positive and seen by both detectors; None
    where no single axle is.  ``corr``: the segments' correlations end to end; every
    segment's hypotheses of one count evaluated at once."""
    n = lengths.size
    offsets = lengths.cumsum() - lengths
    # one axle at every grid point: explained() without the indexing
    b = np.array(corr).T  # (n, 2)
    one = np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
    amps = b / one
    gained = last_axis_sum(amps * b)
    positive = (amps[:, 0] > 0) & (amps[:, 1] > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.log(amps[:, 1] / (pb.ratio * amps[:, 0]))
    valid = positive & (np.abs(lr) <= pb.bound)  # (lr of a non-positive one: ANDed away)
    score = np.where(valid, gained, -np.inf)
    best: list = [None] * n
    active = []
    for i in range(n):
        o = int(offsets[i])
        j = int(score[o:o + lengths[i]].argmax())
        if score[o + j] > -np.inf:  # a valid one (valid ones are finite)
            best[i] = (float(gained[o + j]), np.array([j]))
            active.append(i)
    for k in range(2, GROUP_AXLES + 1):
        if not active:
            break
        sub = [corr[c][np.concatenate([np.arange(offsets[i], offsets[i] + lengths[i])
                                       for i in active])] for c in range(2)]
        hyp, owner, gained, amps = evenly_explained(lengths[active], k, s_min, s_max, sub,
                                                    auto)
        with np.errstate(divide="ignore", invalid="ignore"):
            lr = np.log(amps[..., 1] / (pb.ratio * amps[..., 0]))
        # every axle positive at both detectors and seen by both
        valid = ((amps[..., 0] > 0) & (amps[..., 1] > 0) & (np.abs(lr) <= pb.bound)).all(axis=1)
        score = np.where(valid, gained, -np.inf)
        bounds = owner.searchsorted(np.arange(len(active) + 1))
        rare = RARE_GROUP if k > 3 else 1.0
        still = []
        for q, i in enumerate(active):
            h0, h1 = int(bounds[q]), int(bounds[q + 1])
            if h0 == h1:
                continue  # no k axles fit in the segment
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


def explained(hyp: np.ndarray, corr, auto) -> tuple[np.ndarray, np.ndarray]:
    """Misfit each hypothesis removes (both detectors) and its amplitudes (n_hyp, k, 2)."""
    k = hyp.shape[1]
    if k == 1:
        b = np.array([corr[0][hyp[:, 0]], corr[1][hyp[:, 0]]]).T  # (n_hyp, 2)
        a = b / np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
        return last_axis_sum(a * b), a[:, None, :]
    lag = np.abs(hyp[:, :, None] - hyp[:, None, :])
    eye = np.eye(k)
    # both detectors' systems as one stack (each solved on its own: the same numbers)
    b = np.array([corr[0][hyp], corr[1][hyp]])  # (2, n_hyp, k)
    G = np.array([auto[c][lag] + 1e-12 * auto[c][0] * eye for c in range(2)])
    a = np.linalg.solve(G, b[..., None])[..., 0]
    gained = last_axis_sum(a * b)
    return gained[0] + gained[1], a.transpose(1, 2, 0)
