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
  autocorrelation (:func:`explained`).  A group whose count stands keeps its refined
  times unless they fit worse by the threshold.
* Misfits in level variances (see :mod:`bwim.detect.vehicle_fit`); times in s, distances
  in m, speeds in m/s.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.signal import find_peaks

from .vehicle_fit import REACH, Problem

__all__ = ["GROUP_AXLES", "GROUP_DIP", "GROUP_EXTENT", "GROUP_SPACING", "LEVEL_GAIN",
           "PEAK_FLOOR", "RARE_GROUP", "SEGMENT_MARGIN", "choose_groups", "explained",
           "hypotheses", "segments", "templates"]

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
    n = taus.size
    lo = int(np.searchsorted(pb.t, span[0] - REACH / v))
    hi = int(np.searchsorted(pb.t, span[1] + (pb.shift[1] + REACH) / v, side="right"))
    rows = np.arange(lo, hi)
    X = pb.atoms(taus, v, rows)
    local, parts = [], []
    for c in range(2):
        M = np.hstack([X[c], pb.rest[c][rows]])
        G = M.T @ M
        G.flat[::G.shape[0] + 1] += 1e-12 * (np.trace(G) / G.shape[0] + 1e-300)
        coef = np.linalg.solve(G, M.T @ pb.y[rows, c])
        local.append(pb.y[rows, c] - pb.rest[c][rows] @ coef[n:])
        parts.append(X[c] * coef[:n])
    fitted = [p.sum(axis=1) for p in parts]
    resid = [local[c] - fitted[c] for c in range(2)]
    r_total = sum(float(r @ r) for r in resid)
    n_samples = 2 * rows.size
    tpl = templates(pb, v)
    st = pb.step  # hypotheses on every st-th sample
    at = np.round((taus - pb.t[lo]) * pb.fs / st).astype(int)  # axles' grid points
    margin = round(SEGMENT_MARGIN / v * pb.fs)
    s_min = max(1, int(np.ceil(min_sp / v * pb.fs / st)))
    s_max = int(np.floor(GROUP_SPACING / v * pb.fs / st))
    n_grid = (rows.size - 1) // st + 1
    out, changed = [], False
    parts_of = segments(pb, local, v, margin, st)
    for first, last in parts_of:
        g = np.flatnonzero((at >= first) & (at <= last))
        corr, auto = [], []
        first, last = max(first, 0), min(last, n_grid - 1)
        energy = r_inside = 0.0  # the group's readings and residual where it acts
        for c, (j0, h, r) in enumerate(tpl):
            z = local[c] - fitted[c] + parts[c][:, g].sum(axis=1)  # less the others
            a, b = max(first * st + j0, 0), min(last * st + j0 + h.size, rows.size)
            energy += float(z[a:b] @ z[a:b])
            r_inside += float(resid[c][a:b] @ resid[c][a:b])
            # correlation with an axle at grid point m (sample st m), on the segment:
            # Σ_j z[st m + j0 + j] h[j], zero where the response leaves the window
            full = np.zeros(n_grid)
            q0 = max(first * st + j0, 0)
            q1 = min(last * st + j0, rows.size - h.size)
            if q1 >= q0:
                cc = np.correlate(z[q0:q1 + h.size], h, mode="valid")  # q = q0 … q1
                m = np.arange(first, last + 1)
                q = st * m + j0
                ok = (q >= q0) & (q <= q1)
                full[m[ok]] = cc[q[ok] - q0]
            corr.append(full)
            r = r[::st]
            auto.append(np.concatenate([r, np.zeros(max(0, s_max * GROUP_AXLES - r.size + 1))]))
        best = None
        for k in range(1, GROUP_AXLES + 1):
            hyp = hypotheses(first, last, k, s_min, s_max)
            if hyp.shape[0] == 0:
                break
            gained, amps = explained(hyp, corr, auto)
            positive = np.all(amps > 0, axis=(1, 2))
            with np.errstate(divide="ignore", invalid="ignore"):
                lr = np.log(amps[..., 1] / (pb.ratio * amps[..., 0]))
            valid = positive & np.all(np.abs(np.where(positive[:, None], lr, np.inf))
                                      <= pb.bound, axis=1)
            if not valid.any():
                break
            j = int(np.argmax(np.where(valid, gained, -np.inf)))
            if best is not None:
                gain = gained[j] - best[0]
                left = energy - best[0]  # the group's residual with one axle fewer
                level = (r_total - r_inside + left) / n_samples
                rare = RARE_GROUP if k > 3 else 1.0
                if gain < limit or gain < LEVEL_GAIN * rare * level:
                    break
            best = (float(gained[j]), hyp[j])
        if best is None:
            out.extend(taus[g])
            continue
        if best[1].size == g.size:
            # the count stands: the refined times stay unless they fit worse by more
            # than the threshold (two of a tridem's axles on one merged peak)
            mine = np.clip(at[g], first, last)[None, :]
            if explained(mine, corr, auto)[0][0] > best[0] - limit:
                out.extend(taus[g])
                continue
        out.extend(pb.t[lo + st * best[1]])
        changed = True
    # axles outside every segment: noise the pursuit took
    changed |= not all(any(a <= m <= b for a, b in parts_of) for m in at)
    return np.sort(np.array(out)) if changed else None


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
        lo = max(a + int(above[0]) - margin, a)
        hi = min(a + int(above[-1]) + margin, b)
        out.append((lo // st, hi // st))
    return out


def hypotheses(first: int, last: int, k: int, s_min: int, s_max: int) -> np.ndarray:
    """Sample indices (n_hyp, k) of k evenly spaced axles between ``first`` and ``last``
    (spacings s_min … s_max samples)."""
    if k == 1:
        return np.arange(first, last + 1)[:, None]
    start, sp = np.nonzero(np.arange(first, last + 1)[:, None]
                           + (k - 1) * np.arange(s_min, s_max + 1)[None, :] <= last)
    return (first + start)[:, None] + (s_min + sp)[:, None] * np.arange(k)[None, :]


def explained(hyp: np.ndarray, corr, auto) -> tuple[np.ndarray, np.ndarray]:
    """Misfit each hypothesis removes (both detectors) and its amplitudes (n_hyp, k, 2)."""
    k = hyp.shape[1]
    if k == 1:
        b = np.stack([corr[0][hyp[:, 0]], corr[1][hyp[:, 0]]], axis=-1)  # (n_hyp, 2)
        a = b / np.array([max(auto[0][0], 1e-300), max(auto[1][0], 1e-300)])
        return np.sum(a * b, axis=1), a[:, None, :]
    lag = np.abs(hyp[:, :, None] - hyp[:, None, :])
    total = np.zeros(hyp.shape[0])
    amps = np.zeros((*hyp.shape, 2))
    for c in range(2):
        b = corr[c][hyp]
        G = auto[c][lag] + 1e-12 * auto[c][0] * np.eye(k)
        a = np.linalg.solve(G, b[..., None])[..., 0]
        total += np.sum(a * b, axis=1)
        amps[..., c] = a
    return total, amps
