"""Every result with a figure has a thin ``.plot(ax=None, **kw)`` method: it draws what its
bwim.plots function draws, on the given axes if any.  Reference: the plot functions
themselves (the method must be the function, not a second drawing)."""

import numpy as np
import pytest

import bwim
from bwim.calibration import Calibration, StageResult
from bwim.optimize import minimize_ce
from bwim.plots import axes
from bwim.plots.calibration import plot_ce_convergence
from bwim.plots.mfi import plot_lcurve
from bwim.plots.records import plot_record
from bwim.plots.wim import plot_influence_line, plot_static_fit


@pytest.fixture(scope="module")
def beam_results():
    beam = bwim.Bridge.beam(length=10.0, n_elements=10, E=3e10, I=0.5, mu=5e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x) for x in (2.5, 5.0, 7.5)]
    truck = bwim.MovingForces(axle_loads=[5e4, 8e4], axle_spacings=[3.0])
    rec = bwim.simulate(beam, truck, speed=25.0, sensors=sensors, approach=0.0)
    il = bwim.model_influence_line(beam, sensors)
    return rec, il, bwim.weigh_static(rec, il), bwim.identify_forces(beam, rec, n_lam=8)


def _lines(fig):
    return [(ln.get_label(), ln.get_xydata().tolist()) for ln in fig.axes[0].lines]


def test_record_influence_line_and_weights(beam_results):
    rec, il, weights, ident = beam_results
    pairs = [(rec.plot(length=10.0), plot_record(rec, length=10.0)),
             (il.plot(reference=il), plot_influence_line(il, reference=il)),
             (weights.plot(record=rec), plot_static_fit(weights, record=rec)),
             (ident.lcurve.plot(), plot_lcurve(ident))]
    for method, function in pairs:
        assert _lines(method) == _lines(function) and _lines(method)
    ax = axes()
    assert rec.plot(ax) is ax.figure and len(ax.lines) == len(rec.sensors)
    assert ident.plot(ax=axes(), by="wheel").axes[0].get_ylabel() == "force (kN)"


def test_cross_entropy_results_and_calibration_stages():
    res = minimize_ce(lambda x: float(np.sum((np.asarray(x) - 1.0) ** 2)), [3.0, -2.0],
                      seed=0, convergences=1)
    fig = res.plot(parameter=1)
    assert _lines(fig) == _lines(plot_ce_convergence(res, parameter=1))
    assert fig.axes[0].get_title() == "Cross-Entropy: x[1]"
    stage = StageResult(name="stiffness", labels=("E_x", "E_y"), start=np.array([3.0, -2.0]),
                        x=res.x, fun=res.fun, nfev=res.nfev, nit=res.nit, success=True,
                        message="", uncertainty=np.zeros(2), history=res.history,
                        wall_time=0.0)
    cal = Calibration(bridge=None, params={}, uncertainty={}, stages=(stage,), nfev=res.nfev,
                      x=res.x, labels=("E_x[0]", "E_y[0]"), fun=res.fun, nit=res.nit,
                      success=True, message="", wall_time=0.0, identifiability=None)
    assert cal.plot(parameter=1).axes[0].get_title() == "stiffness: E_y"
    lm = StageResult(**{**stage.__dict__, "history": np.ones(3)})
    with pytest.raises(ValueError, match="not run by Cross-Entropy"):
        lm.plot()
