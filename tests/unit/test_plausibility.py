"""No weight leaves bwim without a plausibility check (issue 14): the shared flags, Moses'
static weights and MFI's identified weights on records that are wrong in the ways a
careless user makes them wrong (readings in microstrain, a time axis offset, swapped
channels).  References: the simulated truth of a crossing of the paper's slab."""

import dataclasses

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.plausibility import HARD_FLAGS, Limits, ordered_flags, quality_of, weight_flags
from bwim.wim import calibrate_influence_line, weigh_static


def test_weight_flags_against_the_limits():
    lim = Limits()
    assert weight_flags([60e3, 100e3], [60e3, 100e3], lim) == []
    assert weight_flags([-5e3, 100e3], [-5e3, 100e3], lim) == ["negative_axle_weight",
                                                               "negative_group_weight"]
    assert "axle_weight_high" in weight_flags([300e3, 100e3], [400e3], lim)
    assert "gvw_high" in weight_flags([240e3] * 5, [1200e3], lim)
    assert weight_flags([0.0, 0.0], [0.0], lim) == ["axle_weight_low", "gvw_low"]
    assert quality_of(()) == "ok" and quality_of(("ill_conditioned",)) == "warning"
    assert quality_of(ordered_flags(["ill_conditioned", "gvw_low"])) == "reject"
    assert set(HARD_FLAGS).isdisjoint({"ill_conditioned", "lateral_extrapolated"})


@pytest.fixture(scope="module")
def crossing():
    """Per-gauge lines: a summed channel cannot tell a swap among its gauges (or with
    another gauge) from a lighter or heavier vehicle; per-gauge lines can."""
    bridge, sensors = paper.slab_bridge(), paper.sensors()
    cal = [bwim.simulate(bridge, paper.truck(), speed=v, lane=paper.LANE, sensors=sensors,
                         road=paper.road(k), approach=20.0) for k, v in ((1, 18.0), (2, 22.0))]
    il = calibrate_influence_line(cal, paper.truck(), channels="each")
    rec = bwim.simulate(bridge, bwim.vehicles.three_axle_truck(), speed=20.0, lane=paper.LANE,
                        sensors=sensors, road=paper.road(7), approach=20.0)
    return bridge, il, rec


def test_moses_on_a_good_record_is_ok(crossing):
    _, il, rec = crossing
    w = weigh_static(rec, il)
    assert w.quality == "ok" and w.flags == ()
    assert abs(w.gvw / rec.truth.static_axle_loads.sum() - 1) < 0.05


@pytest.mark.parametrize(("how", "expected"), [
    ("microstrain", "gvw_high"),          # readings 1e6 times too large
    ("offset", "residual_high"),          # the time axis 0.3 s off the passage
    ("swapped", "residual_high"),         # two channels' names swapped
])
def test_moses_flags_wrong_records(crossing, how, expected):
    _, il, rec = crossing
    if how == "microstrain":
        rec = dataclasses.replace(rec, data=rec.data * 1e6)
    elif how == "offset":
        rec = dataclasses.replace(rec, passages=(dataclasses.replace(
            rec.passage, delay=rec.passage.delay + 0.3),))
    else:
        kinds = [s.kind for s in rec.sensors]
        peak = np.abs(rec.data).max(axis=0)
        # the largest longitudinal gauge's name swapped with a transverse gauge's
        i = max((k for k in range(len(kinds)) if kinds[k] == "strain_x"), key=peak.__getitem__)
        j = kinds.index("strain_y")
        data = rec.data.copy()
        data[:, [i, j]] = data[:, [j, i]]
        rec = dataclasses.replace(rec, data=data)
    w = weigh_static(rec, il)
    assert w.quality == "reject" and expected in w.flags


def test_mfi_weights_carry_flags(crossing):
    bridge, _, rec = crossing
    ident = bwim.identify_forces(bridge, rec, n_modes=12)
    assert ident.vehicle_quality == ("ok",)
    assert 0 < ident.residual < 0.1
    kinds = [s.kind for s in rec.sensors]
    data = rec.data.copy()
    i, j = kinds.index("strain_x"), kinds.index("strain_y")
    data[:, [i, j]] = data[:, [j, i]]
    swapped = bwim.identify_forces(bridge, dataclasses.replace(rec, data=data), n_modes=12)
    assert swapped.vehicle_quality == ("reject",)
    bad = bwim.identify_forces(bridge, dataclasses.replace(rec, data=rec.data * 1e6),
                               n_modes=12)
    assert bad.vehicle_quality == ("reject",) and "gvw_high" in bad.vehicle_flags[0]
