"""A sprung mass crossing a simply supported beam against the coupled solution of Biggs
(1964) / Yang & Yau (1997): analytic modes integrated by DOP853 (tests/references.py),
with and without damping and a road irregularity."""

import numpy as np
import pytest

import bwim
from bwim.dynamics import simulate
from bwim.road import RoadProfile
from bwim.vehicles import SprungMass

from tests.references import sprung_mass_on_beam

L, E, I, MU = 25.0, 2.943e10, 3.81, 2303.0  # Yang & Yau (1997), J. Eng. Mech. 123(11)
MASS, K, V = 5750.0, 1595e3, 27.78


def _irregularity():
    amp, wavelength = 0.005, 6.0

    def r(x):
        return amp * np.sin(2 * np.pi * x / wavelength)

    def rp(x):
        return amp * 2 * np.pi / wavelength * np.cos(2 * np.pi * x / wavelength)

    xs = np.arange(-1.0, L + 1.0, 0.001)
    return RoadProfile(x=xs, elevation=r(xs)), (r, rp)


@pytest.mark.parametrize(
    ("zeta", "c", "rough"),
    [(0.0, 0.0, False), (0.02, 20e3, False), (0.02, 20e3, True)],
    ids=["undamped-smooth", "damped-smooth", "damped-irregular"],
)
def test_sprung_mass_on_beam(zeta, c, rough):
    beam = bwim.Bridge.beam(length=L, n_elements=40, E=E, I=I, mu=MU, z_bottom=1.0,
                            damping_ratio=zeta)
    road, fns = _irregularity() if rough else (None, None)
    rec = simulate(beam, SprungMass(mass=MASS, stiffness=K, damping=c), speed=V,
                   sensors=[bwim.Sensor(x=L / 2, kind="deflection")], approach=0.0,
                   sampling_rate=2000.0, road=road)
    on = rec.time <= L / V
    ray = beam.rayleigh
    w, F = sprung_mass_on_beam(L=L, EI=E * I, m=MU, mass=MASS, k=K, c=c, v=V,
                               zeta=lambda om: ray.ratio(om) if zeta else 0.0 * om,
                               t=rec.time[on], road=fns)
    # measured: deflection ≤ 0.1 %, contact force ≤ 4e-5 of the weight
    assert np.abs(rec.data[on, 0] - w).max() < 3e-3 * np.abs(w).max()
    assert np.abs(rec.truth.wheel_forces[on, 0] - F).max() < 5e-4 * MASS * 9.81
    if rough:  # the irregularity really drives the mass
        assert np.ptp(F) > 0.1 * MASS * 9.81
