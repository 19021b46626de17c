"""Multi-run influence lines and weighing of unknown traffic on a simulated installation
(issue 11): GVW, axle and group errors, gauge combinations, lateral model, scale trend,
and the weighing throughput.

The installation (the user's, simulated): a 9 m × 10 m simply supported slab (Kirchhoff
plate FE, 0.25 m elements, far finer than the influence-line grid), 14 longitudinal strain
gauges across the width at mid-span, the first axle detector 1.5 m onto the deck (the
frame origin of the lines: their support starts near −1.5 m), 512 Hz, 0.25 s of
pre-trigger, absolute gauge noise 0.5 µε (three gauges 3 µε), a random offset per channel
and event, and a strain-to-load ratio drifting 6 % between 7:00 and 18:00 (``drift``).
The calibration truck (5 axles, 3.8 / 6.0 / 1.3 / 1.3 m, ≈ 40 t) runs 12 times between
7:00 and 18:00 at 15–25 m/s with ±0.3 m lateral wander on an ISO class A road (3-D
vehicle model, coupled vehicle–bridge interaction); the traffic is 2-axle, 3-axle and
5-axle trucks of random loads at other times, speeds, wander and road seeds.  Passages
are taken from the simulation's truth (detection is tested elsewhere).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from benchmarks._timing import median_time, print_table
from bwim.dynamics import simulate
from bwim.fe.bridge import Bridge
from bwim.records import Passage, Record
from bwim.road import RoadProfile
from bwim.sensors import Sensor
from bwim.vehicles import library
from bwim.wim.multirun import calibrate_lines
from bwim.wim.weigh import weigh

LENGTH, WIDTH = 9.0, 10.0
DETECTOR_X = 1.5  #: first axle detector, m from the bridge start
FS = 512.0
PRE = 0.25  #: pre-trigger, s
#: Absolute gauge noise (standard deviation), strain: 0.5 µε, three gauges 3 µε (a poor
#: bond, a long cable): what per-gauge weights are for.
NOISE = np.where(np.isin(np.arange(14), (2, 6, 11)), 3e-6, 0.5e-6)
OFFSET = 20e-6  #: offsets uniform in ±OFFSET, strain
LANE = 3.0  #: nominal vehicle centre line, m from the right-hand edge
WANDER = 0.3  #: lateral wander, ± m
APPROACH = 40.0
HOUR = 3600.0


def drift(clock: float) -> float:
    """Strain-to-load ratio over the day (temperature): 1 + 4 % sin(2π (t − 9 h) / 24 h)."""
    return 1.0 + 0.04 * np.sin(2 * np.pi * (clock - 9 * HOUR) / (24 * HOUR))


def bridge(nx: int = 36, ny: int = 40) -> Bridge:
    """The slab: 9 m span, 10 m wide, 0.55 m thick, E = 35 GPa, 2500 kg/m³."""
    return Bridge.plate(length=LENGTH, width=WIDTH, nx=nx, ny=ny, thickness=0.55, E=35e9,
                        mu=0.55 * 2500.0)


def sensors() -> list[Sensor]:
    """14 longitudinal gauges at mid-span, 0.66 m apart across the width."""
    return [Sensor(x=LENGTH / 2, y=float(y), kind="strain_x", name=f"s{k + 1:02d}")
            for k, y in enumerate(np.linspace(0.7, 9.3, 14))]


def calibration_truck():
    """The issue's truck: tractor–semitrailer with spacings 3.8, 6.0, 1.3, 1.3 m."""
    return dataclasses.replace(library.tractor_semitrailer(),
                               axle_spacings=np.array([3.8, 6.0, 1.3, 1.3]))


def traffic_vehicle(rng: np.random.Generator):
    """A random truck: 2-axle, 3-axle (tandem) or 5-axle (tridem), random body mass."""
    kind = rng.integers(3)
    if kind == 0:
        return library.Truck3D.from_axle_loads(
            axle_loads=[rng.uniform(45e3, 70e3), rng.uniform(60e3, 115e3)],
            axle_spacings=[rng.uniform(4.5, 6.0)], wheel_mass=[350.0, 550.0],
            pitch_inertia=65.0e3, roll_inertia=13.0e3, suspension_stiffness=[200e3, 500e3],
            suspension_damping=[5e3, 10e3], tyre_stiffness=[1.75e6, 3.5e6],
            tyre_damping=[1e3, 1e3], track_width=2.0)
    if kind == 1:
        return dataclasses.replace(library.three_axle_truck(),
                                   body_mass=rng.uniform(12e3, 24e3))
    return dataclasses.replace(library.tractor_semitrailer(),
                               trailer_mass=rng.uniform(8e3, 30e3))


@dataclasses.dataclass(frozen=True, kw_only=True, eq=False)
class Event:
    """A logger record, the detected (here: true) passage and the truth."""

    record: Record
    passage: Passage
    static_axle_loads: np.ndarray
    clock: float


def event(bridge: Bridge, gauges: Sequence[Sensor], vehicle, *, speed: float, lane: float,
          clock: float, seed: int, scale: float | None = None, others=(),
          road_class: str = "A", noise=NOISE) -> Event:
    """One event as the logger records it: pre-trigger, crossing and a short tail, scaled
    by ``drift(clock)`` (or ``scale``), noise and offsets added, clock time axis; the
    passage in the detector frame.  ``others``: (vehicle, speed, lane, delay) of further
    vehicles on the bridge (multiple presence), not in the passages."""
    rng = np.random.default_rng(seed)
    crossing = (LENGTH + vehicle.length) / speed
    tail = max(0.1, 1.5 - PRE - crossing)
    vehicles, speeds, lanes, delays = [vehicle], [speed], [lane], [0.0]
    for v, s, y, d in others:
        vehicles.append(v)
        speeds.append(s)
        lanes.append(y)
        delays.append(d)
    road = (RoadProfile.flat() if road_class == "flat" else
            RoadProfile.iso8608(road_class, length=APPROACH + LENGTH + 100.0,
                                start=-(APPROACH + 45.0), seed=seed))
    rec = simulate(bridge, vehicles if others else vehicle,
                   speed=speeds if others else speed, lane=lanes if others else lane,
                   delay=delays if others else 0.0, sensors=gauges, road=road,
                   sampling_rate=FS, approach=APPROACH, tail=tail)
    n_pre = round(PRE * FS)
    data = np.vstack([np.zeros((n_pre, len(gauges))), rec.data])
    data = data * (drift(clock) if scale is None else scale)
    data += rng.uniform(-OFFSET, OFFSET, len(gauges)) + noise * rng.standard_normal(data.shape)
    time = clock + np.arange(data.shape[0]) / FS
    p = rec.passages[0]
    passage = Passage(speed=speed, lane=lane, axle_spacings=p.axle_spacings,
                      track_width=p.track_width, delay=clock + PRE + DETECTOR_X / speed)
    record = Record(time=time, data=data, sensors=tuple(gauges))
    return Event(record=record, passage=passage,
                 static_axle_loads=rec.truths[0].static_axle_loads, clock=clock)


def calibration_day(bridge: Bridge, gauges: Sequence[Sensor], *, n_runs: int = 12,
                    seed: int = 11, road_class: str = "A") -> list[Event]:
    """The calibration truck's runs between 7:00 and 18:00."""
    rng = np.random.default_rng(seed)
    truck = calibration_truck()
    clocks = np.linspace(7 * HOUR, 18 * HOUR, n_runs) + rng.uniform(-600, 600, n_runs)
    return [event(bridge, gauges, truck, speed=rng.uniform(15.0, 25.0),
                  lane=LANE + rng.uniform(-WANDER, WANDER), clock=float(c),
                  seed=1000 + k, road_class=road_class)
            for k, c in enumerate(clocks)]


def traffic(bridge: Bridge, gauges: Sequence[Sensor], *, n: int = 24, seed: int = 23,
            hours: tuple[float, float] = (7.5, 17.5), road_class: str = "A") -> list[Event]:
    """Unknown traffic within the calibrated hours."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        v = traffic_vehicle(rng)
        out.append(event(bridge, gauges, v, speed=rng.uniform(15.0, 25.0),
                         lane=LANE + rng.uniform(-WANDER, WANDER),
                         clock=float(rng.uniform(*hours) * HOUR), seed=5000 + k,
                         road_class=road_class))
    return out


def errors(cal, events: Sequence[Event], **kw) -> dict[str, np.ndarray]:
    """GVW, axle and group errors (%) of weighing ``events`` with ``cal``."""
    gvw, axle, group = [], [], []
    for e in events:
        w = weigh(e.record, e.passage, cal, **kw)
        true = e.static_axle_loads
        gvw.append(100 * (w.gvw / true.sum() - 1))
        axle.extend(100 * (w.axle_weights / true - 1))
        tg = np.array([true[list(g)].sum() for g in w.groups])
        group.extend(100 * (w.group_weights / tg - 1))
    return {"gvw": np.array(gvw), "axle": np.array(axle), "group": np.array(group)}


def _stat(e: np.ndarray) -> str:
    return f"{e.mean():+.2f} ± {e.std(ddof=1):.2f}"


def _rms(e: np.ndarray) -> str:
    return f"{np.sqrt(np.mean(e**2)):.2f}"


def run(*, roads: Sequence[str] = ("A", "flat"), days: Sequence[int] = (11, 12, 13),
        n_traffic: int = 40) -> tuple[list[list[object]], float]:
    """Rows: road, lateral model, scale trend, combination, GVW / axle / group error %
    (mean ± sd and RMS) over ``n_traffic`` trucks on each of ``days`` calibration days;
    and the weighing rate, events/s."""
    br, gauges = bridge(), sensors()
    rows = []
    rate = 0.0
    for road in roads:
        errs: dict[tuple, list[dict[str, np.ndarray]]] = {}
        for seed in days:
            day = calibration_day(br, gauges, seed=seed, road_class=road)
            events = traffic(br, gauges, n=n_traffic, seed=seed + 100, road_class=road)
            recs, pas = [e.record for e in day], [e.passage for e in day]
            for lat in (None, "linear"):
                for scale in (False, True):
                    cal = calibrate_lines(recs, pas, day[0].static_axle_loads, lateral=lat,
                                          per_run_scale=scale)
                    for combine in ("sum", "gls", "blue", "auto"):
                        errs.setdefault((lat, scale, combine), []).append(
                            errors(cal, events, combine=combine))
                    if rate == 0.0 and lat is None and scale:
                        e0 = events[0]
                        rate = 1.0 / median_time(lambda c=cal, e=e0: weigh(e.record,
                                                                             e.passage, c))
        for (lat, scale, combine), parts in errs.items():
            e = {k: np.concatenate([p[k] for p in parts]) for k in ("gvw", "axle", "group")}
            rows.append([road, lat or "none", "trend" if scale else "none", combine,
                         _stat(e["gvw"]), _rms(e["gvw"]), _stat(e["axle"]), _rms(e["axle"]),
                         _stat(e["group"]), _rms(e["group"])])
    return rows, rate


def weigh_test_day(folder: str, *, combine: str = "auto") -> None:
    """Weigh a test day of :func:`bwim.synthetic.make_test_day` end to end: logger files,
    detection by the axle detectors, :func:`calibrate_lines` on the calibration runs
    (detection's flags as upstream flags), :func:`weigh` on the single-vehicle traffic
    events, and the COST 323 classes against ``reference.csv``."""
    import glob
    from pathlib import Path

    from bwim.accuracy import SummaryRow, assess
    from bwim.detect import detect_axles
    from bwim.io import read_logger, read_reference
    from bwim.scenario import load_scenario
    from bwim.scenario.build import build_logger_format, build_sensors, build_vehicle

    root = Path(folder)
    scenario = load_scenario(root / "scenario.toml")
    fmt, gauges = build_logger_format(scenario), build_sensors(scenario)
    loads = build_vehicle(scenario).static_axle_loads

    def load(path):
        record = read_logger(path, fmt, sensors=gauges)
        return record, detect_axles(record, ("ad1", "ad2"), 3.0)

    runs = [load(p) for p in sorted(glob.glob(str(root / "calibration" / "*.txt")))]
    cal = calibrate_lines([r for r, _ in runs], [d.vehicles[0].passage for _, d in runs],
                          loads, run_flags=[d.flags for _, d in runs])
    rows, errs = [], []
    ref = {r.record: r for r in read_reference(root / "reference.csv")}
    for path in sorted(glob.glob(str(root / "traffic" / "*.txt"))):
        record, det = load(path)
        name = Path(path).name
        if det.n_vehicles != 1:
            rows.append(SummaryRow(record=name, gvw=None, axle_weights=(), axle_spacings=(),
                                   n_axles=None, speed=None, flags=tuple(det.flags)))
            continue
        p = det.vehicles[0].passage
        w = weigh(record, p, cal, combine=combine)
        flags = tuple(det.flags) + w.flags
        ok = w.quality != "reject" and "multiple_presence" not in flags
        rows.append(SummaryRow(record=name, gvw=w.gvw if ok else None,
                               axle_weights=tuple(w.axle_weights) if ok else (),
                               axle_spacings=tuple(p.axle_spacings), n_axles=p.n_axles,
                               speed=p.speed, flags=flags))
        if ok and name in ref:
            errs.append(100 * (w.gvw / ref[name].gvw - 1))
    res = assess(rows, list(ref.values()))
    e = np.array(errs)
    print(f"\ntest day {folder} (combine={combine}): {e.size} trucks weighed, GVW error "
          f"{_stat(e)} %, RMS {_rms(e)} %; rejected runs "
          f"{[(r.index, r.reason) for r in cal.rejected]}")
    print_table("COST 323 (RR2, environment I)", ["criterion", "n", "mean %", "sd %", "class"],
                [[c.name, c.n, f"{c.mean:+.2f}", f"{c.std:.2f}", c.class_name]
                 for c in res.criteria] + [["overall", "", "", "", res.overall_class]])


def main() -> None:
    import sys

    if len(sys.argv) > 2 and sys.argv[1] == "--test-day":
        for combine in ("auto", "sum", "gls"):
            weigh_test_day(sys.argv[2], combine=combine)
        return
    rows, rate = run()
    print_table(
        "Multi-run lines, weighing unknown traffic on the simulated 9 m slab: error % "
        "(3 calibration days x 40 trucks per road)",
        ["road", "lateral", "scale", "combine", "GVW mean ± sd", "GVW rms", "axles mean ± sd",
         "axles rms", "groups mean ± sd", "groups rms"], rows)
    print(f"\nweighing throughput: {rate:.0f} events/s (1.5 s at 512 Hz, 14 gauges, one core)")


if __name__ == "__main__":
    main()
