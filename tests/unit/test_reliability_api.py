"""Issue 14, the library's bad-argument suite: every public function called with a bad
argument raises InputError (never TypeError, AttributeError, a bare ValueError or
LinAlgError) with a one-line message naming the argument.  Reference: the issue's list of
escapes (bridge=None, n_modes=0 or 2.5, n_lam 0 or 1, lam=None, NaN or wrong-length
weights, max_evals=0, records=None)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bwim
from bwim.errors import InputError
from bwim.optimize import CrossEntropy, minimize_ce


@pytest.fixture(scope="module")
def setup():
    bridge = bwim.Bridge.beam(length=20.0, n_elements=10, E=3e10, I=1.0, mu=1e4,
                              z_bottom=0.5)
    truck = bwim.MovingForces(axle_loads=[50e3, 100e3], axle_spacings=[4.0])
    sensors = [bwim.Sensor(x=7.0), bwim.Sensor(x=10.0), bwim.Sensor(x=13.0)]
    rec = bwim.simulate(bridge, truck, speed=20.0, sensors=sensors, sampling_rate=200.0,
                        approach=0.0)
    return {"bridge": bridge, "truck": truck, "sensors": sensors, "record": rec}


def _sphere(x):
    return float(np.sum(np.asarray(x) ** 2))


CASES = {
    # identify_forces
    "identify bridge=None": (lambda s: bwim.identify_forces(None, s["record"]), "bridge"),
    "identify record=None": (lambda s: bwim.identify_forces(s["bridge"], None), "record"),
    "identify n_modes=0": (lambda s: bwim.identify_forces(s["bridge"], s["record"],
                                                          n_modes=0), "n_modes"),
    "identify n_modes=2.5": (lambda s: bwim.identify_forces(s["bridge"], s["record"],
                                                            n_modes=2.5), "n_modes"),
    "identify n_lam=0": (lambda s: bwim.identify_forces(s["bridge"], s["record"], n_lam=0),
                         "n_lam"),
    "identify n_lam=1": (lambda s: bwim.identify_forces(s["bridge"], s["record"], n_lam=1),
                         "n_lam"),
    "identify lam=None": (lambda s: bwim.identify_forces(s["bridge"], s["record"], lam=None),
                          "lam"),
    "identify lam=-1": (lambda s: bwim.identify_forces(s["bridge"], s["record"], lam=-1.0),
                        "lam"),
    "identify reversed lam_range": (lambda s: bwim.identify_forces(
        s["bridge"], s["record"], lam_range=(1e3, 1e-6)), "lam_range"),
    "identify weights NaN": (lambda s: bwim.identify_forces(
        s["bridge"], s["record"], weights=[1.0, math.nan, 1.0]), "weights"),
    "identify weights length": (lambda s: bwim.identify_forces(
        s["bridge"], s["record"], weights=[1.0, 1.0]), "weights"),
    "identify central=None": (lambda s: bwim.identify_forces(
        s["bridge"], s["record"], central=None), "central"),
    # simulate
    "simulate bridge=None": (lambda s: bwim.simulate(None, s["truck"], speed=20.0,
                                                     sensors=s["sensors"]), "bridge"),
    "simulate sensors=None": (lambda s: bwim.simulate(s["bridge"], s["truck"], speed=20.0,
                                                      sensors=None), "sensors"),
    "simulate speed=nan": (lambda s: bwim.simulate(s["bridge"], s["truck"], speed=math.nan,
                                                   sensors=s["sensors"]), "speed"),
    "simulate sampling_rate=0.5": (lambda s: bwim.simulate(
        s["bridge"], s["truck"], speed=20.0, sensors=s["sensors"], sampling_rate=0.5),
        "sampling_rate"),
    # Bridge
    "modes n=0": (lambda s: s["bridge"].modes(0), "n"),
    "modes n=2.5": (lambda s: s["bridge"].modes(2.5), "n"),
    "modes n=None": (lambda s: s["bridge"].modes(None), "n"),
    "beam n_elements=True": (lambda s: bwim.Bridge.beam(length=20.0, n_elements=True, E=3e10,
                                                        I=1.0, mu=1e4), "n_elements"),
    # calibrate
    "calibrate bridge=None": (lambda s: bwim.calibrate(None, s["record"], s["truck"]),
                              "start_bridge"),
    "calibrate records=None": (lambda s: bwim.calibrate(s["bridge"], None, s["truck"]),
                               "records"),
    "calibrate records=[]": (lambda s: bwim.calibrate(s["bridge"], [], s["truck"]),
                             "records"),
    "calibrate records=[None]": (lambda s: bwim.calibrate(s["bridge"], [None], s["truck"]),
                                 "records"),
    "calibrate max_evals=0": (lambda s: bwim.calibrate(s["bridge"], s["record"], s["truck"],
                                                       max_evals=0), "max_evals"),
    "calibrate population=0": (lambda s: bwim.calibrate(s["bridge"], s["record"], s["truck"],
                                                        population=0), "population"),
    "calibrate n_jobs=-5": (lambda s: bwim.calibrate(s["bridge"], s["record"], s["truck"],
                                                     n_jobs=-5), "n_jobs"),
    "calibrate n_modes=0": (lambda s: bwim.calibrate(s["bridge"], s["record"], s["truck"],
                                                     n_modes=0), "n_modes"),
    "calibrate E_y on a beam": (lambda s: bwim.calibrate(
        s["bridge"], s["record"], s["truck"], unknowns=("E_y",)), "E_y"),
    "calibrate bounds=None": (lambda s: bwim.calibrate(s["bridge"], s["record"], s["truck"],
                                                       bounds=None), "bounds"),
    "calibrate weights NaN": (lambda s: bwim.calibrate(
        s["bridge"], s["record"], s["truck"], weights=[[1.0, math.nan, 1.0]]), "weights"),
    "calibrate weights length": (lambda s: bwim.calibrate(
        s["bridge"], s["record"], s["truck"], weights=[[1.0] * 3, [1.0] * 3]), "weights"),
    # influence lines and Moses
    "influence records=None": (lambda s: bwim.calibrate_influence_line(None, s["truck"]),
                               "records"),
    "influence regularization=nan": (lambda s: bwim.calibrate_influence_line(
        s["record"], s["truck"], regularization=math.nan), "regularization"),
    "weigh_static record=None": (lambda s: bwim.weigh_static(
        None, bwim.model_influence_line(s["bridge"], s["sensors"])), "record"),
    # optimisers
    "minimize_ce max_evals=0": (lambda s: minimize_ce(_sphere, [1.0, 1.0], max_evals=0),
                                "max_evals"),
    "minimize_ce population=0": (lambda s: minimize_ce(_sphere, [1.0, 1.0], population=0),
                                 "population"),
    "CrossEntropy mean=None": (lambda s: CrossEntropy(None), "mean"),
    # road
    "iso8608 length=nan": (lambda s: bwim.RoadProfile.iso8608("A", length=math.nan, seed=0),
                           "length"),
    "iso8608 roughness=None": (lambda s: bwim.RoadProfile.iso8608(None, length=10.0, seed=0),
                               "roughness"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_bad_argument_is_an_input_error(setup, name):
    call, needle = CASES[name]
    try:
        call(setup)
    except InputError as exc:
        msg = str(exc)
        assert "\n" not in msg and needle in msg, msg
    except Exception as exc:  # the point: nothing else may escape
        pytest.fail(f"{name}: {type(exc).__name__} escaped: {exc}")
    else:
        pytest.fail(f"{name}: accepted")


def test_beam_default_unknowns_follow_the_bridge(setup, monkeypatch):
    """calibrate on a beam with default unknowns no longer asks for E_y: the default is
    the bridge's own families (issue 14: examples/beam.toml could not be calibrated)."""
    from bwim.calibration import driver

    seen = {}

    def stop(*args, **kwargs):
        seen["unknowns"] = args[1]
        raise InputError("stop")

    monkeypatch.setattr(driver, "_plan", stop)
    with pytest.raises(InputError, match="stop"):
        bwim.calibrate(setup["bridge"], setup["record"], setup["truck"])
    assert seen["unknowns"] == ("E_x", "mu")


@pytest.mark.parametrize("noise", [1e300, -0.1, math.nan, None, "0.1"])
def test_noise_fraction_bounded(setup, noise):
    """Issue 14: ``noise = 1e300`` was accepted; a noise fraction lies in [0, 1]."""
    with pytest.raises(InputError, match="noise fraction"):
        setup["record"].with_noise(noise, seed=0)
