"""Issue 22: a faulty axle detector never yields a weight.  One of the lane's two
detectors dead, replaced by noise, reversed or at three times its gain: the truck is not
weighed (no axle fits the learned responses of the pair), never weighed with a wrong
speed or axle layout.  The reason names the faulty detector by its channel where the
readings say which (:func:`bwim.detect.faults.detector_faults`): a dead, noisy or
reversed one against the healthy one; a gain change names both (one record cannot tell
which of the two changed).

Data: the session's small realistic site, its lane-1 traffic truck (weighed +2.3 % with
both detectors healthy), one detector channel changed about its first sample."""

import dataclasses

import numpy as np
import pytest

from bwim.site import weigh_event


@pytest.fixture
def truck(small_site_truck):
    return small_site_truck


def _faulty(column: np.ndarray, kind: str) -> np.ndarray:
    rest = column[0]
    if kind == "dead":
        return np.full_like(column, rest)
    if kind == "noise":
        sigma = float(np.std(np.diff(column[:20])))
        return rest + np.random.default_rng(0).normal(0.0, sigma, column.size)
    return rest + {"reversed": -1.0, "gain3": 3.0}[kind] * (column - rest)


@pytest.mark.parametrize("channel", ["ad1", "ad2"])
@pytest.mark.parametrize("kind", ["dead", "noise", "reversed", "gain3"])
def test_a_faulty_detector_gives_no_weight(truck, channel, kind):
    site, rec = truck
    assert weigh_event(rec, site).weighed
    k = [s.name for s in rec.sensors].index(channel)
    data = rec.data.copy()
    data[:, k] = _faulty(data[:, k], kind)
    ev = weigh_event(dataclasses.replace(rec, data=data), site)
    assert not ev.weighed and not any(v.weighed for v in ev.vehicles)
    assert ev.reason
    other = {"ad1": "ad2", "ad2": "ad1"}[channel]
    said = ev.reason.split("; ", 1)[1] if "; " in ev.reason else ""
    if kind == "gain3":
        assert channel in said and other in said and "changed gain" in said
    elif kind == "reversed":
        assert said.startswith(f"{channel} reads the vehicle {other} sees reversed")
    else:
        assert said.startswith(f"{channel} reads nothing of the vehicle {other} sees")
