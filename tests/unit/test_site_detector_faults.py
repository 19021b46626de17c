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


def _diagnose_reference(y, learned):
    """bwim.detect.faults.diagnose as written with numpy arrays (before its kernel and
    scalars): (kind, message)."""
    from bwim.detect.faults import GAIN_FACTOR, NOTHING, REST_SHARE, SEEN

    rest = np.median(y[:max(1, int(REST_SHARE * y.shape[0]))], axis=0)
    names = learned.channels
    scale = np.array([1.0, learned.gain_ratio])
    z = (y - rest) * np.array([r.sign for r in learned.responses])
    up, down = z.max(axis=0), -z.min(axis=0)
    level = np.array([max(r.level, 1e-300) for r in learned.responses])
    peak = up / scale
    sees = (up >= SEEN * level) & (up > down)

    def gain(ratio):
        return "gain", (f"{names[1]} reads the vehicle {ratio:.2g} × {names[0]} in their "
                        f"learned gain ratio: {names[0]} or {names[1]} has changed gain")

    if sees.all():
        ratio = peak[1] / peak[0]
        return gain(ratio) if ratio > GAIN_FACTOR or ratio < 1.0 / GAIN_FACTOR else ("", "")
    if not sees.any():
        return "", ""
    d = int(np.flatnonzero(sees)[0])
    o = 1 - d
    dip = down[o] / scale[o]
    if down[o] > up[o] and peak[d] / GAIN_FACTOR <= dip <= peak[d] * GAIN_FACTOR:
        return "reversed", (f"{names[o]} reads the vehicle {names[d]} sees reversed (its "
                            "peaks have the opposite sign of its learned response)")
    if max(up[o], down[o]) / scale[o] < NOTHING * peak[d]:
        return "nothing", (f"{names[o]} reads nothing of the vehicle {names[d]} sees (dead, "
                           "disconnected or only noise)")
    if up[o] > down[o] and up[o] / scale[o] < peak[d] / GAIN_FACTOR:
        return gain(float(peak[1] / peak[0]))
    return "", ""


def test_diagnose_is_its_numpy_form(truck):
    """diagnose (its excursions compiled, the rest numpy scalars) says what the numpy
    form said, word for word, on the truck's pair changed in many ways."""
    from bwim.detect.faults import diagnose

    site, rec = truck
    learned = site.responses[1]
    y0 = rec.channels(list(learned.channels)).data
    rng = np.random.default_rng(2)
    kinds = set()
    for trial in range(300):
        y = y0.copy()
        c = int(rng.integers(0, 2))
        rest = y[0, c]
        y[:, c] = rest + rng.choice([-1.0, 0.0, 0.3, 1.0, 2.5, 4.0]) * (y[:, c] - rest)
        if trial % 3 == 0:
            y[:, 1 - c] += rng.normal(0.0, 10.0 ** rng.uniform(-3, 1), y.shape[0])
        if trial % 5 == 0:
            y = np.asfortranarray(y)
        ref = _diagnose_reference(y, learned)
        got = diagnose(y, learned)
        assert (got.kind, got.message) == ref, trial
        kinds.add(got.kind)
    assert kinds == {"", "gain", "reversed", "nothing"}
