"""A girder under a narrow slab against composite beam theory (hand calculation).

A 2 m wide slab (ν = 0, free long edges) on one girder along its centre line.  When the
mid-span load and the mass are shared between slab and girder line in proportion to their
bending stiffness, every longitudinal fibre has the same load-to-stiffness ratio, so the
cross-section stays straight (w independent of y, no transverse bending or shear) and the
deck is exactly a beam with the composite section's stiffness E_g I_comp (parallel-axis
theorem, e.g. Gere & Goodno, *Mechanics of Materials*, §6.2, transformed sections):
deflection P L³/(48 E_g I_comp), girder soffit strain M z_b / (E_g I_comp), and the first
frequency of a beam with that stiffness and the total mass.
"""

import numpy as np
import pytest

import bwim

from tests.references import beam_frequencies, beam_midspan_point_load
from tests.validation.test_beam_and_strip import _line_load

L, WIDTH, T, E_SLAB, E_GIRDER, MU_SLAB = 16.0, 2.0, 0.2, 31e9, 35e9, 480.0
D_SLAB = E_SLAB * T**3 / 12  # ν = 0


def _section():
    return bwim.composite_section(
        girder_area=0.35, girder_inertia=0.045, girder_depth=0.9, slab_width=WIDTH,
        slab_thickness=T, modular_ratio=E_SLAB / E_GIRDER,
    )


def test_composite_section_hand_calculation():
    sec = _section()
    n = E_SLAB / E_GIRDER
    # hand calculation: centroid from the girder soffit, then parallel axes
    A_s = n * WIDTH * T
    c = (0.35 * 0.45 + A_s * (0.9 + T / 2)) / (0.35 + A_s)
    I_comp = 0.045 + 0.35 * (c - 0.45) ** 2 + n * WIDTH * T**3 / 12 + A_s * (1.0 - c) ** 2
    assert sec.z_bottom == pytest.approx(c, rel=1e-12)
    assert sec.I_composite == pytest.approx(I_comp, rel=1e-12)
    assert sec.I == pytest.approx(I_comp - n * WIDTH * T**3 / 12, rel=1e-12)


def test_single_girder_bridge_against_composite_beam():
    sec = _section()
    ei_slab, ei_girder = D_SLAB * WIDTH, E_GIRDER * sec.I
    mu_girder = MU_SLAB / D_SLAB * ei_girder  # same mass-to-stiffness ratio as the slab
    girder = bwim.Girder(y=WIDTH / 2, I=sec.I, z_bottom=sec.z_bottom, E=E_GIRDER, mu=mu_girder,
                         J=0.0)
    bridge = bwim.Bridge.plate(length=L, width=WIDTH, nx=16, ny=2, thickness=T, E=E_SLAB,
                               mu=MU_SLAB, poisson=0.0, girders=[girder])
    EI = E_GIRDER * sec.I_composite
    assert ei_slab + ei_girder == pytest.approx(EI, rel=1e-12)
    P = 100e3
    loads = _line_load(L / 2, WIDTH, 2, P * ei_slab / EI)
    loads.append(bwim.PointLoad(x=L / 2, y=WIDTH / 2, P=P * ei_girder / EI))
    d, moment = beam_midspan_point_load(L, EI, P)
    got = bridge.static(
        loads,
        [bwim.Sensor(x=L / 2, y=WIDTH / 2, kind="deflection"),
         bwim.Sensor(x=L / 2, y=WIDTH / 2, kind="strain_x"),
         bwim.Sensor(x=L / 2, y=0.0, kind="deflection")],
    )
    np.testing.assert_allclose(got, [d, moment * sec.z_bottom / EI, d], rtol=1e-8)
    f1 = bridge.modes(1).frequencies[0]
    f_ref = beam_frequencies(L, EI, MU_SLAB * WIDTH + mu_girder, 1)[0]
    np.testing.assert_allclose(f1, f_ref, rtol=1e-4)
    assert set(bridge.params) == {"E_x", "E_y", "mu", "E_girder", "mu_girder"}


def test_girder_torsion_stiffens_eccentric_load():
    sec = _section()
    common = dict(length=L, width=WIDTH, nx=16, ny=2, thickness=T, E=E_SLAB, mu=MU_SLAB,
                  poisson=0.0)
    load = [bwim.PointLoad(x=L / 2, y=0.0, P=1e5)]
    edge = [bwim.Sensor(x=L / 2, y=0.0, kind="deflection")]
    soft = bwim.Bridge.plate(**common, girders=[bwim.Girder(
        y=1.0, I=sec.I, z_bottom=sec.z_bottom, E=E_GIRDER, mu=900.0, J=0.0)])
    stiff = bwim.Bridge.plate(**common, girders=[bwim.Girder(
        y=1.0, I=sec.I, z_bottom=sec.z_bottom, E=E_GIRDER, mu=900.0, J=0.05)])
    assert stiff.static(load, edge)[0] < soft.static(load, edge)[0]
