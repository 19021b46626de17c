"""Vehicle models: static loads from equilibrium, frequencies, the named library."""

import numpy as np
import pytest

from bwim import vehicles
from bwim.conventions import GRAVITY
from bwim.errors import InputError


def test_sprung_mass_frequency_and_load():
    v = vehicles.SprungMass(mass=5750.0, stiffness=1595e3)
    m = v.model()
    assert m.n_dof == 1
    assert m.frequencies()[0] == pytest.approx(np.sqrt(1595e3 / 5750.0) / (2 * np.pi))
    assert m.static_forces[0] == pytest.approx(5750.0 * GRAVITY)


def test_quarter_car_frequencies_closed_form():
    ms, mu, ks, kt = 4000.0, 500.0, 400e3, 1.75e6
    m = vehicles.SprungMass(mass=ms, stiffness=ks, unsprung_mass=mu, tyre_stiffness=kt).model()
    # det([[ks − ms w², −ks], [−ks, ks + kt − mu w²]]) = 0 (two-DOF quarter car)
    a, b, c = ms * mu, -(ms * (ks + kt) + mu * ks), ks * kt
    w2 = np.sort(np.roots([a, b, c]).real)
    np.testing.assert_allclose(m.frequencies(), np.sqrt(w2) / (2 * np.pi), rtol=1e-10)
    assert m.static_forces[0] == pytest.approx((ms + mu) * GRAVITY)


def test_paper_truck():
    truck = vehicles.two_axle_truck()
    m = truck.model()
    assert m.n_dof == 3 + 2 * 2  # bounce, pitch, roll + a wheel mass at each end of each axle
    np.testing.assert_allclose(truck.static_axle_loads, [59.5e3, 108.6e3], rtol=1e-12)
    f = m.frequencies()
    # body bounce near the paper's 1.2 Hz, axle hop near its 14.3 Hz (Fig. 19)
    assert 1.0 < f[0] < 1.8
    assert 11.0 < f[-1] < 15.0
    p = truck.passage(speed=20.0, lane=2.0)
    assert p.axle_spacings.tolist() == [5.5] and p.track_width == 2.0
    np.testing.assert_allclose(p.wheel_y, [1.0, 3.0, 1.0, 3.0])


def _moment_balance(model, bodies):
    """Σ F_c s_c equals Σ (weights × their positions): static equilibrium about axle 1."""
    lhs = np.sum(model.static_forces * model.contact_offset)
    return lhs, sum(m * GRAVITY * s for m, s in bodies)


def test_three_axle_static_equilibrium_is_indeterminate_but_balanced():
    truck = vehicles.three_axle_truck()
    m = truck.model()
    weights = [(truck.body_mass, truck.cg_offset)] + [
        (2 * wm, s) for wm, s in zip(truck.wheel_mass, truck.axle_offsets, strict=True)]
    total = sum(w for w, _ in weights) * GRAVITY
    assert m.static_forces.sum() == pytest.approx(total, rel=1e-12)
    lhs, rhs = _moment_balance(m, weights)
    assert lhs == pytest.approx(rhs, rel=1e-12)
    # left and right wheels share each axle equally (symmetric vehicle)
    np.testing.assert_allclose(m.static_forces[0::2], m.static_forces[1::2], rtol=1e-12)


def test_symmetric_tandem_shares_equally():
    # CG midway between two identical axles: equal loads (symmetry)
    v = vehicles.Truck3D(body_mass=10e3, pitch_inertia=3e4, roll_inertia=5e3,
                         axle_spacings=[1.4], cg_offset=0.7, wheel_mass=400.0,
                         suspension_stiffness=400e3, suspension_damping=5e3,
                         tyre_stiffness=1.5e6)
    loads = v.static_axle_loads
    assert loads[0] == pytest.approx(loads[1], rel=1e-12)


def test_tractor_semitrailer():
    v = vehicles.tractor_semitrailer()
    m = v.model()
    assert v.n_axles == 5 and m.n_contacts == 10
    assert m.n_dof == 6 + 10 - 2  # two bodies, ten wheels, hitch and roll link
    assert m.static_forces.sum() / GRAVITY == pytest.approx(40e3, rel=1e-9)
    assert np.all(m.static_forces > 0)
    weights = [(v.tractor_mass, v.tractor_cg_offset), (v.trailer_mass, v.trailer_cg_offset)]
    weights += [(2 * wm, s) for wm, s in zip(v.wheel_mass, v.axle_offsets, strict=True)]
    lhs, rhs = _moment_balance(m, weights)
    assert lhs == pytest.approx(rhs, rel=1e-10)
    f = m.frequencies()
    assert f.min() > 0.5 and f.max() < 20


def test_half_car_matches_axle_loads_with_and_without_track():
    common = dict(body_mass=12e3, pitch_inertia=4e4, axle_spacings=[4.0], cg_offset=2.5,
                  wheel_mass=[600.0, 900.0], suspension_stiffness=[300e3, 600e3],
                  suspension_damping=[5e3, 8e3], tyre_stiffness=[1.5e6, 3e6])
    one = vehicles.HalfCar(**common).model()
    two = vehicles.HalfCar(**common, track_width=2.0).model()
    assert one.n_dof == two.n_dof == 4
    np.testing.assert_allclose(one.static_axle_loads, two.static_axle_loads, rtol=1e-12)
    np.testing.assert_allclose(one.frequencies(), two.frequencies(), rtol=1e-10)
    # lever rule on the body plus the wheel weights
    body = 12e3 * GRAVITY
    expected = [body * 1.5 / 4.0 + 600 * GRAVITY, body * 2.5 / 4.0 + 900 * GRAVITY]
    np.testing.assert_allclose(one.static_axle_loads, expected, rtol=1e-12)


def test_moving_forces():
    single = vehicles.MovingForces(axle_loads=[50e3, 80e3], axle_spacings=[4.0]).model()
    assert single.n_dof == 0 and single.n_contacts == 2
    pair = vehicles.MovingForces(axle_loads=[50e3, 80e3], axle_spacings=[4.0],
                                 track_width=1.8).model()
    np.testing.assert_allclose(pair.static_forces, [25e3, 25e3, 40e3, 40e3])
    np.testing.assert_allclose(pair.contact_lateral, [-0.9, 0.9, -0.9, 0.9])


def test_named_library():
    assert set(vehicles.NAMED_VEHICLES) == {"two_axle_truck", "three_axle_truck",
                                            "tractor_semitrailer"}
    assert vehicles.named("three_axle_truck").n_axles == 3
    with pytest.raises(InputError, match="unknown vehicle 'bus'"):
        vehicles.named("bus")


def test_bad_vehicle_input():
    with pytest.raises(InputError, match="mass must be positive, got -1"):
        vehicles.SprungMass(mass=-1.0, stiffness=1e5)
    with pytest.raises(InputError, match=r"one value per axle \(2\)"):
        vehicles.Truck3D(body_mass=1e4, pitch_inertia=1e4, roll_inertia=1e3,
                         axle_spacings=[4.0], cg_offset=2.0, wheel_mass=[1, 2, 3],
                         suspension_stiffness=1e5, suspension_damping=0,
                         tyre_stiffness=1e6)
    with pytest.raises(InputError, match="axle_spacings must be positive"):
        vehicles.MovingForces(axle_loads=[1e4, 1e4], axle_spacings=[-2.0])
    with pytest.raises(InputError, match="static wheel loads are not all positive"):
        vehicles.Truck3D(body_mass=1e4, pitch_inertia=1e4, roll_inertia=1e3,
                         axle_spacings=[4.0], cg_offset=9.0, wheel_mass=100.0,
                         suspension_stiffness=1e5, suspension_damping=0,
                         tyre_stiffness=1e6).model()
