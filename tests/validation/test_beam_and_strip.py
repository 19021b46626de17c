"""1-D beam and a one-way slab (SS-F-SS-F, ν = 0) against Euler–Bernoulli beam theory.

References: tests/references.py (Clough & Penzien eq. 18-12; Roark Table 8.1).  With ν = 0
and free long edges the plate's first mode and its response to a line load uniform across
the width are exactly cylindrical, so beam theory is the exact answer (Timoshenko &
Woinowsky-Krieger §1-2, bending of a plate to a cylindrical surface).
"""

import numpy as np

import bwim

from tests.references import beam_frequencies, beam_midspan_point_load

L, E, I, MU, ZB = 25.0, 3.5e10, 1.3901, 18358.0, 0.8


def test_beam_frequencies():
    bridge = bwim.Bridge.beam(length=L, n_elements=50, E=E, I=I, mu=MU)
    f = bridge.modes(5).frequencies
    # measured: 1.1e-8 (mode 1) … 6.7e-6 (mode 5)
    np.testing.assert_allclose(f, beam_frequencies(L, E * I, MU, 5), rtol=1e-5)


def test_beam_frequencies_converge_with_elements():
    ref = beam_frequencies(L, E * I, MU, 4)
    err = [np.abs(bwim.Bridge.beam(length=L, n_elements=n, E=E, I=I, mu=MU)
                  .modes(4).frequencies / ref - 1).max() for n in (8, 16)]
    assert err[1] < err[0] / 10  # Hermite beam frequencies converge like h^4


def test_beam_point_load_deflection_and_strain():
    bridge = bwim.Bridge.beam(length=L, n_elements=10, E=E, I=I, mu=MU, z_bottom=ZB)
    P = 100e3
    d, moment = beam_midspan_point_load(L, E * I, P)
    got = bridge.static(
        [bwim.PointLoad(x=L / 2, P=P)],
        [bwim.Sensor(x=L / 2, kind="deflection"), bwim.Sensor(x=L / 2, kind="strain_x")],
    )
    # Hermite elements are nodally exact for point loads at nodes
    np.testing.assert_allclose(got, [d, moment * ZB / (E * I)], rtol=1e-9)


def test_beam_load_between_nodes_is_exact_at_nodes():
    # a point load at x = a: w(L/2) = P b (3L² − 4b²)/(48 EI) for a > L/2, b = L − a
    # (Roark Table 8.1 case 1e, deflection at mid-span for an off-centre load)
    bridge = bwim.Bridge.beam(length=L, n_elements=10, E=E, I=I, mu=MU)
    a, P = 16.3, 1e3
    b = L - a
    ref = P * b * (3 * L**2 - 4 * b**2) / (48 * E * I)
    got = bridge.static([bwim.PointLoad(x=a, P=P)], [bwim.Sensor(x=L / 2, kind="deflection")])
    np.testing.assert_allclose(got[0], ref, rtol=1e-9)


def _line_load(x, width, ny, total):
    """Consistent nodal loads of a uniform line load across the width at x: two Gauss
    points per element edge integrate the cubic shape functions exactly."""
    gauss = 0.5 + np.array([-1, 1]) / (2 * np.sqrt(3))
    b = width / ny
    ys = (np.arange(ny)[:, None] + gauss[None, :]).ravel() * b
    return [bwim.PointLoad(x=x, y=yy, P=total / ys.size) for yy in ys]


def test_one_way_slab_equals_beam():
    length, width, h, Ex, mu = 12.0, 8.0, 0.65, 35e9, 1560.0
    bridge = bwim.Bridge.plate(length=length, width=width, nx=12, ny=8, thickness=h,
                               E=Ex, mu=mu, poisson=0.0)
    EI = Ex * h**3 / 12 * width
    f1 = bridge.modes(1).frequencies[0]
    np.testing.assert_allclose(f1, beam_frequencies(length, EI, mu * width, 1)[0], rtol=1e-4)
    P = 200e3
    d, moment = beam_midspan_point_load(length, EI, P)
    sensors = [bwim.Sensor(x=6.0, y=y, kind=k) for y in (0.0, 3.0, 8.0)
               for k in ("deflection", "strain_x", "strain_y")]
    got = bridge.static(_line_load(6.0, width, 8, P), sensors).reshape(3, 3)
    strain = moment / width * (h / 2) / (Ex * h**3 / 12)
    for row in got:
        np.testing.assert_allclose(row[:2], [d, strain], rtol=1e-8)
        assert abs(row[2]) < 1e-8 * strain
