"""MFI figures draw on the Agg backend and return their figure."""

import pytest

import bwim
from bwim.plots.mfi import plot_forces, plot_lcurve


@pytest.fixture(scope="module")
def ident_and_truth():
    beam = bwim.Bridge.beam(length=10.0, n_elements=10, E=3e10, I=0.5, mu=5e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x) for x in (2.5, 5.0, 7.5)]
    rec = bwim.simulate(beam, bwim.MovingForces(axle_loads=[5e4, 8e4], axle_spacings=[3.0]),
                        speed=25.0, sensors=sensors, approach=0.0)
    return bwim.identify_forces(beam, rec, n_lam=8), rec.truth


def test_plot_forces_and_lcurve(ident_and_truth, tmp_path):
    ident, truth = ident_and_truth
    fig = plot_forces(ident, truth)
    assert len(fig.axes[0].lines) == 4  # two identified, two true
    fig.savefig(tmp_path / "forces.png")
    fig2 = plot_lcurve(ident)
    assert fig2.axes[0].get_xscale() == "log"
    assert ident.plot(truth) is not None  # the thin convenience method


def test_plot_lcurve_needs_a_curve(ident_and_truth):
    ident, _ = ident_and_truth
    import dataclasses

    with pytest.raises(ValueError, match="no L-curve"):
        plot_lcurve(dataclasses.replace(ident, lcurve=None))
