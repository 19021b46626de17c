"""Influence lines for static Bridge WIM: calibrated from a known truck, or from the FE model.

Contract
--------
* An :class:`InfluenceLine` is the static reading of one or more *channels* per newton of
  a unit **axle** load at position ``x`` in one lane: ordinates at uniformly spaced
  positions, interpolated linearly between them and zero outside ``[x[0], x[-1]]`` (the
  end ordinates are zero: the line is continuous).  A :class:`Channel` is one sensor or
  the **sum** of several (standard B-WIM practice sums the longitudinal gauges of one
  section, which makes the line almost independent of the vehicle's transverse position).
* :func:`calibrate_influence_line` is the matrix method of OBrien, Quilligan & Karoumi
  (2006): with the static axle loads ``W_i`` of a calibration truck and each record's
  :class:`~bwim.records.Passage`, the reading at sample ``k`` is
  ``ε(t_k) = Σ_i W_i I(v (t_k − delay) − a_i)``, linear in the ordinates of ``I``; the
  ordinates follow in least squares over every sample of every record, with a light
  second-difference (Tikhonov) penalty.  It is linear: exact data from a piecewise-linear
  line on the same grid give that line back.
* :func:`model_influence_line` is the FE model's static influence line for the same
  channels, lane and track width, from the influence surfaces (docs/theory.md §1.5): a unit axle is
  half a newton at each wheel, ``y = lane ∓ track_width / 2`` (one newton on the lane
  centre line for ``track_width=None`` and on 1-D bridges).

Units: positions in m, ordinates in reading per newton (strain/N or m/N).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from bwim.errors import (
    InputError,
    NumericalError,
    require_axis,
    require_columns,
    require_finite,
    require_instance,
    require_positive,
)
from bwim.limits import check_memory
from bwim.records import Passage, Record, record_list
from bwim.sensors import Sensor, SensorKind

if TYPE_CHECKING:
    from bwim.fe.bridge import Bridge
    from bwim.vehicles import Vehicle

__all__ = [
    "DEFAULT_SMOOTHING",
    "Channel",
    "InfluenceLine",
    "calibrate_influence_line",
    "hat_design",
    "model_influence_line",
    "resolve_channels",
    "smoothing_penalty",
    "static_axle_loads",
]

#: Default smoothing length of the matrix method, m (see :func:`calibrate_influence_line`).
DEFAULT_SMOOTHING = 0.1


@dataclass(frozen=True, kw_only=True)
class Channel:
    """One reading used for weighing: a sensor, or the sum of several sensors.

    Attributes
    ----------
    name : str
        The sensor's name, or the summed sensors' names joined by ``+``.
    sensors : tuple of Sensor
        The sensors whose readings are added (one for a single sensor).
    """

    name: str
    sensors: tuple[Sensor, ...]

    @property
    def kind(self) -> SensorKind:
        """The kind of the channel's sensors (all the same)."""
        return self.sensors[0].kind

    @classmethod
    def of(cls, sensors: Sequence[Sensor]) -> Channel:
        """The channel of one sensor, or of the sum of several of the same kind."""
        sensors = tuple(sensors)
        if not sensors:
            raise InputError("a channel needs at least one sensor")
        kinds = {s.kind for s in sensors}
        if len(kinds) > 1:
            raise InputError(
                "a summed channel must add sensors of one kind, got "
                f"{sorted(k.value for k in kinds)} in {[s.name for s in sensors]}"
            )
        names = [s.name for s in sensors]
        if len(set(names)) != len(names):
            raise InputError(f"a summed channel lists a sensor twice: {names}")
        return cls(name="+".join(names), sensors=sensors)

    def read(self, record: Record) -> np.ndarray:
        """The channel's readings in ``record`` (summed), shape (n_t,)."""
        return record.channels([s.name for s in self.sensors]).data.sum(axis=1)


def read_channels(record: Record, channels: Sequence[Channel]) -> np.ndarray:
    """Readings of several channels, shape (n_t, n_channels)."""
    column = {s.name: i for i, s in enumerate(record.sensors)}
    if any(s.name not in column for c in channels for s in c.sensors):
        return np.stack([c.read(record) for c in channels], axis=1)  # names the missing one
    if all(len(c.sensors) == 1 for c in channels):  # one sensor each: its column as it is
        return record.data[:, [column[c.sensors[0].name] for c in channels]]
    return np.stack([record.data[:, [column[s.name] for s in c.sensors]].sum(axis=1)
                     for c in channels], axis=1)


@dataclass(frozen=True, kw_only=True, eq=False)
class InfluenceLine:
    """Static influence line(s) of a unit axle load in one lane.

    Attributes
    ----------
    x : ndarray, shape (n_x,)
        Ordinate positions of the (first) axle, m, uniformly spaced, ascending.
    ordinates : ndarray, shape (n_x, n_channels)
        Reading per newton of axle load at each position; zero at both ends.
    channels : tuple of Channel
        What each column reads.
    lane : float
        Transverse position of the vehicle centre line it applies to, m.
    track_width : float or None
        Wheel track of the unit axle, m (None: one force on the centre line).
    source : str
        ``"matrix method"`` (calibrated) or ``"FE model"``.
    residual : float or None
        Calibrated lines: relative residual ‖G I − ε‖ / ‖ε‖ of the least-squares fit.
    """

    x: np.ndarray
    ordinates: np.ndarray
    channels: tuple[Channel, ...]
    lane: float
    track_width: float | None = None
    source: str = ""
    residual: float | None = None

    def __repr__(self) -> str:
        res = "" if self.residual is None else f", residual {self.residual:.3g}"
        return (f"InfluenceLine({len(self.channels)} channels × {self.x.size} ordinates, "
                f"x {self.x[0]:.2f}–{self.x[-1]:.2f} m, lane {self.lane:g} m"
                f"{', ' + self.source if self.source else ''}{res})")

    def __post_init__(self) -> None:
        x = require_axis("influence line x", self.x, "positions")
        channels = tuple(self.channels)
        ords = require_columns("ordinates", self.ordinates, (x.size, len(channels)),
                               "(n_x, n_channels)")
        if not np.all(np.isfinite(ords)):
            raise InputError("influence line ordinates must be finite")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "ordinates", ords)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "lane", require_finite("lane", self.lane))

    @property
    def support(self) -> tuple[float, float]:
        """First and last ordinate position, m: the line is zero outside."""
        return float(self.x[0]), float(self.x[-1])

    @property
    def spacing(self) -> float:
        """Distance between ordinates, m."""
        return float(self.x[1] - self.x[0])

    @property
    def channel_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.channels)

    def at(self, x: np.ndarray) -> np.ndarray:
        """Ordinates at positions ``x`` (any shape), linear between ordinates, zero outside
        the support; shape ``x.shape + (n_channels,)``."""
        xa = np.asarray(x, dtype=float)
        flat = xa.ravel()
        out = np.stack(
            [np.interp(flat, self.x, col, left=0.0, right=0.0) for col in self.ordinates.T],
            axis=-1,
        )
        return out.reshape(*xa.shape, len(self.channels))

    def plot(self, ax=None, **kw):
        """Each channel's line per kN against position, with a ``reference`` line if given
        (:func:`bwim.plots.wim.plot_influence_line`); returns the figure."""
        from bwim.plots.wim import plot_influence_line

        return plot_influence_line(self, ax=ax, **kw)

    def response(self, passage: Passage, axle_loads: np.ndarray, time: np.ndarray) -> np.ndarray:
        """Static readings of a vehicle of ``axle_loads`` (N) on ``passage`` at ``time``,
        shape (n_t, n_channels): ``Σ_i A_i I(v (t − delay) − a_i)``."""
        loads = np.asarray(axle_loads, dtype=float)
        if loads.shape != (passage.n_axles,):
            raise InputError(
                f"axle_loads needs one value per axle ({passage.n_axles}), got shape "
                f"{loads.shape}")
        return np.einsum("kic,i->kc", self.at(passage.axle_x(time)), loads)


# --- channels ---------------------------------------------------------------------------

def resolve_channels(
    sensors: Sequence[Sensor], spec: Any = "sum", *, section_x: float | None = None
) -> tuple[Channel, ...]:
    """The channels a specification selects among ``sensors``.

    Parameters
    ----------
    sensors : sequence of Sensor
        The available sensors (a record's).
    spec : "sum", "each", None or sequence
        ``"sum"``: one channel, the sum of the longitudinal strain gauges (``strain_x``) of
        the section nearest ``section_x`` (ties: the section with more gauges; gauges
        that all lack ``x`` are taken as one section);
        ``"each"`` or None: every sensor on its own; a sequence: one channel per item, an
        item being a sensor (or its name) or a list/tuple of sensors (or names) to sum.
    section_x : float, optional
        Where the ``"sum"`` section is looked for, m (default: the middle of the
        instrumented sections).
    """
    sensors = tuple(sensors)
    by_name = {s.name: s for s in sensors}

    def lookup(item: Any) -> Sensor:
        key = item.name if isinstance(item, Sensor) else item
        if not isinstance(key, str) or key not in by_name:
            raise InputError(f"no sensor {key!r} among the channels {list(by_name)}")
        return by_name[key]

    if isinstance(spec, str) or spec is None:
        if spec is None or spec == "each":
            if not sensors:
                raise InputError("there are no sensors to read")
            return tuple(Channel.of([s]) for s in sensors)
        if spec != "sum":
            raise InputError(
                f"unknown channels {spec!r}; expected 'sum', 'each', None or a sequence of "
                "sensors (a list or tuple inside it is summed)")
        gauges = [s for s in sensors if s.kind is SensorKind.STRAIN_X]
        if not gauges:
            raise InputError(
                "channels='sum' adds the longitudinal strain gauges (strain_x) of one "
                f"section, but there are none among {list(by_name)}; name the channels")
        unplaced = [s.name for s in gauges if s.x is None]
        if unplaced:
            if len(unplaced) < len(gauges):
                raise InputError(
                    f"channels='sum' cannot tell the section of gauge {unplaced[0]!r} (no "
                    "x) among gauges with positions; name the channels")
            return (Channel.of(gauges),)   # no positions: all gauges are one section
        sections = sorted({round(s.x, 6) for s in gauges})
        target = 0.5 * (sections[0] + sections[-1]) if section_x is None else section_x
        counts = {xs: sum(round(s.x, 6) == xs for s in gauges) for xs in sections}
        best = min(sections, key=lambda xs: (abs(xs - target), -counts[xs], xs))
        return (Channel.of([s for s in gauges if round(s.x, 6) == best]),)
    if not isinstance(spec, (list, tuple)) or not spec:
        raise InputError(f"channels must be 'sum', 'each', None or a non-empty sequence, "
                         f"got {spec!r}")
    out = []
    for item in spec:
        if isinstance(item, (list, tuple)):
            out.append(Channel.of([lookup(s) for s in item]))
        else:
            out.append(Channel.of([lookup(item)]))
    return tuple(out)


# --- the matrix method ------------------------------------------------------------------

def hat_design(positions: np.ndarray, loads: np.ndarray, x0: float, h: float,
               n: int) -> sp.csr_matrix:
    """The matrix method's design matrix: ``G[k, j-1] = Σ_i W_i φ_j(p_ki)`` for the
    interior hat functions j = 1 … n−1 on the nodes ``x0 + j h`` (the end ordinates are
    zero), shape (n_t, n − 1), sparse (at most two entries per axle and row).

    ``positions`` (n_t, n_axles) are axle positions, m; ``loads`` (n_axles,) their loads.
    ``G @ ordinates[1:-1]`` is the static reading ``Σ_i W_i I(p_ki)``."""
    n_t = positions.shape[0]
    u = (positions - x0) / h
    inside = (u > 0.0) & (u < n)
    j = np.floor(np.where(inside, u, 0.0)).astype(np.int64)
    f = np.where(inside, u - j, 0.0)
    w = np.broadcast_to(loads, positions.shape)
    rows = np.broadcast_to(np.arange(n_t)[:, None], positions.shape)
    r = np.concatenate([rows[inside], rows[inside]])
    c = np.concatenate([j[inside], j[inside] + 1])
    v = np.concatenate([(w * (1.0 - f))[inside], (w * f)[inside]])
    keep = (c >= 1) & (c <= n - 1)
    return sp.csr_matrix((v[keep], (r[keep], c[keep] - 1)), shape=(n_t, n - 1))


def smoothing_penalty(n_interior: int, regularization: float, h: float) -> np.ndarray:
    """The matrix method's smoothing term ``(ℓ / h)⁴ D₂ᵀ D₂`` on ``n_interior`` ordinates
    spaced ``h`` (end ordinates zero), dense; multiply it by the mean diagonal of ``GᵀG``
    (see ``regularization`` in :func:`calibrate_influence_line`)."""
    m = n_interior
    D = sp.diags([np.ones(m - 1), -2.0 * np.ones(m), np.ones(m - 1)], [-1, 0, 1],
                 shape=(m, m))
    return (regularization / h) ** 4 * (D.T @ D).toarray()


def static_axle_loads(vehicle: Vehicle | Sequence[float]) -> np.ndarray:
    """Static axle loads, N, of a vehicle (its ``static_axle_loads``) or of a sequence of
    loads; raises :class:`InputError` unless they are positive and finite."""
    loads = getattr(vehicle, "static_axle_loads", vehicle)
    try:
        arr = np.array(loads, dtype=float, ndmin=1)
    except (TypeError, ValueError):
        raise InputError(
            "vehicle must be a vehicle with static_axle_loads or a sequence of static axle "
            f"loads (N), got {type(vehicle).__name__}") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"static axle loads must be positive and finite (N), got "
                         f"{arr.tolist()}")
    return arr


def _check_records(records: Any, n_axles: int | None) -> list[Record]:
    recs = record_list(records, needs="calibration needs at least one crossing")
    for k, r in enumerate(recs):
        if len(r.passages) != 1:
            raise InputError(
                f"records[{k}] has {len(r.passages)} passages; the matrix method needs "
                "records of one known vehicle each (speed, axle spacings, delay)")
        if n_axles is not None and r.passage.n_axles != n_axles:
            raise InputError(
                f"the calibration vehicle has {n_axles} axles but records[{k}]'s passage "
                f"has {r.passage.n_axles}")
    return recs


def calibrate_influence_line(
    records: Sequence[Record] | Record,
    vehicle: Vehicle | Sequence[float],
    *,
    channels: Any = "sum",
    regularization: float = DEFAULT_SMOOTHING,
    spacing: float | None = None,
    support: tuple[float, float] | None = None,
    lane_tolerance: float = 0.5,
) -> InfluenceLine:
    """Influence line(s) from crossings of a truck of known static axle loads.

    The matrix method (OBrien, Quilligan & Karoumi 2006, "Calculating an influence line
    from direct measurements", Proc. ICE Bridge Eng. 159(1), 31–34): with ``I`` piecewise
    linear on ordinates ``x_j = x_0 + j h`` (zero at both ends), every sample of every record
    gives one linear equation ``ε(t_k) = Σ_i W_i I(v (t_k − delay) − a_i)``; the ordinates
    minimise ``‖G I − ε‖² + λ ‖D₂ I‖²``, ``D₂`` the second difference.

    Parameters
    ----------
    records : Record or sequence of Record
        Crossings of the calibration truck, one vehicle each, with passages (speed, lane,
        axle spacings, delay).  Several crossings (speeds, road states) stack into one
        least-squares problem, which averages out the dynamics.
    vehicle : vehicle or sequence of float
        The calibration truck (its ``static_axle_loads`` are used) or its static axle loads,
        N; as many axles as the passages.
    channels : "sum", "each", None or sequence
        Which readings to calibrate (see :func:`resolve_channels`); default the summed
        longitudinal gauges of the section nearest the middle of the support.
    regularization : float
        Smoothing length ℓ, m (≥ 0): λ = (ℓ / h)⁴ × the mean diagonal of GᵀG, so that
        features shorter than about 2πℓ are damped and longer ones follow the data, for any
        spacing, record length or number of records.  The default 0.1 m suppresses the
        sample-to-sample noise of a fine grid and leaves an FE line's shape (element length
        ≥ 0.5 m) unchanged; ``0`` is plain least squares.
    spacing : float, optional
        Ordinate spacing, m; default the largest distance a vehicle travels between two
        samples in the records (so every interval holds data of every record).
    support : (float, float), optional
        Where the line may be non-zero, m.  Default, as OBrien et al.: from the first
        axle's position at the first sample to the last axle's position at the last sample,
        i.e. the bridge if the records run from the first axle's entry to the last axle's
        exit (as :func:`bwim.simulate` records do); longer records only add ordinates that
        the data hold near zero.
    lane_tolerance : float
        The records' lanes may differ by at most this much, m; the line applies to their
        mean lane.

    Returns
    -------
    InfluenceLine
        ``source="matrix method"``, with the fit's relative residual.
    """
    loads = static_axle_loads(vehicle)
    recs = _check_records(records, loads.size)
    ell = require_finite("regularization", regularization)
    if ell < 0:
        raise InputError(f"regularization (a smoothing length, m) must be >= 0, got {ell:g}")
    passages = [r.passage for r in recs]
    lanes = np.array([p.lane for p in passages])
    tol = require_finite("lane_tolerance", lane_tolerance)
    if np.ptp(lanes) > tol:
        raise InputError(
            f"the calibration crossings are in lanes {lanes.tolist()} m, more than "
            f"lane_tolerance = {tol:g} m apart; calibrate each lane separately")
    tracks = {p.track_width for p in passages}
    if len(tracks) > 1:
        raise InputError(f"the calibration crossings have different track widths {tracks}")

    if support is None:
        # from the first axle's first position to the last axle's last one
        starts = [p.axle_x(r.time[:1])[0, 0] for r, p in zip(recs, passages, strict=True)]
        ends = [p.axle_x(r.time[-1:])[0, -1] for r, p in zip(recs, passages, strict=True)]
        x0, x1 = min(starts), max(ends)
        if x1 <= x0:
            raise InputError(
                "the records are shorter than the vehicle's passage over any span (the last "
                "axle never passes the first axle's starting point); give support=")
    else:
        if not isinstance(support, (tuple, list, np.ndarray)) or len(support) != 2:
            raise InputError(f"support must be (start, end) in m, got {support!r}")
        x0, x1 = (require_finite("support", s) for s in support)
        if x1 <= x0:
            raise InputError(f"support must be (start, end) with end > start, got {support!r}")
    if spacing is None:
        h_req = max(p.speed / r.sampling_rate for r, p in zip(recs, passages, strict=True))
    else:
        h_req = require_positive("spacing", spacing)
    n_ord = (x1 - x0) / h_req
    check_memory(8.0 * (3 * n_ord * n_ord + 4 * loads.size * sum(r.time.size for r in recs)),
                 f"an influence line of {n_ord:.3g} ordinates (spacing {h_req:.3g} m)")
    n = max(int(np.ceil(n_ord - 1e-9)), 2)
    h = (x1 - x0) / n

    section = 0.5 * (x0 + x1)
    chans = resolve_channels(recs[0].sensors, channels, section_x=section)
    blocks, data = [], []
    for r, p in zip(recs, passages, strict=True):
        G = hat_design(p.axle_x(r.time), loads, x0, h, n)
        used = np.diff(G.indptr) > 0  # samples with an axle on the support
        if not used.any():
            raise InputError(f"no axle of the record at speed {p.speed:g} m/s is on the "
                             f"support {x0:g} … {x1:g} m")
        blocks.append(G[used])
        data.append(read_channels(r, chans)[used])
    G = sp.vstack(blocks).tocsr()
    E = np.concatenate(data)
    N = (G.T @ G).toarray()
    rhs = G.T @ E
    scale = float(np.mean(np.diag(N)))
    if ell > 0:
        N += scale * smoothing_penalty(n - 1, ell, h)
    try:
        ords = scipy.linalg.solve(N, rhs, assume_a="pos")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        raise NumericalError(
            f"the influence-line ordinates are not determined by the data ({n - 1} ordinates "
            f"at {h:.3g} m): use a larger spacing or regularization > 0") from None
    resid = float(np.linalg.norm(G @ ords - E) / max(np.linalg.norm(E), np.finfo(float).tiny))
    full = np.zeros((n + 1, len(chans)))
    full[1:-1] = ords
    return InfluenceLine(
        x=x0 + h * np.arange(n + 1), ordinates=full, channels=chans,
        lane=float(lanes.mean()), track_width=passages[0].track_width,
        source="matrix method", residual=resid,
    )


# --- the FE model's line ------------------------------------------------------------------

def model_influence_line(
    bridge: Bridge,
    sensors: Sequence[Sensor] | None = None,
    *,
    channels: Any = "sum",
    lane: float | None = None,
    track_width: float | None = None,
    spacing: float = 0.02,
    like: InfluenceLine | None = None,
) -> InfluenceLine:
    """The FE model's static influence line of a unit axle load (docs/theory.md §1.5).

    Parameters
    ----------
    bridge : Bridge
    sensors : sequence of Sensor
        The available sensors (``channels`` selects among them as in
        :func:`resolve_channels`, the ``"sum"`` section nearest mid-span).
    channels : "sum", "each", None or sequence
    lane : float
        Vehicle centre line, m from the right-hand edge (ignored on a beam).
    track_width : float or None
        Wheel track of the unit axle, m: half a newton at ``lane ∓ track_width / 2``; None:
        one newton on the centre line.
    spacing : float
        Ordinate spacing over ``[0, bridge.length]``, m.
    like : InfluenceLine, optional
        Take channels, lane, track width and ordinate positions from this line instead
        (to compare a calibrated line with the model's); then give none of the others.

    Returns
    -------
    InfluenceLine
        ``source="FE model"``.
    """
    from bwim.fe.bridge import Bridge

    require_instance("bridge", bridge, Bridge)
    if like is not None:
        if sensors is not None or lane is not None or track_width is not None:
            raise InputError("give either like= or sensors/lane/track_width, not both")
        chans, lane_v, track, x = like.channels, like.lane, like.track_width, like.x
    else:
        if sensors is None:
            raise InputError("model_influence_line needs sensors (or like=)")
        chans = resolve_channels(sensors, channels, section_x=bridge.length / 2)
        if lane is None:
            if bridge.is_plate:
                raise InputError("lane (vehicle centre line, m from the right-hand edge) is "
                                 "required on a plate bridge")
            lane = 0.0
        lane_v = require_finite("lane", lane)
        track = None if track_width is None else require_positive("track_width", track_width)
        h = require_positive("spacing", spacing)
        n = max(int(np.ceil(bridge.length / h - 1e-9)), 2)
        x = np.linspace(0.0, bridge.length, n + 1)
    if not bridge.is_plate:
        ys = [None]
    else:
        ys = [lane_v] if track is None else [lane_v - track / 2, lane_v + track / 2]
        for y in ys:
            if not 0.0 <= y <= bridge.width:
                raise InputError(f"wheel at y = {y:g} m is off the deck (width "
                                 f"{bridge.width:g} m) for lane {lane_v:g} m")
    sens: list[Sensor] = []
    for c in chans:
        sens += [s for s in c.sensors if s not in sens]
    inf = bridge.influence(sens)
    per_sensor = sum(inf.at(x, None if y is None else np.full(x.shape, y)) for y in ys)
    per_sensor = per_sensor / len(ys)
    ords = np.stack([per_sensor[:, [sens.index(s) for s in c.sensors]].sum(axis=1)
                     for c in chans], axis=1)
    return InfluenceLine(x=x, ordinates=ords, channels=chans, lane=lane_v, track_width=track,
                         source="FE model")
