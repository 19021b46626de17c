"""``identify_forces``: axle force histories and static axle weights from a strain record.

Contract
--------
* Input: a bridge model (exact or calibrated), a :class:`~bwim.records.Record` with its
  sensors and the vehicle passage(s) (speed, lane, axle spacings, track width, delay).
* The forces are identified by first-order Tikhonov regularisation solved by dynamic
  programming (González, Rowley & OBrien 2008; docs/theory.md §4) on ``n_modes`` modes with the
  static correction of the truncated modes, λ by the L-curve (default), GCV, or given
  (physical units: strain m/m, force rate N/s for first order, force N for zeroth).
* The model order (``n_modes=None``) comes from the record: the modes up to the first
  frequency from which the readings' spectrum (Welch, channels normalised and averaged)
  stays within :data:`BAND_FACTOR` of its noise floor (the median over the top half of
  the band, fs/4 … fs/2), plus the next mode, at most :data:`DEFAULT_MAX_MODES` and
  below fs/4 (:func:`record_band`); the truncated modes enter through the static
  correction.  This holds with the L-curve λ (the default); with GCV or a given λ the
  order stays at :data:`DEFAULT_MAX_MODES` below fs/4, because GCV picks far too small a
  λ on low-order models of records with per-channel noise (``benchmarks/mfi_accuracy.py``
  compares the two rules).
* Unknowns are per wheel or per axle (``unknowns="auto"``: wheels when the strain sensors
  sit at two or more transverse positions on a plate and there are at least as many
  channels as wheels, else axles).  Axle force = sum of
  its wheels.  Static axle weight = mean identified axle force over the central
  ``central`` fraction (default 80 %) of the axle's time on the deck; GVW = their sum.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from bwim.errors import InputError, parse_enum
from bwim.fe.bridge import Bridge
from bwim.fe.modal import select_modes
from bwim.limits import check_memory
from bwim.mfi.dp import Solution, sweep
from bwim.mfi.lcurve import CoarseProblem, LCurve, gcv, lcurve_search
from bwim.mfi.statespace import ForceUnknowns, MFIModel, Order, build_model, force_layout
from bwim.plausibility import Limits, ordered_flags, quality_of, weight_flags
from bwim.records import Passage, Record
from bwim.summary import SummaryRow

__all__ = ["BAND_FACTOR", "COARSE_RATE", "DEFAULT_MAX_MODES", "MAX_RESIDUAL",
           "SMALL_MODEL_MODES", "ForceIdentification", "identify_forces", "record_band"]

#: Relative residual of the identified forces' readings above which a vehicle's weights
#: are ``residual_high``: MFI reproduces a crossing of the model's own bridge to the noise
#: level (a few per cent); a wrong model, passage or channel leaves far more.
MAX_RESIDUAL = 0.3

#: Default cap on the number of modes (with the static correction more add little).
DEFAULT_MAX_MODES = 20

#: A frequency bin of the record stands out of the noise when its power exceeds this
#: multiple of the noise floor (Welch averaging over segments and channels keeps a pure
#: noise bin within about ±30 % of the floor).
BAND_FACTOR = 2.0

#: Welch segment length (samples) of :func:`record_band`: about 8 Hz bins at 1 kHz.
BAND_SEGMENT = 128

#: Models with at most this many modes solve the L-curve's fine grid over twice the
#: window (two coarse spacings either side, the same spacing): their λ cost little
#: beside one pass of the recursion, and a wider window spares extending it.
SMALL_MODEL_MODES = 4

#: The L-curve's bracketing pass runs on every m-th sample, at least this rate (Hz),
#: when that divides the sampling rate by two or more (:func:`_coarse_problem`).
COARSE_RATE = 250.0


@dataclass(frozen=True, kw_only=True, eq=False)
class ForceIdentification:
    """Identified moving forces.

    Attributes
    ----------
    time : ndarray (n_t,)
    wheel_forces : ndarray (n_t, n_wheels)
        N, in the wheel order of the passages (axle unknowns are shared equally by the
        axle's wheels).
    axle_forces : ndarray (n_t, n_axles)
        N; all vehicles' axles in passage order.
    axle_weights : ndarray (n_axles,)
        Static axle weights, N.
    gvw : ndarray (n_vehicles,)
        Gross vehicle weights, N.
    lam, lam_scaled : float
        The λ used (physical and scaled units).
    lcurve : LCurve or None
    fitted : ndarray (n_t, n_sensors)
        Readings reproduced by the identified forces.
    passages : tuple of Passage
    axle_windows : ndarray (n_axles, 2)
        Time window used for each static weight, s.
    unknowns : ForceUnknowns
    order : Order
    residual : float
        Relative residual ‖fitted − measured‖ / ‖measured‖ over all samples and sensors
        (NaN when unknown, e.g. read from an older file).
    n_modes : int
        Modes in the state-space model (0 when unknown, e.g. read from a file).
    """

    time: np.ndarray
    wheel_forces: np.ndarray
    axle_forces: np.ndarray
    axle_weights: np.ndarray
    gvw: np.ndarray
    lam: float
    lam_scaled: float
    lcurve: LCurve | None
    fitted: np.ndarray
    passages: tuple[Passage, ...]
    axle_windows: np.ndarray
    unknowns: ForceUnknowns
    order: Order
    residual: float = float("nan")
    n_modes: int = 0
    residual_limit: float = MAX_RESIDUAL

    @property
    def vehicle_flags(self) -> tuple[tuple[str, ...], ...]:
        """Plausibility flags of each vehicle's weights (:mod:`bwim.plausibility`):
        implausible axle weights or GVW; ``negative_force`` (an axle pushing up by more
        than 10 % of its weight, or 1 kN, while weighed); ``residual_high`` (the forces
        reproduce the readings worse than ``residual_limit``, by default
        :data:`MAX_RESIDUAL`)."""
        out, a0 = [], 0
        t = self.time
        for p in self.passages:
            axles = range(a0, a0 + p.n_axles)
            a0 += p.n_axles
            w = self.axle_weights[list(axles)]
            flags = weight_flags(w, w, Limits())
            for a in axles:
                inside = (t >= self.axle_windows[a, 0]) & (t <= self.axle_windows[a, 1])
                floor = -max(0.1 * abs(self.axle_weights[a]), 1e3)
                if inside.any() and self.axle_forces[inside, a].min() < floor:
                    flags.append("negative_force")
                    break
            if not self.residual <= self.residual_limit and np.isfinite(self.residual):
                flags.append("residual_high")
            out.append(ordered_flags(flags))
        return tuple(out)

    @property
    def vehicle_quality(self) -> tuple[str, ...]:
        """``"reject"``, ``"warning"`` or ``"ok"`` per vehicle (see :attr:`vehicle_flags`)."""
        return tuple(quality_of(f) for f in self.vehicle_flags)

    def to_summary_rows(self, record: str) -> tuple[SummaryRow, ...]:
        """One :class:`~bwim.summary.SummaryRow` per vehicle, named ``record``: a vehicle
        whose weights fail the plausibility checks is refused, with its flags and no
        weights."""
        from bwim.classify import axle_configuration

        rows, a0 = [], 0
        for v, (p, flags, quality) in enumerate(zip(self.passages, self.vehicle_flags,
                                                    self.vehicle_quality, strict=True)):
            weights = self.axle_weights[a0:a0 + p.n_axles]
            a0 += p.n_axles
            ok = quality != "reject"
            rows.append(SummaryRow(
                record=record, vehicle=v + 1, status="weighed" if ok else "refused",
                n_axles=p.n_axles, speed=p.speed, axle_spacings=tuple(p.axle_spacings),
                vehicle_class=axle_configuration(p.axle_spacings),
                axle_weights=tuple(weights) if ok else (),
                gvw=float(self.gvw[v]) if ok else None, flags=flags, residual=self.residual,
                quality=quality, method="mfi", lam=self.lam,
                reason="" if ok else f"implausible weights ({', '.join(flags)})"))
        return tuple(rows)

    def plot(self, truth=None, ax=None, **kw):
        """Forces against the truth if known (see :func:`bwim.plots.mfi.plot_forces`;
        ``kw``: by, label); returns the figure."""
        from bwim.plots.mfi import plot_forces

        return plot_forces(self, truth=truth, ax=ax, **kw)


def _auto_unknowns(bridge: Bridge, record: Record) -> ForceUnknowns:
    if not bridge.is_plate or all(p.track_width is None for p in record.passages):
        return ForceUnknowns.AXLE
    ys = {round(s.y, 6) for s in record.sensors if s.kind.is_strain and s.y is not None}
    wheels = sum(p.n_axles * p.wheels_per_axle for p in record.passages)
    # wheels need transverse information and at least one channel per wheel force
    return (ForceUnknowns.WHEEL if len(ys) >= 2 and len(record.sensors) >= wheels
            else ForceUnknowns.AXLE)


def identify_forces(
    bridge: Bridge,
    record: Record,
    *,
    n_modes: int | None = None,
    lam: float | str = "lcurve",
    order: Order | str = Order.FIRST,
    unknowns: ForceUnknowns | str = ForceUnknowns.AUTO,
    weights: np.ndarray | None = None,
    static_correction: bool = True,
    lam_range: tuple[float, float] = (1e-6, 1e3),
    n_lam: int = 16,
    central: float = 0.8,
    max_residual: float = MAX_RESIDUAL,
) -> ForceIdentification:
    """Identify the moving forces of a record (see module docstring).

    Parameters
    ----------
    bridge : Bridge
        The bridge model (its modes, damping and sensor rows are used).
    record : Record
        Strain (and/or deflection) readings with sensors and passage(s).
    n_modes : int, optional
        Modes in the state-space model (default with the L-curve: chosen from the record,
        the modes up to the frequency where its spectrum meets the noise floor plus one,
        at most 20 and below sampling_rate / 4 (:func:`record_band`); otherwise up to 20
        below sampling_rate / 4; the truncated ones enter through the static correction).
    lam : "lcurve", "gcv" or float
        Regularisation: the L-curve's corner, GCV, or a value in physical units.
    order : "first" or "zeroth"
    unknowns : "auto", "wheel" or "axle"
    weights : array (n_sensors,), optional
        Sensor weights W (default: all 1 on the common strain scale).
    static_correction : bool
        Include the truncated modes' static response in the readings model.
    lam_range, n_lam
        Scaled λ range of the L-curve (and the GCV search interval), and the number of λ
        of the L-curve search (:func:`bwim.mfi.lcurve.lcurve_search`): half on a coarse
        log grid over the range (on every m-th sample, about :data:`COARSE_RATE`, when
        the record is sampled at least twice as fast), half within one coarse spacing of
        its corner on the record's model (more when the corner sits at an end of that
        grid, and twice as many over twice the width for models of at most
        :data:`SMALL_MODEL_MODES` modes).  Larger first-order models solve every other
        fine λ first and keep that answer when the static weights of all of them agree
        within :data:`bwim.mfi.lcurve.FLAT_TOL` (:func:`bwim.mfi.lcurve.lcurve_search`).
    central : float
        Fraction of each axle's time on the deck used for its static weight.
    max_residual : float
        Relative residual above which the weights are flagged ``residual_high`` (a
        caller that knows the readings' noise and its model's error sets it from them).
    """
    _check_arguments(bridge, record, n_modes, lam, weights, lam_range, n_lam, central)
    if not isinstance(max_residual, (int, float)) or not max_residual > 0:
        raise InputError(f"max_residual must be a positive fraction, got {max_residual!r}")
    max_residual = float(max_residual)
    if not record.passages:
        raise InputError("the record has no passage: speed, lane and axle layout are needed "
                         "to place the forces")
    if not np.all(np.isfinite(record.data)):
        raise InputError("the record contains NaN or infinite samples")
    order = parse_enum(Order, order, "order")
    unknowns = parse_enum(ForceUnknowns, unknowns, "unknowns")
    if unknowns is ForceUnknowns.AUTO:
        unknowns = _auto_unknowns(bridge, record)
    if not 0.0 < central <= 1.0:
        raise InputError(f"central must lie in (0, 1], got {central!r}")
    fs = record.sampling_rate
    if n_modes is None:
        below = select_modes(bridge, max_frequency=fs / 4, sampling_rate=fs)
        n = min(DEFAULT_MAX_MODES, below.n)
        if isinstance(lam, str) and lam == "lcurve":  # see the module docstring
            band = record_band(record)
            n = min(n, int(np.searchsorted(below.frequencies, band, side="right")) + 1)
        modes = bridge.modes(max(n, 1))
    else:
        modes = select_modes(bridge, n_modes=n_modes, sampling_rate=fs)
    d = record.data
    d_scale = float(np.abs(d).max())
    if d_scale == 0.0:
        raise InputError("the record is all zeros")
    passage_of, axle_of, _ = force_layout(record.passages, unknowns)
    n_f = axle_of.size
    # each force's axle in the record's axle order (passage after passage)
    axles = np.cumsum([0, *(p.n_axles for p in record.passages)])[passage_of] + axle_of
    if record.data.shape[1] < n_f and unknowns is ForceUnknowns.WHEEL:
        raise InputError(
            f"{record.data.shape[1]} sensor channels cannot identify {n_f} wheel forces; "
            "use unknowns='axle' or more sensors"
        )
    model = build_model(bridge, modes, record, d_scale, unknowns=unknowns, order=order,
                        static_correction=static_correction)
    w = None if weights is None else np.asarray(weights, dtype=float)
    d_scaled = d / d_scale
    W = np.ones(model.n_s) if w is None else w
    curve = None
    windows = _central_windows(record.passages, bridge.length, central)
    sol = None
    if isinstance(lam, str):
        if lam == "lcurve":
            n_coarse = max(4, n_lam // 2)
            # first order only: its λ → ∞ limit is constant forces (the static weights),
            # zeroth order's is zero force, which no sign test can tell from a good answer
            weighed = _weighed(record.time, windows, axles) if order is Order.FIRST else None
            coarse = _coarse_problem(bridge, record, modes, d_scale, W, weighed,
                                     unknowns=unknowns, order=order,
                                     static_correction=static_correction)
            n_fine = max(n_lam - n_coarse, 0)
            # a small model's λ cost little beside a pass: twice the window, same spacing
            window = 2 if modes.n <= SMALL_MODEL_MODES and coarse is not None else 1
            search = lcurve_search(model, d_scaled, W, lam_range, n_coarse=n_coarse,
                                   n_fine=window * n_fine + window - 1,
                                   admissible=_compressive(weighed),
                                   coarse=coarse if n_fine >= 4 else None, window=window,
                                   weigh=(_static(weighed, axles, windows.shape[0])
                                          if window == 1 and weighed is not None else None))
            curve, sol = search.curve, search.solution
            lam_s = curve.corner_scaled
        elif lam == "gcv":
            lam_s = gcv(model, d_scaled, W, lam_range)
        else:
            raise InputError(f"unknown lam {lam!r}; expected 'lcurve', 'gcv' or a number")
    else:
        if not np.isfinite(lam) or lam <= 0:
            raise InputError(f"lam must be positive, got {lam!r}")
        lam_s = model.lam_scaled(float(lam))
    if sol is None:
        best = sweep(model, d_scaled, [lam_s], W, keep=True)
        sol = Solution(X=np.ascontiguousarray(best.X[0]), r=np.ascontiguousarray(best.r[0]),
                       residual_norm=float(best.residual_norm[0]),
                       seminorm=float(best.seminorm[0]))
    ident = _result(model, sol, record, unknowns, order, lam_s, curve, windows)
    return replace(ident, n_modes=modes.n, residual_limit=max_residual)


def _weighed(time: np.ndarray, windows: np.ndarray, axles: np.ndarray) -> np.ndarray:
    """Whether each force's axle is weighed at each time, shape (n_t, n_f)."""
    return np.stack([(time >= windows[a, 0]) & (time <= windows[a, 1]) for a in axles],
                    axis=1)


def _compressive(weighed: np.ndarray | None):
    """The L-curve's admissibility test: per λ, every force positive where its axle is
    weighed (``forces``: scaled, (n_λ, n_t, n_f)); None without ``weighed``."""
    if weighed is None:
        return None

    def admissible(forces: np.ndarray) -> np.ndarray:
        return np.all((forces > 0) | ~weighed[None], axis=(1, 2))

    return admissible


def _static(weighed: np.ndarray, axles: np.ndarray, n_axles: int):
    """Static axle weights per λ from scaled forces (n_λ, n_t, n_f): each axle's forces
    summed, averaged where it is weighed (``weighed``, (n_t, n_f), as :func:`_weighed`)."""
    count = weighed.sum(axis=0)

    def weigh(forces: np.ndarray) -> np.ndarray:
        mean = np.einsum("ltf,tf->lf", forces, weighed) / np.maximum(count, 1)
        out = np.zeros((forces.shape[0], n_axles))
        np.add.at(out, (slice(None), axles), mean)
        return out

    return weigh


def _coarse_problem(bridge: Bridge, record: Record, modes, d_scale: float, W: np.ndarray,
                    weighed: np.ndarray | None, **build) -> CoarseProblem | None:
    """Every ``m``-th sample of the record, ``m`` the largest integer with ``fs / m`` ≥
    :data:`COARSE_RATE`, on the modes below a quarter of that rate (at most those of the
    record's model), for the L-curve's bracketing pass; None when ``m < 2``.  The samples
    are taken as they are (no anti-alias filter): the gauge noise keeps its level per
    sample, which is what places the corner."""
    fs = record.sampling_rate
    m = int(np.floor(fs / COARSE_RATE * (1 + 1e-9)))
    if m < 2 or record.time.size < 64 * m:
        return None
    below = int(np.searchsorted(modes.frequencies, fs / m / 4, side="right"))
    data = record.data[::m]
    rec = Record(time=record.time[::m], data=data, sensors=record.sensors,
                 passages=record.passages)
    model = build_model(bridge, bridge.modes(max(below, 1)), rec, d_scale, **build)
    return CoarseProblem(model=model, d=data / d_scale, weights=W,
                         admissible=_compressive(None if weighed is None else weighed[::m]))


def _central_windows(passages, length: float, central: float) -> np.ndarray:
    """(first, last) time of every axle's central ``central`` fraction on the deck, s,
    shape (n_axles, 2): where its static weight is averaged."""
    windows = np.concatenate([p.axle_times_on(length) for p in passages])
    cut = 0.5 * (1.0 - central) * (windows[:, 1] - windows[:, 0])
    return np.stack([windows[:, 0] + cut, windows[:, 1] - cut], axis=1)


def record_band(record: Record) -> float:
    """The frequency (Hz) from which the readings' spectrum stays within
    :data:`BAND_FACTOR` of its noise floor up to fs/4 (the bin after the last one that
    stands out): the readings carry no information on the bridge's response above it.

    Welch periodograms (segments of :data:`BAND_SEGMENT` samples, linear detrend) of each
    channel scaled by its peak, averaged over channels; the floor is their median over
    fs/4 … fs/2 (white noise is flat, the response has decayed there).  A record whose
    spectrum never meets the floor below fs/4 (clean, or too short to tell) gives
    ``inf``: no cut.  One in which no bin stands out (the detrended response is below the
    noise at every frequency: only its quasi-static part is informative) gives the first
    bin above 0 Hz, the lowest cut.
    """
    from scipy import signal

    d = np.asarray(record.data, dtype=float)
    peak = np.abs(d).max(axis=0)
    d = d[:, peak > 0] / peak[peak > 0]
    fs = record.sampling_rate
    if d.shape[0] < 2 * BAND_SEGMENT or d.shape[1] == 0:
        return float("inf")
    f, P = signal.welch(d, fs=fs, nperseg=BAND_SEGMENT, axis=0, detrend="linear")
    P = P.mean(axis=1)
    floor = float(np.median(P[f >= fs / 4]))
    below = f < fs / 4
    loud = np.flatnonzero((P > BAND_FACTOR * floor) & below)
    if floor <= 0 or (loud.size and loud[-1] + 1 >= np.count_nonzero(below)):
        return float("inf")
    return float(f[loud[-1] + 1] if loud.size else f[1])


def _check_arguments(bridge, record, n_modes, lam, weights, lam_range, n_lam, central):
    """identify_forces' argument checks (InputError naming the argument) and its memory
    estimate: the Riccati gains of every step, n_t × (state size)² doubles."""
    if not isinstance(bridge, Bridge):
        raise InputError(f"bridge must be a bwim.Bridge, got {type(bridge).__name__}")
    if not isinstance(record, Record):
        raise InputError(f"record must be a bwim.Record, got {type(record).__name__}")
    if n_modes is not None and (isinstance(n_modes, bool)
                                or not isinstance(n_modes, (int, np.integer)) or n_modes < 1):
        raise InputError(f"n_modes must be a positive integer, got {n_modes!r}")
    if lam is None or isinstance(lam, bool) or not isinstance(lam, (str, int, float,
                                                                     np.number)):
        raise InputError(f"lam must be 'lcurve', 'gcv' or a positive number, got {lam!r}")
    if isinstance(lam, str) and lam not in ("lcurve", "gcv"):
        raise InputError(f"unknown lam {lam!r}; expected 'lcurve', 'gcv' or a number")
    if isinstance(n_lam, bool) or not isinstance(n_lam, (int, np.integer)) or n_lam < 2:
        raise InputError(f"n_lam must be an integer >= 2 (points of the L-curve), got "
                         f"{n_lam!r}")
    try:
        lo, hi = (float(v) for v in lam_range)
    except (TypeError, ValueError):
        raise InputError(f"lam_range must be (low, high), got {lam_range!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo < hi):
        raise InputError(f"lam_range must be (low, high) with 0 < low < high, got "
                         f"{lam_range!r}")
    if isinstance(central, bool) or not isinstance(central, (int, float, np.number)):
        raise InputError(f"central must be a number in (0, 1], got {central!r}")
    if weights is not None:
        try:
            w = np.asarray(weights, dtype=float)
        except (TypeError, ValueError):
            raise InputError("weights must be an array of numbers, one per sensor") from None
        n_s = len(record.sensors)
        if w.shape != (n_s,):
            raise InputError(f"weights must have one value per sensor ({n_s}), got shape "
                             f"{w.shape}")
        if not np.all(np.isfinite(w)) or np.any(w < 0) or not np.any(w > 0):
            raise InputError("weights must be finite, >= 0 and not all zero")
    n_f = 2 * sum(p.n_axles for p in record.passages)
    n_x = 2 * (DEFAULT_MAX_MODES if n_modes is None else int(n_modes)) + n_f
    n_s = len(record.sensors)
    n_t = float(record.time.size)
    if isinstance(lam, str) and lam == "gcv":  # GCV keeps the Riccati gains of every step
        need = n_t * n_x * n_x * 8.0 * 3
    else:  # the model arrays, and the stacked sweep of one λ with its trajectory kept
        need = 8.0 * n_t * (3 * n_x * n_f + 2 * n_s * n_f + 8 * (n_x + n_s)
                            + (n_x + 1) * (2 * n_f + 3) + n_x * n_f + 2 * n_s + 4 * n_f)
        if isinstance(lam, str):  # the L-curve keeps the fine λ's trajectories (and joins them)
            need += 8.0 * n_t * (n_x + 2 * n_f) * 2 * (n_lam + 1)
    check_memory(need, f"identifying the forces of a record of {record.time.size} samples")


def _result(model: MFIModel, sol: Solution, record: Record, unknowns, order, lam_s, curve,
            windows: np.ndarray) -> ForceIdentification:
    forces = sol.forces * model.f_scale  # (n_t, n_f)
    passages = record.passages
    wheel_cols = [p.wheels_per_axle * p.n_axles for p in passages]
    axle_cols = [p.n_axles for p in passages]
    n_t = forces.shape[0]
    wheels = np.zeros((n_t, sum(wheel_cols)))
    axles = np.zeros((n_t, sum(axle_cols)))
    f = w0 = a0 = 0
    for p in passages:
        n_w = p.wheels_per_axle
        for a in range(p.n_axles):
            if unknowns is ForceUnknowns.WHEEL:
                wheels[:, w0 + a * n_w: w0 + (a + 1) * n_w] = forces[:, f: f + n_w]
                axles[:, a0 + a] = forces[:, f: f + n_w].sum(axis=1)
                f += n_w
            else:
                wheels[:, w0 + a * n_w: w0 + (a + 1) * n_w] = forces[:, [f]] / n_w
                axles[:, a0 + a] = forces[:, f]
                f += 1
        w0 += n_w * p.n_axles
        a0 += p.n_axles
    t = record.time
    weights = np.empty(axles.shape[1])
    for a in range(axles.shape[1]):
        inside = (t >= windows[a, 0]) & (t <= windows[a, 1])
        if not inside.any():
            raise InputError(f"axle {a} is not on the bridge during the record")
        weights[a] = axles[inside, a].mean()
    gvw = np.array([weights[s:s + n].sum() for s, n in zip(np.cumsum([0, *axle_cols[:-1]]),
                                                             axle_cols, strict=True)])
    nz = model.n_z
    fitted = (sol.X[:, :nz] @ model.Qz.T + np.einsum("ksf,kf->ks", model.D, sol.X[:, nz:])
              ) * model.d_scale
    measured = record.data
    den = float(np.linalg.norm(measured))
    residual = float(np.linalg.norm(fitted - measured)) / den if den > 0 else float("nan")
    return ForceIdentification(
        time=t.copy(), wheel_forces=wheels, axle_forces=axles, axle_weights=weights, gvw=gvw,
        lam=model.lam_physical(lam_s), lam_scaled=lam_s, lcurve=curve, fitted=fitted,
        passages=tuple(passages), axle_windows=windows, unknowns=unknowns, order=order,
        residual=residual,
    )
