"""A vehicle's axles at two detectors as one least-squares model, and its refinement.

Contract
--------
* :class:`Problem` holds one record's two detector channels for the fit: weighted by each
  detector's level (:attr:`~bwim.detect.response.DetectorResponse.level`: what the
  learned response missed of the calibration truck's axles, or the noise if more; all
  misfits of :mod:`bwim.detect.pursuit` and :mod:`bwim.detect.groups` are in these
  "level variances"), the columns of their **rest** (with gauges: the bending as the
  learned gauge combination reads it, an offset and a drift; without: none, readings and
  responses high-passed in space over :data:`~bwim.detect.response.HIGH_PASS` m of
  travel at the record's first speed estimate), and the responses ``K_d`` on their grids.
* Model of a vehicle's axles on its window (:func:`window`: :data:`REACH` m of travel
  before its first axle reaches detector 1 to REACH m after its last leaves detector 2,
  every ``step``-th sample: at least :data:`WINDOW_SAMPLES` per response width at half
  height)::

      y_d(t) = Σ_i A_id K_d(v (t − τ_i) − D_d) + rest_d(t) + e,   D_1 = 0, D_2 = D,

  ``τ_i`` the time axle ``i`` passes detector 1, ``v`` the speed, ``A_id`` its amplitude
  at each detector (free: an axle's dynamic force differs at the two instants it passes
  them).  :func:`solve` gives the amplitudes and rest by linear least squares, the
  residual, each axle's **removal cost** (the misfit's rise without it:
  ``A_i² / [(MᵀM)⁻¹]_ii`` summed over the detectors) and, on request, the
  variable-projection Jacobian of the residual in (τ, v) (Kaufman's approximation);
  residuals and costs are scaled to the misfit of all samples.  :func:`refine` is
  Levenberg–Marquardt on (τ, v) over that projection (at most :data:`MAX_LM`
  iterations, until the misfit falls by less than :data:`CONVERGED` of itself).
* An axle is **seen by both** detectors when ``|ln(A_2 / (ρ A_1))|`` (``ρ`` the learned
  gain ratio) is at most :data:`RATIO_SPREADS` times the spread the calibration runs
  showed, and at least :data:`MIN_RATIO_BOUND`.
* Compiled (:mod:`bwim.detect.fit_kernels`, numba): the atoms (element by element the
  operations of :meth:`Problem.atoms`: the same numbers), a :class:`Solution`'s least
  squares, amplitudes, removal costs (numpy's ``a**2 / maximum(diag, 1e-300)``, the same
  operations) and Jacobian, and :func:`refine`'s whole Levenberg–Marquardt loop.  The same
  equations; their sums run in orders of their own, as numpy's BLAS and LAPACK run in
  theirs, so the numbers agree with a numpy version's to rounding.  A fit of coincident
  axles (singular but for the 1e-12 ridge) turns that rounding into differences of any
  size, in numpy as much (its results then change with the BLAS kernel).
* A vehicle's per-axle tests for the pursuit in Python floats (:meth:`Problem.log_ratios`,
  :meth:`Problem.seen`): numpy's numbers (the same IEEE operations; the logarithms
  numpy's own, on an array of the same size) without a dozen numpy calls on a few values.
* Times in s, distances in m, speeds in m/s; amplitudes in each detector's reading units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .fit_kernels import (
    GridTable,
    grid_atoms,
    grid_table,
    jacobian,
    least_squares,
    levenberg_marquardt,
)
from .response import HIGH_PASS, LearnedResponses, high_pass

__all__ = ["CONVERGED", "MAX_LM", "MIN_RATIO_BOUND", "RATIO_SPREADS", "REACH",
           "WINDOW_SAMPLES", "Problem", "Rows", "Solution", "VehicleFit", "make_problem", "refine",
           "relative", "ridged_normal", "solution", "solve", "window"]

#: A vehicle's fit looks this far beyond its first and last axle, m of travel.
REACH = 2.0
#: An axle's two amplitudes may differ from the gain ratio by this many learned spreads.
RATIO_SPREADS = 4.0
#: ... and at least by this factor (natural log: a factor 3).
MIN_RATIO_BOUND = float(np.log(3.0))
#: Samples per response width (at half height) a vehicle's fit keeps at least.
WINDOW_SAMPLES = 8
#: Levenberg–Marquardt iterations of a refinement, at most ...
MAX_LM = 15
#: ... which stops when the misfit falls by less than this share (or the times move by
#: less than 5 mm of travel).
CONVERGED = 3e-3


def ridged_normal(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Mᵀ, G)`` for both detectors' design matrices stacked, ``M`` (2, n, p): ``G =
    Mᵀ M`` with its diagonal raised by 1e-12 of its mean (a ridge far below the data's
    scale that keeps a rank-deficient fit solvable)."""
    Mt = M.transpose(0, 2, 1)
    G = Mt @ M
    p = G.shape[1]
    diag = G.reshape(2, -1)[:, ::p + 1]  # a view
    diag += 1e-12 * (diag.sum(axis=-1) / p + 1e-300)[:, None]
    return Mt, G


@dataclass(frozen=True, eq=False)
class Problem:
    """One record's two channels, weighted, their rest's columns and the responses (see
    the module contract); made by :func:`make_problem`."""

    t: np.ndarray
    y: np.ndarray  # (n_t, 2) weighted (level units); high-passed without gauges
    rest: tuple[np.ndarray, np.ndarray]  # per detector (n_t, k) weighted columns
    q_rest: tuple[np.ndarray, np.ndarray]  # their orthonormal bases (all samples)
    w: np.ndarray  # (2,) 1 / level
    ratio: float  # the second detector's gain over the first's
    bound: float  # largest |ln(A_2 / (ratio A_1))| of an axle
    spread: float  # learned spread of that log ratio
    shift: tuple[float, float]  # D_d
    grids: tuple  # per detector (u, K, dK/du), high-passed without gauges
    steps: tuple  # per detector K's differences between ordinates (0 after the last)
    fs: float
    step: int  # every step-th sample in a vehicle's window

    def atoms(self, taus: np.ndarray, v: float, rows: slice | np.ndarray = slice(None),
              slopes: bool = False, only: int | None = None,
              dt: np.ndarray | None = None):
        """Per detector the weighted columns K(v (t − τ_i) − D_d), (n_rows, n), K linear
        between its ordinates; with ``slopes`` also their slopes dK/du (of the linear
        pieces) at the same points; with ``only`` that detector's (None for the other).
        ``dt``: the rows' times less ``taus`` (n_rows, n), when already made."""
        if dt is None:
            dt = self.t[rows][:, None] - taus[None, :]
        out, der = [], []
        for c, (u, k, _) in enumerate(self.grids):
            if only is not None and c != only:
                out.append(None)
                der.append(None)
                continue
            du = u[1] - u[0]
            x = (v * dt - (self.shift[c] + u[0])) * (1.0 / du)
            np.clip(x, 0.0, u.size - 1.000001, out=x)  # the grids end in zeros
            j = x.astype(np.intp)
            x -= j
            step = self.steps[c][j]
            out.append((k[j] + x * step) * self.w[c])
            if slopes:
                der.append(step * (self.w[c] / du))
        return (out, der) if slopes else out

    @cached_property
    def stacked(self) -> tuple[np.ndarray, np.ndarray]:
        """The readings (2, n_t, 1) and the rest's columns (2, n_t, k), one detector after
        the other."""
        return np.array([self.y[:, c] for c in range(2)])[..., None], np.array(self.rest)

    @cached_property
    def table(self) -> GridTable:
        """Both detectors' grids as the compiled kernels read them
        (:mod:`bwim.detect.fit_kernels`)."""
        return grid_table(self.grids, self.steps, self.shift, self.w)

    def both_atoms(self, v: float, dt: np.ndarray, slopes: bool = False,
                   out: np.ndarray | None = None):
        """:meth:`atoms` of both detectors as one array (2, n_rows, n), the same numbers
        (compiled: :func:`~bwim.detect.fit_kernels.grid_atoms`, element by element the
        operations of :meth:`atoms`), from the rows' times less the axles' ``dt``
        (n_rows, n; or (2, n_rows, n): each detector's own); with ``slopes`` also the
        slopes (2, n_rows, n).  ``out``: where to write the atoms (2, n_rows, n)."""
        d = np.ascontiguousarray(dt, dtype=float)
        if d.ndim == 2:
            d = d[None]
        shape = (2, *d.shape[1:])
        o = out if out is not None and out.flags.c_contiguous else np.empty(shape)
        der = np.empty(shape if slopes else (0, 0, 0))
        g = self.table
        grid_atoms(g.scalars, g.first, g.values, float(v), d, o, der)
        if out is not None and o is not out:
            out[...] = o
            o = out
        return (o, der) if slopes else (o, None)

    def log_ratio(self, amps: np.ndarray) -> np.ndarray:
        """``ln(A_2 / (ratio A_1))`` per axle (±inf where one detector sees nothing)."""
        a1 = np.maximum(amps[:, 0], 0.0)
        a2 = np.maximum(amps[:, 1], 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log(a2 / (self.ratio * a1))
        return np.where(np.isnan(r), np.inf, r)

    def seen_by_both(self, amps: np.ndarray) -> np.ndarray:
        return np.abs(self.log_ratio(amps)) <= self.bound

    def log_ratios(self, amps: np.ndarray) -> list[float]:
        """:meth:`log_ratio`'s numbers as Python floats (for a few axles: one numpy call,
        the logarithm's, on an array of the same size).  ``max(A, 0)`` and ``ratio A_1``
        and the quotient are the same IEEE operations in Python; a quotient of 0 gives
        −inf, a zero divisor, a NaN or a negative quotient +inf (what the logarithm and
        :meth:`log_ratio`'s NaN → inf make of them); only the positive finite quotients
        are numpy's logarithms (at their places in the array: numpy's own routines)."""
        ratio = self.ratio
        out = []
        q = []
        for a1, a2 in amps.tolist():
            a1 = a1 if a1 != a1 or a1 > 0.0 else 0.0  # np.maximum(·, 0): NaN stays
            a2 = a2 if a2 != a2 or a2 > 0.0 else 0.0
            den = ratio * a1
            x = a2 / den if den != 0.0 else math.nan
            if x == 0.0:
                out.append(-math.inf)
            elif 0.0 < x < math.inf:
                out.append(None)  # a logarithm
                q.append(x)
                continue
            else:  # NaN, inf or negative: log gives inf or NaN, NaN counts inf
                out.append(math.inf)
            q.append(1.0)
        if None in out:
            logs = np.log(np.array(q)).tolist()
            out = [logs[i] if r is None else r for i, r in enumerate(out)]
        return out

    def seen(self, amps: np.ndarray) -> list[bool]:
        """:meth:`seen_by_both` as Python bools (:meth:`log_ratios`)."""
        bound = self.bound
        return [abs(r) <= bound for r in self.log_ratios(amps)]

    @cached_property
    def rows_source(self) -> tuple[np.ndarray, np.ndarray]:
        """The readings (2, n_t) and the rest's columns transposed (2, k, n_t), each C
        order: what :class:`Rows` copies a window's rows from."""
        y, rest = self.stacked
        return (np.ascontiguousarray(y[..., 0]),
                np.ascontiguousarray(rest.transpose(0, 2, 1)))


@dataclass(frozen=True, eq=False)
class VehicleFit:
    """A vehicle's fit on its window: times, speed, amplitudes (n, 2), misfit, each axle's
    removal cost (level variances)."""

    taus: np.ndarray
    v: float
    amps: np.ndarray
    chi: float
    gains: np.ndarray
    #: the least squares (with slopes) at these times and speed on the refinement's
    #: window (a later fit on the same window starts from it)
    solution: Solution | None = None


def make_problem(t: np.ndarray, y: np.ndarray, gauges: np.ndarray | None,
                 learned: LearnedResponses, v: float, *, fs: float | None = None,
                 bending: np.ndarray | None = None) -> Problem:
    """The :class:`Problem` of a record's times ``t``, detector channels ``y`` (n_t, 2)
    and ``gauges`` (n_t, n_gauges; None: high-pass) at the first speed estimate ``v``.
    ``fs`` (the sampling rate from the median step) and ``bending`` (n_t, 2: the gauges
    less their mean, combined with each response's weights) when already made."""
    if fs is None:
        fs = 1.0 / float(np.median(np.diff(t)))
    w = 1.0 / np.array([max(r.level, 1e-300) for r in learned.responses])
    spread = float(learned.amplitude_spread)
    bound = max(RATIO_SPREADS * spread, MIN_RATIO_BOUND)
    # a vehicle's fit samples every step-th reading: at least WINDOW_SAMPLES per response
    # width at half height (the response is smooth on that scale)
    width = min(r.fwhm for r in learned.responses) / v * fs
    step = max(1, int(width // WINDOW_SAMPLES))
    common = dict(t=t, w=w, ratio=float(learned.gain_ratio), bound=bound, spread=spread,
                  shift=(0.0, learned.distance), fs=fs, step=step)
    if learned.gauges and gauges is not None:
        if bending is None:
            g = gauges - gauges.mean(axis=0)
            bending = np.column_stack([g @ r.bending for r in learned.responses])
        tc = t - np.add.reduce(t) / t.size  # t.mean(): its sum / count
        tc = tc / max(float(tc.max() - tc.min()), 1e-300)  # np.ptp's numbers
        # per detector the columns (bending, 1, tc), weighted (np.column_stack's layout)
        stack = np.empty((2, t.size, 3))
        stack[:, :, 0] = bending.T
        stack[:, :, 1] = 1.0
        stack[:, :, 2] = tc
        stack *= w[:, None, None]
        grids = tuple(r.padded() for r in learned.responses)
        q = np.linalg.qr(stack)[0]  # both at once (each on its own: the same)
        return Problem(y=(y - np.add.reduce(y, axis=0) / y.shape[0]) * w,
                       rest=(stack[0], stack[1]),
                       q_rest=(q[0], q[1]), grids=grids, steps=_steps(grids), **common)
    y_hp = high_pass(y, HIGH_PASS / v * fs) * w
    empty = np.zeros((t.size, 0))
    grids = tuple(r.high_passed() for r in learned.responses)
    return Problem(y=y_hp, rest=(empty, empty), q_rest=(empty, empty), grids=grids,
                    steps=_steps(grids), **common)


def _steps(grids) -> tuple:
    """Per grid K's differences between ordinates, 0 after the last (np.diff and
    np.append's numbers, by slices)."""
    out = []
    for _, k, _ in grids:
        if k.size == 0:
            out.append(np.zeros(1))
            continue
        s = np.empty(k.size)
        np.subtract(k[1:], k[:-1], out=s[:-1])
        s[-1] = 0.0
        out.append(s)
    return tuple(out)


def relative(amps: np.ndarray) -> np.ndarray:
    """Amplitudes over each detector's largest, (n, 2)."""
    top = amps.max(axis=0) if amps.size else np.zeros(2)
    return amps / np.where(top > 0, top, 1.0)


def window(pb: Problem, taus: np.ndarray, v: float) -> np.ndarray:
    """Samples from REACH m of travel before the first axle reaches detector 1 to REACH m
    after the last leaves detector 2."""
    lo, hi = _bounds(pb, taus, v)
    return np.arange(lo, hi, pb.step)


def _bounds(pb: Problem, taus: np.ndarray, v: float) -> tuple[int, int]:
    """:func:`window`'s first sample and the end of its range (``np.arange(lo, hi,
    step)``); the axles' first and last time as Python floats (the same numbers as
    numpy's min and max, which a NaN makes NaN: left to numpy then)."""
    times = taus.tolist()
    first, last = min(times), max(times)
    if math.isnan(sum(times)):
        first, last = taus.min(), taus.max()
    t = pb.t
    return (int(t.searchsorted(first - REACH / v)),
            int(t.searchsorted(last + (pb.shift[1] + REACH) / v, side="right")))


class Rows:
    """What every fit on one vehicle's window reads: the sampled rows' times, readings
    (:attr:`y2`, 2 × n_rows) and rest columns transposed (:attr:`rest_t`, 2 × k ×
    n_rows), in C order as the compiled kernels read them, copied once per window;
    :attr:`y` (2, n_rows, 1) and :attr:`rest` (2, n_rows, k) are views of them."""

    def __init__(self, pb: Problem, rows: np.ndarray, index: slice | None = None):
        """``index``: a slice selecting the same rows (read through views rather than
        gathered by the index array: the same numbers, faster)."""
        y, rest_t = pb.rows_source
        at = rows if index is None else index
        self.rows = rows
        #: (first row, number of rows, step) when the rows are a window's (a slice),
        #: else None: two windows' rows are the same when these are
        self.key = None
        if index is not None and rows.size:
            self.key = (int(rows[0]), rows.size, pb.step)
        self.t = np.ascontiguousarray(pb.t[at])  # C order, as the compiled kernels read
        self.y2 = np.ascontiguousarray(y[:, at])
        self.rest_t = np.ascontiguousarray(rest_t[:, :, at])

    @property
    def y(self) -> np.ndarray:
        """The readings (2, n_rows, 1)."""
        return self.y2[..., None]

    @property
    def rest(self) -> np.ndarray:
        """The rest columns (2, n_rows, k)."""
        return self.rest_t.transpose(0, 2, 1)

    def same(self, other: Rows) -> bool:
        """Whether ``other`` holds the same rows (``np.array_equal`` of theirs)."""
        if self.key is not None and other.key is not None:
            return self.key == other.key
        return np.array_equal(self.rows, other.rows)


class Solution:
    """Both detectors' least-squares amplitudes and rest of the axles ``taus`` at speed
    ``v`` on a window's rows (see :func:`solve`), as one stack of two problems; the
    Jacobian on request.  Made by the compiled
    :func:`~bwim.detect.fit_kernels.least_squares`: ``Mt`` (2, n + k, n_rows) the
    design matrix transposed (the atoms, then the rest), ``dXt`` (2, n, n_rows) the
    atoms' slopes (None without), ``dtt`` (n, n_rows) the rows' times less each axle's,
    ``Ginv`` ``(MᵀM + ridge)⁻¹`` (the ridge of :func:`ridged_normal`; the pseudo-inverse
    where singular), ``a`` (2, n) the amplitudes, ``res`` the residual of both
    detectors end to end, :attr:`amps` and :attr:`gains`."""

    def __init__(self, pb: Problem, taus: np.ndarray, v: float, w: Rows, slopes: bool):
        taus = np.ascontiguousarray(taus, dtype=float)
        self._empty(pb, taus, v, w, slopes)
        g = pb.table
        least_squares(g.scalars, g.first, g.values, w.t, w.y2, w.rest_t, taus, float(v),
                      self.k, float(self.step), self.dtt, self.Mt,
                      self.dXt if slopes else np.empty((0, 0, 0)), self.Ginv, self.a,
                      self.res, self.amps, self.gains)

    def _empty(self, pb: Problem, taus: np.ndarray, v: float, w: Rows, slopes: bool):
        """Its times, speed, rows and arrays to be written."""
        n, r = taus.size, w.t.size
        p = n + w.rest_t.shape[1]
        self.taus, self.v, self.w, self.slopes = taus, v, w, slopes
        # every step-th sample: scaled to the misfit of all samples
        self.k, self.step = math.sqrt(pb.step), pb.step
        self.dtt, self.Mt = np.empty((n, r)), np.empty((2, p, r))
        self.dXt = np.empty((2, n, r)) if slopes else None
        self.Ginv, self.a, self.res = np.empty((2, p, p)), np.empty((2, n)), np.empty(2 * r)
        #: the axles' amplitudes (n, 2)
        self.amps = np.empty((n, 2))
        #: each axle's removal cost (level variances of all samples): removing regressor
        #: i raises the misfit by coef_i² / [(MᵀM)⁻¹]_ii (compiled with the least squares)
        self.gains = np.empty(n)

    def copy(self) -> Solution:
        """The same solution with arrays of its own (its times, speed and rows shared)."""
        out = Solution.__new__(Solution)
        out.__dict__.update(self.__dict__)
        out.dtt, out.Mt, out.dXt = self.dtt.copy(), self.Mt.copy(), (
            None if self.dXt is None else self.dXt.copy())
        out.Ginv, out.a, out.res = self.Ginv.copy(), self.a.copy(), self.res.copy()
        out.amps, out.gains = self.amps.copy(), self.gains.copy()
        return out

    @property
    def M(self) -> np.ndarray:
        """The design matrices (2, n_rows, n + k): the atoms, then the rest."""
        return self.Mt.transpose(0, 2, 1)

    @property
    def dX(self) -> np.ndarray | None:
        """The atoms' slopes (2, n_rows, n), None without."""
        return None if self.dXt is None else self.dXt.transpose(0, 2, 1)

    @property
    def dt(self) -> np.ndarray:
        """The rows' times less the axles' (n_rows, n)."""
        return self.dtt.T

    def jacobian(self) -> np.ndarray:
        """The variable-projection Jacobian (Kaufman) of the residual in (τ_1 … τ_n, v)
        (compiled: :func:`~bwim.detect.fit_kernels.jacobian`), (2 n_rows, n + 1)."""
        Jt = np.empty((self.taus.size + 1, self.res.size))
        jacobian(self.Mt, self.Ginv, self.a, self.dXt, self.dtt, float(self.v), self.k, Jt)
        return Jt.T.copy()


def solve(pb: Problem, taus: np.ndarray, v: float, rows: np.ndarray, slopes: bool):
    """Per detector the least-squares amplitudes and rest on ``rows`` (free in sign), the
    residual; with ``slopes`` the variable-projection Jacobian (Kaufman) of the residual
    with respect to (τ_1 … τ_n, v); each axle's removal cost.  Residual and costs are
    scaled by the window's sampling step (misfits of all samples)."""
    sol = Solution(pb, taus, v, rows if isinstance(rows, Rows) else Rows(pb, rows), slopes)
    return sol.res, (sol.jacobian() if slopes else None), sol.amps, sol.gains


def solution(pb: Problem, taus: np.ndarray, v: float, start: Solution | None = None
             ) -> Solution:
    """The least squares with slopes of the axles ``taus`` (ascending) at speed ``v`` on
    their window: ``start`` when it is that one (the same numbers, not made again); when
    ``start`` is on the same window, its rows are read again (not copied again)."""
    same, w = _start_or_rows(pb, taus, v, start)
    return same if same is not None else Solution(pb, taus, v, w, True)


def _start_or_rows(pb: Problem, taus: np.ndarray, v: float, start: Solution | None
                   ) -> tuple[Solution | None, Rows]:
    """``start`` if it is the least squares with slopes of ``taus`` at ``v`` on their
    window (else None), and that window's rows (``start``'s when the same)."""
    lo, hi = _bounds(pb, taus, v)
    step = pb.step
    size = len(range(lo, hi, step))
    if start is not None and start.w.key is not None and size and start.w.key == (
            lo, size, step):
        # the same times (np.array_equal: NaN differs, −0 equals 0) and speed
        if start.v == v and start.slopes and taus.shape == start.taus.shape and (
                taus.tolist() == start.taus.tolist()):
            return start, start.w
        return None, start.w
    rows = np.arange(lo, hi, step)
    if (start is not None and start.w.key is None and start.v == v
            and np.array_equal(start.taus, taus) and start.slopes
            and np.array_equal(start.w.rows, rows)):
        return start, start.w
    # the window is every step-th sample from its first: a slice selects the same rows
    return None, Rows(pb, rows, slice(lo, hi, step) if size else None)


def refine(pb: Problem, taus: np.ndarray, v: float, iterations: int = MAX_LM, *,
           start: Solution | None = None) -> VehicleFit:
    """The vehicle's axle times and speed by Levenberg–Marquardt on the variable
    projection (amplitudes and rest by least squares inside), on a fixed window: the
    whole loop compiled (:func:`~bwim.detect.fit_kernels.levenberg_marquardt`: A = JsᵀJs,
    trials of (A + λ diag(diag(A) + 1e-12)) x = Jsᵀr, λ ×10 on a rejected trial, /3 on
    an accepted one, the stops of the module contract), the least squares at the start
    too when not given.  ``start``: the :class:`Solution` with slopes at these times and
    speed on their window when already made (the same numbers, not made again), or one
    on the same window (its rows read again)."""
    taus = np.sort(np.asarray(taus, dtype=float))
    n = taus.size
    p = np.empty(n + 1)
    p[:n] = taus
    p[n] = v
    sol, w = _start_or_rows(pb, taus, v, start)
    if sol is not None:
        # the kernel starts from (copies of) sol's arrays and leaves the last accepted
        # trial's in them, with their amplitudes and removal costs
        last = sol.copy()
    else:  # the kernel makes the least squares at the start (least_squares' numbers)
        last = Solution.__new__(Solution)
        last._empty(pb, taus, v, w, True)
    g = pb.table
    before = p.tobytes()
    cost = levenberg_marquardt(g.scalars, g.first, g.values, w.t, w.y2, w.rest_t, p,
                               int(iterations), last.k, CONVERGED, float(last.step),
                               sol is None, last.dtt, last.Mt, last.dXt, last.Ginv, last.a,
                               last.res, last.amps, last.gains)
    if sol is not None and p.tobytes() == before:
        last = sol  # no trial accepted (an accepted one lowers the misfit: moves)
    else:
        last.taus, last.v = p[:-1].copy(), float(p[-1])
    return VehicleFit(taus=p[:-1], v=float(p[-1]), amps=last.amps, chi=cost,
                      gains=last.gains, solution=last)
