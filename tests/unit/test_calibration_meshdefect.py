"""The defect-correction passes' shape (bwim.calibration.meshdefect.DefectCorrection), and
the calibration package's public names.

Reference: on a linear toy problem (same-model algebra: it checks the iteration, not the
physics; the physics is tests/validation/test_mesh_correction.py) the passes are the
fixed-point iteration ``p_{k+1} = (d − (a_f − a_h) p_k) / a_h`` (docs/theory.md §12 with
``F_h(p) = a_h p``, ``F_f(p) = a_f p``), whose closed form is
``p_k − p* = ρ^k (p_0 − p*)``, ``ρ = −(a_f − a_h)/a_h``, ``p* = d/a_f``.
"""

import ast
import importlib
from pathlib import Path

import numpy as np
import pytest

import bwim
from bwim.calibration.meshdefect import DefectCorrection, MeshCorrection
from bwim.optimize import OptimizeResult

A_H, A_F = 1.0, 1.1  # the coarse and the fine model's response per unit parameter
P_TRUE = 30e9


class _Toy(DefectCorrection):
    """Data ``d = a_f p_true``; a state is the calibrated parameter p (the beam's E_x)."""

    def __init__(self, levels, beam, **kw):
        super().__init__(levels, **kw)
        self.beam, self.d = beam, A_F * P_TRUE
        self.data = self.d

    def model(self, state):
        return self.beam.with_params(E_x=state)

    def correct(self, state, coarse, fine):
        defect = A_F * float(fine.params["E_x"][0]) - A_H * float(coarse.params["E_x"][0])
        self.data = self.d - defect
        return abs(defect) / self.d

    def refit(self, state, k):
        return self.data / A_H

    def change(self, old, new):
        return abs(new / old - 1)


@pytest.fixture(scope="module")
def beam():
    return bwim.Bridge.beam(length=20.0, n_elements=8, E=P_TRUE, I=0.4, mu=4000.0,
                            z_bottom=0.5)


def _closed_form(k):
    p0, rho = A_F * P_TRUE / A_H, -(A_F - A_H) / A_H
    return P_TRUE + rho**k * (p0 - P_TRUE)


def test_passes_follow_the_fixed_point_iteration(beam):
    """From the uncorrected answer ``d/a_h`` the passes converge to p* (the fine model's
    calibration) as the closed form says; they stop at the first change below tol (the
    4th: changes 10 %, 1.1 %, 0.11 %, 0.011 %)."""
    toy = _Toy(1, beam)
    start = toy.d / A_H
    report = toy.solve(start)
    p = [_closed_form(k) for k in range(5)]
    assert isinstance(report, MeshCorrection) and report.passes == 4 and report.converged
    np.testing.assert_allclose(toy.states, p[1:], rtol=1e-12)
    np.testing.assert_allclose(report.change, [abs(p[k + 1] / p[k] - 1) for k in range(4)],
                               rtol=1e-9)
    np.testing.assert_allclose(report.defect, [(A_F - A_H) * p[k] / toy.d for k in range(4)],
                               rtol=1e-12)
    assert report.change[-1] < report.tol <= report.change[-2]
    assert report.levels == 1 and report.mesh == (16, 0)  # the corrector: 8 elements bisected
    assert report.bridge.params["E_x"][0] == pytest.approx(p[4], rel=1e-12)
    assert toy.state == toy.states[-1]


def test_step_by_step_and_the_pass_limit(beam):
    """``step`` is one pass (its change returned, the state advanced); ``run`` stops at
    ``max_passes`` without claiming convergence; ``setup`` starts afresh."""
    toy = _Toy(1, beam, max_passes=2)
    toy.setup(toy.d / A_H)
    assert not toy.converged and toy.fine is None
    change = toy.step()
    assert change == pytest.approx(abs(_closed_form(1) / _closed_form(0) - 1), rel=1e-9)
    assert toy.state == pytest.approx(_closed_form(1), rel=1e-12)
    assert toy.fine.model.grid.nx == 16
    toy.run()
    report = toy.finalize()
    assert report.passes == 2 and not report.converged
    assert "NOT converged" in report.summary()
    toy.setup(toy.d / A_H)
    assert toy.states == [] and toy.changes == []


def test_calibration_results_and_public_names():
    """The calibration results speak scipy.optimize's vocabulary (their classes inherit
    OptimizeResult); the package's names resolve; no module of bwim.calibration imports
    another's underscore names."""
    import bwim.calibration as calibration
    from bwim.calibration import Calibration, QuasiStaticCalibration

    assert issubclass(Calibration, OptimizeResult)
    assert issubclass(QuasiStaticCalibration, OptimizeResult)
    for name in calibration.__all__:
        assert getattr(calibration, name) is not None, name
    meshdefect = importlib.import_module("bwim.calibration.meshdefect")
    for name in meshdefect.__all__:
        assert getattr(meshdefect, name) is not None, name
    root = Path(calibration.__file__).parent
    found = []
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.level or (
                    node.module or "").startswith("bwim")):
                found += [f"{path.name}: {a.name}" for a in node.names
                          if a.name.startswith("_") and not a.name.startswith("__")]
    assert found == []
