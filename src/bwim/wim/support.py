"""Where multi-run influence lines may be non-zero: the lines' grid, the runs' signal
window and the trimming of first-pass lines.

Contract
--------
* Positions are in the passages' frame, m (with detected passages x = 0 is the first
  axle detector and the support may start at negative x).
* A :class:`Grid` is uniform, ``n`` intervals of ``h`` from ``x0``; the lines are zero at
  both ends, so ``n − 1`` interior ordinates are unknown.  :func:`uniform_grid` spans a
  support with the fewest intervals not longer than the requested spacing (at least 2).
* Unless the support is given, :func:`~bwim.wim.calibrate_lines` estimates it in two
  passes (docs/theory.md §14): :func:`generous_grid` over where the runs' signals are
  significant (:func:`signal_window`), widened by that length on each side within the
  records; then :func:`trimmed_support` of the first-pass lines.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Grid", "generous_grid", "signal_window", "trimmed_support", "uniform_grid"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Grid:
    """A uniform grid of influence-line ordinates.

    Attributes
    ----------
    x0 : float
        First node (the support's start), m.
    h : float
        Spacing, m.
    n : int
        Intervals; ``n − 1`` interior ordinates.
    """

    x0: float
    h: float
    n: int

    @property
    def x(self) -> np.ndarray:
        """The nodes, m, shape (n + 1,)."""
        return self.x0 + self.h * np.arange(self.n + 1)


def uniform_grid(x0: float, x1: float, h_req: float) -> Grid:
    """The grid from ``x0`` to ``x1`` (m, ``x1 > x0``) with the fewest intervals (at least
    2) not longer than ``h_req`` (m)."""
    n = max(int(np.ceil((x1 - x0) / h_req - 1e-9)), 2)
    return Grid(x0=x0, h=(x1 - x0) / n, n=n)


def signal_window(E: np.ndarray, P: np.ndarray, threshold: float,
                  fs: float) -> tuple[float, float] | None:
    """First-axle position where a run's signal becomes significant and last-axle position
    where it stops being so, m (None if it never is).

    ``E`` (n_t, n_c) are the run's readings, ``P`` (n_t, n_axles) its axle positions, m,
    ``fs`` its sampling rate, Hz.  Each channel, less its median over the first samples,
    is averaged over 30 ms and divided by its noise there; the envelope (root-sum-square
    over channels) is significant above ``threshold`` × its peak and 5 × its level in the
    first samples.
    """
    n0 = max(8, E.shape[0] // 20)
    width = max(1, round(0.03 * fs))
    kernel = np.ones(width) / width
    Z = np.stack([np.convolve(c, kernel, mode="same") for c in (E - np.median(E[:n0], 0)).T],
                 axis=1)
    sd = Z[width:n0].std(axis=0) if n0 > width + 2 else np.zeros(E.shape[1])
    floor = max(float(sd.max()), 1e-9 * float(np.abs(Z).max()), np.finfo(float).tiny)
    sd = np.where(sd > 0, sd, floor)  # noise-free channels
    env = np.sqrt(((Z / sd) ** 2).sum(axis=1))
    noise = float(np.sqrt(np.mean(env[width:n0] ** 2))) if n0 > width + 2 else 0.0
    thr = max(threshold * float(env.max()), 5.0 * noise)
    idx = np.flatnonzero(env > thr)
    if idx.size == 0:
        return None
    return float(P[idx[0], 0]), float(P[idx[-1], -1])


def generous_grid(windows: Sequence[tuple[float, float]], cover: tuple[float, float],
                  h_req: float) -> Grid:
    """The first pass's grid, m: the union of the runs' signal ``windows`` widened by its
    length on each side (at least ``max(10 h_req, 1 m)`` long), within ``cover`` (the
    positions the records span: the first axle's first and the last axle's last)."""
    lo = min(w[0] for w in windows)
    hi = max(w[1] for w in windows)
    if hi <= lo:
        hi = lo + max(h_req * 10, 1.0)
    pad = hi - lo
    return uniform_grid(max(lo - pad, cover[0]), min(hi + pad, cover[1]), h_req)


def trimmed_support(theta0: np.ndarray, grid: Grid, threshold: float, *,
                    keep_lobes: bool = False) -> tuple[float, float]:
    """The support of first-pass lines, m.

    ``theta0`` (n − 1, n_c) are the lines' interior ordinates on ``grid``.  From the peak
    of their magnitude (root-sum-square over channels) outward to where it falls below
    ``threshold`` × the peak, then on to the next local minimum (where the line returns to
    zero; beyond it a first-pass line carries the bridge's free vibration, phase-locked to
    the axles) or to where it is negligible (0.1 % of the peak), plus 2 spacings (within
    the grid).  With ``keep_lobes``, where the magnitude rises above ``threshold`` × the
    peak again further out, that lobe is part of the line too and the walk goes on from
    it: a slab continuous over its supports (or an abutment that carries moment) reads a
    load beyond the span with the opposite sign, and cutting that lobe off puts its
    reading on the axles on the span (issue 20 item 5; lobes below the threshold still
    end the line at the zero before them).  Only one lobe each side, and only of the
    opposite sign (its largest ordinates against the peak's: a negative scalar product),
    as the adjacent span of a continuous slab reads: a first pass whose signal spreads
    (wrong declared loads) keeps no lobe of the same sign.
    """
    zero = np.zeros((1, theta0.shape[1]))
    full = np.vstack([zero, theta0, zero])  # on grid.x
    mag = np.sqrt((full**2).sum(axis=1))
    peak = int(np.argmax(mag))
    small = mag < threshold * mag[peak]
    negligible = 1e-3 * mag[peak]

    def lobe_peak(k: int, step: int) -> int:
        """The largest node of the significant run that starts at ``k``."""
        run = [k]
        while 0 < run[-1] + step < mag.size - 1 and not small[run[-1] + step]:
            run.append(run[-1] + step)
        return max(run, key=lambda i: mag[i])

    def walk(step: int) -> int:
        j, lobes = peak, 0
        while True:
            while 0 < j < mag.size - 1 and not small[j]:
                j += step
            while 0 < j < mag.size - 1 and mag[j + step] < mag[j] and mag[j] > negligible:
                j += step
            if not 0 < j < mag.size - 1:
                return j
            ahead = ~small[j + step::step] if step > 0 else ~small[j - 1::-1]
            if not keep_lobes or lobes or not ahead.any():  # nothing beyond: it ends
                return j
            k = j + step * (int(np.argmax(ahead)) + 1)
            # a continuous slab's lobe: the adjacent span, read with the opposite sign
            if float(full[lobe_peak(k, step)] @ full[peak]) >= 0:
                return j
            j, lobes = k, 1  # keep it

    x = grid.x
    return (max(x[walk(-1)] - 2 * grid.h, x[0]), min(x[walk(+1)] + 2 * grid.h, x[-1]))
