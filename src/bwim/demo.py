"""The demo's computation: calibrate the paper's slab, then weigh a second vehicle.

Contract
--------
:func:`run_demo` does everything ``bwim demo`` shows and returns a :class:`DemoResult`;
the command line prints it and writes its files.  Every number is computed by the run:

1. the paper's truck crosses the paper's slab (vehicle–bridge interaction on the true
   bridge) — the calibration record;
2. E_x, E_y and μ are calibrated by Cross-Entropy from E_x × 0.8, E_y × 1.2, μ × 1.25
   (:data:`bwim.reproduce.START`);
3. a second vehicle (the 3-axle rigid truck) crosses at another speed over another
   stretch of road; its forces are identified by MFI with the calibrated and with the
   starting model, and it is weighed by Moses with the influence line calibrated from the
   first crossing.
"""

from __future__ import annotations

from dataclasses import dataclass

from bwim import paper
from bwim.calibration import Calibration, calibrate
from bwim.dynamics.crossing import simulate
from bwim.fe.bridge import Bridge
from bwim.mfi import ForceIdentification, identify_forces
from bwim.records import Record
from bwim.reproduce import START
from bwim.vehicles import three_axle_truck
from bwim.wim import InfluenceLine, StaticWeights, calibrate_influence_line, weigh_static

__all__ = ["DEMO_ROAD_SEED", "DEMO_SPEED", "DemoResult", "DemoSettings", "run_demo"]

DEMO_SPEED = 15.0  #: m/s, the second vehicle
DEMO_ROAD_SEED = 2  #: the second vehicle's stretch of road


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
class DemoResult:
    """Everything the demo computed."""

    truth: Bridge
    start: Bridge
    settings: DemoSettings
    calibration_record: Record
    calibration: Calibration
    second_record: Record
    identified: ForceIdentification  # with the calibrated model
    identified_start: ForceIdentification  # with the starting model
    influence_line: InfluenceLine
    moses: StaticWeights


def run_demo(*, quick: bool = False, seed: int = 0, n_jobs: int = 1, callback=None,
             on_step=None) -> DemoResult:
    """Run the demo (see module docstring).

    ``callback`` receives the calibration's progress; ``on_step(n, text)`` is called as
    each of the three steps starts.
    """
    s = SETTINGS[quick]
    truth = paper.slab_bridge()
    sensors = paper.sensors()
    unknowns = ("E_x", "E_y", "mu")
    start = truth.with_params(**{u: truth.params[u] * START[u] for u in unknowns})
    road = paper.road(1, approach=s.approach)
    say = on_step or (lambda n, text: None)
    say(1, "calibration crossing")
    cal_rec = simulate(truth, paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                       sensors=sensors, road=road, approach=s.approach)
    say(2, "calibration")
    cal = calibrate(start, [cal_rec], paper.truck(), road=road, approach=s.approach,
                    unknowns=unknowns, seed=seed, method="ce", population=s.population,
                    convergences=s.convergences, n_jobs=n_jobs, callback=callback)
    say(3, "second vehicle")
    rec = simulate(truth, three_axle_truck(), speed=DEMO_SPEED, lane=paper.LANE,
                   sensors=sensors, road=paper.road(DEMO_ROAD_SEED, approach=s.approach),
                   approach=s.approach)
    strain_x = rec.channels([x for x in sensors if x.kind.value == "strain_x"])
    il = calibrate_influence_line([cal_rec], paper.truck())
    return DemoResult(
        truth=truth, start=start, settings=s, calibration_record=cal_rec, calibration=cal,
        second_record=rec, identified=identify_forces(cal.bridge, strain_x),
        identified_start=identify_forces(start, strain_x), influence_line=il,
        moses=weigh_static(rec, il),
    )
