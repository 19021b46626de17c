"""The demo: calibrate the paper's slab, then weigh a second vehicle, as a report.

Contract
--------
:func:`run_demo` does everything ``bwim demo`` shows and returns a :class:`DemoReport`:
the computed objects, a printable transcript (:meth:`DemoReport.render`, built of text and
:class:`~bwim.tables.Table` blocks) and the sections of its HTML report
(:meth:`DemoReport.sections`).  The command line only prints and writes.  Every number is
computed by the run:

0. the slab's lowest natural frequencies and its static strains under the truck's rear
   axle at mid-span (printed before the run starts);
1. the paper's truck crosses the paper's slab (vehicle–bridge interaction on the true
   bridge) — the calibration record;
2. E_x, E_y and μ are calibrated by Cross-Entropy from E_x × 0.8, E_y × 1.2, μ × 1.25
   (:data:`bwim.paper.reproduce.START`);
3. a second vehicle (the 3-axle rigid truck) crosses at another speed over another
   stretch of road; its forces are identified by MFI with the calibrated and with the
   starting model, and it is weighed by Moses with the influence line calibrated from the
   first crossing.

Units are SI in the objects; the transcript shows kN, µε and %.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bwim import paper
from bwim.calibration import Calibration, calibrate
from bwim.conventions import MICROSTRAIN
from bwim.dynamics.crossing import simulate
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.loads import PointLoad
from bwim.mfi import ForceIdentification, force_errors, identify_forces
from bwim.paper.reproduce import START
from bwim.records import Record
from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values
from bwim.vehicles import three_axle_truck
from bwim.wim import InfluenceLine, StaticWeights, calibrate_influence_line, weigh_static

__all__ = ["DEMO_ROAD_SEED", "DEMO_SPEED", "REPORT_INTRO", "REPORT_TITLE", "SETTINGS",
           "UNKNOWNS", "DemoReport", "DemoSettings", "run_demo"]

DEMO_SPEED = 15.0  #: m/s, the second vehicle
DEMO_ROAD_SEED = 2  #: the second vehicle's stretch of road
MAX_MODES = 50  #: most natural frequencies the summary prints
UNKNOWNS = ("E_x", "E_y", "mu")  #: the calibrated parameter families
SHOWN = ("E_x", "E_y", "μ")  #: ... as the transcript names them

#: Title and introduction of the demo's HTML report.
REPORT_TITLE = "bwim demo: the paper's slab bridge"
REPORT_INTRO = (
    "Everything below was computed by this run: a simulated calibration crossing of the "
    "paper's truck, a Cross-Entropy calibration from a wrong starting model, and the "
    "weighing of a second vehicle by moving force identification (calibrated and starting "
    "model) and by Moses' static algorithm.")


@dataclass(frozen=True)
class DemoSettings:
    """Run-up length (m), CE populations (static, dynamic) and convergences."""

    approach: float
    population: tuple[int, int]
    convergences: int


#: The demo's settings: the default one runs in well under a minute on 2 cores; ``quick``
#: is for the test suite.
SETTINGS = {False: DemoSettings(30.0, (100, 24), 2), True: DemoSettings(10.0, (60, 16), 1)}


@dataclass(frozen=True, kw_only=True, eq=False)
class DemoReport:
    """Everything the demo computed, and how it is shown.

    Attributes
    ----------
    frequencies : ndarray
        The true slab's lowest natural frequencies, Hz.
    static_strain : ndarray, shape (n_x, n_y)
        Longitudinal strain at the sensor grid (x rows, y columns) under the truck's rear
        axle at mid-span (front axle too if on the deck), dimensionless.
    blocks : tuple of str or Table
        The transcript, in order (see :meth:`render`).
    wall_time : float
        Seconds of the whole run.
    """

    truth: Bridge
    start: Bridge
    settings: DemoSettings
    frequencies: np.ndarray
    static_strain: np.ndarray
    calibration_record: Record
    calibration: Calibration
    second_record: Record
    identified: ForceIdentification  # with the calibrated model
    identified_start: ForceIdentification  # with the starting model
    influence_line: InfluenceLine
    moses: StaticWeights
    blocks: tuple[str | Table, ...]
    wall_time: float

    @property
    def tables(self) -> tuple[Table, ...]:
        """The transcript's tables (calibrated parameters, then the weighings)."""
        return tuple(b for b in self.blocks if isinstance(b, Table))

    def render(self) -> str:
        """The transcript as text, as ``bwim demo`` prints it."""
        return "\n".join(_text(b) for b in self.blocks)

    def sections(self) -> list:
        """The sections of the demo's HTML report (:func:`bwim.report.section`), with their
        figures; imports matplotlib."""
        from bwim.report import section

        length = self.truth.length
        true = self.second_record.truth
        return [
            section(self.calibration, "E_x, E_y, μ of the paper's slab", start=self.start,
                    true_bridge=self.truth),
            section(self.calibration_record, "calibration crossing (2-axle truck)",
                    length=length),
            section(self.second_record, "second vehicle (3-axle truck)", length=length),
            section(self.identified, "second vehicle, calibrated model", truth=true),
            section(self.identified_start, "second vehicle, starting (uncalibrated) model",
                    truth=true),
            section(self.influence_line, "calibrated from crossing 1", true_bridge=self.truth),
            section(self.moses, "second vehicle", truth=true),
        ]


def _text(block: str | Table) -> str:
    return block if isinstance(block, str) else block.render()


def _slab_summary(truth: Bridge, n_modes: int) -> tuple[str, np.ndarray, np.ndarray]:
    """The slab's description, frequencies and static strains (text, Hz, strain grid)."""
    grid = truth.model.grid
    frequencies = truth.modes(n_modes).frequencies
    x2 = grid.length / 2  # rear (heavier) axle at mid-span
    x1 = x2 + paper.AXLE_SPACING
    half = paper.TRACK_WIDTH / 2
    loads = [
        PointLoad(x=x, y=paper.LANE + dy, P=p / 2)
        for x, p in ((x1, paper.AXLE_LOADS[0]), (x2, paper.AXLE_LOADS[1]))
        if x <= grid.length
        for dy in (-half, half)
    ]
    sensors = [s for s in paper.sensors() if s.kind.value == "strain_x"]
    xs = sorted({s.x for s in sensors})
    ys = sorted({s.y for s in sensors})
    strain = np.asarray(truth.static(loads, sensors)).reshape(len(xs), len(ys))
    shown = strain / MICROSTRAIN
    lines = [
        "bwim demo: the paper's slab bridge (Dowling, OBrien & González 2012, §5.1)",
        f"  {grid.length:g} m × {grid.width:g} m slab, {grid.nx} × {grid.ny} BFS elements, "
        f"{truth.n_free} free DOF, E = {paper.SLAB_E / 1e9:g} GPa, "
        f"μ = {paper.SLAB_MU:g} kg/m², h = {paper.SLAB_THICKNESS:g} m (assumed)",
        f"\nLowest {n_modes} natural frequencies (Hz):",
        "  " + "  ".join(f"{f:7.2f}" for f in frequencies),
        f"\nStatic longitudinal soffit strain (µε), rear axle "
        f"({paper.AXLE_LOADS[1] / 1e3:g} kN) at mid-span, lane centre y = {paper.LANE:g} m:",
        "   y (m) " + "".join(f"{'x = ' + format(x, 'g') + ' m':>12}" for x in xs),
        *(f"  {y:6.1f} " + "".join(f"{shown[i, j]:12.2f}" for i in range(len(xs)))
          for j, y in enumerate(ys)),
    ]
    return "\n".join(lines), frequencies, strain


def _calibration_table(cal: Calibration, start: Bridge, truth: Bridge) -> Table:
    rows = [(u, f"{t:.5g}", f"{s0:.5g}", format_pct(s0, t), f"{c:.5g}", format_pct(c, t),
             f"{sd:.3g}") for u, c, s0, t, sd in
            param_values(cal.params, start.params, truth.params, cal.uncertainty)]
    return Table(f"   {cal.nfev} evaluations, {cal.wall_time:.1f} s:",
                 ("parameter", "true", "start", "error %", "calibrated", "error %",
                  "uncertainty"), rows)


def _weighing_table(record: Record, weighings: dict[str, np.ndarray]) -> Table:
    """Axle weights and GVW of each method beside the truth, and their errors %."""
    true = record.truth
    n = record.passage.n_axles
    header = ("method", *(f"axle {i + 1} (kN)" for i in range(n)), "GVW (kN)",
              *(f"axle {i + 1} err %" for i in range(n)), "GVW err %")
    rows = [(name, *format_kn_each(w), format_kn(np.sum(w)),
             *(format_pct(a, b) for a, b in zip(w, true.static_axle_loads, strict=True)),
             format_pct(np.sum(w), true.gvw))
            for name, w in {"truth (static)": true.static_axle_loads, **weighings}.items()]
    return Table("", header, rows)


def run_demo(*, quick: bool = False, seed: int = 0, n_jobs: int = 1, n_modes: int = 6,
             callback=None, echo: Callable[[str], object] | None = None) -> DemoReport:
    """Run the demo (see module docstring).

    Parameters
    ----------
    quick : bool
        The smaller, faster settings (:data:`SETTINGS`).
    seed : int
        Seed of the calibration.
    n_jobs : int
        Worker processes for the CE populations.
    n_modes : int
        Natural frequencies in the summary, 1 to 50.
    callback : callable, optional
        Receives the calibration's progress (see :func:`bwim.calibrate`).
    echo : callable, optional
        Called with the text of each block of the transcript as soon as it is known (the
        summary and each step's heading before the step runs), so that a caller can print
        as the demo goes; the blocks joined by newlines are :meth:`DemoReport.render`.
    """
    if not 1 <= n_modes <= MAX_MODES:
        raise InputError(f"n_modes must be between 1 and {MAX_MODES}, got {n_modes}")
    t0 = time.perf_counter()
    blocks: list[str | Table] = []

    def say(block: str | Table) -> None:
        blocks.append(block)
        if echo is not None:
            echo(_text(block))

    s = SETTINGS[quick]
    truth = paper.slab_bridge()
    summary, frequencies, strain = _slab_summary(truth, n_modes)
    say(summary)
    sensors = paper.sensors()
    start = truth.with_params(**{u: truth.params[u] * START[u] for u in UNKNOWNS})
    road = paper.road(1, approach=s.approach)
    say(f"\n1. Calibration crossing: the paper's {paper.truck().n_axles}-axle truck at "
        f"{paper.SPEED:g} m/s, lane {paper.LANE:g} m, road class C, {s.approach:g} m "
        "approach (vehicle-bridge interaction simulated on the true bridge)")
    cal_rec = simulate(truth, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                       sensors=sensors, road=road, approach=s.approach)
    factors = ", ".join(f"{name}×{START[u]:g}" for u, name in zip(UNKNOWNS, SHOWN,
                                                                  strict=True))
    say(f"2. Calibrating {', '.join(SHOWN)} by Cross-Entropy from {factors} "
        f"(populations {s.population[0]}/{s.population[1]}) …")
    cal = calibrate(start, [cal_rec], paper.truck(), road=road, approach=s.approach,
                    unknowns=UNKNOWNS, seed=seed, method="ce", population=s.population,
                    convergences=s.convergences, n_jobs=n_jobs, callback=callback)
    say(_calibration_table(cal, start, truth))
    vehicle = three_axle_truck()
    say(f"\n3. A second vehicle: {vehicle.n_axles}-axle rigid truck at {DEMO_SPEED:g} m/s "
        f"over another stretch of road (seed {DEMO_ROAD_SEED}); forces identified with the "
        "calibrated and the starting model (longitudinal strains, L-curve λ), and Moses "
        "with the influence line calibrated from crossing 1")
    rec = simulate(truth, vehicle, speed=DEMO_SPEED, lane=paper.LANE, sensors=sensors,
                   road=paper.road(DEMO_ROAD_SEED, approach=s.approach), approach=s.approach)
    strain_x = rec.channels([x for x in sensors if x.kind.value == "strain_x"])
    ident = identify_forces(cal.bridge, strain_x)
    ident_start = identify_forces(start, strain_x)
    il = calibrate_influence_line([cal_rec], paper.truck())
    moses = weigh_static(rec, il)
    say(_weighing_table(rec, {"MFI, calibrated model": ident.axle_weights,
                              "MFI, starting model": ident_start.axle_weights,
                              "Moses, calibrated IL": moses.axle_weights}))
    err = force_errors(ident, rec.truth)
    say("   MFI (calibrated) force RMS error, % of static axle load: "
        + ", ".join(f"{100 * e:.1f}" for e in err.rms_error) + f"; λ = {ident.lam:.3g}")
    return DemoReport(
        truth=truth, start=start, settings=s, frequencies=frequencies, static_strain=strain,
        calibration_record=cal_rec, calibration=cal, second_record=rec, identified=ident,
        identified_start=ident_start, influence_line=il, moses=moses, blocks=tuple(blocks),
        wall_time=time.perf_counter() - t0)
