"""A realistic simulated installation: a calibration day and a traffic day two days later.

Contract
--------
:func:`make_site_days` simulates the installation of a :class:`~bwim.synthetic.layout.
SiteLayout` (default :data:`~bwim.synthetic.layout.SHORT_SPAN_4_LANE`) on two dates and
writes what its logger would have recorded, plus the ground truth, into a new folder:

``calibration/YYYY-MM-DD-HH-MM-SS-mmm.txt``
    Runs of the calibration truck (:func:`~bwim.synthetic.traffic.calibration_truck`,
    5 axles, 40 t) in lane 1 at 20–25 m/s, spread over 09:00–16:00 of the calibration
    date.  In ``round(n_calibration / 2)`` of them (chosen at random) a vehicle of 4–7
    axles crosses in lane 3, the other direction, while the truck is on the bridge.
``calibration_day_traffic/PL<lane>_YYYY-...txt``, ``traffic/PL<lane>_YYYY-...txt``
    Ordinary traffic on the calibration date (during the calibration, from an hour before
    the first run to an hour after the last) and on the traffic date (06:00–20:00), one
    file per heavy vehicle (its lane in the name), vehicles of :mod:`bwim.synthetic.fleet`
    in the lanes' shares (:attr:`~bwim.synthetic.layout.Lane.heavy_share`) at 18–27 m/s.
    ``n_multiple`` events of each day have a second vehicle on the bridge: in the other
    direction (half of them; 4–7 axles), side by side in the other lane of the same
    direction (30 %) or following in the same lane at its speed (20 %), a time gap of
    :data:`FOLLOWING_GAP` between the bodies, in the first one's file (on a span shorter
    than that gap, as the default layout's, never on the bridge with it: ``n_vehicles``
    of ``truth.csv`` counts the vehicles on the bridge at once).
``scenario.toml``
    ``[bridge]`` the starting model an engineer would declare (the measured geometry,
    nominal concrete: :data:`NOMINAL_MODULUS`, :data:`NOMINAL_DENSITY`; elements of about
    :data:`MODEL_MESH` m, coarser than the simulation's); ``[logger] columns,
    sampling_rate``; ``[[sensors]]`` the gauges (names, kind, x, y);
    ``[[axle_detectors]]`` per lane with detectors (lane, direction, channels in the order
    the lane's traffic meets them, distance, y); ``[vehicle]`` the calibration truck's
    nominal spacings and static axle loads (N).  With ``temperature_channel``, a
    ``[[sensors]]`` ``temp_C`` of kind ``temperature``.  Written last.
``reference.csv``
    The statically weighed vehicles: one row per single-vehicle event of the traffic date
    whose vehicle is in a lane with detectors: ``record, n_axles, axle_spacings_m,
    axle_weights_kN, gvw_kN, speed_m_s, time, lane, direction`` (``time``: ISO 8601 of
    the first axle at the gauge line; lists ``;``-separated).
``truth.csv``
    One row per vehicle of every event: ``record, kind, date, vehicle, trigger,
    n_vehicles, configuration, vehicle_type, n_axles, axle_spacings_m, axle_weights_kN,
    gvw_kN, steer_kN, tyres, loading, speed_m_s, lane, direction, lane_y_m, time,
    event_start, strain_factor, temperature_C, road_gd0_m3, road_seed, contact_lost,
    force_ratio_min, force_ratio_max``.
``site_truth.toml``, ``README.txt``
    The hidden facts (the weighing side never reads them) and this layout in short.

**Event files.**  Tab-separated text without a header, at the layout's 512 Hz, columns in
the layout's order: ``time`` from 0 in every file (s, exact multiples of 1/512 written
with 9 decimals); the lane-1 detectors; the gauges in uncalibrated logger units
``gain_j × (f ε + noise + offset + baseline drift) / 10⁻⁶`` with per-gauge gains in
0.95–1.05, one absolute noise σ for every gauge (``noise`` × the calibration truck's peak
static gauge strain in lane 1), an offset per channel per event uniform in ±50 µε and a
linear baseline drift per channel per event (change over the event normal with σ = 2
noise σ); the lane-3 detectors; two digital status columns (``1`` and ``0``); with
``temperature_channel`` a last column ``temp_C`` (deck temperature, noise σ 0.1 °C).  The
clock is only in the file name: the date and time of the first sample to the
millisecond.  An event starts 154 samples (0.30 s) before the first axle of any of its
vehicles enters the bridge (the bridge is at rest) and ends 0.2 s after the last axle
leaves.  Axle detectors: :mod:`bwim.synthetic.detector`; gains drawn per site, a lane's
two about 3–5 × apart.

**Drift.**  The strain-to-load factor ``f`` (:mod:`bwim.synthetic.thermal`) follows the
deck temperature of each date (two different days); it multiplies every simulated strain
(the gauges and the detectors' global part) of an event, at the clock time of its trigger
vehicle's first axle at the gauge line.

**Simulation.**  Vehicle–bridge interaction (:mod:`bwim.dynamics`, modal, static
correction) at 1024 Hz, anti-alias FIR and decimation to 512 Hz, a 60 m run-up on the
vehicles' own ISO 8608 road (G_d(n₀) log-uniform in ``roughness``, default
:data:`ROUGHNESS`, a WIM-grade approach: docs/realistic_site.md; one
road per direction and event, smoothed over a 0.24 m tyre patch; an event whose tyre
loses contact is simulated again on a new road, at most 10 times).  Vehicles of one
direction are simulated together (their coupling through the bridge included); a -x
group is simulated in the mirrored frame (:mod:`bwim.synthetic.layout`; the simulated
vehicle is the mirror image of the real one, the same for these laterally symmetric
models) and the responses of the two directions are superposed: the bridge is linear,
only the coupling of vehicles of opposite directions through the bridge's motion is
neglected (its size is measured by ``tests/validation/test_synthetic_superposition.py``).
"""

from __future__ import annotations

import csv
import dataclasses
import datetime as dt
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import resample_poly

from bwim.conventions import KILONEWTON, MICROSTRAIN
from bwim.dynamics.crossing import prepare_crossing, run_crossing
from bwim.errors import InputError
from bwim.io.atomic import atomic_open
from bwim.io.toml_writer import to_toml
from bwim.road import ISO_CLASSES, RoadProfile
from bwim.synthetic.detector import detector_reading, local_response
from bwim.synthetic.fleet import (
    FLEET_KINDS,
    FLEET_MIX,
    GVW_RANGE,
    TrafficVehicle,
    draw_kind,
    traffic_vehicle,
)
from bwim.synthetic.layout import SHORT_SPAN_4_LANE, SiteLayout
from bwim.synthetic.outfolder import checked_count, joined, prepare_folder
from bwim.synthetic.thermal import ThermalDrift, draw_days
from bwim.synthetic.traffic import calibration_truck

__all__ = ["CALIBRATION_TYRES", "SITE_DAYS_VERSION", "SiteDays", "SiteEvent", "VehicleRun",
           "make_site_days", "nominal_bridge"]

#: Raised whenever the same arguments simulate other files, so that a folder cached under
#: an older version is not taken for this one's (2: following vehicles at the time gaps
#: traffic keeps, instead of 3-7 m behind; 3: the real site's drift, steady through the
#: working day and a few per cent apart between the dates; 4: the detectors' dips between
#: axle groups in the middle of the real range, global share 0.9).
SITE_DAYS_VERSION = 4

PRE_TRIGGER = 154  #: samples before the first axle enters the bridge (0.30 s at 512 Hz)
POST_TRIGGER = 0.2  #: s after the last axle leaves
OVERSAMPLE = 2  #: the simulation runs at OVERSAMPLE × the logger's rate
EDGE = 0.05  #: s of extra simulated tail, cut after filtering
OFFSET = 50.0 * MICROSTRAIN  #: half-range of a gauge's per-event offset (strain)
BASELINE = 2.0  #: σ of a gauge's baseline change over an event, in noise σ
TEMPERATURE_NOISE = 0.1  #: °C
TYRE_PATCH = 0.24  #: m, road smoothing length
#: G_d(n₀) range, m³/cycle: a WIM-grade approach, ISO 8608 class A down to an eighth of it:
#: the roads on which a weighing that knows the true passages, lateral positions and drift
#: scatters about as much as the commercial system did on the real site (class A-B roads
#: leave it clearly worse; docs/realistic_site.md, benchmarks/bench_realsite.py).
ROUGHNESS = (ISO_CLASSES["A"] / 8.0, ISO_CLASSES["A"])
WANDER = (0.25, 0.6)  #: m: σ of the lateral wander (normal), truncated at ± the second
CAL_SPEED = (20.0, 25.0)  #: m/s, uniform
TRAFFIC_SPEED = (22.5, 1.8, 18.0, 27.0)  #: m/s: mean, σ of a normal truncated to [min, max]
CAL_WINDOW = (9 * 3600.0, 16 * 3600.0)  #: s, clock window of the calibration runs
TRAFFIC_WINDOW = (6 * 3600.0, 20 * 3600.0)  #: s, clock window of the traffic date
MIN_GAP = 12.0  #: s between event starts on one date
REDRAWS = 10  #: attempts at a road on which no tyre loses contact
CONFIG_SHARE = (("opposite", 0.5), ("side_by_side", 0.3), ("following", 0.2))
#: s, uniform: the time gap between a following vehicle's front and the vehicle ahead's
#: rear at their common speed: up to the two seconds trucks are asked to keep in
#: free-flowing traffic, and closer (docs/realistic_site.md, "Other traffic")
FOLLOWING_GAP = (0.6, 2.0)
FRONT_OVERHANG = 1.4  #: m, a vehicle's front from its first axle (docs/realistic_site.md)
REAR_OVERHANG = 2.5  #: m, a vehicle's rear from its last axle (docs/realistic_site.md)
#: The scenario's [bridge]: the starting model a user would declare (measured geometry,
#: nominal concrete), coarser than the simulation's mesh (no inverse crime).
MODEL_MESH = 0.75  #: m
NOMINAL_MODULUS = 30e9  #: Pa
NOMINAL_DENSITY = 2500.0  #: kg/m³
CALIBRATION_TYRES = ("single", "dual", "wide", "wide", "wide")  #: the calibration truck's


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleRun:
    """One vehicle of an event, as simulated."""

    vehicle: object  #: the vehicle model (Truck3D or TractorSemitrailer)
    vehicle_type: str  #: ``calibration`` or a :data:`~bwim.synthetic.fleet.FLEET_KINDS`
    tyres: tuple[str, ...]
    loading: float  #: fraction of the payload range (the calibration truck: 1)
    trigger: bool  #: the vehicle the event file is for
    speed: float  #: m/s
    lane: int
    direction: int  #: +1 / -1
    lane_y: float  #: m, centre line with wander
    entry: float  #: record time (s from the file's first sample) of the first axle on the deck
    gauge_time: dt.datetime  #: clock time of the first axle at the gauge line
    static_axle_loads: np.ndarray  #: N
    road_gd0: float
    road_seed: int
    contact_lost: bool
    force_ratio: tuple[float, float]  #: least, largest axle force / static load on the deck


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteEvent:
    """One written event file."""

    name: str
    path: Path
    kind: str  #: ``calibration`` or ``traffic``
    date: dt.date
    start: dt.datetime  #: clock time of the first sample
    n_samples: int
    strain_factor: float
    temperature: float  #: °C, deck temperature at the trigger's gauge-line time
    configuration: str  #: ``single``, ``opposite``, ``side_by_side`` or ``following``
    n_vehicles: int  #: most vehicles on the bridge at once
    vehicles: tuple[VehicleRun, ...]


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteDays:
    """What :func:`make_site_days` wrote, and the site's hidden facts."""

    out_dir: Path
    scenario: Path
    calibration: tuple[Path, ...]
    calibration_day_traffic: tuple[Path, ...]
    traffic: tuple[Path, ...]
    reference: Path
    truth: Path
    site_truth: Path
    readme: Path
    events: tuple[SiteEvent, ...]
    layout: SiteLayout
    seed: int
    mesh: float
    sampling_rate: float
    calibration_date: dt.date
    traffic_date: dt.date
    noise_sigma: float  #: gauge noise σ, strain
    reference_strain: float  #: the calibration truck's peak static gauge strain, lane 1
    gauge_gains: tuple[float, ...]
    detector_gains: tuple[float, ...]  #: in the layout's detector order
    drift: tuple[ThermalDrift, ThermalDrift]  #: calibration date, traffic date
    drifting: bool  #: False: every strain factor is 1 (``drift=False``)
    calibration_axle_loads: tuple[float, ...]  #: N, static
    temperature_channel: bool


@dataclass(frozen=True, kw_only=True, eq=False)
class _Vehicle:
    tv: TrafficVehicle
    trigger: bool
    speed: float
    lane: int
    direction: int
    lane_y: float
    rel: float  # s, entry relative to the trigger's, a multiple of the simulation step


@dataclass(frozen=True, kw_only=True, eq=False)
class _Plan:
    kind: str
    day: int  # 0 calibration date, 1 traffic date
    folder: str
    clock: float  # s since midnight of the first sample, a whole millisecond
    configuration: str
    vehicles: tuple[_Vehicle, ...]
    roads: tuple  # per direction (+1, -1): (gd0, correlation, seed)
    noise_seed: np.random.SeedSequence


@dataclass(frozen=True, kw_only=True, eq=False)
class _Model:
    """Everything shared by the events: bridge, sensors, influence surfaces."""

    layout: SiteLayout
    bridge: object
    points: dict  # direction -> tuple of sensors (gauge points then detector-line points)
    influence: dict  # direction -> InfluenceSurfaces
    weights: np.ndarray  # (n_points, n_gauges + n_lines)
    lines: tuple[float, ...]  # y of the detector lines (global part)
    fs: float
    continuous: object = None  # ContinuousSpan of the real-frame points (layout.continuity)


def make_site_days(
    out_dir: str | os.PathLike,
    *,
    layout: SiteLayout = SHORT_SPAN_4_LANE,
    seed: int = 0,
    n_calibration: int = 12,
    n_traffic: int = 700,
    n_calibration_day_traffic: int | None = None,
    n_multiple: int | None = None,
    mesh: float = 0.25,
    noise: float = 0.02,
    approach: float = 60.0,
    roughness: tuple[float, float] = ROUGHNESS,
    temperature_channel: bool = False,
    drift: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> SiteDays:
    """Simulate the installation's calibration date and traffic date into ``out_dir``.

    Parameters
    ----------
    out_dir : path
        New or empty folder (created with its parents); a non-empty one is refused.
    layout : SiteLayout
        The installation; its first lane with detectors carries the calibration runs.
    seed : int
        All randomness derives from it (the dates too).
    n_calibration : int
        Calibration runs (09:00–16:00 of the calibration date).
    n_traffic : int
        Heavy-vehicle events of the traffic date (06:00–20:00).
    n_calibration_day_traffic : int, optional
        Heavy-vehicle events on the calibration date from an hour before the first run to
        an hour after the last; default: the traffic date's rate over that window.
    n_multiple : int, optional
        Traffic events of each date with a second vehicle on the bridge (at most all of
        them); default 6 % of the date's traffic events (at least 1 when there are any).
    mesh : float
        Data-mesh element size, m, in [0.1, 0.6].
    noise : float
        Gauge noise σ as a fraction of the calibration truck's peak static gauge strain.
    approach : float
        Run-up of each vehicle on its road before the bridge, m.
    roughness : (float, float)
        Range of the roads' G_d(n₀), m³/cycle (log-uniform per event and direction).
    temperature_channel : bool
        Write a ``temp_C`` column (deck temperature) and declare it in the scenario.
    drift : bool
        False: the strain factor is 1 at all times (the same site, temperature and noise
        otherwise): a drift-free reference for studies and tests.
    progress : callable, optional
        Called as ``progress(done, total)`` after each event file.
    """
    if not isinstance(layout, SiteLayout):
        raise InputError(f"layout must be a SiteLayout, got {type(layout).__name__}")
    if not layout.detector_lanes:
        raise InputError(f"layout {layout.name} has no axle detectors")
    n_calibration = checked_count("n_calibration", n_calibration, 1)
    n_traffic = checked_count("n_traffic", n_traffic, 0)
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    if not isinstance(mesh, (int, float)) or not 0.1 <= mesh <= 0.6:
        raise InputError(f"mesh must be an element size in [0.1, 0.6] m, got {mesh!r}")
    if not isinstance(noise, (int, float)) or not 0 <= noise < 1:
        raise InputError(f"noise must be a fraction in [0, 1), got {noise!r}")
    if not isinstance(approach, (int, float)) or not 0 <= approach <= 500:
        raise InputError(f"approach must be in [0, 500] m, got {approach!r}")
    try:
        lo_r, hi_r = (float(v) for v in roughness)
    except (TypeError, ValueError):
        raise InputError(f"roughness must be two numbers (m³/cycle), got {roughness!r}") from None
    if not 0 < lo_r <= hi_r < 1e-3:
        raise InputError(f"roughness must be 0 < low <= high < 1e-3 m³/cycle, got {roughness!r}")
    if not isinstance(temperature_channel, bool):
        raise InputError(f"temperature_channel must be true or false, got "
                         f"{temperature_channel!r}")
    if not isinstance(drift, bool):
        raise InputError(f"drift must be true or false (the site's drift is thermal), got "
                         f"{drift!r}")
    if progress is not None and not callable(progress):
        raise InputError("progress must be a callable (done, total) or None")
    cal_window_hours = (CAL_WINDOW[1] - CAL_WINDOW[0]) / 3600.0 + 2.0
    traffic_hours = (TRAFFIC_WINDOW[1] - TRAFFIC_WINDOW[0]) / 3600.0
    if n_calibration_day_traffic is None:
        n_calibration_day_traffic = round(n_traffic * cal_window_hours / traffic_hours)
    n_cdt = checked_count("n_calibration_day_traffic", n_calibration_day_traffic, 0)
    if n_multiple is not None:
        n_multiple = checked_count("n_multiple", n_multiple, 0)
    for n, hours in ((n_traffic, traffic_hours), (n_cdt, cal_window_hours)):
        if n * MIN_GAP > 0.8 * hours * 3600.0:
            raise InputError(f"{n} events do not fit in {hours:g} h at least {MIN_GAP:g} s "
                             "apart")
    out = prepare_folder(out_dir)

    fs = float(layout.sampling_rate)
    root = np.random.SeedSequence(int(seed))
    site_ss, plan_ss = root.spawn(2)
    site_rng = np.random.default_rng(site_ss)
    cal_date = dt.date(2026, 3, 2) + dt.timedelta(days=int(site_rng.integers(0, 180)))
    dates = (cal_date, cal_date + dt.timedelta(days=2))
    days = draw_days(site_rng)
    gauge_gains = site_rng.uniform(0.95, 1.05, len(layout.gauges))
    det_gain = {}
    for lane in layout.detector_lanes:
        pair = layout.lane_detectors(lane)
        for d, g in zip(pair, layout.detector_response.draw_gains(site_rng), strict=True):
            det_gain[d.name] = g
    detector_gains = np.array([det_gain[d.name] for d in layout.detectors])

    model = _site_model(layout, mesh, fs)
    cal_truck = calibration_truck()
    cal_loads = cal_truck.model().static_axle_loads
    ref_strain = _peak_static_strain(model, cal_truck, cal_loads)
    sigma = noise * ref_strain

    plans = _plan(plan_ss, layout, n_calibration, n_traffic, n_cdt, n_multiple, cal_truck,
                  fs, (lo_r, hi_r))
    for folder in ("calibration", "calibration_day_traffic", "traffic"):
        (out / folder).mkdir()
    events = []
    for k, plan in enumerate(plans):
        events.append(_simulate_and_write(
            plan, out, model=model, approach=float(approach), drift=days[plan.day],
            drifting=drift, date=dates[plan.day], sigma=sigma, gauge_gains=gauge_gains,
            det_gain=det_gain, temperature_channel=temperature_channel))
        if progress is not None:
            progress(k + 1, len(plans))

    reference = out / "reference.csv"
    truth = out / "truth.csv"
    _write_reference(reference, [e for e in events if e.kind == "traffic"
                                 and e.date == dates[1]], layout)
    _write_truth(truth, events)
    site_truth = out / "site_truth.toml"
    _write_site_truth(site_truth, seed=int(seed), mesh=float(mesh), model=model, noise=noise,
                      sigma=sigma, ref_strain=ref_strain, gauge_gains=gauge_gains,
                      det_gain=det_gain, drift=days, drifting=drift, dates=dates,
                      approach=approach, roughness=(lo_r, hi_r))
    readme = out / "README.txt"
    _write_readme(readme, layout, events, dates, temperature_channel)
    scenario = out / "scenario.toml"
    _write_scenario(scenario, layout, cal_truck, cal_loads, temperature_channel)
    return SiteDays(
        out_dir=out, scenario=scenario,
        calibration=tuple(e.path for e in events if e.kind == "calibration"),
        calibration_day_traffic=tuple(e.path for e in events
                                      if e.kind == "traffic" and e.date == dates[0]),
        traffic=tuple(e.path for e in events if e.kind == "traffic" and e.date == dates[1]),
        reference=reference, truth=truth, site_truth=site_truth, readme=readme,
        events=tuple(events), layout=layout, seed=int(seed), mesh=float(mesh),
        sampling_rate=fs, calibration_date=dates[0], traffic_date=dates[1],
        noise_sigma=float(sigma), reference_strain=float(ref_strain),
        gauge_gains=tuple(float(g) for g in gauge_gains),
        detector_gains=tuple(float(g) for g in detector_gains), drift=days,
        drifting=drift,
        calibration_axle_loads=tuple(float(v) for v in cal_loads),
        temperature_channel=temperature_channel,
    )


# --- validation ------------------------------------------------------------------------------




# --- the model shared by all events ----------------------------------------------------------
def _site_model(layout: SiteLayout, mesh: float, fs: float) -> _Model:
    bridge = layout.bridge(mesh)
    lines = tuple(sorted({d.y for d in layout.detectors}))
    locations = [(g.x, g.y) for g in layout.gauges] + [(layout.span / 2, y) for y in lines]
    points, influence = {}, {}
    weights = None
    for direction in (1, -1):
        spread = layout.spread_points(locations, mirrored=direction < 0)
        points[direction] = spread.points
        influence[direction] = bridge.influence(list(spread.points))
        weights = spread.weights
    continuous = (None if layout.continuity is None
                  else layout.continuous_span(mesh, points[1]))
    return _Model(layout=layout, bridge=bridge, points=points, influence=influence,
                  weights=weights, lines=lines, fs=fs, continuous=continuous)


def _continuity_strain(model: _Model, passage, truth, direction: int,
                       tau: np.ndarray) -> np.ndarray:
    """What the slab's continuity (:attr:`SiteLayout.continuity`) adds to the simply
    supported span's readings of a vehicle at its record times ``tau`` (s; before 0 its
    wheels carry their static loads, the crossing's record starting as its first axle
    enters): ``Σ_w F_w(t) (I_cont − I_ss)(x_w, y_w)`` quasi-statically, shape
    (n_t, n_gauges + n_lines)."""
    layout = model.layout
    x = passage.wheel_x(tau)
    if direction < 0:
        x = layout.span - x
    a = layout.continuity.side_span
    rows = np.clip(np.round(tau * OVERSAMPLE * model.fs).astype(int), 0,
                   truth.wheel_forces.shape[0] - 1)
    forces = np.where((tau >= 0)[:, None], truth.wheel_forces[rows],
                      truth.static_wheel_loads[None, :])
    on = (x > -a) & (x < layout.span + a)
    k, w = np.nonzero(on)
    out = np.zeros((tau.size, model.weights.shape[0]))
    if k.size:
        xs, ys = x[k, w], passage.wheel_y[w]
        delta = model.continuous.at(xs, ys) - model.influence[1].at(xs, ys)
        np.add.at(out, k, forces[k, w][:, None] * delta)
    return out @ model.weights


def _peak_static_strain(model: _Model, truck, loads) -> float:
    """Largest gauge strain under the truck's static loads along the calibration lane."""
    layout = model.layout
    lane = layout.lane(layout.detector_lanes[0])
    offsets = truck.axle_offsets
    front = np.arange(0.0, layout.span + offsets[-1] + 0.025, 0.025)
    xw = front[:, None] - np.repeat(offsets, 2)[None, :]
    half = truck.track_width / 2
    yw = np.tile([lane.y - half, lane.y + half], offsets.size)
    if lane.direction < 0:
        xw = layout.span - xw
    inf = model.influence[1]
    n_g = len(layout.gauges)
    ordinates = inf.at(xw.ravel(), np.broadcast_to(yw, xw.shape).ravel())
    gauge = (ordinates @ model.weights[:, :n_g]).reshape(*xw.shape, n_g)
    return float(np.max(np.einsum("w,pws->ps", np.repeat(loads / 2, 2), gauge)))


# --- planning -------------------------------------------------------------------------------
def _wander(rng: np.random.Generator) -> float:
    sd, cut = WANDER
    while True:
        w = rng.normal(0.0, sd)
        if abs(w) <= cut:
            return float(w)


def _speed(rng: np.random.Generator) -> float:
    mean, sd, lo, hi = TRAFFIC_SPEED
    while True:
        v = rng.normal(mean, sd)
        if lo <= v <= hi:
            return float(v)


def _on_time(layout: SiteLayout, vehicle, speed: float) -> float:
    """s from a vehicle's first axle entering the deck to its last axle leaving."""
    return (layout.span + float(vehicle.length)) / speed


def _times(rng, lo: float, hi: float, n: int, fixed=()) -> np.ndarray:
    """n clock times in [lo, hi) at least MIN_GAP from each other and from ``fixed``."""
    taken = list(fixed)
    out = []
    while len(out) < n:
        t = float(rng.uniform(lo, hi))
        if all(abs(t - s) >= MIN_GAP for s in taken):
            taken.append(t)
            out.append(t)
    return np.sort(np.array(out))


def _lane_draw(layout: SiteLayout, rng: np.random.Generator) -> int:
    share = np.array([ln.heavy_share for ln in layout.lanes])
    return layout.lanes[int(rng.choice(len(share), p=share))].number


def _other_lane(layout: SiteLayout, lane: int, *, same_direction: bool,
                rng: np.random.Generator) -> int:
    """Another lane of the same or the opposite direction, drawn by heavy share."""
    d = layout.lane(lane).direction
    cands = [ln for ln in layout.lanes if ln.number != lane
             and (ln.direction == d) == same_direction]
    if not cands:
        return 0
    share = np.array([ln.heavy_share for ln in cands]) + 1e-12
    return cands[int(rng.choice(len(cands), p=share / share.sum()))].number


def _plan(ss, layout, n_cal, n_traffic, n_cdt, n_multiple, cal_truck, fs, roughness):
    """Every event of both dates, in time order within each date (calibration date first)."""
    sched_ss, *event_ss = ss.spawn(1 + n_cal + n_traffic + n_cdt)
    rng = np.random.default_rng(sched_ss)
    cal_lane = layout.detector_lanes[0]
    # calibration runs spread over CAL_WINDOW, then the day's traffic around them
    span = (CAL_WINDOW[1] - CAL_WINDOW[0]) / n_cal
    cal_t = CAL_WINDOW[0] + span * (np.arange(n_cal) + 0.5 + rng.uniform(-0.3, 0.3, n_cal))
    opposite_runs = set(rng.choice(n_cal, round(n_cal / 2), replace=False).tolist())
    cdt_t = _times(rng, cal_t[0] - 3600.0, cal_t[-1] + 3600.0, n_cdt, fixed=cal_t)
    traffic_t = _times(rng, *TRAFFIC_WINDOW, n_traffic)
    multi = []
    for n in (n_cdt, n_traffic):
        m = (max(1, round(0.06 * n)) if n else 0) if n_multiple is None else n_multiple
        m = min(m, n)
        multi.append(set(rng.choice(n, m, replace=False).tolist()) if m else set())
    items = ([("calibration", 0, t, k in opposite_runs) for k, t in enumerate(cal_t)]
             + [("traffic", 0, t, k in multi[0]) for k, t in enumerate(cdt_t)])
    items.sort(key=lambda it: it[2])
    items += [("traffic", 1, t, k in multi[1]) for k, t in enumerate(traffic_t)]
    step = 1.0 / (OVERSAMPLE * fs)
    plans = []
    for (kind, day, clock, other), ess in zip(items, event_ss, strict=True):
        p_ss, noise_ss = ess.spawn(2)
        r = np.random.default_rng(p_ss)
        if kind == "calibration":
            tv = TrafficVehicle(kind="calibration", vehicle=cal_truck, tyres=CALIBRATION_TYRES,
                                loading=1.0)
            lane = cal_lane
            speed = float(r.uniform(*CAL_SPEED))
            config = "opposite" if other else "single"
        else:
            tv = traffic_vehicle(draw_kind(r), r)
            lane = _lane_draw(layout, r)
            speed = _speed(r)
            config = "single"
            if other:
                u = r.uniform()
                acc = 0.0
                for name, share in CONFIG_SHARE:
                    acc += share
                    if u < acc:
                        config = name
                        break
        vehicles = [_Vehicle(tv=tv, trigger=True, speed=speed, lane=lane,
                             direction=layout.lane(lane).direction,
                             lane_y=layout.lane(lane).y + _wander(r), rel=0.0)]
        if config != "single":
            # a calibration run's other vehicle is in the other direction's detector lane
            lane2 = next((ln for ln in layout.detector_lanes if layout.lane(ln).direction
                          != vehicles[0].direction), 0) if kind == "calibration" else 0
            second = _second(layout, vehicles[0], config, r, step, lane=lane2)
            if second is None:
                config = "single"
            else:
                vehicles.append(second)
        roads = tuple((float(np.exp(r.uniform(*np.log(roughness)))),
                       float(r.uniform(0.7, 0.95)), int(r.integers(2**31))) for _ in range(2))
        folder = ("calibration" if kind == "calibration"
                  else ("calibration_day_traffic", "traffic")[day])
        plans.append(_Plan(kind=kind, day=day, folder=folder,
                           clock=round(clock, 3), configuration=config,
                           vehicles=tuple(vehicles), roads=roads, noise_seed=noise_ss))
    return plans


def _second(layout, first: _Vehicle, config: str, r, step: float, *,
            lane: int = 0) -> _Vehicle | None:
    """The other vehicle of a multiple-vehicle event (in ``lane`` when given): on the
    bridge with the first, or following it in its lane at its speed (module
    docstring)."""
    d_first = _on_time(layout, first.tv.vehicle, first.speed)
    if config == "following":
        tv = traffic_vehicle(draw_kind(r), r)
        gap = float(r.uniform(*FOLLOWING_GAP)) * first.speed  # bumper to bumper, m
        rel = (float(first.tv.vehicle.length) + REAR_OVERHANG + gap + FRONT_OVERHANG) \
            / first.speed
        lane, speed = first.lane, first.speed
    else:
        lane = lane or _other_lane(layout, first.lane, same_direction=config == "side_by_side",
                                   rng=r)
        if not lane:
            return None
        tv = traffic_vehicle(draw_kind(r, min_axles=4 if config == "opposite" else 2), r)
        speed = _speed(r)
        d_second = _on_time(layout, tv.vehicle, speed)
        if config == "side_by_side":
            rel = float(r.uniform(-0.4, 0.4))
        else:  # any overlap of the two vehicles' times on the deck, by at least 0.2 s
            rel = float(r.uniform(-d_second + 0.2, d_first - 0.2))
    rel = round(rel / step) * step
    return _Vehicle(tv=tv, trigger=False, speed=speed, lane=lane,
                    direction=layout.lane(lane).direction,
                    lane_y=layout.lane(lane).y + _wander(r), rel=rel)


# --- simulation -------------------------------------------------------------------------------
def _road(layout, group, delays, approach, gd0, corr, seed, t_end) -> RoadProfile:
    t_start = min(d - approach / v.speed for d, v in zip(delays, group, strict=True))
    lo = min(v.speed * (t_start - d) - float(v.tv.vehicle.length)
             for d, v in zip(delays, group, strict=True))
    hi = max(v.speed * (t_end - d) for d, v in zip(delays, group, strict=True))
    start = lo - 5.0
    return RoadProfile.iso8608(gd0, length=hi + 5.0 - start, start=start, seed=seed,
                               track_correlation=corr).smoothed(TYRE_PATCH)


def _simulate(plan: _Plan, model: _Model, approach: float):
    """Strain at the logger rate over the event (gauges then detector lines) and, per
    vehicle, (passage, truth, first-entry offset in fine steps, record time)."""
    layout, fs = model.layout, model.fs
    step = 1.0 / (OVERSAMPLE * fs)
    first = min(v.rel for v in plan.vehicles)
    start = first - PRE_TRIGGER / fs  # record time 0 = the first sample
    entry = [v.rel - start for v in plan.vehicles]
    end = max(e + _on_time(layout, v.tv.vehicle, v.speed)
              for e, v in zip(entry, plan.vehicles, strict=True)) + POST_TRIGGER
    n_fine = int(np.floor((end + EDGE) / step + 1e-9)) + 1
    fine = np.zeros((n_fine, model.weights.shape[1]))
    runs = [None] * len(plan.vehicles)
    for gi, direction in enumerate((1, -1)):
        idx = [i for i, v in enumerate(plan.vehicles) if v.direction == direction]
        if not idx:
            continue
        group = [plan.vehicles[i] for i in idx]
        g0 = min(entry[i] for i in idx)
        delays = [entry[i] - g0 for i in idx]
        last_exit = max(d + _on_time(layout, v.tv.vehicle, v.speed)
                        for d, v in zip(delays, group, strict=True))
        tail = (end + EDGE) - g0 - last_exit
        gd0, corr, seed = plan.roads[gi]
        road = _road(layout, group, delays, approach, gd0, corr, seed, last_exit + tail)
        prepared = prepare_crossing(
            model.bridge, [v.tv.vehicle for v in group], speed=[v.speed for v in group],
            sensors=model.points[direction], lane=[v.lane_y for v in group], road=road,
            sampling_rate=OVERSAMPLE * fs, approach=approach, tail=tail, delay=delays)
        rec = run_crossing(prepared, model.bridge, influence=model.influence[direction],
                           warn=False)
        k0 = round(g0 / step)
        n = min(rec.data.shape[0], n_fine - k0)
        fine[k0:k0 + n] += rec.data[:n] @ model.weights
        for i, passage, truth in zip(idx, rec.passages, rec.truths, strict=True):
            runs[i] = (passage, truth, k0, rec.time)
            if model.continuous is not None:
                fine += _continuity_strain(model, passage, truth, direction,
                                           np.arange(n_fine) * step - g0)
    coarse = resample_poly(fine, 1, OVERSAMPLE, axis=0)
    n = int(np.floor(end * fs + 1e-9)) + 1
    return coarse[:n], entry, runs


def _force_ratio(layout, passage, truth, time) -> tuple[float, float]:
    x = passage.axle_x(time)
    on = (x >= 0) & (x <= layout.span)
    ratio = truth.axle_forces / truth.static_axle_loads
    return float(ratio[on].min()), float(ratio[on].max())


def _most_on_bridge(intervals) -> int:
    ends = sorted([(a, 1) for a, _ in intervals] + [(b, -1) for _, b in intervals],
                  key=lambda e: (e[0], e[1]))
    most = count = 0
    for _, s in ends:
        count += s
        most = max(most, count)
    return most


def _stamp(moment: dt.datetime) -> str:
    return moment.strftime("%Y-%m-%d-%H-%M-%S-") + f"{moment.microsecond // 1000:03d}"


def _simulate_and_write(plan: _Plan, out: Path, *, model: _Model, approach: float,
                        drift: ThermalDrift, drifting: bool, date: dt.date, sigma: float,
                        gauge_gains,
                        det_gain: dict, temperature_channel: bool) -> SiteEvent:
    layout, fs = model.layout, model.fs
    for _ in range(REDRAWS):
        strain, entry, runs = _simulate(plan, model, approach)
        if not any(run[1].contact_lost.any() for run in runs):
            break
        plan = dataclasses.replace(plan, roads=tuple(
            (g, c, (s + 7919) % 2**31) for g, c, s in plan.roads))
    n = strain.shape[0]
    t = np.arange(n) / fs
    midnight = dt.datetime.combine(date, dt.time())
    start = midnight + dt.timedelta(seconds=plan.clock)
    gauge_x = float(np.mean([g.x for g in layout.gauges]))

    # the trigger's gauge-line time sets the event's strain factor and temperature
    trig = next(i for i, v in enumerate(plan.vehicles) if v.trigger)
    tv0 = plan.vehicles[trig]
    to_line = (gauge_x if tv0.direction > 0 else layout.span - gauge_x) / tv0.speed
    clock0 = plan.clock + entry[trig] + to_line
    factor = float(drift.factor(clock0)) if drifting else 1.0
    temperature = float(drift.temperature.at(clock0))

    rng = np.random.default_rng(plan.noise_seed)
    n_g = len(layout.gauges)
    offset = rng.uniform(-OFFSET, OFFSET, n_g)
    slope = rng.normal(0.0, BASELINE * sigma, n_g) / t[-1]
    measured = (factor * strain[:, :n_g] + sigma * rng.standard_normal((n, n_g)) + offset
                + slope * t[:, None])
    columns = {g.name: gain * measured[:, j] / MICROSTRAIN
               for j, (g, gain) in enumerate(zip(layout.gauges, gauge_gains, strict=True))}

    # axle detectors: local response to every tyre + the global share of the slab's bending
    line_strain = {y: factor * strain[:, n_g + k] for k, y in enumerate(model.lines)}
    wheels = []
    for v, (passage, truth, k0, _) in zip(plan.vehicles, runs, strict=True):
        step_idx = OVERSAMPLE * np.arange(n) - k0  # fine index of t on the group's record
        at = np.clip(step_idx, 0, truth.wheel_forces.shape[0] - 1)
        forces = truth.wheel_forces[at]
        x = passage.wheel_x(t - k0 / (OVERSAMPLE * fs))
        if v.direction < 0:
            x = layout.span - x
        tyres = np.repeat(np.array(v.tv.tyres), passage.wheels_per_axle)
        side = np.sign(passage.wheel_y - v.lane_y)
        wheels.append((x, side, v.lane_y, forces, tyres))
    resp = layout.detector_response
    for d in layout.detectors:
        local = sum(local_response(x, sd, ly, f, ty, d.x, d.y, resp)
                    for x, sd, ly, f, ty in wheels)
        columns[d.name] = detector_reading(local, line_strain[d.y], gain=det_gain[d.name],
                                           response=resp, rng=rng)
    temp = temperature + TEMPERATURE_NOISE * rng.standard_normal(n)

    table, fmt, status = [], [], 0
    for name in layout.columns:
        if name == "time":
            table.append(t)
            fmt.append("%.9f")
        elif name == "-":
            table.append(np.full(n, 1.0 if status == 0 else 0.0))
            fmt.append("%d")
            status += 1
        else:
            table.append(columns[name])
            fmt.append("%.3f")
    if temperature_channel:
        table.append(temp)
        fmt.append("%.2f")
    trigger_lane = plan.vehicles[trig].lane
    name = (f"{_stamp(start)}.txt" if plan.kind == "calibration"
            else f"PL{trigger_lane}_{_stamp(start)}.txt")
    path = out / plan.folder / name
    with atomic_open(path, newline="") as f:
        np.savetxt(f, np.column_stack(table), fmt=fmt, delimiter="\t", newline="\n")

    vehicles = []
    intervals = []
    for v, e, (passage, truth, _, rec_time) in zip(plan.vehicles, entry, runs, strict=True):
        line = (gauge_x if v.direction > 0 else layout.span - gauge_x) / v.speed
        on = _on_time(layout, v.tv.vehicle, v.speed)
        intervals.append((e, e + on))
        vehicles.append(VehicleRun(
            vehicle=v.tv.vehicle, vehicle_type=v.tv.kind, tyres=v.tv.tyres,
            loading=v.tv.loading, trigger=v.trigger, speed=v.speed, lane=v.lane,
            direction=v.direction, lane_y=v.lane_y, entry=e,
            gauge_time=start + dt.timedelta(seconds=e + line),
            static_axle_loads=truth.static_axle_loads.copy(),
            road_gd0=plan.roads[0 if v.direction > 0 else 1][0],
            road_seed=plan.roads[0 if v.direction > 0 else 1][2],
            contact_lost=bool(truth.contact_lost.any()),
            force_ratio=_force_ratio(layout, passage, truth, rec_time)))
    return SiteEvent(name=name, path=path, kind=plan.kind, date=date, start=start,
                     n_samples=n, strain_factor=factor, temperature=temperature,
                     configuration=plan.configuration, n_vehicles=_most_on_bridge(intervals),
                     vehicles=tuple(vehicles))


# --- writing --------------------------------------------------------------------------------


def _iso(moment: dt.datetime) -> str:
    return moment.isoformat(timespec="microseconds")


def _write_reference(path: Path, events: list[SiteEvent], layout: SiteLayout) -> None:
    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["record", "n_axles", "axle_spacings_m", "axle_weights_kN", "gvw_kN",
                    "speed_m_s", "time", "lane", "direction"])
        for e in events:
            if len(e.vehicles) != 1 or e.vehicles[0].lane not in layout.detector_lanes:
                continue
            v = e.vehicles[0]
            loads = v.static_axle_loads / KILONEWTON
            w.writerow([e.name, v.vehicle.n_axles, joined(v.vehicle.axle_spacings, ".3f"),
                        joined(loads, ".3f"), f"{loads.sum():.3f}", f"{v.speed:.3f}",
                        _iso(v.gauge_time), v.lane, "+x" if v.direction > 0 else "-x"])


def _write_truth(path: Path, events: list[SiteEvent]) -> None:
    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["record", "kind", "date", "vehicle", "trigger", "n_vehicles",
                    "configuration", "vehicle_type", "n_axles", "axle_spacings_m",
                    "axle_weights_kN", "gvw_kN", "steer_kN", "tyres", "loading", "speed_m_s",
                    "lane", "direction", "lane_y_m", "time", "event_start", "strain_factor",
                    "temperature_C", "road_gd0_m3", "road_seed", "contact_lost",
                    "force_ratio_min", "force_ratio_max"])
        for e in events:
            for k, v in enumerate(e.vehicles):
                loads = v.static_axle_loads / KILONEWTON
                w.writerow([e.name, e.kind, e.date.isoformat(), k + 1, str(v.trigger).lower(),
                            e.n_vehicles, e.configuration, v.vehicle_type, v.vehicle.n_axles,
                            joined(v.vehicle.axle_spacings, ".3f"), joined(loads, ".3f"),
                            f"{loads.sum():.3f}", f"{loads[0]:.3f}", ";".join(v.tyres),
                            f"{v.loading:.3f}", f"{v.speed:.3f}", v.lane,
                            "+x" if v.direction > 0 else "-x", f"{v.lane_y:.3f}",
                            _iso(v.gauge_time), _iso(e.start), f"{e.strain_factor:.6f}",
                            f"{e.temperature:.3f}", f"{v.road_gd0:.4e}", v.road_seed,
                            str(v.contact_lost).lower(), f"{v.force_ratio[0]:.4f}",
                            f"{v.force_ratio[1]:.4f}"])


def nominal_bridge(layout: SiteLayout) -> dict:
    """The scenario's ``[bridge]`` table: the model an engineer would start from, the
    layout's measured geometry with nominal concrete (:data:`NOMINAL_MODULUS`,
    :data:`NOMINAL_DENSITY`, not the simulation's), elements of about :data:`MODEL_MESH` m;
    the joints' lines where the layout has joints (an engineer knows them from the
    drawings; their stiffness is for the calibration to find)."""
    return {"kind": "plate", "length": float(layout.span), "width": float(layout.width),
            "nx": max(2, round(layout.span / MODEL_MESH)),
            "ny": max(2, round(layout.width / MODEL_MESH)),
            "thickness": float(layout.thickness), "E": NOMINAL_MODULUS,
            "mu": NOMINAL_DENSITY * float(layout.thickness), "poisson": float(layout.poisson),
            "damping_ratio": float(layout.damping_ratio), "supports": "ss-free",
            **({"joints": [float(j.y) for j in layout.joints]} if layout.joints else {})}


def _write_scenario(path: Path, layout: SiteLayout, truck, loads, temperature: bool) -> None:
    columns = list(layout.columns) + (["temp_C"] if temperature else [])
    xs = {float(g.x) for g in layout.gauges}
    if len(xs) == 1:  # one line of gauges: x once (a list of x and y would be a grid)
        sensors = [{"name": [g.name for g in layout.gauges], "kind": "strain_x",
                    "x": xs.pop(), "y": [float(g.y) for g in layout.gauges]}]
    else:
        sensors = [{"name": g.name, "kind": "strain_x", "x": float(g.x), "y": float(g.y)}
                   for g in layout.gauges]
    if temperature:
        sensors.append({"name": "temp_C", "kind": "temperature"})
    detectors = []
    for lane in layout.detector_lanes:
        pair = layout.lane_detectors(lane)
        detectors.append({"lane": lane, "direction": layout.lane(lane).direction_name,
                          "channels": [d.name for d in pair],
                          "distance": round(abs(pair[1].x - pair[0].x), 6),
                          "y": float(pair[0].y)})
    doc = {
        "bridge": nominal_bridge(layout),
        "logger": {"columns": columns, "sampling_rate": float(layout.sampling_rate)},
        "sensors": sensors,
        "axle_detectors": detectors,
        "vehicle": {"axle_spacings": [float(s) for s in truck.axle_spacings],
                    "axle_loads": [round(float(v), 1) for v in loads]},
    }
    header = (f"A simulated B-WIM installation ({layout.name}, bwim.synthetic).\n"
              "Logger files: calibration/ (the truck below), calibration_day_traffic/, "
              "traffic/.\nThe clock of each file is in its name. Static axle loads in N.")
    with atomic_open(path) as f:
        f.write(to_toml(doc, header=header))


def _drift_table(d: ThermalDrift) -> dict:
    temp = d.temperature
    return {"coefficient_per_C": d.coefficient, "t_ref_C": d.t_ref,
            "nonthermal": d.nonthermal, "nonthermal_period_s": d.period,
            "nonthermal_phase_rad": d.phase, "t_min_s": temp.t_min, "t_max_s": temp.t_max,
            "minimum_C": temp.minimum, "amplitude_C": temp.amplitude}


def _write_site_truth(path: Path, *, seed, mesh, model: _Model, noise, sigma, ref_strain,
                      gauge_gains, det_gain, drift, drifting, dates, approach,
                      roughness) -> None:
    layout = model.layout
    grid = model.bridge.model.grid
    resp = layout.detector_response
    doc = {
        "seed": seed, "layout": layout.name, "note": layout.note,
        "dates": {"calibration": dates[0].isoformat(), "traffic": dates[1].isoformat()},
        "bridge": {"span": layout.span, "width": layout.width,
                   "thickness": layout.thickness, "E": layout.modulus,
                   "poisson": layout.poisson, "mu": layout.density * layout.thickness,
                   "damping_ratio": layout.damping_ratio, "supports": "ss-free",
                   "nx": grid.nx, "ny": grid.ny, "mesh": mesh,
                   "load_spread": list(layout.load_spread),
                   **({} if layout.continuity is None else
                      {"continuous_side_spans": layout.continuity.side_span})},
        "lanes": [{"number": ln.number, "y": ln.y, "direction": ln.direction_name,
                   "heavy_share": ln.heavy_share} for ln in layout.lanes],
        "wander": {"sigma": WANDER[0], "cut": WANDER[1]},
        "gauges": {"name": [g.name for g in layout.gauges], "kind": "strain_x",
                   "x": [g.x for g in layout.gauges], "y": [g.y for g in layout.gauges],
                   "gain": [float(g) for g in gauge_gains], "units": "gain * strain / 1e-6"},
        "axle_detectors": {
            "name": [d.name for d in layout.detectors], "lane": [d.lane for d in layout.detectors],
            "x": [d.x for d in layout.detectors], "y": [d.y for d in layout.detectors],
            "gain": [float(det_gain[d.name]) for d in layout.detectors],
            "width": resp.width, "lateral_sigma": resp.lateral_sigma,
            "dual_spacing": resp.dual_spacing, "global_share_per_microstrain": resp.global_share,
            "global_x": layout.span / 2, "noise_sigma": resp.noise,
            "offset_half_range": resp.offset},
        "noise": {"fraction": noise, "sigma_strain": sigma, "reference_strain": ref_strain,
                  "offset_half_range_strain": OFFSET, "baseline_sigma_in_noise": BASELINE,
                  "temperature_sigma_C": TEMPERATURE_NOISE},
        "drift": {"applied": drifting, "calibration_day": _drift_table(drift[0]),
                  "traffic_day": _drift_table(drift[1])},
        "fleet": {"kinds": list(FLEET_KINDS), "mix": list(FLEET_MIX),
                  "gvw_empty_t": [GVW_RANGE[k][0] for k in FLEET_KINDS],
                  "gvw_full_t": [GVW_RANGE[k][1] for k in FLEET_KINDS]},
        "simulation": {"sampling_rate": layout.sampling_rate, "oversample": OVERSAMPLE,
                       "pre_trigger_samples": PRE_TRIGGER, "post_trigger_s": POST_TRIGGER,
                       "approach_m": approach, "tyre_patch_m": TYRE_PATCH,
                       "roughness_range_m3": list(roughness),
                       "opposite_directions": "simulated apart and superposed"},
    }
    with atomic_open(path) as f:
        f.write(to_toml(doc, header="Hidden facts of the simulated site (not for weighing)."))


def _write_readme(path: Path, layout: SiteLayout, events, dates, temperature: bool) -> None:
    n_cal = sum(e.kind == "calibration" for e in events)
    n_opp = sum(e.kind == "calibration" and e.n_vehicles > 1 for e in events)
    n_cdt = sum(e.kind == "traffic" and e.date == dates[0] for e in events)
    n_tr = sum(e.kind == "traffic" and e.date == dates[1] for e in events)
    cols = list(layout.columns) + (["temp_C"] if temperature else [])
    text = f"""Simulated B-WIM installation {layout.name} (bwim.synthetic)

scenario.toml             the installation's scenario ([bridge] = a nominal starting
                          model, [logger], [[sensors]], [[axle_detectors]],
                          [vehicle] = calibration truck)
calibration/              {n_cal} runs of the calibration truck on {dates[0]}
                          ({n_opp} with a vehicle in the other direction)
calibration_day_traffic/  {n_cdt} traffic events on {dates[0]} (PL<lane>_...)
traffic/                  {n_tr} traffic events on {dates[1]} (PL<lane>_...)
reference.csv             static weights of the single-vehicle traffic events of
                          {dates[1]} in lanes with detectors
truth.csv                 everything simulated, one row per vehicle of every event
site_truth.toml           hidden facts: gauge gains, detectors, noise, drift, dates

Event files: tab-separated, no header, {layout.sampling_rate:g} Hz; columns
{" ".join(cols)}
("-" = digital status). time starts at 0 in every file; the clock time of the first
sample is in the file name: YYYY-MM-DD-HH-MM-SS-mmm. Strain channels in uncalibrated
logger units.
"""
    with atomic_open(path) as f:
        f.write(text)
