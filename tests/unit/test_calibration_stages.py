"""run_stage: one result shape for the three optimisers, and a truthful success flag.

References: scipy.optimize's convention (``success`` is False when the evaluation budget
ends the run, e.g. ``least_squares`` status 0 "the maximum number of function evaluations
is exceeded"); the CE stop reasons of bwim.optimize.ce.
"""

import numpy as np
import pytest

import bwim
from bwim.calibration import Method, ParameterSpace, StaticObjective, calibrate, run_stage
from bwim.errors import InputError


def _crossing():
    """A two-zone beam, a moving-force crossing (static readings at 200 Hz) and the start
    20 % off."""
    beam = bwim.Bridge.beam(length=20.0, n_elements=8, E=30e9, I=0.4, mu=4000.0,
                            z_bottom=0.5, zones=2)
    truck = bwim.MovingForces(axle_loads=[60e3, 100e3], axle_spacings=[4.0])
    sensors = [bwim.Sensor(x=6.0), bwim.Sensor(x=14.0)]
    rec = bwim.simulate(beam, truck, speed=20.0, sensors=sensors, approach=0.0,
                        sampling_rate=200.0)
    return rec, truck, beam.with_params(E_x=[24e9, 36e9])


@pytest.fixture(scope="module")
def problem():
    """The beam's stiffness stage."""
    rec, truck, start = _crossing()
    space = ParameterSpace(start, ("E_x",))
    return StaticObjective(space, [rec], truck), space


@pytest.mark.parametrize(("method", "population", "budget"),
                         [("lm", None, 3), ("cma", 4, 5), ("ce", 3, 3)])
def test_a_spent_budget_is_not_success(problem, method, population, budget):
    obj, space = problem
    res = run_stage(method, obj, space, seed=1, population=population, max_evals=budget)
    assert res.success is False
    assert res.message  # says why
    assert res.nfev <= budget and res.x.shape == (2,) and res.labels == ("E_x[0]", "E_x[1]")
    # fun is the summed squared misfit at x
    assert res.fun == pytest.approx(float(obj(res.x).sum()), rel=1e-9)


def test_messages_name_the_budget(problem):
    obj, space = problem
    cma = run_stage(Method.CMA, obj, space, seed=1, population=4, max_evals=5)
    assert cma.nit == 1 and cma.nfev == 4 and "budget" in cma.message
    lm = run_stage(Method.LM, obj, space, max_evals=3)
    assert "function evaluations" in lm.message


def test_converged_least_squares_is_success(problem):
    obj, space = problem
    res = run_stage(Method.LM, obj, space)
    assert res.success is True and "termination condition" in res.message
    assert res.fun < float(obj(space.vector()).sum())


def test_stop_ends_a_population_method_and_is_success(problem):
    obj, space = problem
    res = run_stage(Method.CMA, obj, space, seed=2, population=4, max_evals=400,
                    stop=lambda x: True)
    assert res.success is True and res.nit == 1 and res.nfev == 4
    with pytest.raises(InputError, match="stop ends a population method"):
        run_stage(Method.LM, obj, space, stop=lambda x: True)


def test_bad_stage_input(problem):
    obj, space = problem
    with pytest.raises(InputError, match="unknown method 'newton'; expected one of ce, lm, cma"):
        run_stage("newton", obj, space)
    with pytest.raises(InputError, match="bounds must be factors"):
        run_stage(Method.LM, obj, space, bounds=(1.2, 5.0))
    with pytest.raises(InputError, match="must allow one CMA-ES population"):
        run_stage(Method.CMA, obj, space, population=6, max_evals=3)


def test_calibration_speaks_scipys_vocabulary():
    """``calibrate``'s result: ``x`` the parameters in ``labels``' order, ``fun`` the last
    stage's objective, ``nfev``/``nit`` summed over the stages, ``success`` False with the
    stage that spent its budget named in ``message``; converged, a success with a smaller
    objective."""
    rec, truck, start = _crossing()
    short = calibrate(start, [rec], truck, unknowns=("E_x",), method="lm", refine="none",
                      max_evals=3)
    assert short.labels == ("E_x[0]", "E_x[1]")
    np.testing.assert_array_equal(short.x, short.params["E_x"])
    assert short.fun == short.stages[-1].fun
    assert short.nfev == sum(s.nfev for s in short.stages)
    assert short.nit == sum(s.nit for s in short.stages)
    assert not short.success and "stiffness (static)" in short.message
    full = calibrate(start, [rec], truck, unknowns=("E_x",), method="lm", refine="none")
    assert full.success and "every stage succeeded" in full.message
    assert full.fun < short.fun
