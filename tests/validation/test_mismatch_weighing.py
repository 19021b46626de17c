"""Weighing with a mismatched model, road-free calibration (issue 12, first target).

No inverse crime: the data come from a 24 × 16 mesh of the paper's slab (bwim.paper), the
model is 18 × 12, every record carries one absolute gauge σ (2 % of the calibration
crossings' peak strain), the calibration truck's road is never given to the calibration
(bwim.calibration.calibrate_quasistatic, two crossings at 15 and 22 m/s, start 28 / 42 GPa,
1950 kg/m²) and the weighed vehicles cross other ISO roads.  References: the true slab
(35 GPa, 1560 kg/m²), the simulated static axle loads, and the true dynamic axle forces
averaged over MFI's own windows — the best a window-mean static weight can do.

Tolerances are ≈ 1.6 × the errors measured by benchmarks/bench_mismatch.py
(mismatch_weighing, row "18x12 / none"): parameters −1.20 / −1.20 / −1.08 %; GVW
−0.42, −1.34, −3.81, −3.73, −0.46, −2.19 %; largest axle error 8.2 % (semitrailer tridem),
2.5 % for the rigid trucks; GVW at most 1.49 % from the window-mean limit.  Issue 12's
target (GVW 2 %, axles 5 %) is not met by the semitrailer on these roads (the paper's
roughness): the true forces' window mean already misses its GVW by 2.2-2.9 %.  On ISO
class A roads, with the mesh correction, the whole chain meets the GVW target on data from
a 48 × 32 truth (last test).
"""

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.calibration import calibrate_quasistatic
from bwim.mfi import force_errors, identify_forces
from bwim.vehicles import three_axle_truck, tractor_semitrailer, two_axle_truck

APPROACH = 20.0
#: (vehicle factory, speed m/s, lane m, ISO road seed), as in the benchmark
WEIGHED = (
    (three_axle_truck, 14.0, 2.0, 11),
    (three_axle_truck, 23.0, 6.0, 12),
    (tractor_semitrailer, 18.0, 2.0, 13),
    (tractor_semitrailer, 25.0, 6.0, 14),
    (two_axle_truck, 12.0, 6.0, 15),
    (two_axle_truck, 20.0, 2.0, 16),
)


@pytest.fixture(scope="module")
def weighed():
    truth = paper.slab_bridge(nx=24, ny=16)
    road = paper.road(1, approach=APPROACH)
    cal = [bwim.simulate(truth, paper.truck(), speed=v, lane=paper.LANE,
                         sensors=paper.sensors(), road=road, approach=APPROACH, tail=1.0)
           for v in (15.0, 22.0)]
    sigma = 0.02 * max(float(np.abs(r.data).max()) for r in cal)
    cal = [r.with_noise(sigma=sigma, seed=40 + k) for k, r in enumerate(cal)]
    start = paper.slab_bridge(nx=18, ny=12).with_params(E_x=28e9, E_y=42e9, mu=1950.0)
    c = calibrate_quasistatic(start, cal, paper.truck())
    out = []
    for k, (make, v, lane, rs) in enumerate(WEIGHED):
        rec = bwim.simulate(truth, make(), speed=v, lane=lane, sensors=paper.sensors(),
                            road=paper.road(rs, approach=APPROACH),
                            approach=APPROACH).with_noise(sigma=sigma, seed=60 + k)
        ident = identify_forces(c.bridge, rec)
        err = force_errors(ident, rec.truth)
        t, tr = ident.time, rec.truth
        mean = np.array([tr.axle_forces[(t >= lo) & (t <= hi), a].mean()
                         for a, (lo, hi) in enumerate(ident.axle_windows)])
        out.append((err, mean.sum() / tr.gvw - 1.0))
    return truth, c, out


def test_road_free_calibration_of_the_coarser_model(weighed):
    truth, c, _ = weighed
    assert c.success
    for k in ("E_x", "E_y", "mu"):
        assert abs(c.params[k][0] / truth.params[k][0] - 1) < 0.02, k


def test_rigid_trucks_meet_the_target(weighed):
    """3-axle and 2-axle trucks, both lanes: GVW within 3.5 %, axles within 4.5 % (the
    3-axle truck's second axle measured −4.05 % since MFI's half-step lag was fixed: the
    lag had offset the road-free calibration's −1 % bias against the window-mean force)."""
    _, _, out = weighed
    for k in (0, 1, 4, 5):
        err, _ = out[k]
        assert abs(err.gvw_error) < 0.035, (k, err.gvw_error)
        assert np.abs(err.weight_error).max() < 0.045, (k, err.weight_error)


def test_semitrailer_within_measured_bounds(weighed):
    """Tractor-semitrailer: GVW within 6 %, axles within 13 % (the tridem)."""
    _, _, out = weighed
    for k in (2, 3):
        err, _ = out[k]
        assert abs(err.gvw_error) < 0.06, (k, err.gvw_error)
        assert np.abs(err.weight_error).max() < 0.13, (k, err.weight_error)


def test_gvw_close_to_the_window_mean_limit(weighed):
    """Every GVW within 2.5 % of the true forces' mean over the same windows."""
    _, _, out = weighed
    for k, (err, limit) in enumerate(out):
        assert abs(err.gvw_error - limit) < 0.025, (k, err.gvw_error, limit)


def test_corrected_chain_on_wim_grade_roads_with_a_finer_truth():
    """The whole chain with the mesh correction, on data from a 48 × 32 truth (finer than
    every model the chain builds: no inverse crime): the 12 × 8 model calibrated from the
    two crossings (road measured with 1 mm RMS error, start 28 / 42 GPa, 1950 kg/m²,
    ``mesh_correction=1``), then MFI on the 24 × 16 model its parameters belong to, of the
    six vehicles on ISO class A roads (COST 323's smooth approach; same seeds and noise).
    Issue 12's target: every GVW within 2 % (met: measured +0.55, +0.11, −1.13, −1.09,
    +0.57, −0.32 %), every axle within 5 % (met since the mass comes from the free
    vibration after exit, ``calibrate``'s default ``mass="auto"``: largest axle error
    2.62 %; with the stages' mass, ``mass="dynamic"``, one tridem axle missed it at
    5.25 %)."""
    from benchmarks.bench_mismatch import (
        corrected_chain,
        smooth_road_records,
        weigh_all,
        weighing_data,
    )

    data = weighing_data(data_mesh=(48, 32))
    chain = corrected_chain(data)
    assert chain.mesh_correction.converged and chain.mesh_correction.mesh == (24, 16)
    _, recs = smooth_road_records("A", sigma=data[4], data_mesh=(48, 32))
    for k, (gvw, axles) in enumerate(weigh_all(chain.mesh_correction.bridge, recs)):
        assert abs(gvw) < 2.0 and np.abs(axles).max() < 5.0, (k, gvw, axles)
