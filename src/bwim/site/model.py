"""A site's finite-element model calibrated from its logger files, checked on its own runs.

Contract
--------
* :func:`calibrate_site_model` takes the calibration runs (logger records, as for
  :func:`~bwim.site.calibrate_site`), the site calibration made from them (its detection
  of each run, its rejection of runs with other traffic, each run's drift factor) and a
  starting bridge model (geometry, nominal modulus and density), and fits with
  :func:`~bwim.calibration.calibrate_logger`:

  - the stiffness ratios (``E_y`` of a plate, one per zone: each declared joint's own,
    ``joints=`` passed to the fit) with ``E_x`` kept as the scale reference,
  - the gains (one common logger scale by default: logger units per unit of model strain;
    with gains fitted the overall modulus and the units are one unknown),
  - the offsets and baseline slopes of every channel in every run,
  - ``origin``: where the detectors' frame (x = 0 at the calibration lane's first axle
    detector) lies on the model (m), and ``lateral``: the offset of detected lateral
    positions (m),
  - the mass from the free vibration when the records show it above the noise,
  - the mesh's discretisation error, by defect correction with a bisected model when the
    start's mesh check at the gauges asks for it (``mesh_correction="auto"``; the model
    is then the bisected one).

  No passage and no road are given: the passages are the detected ones with the
  calibration truck's declared spacings, each wheel pair ``track_width`` apart
  (``track_width``, default :data:`DEFAULT_TRACK`); the
  road-free method needs no road (docs/theory.md §13).  Each run is divided by its drift
  factor from the site calibration, so the gains belong to the same reference as the
  drift correction of traffic.
* **The weighing calibrated as it is done**: the fit pins the model's strain per newton
  over each run's whole time on the span, while the MFI's weight is a regularised force's
  mean over the central part of each axle's time; a model-form error (point gauges for
  gauges that average over the load's spread, a coarse mesh) moves the two apart by a
  few per cent.  So the used runs are weighed by MFI as traffic is, and the gains are
  multiplied by the mean ratio of weighed to declared GVW (``weighing_scale``); the
  RMS over the runs of the MFI's relative residual beyond their noise is the model's
  error (``model_error``), and a vehicle's weighing is ``residual_high`` beyond
  :data:`RESIDUAL_FACTOR` × what its noise (:func:`noise_share`) and that error (grown as
  √(truck / weight) for a lighter vehicle) explain (:meth:`SiteModel.residual_limit`).
  Each fold of the self-check does the same with its own runs.
* **Self-consistency** (leave-one-out): each used run is weighed, exactly as traffic is
  (:func:`~bwim.site.weigh_event` with detection, drift and plausibility checks), by the
  model calibrated without it; its GVW error against the declared truck is
  ``ModelRun.gvw_error``.  The model is **accepted** only when its fit succeeded (no
  parameter at a bound) and every run is weighed within ``tolerance`` (default
  :data:`DEFAULT_TOLERANCE`, the GVW tolerance of COST 323 class B(10)); otherwise
  ``accepted`` is False with the reason, and :func:`~bwim.site.weigh_event` refuses every
  vehicle it would weigh with this model (never a weight from a model that cannot weigh
  its own calibration truck).
* Weighing with the model (:meth:`SiteModel.readings`): the gauges' readings less their
  mean before the first axle arrives, divided by the drift factor and by each gauge's
  gain, the passage moved into the model's frame (``origin``, ``lateral``) with the
  model's track.  Only the calibration lane's direction is weighed this way.
* Units: N, m, s, Pa; gains in logger units per unit strain.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from bwim.calibration.logger import GAIN_MODES, LoggerCalibration, calibrate_logger
from bwim.calibration.problem import estimate_noise
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.mfi.identify import MAX_RESIDUAL
from bwim.records import Passage, Record

if TYPE_CHECKING:  # pragma: no cover
    from bwim.site.calibrate import SiteCalibration

__all__ = ["DEFAULT_TOLERANCE", "DEFAULT_TRACK", "MAX_WEIGHT_RATIO", "RESIDUAL_FACTOR",
           "ModelRun", "SiteModel",
           "calibrate_site_model", "noise_share"]

#: m: a heavy vehicle's track, centre to centre of its wheels' contact (the calibration
#: truck's when the scenario does not state it).
DEFAULT_TRACK = 1.9
#: The largest leave-one-out GVW error (fraction) of an accepted model: COST 323's GVW
#: tolerance of class B(10).
DEFAULT_TOLERANCE = 0.10
#: A weighing's relative residual may be this many times what the readings' noise and the
#: model's error on its own runs explain (``residual_high`` beyond).
RESIDUAL_FACTOR = 1.5
#: The residual limit grows with the calibration truck's weight over the vehicle's up to
#: this ratio (the model's error at most doubled): the weight is the weighing's own, and a
#: vehicle weighed far too light would otherwise loosen the check that should catch it
#: (review of stop 37: 9.4 kN for a 78 kN vehicle, residual 0.78 accepted under a limit
#: raised to 0.85).
MAX_WEIGHT_RATIO = 4.0


@dataclass(frozen=True, kw_only=True)
class ModelRun:
    """One calibration run in the model's self-check.

    Attributes
    ----------
    index : int
        Position of the run in the records given.
    explained : float
        Share of the run's filtered load response the full model explains.
    gvw_error : float
        GVW weighed by the model fitted without this run, over the declared, minus 1
        (nan when it was not weighed).
    reason : str
        Why the run was not weighed ("" when it was).
    """

    index: int
    explained: float
    gvw_error: float
    reason: str = ""


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteModel:
    """A bridge model with the logger's gains and the detectors' frame (module contract).

    Attributes
    ----------
    bridge : Bridge
    gains : mapping of str to float
        Logger units per unit of model strain, per gauge channel (empty: readings already
        in strain; otherwise a gauge without a gain is refused).
    origin, lateral : float
        The detectors' frame on the model: x of its origin, offset of lateral positions (m).
    track_width : float or None
        The wheels' track of a weighed vehicle (m; None: the detected passage's own).
    tolerance : float
        The largest leave-one-out GVW error accepted (fraction).
    accepted : bool
    reason : str
        Why the model is not accepted ("" when it is).
    runs : tuple of ModelRun
    fit : LoggerCalibration or None
        The full fit (None for a model read from a file).
    weighing_scale : float
        The factor the fit's gains were multiplied by so that the model's MFI weighs its
        runs right on average (already in ``gains``; 1 for a bare bridge).
    model_error : float or None
        The model's error on its own runs: the RMS over them of the MFI's relative
        residual beyond what their noise explains (None: not measured).
    truck_weight : float or None
        The calibration truck's declared GVW, N (the weight ``model_error`` belongs to).
    provenance : tuple of str
        What the model was made from, as ``bwim calibrate`` records it: each calibration
        run's file (name and content digest) and each gauge's name and position; a
        weighing with other runs or gauges is refused (``bwim weigh --bridge``).  Empty:
        not recorded (a model made in Python).
    """

    bridge: Bridge
    gains: Mapping[str, float]
    origin: float = 0.0
    lateral: float = 0.0
    track_width: float | None = None
    tolerance: float = DEFAULT_TOLERANCE
    accepted: bool = True
    reason: str = ""
    runs: tuple[ModelRun, ...] = ()
    fit: LoggerCalibration | None = None
    weighing_scale: float = 1.0
    model_error: float | None = None
    truck_weight: float | None = None
    provenance: tuple[str, ...] = ()

    @classmethod
    def of_bridge(cls, bridge: Bridge) -> SiteModel:
        """A bridge used as it is: readings already in strain, passages in its frame."""
        if not isinstance(bridge, Bridge):
            raise InputError(f"bridge must be a Bridge or a SiteModel, got "
                             f"{type(bridge).__name__}")
        return cls(bridge=bridge, gains={})

    @property
    def gvw_errors(self) -> np.ndarray:
        """The runs' leave-one-out GVW errors (fractions; nan: not weighed)."""
        return np.array([r.gvw_error for r in self.runs])

    def passage(self, passage: Passage) -> Passage:
        """A detected passage in the model's frame, with the model's track."""
        return dataclasses.replace(
            passage, delay=passage.delay - self.origin / passage.speed,
            lane=passage.lane + self.lateral,
            track_width=self.track_width if self.track_width is not None
            else passage.track_width)

    def readings(self, record: Record, passage: Passage, factor: float) -> Record:
        """The record's gauges as model strains with the passage in the model's frame
        (module contract).  Raises InputError with the reason when it cannot."""
        gauges = [s for s in record.sensors if s.kind.is_structural]
        if not gauges or any(s.x is None or s.y is None for s in gauges):
            raise InputError("weighing by MFI needs every gauge's position (x, y) in the "
                             "scenario")
        missing = [s.name for s in gauges if self.gains and s.name not in self.gains]
        if missing:
            raise InputError(f"the model has no gain for gauge(s) {', '.join(missing)}: it "
                             "was calibrated with other channels")
        rec = record.channels(gauges)
        moved = self.passage(passage)
        before = moved.axle_x(rec.time)[:, 0] < 0.0
        if np.count_nonzero(before) < 8:
            raise InputError("weighing by MFI needs readings before the first axle reaches "
                             "the bridge (a pre-trigger) to zero the gauges")
        gains = np.array([float(self.gains.get(s.name, 1.0)) for s in gauges])
        data = (rec.data - rec.data[before].mean(axis=0)) / (factor * gains)
        return dataclasses.replace(rec, data=data, passages=(moved,))

    def residual_limit(self, readings: Record, weight: float | None = None) -> float:
        """The relative residual beyond which an MFI weighing of ``readings`` (as
        :meth:`readings` gives them) is ``residual_high``: :data:`RESIDUAL_FACTOR` × what
        the readings' noise and the model's error explain together (the MFI's default
        without a measured model error).  For a vehicle of ``weight`` (N) lighter than
        the calibration truck the model's relative error grows as √(truck / weight): a
        lighter vehicle bounces relatively more (the dynamic part's variance taken
        proportional to the weight, as for the lines, docs/theory.md §15), the ratio at
        most :data:`MAX_WEIGHT_RATIO`."""
        if self.model_error is None:
            return MAX_RESIDUAL
        error = self.model_error
        if weight is not None and self.truck_weight is not None and 0 < weight:
            ratio = min(max(self.truck_weight / weight, 1.0), MAX_WEIGHT_RATIO)
            error *= float(np.sqrt(ratio))
        return RESIDUAL_FACTOR * float(np.hypot(noise_share(readings), error))

    def plot(self, ax=None):
        """Each run's leave-one-out GVW error against the tolerance
        (:func:`bwim.plots.site_model.plot_site_model`); returns the figure."""
        from bwim.plots.site_model import plot_site_model

        return plot_site_model(self, ax=ax)

    def summary(self) -> str:
        """A few lines: the fit, the self-check and the verdict."""
        lines = []
        if self.fit is not None:
            f = self.fit
            params = ", ".join(f"{k} = {v:.4g}" for k, v in f.params.items())
            lines.append(f"fit: {params}; {'converged' if f.success else f.message}; "
                         f"{f.mass_message}")
        err = self.gvw_errors
        done = err[np.isfinite(err)]
        if done.size:
            lines.append(f"leave-one-out GVW errors of {done.size} run(s): mean "
                         f"{100 * done.mean():+.1f} %, largest {100 * np.abs(done).max():.1f} %"
                         f" (tolerance {100 * self.tolerance:.0f} %)")
        if self.model_error is not None:
            lines.append(f"weighing scale {self.weighing_scale:.4f} (the MFI on its own runs), "
                         f"model error {100 * self.model_error:.1f} % of the readings")
        lines.append("accepted" if self.accepted else f"not accepted: {self.reason}")
        return "\n".join(lines)


def calibrate_site_model(
    records: Sequence[Record],
    calibration: SiteCalibration,
    start_bridge: Bridge,
    *,
    track_width: float | None = None,
    gains: str = "common",
    tolerance: float = DEFAULT_TOLERANCE,
    leave_one_out: bool = True,
    identify_options: Mapping[str, Any] | None = None,
    mesh_correction: int | str = "auto",
    progress: Callable[[int, int], None] | None = None,
    **fit_options: Any,
) -> SiteModel:
    """Calibrate ``start_bridge`` from the site's calibration runs and check it on them.

    Parameters
    ----------
    records : sequence of Record
        The calibration runs, the same as those ``calibration`` was made from.
    calibration : SiteCalibration
    start_bridge : Bridge
        Geometry and nominal parameters; gauges need x, y in its frame.
    track_width : float, optional
        The calibration truck's track, m (default :data:`DEFAULT_TRACK`).
    gains : "common" or "per_channel"
    tolerance : float
        The largest leave-one-out GVW error of an accepted model (fraction).
    leave_one_out : bool
        Run the self-check (without it the model is not accepted: nothing has checked it).
    identify_options : mapping, optional
        Options of :func:`bwim.identify_forces` for the self-check's weighing.
    mesh_correction : int or "auto"
        The mesh defect correction of the fit (:func:`bwim.calibration.calibrate_logger`):
        ``"auto"`` (default) bisects the start's mesh as often as its mesh check at the
        gauges asks, none when it is fine enough; the model is then the bisected one.
        Each fold of the self-check uses the full fit's number of bisections.
    progress : callable, optional
        Called ``progress(done, total)`` after each fit: the full fit, then each run's
        fold of the self-check (``total`` = 1 + the runs used, 1 without the self-check).
    **fit_options
        Passed to :func:`bwim.calibration.calibrate_logger` (``cutoff``, ``n_basis``...).
    """
    from bwim.site.calibrate import SiteCalibration
    from bwim.site.event import weigh_event  # the event module weighs with a SiteModel

    if not isinstance(calibration, SiteCalibration):
        raise InputError(f"calibration must be a SiteCalibration (bwim.calibrate_site), got "
                         f"{type(calibration).__name__}")
    if isinstance(records, (str, bytes)) or not isinstance(records, Sequence) or len(
            records) != len(calibration.reasons):
        raise InputError("records must be the calibration runs the site calibration was "
                         "made from")
    if gains not in GAIN_MODES:
        raise InputError(f"gains must be one of {GAIN_MODES}, got {gains!r}")
    cal_pair = calibration.setup.calibration_pair
    if cal_pair is not None and cal_pair.direction != "+x":
        raise InputError("an FE model is calibrated with the truck travelling the bridge's "
                         "+x, but the calibration lane travels -x: give the scenario's x "
                         "from the other end of the bridge (every x as length - x), so "
                         "that the calibration lane travels +x")
    if not isinstance(tolerance, (int, float)) or not 0 < float(tolerance) < 1:
        raise InputError(f"tolerance must be a fraction in (0, 1), got {tolerance!r}")
    if track_width is not None and not isinstance(track_width, (int, float)):
        raise InputError(f"track_width must be a length in m, got {track_width!r}")
    track = DEFAULT_TRACK if track_width is None else float(track_width)
    if not 0.5 <= track <= 3.0:
        raise InputError(f"track_width must be a vehicle's track in 0.5-3 m, got {track!r}")
    setup = calibration.setup
    used = [k for k, (why, fit) in enumerate(zip(calibration.reasons, calibration.fits,
                                                 strict=True))
            if not why and fit is not None and np.isfinite(fit.scale)]
    if len(used) < 2:
        raise InputError(f"the site calibration used {len(used)} run(s): at least two are "
                         "needed to calibrate a model")
    runs = {k: _run(records[k], calibration, k, track) for k in used}
    origin = -float(calibration.lines.support[0])
    loads = setup.calibration_loads

    def fit(keys: Sequence[int], start: Bridge, start_origin: float, start_lateral: float,
            mass: bool, levels: int | str) -> LoggerCalibration:
        options = {"mass": mass, **fit_options}
        return calibrate_logger(start, [runs[k] for k in keys], loads, origin=start_origin,
                                lateral=start_lateral, gains=gains, mesh_correction=levels,
                                **options)

    total = 1 + (len(used) if leave_one_out else 0)
    full = fit(used, start_bridge, origin, 0.0, bool(fit_options.pop("mass", True)),
               mesh_correction)
    if progress is not None:
        progress(1, total)
    levels = full.mesh_correction.levels if full.mesh_correction is not None else 0
    # the folds start from the full fit's parameters on the start's mesh
    fitted = start_bridge.with_params(**full.bridge.params)
    base = SiteModel(bridge=full.bridge, gains={}, track_width=track,
                     tolerance=float(tolerance))
    weigh = partial(weigh_event, calibration=calibration, identify_options=identify_options)
    model = _scaled(base, full, used, records, weigh, setup)
    explained = dict(zip(used, full.explained, strict=True))
    checks = []
    for k in used:
        if not leave_one_out:
            checks.append(ModelRun(index=k, explained=float(explained[k]),
                                   gvw_error=float("nan"), reason="not checked"))
            continue
        # the full fit is the fold's start (its mass kept: one run changes it little)
        others = [j for j in used if j != k]
        fold = _scaled(base, fit(others, fitted, full.origin, full.lateral, False, levels),
                       others, records, weigh, setup)
        checks.append(_check(k, float(explained[k]), weigh(records[k], bridge=fold),
                             setup))
        if progress is not None:
            progress(1 + len(checks), total)
    reason = _verdict(model, checks, float(tolerance), leave_one_out)
    return dataclasses.replace(model, runs=tuple(checks), accepted=not reason, reason=reason)


def noise_share(record: Record) -> float:
    """The share of a record's readings its noise accounts for: ``√(n_t Σ σ_s²) / ‖data‖``
    (σ_s each channel's noise, :func:`~bwim.calibration.estimate_noise`)."""
    sigma = estimate_noise([record])[0]
    norm = float(np.linalg.norm(record.data))
    return float(np.sqrt(record.data.shape[0] * float((sigma**2).sum())) / norm) if norm else 0.0


def _mine(ev, setup):
    """The calibration lane's vehicle of an event weighed with a model (or None)."""
    mine = [v for v in ev.vehicles if v.lane == setup.calibration_lane]
    return mine[0] if len(mine) == 1 else None


def _scaled(base: SiteModel, fit: LoggerCalibration, keys: Sequence[int],
            records: Sequence[Record], weigh, setup) -> SiteModel:
    """The model of ``fit`` with its gains scaled so that its MFI weighs runs ``keys``
    right on average (weighed as traffic is), and its error measured on them.

    The fit pins the model's strain per newton over each run's whole time on the span;
    the weight the MFI reports is the mean of a regularised force over the central part
    of each axle's time, and a model-form error (a point gauge for one that averages over
    the load's spread, a coarse mesh) moves the two apart by a few per cent.  The truck of
    known weight calibrates the weighing as it is done.
    """
    gains = dict(zip(fit.channels, (float(g) for g in fit.gains), strict=True))
    model = dataclasses.replace(base, bridge=fit.bridge, gains=gains, origin=fit.origin,
                                lateral=fit.lateral, fit=fit)
    ratios, excess = [], []
    for k in keys:
        v = _mine(weigh(records[k], bridge=model), setup)
        if v is None or not v.weighed or v.identification is None:
            continue
        ident = v.identification
        ratios.append(float(v.gvw) / float(np.sum(setup.calibration_loads)))
        rec = model.readings(records[k], v.vehicle.passage, float(v.drift_factor))
        excess.append(max(ident.residual**2 - noise_share(rec) ** 2, 0.0))
    if not ratios:
        return model
    scale = float(np.mean(ratios))
    return dataclasses.replace(model, gains={n: g * scale for n, g in gains.items()},
                               weighing_scale=scale,
                               model_error=float(np.sqrt(np.mean(excess))),
                               truck_weight=float(np.sum(setup.calibration_loads)))


def _check(k: int, explained: float, ev, setup) -> ModelRun:
    """Run k weighed by the model fitted without it."""
    v = _mine(ev, setup)
    loads = setup.calibration_loads
    if v is not None and v.weighed and v.gvw is not None:
        return ModelRun(index=k, explained=explained,
                        gvw_error=float(v.gvw / float(np.sum(loads)) - 1))
    why = (v.reason if v is not None else "not one vehicle in its lane") or "not weighed"
    return ModelRun(index=k, explained=explained, gvw_error=float("nan"), reason=why)


def _run(record: Record, calibration: SiteCalibration, k: int, track: float) -> Record:
    """Run k's gauges divided by its drift factor, its detected passage with the truck's
    declared spacings and ``track``."""
    setup = calibration.setup
    det = calibration.detections[k]
    p = det.single.passage
    passage = Passage(speed=p.speed, lane=p.lane, delay=p.delay,
                      axle_spacings=setup.calibration_spacings, track_width=track)
    gauges = [s for s in record.sensors if s.kind.is_structural]
    rec = record.channels(gauges)
    scale = float(calibration.fits[k].scale)
    return dataclasses.replace(rec, data=rec.data / scale, passages=(passage,))


def _verdict(model: SiteModel, checks: list[ModelRun], tolerance: float,
             leave_one_out: bool) -> str:
    full = model.fit
    if not full.success:
        return f"the fit failed: {full.message}"
    if not leave_one_out:
        return "not checked on its own runs (leave_one_out=False)"
    missed = [c for c in checks if c.reason]
    if missed:
        return (f"{len(missed)} calibration run(s) not weighed by the model: "
                f"run {missed[0].index + 1}: {missed[0].reason}")
    worst = max(checks, key=lambda c: abs(c.gvw_error))
    if abs(worst.gvw_error) > tolerance:
        return (f"it weighs its own calibration run {worst.index + 1} at "
                f"{100 * worst.gvw_error:+.1f} % (tolerance {100 * tolerance:.0f} %)")
    return ""
