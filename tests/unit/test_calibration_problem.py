"""Calibration problem pieces: weighted adjoint Jacobian against finite differences, the
neighbour map of §5.3, shared (tied) parameter families."""

import dataclasses

import numpy as np
import pytest

import bwim
from bwim import paper
from bwim.calibration.problem import (
    DynamicObjective,
    ParameterSpace,
    StaticObjective,
    neighbour_map,
    peak_weights,
)
from bwim.errors import InputError


@pytest.fixture(scope="module")
def record():
    bridge = paper.slab_bridge(zones=(2, 2))
    return bridge, bwim.simulate(bridge, paper.truck(), speed=20.0, lane=2.0,
                                 sensors=paper.sensors(), approach=0.0, sampling_rate=250.0)


def test_weighted_jacobian_equals_finite_differences(record, rng):
    bridge, rec = record
    space = ParameterSpace(bridge, ("E_x", "E_y"))
    w = [rng.uniform(0.5, 2.0, rec.data.shape[1]) / np.abs(rec.data).max(axis=0) ** 2]
    obj = StaticObjective(space, [rec], paper.truck(), weights=w)
    theta = space.vector() * rng.uniform(0.9, 1.1, space.n)
    J = obj.jacobian(theta)
    fd = np.empty_like(J)
    for k in range(space.n):
        h = 1e-4 * theta[k]
        up, dn = theta.copy(), theta.copy()
        up[k] += h
        dn[k] -= h
        fd[:, k] = (obj.residuals(up) - obj.residuals(dn)) / (2 * h)
    np.testing.assert_allclose(J, fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())


def test_shared_girder_family_jacobian_and_broadcast():
    bridge = paper.vransko_bridge()
    rec = bwim.simulate(bridge, paper.truck(), speed=20.0, lane=2.0,
                        sensors=paper.vransko_sensors()[:9], approach=0.0, sampling_rate=200.0)
    space = ParameterSpace(bridge, ("E_x", "E_girder"), frozenset({"E_girder"}))
    assert space.n == 2 and space.split([3e10, 3.6e10])["E_girder"].tolist() == [3.6e10] * 5
    obj = StaticObjective(space, [rec], paper.truck())
    theta = space.vector()
    J = obj.jacobian(theta)
    h = 1e-4 * theta[1]
    step = np.array([0.0, h])
    fd = (obj.residuals(theta + step) - obj.residuals(theta - step)) / (2 * h)
    np.testing.assert_allclose(J[:, 1], fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())


def test_neighbour_map_of_the_sixteen_zones():
    """§5.3: each of the 9 sensors sits on an interior zone corner and touches 4 zones."""
    bridge = paper.slab_bridge(zones=(4, 4))
    space = ParameterSpace(bridge, ("E_x", "E_y"))
    nb = neighbour_map(space, paper.sensors())
    assert nb.shape == (9, 32)
    assert np.all(nb.sum(axis=1) == 8)  # 4 zones × (E_x, E_y)
    assert np.all(nb.any(axis=0))  # every zone parameter neighbours some sensor


def test_peak_weights_and_bad_weights(record):
    bridge, rec = record
    (w,) = peak_weights([rec])
    np.testing.assert_allclose(w * np.abs(rec.data).max(axis=0) ** 2, 1.0)
    space = ParameterSpace(bridge, ("E_x",))
    with pytest.raises(InputError, match="channel weights of record 0 must be 18"):
        StaticObjective(space, [rec], paper.truck(), weights=[np.ones(3)])


def test_dynamic_objective_takes_the_records_settings(record):
    """Equivalence: a record's own simulation settings, the same approach given
    explicitly, and a record without settings (tail from its time axis) re-simulate the
    same crossing."""
    bridge, rec = record
    assert rec.settings == bwim.SimulationSettings(approach=0.0, tail=0.0)
    space = ParameterSpace(bridge, ("mu",))
    theta = space.vector() * 1.1
    own = DynamicObjective(space, [rec], paper.truck(), None, bridge, n_modes=6)
    given = DynamicObjective(space, [rec], paper.truck(), None, bridge, approach=0.0,
                             n_modes=6)
    bare = dataclasses.replace(rec, settings=None)
    derived = DynamicObjective(space, [bare], paper.truck(), None, bridge, approach=0.0,
                               n_modes=6)
    ref = own.residuals(theta)
    assert np.abs(ref).max() > 0
    np.testing.assert_array_equal(given.residuals(theta), ref)
    np.testing.assert_array_equal(derived.residuals(theta), ref)


def test_dynamic_objective_reuses_modes_only_for_a_uniform_mass_factor():
    """Reference: the same crossing simulated on each trial bridge with its own modes
    (eigsh, ``bwim.simulate``'s path).  One μ zone: trials after the first scale the first
    trial's modes (fe/modal.py derivation), equal to round-off; two μ zones with unequal
    factors must not be scaled (they would differ by percents)."""
    from bwim.dynamics.crossing import prepare_crossing, run_crossing

    for zones, factors in (((1, 1), [(1.1,), (0.8,), (1.3,)]),
                           ((2, 1), [(1.1, 1.1), (0.9, 1.2)])):
        bridge = paper.slab_bridge(zones=zones)
        rec = bwim.simulate(bridge, paper.truck(), speed=20.0, lane=2.0,
                            sensors=paper.sensors(), approach=0.0, sampling_rate=250.0)
        space = ParameterSpace(bridge, ("mu",))
        obj = DynamicObjective(space, [rec], paper.truck(), None, bridge, n_modes=6)
        prep = prepare_crossing(bridge, paper.truck(), speed=20.0, lane=2.0,
                                sensors=paper.sensors(), approach=0.0,
                                sampling_rate=rec.sampling_rate, tail=rec.settings.tail)
        for f in factors:
            theta = space.vector() * np.array(f)
            trial = space.bridge(theta)
            ref = run_crossing(prep, trial, n_modes=6, warn=False).data
            got = obj.predicted(theta)[0]
            err = np.abs(got - ref).max() / np.abs(ref).max()
            assert err < 1e-13  # measured 7.6e-15 (scaled), 0 (solved)
            if zones != (1, 1):  # solved, not scaled
                np.testing.assert_array_equal(obj.modes(trial).omega, trial.modes(6).omega)
