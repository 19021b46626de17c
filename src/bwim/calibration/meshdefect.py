"""Mesh defect correction: calibrate a coarse model as if it were a finer one.

Contract
--------
A model whose mesh is too coarse for its sensors (:func:`bwim.fe.convergence.check_mesh`
estimates the error at each sensor; on the paper's 1 m elements the transverse strains
are far from converged) biases a calibration by the discretisation error, not by the
data (docs/theory.md §12).  Defect correction (Stetter
1978, *The defect correction principle and discretization methods*, Numer. Math. 29)
removes that bias at the price of a few simulations of a finer model:

* the **defect** of a model ``h`` at parameters ``p`` is ``δ(p) = F_f(p) − F_h(p)``, the
  readings of the calibration crossings simulated on the model bisected ``levels`` times
  (``f``, :func:`bwim.fe.convergence.refine`) minus those simulated on ``h`` itself, each
  with its own modes up to the same cut-off frequency (:func:`mesh_defects`);
* each pass calibrates ``h`` against the measured readings minus the defect at the
  previous pass's answer: ``p_{k+1} = argmin ‖d − δ(p_k) − F_h(p)‖``;
* at a fixed point ``p*`` the normal equations are ``J_hᵀ (d − F_f(p*)) = 0``: those of the
  finer model but for the coarse Jacobian, so ``p*`` is the finer model's calibration up
  to ``(J_h − J_f)ᵀ r`` — exact when the finer model fits the data, and second order (mesh
  error of the sensitivities times the residual) otherwise.

The passes are an iterative solver with a visible shape, :class:`DefectCorrection`:
``setup`` from a calibration, ``step`` = one pass (returns the largest relative parameter
change), ``run`` until a pass changes no parameter by :data:`TOL` or :data:`MAX_PASSES`
passes are done, ``finalize`` = the :class:`MeshCorrection` report.  A calibration method
says what its state is, how the defect enters its data and how it refits
(:func:`~bwim.calibrate`'s dynamic re-simulation, :func:`~bwim.calibration.
calibrate_quasistatic`'s static filtered prediction).

Readings are in the records' units (strain or m); parameter changes are relative.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bwim.calibration.problem import DynamicObjective, ParameterSpace
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.fe.convergence import refine
from bwim.records import Record
from bwim.road import RoadProfile
from bwim.vehicles import Vehicle

__all__ = ["AUTO_MAX_LEVELS", "AUTO_TOL", "MAX_LEVELS", "MAX_PASSES", "TOL", "DefectCorrection",
           "MeshCorrection", "check_levels", "corrector", "mesh_defects", "requested_levels"]

#: Most bisections of the corrector model (each multiplies a plate's DOF by about 4).
MAX_LEVELS = 3
#: ``mesh_correction="auto"``: the discretisation error to reach at every sensor, and the
#: most bisections it may take.
AUTO_TOL = 0.05
AUTO_MAX_LEVELS = 2
#: A pass that moves no parameter by more than this (relative) ends the correction.
TOL = 1e-3
#: Most correction passes.
MAX_PASSES = 5


@dataclass(frozen=True, kw_only=True, eq=False)
class MeshCorrection:
    """What the defect correction of a calibration did (``calibrate(mesh_correction=)``).

    Attributes
    ----------
    levels : int
        Bisections of the calibrated model that make the corrector model.
    mesh : (int, int)
        The corrector's ``(nx, ny)`` (``ny`` = 0 for a beam).
    change : ndarray, shape (passes,)
        Largest relative change of any calibrated parameter made by each pass.
    defect : ndarray, shape (passes,)
        Largest |defect| of each pass over the records, relative to the peak |reading|.
    converged : bool
        The last pass changed no parameter by more than ``tol``.
    tol : float
    bridge : Bridge
        The corrector model at the corrected parameters: the model those parameters belong
        to, and the one to weigh with (moving force identification on it carries no more
        of the coarse mesh's error).
    """

    levels: int
    mesh: tuple[int, int]
    change: np.ndarray
    defect: np.ndarray
    converged: bool
    tol: float
    bridge: Bridge

    @property
    def passes(self) -> int:
        return int(self.change.size)

    def summary(self) -> str:
        nx, ny = self.mesh
        mesh = f"{nx}x{ny}" if ny else f"{nx} elements"
        state = "converged" if self.converged else "NOT converged"
        return (f"mesh defect correction by the {mesh} model: {self.passes} passes, "
                f"{state} (last change {self.change[-1]:.3%}, tol {self.tol:.3%}); "
                f"defect up to {self.defect[-1]:.2%} of the peak reading")


def check_levels(levels) -> int:
    """``levels`` as an int in 1…:data:`MAX_LEVELS` (InputError otherwise)."""
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or not (
            1 <= levels <= MAX_LEVELS):
        raise InputError(f"mesh_correction must be an integer from 1 to {MAX_LEVELS} "
                         f"(bisections of the model) or 'auto', got {levels!r}")
    return int(levels)


def requested_levels(mesh_correction) -> int:
    """A calibration's integer ``mesh_correction``: 0 (no correction) or
    :func:`check_levels`'s 1…:data:`MAX_LEVELS`."""
    if isinstance(mesh_correction, (int, np.integer)) and not isinstance(
            mesh_correction, bool) and mesh_correction == 0:
        return 0
    return check_levels(mesh_correction)


def corrector(bridge: Bridge, levels: int) -> Bridge:
    """``bridge`` bisected ``levels`` times (same parameters, zones and supports)."""
    for _ in range(check_levels(levels)):
        bridge = refine(bridge)
    return bridge


def mesh_defects(bridge: Bridge, records: Sequence[Record], vehicle: Vehicle,
                 road: RoadProfile | None, *, levels: int = 1, approach: float | None = None,
                 n_modes: int | None = None, fine: Bridge | None = None) -> list[np.ndarray]:
    """The defect ``F_f(p) − F_h(p)`` of each record, shape (n_t, n_sensors) each.

    ``bridge`` is the model ``h`` at ``p``; ``fine`` (default: ``bridge`` bisected
    ``levels`` times) must carry the same parameters.  The crossings are re-simulated as
    :class:`~bwim.calibration.problem.DynamicObjective` does (each record's speed, lane,
    run-up and tail; ``approach`` overrides the run-up).  ``n_modes`` (default: each
    model's modes up to sampling_rate / 8) applies to both models.
    """
    if not isinstance(bridge, Bridge):
        raise InputError(f"bridge must be a bwim.Bridge, got {type(bridge).__name__}")
    fine = corrector(bridge, levels) if fine is None else fine
    out = None
    for model, sign in ((fine, 1.0), (bridge, -1.0)):
        space = ParameterSpace(model, tuple(model.params))
        objective = DynamicObjective(space, records, vehicle, road, model, approach=approach,
                                     n_modes=n_modes)
        pred = objective.predicted(space.vector())
        out = ([sign * p for p in pred] if out is None
               else [o + sign * p for o, p in zip(out, pred, strict=True)])
    return out


class DefectCorrection(ABC):
    """Defect-correction passes (module docstring) in the shape of an iterative solver:
    ``setup``, ``step``, ``run``, ``finalize``.

        correction = SomeCorrection(levels, ...)       # a subclass: the four hooks below
        report = correction.solve(first)               # setup, run, finalize
        last = correction.state                        # the last pass's calibration

    A subclass defines what a calibration *state* is through four hooks:
    :meth:`model` (the calibrated model at a state), :meth:`correct` (the data less the
    defect at a state), :meth:`refit` (the calibration of the corrected data from a
    state) and :meth:`change` (the largest relative parameter change between two states).

    Attributes
    ----------
    state : object
        The current calibration (after the last pass); this and the following attributes
        are set by ``setup``.
    states : list
        Each pass's calibration, in order.
    changes, defects : list of float
        Each pass's largest relative parameter change and largest |defect| relative to
        the peak |reading|.
    fine : Bridge or None
        The last pass's corrector model (``levels`` bisections of the model it started
        from).
    """

    def __init__(self, levels: int, *, tol: float = TOL, max_passes: int = MAX_PASSES) -> None:
        self.levels = check_levels(levels)
        self.tol = float(tol)
        self.max_passes = int(max_passes)

    @abstractmethod
    def model(self, state: Any) -> Bridge:
        """The calibrated (coarse) model at ``state``."""

    @abstractmethod
    def correct(self, state: Any, coarse: Bridge, fine: Bridge) -> float:
        """Take the defect ``fine − coarse`` at ``state`` off the data the next
        :meth:`refit` uses; return its largest |value| relative to the peak |reading|."""

    @abstractmethod
    def refit(self, state: Any, k: int) -> Any:
        """The calibration of the corrected data from ``state`` (pass ``k``, from 1)."""

    @abstractmethod
    def change(self, old: Any, new: Any) -> float:
        """The largest relative change of a calibrated parameter from ``old`` to ``new``."""

    def setup(self, start: Any) -> None:
        """Start from the uncorrected calibration ``start``."""
        self.state = start
        self.states: list = []
        self.changes: list[float] = []
        self.defects: list[float] = []
        self.fine: Bridge | None = None

    def step(self) -> float:
        """One pass: the defect at the current state, the refit; its parameter change."""
        coarse = self.model(self.state)
        self.fine = corrector(coarse, self.levels)
        self.defects.append(self.correct(self.state, coarse, self.fine))
        new = self.refit(self.state, len(self.states) + 1)
        self.changes.append(self.change(self.state, new))
        self.states.append(new)
        self.state = new
        return self.changes[-1]

    @property
    def converged(self) -> bool:
        """The last pass changed no parameter by ``tol`` or more."""
        return bool(self.changes) and self.changes[-1] < self.tol

    def run(self) -> None:
        """Pass until converged or ``max_passes`` passes are done."""
        while not self.converged and len(self.states) < self.max_passes:
            self.step()

    def finalize(self) -> MeshCorrection:
        """The report, with the corrector model at the corrected parameters."""
        fine = self.fine
        g = fine.model.grid
        return MeshCorrection(levels=self.levels, mesh=(g.nx, g.ny if fine.is_plate else 0),
                              change=np.array(self.changes), defect=np.array(self.defects),
                              converged=self.converged, tol=self.tol,
                              bridge=fine.with_params(**self.model(self.state).params))

    def solve(self, start: Any) -> MeshCorrection:
        """``setup``, ``run``, ``finalize``."""
        self.setup(start)
        self.run()
        return self.finalize()
