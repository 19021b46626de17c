"""Vehicle detection on synthetic logger records (no inverse crime).

Data (tests/detect_data.py): axle-detector pulses of a raised-cosine kernel with a
negative lobe that the detector never assumes, amplitude ∝ axle load, absolute noise,
offsets, drifts and unequal gains, at 512 Hz; strain from bwim.simulate (coupled
dynamics) on a fine 0.5 m mesh of a 9 m × 10 m slab with absolute gauge noise (1 µε),
offsets and drifts.  The strain-only path inverts with a coarse 1.5 m model (transverse
modulus 15 % low) or a line calibrated from other crossings.

References: the true speeds, spacings, arrival times and lanes of the simulation; the
targets of the brief (speed within 0.3 % at 512 Hz, spacings within 0.1 m, the tridem's
1.3 m at 25 m/s resolved, detection well under 5 ms per 1.5 s event).  Measured values
are in each test's docstring; the tolerances are about 2–3× them.
"""

import time

import numpy as np
import pytest

import bwim
from bwim.detect import (
    FLAG_COUNT_MISMATCH,
    FLAG_MULTIPLE_PRESENCE,
    FLAG_NO_AXLES,
    FLAG_STRAIN_ONLY,
    FLAG_UNEXPLAINED_STRAIN,
    detect_axles,
    detect_from_strain,
)
from bwim.vehicles import MovingForces
from bwim.wim import calibrate_influence_line, model_influence_line

from tests.detect_data import (
    CAL_LOADS,
    CAL_SPACINGS,
    FS,
    T0,
    coarse_plate,
    detector_record,
    fine_plate,
    finish_simulated,
    gauges,
    strain_record,
    with_detectors,
)

SPEEDS = (18.0, 20.0, 22.0, 25.0)


def _truck() -> MovingForces:
    return MovingForces(axle_loads=CAL_LOADS, axle_spacings=CAL_SPACINGS, track_width=2.0)


@pytest.fixture(scope="module")
def plate():
    return fine_plate()


# --- axle detectors ------------------------------------------------------------------------

@pytest.mark.parametrize(("noise", "max_speed", "max_spacing", "max_delay"), [
    (0.02, 0.002, 0.025, 1e-3),   # measured 0.084 % (rms 0.030 %), 9.5 mm, 0.40 ms
    (0.05, 0.003, 0.06, 2.5e-3),  # measured 0.19 % (rms 0.073 %), 26 mm, 1.0 ms
])
def test_speed_spacings_and_arrival_from_detectors(noise, max_speed, max_spacing, max_delay):
    """The calibration truck at 18–25 m/s, 10 noise seeds each, 512 Hz.  Noise 0.02 V
    puts the lightest axle's peak at 31 σ, 0.05 V at 12 σ (2× the detection threshold)."""
    ev, es, ed = [], [], []
    for v in SPEEDS:
        for seed in range(10):
            t_first = T0 + 0.2 + 0.013 * seed  # every sub-sample phase
            det = detect_axles(detector_record([(v, CAL_SPACINGS, CAL_LOADS, t_first)],
                                               seed=seed, noise=noise))
            veh = det.single
            assert veh.n_axles == 5 and det.flags == ()
            ev.append(veh.speed / v - 1)
            es.append(np.abs(veh.axle_spacings - CAL_SPACINGS).max())
            ed.append(veh.passage.delay - t_first)
    assert np.abs(ev).max() < max_speed
    assert max(es) < max_spacing
    assert np.abs(ed).max() < max_delay


def test_tridem_resolved_at_25_m_per_s():
    """Three axles 1.3 m apart at 25 m/s: 52 ms = 27 samples between peaks of 6 samples'
    base (measured: 3 axles every seed, spacings within 4.8 mm)."""
    for seed in range(10):
        t_first = T0 + 0.3 + 0.011 * seed
        veh = detect_axles(detector_record([(25.0, (1.3, 1.3), (80e3, 80e3, 80e3),
                                             t_first)], seed=seed)).single
        assert veh.n_axles == 3
        np.testing.assert_allclose(veh.axle_spacings, 1.3, atol=0.012)


def test_count_mismatch_flagged_and_axle_kept():
    """ad2 misses the fourth axle: flagged, confidence × 4/5, the axle kept from ad1
    (measured confidence 0.799, spacings within 4.1 mm, speed 0.004 %)."""
    det = detect_axles(detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)],
                                       missed=[(1, 3, 0)]), span=9.0)
    veh = det.single
    assert FLAG_COUNT_MISMATCH in veh.flags and FLAG_COUNT_MISMATCH in det.flags
    assert "ad1 saw 5" in det.message and "ad2 saw 4" in det.message
    assert veh.n_axles == 5
    np.testing.assert_allclose(veh.axle_spacings, CAL_SPACINGS, atol=0.015)
    assert veh.speed == pytest.approx(20.0, rel=1e-3)
    assert veh.confidence <= 0.8  # × 4/5 axles seen by both (measured 0.799)
    assert np.isnan(veh.detector_times[3, 1]) and np.isfinite(veh.detector_times[3, 0])
    clean = detect_axles(detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)]))
    assert clean.single.confidence > 0.95


def test_two_vehicles_split_and_multiple_presence():
    """A 2-axle lorry behind the truck: on the 9 m span together (its first axle enters
    before the truck's last leaves) → two vehicles, both flagged; 0.7 s later → two
    vehicles, no flag; never one vehicle."""
    truck = (20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)   # on the span until T0 + 1.27 s
    close = (22.0, (4.0,), (50e3, 70e3), T0 + 1.05)
    far = (22.0, (4.0,), (50e3, 70e3), T0 + 1.75)
    for second, together in ((close, True), (far, False)):
        det = detect_axles(detector_record([truck, second], duration=2.5), span=9.0)
        assert det.n_vehicles == 2
        assert [v.n_axles for v in det.vehicles] == [5, 2]
        assert [round(v.speed, 1) for v in det.vehicles] == [20.0, 22.0]
        np.testing.assert_allclose(det.vehicles[1].axle_spacings, [4.0], atol=0.02)
        assert (FLAG_MULTIPLE_PRESENCE in det.flags) is together
        assert all((FLAG_MULTIPLE_PRESENCE in v.flags) is together for v in det.vehicles)
        with pytest.raises(bwim.InputError, match="2 vehicles"):
            _ = det.single


def test_vehicle_in_another_lane_is_unexplained_strain(plate):
    """The detectors see the truck (lane 3 m); a lorry in lane 7.5 m crosses before it or
    after it: the summed gauges move outside the truck's time on the span → flagged.  The
    truck alone at 15, 20, 25 m/s (bridge vibration after it leaves) → no flag."""
    other = MovingForces(axle_loads=[50e3, 70e3], axle_spacings=[4.0], track_width=2.0)
    for delays in ([0.6, 0.0], [0.0, 0.9]):
        raw = bwim.simulate(plate, [_truck(), other], speed=[20.0, 22.0], lane=[3.0, 7.5],
                            delay=delays, sensors=gauges(), sampling_rate=FS,
                            approach=0.0, tail=0.4)
        rec = finish_simulated(raw, seed=3)
        full = with_detectors(rec, [(20.0, CAL_SPACINGS, CAL_LOADS,
                                     rec.passages[0].delay)], seed=3)
        det = detect_axles(full, span=9.0)
        assert det.n_vehicles == 1
        assert FLAG_UNEXPLAINED_STRAIN in det.flags and "outside" in det.message
    for v in (15.0, 20.0, 25.0):
        rec = strain_record(plate, _truck(), speed=v, lane=7.0, seed=4, tail=1.0)
        full = with_detectors(rec, [(v, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)], seed=4)
        assert detect_axles(full, span=9.0).flags == ()


def test_lateral_position_across_the_deck(plate):
    """The truck (2 m track) in 16 lanes from 1.25 to 8.75 m at 20 m/s, 14 gauges 0.69 m
    apart: the thresholded centroid is within 0.37 m (rms 0.13 m, measured) of the lane; a
    plain centroid (threshold 0) is pulled toward the centre by up to 2.5 m."""
    lanes = np.arange(1.25, 8.8, 0.5)
    err, plain = [], []
    for k, lane in enumerate(lanes):
        rec = strain_record(plate, _truck(), speed=20.0, lane=lane, seed=k)
        full = with_detectors(rec, [(20.0, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)],
                              seed=k)
        veh = detect_axles(full, span=9.0).single
        assert veh.lateral_unit == "m" and veh.passage.lane == veh.lateral
        err.append(veh.lateral - lane)
        plain.append(detect_axles(full, span=9.0, lateral_threshold=0.0).single.lateral
                     - lane)
    err = np.array(err)
    assert np.abs(err).max() < 0.5
    assert np.sqrt(np.mean(err**2)) < 0.2
    assert np.abs(plain).max() > 3 * np.abs(err).max()


def test_detection_time_per_event(plate):
    """One 1.5 s event: 2 detector + 14 gauge channels at 512 Hz, with span (lateral
    position, multiple presence and strain checks).  Target well under 5 ms (the weigh
    pipeline's 100 events/s); measured 0.6 ms for the detectors alone, 1.0 ms in all."""
    rec = strain_record(plate, _truck(), speed=20.0, lane=3.0, seed=1, tail=0.13)
    full = with_detectors(rec, [(20.0, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)], seed=1)
    assert full.time.size / FS == pytest.approx(1.5, abs=0.01)
    best = np.inf
    for _ in range(20):
        t0 = time.perf_counter()
        detect_axles(full, span=9.0)
        best = min(best, time.perf_counter() - t0)
    assert best < 5e-3


def test_no_axles_in_a_batch():
    """A noise-only event in a batch gives an empty detection with its reason."""
    batch = [detector_record([(20.0, CAL_SPACINGS, CAL_LOADS, T0 + 0.2)], seed=1),
             detector_record([], seed=2)]
    out = [detect_axles(r) for r in batch]
    assert [d.n_vehicles for d in out] == [1, 0]
    assert out[1].flags == (FLAG_NO_AXLES,) and out[1].message


# --- strain only ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def lines(plate):
    """The coarse model's line, and a line calibrated (matrix method) from three other
    crossings whose passages came from the axle detectors."""
    coarse = model_influence_line(coarse_plate(), gauges(), channels="sum", lane=3.0,
                                  track_width=2.0)
    cal = []
    for v, seed in ((17.0, 101), (21.0, 102), (24.0, 103)):
        rec = strain_record(plate, _truck(), speed=v, lane=3.0, seed=seed, offsets=False)
        full = with_detectors(rec, [(v, CAL_SPACINGS, CAL_LOADS, rec.passage.delay)],
                              seed=seed)
        cal.append(detect_axles(full, span=9.0).annotate(rec))
    calibrated = calibrate_influence_line(cal, CAL_LOADS, lane_tolerance=1.0,
                                          support=(-0.5, 9.5))
    return {"coarse": coarse, "calibrated": calibrated}


@pytest.mark.parametrize(("line", "max_speed", "max_delay"), [
    ("coarse", 0.03, 0.015),      # measured 0.5–2.2 %, ≤ 11 ms
    ("calibrated", 0.02, 0.012),  # measured 0.4–1.3 %, ≤ 8.3 ms
])
def test_strain_only_with_known_spacings(plate, lines, line, max_speed, max_delay):
    """The calibration truck's layout known, speed and arrival fitted to the summed gauges
    at 15–25 m/s.  The static model's misfit is the bridge's dynamics (the line's shape
    barely matters: the fine model's own static line does no better), hence ~1–2 %."""
    il = lines[line]
    for v in (15.0, 18.0, 20.0, 22.0, 25.0):
        rec = strain_record(plate, _truck(), speed=v, lane=3.0, seed=int(v))
        veh = detect_from_strain(rec, il, known_spacings=CAL_SPACINGS).single
        assert abs(veh.speed / v - 1) < max_speed
        assert abs(veh.passage.delay - rec.passage.delay) < max_delay
        np.testing.assert_allclose(veh.axle_spacings, CAL_SPACINGS, rtol=1e-9)  # clock round-off
        assert FLAG_STRAIN_ONLY in veh.flags and 0.3 < veh.confidence <= 0.5


def test_strain_only_free_search(plate, lines):
    """No layout: speed within 5.0 % (measured, coarse and calibrated lines, 15–25 m/s;
    median 0.8 %), 5 axles in 9 of the 10 events (4 in one: a 1.3 m tridem on a 9 m span
    is at the edge of what the summed gauges resolve), far below the detectors' accuracy:
    the strain-only path is a fallback, flagged and at most half confident."""
    errors, counts = [], []
    for il in lines.values():
        for v in (15.0, 18.0, 20.0, 22.0, 25.0):
            rec = strain_record(plate, _truck(), speed=v, lane=3.0, seed=int(v))
            det = detect_from_strain(rec, il)
            assert det.method == "strain" and det.n_vehicles >= 1
            errors.append(det.vehicles[0].speed / v - 1)
            counts.append(sum(x.n_axles for x in det.vehicles))
            assert all(FLAG_STRAIN_ONLY in x.flags and x.confidence <= 0.5
                       for x in det.vehicles)
    assert np.abs(errors).max() < 0.08
    assert np.median(np.abs(errors)) < 0.02
    assert all(4 <= n <= 6 for n in counts) and counts.count(5) >= 8


# --- wide detector responses on the realistic site (issue 20) ------------------------------
# tests/detect_data.py site_day: bwim.synthetic's "short-span-4-lane" installation (its own
# finite-element slab, vehicle-bridge interaction on class A-B roads, detectors with wide
# local peaks less a share of the slab's bending, gains 3-5x apart, tyre types, lateral
# wander, gauge noise, offsets and drift, half the calibration runs with a vehicle in the
# other direction), seed 3, 12 calibration runs, 24 traffic events, 0.6 m mesh.  The
# responses are learned from the runs (known layout); nothing of the site's model is given
# to bwim.detect.  References: the simulation's truth (truth.csv, site_truth.toml).

@pytest.fixture(scope="module")
def site(tmp_path_factory):
    from bwim.detect import learn_responses

    from tests.detect_data import site_day

    day, calibration, traffic, truck = site_day(tmp_path_factory.mktemp("site") / "day",
                                                seed=3, n_traffic=24)
    learned = learn_responses(calibration, ("ad1", "ad2"), 3.0, truck["axle_spacings"],
                              loads=truck["axle_loads"])
    lane1 = [(rec, rows[0]) for rec, rows in traffic if len(rows) == 1
             and rows[0]["lane"] == "1"]
    return day, calibration, learned, lane1


def test_site_responses_from_the_calibration_runs(site):
    """Learned from the 12 runs with the gauges' bending, at most one left out (measured:
    none, the largest residual 0.091 against the median 0.052; with the shallower dips
    before stop 35, one, 0.094 against the others' 0.054, since stop 34's larger drift
    within the day: the detectors' bending part drifts with the strain, their local part
    does not, so the runs at the ends of the day fit the common response less well): each
    run's speed within 1.5 % of the truth (measured ≤ 0.37 %; the truck's own dynamic
    tyre forces), the detectors'
    gain ratio within 4 % of the site's (measured 1.0 %), each response even about its
    detector and 1.2 ± 0.12 m wide at half height (the site's local peak: 1.2 m; measured
    1.23 and 1.21 m), the bending read with a negative share of the gauges (the site's
    detectors subtract 0.9 × the slab's strain)."""
    import csv
    import tomllib

    day, _, learned, _ = site
    speeds = {}
    with open(day.truth, newline="") as f:
        for r in csv.DictReader(f):
            if r["kind"] == "calibration" and r["lane"] == "1":
                speeds[r["record"]] = float(r["speed_m_s"])
    truth = np.array([speeds[p.name] for p in day.calibration])
    assert sum(1 for r in learned.reasons if r) <= 1
    assert np.nanmax(np.abs(learned.speeds / truth - 1)) < 0.015
    gains = tomllib.loads(day.site_truth.read_text())["axle_detectors"]
    g = dict(zip(gains["name"], gains["gain"], strict=True))
    assert learned.gain_ratio == pytest.approx(g["ad2"] / g["ad1"], rel=0.04)
    for r in learned.responses:
        np.testing.assert_allclose(r.k, r.k[::-1], atol=1e-12)
        assert r.fwhm == pytest.approx(1.2, abs=0.12)
        assert r.bending.sum() < 0
    assert learned.gauges == tuple(f"s{k:02d}" for k in range(1, 13))


def test_site_lane1_axles_counted(site):
    """Every single lane-1 truck of the traffic date (13 here: 2-axle rigids, 2+3 and 3+3
    artics with tandems and tridems 1.3-1.4 m apart, wide singles) counted right, as one
    vehicle, without a count-mismatch flag (measured 13/13).  Spacings within 0.25 m and
    speeds within 5 % (measured ≤ 0.073 m and ≤ 1.4 %; median 0.52 %): the tyres' dynamic
    forces shift each peak by a few ms at each detector, which sets these errors (with the
    simulation's own forces, exact responses and the true start, the same fit errs by
    1.3 % at the median, 3 % at the 90th percentile: see the benchmark)."""
    from tests.detect_data import site_axles

    _, _, learned, lane1 = site
    assert len(lane1) >= 10
    errors, spacings = [], []
    for rec, row in lane1:
        _, v, sp = site_axles(row)
        det = detect_axles(rec, ("ad1", "ad2"), 3.0, responses=learned)
        assert FLAG_COUNT_MISMATCH not in det.flags and det.method == "learned responses"
        veh = det.single
        assert veh.n_axles == sp.size + 1, row["record"]
        spacings.append(np.abs(veh.axle_spacings - sp).max())
        errors.append(veh.speed / v - 1)
        assert 0.5 <= veh.confidence <= 1.0
    assert max(spacings) < 0.25
    assert np.abs(errors).max() < 0.05 and np.median(np.abs(errors)) < 0.025


def test_site_peaks_alone_miscount(site):
    """The reference point of the issue on the same events: peak picking (no responses)
    gets the count right with both detectors agreeing on at most 4 of them (measured 1),
    the learned responses on all (previous test)."""
    _, _, _, lane1 = site
    right = 0
    for rec, row in lane1:
        det = detect_axles(rec, ("ad1", "ad2"), 3.0)
        right += (det.n_vehicles == 1 and FLAG_COUNT_MISMATCH not in det.flags
                  and det.vehicles[0].n_axles == int(row["n_axles"]))
    assert right <= 4
