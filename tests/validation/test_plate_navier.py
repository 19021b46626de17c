"""Orthotropic plate simply supported on four edges against Navier's series.

Reference: tests/references.py (Timoshenko & Woinowsky-Krieger §86–87; Leissa 1969).
Errors must be small on the 12 × 8 mesh and fall under refinement to 24 × 16.
"""

import numpy as np
import pytest

import bwim

from tests.references import navier_frequencies, navier_point_load, orthotropic_rigidities

A, B, H, EX, EY, NU, MU = 12.0, 8.0, 0.65, 35e9, 20e9, 0.2, 1560.0
LOAD = (5.0, 3.0)
POINT = (8.0, 5.0)  # away from the load, on node lines of both meshes


def _plate(nx, ny):
    return bwim.Bridge.plate(
        length=A, width=B, nx=nx, ny=ny, thickness=H, E_x=EX, E_y=EY, mu=MU, poisson=NU,
        supports="ss-all",
    )


def _errors(nx, ny):
    Dx, Dy, Hh = orthotropic_rigidities(EX, EY, H, NU)
    ref = navier_point_load(A, B, Dx, Dy, Hh, H, *LOAD, *POINT)
    bridge = _plate(nx, ny)
    sensors = [bwim.Sensor(x=POINT[0], y=POINT[1], kind=k)
               for k in ("deflection", "strain_x", "strain_y")]
    got = bridge.static([bwim.PointLoad(x=LOAD[0], y=LOAD[1], P=1.0)], sensors)
    f_ref = navier_frequencies(A, B, Dx, Dy, Hh, MU)
    f = bridge.modes(6).frequencies
    return np.abs(got / np.array(ref) - 1), np.abs(f / f_ref - 1)


@pytest.fixture(scope="module")
def errors():
    return {mesh: _errors(*mesh) for mesh in ((12, 8), (24, 16))}


def test_navier_coarse_mesh_accuracy(errors):
    static, freq = errors[(12, 8)]
    w_err, ex_err, ey_err = static
    # measured: w 3.3e-6, ε_x 4.4e-2, ε_y 2.8e-3, frequencies 2.0e-4
    assert w_err < 1e-5
    assert ex_err < 0.05
    assert ey_err < 0.01
    assert freq.max() < 5e-4


def test_navier_errors_fall_under_refinement(errors):
    (s1, f1), (s2, f2) = errors[(12, 8)], errors[(24, 16)]
    # deflection converges fast (h^5), strains like h^2, frequencies like h^4
    assert s2[0] < s1[0] / 16
    assert s2[1] < s1[1] / 3
    assert s2[2] < s1[2]
    assert f2.max() < f1.max() / 10
    assert s2[1] < 0.015 and f2.max() < 2e-5


def test_navier_first_six_frequencies_in_order():
    Dx, Dy, Hh = orthotropic_rigidities(EX, EY, H, NU)
    f_ref = navier_frequencies(A, B, Dx, Dy, Hh, MU)
    f = _plate(12, 8).modes(6).frequencies
    np.testing.assert_allclose(f, f_ref, rtol=5e-4)
