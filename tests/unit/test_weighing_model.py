"""One vehicle's weighing made once before its scale (bwim.wim.weigh.weighing_model) and
the gauge check's last weighing reused for the drift-corrected one (bwim.site.health,
bwim.site.event).

Reference: :func:`bwim.wim.weigh` with the same arguments, made whole (the model is its
first half: the readings and the lines' readings do not depend on the scale), so every
number must be the same bit for bit, not close.  Data: the small realistic site of the
session fixtures (an FE plate with vehicle dynamics, noise, offsets and drift; influence
lines calibrated from runs: no inverse crime) and its lane-1 truck, clean and with one
gauge's gain doubled (the gauge check then leaves it out and weighs again without it).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bwim.errors import InputError
from bwim.site import weigh_event
from bwim.site.health import check_gauges
from bwim.wim import weigh
from bwim.wim.influence_line import read_channels
from bwim.wim.weigh import weighing_model

FIELDS = ("axle_weights", "group_weights", "groups", "gvw", "residual", "misfit",
          "condition", "scale_factor", "flags", "quality", "lateral", "clock_time",
          "combine", "baseline", "offsets", "time", "measured", "fitted")


def _same(a, b) -> None:
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), name
        else:
            assert x == y or (x != x and y != y), (name, x, y)
    assert [c.name for c in a.channels] == [c.name for c in b.channels]


@pytest.fixture(scope="module")
def truck(small_site_truck):
    site, record = small_site_truck
    ev = weigh_event(record, site)
    v = next(v for v in ev.vehicles if v.weighed)
    return site, record, v.vehicle.passage


@pytest.mark.parametrize("scaling", [{"scale_correction": False},
                                     {"scale_correction": True},
                                     {"scale": 0.93}, {"scale": 1.0}])
def test_model_weighs_as_weigh(truck, scaling):
    """The model of a vehicle weighs it with any scale as :func:`weigh` does, and one
    model gives each scale's weighing in turn (nothing of it is changed by a weighing)."""
    site, record, passage = truck
    lines, combine = site.lines, site.setup.combine
    model = weighing_model(record, passage, lines, combine=combine)
    first = model.weigh(scale=1.07)  # another scale first: the model must not keep it
    _same(model.weigh(**scaling), weigh(record, passage, lines, combine=combine,
                                        **scaling))
    _same(model.weigh(scale=1.07), first)


@pytest.mark.parametrize("gain", [1.0, 2.0])
def test_gauge_check_model_is_the_healthy_channels_weighing(truck, gain):
    """The gauge check's model is the healthy channels' (after a fault is left out, not
    the one that still held it): scaled, it is the weighing of :attr:`lines`."""
    site, record, passage = truck
    if gain != 1.0:
        data = record.data.copy()
        k = record.channel_indices(["s05"])[0]
        data[:, k] = record.data[:, k] * gain
        record = dataclasses.replace(record, data=data)
    health = check_gauges(record, passage, site.lines, combine=site.setup.combine)
    assert [f.gauge for f in health.faults] == ([] if gain == 1.0 else ["s05"])
    assert health.model is not None
    assert [c.name for c in health.model.calibration.channels] == list(health.healthy)
    for scaling in ({"scale": 0.95}, {"scale_correction": False}):
        _same(health.model.weigh(**scaling),
              weigh(record, passage, health.lines, combine=site.setup.combine, **scaling))


def test_model_scale_divides_the_readings(truck):
    """Closed form: the readings divided by the scale ``s`` (``combine="sum"``: one least
    squares, no weight-dependent covariance) give the weights at ``s = 1`` divided by
    ``s`` (to rounding); the weighing reports the scale it used, and with
    ``scale_correction`` the calibration's scale trend at the record's clock time."""
    site, record, passage = truck
    model = weighing_model(record, passage, site.lines, combine="sum")
    one = model.weigh(scale=1.0)
    for s in (0.9, 1.25):
        w = model.weigh(scale=s)
        assert w.scale_factor == s
        np.testing.assert_allclose(w.axle_weights, one.axle_weights / s, rtol=1e-12)
    trend = site.lines.scale_trend
    expected = 1.0 if trend is None else float(trend(record.clock_seconds()))
    assert model.weigh(scale_correction=True).scale_factor == expected
    assert model.weigh(scale_correction=False).scale_factor == 1.0


def test_model_of_readings_already_read(truck):
    """The readings given (the gauge check reads them once) make the same model: every
    weighing bit for bit; the samples it fits are :attr:`on_support`'s; readings of
    another shape are refused."""
    site, record, passage = truck
    lines, combine = site.lines, site.setup.combine
    readings = read_channels(record, lines.channels)
    model = weighing_model(record, passage, lines, combine=combine, readings=readings)
    assert model.readings is readings
    for scaling in ({"scale": 0.95}, {"scale_correction": False}):
        w = model.weigh(**scaling)
        _same(w, weigh(record, passage, lines, combine=combine, **scaling))
        assert np.array_equal(w.time, record.time[model.on_support])
    with pytest.raises(InputError, match="readings must have shape"):
        weighing_model(record, passage, lines, readings=readings[:, :-1])


def test_error_variance_is_the_covariance_diagonal(truck):
    """:meth:`error_variance` is :meth:`error_covariance`'s diagonal bit for bit, for no
    weight, weights below, at and above the truck's (and none at all), as a new array."""
    lines = truck[0].lines
    for weight in (None, 0.0, -5.0, 0.3, 0.999, 1.0, 2.5):
        w = None if weight is None else weight * lines.truck_weight
        var = lines.error_variance(w)
        assert np.array_equal(var, np.diag(lines.error_covariance(w)))
        assert var.flags.writeable and var.flags.owndata
