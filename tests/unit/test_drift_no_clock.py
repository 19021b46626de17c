"""The time-of-day drift needs clocks (review of stop 32, finding 6).

Without a clock a record's time column is either the clock time of day (older loggers)
or a record time from 0.  Runs of the second kind all sat at "midnight": the
time-of-day drift was fitted over nothing and applied as if measured, and an event
without a clock was weighed with the first run's factor.  Now (bwim.site.drift's
contract): runs that cannot be placed in the day give no time-of-day drift, and an event
that cannot be placed keeps the mean factor, flagged ``no_clock``.  Reference: the same
runs and event with their clocks (from the small simulated site's file names), and the
same with the clock written into the time column as the time of day.
"""

import dataclasses

import numpy as np
import pytest

from bwim.site import calibrate_site, weigh_event
from bwim.site.drift import seconds_of_day


def _without_clock(rec, *, time_of_day: bool):
    """``rec`` without its clock; its time column from 0, or the clock time of day."""
    t = rec.time - rec.time[0]
    if time_of_day:
        t = t + seconds_of_day(rec.clock_at(rec.time[0]))
    return dataclasses.replace(rec, time=t, clock=None)


def test_runs_without_a_clock_give_no_time_of_day_drift(small_site_calibrated):
    _, _, records, site = small_site_calibrated
    assert site.time_of_day is not None and all(r.clock is not None for r in records)
    plain = [_without_clock(r, time_of_day=False) for r in records]
    assert not any(r.time_of_day for r in plain)
    without = calibrate_site(plain, site.setup)
    assert without.time_of_day is None
    assert any("the calibration runs have no clock" in n for n in without.notes)
    assert not any("no clock" in n for n in site.notes)
    # the clock written into the time columns: the same trend as from the clocks
    of_day = [_without_clock(r, time_of_day=True) for r in records]
    assert all(r.time_of_day for r in of_day)
    tod = calibrate_site(of_day, site.setup).time_of_day
    assert tod is not None and tod.dates == ()
    np.testing.assert_allclose(tod.trend.time, site.time_of_day.trend.time, atol=1e-6)
    # the runs' fits on a time axis ~8 h from 0 round differently: 3.0e-7 measured
    np.testing.assert_allclose(tod.trend.factor, site.time_of_day.trend.factor, rtol=1e-6)
    # half the runs with their clocks, half with the clock as the time column: the same
    mixed = [r if k % 2 else _without_clock(r, time_of_day=True)
             for k, r in enumerate(records)]
    tod = calibrate_site(mixed, site.setup).time_of_day
    assert tod is not None and tod.dates == ()
    np.testing.assert_allclose(tod.trend.time, site.time_of_day.trend.time, atol=1e-6)
    np.testing.assert_allclose(tod.trend.factor, site.time_of_day.trend.factor, rtol=1e-6)


def test_an_event_without_a_clock_keeps_the_mean_factor_flagged(small_site_truck):
    site, truck = small_site_truck
    clocked = weigh_event(truck, site)
    (v,) = [v for v in clocked.vehicles if v.weighed]
    assert v.drift_method == "time_of_day" and "no_clock" not in v.flags
    assert v.drift_factor != pytest.approx(1.0, abs=1e-6)  # a factor of its own
    plain = weigh_event(_without_clock(truck, time_of_day=False), site)
    (w,) = [w for w in plain.vehicles if w.weighed]
    assert (w.drift_method, w.drift_factor) == ("", 1.0) and "no_clock" in w.flags
    # weights scale with the factor (weights are divided by it): the same weighing
    assert w.gvw == pytest.approx(v.gvw * v.drift_factor, rel=1e-9)
    assert plain.to_summary_rows("x")[0].time is None
    of_day = weigh_event(_without_clock(truck, time_of_day=True), site)
    (u,) = [u for u in of_day.vehicles if u.weighed]
    assert u.drift_method == "time_of_day" and "no_clock" not in u.flags
    assert u.drift_factor == pytest.approx(v.drift_factor, rel=1e-6)


def test_a_vehicle_past_midnight_in_a_time_of_day_record(small_site_truck):
    """A record in clock time of day that starts just before midnight (half the time its
    truck takes to reach the detectors): its truck passes after midnight, at the record's
    time less 86400 s (the next day's clock), not at no time (the summary's time; the
    clocked truck's time of day is the reference)."""
    site, truck = small_site_truck
    clocked = weigh_event(truck, site).to_summary_rows("x")
    (ref,) = [r for r in clocked if r.weighed]
    offset = seconds_of_day(ref.time) - seconds_of_day(truck.clock_at(truck.time[0]))
    rec = _without_clock(truck, time_of_day=True)
    start = 86400.0 - 0.5 * offset
    late = weigh_event(dataclasses.replace(rec, time=rec.time - rec.time[0] + start),
                       site).to_summary_rows("x")
    (row,) = [r for r in late if r.weighed]
    assert offset > 0.1
    assert seconds_of_day(row.time) == pytest.approx(0.5 * offset, abs=1e-3)


def test_a_drift_flag_alone_makes_the_row_a_warning(small_site_truck):
    """A weighed row's quality counts the vehicle's own flags, not only its weighing's
    (review of stop 34: a row flagged only ``outside_calibration_time``, added by the
    drift after the weighing, was written with quality "ok"; docs/flags.md: a soft flag
    makes it a warning).  The truck's weighing with no flag of its own, the drift's flag
    on the vehicle: warning; no flag at all: ok."""
    site, truck = small_site_truck
    ev = weigh_event(truck, site)
    k = next(i for i, v in enumerate(ev.vehicles) if v.weighed)
    v = ev.vehicles[k]
    clean = dataclasses.replace(v.weighing, flags=(), quality="ok")
    for flags, quality in ((("outside_calibration_time",), "warning"), ((), "ok")):
        vw = dataclasses.replace(v, weighing=clean, flags=flags)
        vehicles = (*ev.vehicles[:k], vw, *ev.vehicles[k + 1:])
        row = dataclasses.replace(ev, vehicles=vehicles).to_summary_rows("x")[k]
        assert row.weighed and row.flags == flags and row.quality == quality


def test_runs_without_a_clock_flag_every_weight_no_drift(small_site_calibrated,
                                                          small_site_truck):
    """Runs that cannot be placed in the day give no drift; the weights they make carry
    ``no_drift`` (quality warning), never an uncorrected weight that looks corrected
    (review of stop 34: quality ok, no flag, drift_factor 1, 18 % light on the realistic
    site).  The same truck with clocked runs: no such flag."""
    _, _, records, site = small_site_calibrated
    _, truck = small_site_truck
    without = calibrate_site([_without_clock(r, time_of_day=False) for r in records],
                             site.setup)
    (row,) = [r for r in weigh_event(truck, without).to_summary_rows("x") if r.weighed]
    assert "no_drift" in row.flags and row.quality == "warning"
    assert (row.drift_factor, row.drift_method) == (1.0, "")
    (ref,) = [r for r in weigh_event(truck, site).to_summary_rows("x") if r.weighed]
    assert "no_drift" not in ref.flags and ref.drift_method == "time_of_day"
