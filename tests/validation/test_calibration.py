"""Calibration smoke versions of the paper's §5.1 and §5.4 (the full runs are
``make reproduce``): the calibrated parameters come back, and MFI with the calibrated
model weighs like MFI with the true one.  Short approach and small populations keep them
fast; the physics is the paper's.

Without the inverse crime (issue 12): ``test_slab_5_1_from_finer_mesh_data`` calibrates
the paper's 12 × 8 model on data from a 24 × 16 mesh with 2 % gauge noise.  The
same-model cases check what only same-model data can: that the refinement lands on the
exact minimiser when the data are consistent with the model (§5.1 noise-free, to 3e-8),
the dynamics' bias of the two stages in isolation, and the five-parameter algebra of §5.4
(its finer-mesh version, with the mesh correction, takes 40 s: make bench)."""

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.calibration import calibrate
from bwim.errors import InputError

APPROACH = 20.0


@pytest.fixture(scope="module")
def slab_case():
    bridge, sensors, truck = paper.slab_bridge(), paper.sensors(), paper.truck()
    road = paper.road(1, approach=APPROACH)
    rec = bwim.simulate(bridge, truck, speed=paper.SPEED, lane=paper.LANE, sensors=sensors,
                        road=road, approach=APPROACH)
    return bridge, truck, road, rec


def _errors(params, true):
    return {k: np.abs(v / true[k] - 1).max() for k, v in params.items()}


def test_slab_5_1_ce_then_mfi(slab_case):
    bridge, truck, road, rec = slab_case
    start = bridge.with_params(E_x=0.8 * 35e9, E_y=1.2 * 35e9, mu=1.25 * 1560.0)
    cal = calibrate(start, [rec], truck, road=road, approach=APPROACH, seed=3,
                    population=(100, 24), convergences=2)
    err = _errors(cal.params, bridge.params)
    # the paper's two stages then the joint dynamic refinement: every parameter back to
    # the truth in a noise-free run (README: "refined 0.000 %"); measured ≤ 1.0e-6 %
    assert max(err.values()) < 3e-8
    static = cal.stages[0]
    assert static.name.startswith("stiffness") and static.nfev >= 100
    assert cal.nfev == sum(s.nfev for s in cal.stages)
    assert not cal.identifiability.unseen and cal.identifiability.condition < 1e3
    # MFI with the calibrated model weighs like the exact model (docs/paper_cases.md §5.1)
    ident = bwim.identify_forces(cal.bridge, rec)
    e = bwim.force_errors(ident, rec.truth)
    # (docs/paper_cases.md's targets: weights within 2 %, RMS within 5 %; measured −0.86 / −0.14 %
    # and 0.69 / 0.69 %, the MFI's own error with the exact model)
    assert np.all(np.abs(e.weight_error) < 0.015) and np.all(e.rms_error < 0.012)


def test_slab_5_1_from_finer_mesh_data():
    """§5.1 by CE on data from a 24 × 16 mesh, 2 % gauge noise, with the mesh correction
    (bwim.calibration.meshdefect); MFI with the calibrated 12 × 8 model weighs the
    noise-free crossing."""
    truth, truck = paper.slab_bridge(nx=24, ny=16), paper.truck()
    road = paper.road(1, approach=APPROACH)
    clean = bwim.simulate(truth, truck, speed=paper.SPEED, lane=paper.LANE,
                          sensors=paper.sensors(), road=road, approach=APPROACH)
    rec = clean.with_noise(0.02, seed=11)
    start = paper.slab_bridge().with_params(E_x=0.8 * 35e9, E_y=1.2 * 35e9, mu=1.25 * 1560.0)
    cal = calibrate(start, [rec], truck, road=road, approach=APPROACH, seed=3,
                    population=(100, 24), convergences=2, weights="noise", mesh_correction=1)
    err = _errors(cal.params, truth.params)
    # measured −0.002, +0.27, +0.004 % (seeds 3 and 4 alike); the paper's two stages on the
    # uncorrected model +1.0, +4.6, +1.5 % (seed 3)
    assert max(err.values()) < 0.005, err
    assert _errors(cal.two_stage, truth.params)["E_y"] > 0.02
    assert cal.mesh_correction.converged and cal.stages[0].nfev >= 100
    e = bwim.force_errors(bwim.identify_forces(cal.bridge, clean), clean.truth)
    # measured weights −1.27, −0.90 %, RMS 1.42, 1.29 % (the 1 m mesh's own MFI error)
    assert np.all(np.abs(e.weight_error) < 0.02) and np.all(e.rms_error < 0.025)


def test_two_stages_alone_are_biased_by_dynamics(slab_case):
    """Without the refinement the pseudo-static stage carries the dynamics' bias (the
    reason for the refinement, README: "biases that fit by 0.5–5 % in E"): fitting static
    influence surfaces to strains that carry the bridge's dynamic amplification over this
    20 m approach overestimates E_x and μ (measured +0.54 %, +0.45 %) and leaves E_y
    within 0.2 % (measured −0.11 %).  The bias is a property of the data, not of the
    optimiser: CE's two stages (tests/regression/test_reproduce_smoke.py) land within
    0.1 % of these E_x and μ."""
    bridge, truck, road, rec = slab_case
    start = bridge.with_params(E_x=0.9 * 35e9, E_y=1.1 * 35e9, mu=1.1 * 1560.0)
    cal = calibrate(start, [rec], truck, road=road, approach=APPROACH, method="lm",
                    refine="none")
    assert len(cal.stages) == 2
    bias = {k: float(v[0] / bridge.params[k][0] - 1) * 100 for k, v in cal.params.items()}
    # the dynamic amplification biases the static fit upwards, beyond round-off
    assert bias["E_x"] > 0.3 and bias["mu"] > 0.3, bias
    assert abs(bias["E_y"]) < 0.2, bias


def test_vransko_5_4_lm():
    bridge, sensors, truck = paper.vransko_bridge(), paper.vransko_sensors(), paper.truck()
    road = paper.road(2, approach=APPROACH)
    rec = bwim.simulate(bridge, truck, speed=paper.SPEED, lane=paper.LANE, sensors=sensors,
                        road=road, approach=APPROACH)
    start = bridge.with_params(E_x=0.85 * 31e9, E_y=1.15 * 31e9, mu=1.2 * 576.0,
                               E_girder=0.9 * 35e9, mu_girder=0.85 * 1373.0)
    # 20 modes (the record has 47 below 125 Hz): fast, at a small truncation bias
    cal = calibrate(start, [rec], truck, road=road, approach=APPROACH, method="lm",
                    unknowns=("E_x", "E_y", "mu", "E_girder", "mu_girder"), n_modes=20)
    err = _errors(cal.params, bridge.params)
    # docs/paper_cases.md §5.4: all five within 1.5 %; measured ≤ 0.4 % (the slab/girder mass split)
    assert max(err.values()) < 0.015
    assert cal.stages[-1].x.size == 5  # one shared E and mu for the five girders


def test_bad_calibration_input(slab_case):
    bridge, truck, _, rec = slab_case
    with pytest.raises(InputError, match="unknown 'E_girder' is not a parameter"):
        calibrate(bridge, [rec], truck, unknowns=("E_girder",))
    with pytest.raises(InputError, match="unknown method 'genetic'"):
        calibrate(bridge, [rec], truck, method="genetic")
    with pytest.raises(InputError, match="at least one record"):
        calibrate(bridge, [], truck)
    with pytest.raises(InputError, match="has 2 axles but the calibration vehicle has 5"):
        calibrate(bridge, [rec], bwim.vehicles.tractor_semitrailer())
