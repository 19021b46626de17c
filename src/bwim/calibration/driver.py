"""``calibrate``: the bridge FE model from strains under a truck of known weight.

Contract
--------
The paper's procedure (Dowling, OBrien & González 2012, §5.1 steps 3–4; docs/theory.md §7):

1. **Stiffness, pseudo-static.**  ``E_x``, ``E_y`` per zone (and ``E_girder``) minimise the
   misfit between the measured strains and the *static* strains of the truck's static
   wheel loads at their positions (:class:`~bwim.calibration.problem.StaticObjective`).
2. **Mass, dynamic.**  With that stiffness, ``mu`` per zone (and ``mu_girder``) minimise
   the misfit between measured strains and the simulated dynamic strains of the crossing
   (vehicle–bridge interaction over the given road).

Beyond the paper, an optional third stage (``refine="lm"``, the default) polishes every
unknown together on the dynamic misfit by bounded least squares from the two-stage answer
(docs/theory.md §10): the pseudo-static fit is biased by the dynamics in the measured
strains, the dynamic misfit is not (on noise-free data of the model itself its minimiser
is the truth).  Both answers are reported (:attr:`Calibration.two_stage`); the bias and
its removal are measured by ``tests/validation/test_calibration.py`` and
``bwim reproduce``.

**Mass from the free vibration** (``mass="auto"``, the default, when the records carry
a tail of free vibration after the truck leaves; ``"free"`` to require it; ``"dynamic"``
for the stages' answer alone): after the stages (and the mesh correction), every mass
family is scaled by one factor fitted to the free vibration after exit
(:func:`~bwim.calibration.quasistatic.fit_mass`, the first mode, amplitudes free, the
calibrated stiffness fixed; docs/theory.md §12), on the model the parameters belong to
(the corrector model with the mesh correction).  The free vibration depends on the bridge
alone, so the mass it gives carries no error of the road or of the truck's model, which
the dynamic misfit passes on to the mass; it sets the model's first natural frequency to
the measured one, and the mass error becomes that of the stiffness.  The stages' mass
distribution over zones and girders is kept; the standard error is the fit's
(:attr:`~bwim.calibration.quasistatic.MassFit.standard_error`).  A record's tail is
fitted when it holds :data:`FREE_MASS_PERIODS` periods of the model's first mode; the fit
fails when the free vibration does not stand out of the noise
(:attr:`~bwim.calibration.quasistatic.MassFit.snr` below ``snr_noise``: its optimum would
be the noise's) or when the scale reaches a bound of :data:`FREE_MASS_BOUNDS`.

Every stage is one :func:`~bwim.calibration.stages.run_stage`.  ``method`` chooses the
optimiser of stages 1–2: ``"ce"`` (the paper's Cross-Entropy, sub-structured when there
are several zones, with the neighbour map from which zones touch which measurement
points), ``"lm"`` (``scipy.optimize.least_squares``; adjoint Jacobian for the stiffness,
finite differences for the mass) or ``"cma"`` (CMA-ES from the ``cmaes`` package).
Populations are evaluated in parallel with ``n_jobs`` worker processes or on a dask
``client``.

Each parameter's ``uncertainty`` is the spread of its final elite set (CE), or the
standard error ``σ sqrt(diag((JᵀJ)⁻¹))`` of the last least-squares stage that moved it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np

from bwim.calibration.meshdefect import (
    AUTO_MAX_LEVELS,
    AUTO_TOL,
    DefectCorrection,
    MeshCorrection,
    check_levels,
    mesh_defects,
    requested_levels,
)
from bwim.calibration.problem import (
    DynamicObjective,
    ParameterSpace,
    StaticObjective,
    neighbour_map,
    noise_weights,
    peak_weights,
)
from bwim.calibration.quasistatic import MassFit, fit_mass
from bwim.calibration.sensitivity import Identifiability, identifiability
from bwim.calibration.stages import SUBSTRUCTURED_SMOOTHING, Method, StageResult, run_stage
from bwim.errors import InputError, parse_enum
from bwim.fe.bridge import Bridge
from bwim.fe.convergence import MeshConvergence, check_mesh
from bwim.optimize import OptimizeResult
from bwim.records import Record
from bwim.road import RoadProfile
from bwim.vehicles import Vehicle

__all__ = ["FREE_MASS_BOUNDS", "FREE_MASS_MODES", "FREE_MASS_PERIODS", "Calibration",
           "MassSource", "Refine", "calibrate"]


_REFINE_NAME = "joint refinement (dynamic)"

#: Relative tolerance of the mesh check behind ``weights="model"`` when ``mesh_check``
#: is not given.
DEFAULT_MESH_TOL = 0.01


class Refine(StrEnum):
    """Optional joint dynamic refinement after the two stages."""

    NONE = "none"
    LM = "lm"


class MassSource(StrEnum):
    """Where the calibrated mass comes from (module docstring)."""

    AUTO = "auto"  #: the free vibration when the records have one, else the stages
    FREE = "free"  #: the free vibration after exit, required
    DYNAMIC = "dynamic"  #: the stages' dynamic misfit (the paper's)


#: Modes of the free-vibration mass fit: the first (the higher modes' frequencies also
#: carry the transverse stiffness's error into the mass).
FREE_MASS_MODES = 1
#: Search box of the free-vibration mass scale, factors of the stages' masses; a scale at
#: either end is a failed fit.
FREE_MASS_BOUNDS = (0.5, 2.0)
#: Periods of the model's first mode (the stages' model) a record's free vibration after
#: exit must hold to be fitted.
FREE_MASS_PERIODS = 3.0


@dataclass(frozen=True, kw_only=True, eq=False)
class Calibration(OptimizeResult):
    """A calibrated bridge model, with the calibration's outcome in
    :mod:`scipy.optimize`'s vocabulary.

    Attributes
    ----------
    bridge : Bridge
        The calibrated model.
    params : dict of str to ndarray
        The calibrated parameter families.
    uncertainty : dict of str to ndarray
        Their uncertainty (see module docstring), same shapes.
    x : ndarray
        The calibrated parameter vector, SI units, in the order of ``labels``: the
        families of ``unknowns`` in turn, one entry per zone or girder (one for a family
        shared by identical girders: their common value).
    labels : tuple of str
        The entries of ``x``, ``"family[i]"``.
    fun : float
        The objective of the last stage at its answer (the summed squared misfit,
        :attr:`StageResult.fun`): by default the joint refinement's dynamic misfit; with
        the mesh correction, against the last pass's corrected readings.  With the mass
        from the free vibration (:attr:`mass`) it is the stages' misfit, before the
        masses were scaled (``x`` holds the scaled masses).
    nfev : int
        Objective evaluations over all stages.
    nit : int
        Iterations over all stages (each stage's ``nit``).
    success : bool
        Every stage stopped normally and, with the mesh correction, its passes converged;
        with ``mass="free"``, the free-vibration fit succeeded too.
    message : str
        Why the calibration stopped: the first stage that did not succeed, the
        correction that did not converge, or the last stage's message.
    stages : tuple of StageResult
    wall_time : float
        Seconds.
    identifiability : Identifiability
    two_stage : dict of str to ndarray
        The parameters after the paper's two stages (before the refinement; equal to
        ``params`` when ``refine="none"``).
    weighting : str
        How channels were weighted: "none", "noise", "peak" or "given".
    discretisation : MeshConvergence or None
        The model's discretisation error at the sensors
        (:func:`bwim.fe.convergence.check_mesh`), when ``calibrate`` was asked for it.
    mesh_correction : MeshCorrection or None
        What the mesh defect correction did (``mesh_correction=``): its passes, parameter
        changes and defect.  ``two_stage`` then holds the paper's two stages on the
        uncorrected model, ``params`` the corrected answer.
    mass : MassFit or None
        The free-vibration mass fit (``mass=``; its ``x`` scales the stages' masses), or
        None when the mass is the stages' (``mass="dynamic"``, no mass unknown, or
        ``"auto"`` without a free vibration to fit).
    """

    bridge: Bridge
    params: dict
    uncertainty: dict
    labels: tuple[str, ...]
    stages: tuple[StageResult, ...]
    wall_time: float
    identifiability: Identifiability
    two_stage: dict = field(default_factory=dict)
    weighting: str = "none"
    discretisation: MeshConvergence | None = None
    mesh_correction: MeshCorrection | None = None
    mass: MassFit | None = None

    @property
    def history(self) -> tuple[object, ...]:
        return tuple(s.history for s in self.stages)

    def plot(self, stage: int = 0, ax=None, **kw):
        """CE convergence of one parameter of ``stages[stage]`` (see
        :meth:`StageResult.plot`); returns the figure."""
        return self.stages[stage].plot(ax=ax, **kw)


@dataclass(frozen=True, kw_only=True)
class _Stage:
    """One planned stage of :func:`calibrate`."""

    name: str
    families: tuple[str, ...]
    dynamic: bool
    method: Method
    population: int | None
    max_evals: int | None
    substructured: bool
    keeps_uncertainty: bool


def calibrate(
    start_bridge: Bridge,
    records: Record | Sequence[Record],
    vehicle: Vehicle,
    *,
    road: RoadProfile | None = None,
    unknowns: Sequence[str] | None = None,
    seed: int | np.random.Generator | None = None,
    method: Method | str = Method.CE,
    refine: Refine | str = Refine.LM,
    approach: float | None = None,
    population: int | tuple[int, int] | None = None,
    elite_fraction: float = 0.05,
    convergences: int = 3,
    max_evals: int | tuple[int, int] | None = None,
    bounds: tuple[float, float] = (0.2, 5.0),
    substructure: bool | None = None,
    shared_girders: bool = True,
    weights=None,
    mesh_check: float | None = None,
    mesh_correction: int | str = 0,
    mass: MassSource | str = MassSource.AUTO,
    n_modes: int | None = None,
    n_jobs: int = 1,
    client=None,
    callback: Callable[[str, int, float], None] | None = None,
    ce_options: dict | None = None,
) -> Calibration:
    """Calibrate a bridge model from crossings of a truck of known weight.

    Parameters
    ----------
    start_bridge : Bridge
        The starting model (its zones define the unknowns' layout; its parameter values
        are the starting means).
    records : Record or sequence of Record
        Strain records of the calibration truck (one passage each; several speeds, lanes
        or runs stack).
    vehicle : Vehicle
        The calibration truck (its static wheel loads, and its dynamic model for the mass
        stage).
    road : RoadProfile, optional
        The road the crossings were made on (default flat), for the dynamic stages.
    unknowns : sequence of str
        Parameter families to calibrate: stiffness ones (``E_x``, ``E_y``, ``E_girder``)
        in stage 1, mass ones (``mu``, ``mu_girder``) in stage 2.  Default: those of
        ``E_x``, ``E_y``, ``mu`` the bridge has (``E_x``, ``mu`` on a beam).
    seed : int or Generator
        Randomness of the population methods.
    method : "ce", "lm" or "cma"
    refine : "lm" or "none"
        The joint dynamic refinement after the two stages (see module docstring).
    approach : float, optional
        Run-up length of the crossings, m (the vehicle's dynamic state on entry); default
        each record's own (:attr:`~bwim.Record.settings`, set by :func:`bwim.simulate`),
        else :data:`~bwim.dynamics.DEFAULT_APPROACH`.
    population : int or (int, int), optional
        CE/CMA population of the static and dynamic stages (default 200 and
        ``clip(10 × n_unknowns, 40, 100)``).
    elite_fraction, convergences : CE settings (paper: 5 %, but at least
        :data:`~bwim.calibration.stages.MIN_ELITE` trials; convergences with variance
        injection).
    max_evals : int or (int, int), optional
        Evaluation budget of the static and dynamic stages.
    bounds : (float, float)
        Search box as factors of the starting values.
    substructure : bool, optional
        Sub-structured CE (default: when the bridge has more than one zone).
    shared_girders : bool
        Calibrate one ``E_girder`` and one ``mu_girder`` for all girders (the paper's
        §5.4; identical girders), rather than one per girder.
    weights : "none", "noise", "peak" or sequence of arrays, optional
        Per-record, per-channel weights of the squared residuals.  Default (None,
        "none"): 1, the paper's plain sum.  "noise": ``1 / σ̂²`` with each channel's noise
        estimated from the data (:func:`~bwim.calibration.problem.noise_weights`; assumes
        no noise model).  "peak": ``1 / peak²``
        (:func:`~bwim.calibration.problem.peak_weights`; maximum likelihood only for the
        paper's noise proportional to each channel's peak).  "model": ``1 / (σ̂² + e²)``
        with ``e`` the starting model's discretisation error at each sensor
        (:func:`bwim.fe.convergence.check_mesh` under the truck's static loads where its
        strains peak): channels the mesh cannot reproduce weigh less.
    mesh_check : float, optional
        Relative tolerance of a mesh-convergence check of the *calibrated* model at the
        sensors under the calibration truck's static loads
        (:func:`bwim.fe.convergence.check_mesh`); its discretisation error per sensor is
        :attr:`Calibration.discretisation`.  Default: no check.
    mesh_correction : int or "auto"
        Remove the model's discretisation error by defect correction
        (:mod:`bwim.calibration.meshdefect`): after the stages, the crossings are simulated
        on the calibrated model and on it bisected ``mesh_correction`` times (1 to
        :data:`~bwim.calibration.meshdefect.MAX_LEVELS`); the measured readings minus
        that difference are calibrated again from the answer (least squares, the same
        stages), until no parameter moves by more than
        :data:`~bwim.calibration.meshdefect.TOL` (at most
        :data:`~bwim.calibration.meshdefect.MAX_PASSES` passes).  The answer is the finer
        model's calibration at the cost of a few of its simulations.  ``"auto"``: as many
        bisections as :func:`~bwim.fe.convergence.check_mesh` of the starting model needs
        to bring its estimated error below ``mesh_check`` (default
        :data:`~bwim.calibration.meshdefect.AUTO_TOL`) at every sensor, at most
        :data:`~bwim.calibration.meshdefect.AUTO_MAX_LEVELS`; none if it is already
        there.  Default 0: no correction.  See :attr:`Calibration.mesh_correction`.
    mass : "auto", "free" or "dynamic"
        Where the mass comes from (module docstring): ``"free"``, one scale of every mass
        family fitted to the free vibration after the truck leaves (needs every mass
        family of the bridge among ``unknowns`` and a tail of at least
        :data:`FREE_MASS_PERIODS` (three) periods of the model's first mode recorded; a fit
        that fails, the free vibration not out of the noise or the scale at a bound, gives
        ``success=False`` with the reason); ``"dynamic"``, the stages' answer (the
        paper's); ``"auto"`` (default), ``"free"`` when those hold, else ``"dynamic"`` (a
        failed fit then keeps the stages' masses and says why in ``message``, without
        failing the calibration).  The scale is
        searched within :data:`FREE_MASS_BOUNDS` of the stages' masses.  See
        :attr:`Calibration.mass`.
    n_modes : int, optional
        Modes of the dynamic simulations (default: up to sampling_rate / 8).
    n_jobs, client
        Parallel evaluation of populations (joblib workers or a dask client).
    callback : callable, optional
        ``callback(stage, iteration, best_objective)`` after each iteration.
    ce_options : dict, optional
        Further :class:`~bwim.optimize.CrossEntropy` options (smoothing, tol, injection…).
    """
    t0 = time.perf_counter()
    method = parse_enum(Method, method, "method")
    refine = parse_enum(Refine, refine, "refine")
    mass = parse_enum(MassSource, mass, "mass")
    if isinstance(start_bridge, Bridge) and unknowns is None:
        unknowns = tuple(u for u in ("E_x", "E_y", "mu") if u in start_bridge.params)
    records = _check_inputs(start_bridge, records, unknowns, bounds)
    _check_options(population=population, max_evals=max_evals, n_jobs=n_jobs,
                   n_modes=n_modes, elite_fraction=elite_fraction,
                   weights=None if isinstance(weights, str) else weights,
                   n_records=len(records))
    weighting, weights, disc = _weights(weights, records, start_bridge, vehicle, mesh_check)
    unknowns = tuple(unknowns)
    ctx = _Context(vehicle=vehicle, road=road, approach=approach, n_modes=n_modes,
                   weights=weights, bounds=bounds, rng=np.random.default_rng(seed),
                   shared=frozenset(Bridge.GIRDER_FAMILIES if shared_girders else ()),
                   elite_fraction=elite_fraction, convergences=convergences, n_jobs=n_jobs,
                   client=client, callback=callback, ce_options=ce_options)
    levels = _correction_levels(mesh_correction, start_bridge, records, vehicle, mesh_check)
    first = _run_plan(_plan(start_bridge, unknowns, method, refine, population, max_evals,
                            substructure), start_bridge, records, ctx)
    passes, correction = [first], None
    if levels:
        mesh = _DynamicCorrection(levels, plan=_plan(first.bridge, unknowns, Method.LM, refine,
                                                     None, max_evals, False),
                                  unknowns=unknowns, records=records, ctx=ctx)
        correction = mesh.solve(first)
        passes += mesh.states
    free = _free_mass(mass, passes[-1].bridge, correction, unknowns, records, ctx)
    return _result(passes, correction, free, mass is MassSource.FREE, unknowns=unknowns,
                   records=records, ctx=ctx, weighting=weighting, disc=disc,
                   mesh_check=mesh_check, t0=t0)


def _free_mass(mass: MassSource, bridge: Bridge, correction: MeshCorrection | None,
               unknowns: tuple[str, ...], records: list[Record],
               ctx: _Context) -> MassFit | None:
    """The free-vibration mass fit ``mass`` asks for (None: keep the stages' masses)."""
    if mass is MassSource.DYNAMIC:
        return None
    families = [f for f in Bridge.MASS_FAMILIES if f in bridge.params]
    missing = [f for f in families if f not in unknowns]
    if missing or not families:
        if mass is MassSource.AUTO:
            return None
        why = (f"the mass families {missing} are not among the unknowns" if missing
               else "the bridge has no mass family")
        return MassFit(x=np.nan, fun=np.nan, frequencies=np.zeros(0), n_samples=0,
                       success=False, message=f"mass='free': {why}")
    model = correction.bridge if correction is not None else bridge
    lo, hi = FREE_MASS_BOUNDS
    # fit_mass counts periods of the search box's highest first frequency, f1 / sqrt(lo)
    fit = fit_mass(model, records, n_modes=FREE_MASS_MODES, weights=ctx.weights,
                   bounds=FREE_MASS_BOUNDS, min_periods=FREE_MASS_PERIODS / np.sqrt(lo))
    if mass is MassSource.AUTO and fit.n_samples == 0:
        return None
    if fit.success and not lo * (1 + 1e-3) < fit.x < hi * (1 - 1e-3):
        fit = replace(fit, success=False, message=f"the mass scale {fit.x:.4g} reached a "
                                                  f"bound of {FREE_MASS_BOUNDS}")
    return fit


def _result(passes: list[_Pass], correction: MeshCorrection | None, free: MassFit | None,
            free_required: bool, *,
            unknowns: tuple[str, ...], records: list[Record], ctx: _Context, weighting: str,
            disc: MeshConvergence | None, mesh_check: float | None, t0: float) -> Calibration:
    """The last pass's model and uncertainties (its masses scaled by the free-vibration
    fit ``free`` when it succeeded; a failed fit fails the calibration when
    ``free_required``), the first pass's two stages, every stage, the
    identifiability and mesh check of the answer, and the outcome in scipy's terms."""
    current, uncertainty = passes[-1].bridge, dict(passes[-1].uncertainty)
    if free is not None and free.success:
        scaled = {f: current.params[f] * free.x for f in Bridge.MASS_FAMILIES
                  if f in current.params}
        current = current.with_params(**scaled)
        uncertainty.update({f: np.abs(v) * free.standard_error / free.x
                            for f, v in scaled.items()})
        if correction is not None:
            correction = replace(correction, bridge=correction.bridge.with_params(**scaled))
    stages = tuple(s for p in passes for s in p.stages)
    two_stage = passes[0].two_stage
    stiff = tuple(u for u in unknowns if u in Bridge.STIFFNESS_FAMILIES)
    report = identifiability(current, records, ctx.vehicle, names=stiff or None)
    params = {u: current.params[u] for u in unknowns}
    unc = {u: uncertainty.get(u, np.full(params[u].shape, np.nan)) for u in unknowns}
    two = {u: two_stage.get(u, params[u]) for u in unknowns}
    if mesh_check is not None:
        disc = check_mesh(current, records[0].sensors,
                          _static_loads(records[0], ctx.vehicle, current), tol=mesh_check)
    space = ParameterSpace(current, unknowns, ctx.shared)
    failed = [s for s in stages if not s.success]
    if failed:
        message = (f"{len(failed)} of {len(stages)} stages did not succeed; the first, "
                   f"{failed[0].name}: {failed[0].message}")
    elif correction is not None and not correction.converged:
        message = correction.summary()
    elif free is not None and not free.success:
        message = (f"the free-vibration mass fit did not succeed ({free.message}); the "
                   "masses are the stages'")
    else:
        message = f"every stage succeeded; the last, {stages[-1].name}: {stages[-1].message}"
    return Calibration(bridge=current, params=params, uncertainty=unc, stages=stages,
                       x=space.vector(), labels=tuple(space.labels()), fun=stages[-1].fun,
                       nfev=sum(s.nfev for s in stages), nit=sum(s.nit for s in stages),
                       success=not failed and (correction is None or correction.converged)
                       and (free is None or free.success or not free_required),
                       message=message, wall_time=time.perf_counter() - t0,
                       identifiability=report, two_stage=two, weighting=weighting,
                       discretisation=disc, mesh_correction=correction, mass=free)


def _weights(weights, records: list[Record], bridge: Bridge, vehicle: Vehicle,
             mesh_check: float | None):
    """``(name, per-record channel weights, mesh check or None)`` from ``weights``."""
    if weights is None:
        return "none", None, None
    if isinstance(weights, str):
        key = weights.strip().lower()
        if key == "none":
            return "none", None, None
        if key == "noise":
            return "noise", noise_weights(records), None
        if key == "peak":
            return "peak", peak_weights(records), None
        if key == "model":
            mc = check_mesh(bridge, records[0].sensors,
                            _static_loads(records[0], vehicle, bridge),
                            tol=mesh_check or DEFAULT_MESH_TOL)
            err = np.abs(mc.error[0]).max(axis=0)
            return "model", noise_weights(records, model_error=err), mc
        raise InputError(f"weights must be 'none', 'noise', 'peak', 'model' or arrays, got "
                         f"{weights!r}")
    return "given", list(weights), None


def _static_loads(record: Record, vehicle: Vehicle, bridge: Bridge):
    """The calibration truck's static wheel loads at its position of peak total strain
    in ``record`` (the load case of the mesh check)."""
    from bwim.loads import PointLoad

    p = record.passage
    k = int(np.argmax(np.abs(record.data).sum(axis=1)))
    x = p.wheel_x(record.time[k : k + 1])[0]
    y = p.wheel_y if bridge.is_plate else np.zeros_like(x)
    f = vehicle.model().static_forces
    return [PointLoad(x=float(xi), y=float(yi), P=float(fi))
            for xi, yi, fi in zip(x, y, f, strict=True) if 0 < xi < bridge.length]


def _check_inputs(start_bridge, records, unknowns, bounds) -> list[Record]:
    """The records as a list, after checking the bridge, the unknowns and the bounds."""
    if not isinstance(start_bridge, Bridge):
        raise InputError(f"start_bridge must be a bwim.Bridge, got {type(start_bridge).__name__}")
    if isinstance(records, Record):
        records = [records]
    elif records is None or isinstance(records, (str, bytes)) or not hasattr(records,
                                                                            "__iter__"):
        raise InputError(f"records must be a bwim.Record or a sequence of them, got "
                         f"{type(records).__name__}")
    records = list(records)
    if not records:
        raise InputError("records must hold at least one record")
    for k, r in enumerate(records):
        if not isinstance(r, Record):
            raise InputError(f"records[{k}] must be a bwim.Record, got {type(r).__name__}")
    if unknowns is None or isinstance(unknowns, str):
        raise InputError(f"unknowns must be a sequence of parameter names, got {unknowns!r}")
    present = start_bridge.params
    for u in unknowns:
        if u not in present:
            raise InputError(f"unknown {u!r} is not a parameter of this bridge; it has "
                             f"{sorted(present)}")
    if not tuple(unknowns):
        raise InputError("unknowns must name at least one parameter family")
    try:
        lo_f, hi_f = (float(b) for b in bounds)
    except (TypeError, ValueError):
        raise InputError(f"bounds must be two factors (low, high), got {bounds!r}") from None
    if not 0 < lo_f < 1 < hi_f:
        raise InputError(f"bounds must be factors (low < 1 < high), got {bounds}")
    return records


def _positive_int(name: str, value, low: int = 1) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")


def _check_options(*, population, max_evals, n_jobs, n_modes, elite_fraction, weights,
                   n_records) -> None:
    """calibrate's numeric options: refused (never silently replaced) when out of range."""
    for name, value, low in (("population", population, 2), ("max_evals", max_evals, 1)):
        if value is None:
            continue
        for v in (value if isinstance(value, tuple) else (value,)):
            _positive_int(name, v, low)
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, (int, np.integer)) or (
            n_jobs < 1 and n_jobs != -1):
        raise InputError(f"n_jobs must be a positive integer or -1 (all cores), got {n_jobs!r}")
    if n_modes is not None:
        _positive_int("n_modes", n_modes)
    if not isinstance(elite_fraction, (int, float, np.number)) or not (
            0.0 < float(elite_fraction) <= 1.0):
        raise InputError(f"elite_fraction must lie in (0, 1], got {elite_fraction!r}")
    if weights is not None:
        if isinstance(weights, (str, bytes)) or not hasattr(weights, "__len__") or len(
                weights) != n_records:
            raise InputError(f"weights must hold one array per record ({n_records})")
        for k, w in enumerate(weights):
            try:
                arr = np.asarray(w, dtype=float)
            except (TypeError, ValueError):
                raise InputError(f"weights[{k}] must be an array of numbers") from None
            if not np.all(np.isfinite(arr)) or np.any(arr < 0):
                raise InputError(f"weights[{k}] must be finite and >= 0")


def _pair(value) -> tuple:
    """``(static, dynamic)`` from one value for both or a pair."""
    return value if isinstance(value, tuple) else (value, value)


def _plan(bridge: Bridge, unknowns: tuple[str, ...], method: Method, refine: Refine,
          population, max_evals, substructure: bool | None) -> list[_Stage]:
    """The stages to run: stiffness (static), mass (dynamic), then the refinement."""
    pop_s, pop_d = _pair(population)
    ev_s, ev_d = _pair(max_evals)
    sub = (bridge.n_zones > 1 if substructure is None else substructure) and (
        method is Method.CE)
    stiff = tuple(u for u in unknowns if u in Bridge.STIFFNESS_FAMILIES)
    mass = tuple(u for u in unknowns if u in Bridge.MASS_FAMILIES)
    plan = []
    if stiff:
        plan.append(_Stage(name="stiffness (static)", families=stiff, dynamic=False,
                           method=method, population=pop_s, max_evals=ev_s,
                           substructured=sub, keeps_uncertainty=True))
    if mass:
        plan.append(_Stage(name="mass (dynamic)", families=mass, dynamic=True,
                           method=method, population=pop_d, max_evals=ev_d,
                           substructured=sub, keeps_uncertainty=True))
    if refine is Refine.LM:
        # CE's elite spread stays the reported uncertainty; otherwise the last LM's
        plan.append(_Stage(name=_REFINE_NAME, families=unknowns,
                           dynamic=True, method=Method.LM, population=None, max_evals=ev_d,
                           substructured=False, keeps_uncertainty=method is not Method.CE))
    return plan


def _population(stage: _Stage, n_params: int) -> int | None:
    """The stage's population (defaults: 200 static, ``clip(10 n, 40, 100)`` dynamic)."""
    if stage.method is Method.LM:
        return None
    if stage.population:
        return stage.population
    return int(np.clip(10 * n_params, 40, 100)) if stage.dynamic else 200


def _ce_options(stage: _Stage, ce_options: dict | None) -> dict | None:
    """CrossEntropy options of a CE stage (smoothing by default when sub-structured)."""
    if stage.method is not Method.CE:
        return None
    opts = dict(ce_options or {})
    if stage.substructured:  # std smoothing makes sub-structured CE reliable on NLC problems
        opts.setdefault("smoothing", SUBSTRUCTURED_SMOOTHING)
    return opts


@dataclass(frozen=True, kw_only=True, eq=False)
class _Context:
    """What every stage of one :func:`calibrate` call shares."""

    vehicle: Vehicle
    road: RoadProfile | None
    approach: float | None
    n_modes: int | None
    weights: list | None
    bounds: tuple[float, float]
    rng: np.random.Generator
    shared: frozenset
    elite_fraction: float
    convergences: int
    n_jobs: int
    client: object
    callback: Callable | None
    ce_options: dict | None


@dataclass(frozen=True, kw_only=True, eq=False)
class _Pass:
    """One run of a plan: the model it ends on, its stages, the uncertainties they kept
    and the parameters after the paper's two stages."""

    bridge: Bridge
    stages: tuple[StageResult, ...]
    uncertainty: dict
    two_stage: dict


def _run_plan(plan: list[_Stage], bridge: Bridge, records: list[Record], ctx: _Context,
              suffix: str = "") -> _Pass:
    """Run the stages of ``plan`` in turn from ``bridge``, each from the last's answer."""
    current = bridge
    stages: list[StageResult] = []
    uncertainty: dict[str, np.ndarray] = {}
    two_stage: dict[str, np.ndarray] = {}
    for stage in plan:
        space = ParameterSpace(current, stage.families, ctx.shared)
        if stage.dynamic:
            objective = DynamicObjective(space, records, ctx.vehicle, ctx.road, current,
                                         approach=ctx.approach, n_modes=ctx.n_modes,
                                         weights=ctx.weights)
        else:
            objective = StaticObjective(space, records, ctx.vehicle, base=current,
                                        weights=ctx.weights)
        result = run_stage(
            stage.method, objective, space, name=stage.name + suffix, bounds=ctx.bounds,
            seed=ctx.rng, population=_population(stage, space.n),
            elite_fraction=ctx.elite_fraction, convergences=ctx.convergences,
            max_evals=stage.max_evals,
            neighbours=neighbour_map(space, records[0].sensors) if stage.substructured
            else None, n_jobs=ctx.n_jobs, client=ctx.client, callback=ctx.callback,
            options=_ce_options(stage, ctx.ce_options))
        current = space.bridge(result.x, current)
        stages.append(result)
        if stage.method is not Method.LM or stage.name != _REFINE_NAME:
            two_stage.update({f: current.params[f] for f in stage.families})
        if stage.keeps_uncertainty:
            uncertainty.update(space.split(result.uncertainty))
    return _Pass(bridge=current, stages=tuple(stages), uncertainty=uncertainty,
                 two_stage=two_stage)


def _correction_levels(mesh_correction, bridge: Bridge, records: list[Record],
                       vehicle: Vehicle, mesh_check: float | None) -> int:
    """Bisections of the corrector model (0: no correction); see ``calibrate``."""
    if isinstance(mesh_correction, str):
        if mesh_correction.strip().lower() != "auto":
            check_levels(mesh_correction)  # the one-line error
        mc = check_mesh(bridge, records[0].sensors, _static_loads(records[0], vehicle, bridge),
                        tol=mesh_check or AUTO_TOL, max_levels=AUTO_MAX_LEVELS + 1)
        return AUTO_MAX_LEVELS if mc.adequate is None else mc.meshes.index(mc.adequate)
    return requested_levels(mesh_correction)


class _DynamicCorrection(DefectCorrection):
    """:func:`calibrate`'s defect correction (meshdefect module docstring): the crossings
    re-simulated on the model and on its corrector; each pass runs ``plan`` (least
    squares) on the measured readings less the defect.  A state is a :class:`_Pass`."""

    def __init__(self, levels: int, *, plan: list[_Stage], unknowns: tuple[str, ...],
                 records: list[Record], ctx: _Context) -> None:
        super().__init__(levels)
        self.plan, self.unknowns, self.records, self.ctx = plan, unknowns, records, ctx
        self.peak = max(float(np.abs(r.data).max()) for r in records)
        self.corrected = records

    def model(self, state: _Pass) -> Bridge:
        return state.bridge

    def correct(self, state: _Pass, coarse: Bridge, fine: Bridge) -> float:
        ctx = self.ctx
        d = mesh_defects(coarse, self.records, ctx.vehicle, ctx.road, fine=fine,
                         approach=ctx.approach, n_modes=ctx.n_modes)
        self.corrected = [replace(r, data=r.data - dk)
                          for r, dk in zip(self.records, d, strict=True)]
        return max(float(np.abs(dk).max()) for dk in d) / self.peak

    def refit(self, state: _Pass, k: int) -> _Pass:
        return _run_plan(self.plan, state.bridge, self.corrected, self.ctx,
                         suffix=f", mesh pass {k}")

    def change(self, old: _Pass, new: _Pass) -> float:
        return max(float(np.abs(new.bridge.params[u] / old.bridge.params[u] - 1).max())
                   for u in self.unknowns)
