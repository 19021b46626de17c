"""Synthetic logger records for the detection tests (no inverse crime).

The axle-detector pulse here is a raised cosine of 0.3 m base followed by a small negative
lobe (a raised cosine of 0.5 m, 12 % deep, centred 0.4 m behind the axle): a shape that
bwim.detect never assumes (it times peaks by parabolas and the lag by cross-correlation).
Amplitude ∝ axle load, plus absolute Gaussian noise, a constant offset and a linear drift
per channel, different gains per detector.  Strain records come from bwim.simulate on a
fine plate (0.5 m elements) with a pre-trigger of quiet samples, absolute gauge noise,
offsets and drift; detection uses a coarser model's influence line.
"""

from __future__ import annotations

import dataclasses

import numpy as np

import bwim
from bwim.sensors import Sensor

FS = 512.0  #: Hz, the logger's rate
T0 = 36000.0  #: s, clock time of day at the start of an event (10:00)
DISTANCE = 3.0  #: m between the axle detectors
CAL_SPACINGS = (3.8, 6.0, 1.3, 1.3)  #: m, the calibration truck of the issue
CAL_LOADS = (61607.0, 108499.0, 90841.0, 69847.0, 70632.0)  #: N

SPAN, WIDTH = 9.0, 10.0  #: m, the slab
GAUGE_Y = np.linspace(0.5, 9.5, 14)  #: m, 14 gauges across mid-span


def pulse(x: np.ndarray, width: float = 0.3) -> np.ndarray:
    """Detector response to a unit axle at distance ``x`` (m) past the detector."""
    main = np.where(np.abs(x) <= width / 2, np.cos(np.pi * x / width) ** 2, 0.0)
    lobe = np.where(np.abs(x - 0.4) <= 0.25, np.cos(np.pi * (x - 0.4) / 0.5) ** 2, 0.0)
    return main - 0.12 * lobe


def detector_channels(time: np.ndarray, vehicles, *, noise: float = 0.02, seed: int = 0,
                      gains=(1.0, 1.1), offsets=(0.5, -0.3), drifts=(0.2, -0.1),
                      volts_per_newton: float = 1e-5, missed=()) -> np.ndarray:
    """Readings (n_t, 2) of two detectors DISTANCE apart.

    ``vehicles``: (speed m/s, spacings m, loads N, time the first axle passes detector 1 s).
    ``missed``: (detector index, axle index, vehicle index) triples a detector does not see.
    """
    rng = np.random.default_rng(seed)
    t = np.asarray(time, dtype=float)
    out = np.zeros((t.size, 2))
    for c in range(2):
        for k, (v, spacings, loads, t_first) in enumerate(vehicles):
            offs = np.concatenate([[0.0], np.cumsum(spacings)])
            for i, (a, w) in enumerate(zip(offs, loads, strict=True)):
                if (c, i, k) in missed:
                    continue
                out[:, c] += gains[c] * w * volts_per_newton * pulse(
                    v * (t - t_first) - a - c * DISTANCE)
        out[:, c] += offsets[c] + drifts[c] * (t - t[0]) + noise * rng.standard_normal(t.size)
    return out


def detector_sensors() -> list[Sensor]:
    return [Sensor(x=0.0, name="ad1", kind="axle_detector"),
            Sensor(x=DISTANCE, name="ad2", kind="axle_detector")]


def detector_record(vehicles, *, duration: float = 1.5, fs: float = FS, **kw) -> bwim.Record:
    """A record of the two detectors only, starting at clock time T0."""
    t = T0 + np.arange(round(duration * fs)) / fs
    return bwim.Record(time=t, data=detector_channels(t, vehicles, **kw),
                       sensors=detector_sensors())


def gauges() -> list[Sensor]:
    return [Sensor(x=SPAN / 2, y=y, name=f"s{k + 1:02d}") for k, y in enumerate(GAUGE_Y)]


def fine_plate() -> bwim.Bridge:
    """The 'true' slab: 9 m × 10 m, 0.5 m thick, C35 concrete, 0.5 m elements."""
    return bwim.Bridge.plate(length=SPAN, width=WIDTH, nx=18, ny=20, thickness=0.5, E=35e9,
                             mu=1250.0)


def coarse_plate() -> bwim.Bridge:
    """The detection model: 1.5 m × 1.67 m elements, transverse modulus 15 % low."""
    return bwim.Bridge.plate(length=SPAN, width=WIDTH, nx=6, ny=6, thickness=0.5, E_x=35e9,
                             E_y=30e9, mu=1250.0)


def strain_record(bridge, vehicle, *, speed, lane, seed=0, noise=1e-6, pre=0.3, tail=0.4,
                  offsets=True) -> bwim.Record:
    """Simulated gauges (coupled dynamics) at FS with ``pre`` s of quiet samples before
    the first axle reaches x = 0, time shifted to start at T0, absolute noise (strain),
    offsets up to ±20 µε and drifts up to ±5 µε/s per gauge.  Several vehicles: pass
    sequences for vehicle, speed and lane (and their ``delay`` via ``vehicle`` tuples is
    not supported: use :func:`bwim.simulate` directly)."""
    rec = bwim.simulate(bridge, vehicle, speed=speed, lane=lane, sensors=gauges(),
                        sampling_rate=FS, approach=0.0, tail=tail)
    return _finish(rec, seed=seed, noise=noise, pre=pre, offsets=offsets)


def _finish(rec: bwim.Record, *, seed, noise, pre, offsets) -> bwim.Record:
    npre = round(pre * FS)
    t = np.concatenate([rec.time[0] - np.arange(npre, 0, -1) / FS, rec.time])
    data = np.vstack([np.zeros((npre, rec.data.shape[1])), rec.data])
    rng = np.random.default_rng(seed)
    n, m = data.shape
    data = data + noise * rng.standard_normal((n, m))
    if offsets:
        data = data + rng.uniform(-20e-6, 20e-6, m) + rng.uniform(-5e-6, 5e-6, m) * (
            t[:, None] - t[0])
    shift = T0 - t[0]
    passages = tuple(dataclasses.replace(p, delay=p.delay + shift) for p in rec.passages)
    return dataclasses.replace(rec, time=t + shift, data=data, passages=passages, truths=())


def finish_simulated(rec: bwim.Record, **kw) -> bwim.Record:
    """Pre-trigger, noise, offsets and the T0 shift for a record from bwim.simulate."""
    kw.setdefault("seed", 0)
    kw.setdefault("noise", 1e-6)
    kw.setdefault("pre", 0.3)
    kw.setdefault("offsets", True)
    return _finish(rec, **kw)


def with_detectors(rec: bwim.Record, vehicles, **kw) -> bwim.Record:
    """``rec`` with two detector channels added (``vehicles`` as in
    :func:`detector_channels`)."""
    ad = detector_channels(rec.time, vehicles, **kw)
    return dataclasses.replace(rec, data=np.hstack([ad, rec.data]),
                               sensors=(*detector_sensors(), *rec.sensors))


# --- wide detector responses (a real site's: issue 20) ---------------------------------------
#: The wide-response detectors' bridge: a 6 m simply supported span, detectors 1.5 m and
#: 4.5 m from its first support, in the wheel path's lane at y = 0 (lateral offsets of the
#: vehicles are relative to it).
WIDE_SPAN = 6.0
WIDE_X = (1.5, 4.5)


def wide_pulse(u: np.ndarray, lateral: float = 0.0, x_axle: np.ndarray | None = None, *,
               detector_x: float = 1.5, width: float = 0.65, bending: float = 0.25
               ) -> np.ndarray:
    """A detector's reading for a unit axle ``u`` m past it (this test suite's own model,
    not bwim's nor the simulated site's): a local peak ``(1 + (u/width)²)^-1.5`` (full
    width at half maximum ≈ 1.0 m for ``width`` 0.65) of the two wheels 0.9 m either side
    of ``lateral`` seen through a lateral sensitivity ``exp(−½ (dy/1.0)²)``, less
    ``bending`` × the span's bending at the detector (the slab's global response: the
    simply supported moment line, 1 at the detector), which pulls the reading below zero
    between axle groups."""
    u = np.asarray(u, dtype=float)
    local = (1.0 + (u / width) ** 2) ** -1.5
    side = 0.5 * (np.exp(-0.5 * (lateral - 0.9) ** 2) + np.exp(-0.5 * (lateral + 0.9) ** 2))
    x = detector_x + u if x_axle is None else x_axle
    L = WIDE_SPAN
    moment = np.where(x < detector_x, x * (L - detector_x), detector_x * (L - x)) / L
    moment = np.where((x > 0) & (x < L), moment, 0.0) / (detector_x * (L - detector_x) / L)
    return side * local - bending * moment


def wide_channels(time: np.ndarray, vehicles, *, noise: float = 0.01, seed: int = 0,
                  gains=(1.0, 0.25), steer: float = 0.45, offsets=(0.3, -0.2),
                  drifts=(0.1, -0.05), per_newton: float = 1e-5) -> np.ndarray:
    """Readings (n_t, 2) of two wide-response detectors DISTANCE apart (WIDE_X).

    ``vehicles``: (speed m/s, spacings m, loads N, time the first axle passes detector 1
    s, lateral offset m).  The steering axle is seen ``steer`` × its load's share (single
    tyres, narrower: the real sites' 0.2–0.55 of the largest peak); gains differ 4×.
    """
    rng = np.random.default_rng(seed)
    t = np.asarray(time, dtype=float)
    out = np.zeros((t.size, 2))
    for c in range(2):
        for v, spacings, loads, t_first, lat in vehicles:
            offs = np.concatenate([[0.0], np.cumsum(spacings)])
            for i, (a, w) in enumerate(zip(offs, loads, strict=True)):
                x = WIDE_X[0] + v * (t - t_first) - a
                vis = steer if i == 0 else 1.0
                out[:, c] += gains[c] * w * per_newton * vis * wide_pulse(
                    x - WIDE_X[c], lat, x, detector_x=WIDE_X[c])
        out[:, c] += offsets[c] + drifts[c] * (t - t[0])
    scale = np.abs(out - np.median(out[:20], axis=0)).max(axis=0)
    out += noise * scale * rng.standard_normal(out.shape)
    return out


def wide_record(vehicles, *, duration: float = 2.0, fs: float = FS, t0: float = 0.0,
                **kw) -> bwim.Record:
    """A record of the two wide-response detectors (ad1, ad2) from time ``t0``."""
    t = t0 + np.arange(round(duration * fs)) / fs
    return bwim.Record(time=t, data=wide_channels(t, vehicles, **kw),
                       sensors=detector_sensors())


# --- the realistic simulated site (issue 20: bwim.synthetic, "short-span-4-lane") ---------
def site_day(out_dir, *, seed: int, n_traffic: int, n_calibration: int = 12,
             mesh: float = 0.6):
    """A simulated installation (its own finite-element model, vehicle-bridge interaction
    on class A-B roads, detectors with wide local peaks, a negative share of the slab's
    bending, gains 3-5x apart, tyre types and lateral wander; none of it is what
    bwim.detect assumes) read back as the site chain would: returns ``(day, calibration,
    traffic, vehicle)`` with the calibration runs' records, the traffic date's
    ``(record, truth rows)`` pairs and the scenario's calibration truck (spacings, loads)."""
    import csv
    import tomllib
    from collections import defaultdict

    from bwim.io import LoggerFormat, read_logger
    from bwim.synthetic import make_test_day

    day = make_test_day(out_dir, site="short-span-4-lane", seed=seed,
                        n_calibration=n_calibration, n_traffic=n_traffic,
                        n_calibration_day_traffic=0, mesh=mesh)
    scenario = tomllib.loads(day.scenario.read_text())
    columns = tuple(scenario["logger"]["columns"])
    kinds = {c: "axle_detector" for c in columns if c.startswith("ad")}
    fmt = LoggerFormat(columns=columns, sampling_rate=scenario["logger"]["sampling_rate"],
                       kinds=kinds)
    rows = defaultdict(list)
    with open(day.truth, newline="") as f:
        for r in csv.DictReader(f):
            rows[r["record"]].append(r)
    calibration = [read_logger(p, fmt) for p in day.calibration]
    traffic = [(read_logger(p, fmt), rows[p.name]) for p in day.traffic]
    return day, calibration, traffic, scenario["vehicle"]


def site_axles(row) -> tuple[np.ndarray, float, np.ndarray]:
    """Truth of one vehicle (a truth.csv row of a +x lane): the record times its axles
    pass x = 1.5 m (the lane's first detector), its speed (m/s) and axle spacings (m)."""
    import datetime as dt

    v = float(row["speed_m_s"])
    spacings = np.array([float(s) for s in row["axle_spacings_m"].split(";")])
    at_gauges = (dt.datetime.fromisoformat(row["time"])
                 - dt.datetime.fromisoformat(row["event_start"])).total_seconds()
    offsets = np.concatenate([[0.0], np.cumsum(spacings)])
    return at_gauges - 1.5 / v + offsets / v, v, spacings
