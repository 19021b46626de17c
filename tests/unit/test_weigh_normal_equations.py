"""Weighing's least squares by the normal equations (issue 21 item 6: speed) against
``numpy.linalg.lstsq``, which it replaces for well-conditioned designs.

Reference: the same weighing with ``NORMAL_CONDITION = 0`` (every design solved by
``numpy.linalg.lstsq``, the code before this change).  The normal equations' relative
error is about ``eps × cond²``; on these designs (condition numbers 1.1 to 1.5) the
weights agree to 1.1e-14 and the condition numbers to 1.6e-15 (measured; tolerances
1e-13 and 1e-14).
A design beyond ``NORMAL_CONDITION`` (here a group never on the lines: rank deficient)
takes lstsq's path and stays ``undetermined``.

Algebra checks on same-model data: readings made here with ``np.interp`` from known
piecewise-linear lines (as in ``tests/unit/test_multirun.py``), with noise so that the
fits are not exact.
"""

import importlib

import numpy as np
import pytest

from bwim.records import Passage, Record
from bwim.sensors import Sensor
from bwim.wim.multirun import calibrate_lines
from bwim.wim.weigh import NORMAL_CONDITION, weigh

weigh_module = importlib.import_module("bwim.wim.weigh")  # bwim.wim.weigh: the function
FS = 256.0
X = np.linspace(-1.5, 7.5, 91)  # the lines' grid, m
TRUCK = np.array([60e3, 110e3, 80e3, 80e3, 80e3])
SPACINGS = np.array([3.6, 5.9, 1.3, 1.3])
SENSORS = tuple(Sensor(x=4.5, y=1.0 + k, name=f"g{k}") for k in range(4))


def _event(loads, spacings, *, speed, clock, seed, noise=2e-8, tail=0.2):
    """A record of ``loads`` crossing known lines (one per channel, of different sizes),
    with noise; the passage in the lines' frame."""
    u = (X - X[0]) / (X[-1] - X[0])
    lines = np.stack([(1.0 + 0.3 * g) * np.sin(np.pi * u) ** 1.5 for g in range(4)], 1)
    offs = np.concatenate([[0.0], np.cumsum(spacings)])
    duration = 0.3 + (X[-1] - X[0] + offs[-1]) / speed + tail
    time = clock + np.arange(int(duration * FS)) / FS
    delay = clock + 0.3 + 1.5 / speed
    pos = speed * (time[:, None] - delay) - offs[None, :]
    data = np.column_stack([np.interp(pos, X, lines[:, g] * 1e-10, left=0, right=0)
                            @ loads for g in range(4)])
    data += noise * np.random.default_rng(seed).standard_normal(data.shape)
    return (Record(time=time, data=data, sensors=SENSORS),
            Passage(speed=speed, lane=3.0, axle_spacings=spacings, delay=delay))


@pytest.fixture(scope="module")
def calibration():
    runs = [_event(TRUCK, SPACINGS, speed=v, clock=3600.0 * (8 + k), seed=k)
            for k, v in enumerate(np.linspace(12.0, 25.0, 5))]
    return calibrate_lines([r for r, _ in runs], [p for _, p in runs], TRUCK, lateral=None)


def _pairs(calibration, monkeypatch, **kw):
    """(normal equations, lstsq) weighings of a few vehicles."""
    out = []
    vehicles = [(np.array([55e3, 95e3, 90e3]), np.array([4.2, 1.35]), 18.0),
                (TRUCK * 0.8, SPACINGS, 22.0), (np.array([40e3, 60e3]), np.array([3.0]), 14.0)]
    for k, (loads, spacings, v) in enumerate(vehicles):
        rec, p = _event(loads, spacings, speed=v, clock=3600.0 * 12, seed=10 + k, **kw)
        for combine in ("sum", "gls", "blue"):
            fast = weigh(rec, p, calibration, combine=combine)
            with monkeypatch.context() as m:
                m.setattr(weigh_module, "NORMAL_CONDITION", 0.0)
                out.append((fast, weigh(rec, p, calibration, combine=combine)))
    return out


def test_the_normal_equations_give_lstsqs_weights(calibration, monkeypatch):
    for fast, ref in _pairs(calibration, monkeypatch):
        assert fast.condition < NORMAL_CONDITION
        np.testing.assert_allclose(fast.group_weights, ref.group_weights, rtol=1e-13)
        np.testing.assert_allclose(fast.axle_weights, ref.axle_weights, rtol=1e-13)
        assert fast.condition == pytest.approx(ref.condition, rel=1e-14)
        assert fast.residual == pytest.approx(ref.residual, rel=1e-13)
        assert fast.flags == ref.flags


def test_a_rank_deficient_design_takes_lstsqs_path(calibration, monkeypatch):
    """The second axle stays beyond the lines for the whole record (the record ends
    first): its column is zero, the design singular; lstsq's rank says undetermined."""
    rec, p = _event(np.array([60e3, 90e3]), np.array([16.0]), speed=20.0, clock=3600.0 * 12,
                    seed=3, tail=-0.75)
    fast = weigh(rec, p, calibration, combine="sum", groups=None)
    with monkeypatch.context() as m:
        m.setattr(weigh_module, "NORMAL_CONDITION", 0.0)
        ref = weigh(rec, p, calibration, combine="sum", groups=None)
    assert "undetermined" in fast.flags and fast.flags == ref.flags
    assert np.isnan(fast.gvw) and np.isnan(ref.gvw)
