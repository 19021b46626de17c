"""A simulated B-WIM test day written as a real installation's files.

Contract
--------
:func:`make_test_day` is the entry point for every simulated site: ``site`` names a
preset of :data:`SITES` (:data:`SITE_NAMES`).  The default, ``basic-2-lane``
(:func:`basic_test_day`, kept as it was: the same files for the same seed), simulates a
day of trucks crossing the slab of :mod:`bwim.synthetic.site` (vehicle–bridge interaction
with :mod:`bwim.dynamics`, each truck on its own ISO 8608 road) and writes what the
installation's logger would have recorded, plus the ground truth, into a new folder (the
realistic ``short-span-4-lane`` preset and its files: :mod:`bwim.synthetic.sitedays`):

``scenario.toml``
    The site's scenario in the shape of an installation without an FE model:
    ``[logger] columns``, ``[[sensors]]`` (names and kind, no positions),
    ``[axle_detectors] channels, distance`` and the calibration truck in ``[vehicle]``
    (nominal axle spacings 3.8, 6.0, 1.3, 1.3 m; static axle loads, N, from the model's
    static equilibrium).  Written last: a folder without it is incomplete.
``calibration/cal_NN_hhmmss.txt``, ``traffic/evt_NNNN_hhmmss.txt``
    One logger file per event (numbered in time order; ``hhmmss`` = clock time of the
    first sample).  Tab-delimited text, one header row, then one row per sample at
    :data:`SAMPLING_RATE` = 512 Hz with the columns (header names)
    ``time ad1 ad2 s01 … s14 temp_C batt_V``:

    * ``time``: clock time of day, s since midnight, written with 9 decimals (exact
      multiples of 1/512 s, so the step is exactly uniform);
    * ``ad1``, ``ad2``: axle detectors at x = 0 and x = 3.0 m (uncalibrated units: gain ×
      axle force in kN × kernel, see :mod:`bwim.synthetic.site`), noise σ 0.2 units and a
      random offset per event;
    * ``s01 … s14``: mid-span soffit strain in **uncalibrated** logger units:
      ``gain_j × (f(t) ε + noise + offset + baseline drift) / 10⁻⁶`` with a per-gauge gain
      ``gain_j`` ∈ [0.95, 1.05] (gauge factors differ), the day's strain factor ``f``
      (:class:`~bwim.synthetic.site.Drift`, ±``drift``), Gaussian white noise of one
      absolute σ (strain) for all gauges = ``noise`` × the calibration truck's peak gauge
      strain (static, lane 1 centre, largest gauge), an offset per channel per event
      uniform in ±50 µε and a linear baseline drift per channel per event whose change
      over the event is normal with σ = 2 noise σ;
    * ``temp_C``, ``batt_V``: deck temperature and logger battery voltage, which the
      scenario skips (``"-"``).

    An event starts :data:`PRE_TRIGGER` (154 samples, 0.30 s) before the first axle
    reaches ``ad1`` (= the bridge's first support, record time 0 of the simulation; the
    bridge is at rest before it) and ends :data:`POST_TRIGGER` = 0.2 s after the last
    axle leaves the bridge, so event lengths vary with speed and vehicle length
    (1.0–2.7 s, median 1.5 s, in the default day).
``reference.csv``
    One row per single-vehicle traffic event (events with two trucks on the bridge are
    for the system to flag, not to weigh: they are in ``truth.csv`` only), the columns of
    ISSUE 11's reference file: ``record, n_axles, axle_spacings_m, axle_weights_kN,
    gvw_kN, speed_m_s``; lists ``;``-separated; ``record`` = event file name; static axle
    loads from the simulation's vehicle models (N → kN, 3 decimals).
``truth.csv``
    One row per vehicle of every event (calibration too): ``record, kind, vehicle,
    n_vehicles, configuration, vehicle_type, n_axles, axle_spacings_m, axle_weights_kN,
    gvw_kN, speed_m_s, lane, lane_y_m, clock_time_s, event_start_s, strain_factor,
    road_gd0_m3, road_seed, contact_lost, force_ratio_min, force_ratio_max`` —
    ``n_vehicles`` is the largest number of
    vehicles on the bridge at once (2 in a multiple-presence event), ``configuration``
    ``single``, ``side_by_side`` (other lane, overlapping) or ``following`` (same lane,
    3–7 m behind), ``lane`` 1 or 2, ``lane_y_m`` the vehicle centre line including wander
    (m from the right-hand edge), ``clock_time_s`` when its first axle passes ``ad1``,
    ``force_ratio_*`` the range of axle force / static axle load while on the bridge.
``site_truth.toml``
    What the installation does not know: bridge, mesh, gauge and detector positions and
    gains, noise σ, drift parameters.
``README.txt``
    This layout in short.

Simulation choices (measured on the calibration truck at 22 m/s, 0.25 m mesh):

* VBI coupled solver (modal, modes up to 128 Hz, static correction) at 1024 Hz, then an
  anti-alias FIR and decimation to 512 Hz (``scipy.signal.resample_poly``).  Against a
  converged 8192 Hz run the gauge strains differ by ≤ 0.43 % of the peak (RMS 0.13 %) on
  a class B road; simulating at 512 Hz directly would give ≤ 1.6 % (RMS 0.54 %), close
  to the 2 % noise σ, so the day pays twice the steps.
* A 60 m run-up (``approach``): the vehicle starts in static equilibrium on its road; its
  start-up transient changes the strains on the bridge by ≤ 0.5 % and the axle forces by
  ≤ 2 % of static compared with a 300 m run-up (0.2 % / 0.5 % with 100 m).
* Each vehicle's road is an ISO 8608 profile with G_d(n₀) log-uniform between the class A
  and class B means (16–64 × 10⁻⁶ m³), two tracks with correlation 0.7–0.95, smoothed
  over a 0.24 m tyre patch; the two trucks of a multiple-presence event share one road.
  On class B roads the axle forces on the bridge range over about 0.5–1.6 × static (the
  axle hop, 12–14 Hz, is near the slab's first mode, 11.9 Hz): the test day is dynamic.
* A linear tyre that loses contact pulls on the road: such an event (1 in the default
  day) is simulated again on a new road (seed + 7919, at most :data:`REDRAWS` times;
  truth gives the road seed used and ``contact_lost`` if every attempt lost contact).
* Truth axle forces exist from record time 0: the detector pulse of a first axle less
  than 0.15 m before ``ad1`` uses the force at time 0.
"""

from __future__ import annotations

import csv
import dataclasses
import inspect
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import resample_poly

from bwim.conventions import KILONEWTON, MICROSTRAIN
from bwim.dynamics.crossing import prepare_crossing, run_crossing
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.io.atomic import atomic_open
from bwim.io.toml_writer import to_toml
from bwim.road import ISO_CLASSES, RoadProfile
from bwim.synthetic import site
from bwim.synthetic.layout import SHORT_SPAN_4_LANE, SiteLayout
from bwim.synthetic.outfolder import checked_count, joined, prepare_folder
from bwim.synthetic.site import Drift
from bwim.synthetic.sitedays import SiteDays, make_site_days
from bwim.synthetic.traffic import (
    TRUCK_KINDS,
    TRUCK_MIX,
    calibration_truck,
    random_truck,
)
from bwim.vehicles.types import TractorSemitrailer, Truck3D

__all__ = ["BASIC_SITE", "COLUMNS", "POST_TRIGGER", "PRE_TRIGGER", "SAMPLING_RATE",
           "SITES", "SITE_NAMES", "Event", "TestDay", "VehicleTruth", "basic_test_day",
           "make_test_day"]

SAMPLING_RATE = 512.0  #: Hz
OVERSAMPLE = 2  #: the simulation runs at OVERSAMPLE × SAMPLING_RATE
EDGE = 0.05  #: s of extra simulated tail, cut after filtering
PRE_TRIGGER = 154  #: samples before the first axle reaches ad1 (0.30 s)
POST_TRIGGER = 0.2  #: s after the last axle leaves the bridge
JUNK = ("temp_C", "batt_V")
#: Column names of a logger file, in order (the header row).
COLUMNS = ("time", *site.DETECTOR_NAMES, *site.GAUGE_NAMES, *JUNK)
DELIMITER = "\t"

OFFSET = 50.0 * MICROSTRAIN  #: half-range of the per-event channel offset (strain)
BASELINE = 2.0  #: σ of a channel's baseline change over an event, in noise σ
DETECTOR_NOISE = 0.2  #: σ of detector noise, logger units
DETECTOR_OFFSET = 2.0  #: half-range of the per-event detector offset, logger units
TYRE_PATCH = 0.24  #: m, road smoothing length
#: Default G_d(n₀) range of the roads, m³/cycle: from the ISO 8608 class A mean to the
#: class B mean (drawn log-uniformly per event).
ROUGHNESS = (ISO_CLASSES["A"], ISO_CLASSES["B"])
#: A WIM-grade approach: within ISO 8608 class A (G_d(n₀) ≤ 16e-6 m³), the even pavement
#: a WIM site asks for (the COST 323 specification grades sites by the pavement's
#: evenness before the sensors; a B-WIM site is chosen on a smooth approach).
WIM_GRADE_ROUGHNESS = (ISO_CLASSES["A"] / 8.0, ISO_CLASSES["A"])
LANE2_SHARE = 0.15  #: share of single traffic vehicles in lane 2
WANDER = 0.3  #: m, half-range of the lateral wander about the lane centre
CAL_SPEED = (18.0, 25.0)  #: m/s
TRAFFIC_SPEED = (21.5, 2.5, 15.0, 25.0)  #: m/s: mean, σ of a normal truncated to [min, max]
MIN_GAP = 20.0  #: s between event starts
REDRAWS = 10  #: attempts at a road on which no wheel loses contact

BASIC_SITE = "basic-2-lane"  #: the default preset: this module's test day
#: The realistic presets by name (layouts simulated by make_site_days).
SITES = {SHORT_SPAN_4_LANE.name: SHORT_SPAN_4_LANE}
SITE_NAMES = (BASIC_SITE, *SITES)


@dataclass(frozen=True, kw_only=True, eq=False)
class VehicleTruth:
    """One vehicle of an event, as simulated."""

    vehicle: Truck3D | TractorSemitrailer
    vehicle_type: str  #: ``calibration`` or one of the traffic kinds
    speed: float  #: m/s
    lane: int  #: 1 or 2
    lane_y: float  #: m, centre line (wander included) from the right-hand edge
    clock_time: float  #: s since midnight when the first axle passes ad1 (x = 0)
    static_axle_loads: np.ndarray  #: N, from the simulation's model
    road_gd0: float  #: m³/cycle
    road_seed: int
    contact_lost: bool
    force_ratio: tuple[float, float]  #: min, max of axle force / static load on the bridge


@dataclass(frozen=True, kw_only=True, eq=False)
class Event:
    """One written event file."""

    name: str  #: file name
    path: Path
    kind: str  #: ``calibration`` or ``traffic``
    start_time: float  #: clock time of the first sample, s
    n_samples: int
    strain_factor: float
    configuration: str  #: ``single``, ``side_by_side`` or ``following``
    n_vehicles: int  #: most vehicles on the bridge at once
    vehicles: tuple[VehicleTruth, ...]


@dataclass(frozen=True, kw_only=True, eq=False)
class TestDay:
    """What :func:`make_test_day` wrote (paths) and the hidden facts of the site."""

    __test__ = False  # not a pytest test class

    out_dir: Path
    scenario: Path
    calibration: tuple[Path, ...]
    traffic: tuple[Path, ...]
    reference: Path
    truth: Path
    site_truth: Path
    readme: Path
    events: tuple[Event, ...]
    seed: int
    mesh: float  #: m, data mesh element size (upper bound)
    sampling_rate: float  #: Hz
    noise_sigma: float  #: gauge noise σ, strain
    reference_strain: float  #: the calibration truck's peak gauge strain (static)
    gauge_gains: tuple[float, ...]
    detector_gains: tuple[float, ...]
    drift: Drift
    calibration_axle_loads: tuple[float, ...]  #: N, static


@dataclass(frozen=True, kw_only=True, eq=False)
class _Plan:
    kind: str
    clock: float  # s, record time 0 (first axle at x = 0), multiple of 1/fs
    configuration: str
    vehicles: tuple
    types: tuple[str, ...]
    speeds: tuple[float, ...]
    lanes: tuple[int, ...]
    lane_y: tuple[float, ...]
    delays: tuple[float, ...]
    road_gd0: float
    road_corr: float
    road_seed: int
    noise_seed: np.random.SeedSequence


def make_test_day(
    out_dir: str | os.PathLike,
    *,
    site: str | SiteLayout = BASIC_SITE,
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> TestDay | SiteDays:
    """Simulate an installation's test data and write it to the new folder ``out_dir``.

    ``site`` names a preset of :data:`SITES`: ``"basic-2-lane"`` (the default; this
    module's day, the same files for the same seed as before presets existed; options
    those of :func:`basic_test_day`) or ``"short-span-4-lane"`` (a realistic site with a
    calibration date and a traffic date: :func:`bwim.synthetic.sitedays.make_site_days`
    with :data:`~bwim.synthetic.layout.SHORT_SPAN_4_LANE`, whose keywords are its
    options).  A :class:`~bwim.synthetic.layout.SiteLayout` instance is simulated like
    the realistic preset.  ``progress(done, total)`` is called after each event file.
    An option the site does not have is an :class:`~bwim.errors.InputError`.
    """
    if isinstance(site, SiteLayout):
        layout = site
    elif site == BASIC_SITE:
        _check_options(basic_test_day, options, site)
        return basic_test_day(out_dir, progress=progress, **options)
    elif site in SITES:
        layout = SITES[site]
    else:
        raise InputError(f"unknown site {site!r}; expected one of {', '.join(SITE_NAMES)}")
    _check_options(make_site_days, options, layout.name, exclude=("layout",))
    return make_site_days(out_dir, layout=layout, progress=progress, **options)


def _check_options(fn, options: dict, site: str, exclude=()) -> None:
    allowed = [p.name for p in inspect.signature(fn).parameters.values()
               if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name not in exclude
               and p.name != "progress"]
    for key in options:
        if key not in allowed:
            raise InputError(f"{key!r} is not an option of site {site}; its options are "
                             f"{', '.join(allowed)}")


def basic_test_day(
    out_dir: str | os.PathLike,
    *,
    seed: int = 0,
    n_calibration: int = 12,
    n_traffic: int = 100,
    n_multiple: int | None = None,
    mesh: float = 0.25,
    noise: float = 0.02,
    drift: float = 0.08,
    approach: float = 60.0,
    roughness: tuple[float, float] = ROUGHNESS,
    progress: Callable[[int, int], None] | None = None,
) -> TestDay:
    """Simulate the ``basic-2-lane`` test day and write it to the new folder ``out_dir``.

    Parameters
    ----------
    out_dir : path
        Output folder: created (with parents) if missing; an existing non-empty folder is
        refused.
    seed : int
        All randomness derives from it.
    n_calibration : int
        Runs of the calibration truck (lane 1, 18–25 m/s), spread over 07:00–18:00.
    n_traffic : int
        Traffic event files (06:00–20:00); ``n_multiple`` of them hold two trucks.
    n_multiple : int, optional
        Multiple-presence events; default ``max(1, round(0.04 n_traffic))`` (0 without
        traffic).
    mesh : float
        Data-mesh element size, m, in [0.1, 0.6] (finer than a 0.75 m weighing model).
    noise : float
        Gauge noise σ as a fraction of the calibration truck's peak gauge strain.
    drift : float
        Amplitude of the strain factor's variation over the day (0.08: ±8 %).
    approach : float
        Run-up of each vehicle on its road before the bridge, m.
    roughness : (float, float)
        Range of the roads' G_d(n₀), m³/cycle (drawn log-uniformly per event); default
        :data:`ROUGHNESS`, class A to B; :data:`WIM_GRADE_ROUGHNESS` is a smooth approach.
    progress : callable, optional
        Called as ``progress(done, total)`` after each event file.

    Returns
    -------
    TestDay
    """
    if progress is not None and not callable(progress):
        raise InputError("progress must be a callable (done, total) or None")
    n_calibration = checked_count("n_calibration", n_calibration, 1)
    n_traffic = checked_count("n_traffic", n_traffic, 0)
    if n_multiple is None:
        n_multiple = max(1, round(0.04 * n_traffic)) if n_traffic else 0
    n_multiple = checked_count("n_multiple", n_multiple, 0)
    if n_multiple > n_traffic:
        raise InputError(f"n_multiple ({n_multiple}) exceeds n_traffic ({n_traffic})")
    if not isinstance(mesh, (int, float)) or not 0.1 <= mesh <= 0.6:
        raise InputError(f"mesh must be an element size in [0.1, 0.6] m, got {mesh!r}")
    if not isinstance(noise, (int, float)) or not 0 <= noise < 1:
        raise InputError(f"noise must be a fraction in [0, 1), got {noise!r}")
    if not isinstance(approach, (int, float)) or not 0 <= approach <= 500:
        raise InputError(f"approach must be in [0, 500] m, got {approach!r}")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    if not isinstance(drift, (int, float)) or not 0 <= drift < 1:
        raise InputError(f"drift must be a fraction in [0, 1), got {drift!r}")
    try:
        lo_r, hi_r = (float(v) for v in roughness)
    except (TypeError, ValueError):
        raise InputError(f"roughness must be two numbers (m³/cycle), got {roughness!r}") from None
    if not 0 < lo_r <= hi_r < 1e-3:
        raise InputError(f"roughness must be 0 < low <= high < 1e-3 m³/cycle, got {roughness!r}")
    out = prepare_folder(out_dir)

    root = np.random.SeedSequence(int(seed))
    site_ss, plan_ss = root.spawn(2)
    site_rng = np.random.default_rng(site_ss)
    day_drift = Drift.random(drift, site_rng)
    gauge_gains = site_rng.uniform(0.95, 1.05, len(site.GAUGE_NAMES))
    detector_gains = site_rng.uniform(0.8, 1.2, len(site.DETECTOR_NAMES))

    fs = SAMPLING_RATE
    bridge = site.site_bridge(mesh)
    spread = site.gauge_points()
    points, weights = list(spread.points), spread.weights
    influence = bridge.influence(points)
    cal_truck = calibration_truck()
    cal_loads = cal_truck.model().static_axle_loads
    ref_strain = _peak_static_strain(influence, weights, cal_truck, cal_loads)
    sigma = noise * ref_strain

    plans = _plan_day(plan_ss, n_calibration, n_traffic, n_multiple, cal_truck, fs,
                      (lo_r, hi_r))
    (out / "calibration").mkdir()
    (out / "traffic").mkdir()
    events = []
    counters = {"calibration": 0, "traffic": 0}
    for k, plan in enumerate(plans):
        counters[plan.kind] += 1
        events.append(_simulate_and_write(
            plan, counters[plan.kind], out, bridge=bridge, points=points, weights=weights,
            influence=influence, approach=float(approach), drift=day_drift, sigma=sigma,
            gauge_gains=gauge_gains, detector_gains=detector_gains, fs=fs))
        if progress is not None:
            progress(k + 1, len(plans))

    reference = out / "reference.csv"
    truth = out / "truth.csv"
    _write_reference(reference, [e for e in events if e.kind == "traffic"])
    _write_truth(truth, events)
    site_truth = out / "site_truth.toml"
    _write_site_truth(site_truth, seed=int(seed), mesh=float(mesh), bridge=bridge, noise=noise,
                      sigma=sigma, ref_strain=ref_strain, gauge_gains=gauge_gains,
                      detector_gains=detector_gains, drift=day_drift, approach=approach,
                      roughness=(lo_r, hi_r))
    readme = out / "README.txt"
    _write_readme(readme, n_calibration, n_traffic, n_multiple)
    scenario = out / "scenario.toml"
    _write_scenario(scenario, cal_truck, cal_loads)
    return TestDay(
        out_dir=out, scenario=scenario,
        calibration=tuple(e.path for e in events if e.kind == "calibration"),
        traffic=tuple(e.path for e in events if e.kind == "traffic"),
        reference=reference, truth=truth, site_truth=site_truth, readme=readme,
        events=tuple(events), seed=int(seed), mesh=float(mesh), sampling_rate=fs,
        noise_sigma=float(sigma), reference_strain=float(ref_strain),
        gauge_gains=tuple(float(g) for g in gauge_gains),
        detector_gains=tuple(float(g) for g in detector_gains), drift=day_drift,
        calibration_axle_loads=tuple(float(v) for v in cal_loads),
    )


# --- validation -----------------------------------------------------------------------------




# --- planning -------------------------------------------------------------------------------
def _kinds(n: int, rng: np.random.Generator) -> list[str]:
    """Truck kinds in the proportions of TRUCK_MIX (largest remainder), shuffled."""
    share = np.asarray(TRUCK_MIX) * n
    counts = np.floor(share).astype(int)
    if n >= len(TRUCK_KINDS):  # every kind at least once
        counts = np.maximum(counts, 1)
    order = np.argsort(-(share - np.floor(share)), kind="stable")
    k = 0
    while counts.sum() < n:
        counts[order[k % len(order)]] += 1
        k += 1
    while counts.sum() > n:
        counts[int(np.argmax(counts))] -= 1
    kinds = [kd for kd, c in zip(TRUCK_KINDS, counts, strict=True) for _ in range(c)]
    return [kinds[i] for i in rng.permutation(len(kinds))]


def _event_times(rng, n_cal, n_traffic, fs):
    """Clock times (s) of record time 0 of every event, at least MIN_GAP apart."""
    span = (18 - 7) * 3600.0 / n_cal
    cal = 7 * 3600.0 + span * (np.arange(n_cal) + 0.5 + rng.uniform(-0.3, 0.3, n_cal))
    lo, hi = site.DAY[0] + 60.0, site.DAY[1] - 60.0 - MIN_GAP * (n_cal + n_traffic)
    traffic = rng.uniform(lo, hi, n_traffic)
    kinds = np.array(["calibration"] * n_cal + ["traffic"] * n_traffic)
    t = np.concatenate([cal, traffic])
    order = np.argsort(t, kind="stable")
    t, kinds = t[order], kinds[order]
    for i in range(1, t.size):
        t[i] = max(t[i], t[i - 1] + MIN_GAP)
    return np.round(t * fs) / fs, kinds


def _traffic_speed(rng: np.random.Generator) -> float:
    """A normal speed truncated to [min, max] (redrawn until inside)."""
    mean, sd, vmin, vmax = TRAFFIC_SPEED
    while True:
        v = rng.normal(mean, sd)
        if vmin <= v <= vmax:
            return float(v)


def _plan_day(ss, n_cal, n_traffic, n_multiple, cal_truck, fs, roughness) -> list[_Plan]:
    schedule_ss, *event_seeds = ss.spawn(1 + n_cal + n_traffic)
    rng = np.random.default_rng(schedule_ss)
    times, kinds = _event_times(rng, n_cal, n_traffic, fs)
    n_trucks = n_traffic + n_multiple
    truck_kinds = iter(_kinds(n_trucks, rng))
    multiple = set(rng.choice(n_traffic, n_multiple, replace=False).tolist())
    plans, i_traffic, i_multi = [], 0, 0
    for clock, kind, ess in zip(times, kinds, event_seeds, strict=True):
        plan_ss, noise_ss = ess.spawn(2)
        r = np.random.default_rng(plan_ss)
        road = (float(np.exp(r.uniform(*np.log(roughness)))), float(r.uniform(0.7, 0.95)),
                int(r.integers(2**31)))
        if kind == "calibration":
            plans.append(_Plan(
                kind=str(kind), clock=float(clock), configuration="single",
                vehicles=(cal_truck,), types=("calibration",),
                speeds=(float(r.uniform(*CAL_SPEED)),), lanes=(1,),
                lane_y=(site.LANE_Y[0] + float(r.uniform(-WANDER, WANDER)),), delays=(0.0,),
                road_gd0=road[0], road_corr=road[1], road_seed=road[2], noise_seed=noise_ss))
            continue
        first = next(truck_kinds)
        types = [first]
        speeds = [_traffic_speed(r)]
        lanes = [2 if r.uniform() < LANE2_SHARE else 1]
        delays = [0.0]
        vehicles = [random_truck(first, r)]
        configuration = "single"
        if i_traffic in multiple:
            configuration = "following" if i_multi % 3 == 2 else "side_by_side"
            i_multi += 1
            second = next(truck_kinds)
            types.append(second)
            vehicles.append(random_truck(second, r))
            if configuration == "following":
                speeds.append(speeds[0])
                lanes.append(lanes[0])
                gap = r.uniform(3.0, 7.0)
                delays.append((vehicles[0].length + gap) / speeds[0])
            else:
                speeds.append(_traffic_speed(r))
                lanes.append(3 - lanes[0])
                delays.append(float(r.uniform(0.0, 0.4)))
        lane_y = [site.LANE_Y[ln - 1] + float(r.uniform(-WANDER, WANDER)) for ln in lanes]
        plans.append(_Plan(
            kind=str(kind), clock=float(clock), configuration=configuration,
            vehicles=tuple(vehicles), types=tuple(types), speeds=tuple(speeds),
            lanes=tuple(lanes), lane_y=tuple(lane_y), delays=tuple(delays),
            road_gd0=road[0], road_corr=road[1], road_seed=road[2], noise_seed=noise_ss))
        i_traffic += 1
    return plans


# --- simulation -------------------------------------------------------------------------------
def _peak_static_strain(influence, weights, truck, loads) -> float:
    """Largest gauge strain under the truck's static loads along lane 1's centre line."""
    offsets = truck.axle_offsets
    front = np.arange(0.0, site.SPAN + offsets[-1] + 0.025, 0.025)
    xw = front[:, None] - np.repeat(offsets, 2)[None, :]
    half = truck.track_width / 2
    yw = np.tile([site.LANE_Y[0] - half, site.LANE_Y[0] + half], offsets.size)
    pw = np.repeat(loads / 2, 2)
    ordinates = influence.at(xw.ravel(), np.broadcast_to(yw, xw.shape).ravel())
    gauge = (ordinates @ weights).reshape(*xw.shape, -1)  # (position, wheel, gauge)
    return float(np.max(np.einsum("w,pws->ps", pw, gauge)))


def _road(plan: _Plan, approach: float) -> RoadProfile:
    t_start = min(d - approach / v for d, v in zip(plan.delays, plan.speeds, strict=True))
    t_end = max(d + (site.SPAN + veh.length) / v
                for d, v, veh in zip(plan.delays, plan.speeds, plan.vehicles, strict=True))
    t_end += POST_TRIGGER + 0.05
    lo = min(v * (t_start - d) - veh.length
             for d, v, veh in zip(plan.delays, plan.speeds, plan.vehicles, strict=True))
    hi = max(v * (t_end - d) for d, v in zip(plan.delays, plan.speeds, strict=True))
    start = lo - 5.0
    return RoadProfile.iso8608(plan.road_gd0, length=hi + 5.0 - start, start=start,
                               seed=plan.road_seed,
                               track_correlation=plan.road_corr).smoothed(TYRE_PATCH)


def _simulate(plan: _Plan, bridge, points, weights, influence, approach, fs):
    """Gauge strain at ``fs`` from record time 0 to POST_TRIGGER after the last axle leaves.

    Simulated at ``OVERSAMPLE × fs`` with EDGE s more tail, the bridge at rest before time
    0 (zeros), low-pass filtered and decimated (:func:`scipy.signal.resample_poly`, a
    Kaiser-windowed FIR with its delay compensated), then cut.
    """
    prepared = prepare_crossing(
        bridge, list(plan.vehicles), speed=list(plan.speeds), sensors=points,
        lane=list(plan.lane_y), road=_road(plan, approach), sampling_rate=OVERSAMPLE * fs,
        approach=approach, tail=POST_TRIGGER + EDGE, delay=list(plan.delays))
    rec = run_crossing(prepared, bridge, influence=influence, warn=False)
    fine = rec.data @ weights  # (n_t, 14) noise-free soffit strain, t = 0, 1/(q fs), ...
    lead = OVERSAMPLE * PRE_TRIGGER
    padded = np.vstack([np.zeros((lead, fine.shape[1])), fine])
    coarse = resample_poly(padded, 1, OVERSAMPLE, axis=0)[PRE_TRIGGER:]
    t_end = max(p.delay + (site.SPAN + p.axle_offsets[-1]) / p.speed
                for p in rec.passages) + POST_TRIGGER
    n = int(np.floor(t_end * fs + 1e-9)) + 1
    return coarse[:n], np.arange(n) / fs, rec


def _simulate_and_write(plan: _Plan, number: int, out: Path, *, bridge: Bridge, points,
                        weights, influence, approach, drift: Drift, sigma, gauge_gains,
                        detector_gains, fs) -> Event:
    for _ in range(REDRAWS):
        strain, time, rec = _simulate(plan, bridge, points, weights, influence, approach, fs)
        if not any(t.contact_lost.any() for t in rec.truths):
            break
        plan = dataclasses.replace(plan, road_seed=(plan.road_seed + 7919) % 2**31)
    n = PRE_TRIGGER + time.size
    t_rel = (np.arange(n) - PRE_TRIGGER) / fs
    strain = np.vstack([np.zeros((PRE_TRIGGER, strain.shape[1])), strain])

    # axle detectors: gain × Σ axle force (kN) × kernel(x_axle − x_detector)
    pulses = np.zeros((n, len(site.DETECTOR_X)))
    for passage, truth in zip(rec.passages, rec.truths, strict=True):
        at = truth.axle_forces[::OVERSAMPLE][:time.size]
        force = np.vstack([np.repeat(at[:1], PRE_TRIGGER, axis=0), at]) / KILONEWTON
        x_axle = passage.speed * (t_rel[:, None] - passage.delay) - passage.axle_offsets
        for k, xd in enumerate(site.DETECTOR_X):
            pulses[:, k] += np.sum(force * site.detector_kernel(x_axle - xd), axis=1)

    rng = np.random.default_rng(plan.noise_seed)
    clock0 = plan.clock
    start = clock0 - PRE_TRIGGER / fs
    factor = float(drift.factor(clock0))
    n_g = strain.shape[1]
    offset = rng.uniform(-OFFSET, OFFSET, n_g)
    slope = rng.normal(0.0, BASELINE * sigma, n_g) / (t_rel[-1] - t_rel[0])
    measured = (factor * strain + sigma * rng.standard_normal((n, n_g)) + offset
                + slope * (t_rel - t_rel[0])[:, None])
    gauges = np.asarray(gauge_gains) * measured / MICROSTRAIN
    detectors = (np.asarray(detector_gains) * pulses
                 + DETECTOR_NOISE * rng.standard_normal(pulses.shape)
                 + rng.uniform(-DETECTOR_OFFSET, DETECTOR_OFFSET, pulses.shape[1]))
    hours = clock0 / 3600.0
    temp = 14.0 + 8.0 * np.sin(2 * np.pi * (hours - 9.0) / 24.0) + 0.05 * rng.standard_normal(n)
    batt = 12.8 - 0.4 * (hours - 6.0) / 14.0 + 0.005 * rng.standard_normal(n)

    stamp = _hhmmss(start)
    if plan.kind == "calibration":
        name, folder = f"cal_{number:02d}_{stamp}.txt", out / "calibration"
    else:
        name, folder = f"evt_{number:04d}_{stamp}.txt", out / "traffic"
    path = folder / name
    table = np.column_stack([start + np.arange(n) / fs, detectors, gauges, temp, batt])
    fmt = ["%.9f"] + ["%.3f"] * (detectors.shape[1] + n_g) + ["%.2f", "%.3f"]
    with atomic_open(path, newline="") as f:
        np.savetxt(f, table, fmt=fmt, delimiter=DELIMITER, header=DELIMITER.join(COLUMNS),
                   comments="", newline="\n")

    vehicles = tuple(
        VehicleTruth(vehicle=veh, vehicle_type=typ, speed=float(v), lane=int(ln),
                     lane_y=float(y), clock_time=clock0 + p.delay,
                     static_axle_loads=tr.static_axle_loads.copy(), road_gd0=plan.road_gd0,
                     road_seed=plan.road_seed, contact_lost=bool(tr.contact_lost.any()),
                     force_ratio=_force_ratio(p, tr, rec.time))
        for veh, typ, v, ln, y, p, tr in zip(plan.vehicles, plan.types, plan.speeds,
                                             plan.lanes, plan.lane_y, rec.passages,
                                             rec.truths, strict=True))
    return Event(name=name, path=path, kind=plan.kind, start_time=start, n_samples=n,
                 strain_factor=factor, configuration=plan.configuration,
                 n_vehicles=_most_on_bridge(rec.passages), vehicles=vehicles)


def _force_ratio(passage, truth, time) -> tuple[float, float]:
    """Least and largest axle force / static axle load while the axle is on the bridge."""
    x = passage.speed * (time[:, None] - passage.delay) - passage.axle_offsets
    on = (x >= 0) & (x <= site.SPAN)
    ratio = truth.axle_forces / truth.static_axle_loads
    return float(ratio[on].min()), float(ratio[on].max())


def _most_on_bridge(passages) -> int:
    """Largest number of vehicles with an axle on the bridge at the same time."""
    spans = [(p.delay, p.delay + (site.SPAN + p.axle_offsets[-1]) / p.speed) for p in passages]
    ends = sorted([(a, 1) for a, _ in spans] + [(b, -1) for _, b in spans],
                  key=lambda e: (e[0], e[1]))
    most = count = 0
    for _, step in ends:
        count += step
        most = max(most, count)
    return most


def _hhmmss(clock: float) -> str:
    s = int(np.floor(clock))
    return f"{s // 3600:02d}{s % 3600 // 60:02d}{s % 60:02d}"


# --- writing --------------------------------------------------------------------------------


def _write_reference(path: Path, events: list[Event]) -> None:
    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["record", "n_axles", "axle_spacings_m", "axle_weights_kN", "gvw_kN",
                    "speed_m_s"])
        for e in events:
            if len(e.vehicles) != 1:  # flagged by a B-WIM system, not weighed: truth.csv only
                continue
            for v in e.vehicles:
                loads = v.static_axle_loads / KILONEWTON
                w.writerow([e.name, v.vehicle.n_axles, joined(v.vehicle.axle_spacings, ".3f"),
                            joined(loads, ".3f"), f"{loads.sum():.3f}", f"{v.speed:.3f}"])


def _write_truth(path: Path, events: list[Event]) -> None:
    with atomic_open(path, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["record", "kind", "vehicle", "n_vehicles", "configuration",
                    "vehicle_type", "n_axles", "axle_spacings_m", "axle_weights_kN",
                    "gvw_kN", "speed_m_s", "lane", "lane_y_m", "clock_time_s",
                    "event_start_s", "strain_factor", "road_gd0_m3", "road_seed",
                    "contact_lost", "force_ratio_min", "force_ratio_max"])
        for e in events:
            for k, v in enumerate(e.vehicles):
                loads = v.static_axle_loads / KILONEWTON
                w.writerow([e.name, e.kind, k + 1, e.n_vehicles, e.configuration,
                            v.vehicle_type, v.vehicle.n_axles,
                            joined(v.vehicle.axle_spacings, ".3f"), joined(loads, ".3f"),
                            f"{loads.sum():.3f}", f"{v.speed:.3f}", v.lane, f"{v.lane_y:.3f}",
                            f"{v.clock_time:.9f}", f"{e.start_time:.9f}",
                            f"{e.strain_factor:.6f}", f"{v.road_gd0:.4e}", v.road_seed,
                            str(v.contact_lost).lower(), f"{v.force_ratio[0]:.4f}",
                            f"{v.force_ratio[1]:.4f}"])


def _write_scenario(path: Path, truck, loads) -> None:
    doc = {
        "logger": {"columns": ["time", *site.DETECTOR_NAMES, *site.GAUGE_NAMES, "-", "-"]},
        "sensors": [{"name": list(site.GAUGE_NAMES), "kind": "strain_x"}],
        "axle_detectors": {"channels": list(site.DETECTOR_NAMES),
                           "distance": float(site.DETECTOR_X[1] - site.DETECTOR_X[0])},
        "vehicle": {"axle_spacings": [float(s) for s in truck.axle_spacings],
                    "axle_loads": [round(float(v), 1) for v in loads]},
    }
    header = ("A simulated B-WIM test day (bwim.synthetic.make_test_day).\n"
              "Logger files: calibration/cal_*.txt (the truck below), traffic/evt_*.txt.\n"
              "The calibration truck: static axle loads in N.")
    with atomic_open(path) as f:
        f.write(to_toml(doc, header=header))


def _write_site_truth(path: Path, *, seed, mesh, bridge: Bridge, noise, sigma, ref_strain,
                      gauge_gains, detector_gains, drift: Drift, approach, roughness
                      ) -> None:
    grid = bridge.model.grid
    doc = {
        "seed": seed,
        "bridge": {"span": site.SPAN, "width": site.WIDTH, "thickness": site.THICKNESS,
                   "E": site.MODULUS, "poisson": site.POISSON,
                   "mu": site.DENSITY * site.THICKNESS, "damping_ratio": site.DAMPING_RATIO,
                   "supports": "ss-free", "nx": grid.nx, "ny": grid.ny, "mesh": mesh,
                   "load_spread": list(site.SPREAD)},
        "lanes": {"y": list(site.LANE_Y), "wander": WANDER},
        "gauges": {"name": list(site.GAUGE_NAMES), "kind": "strain_x", "x": site.GAUGE_X,
                   "y": list(site.GAUGE_Y), "gain": [float(g) for g in gauge_gains],
                   "units": "gain * strain / 1e-6"},
        "axle_detectors": {"name": list(site.DETECTOR_NAMES), "x": list(site.DETECTOR_X),
                           "kernel_width": site.DETECTOR_WIDTH,
                           "gain": [float(g) for g in detector_gains],
                           "units": "gain * axle force (kN) * kernel",
                           "noise_sigma": DETECTOR_NOISE},
        "noise": {"fraction": noise, "sigma_strain": sigma, "reference_strain": ref_strain,
                  "offset_half_range_strain": OFFSET, "baseline_sigma_in_noise": BASELINE},
        "drift": {"amplitude": drift.amplitude, "periods_s": drift.periods.tolist(),
                  "phases_rad": drift.phases.tolist(), "weights": drift.weights.tolist(),
                  "norm": drift.norm},
        "simulation": {"sampling_rate": SAMPLING_RATE, "pre_trigger_samples": PRE_TRIGGER,
                       "post_trigger_s": POST_TRIGGER, "approach_m": approach,
                       "tyre_patch_m": TYRE_PATCH, "roughness_range_m3": list(roughness)},
    }
    with atomic_open(path) as f:
        f.write(to_toml(doc, header="Hidden facts of the simulated site (not for weighing)."))


def _write_readme(path: Path, n_cal: int, n_traffic: int, n_multiple: int) -> None:
    text = f"""Simulated B-WIM test day (bwim.synthetic.make_test_day)

scenario.toml          the installation's scenario ([logger], [[sensors]],
                       [axle_detectors], [vehicle] = calibration truck)
calibration/           {n_cal} runs of the calibration truck: cal_NN_hhmmss.txt
traffic/               {n_traffic} traffic events ({n_multiple} with two trucks):
                       evt_NNNN_hhmmss.txt
reference.csv          static weights of the traffic (single-vehicle events)
truth.csv              everything simulated, one row per vehicle of every event
site_truth.toml        gauge positions and gains, noise, drift (hidden from weighing)

Event files: tab-delimited, one header row, 512 Hz; columns
{" ".join(COLUMNS)}
time = clock time of day (s since midnight); strain channels in uncalibrated units.
"""
    with atomic_open(path) as f:
        f.write(text)
