"""A faulty gauge never yields a silent weight (issue 22 item 1): a dead, stuck,
clipped, reversed, gain-changed or drifting gauge of an event is found
(bwim.site.health), left out, named in the flag ``gauge_fault:NAME`` (quality
``warning``), and the vehicle weighed with the other gauges; with too few healthy gauges
the vehicle is refused.

Data: a tiny realistic site (:mod:`bwim.synthetic`, ``short-span-4-lane``: an FE plate
with vehicle dynamics, gauge noise, offsets and drift; calibrated by influence lines, so
no inverse crime).  One gauge column of the traffic file of its lane-1 truck (a 3+3
articulated truck, 268 kN) is corrupted the way a fault corrupts the logger's file.  The
expected outcome is the issue's: the fault named, and the weight the clean event gives
(the other gauges carry the same information), not the code's output.
"""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from bwim.cli import main
from bwim.errors import InputError
from bwim.report.flags import explain
from bwim.scenario import load_record
from bwim.site import weigh_event
from bwim.site.health import check_gauges, restrict_lines
from bwim.wim import weigh

FAULTS = {
    "dead": lambda y: np.zeros_like(y),
    "stuck": lambda y: np.full_like(y, y[0]),
    "reversed": lambda y: -y,
    "gain x2": lambda y: 2.0 * y,
    "gain x0.5": lambda y: 0.5 * y,
    "gain x10": lambda y: 10.0 * y,
}
KIND = {"dead": "flat", "stuck": "flat", "reversed": "reversed", "gain x2": "gain",
        "gain x0.5": "gain"}


@pytest.fixture(scope="module")
def site(small_site_calibrated):
    day, scenario, _, calibration = small_site_calibrated
    return day, scenario, calibration


@pytest.fixture(scope="module")
def truck(site):
    """The traffic file whose only vehicle is weighed (lane 1, no other vehicle) and its
    clean gross weight."""
    day, scenario, calibration = site
    for path in day.traffic:
        ev = weigh_event(load_record(path, scenario), calibration)
        if len(ev.vehicles) == 1 and ev.vehicles[0].weighed:
            return path, ev.vehicles[0]
    raise AssertionError("the fixture has no single weighed vehicle")


def _corrupted(path: Path, out: Path, scenario, gauges, fault) -> Path:
    """``path`` with the columns of ``gauges`` replaced by ``fault(column)``."""
    columns = list(scenario.logger.columns)
    rows = [line.split() for line in path.read_text().splitlines()]
    for gauge in gauges:
        k = columns.index(gauge)
        values = FAULTS[fault](np.array([float(r[k]) for r in rows]))
        for r, v in zip(rows, values, strict=True):
            r[k] = f"{v:.3f}"
    out.write_text("\n".join("\t".join(r) for r in rows) + "\n")
    return out


def _gauge_faults(flags) -> list[str]:
    return [f for f in flags if f.startswith("gauge_fault")]

def _left_out(record, clean, calibration, gauge, kind):
    """The health check names ``gauge`` of ``kind`` alone; the vehicle is weighed without
    it, flagged, within 4 % of its clean weight; the weighing."""
    health = check_gauges(record, clean.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine)
    assert [(f.gauge, f.kind) for f in health.faults] == [(gauge, kind)]
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and _gauge_faults(v.flags) == [f"gauge_fault:{gauge}"]
    assert v.gvw == pytest.approx(clean.gvw, rel=0.04)
    return v



def test_no_false_alarm_on_the_clean_events(site, truck):
    """Every clean event of the fixture (4 traffic events, 6 calibration runs; 14
    vehicles, 4 weighed; the runs are in-sample) has no gauge_fault flag and no vehicle
    refused for its gauges.  Three runs and one event have a vehicle of the other
    direction on the span: two of them are refused because a gauge disagrees (it feels
    the other vehicle), and the weighing with every gauge refuses both as well
    (residual_high): no weight is lost to the check."""
    day, scenario, calibration = site
    n_weighed, n_other = 0, 0
    for path in (*day.traffic, *day.calibration):
        record = load_record(path, scenario)
        for v in weigh_event(record, calibration).vehicles:
            assert _gauge_faults(v.flags) == [], (path.name, v.flags)
            assert "healthy gauges" not in v.reason, (path.name, v.reason)
            n_weighed += v.weighed
            if v.reason.startswith("another vehicle on the span and gauge"):
                n_other += 1
                w = weigh(record, v.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine)
                assert w.quality == "reject", w.flags
    assert n_weighed >= 4 and n_other == 2


def test_with_another_vehicle_a_disagreeing_gauge_refuses(site, truck, tmp_path):
    """``alone=False`` (another vehicle on the span): the clean truck passes; with s02
    reversed it is refused, the gauge named in the reason but not flagged as faulty
    (its strain cannot be told from the other vehicle's)."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    assert check_gauges(record, clean.vehicle.passage, calibration.lines,
                        alone=False).usable
    bad = load_record(_corrupted(path, tmp_path / path.name, scenario, ["s02"],
                                 "reversed"), scenario)
    health = check_gauges(bad, clean.vehicle.passage, calibration.lines, alone=False)
    assert not health.usable and health.flags == ()
    assert health.reason.startswith("another vehicle on the span and gauge s02 disagrees")


def test_clean_ratios_leave_room_below_the_tolerance(site):
    """The clean vehicles weighed alone (the traffic truck and 3 single runs): every
    gauge's ratio over what the others predict lies within 0.85 … 1.15 (measured:
    0.891 … 1.035; on two 80-event days of seeds 4 and 5, 76 vehicles: 0.878 … 1.204),
    inside the fault tolerance 1/1.3 … 1.3."""
    day, scenario, calibration = site
    ratios = []
    for path in (*day.traffic, *day.calibration):
        record = load_record(path, scenario)
        for v in weigh_event(record, calibration).vehicles:
            if v.weighed and "multiple_presence" not in v.flags:
                health = check_gauges(record, v.vehicle.passage, calibration.lines,
                                      combine=calibration.setup.combine)
                assert not health.faults and len(health.ratios) == 12
                ratios += list(health.ratios.values())
    assert len(ratios) == 4 * 12
    assert 0.85 < min(ratios) and max(ratios) < 1.15


def test_a_smooth_tilt_across_the_deck_is_no_fault(site, truck):
    """A vehicle beside the calibration truck's path loads the gauges on its side more:
    the ratios tilt smoothly with the gauges' y (on the 80-event days, up to 0.79 … 1.30
    across one vehicle against a constant).  Constructed (algebra of the check, no
    physics): every gauge of the clean file scaled by 0.75 … 1.25 linearly in y gives
    no fault and ratios within 0.85 … 1.15 of the line through the others (measured:
    0.903 … 1.030; against a constant instead of the line: 0.846 … 1.358); s05 reversed
    on top is still the one fault found."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    names = [c.name for c in calibration.lines.channels]
    y = np.array([c.sensors[0].y for c in calibration.lines.channels])
    tilt = 1.0 + 0.25 * (y - y.mean()) / (y.max() - y.mean())
    columns = [s.name for s in record.sensors]
    data = record.data.copy()
    for name, t in zip(names, tilt, strict=True):
        data[:, columns.index(name)] *= t
    tilted = dataclasses.replace(record, data=data)
    health = check_gauges(tilted, clean.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine)
    assert health.faults == ()
    assert all(0.85 < r < 1.15 for r in health.ratios.values()), health.ratios
    data[:, columns.index("s05")] *= -1.0
    health = check_gauges(dataclasses.replace(record, data=data), clean.vehicle.passage,
                          calibration.lines, combine=calibration.setup.combine)
    assert [(f.gauge, f.kind) for f in health.faults] == [("s05", "reversed")]


@pytest.mark.parametrize("gauge", ["s02", "s05"])
@pytest.mark.parametrize("fault", list(KIND))
def test_a_faulty_gauge_is_named_and_left_out(site, truck, tmp_path, fault, gauge):
    """Each fault on s02 (under the truck's wheel path, the largest signal) and s05 (the
    lane's far edge) is flagged ``gauge_fault:NAME`` with the fault's kind, quality
    ``warning``, and the gross weight from the other 11 gauges is within 4 % of the clean
    event's (measured: -3.0 … +1.4 % over these ten cases, s05 flat or reversed the
    largest).  The same file weighed with every gauge (no health check) is off by more
    than 5 % (measured: 6.5 % for s02 ×0.5 … 26.2 % for s02 reversed; s05 dead: -12.0 %
    with no flag at all, the issue's silent wrong weight).  The file keeps its name: the
    clock, hence the drift factor, is in it."""
    _, scenario, calibration = site
    path, clean = truck
    bad = _corrupted(path, tmp_path / path.name, scenario, [gauge], fault)
    record = load_record(bad, scenario)
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed, v.reason
    assert _gauge_faults(v.flags) == [f"gauge_fault:{gauge}"]
    assert v.weighing.quality == "warning"
    assert gauge not in [c.name for c in v.weighing.channels]
    assert v.gvw == pytest.approx(clean.gvw, rel=0.04)
    health = check_gauges(record, v.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine)
    assert [(f.gauge, f.kind) for f in health.faults] == [(gauge, KIND[fault])]
    unchecked = weigh(record, v.vehicle.passage, calibration.lines,
                      combine=calibration.setup.combine, scale=v.drift_factor)
    assert abs(unchecked.gvw / clean.gvw - 1.0) > 0.05


@pytest.mark.parametrize("gauge", ["s02", "s05"])
@pytest.mark.parametrize("factor", [0.7, 1.4])
def test_a_gain_change_under_half_again_is_not_found(site, truck, gauge, factor):
    """The gain check's limit, as README.md and docs/flags.md state it (review of stop
    37): a gauge's ratio is measured against a fit that includes it, which takes up part
    of the change (a true x1.5 reads about 1.26), and the clean vehicles' ratios reach
    0.88 ... 1.20, so a change of x0.7 or x1.4 is not found: the vehicle is weighed with
    the gauge, no gauge flag, its weight moved by more than 2 % (measured: 3.9 ... 5.2 %;
    x2 and x0.5 are found and left out: the tests above)."""
    _, scenario, calibration = site
    path, clean = truck
    record = _with(load_record(path, scenario), gauge, lambda y, _t: factor * y)
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and not _gauge_faults(v.flags)
    assert abs(v.gvw / clean.gvw - 1.0) > 0.02


def test_a_far_side_gauge_at_ten_times_its_gain(site, truck, tmp_path):
    """The issue's case: a far-side gauge (s12, 6.3 m from the truck's path) at gain ×10
    moved the weight by tens of percent with only ``lateral_extrapolated`` (measured
    here: +22.5 %).  Found and left out: within 1 % of the clean weight (measured
    -0.1 %)."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(_corrupted(path, tmp_path / path.name, scenario, ["s12"],
                                    "gain x10"), scenario)
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and _gauge_faults(v.flags) == ["gauge_fault:s12"]
    assert v.gvw == pytest.approx(clean.gvw, rel=0.01)
    unchecked = weigh(record, v.vehicle.passage, calibration.lines,
                      combine=calibration.setup.combine, scale=v.drift_factor)
    assert unchecked.gvw > 1.15 * clean.gvw and unchecked.quality == "warning"


@pytest.mark.parametrize("fault", ["dead", "stuck"])
def test_every_flat_gauge_is_found(site, truck, tmp_path, fault):
    """Any one of the 12 gauges dead or stuck, even one the truck hardly loads (s12, 6.3 m
    from its path), is found flat (no noise)."""
    _, scenario, calibration = site
    path, _ = truck
    for gauge in [c.name for c in calibration.lines.channels]:
        record = load_record(_corrupted(path, tmp_path / path.name, scenario, [gauge],
                                        fault), scenario)
        health = check_gauges(record, truck[1].vehicle.passage, calibration.lines)
        assert [(f.gauge, f.kind) for f in health.faults] == [(gauge, "flat")]


@pytest.mark.parametrize("gauge", ["s02", "s05"])
def test_a_gauge_that_reads_only_noise_is_silent(site, truck, gauge):
    """A broken gauge whose logger channel still shows its noise (its offset plus white
    noise of its calibration noise, seed 1): not flat, but no response to the load:
    found as ``silent`` and left out, within 4 % of the clean weight (measured: s02
    +1.4 %, s05 -2.9 %, as when they are dead)."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    k = [s.name for s in record.sensors].index(gauge)
    noise = calibration.lines.channel_noise[[c.name for c in calibration.lines.channels]
                                            .index(gauge)]
    data = record.data.copy()
    data[:, k] = data[0, k] + np.random.default_rng(1).normal(0.0, noise, data.shape[0])
    record = dataclasses.replace(record, data=data)
    _left_out(record, clean, calibration, gauge, "silent")


def test_a_logger_coarser_than_its_noise_is_not_flat(site, truck):
    """Every gauge of the clean event rounded to steps of 3 × its calibration noise (a
    logger whose resolution is coarser than the gauges' noise repeats most samples: more
    than half of the steps are 0, so a median-based noise would be 0) is no fault."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    columns = [s.name for s in record.sensors]
    data = record.data.copy()
    zero_steps = []
    for c, noise in zip(calibration.lines.channels, calibration.lines.channel_noise,
                        strict=True):
        k = columns.index(c.name)
        data[:, k] = np.round(data[:, k] / (3.0 * noise)) * (3.0 * noise)
        zero_steps.append(np.mean(np.diff(data[:, k]) == 0.0))
    assert min(zero_steps) > 0.5
    health = check_gauges(dataclasses.replace(record, data=data), clean.vehicle.passage,
                          calibration.lines, combine=calibration.setup.combine)
    assert health.faults == ()


def test_a_record_without_a_gauge_is_refused_not_raised(site, truck):
    """An event without the column of s05 (a logger that lost a channel): weigh_event
    still returns (its contract: it never raises on a record it can read), not weighed,
    the missing channel named; check_gauges alone names it in an InputError."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    record = record.channels([s.name for s in record.sensors if s.name != "s05"])
    ev = weigh_event(record, calibration)
    assert not ev.weighed and "s05" in ev.reason, ev.reason
    with pytest.raises(InputError, match="s05"):
        check_gauges(record, clean.vehicle.passage, calibration.lines)


def test_too_few_healthy_gauges_refuse_the_vehicle(site, truck, tmp_path):
    """Half the gauges dead (6 of 12): refused with the reason, the faults named; five
    dead: weighed with the other seven."""
    _, scenario, calibration = site
    path, _ = truck
    dead = ["s01", "s03", "s05", "s07", "s09", "s11"]
    record = load_record(_corrupted(path, tmp_path / path.name, scenario, dead, "dead"),
                         scenario)
    v = weigh_event(record, calibration).vehicles[0]
    assert not v.weighed and v.gvw is None
    assert v.reason.startswith("too few healthy gauges: 6 of 12, faulty: s01 (flat)")
    assert _gauge_faults(v.flags) == [f"gauge_fault:{g}" for g in dead]
    record = load_record(_corrupted(path, tmp_path / path.name, scenario, dead[1:], "dead"),
                         scenario)
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and len(_gauge_faults(v.flags)) == 5


def test_restricted_lines_are_the_chosen_columns(site):
    """Algebra: the restricted calibration holds the chosen channels' columns of the
    lines, deviations, covariance and noise; all channels give the calibration itself."""
    _, _, calibration = site
    lines = calibration.lines
    sub = restrict_lines(lines, ["s04", "s02"])
    assert [c.name for c in sub.channels] == ["s02", "s04"]
    np.testing.assert_array_equal(sub.line.ordinates, lines.line.ordinates[:, [1, 3]])
    np.testing.assert_array_equal(sub.channel_covariance,
                                  lines.channel_covariance[np.ix_([1, 3], [1, 3])])
    np.testing.assert_array_equal(sub.channel_std, lines.channel_std[[1, 3]])
    assert restrict_lines(lines, [c.name for c in lines.channels]) is lines
    with pytest.raises(InputError, match="not channels of the calibration: s99"):
        restrict_lines(lines, ["s01", "s99"])


def test_the_flag_is_explained_with_its_gauge():
    meaning = explain("gauge_fault:s02")
    assert meaning.group == "soft" and meaning.flag == "gauge_fault:s02"
    assert "left out" in meaning.meaning


def test_bwim_weigh_writes_the_flag(site, truck, tmp_path):
    """``bwim weigh`` on a folder of the one event with s02 reversed: its row is weighed
    with quality ``warning`` and the flag ``gauge_fault:s02`` in summary.csv."""
    day, scenario, _ = site
    path, clean = truck
    folder = tmp_path / "traffic"
    folder.mkdir()
    _corrupted(path, folder / path.name, scenario, ["s02"], "reversed")
    out = tmp_path / "out"
    assert main(["weigh", str(day.scenario), str(folder), "--calibration-records",
                 str(day.calibration[0].parent), "-o", str(out)]) == 0
    with (out / "summary.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1 and rows[0]["status"] == "weighed", rows
    assert "gauge_fault:s02" in rows[0]["flags"].split(";")
    assert rows[0]["quality"] == "warning"
    assert float(rows[0]["gvw_kN"]) * 1e3 == pytest.approx(clean.gvw, rel=0.04)


# --- clipped and drifting gauges -----------------------------------------------------------
def _with(record, gauge: str, change) -> object:
    """``record`` with the column of ``gauge`` replaced by ``change(column, time)``."""
    k = [s.name for s in record.sensors].index(gauge)
    data = record.data.copy()
    data[:, k] = change(data[:, k], record.time)
    return dataclasses.replace(record, data=data)


def _rail(fraction: float):
    """A logger's rail ``fraction`` of the way from the first reading to the channel's
    farthest reading: the readings beyond it held at it (saturation)."""
    def clip(y, _t):
        up, down = y.max() - y[0], y[0] - y.min()
        if up >= down:
            return np.minimum(y, y[0] + fraction * up)
        return np.maximum(y, y[0] - fraction * down)
    return clip


@pytest.mark.parametrize("gauge", ["s02", "s05"])
def test_a_clipped_gauge_is_named_and_left_out(site, truck, gauge, tmp_path):
    """The truck's gauge held at a rail halfway to its peak (the clean readings, with
    their noise and offset, saturated: 74 consecutive samples for s02, 81 for s05) is
    found ``clipped``, left out and flagged; the weight from the other 11 gauges is
    within 4 % of the clean event's (measured: s02 +1.2 %, s05 -3.0 %, as for the other
    faults of s05 above; weighed with the clipped gauge: -2.8 %, -4.5 %).  Read from the
    logger's text file: the scenario's reader leaves the rail to this check (review of
    stop 37: it refused the whole record, "channel 's03' sits at its maximum", and the
    vehicle was lost)."""
    _, scenario, calibration = site
    path, clean = truck
    record = _with(load_record(path, scenario), gauge, _rail(0.5))
    k = [s.name for s in record.sensors].index(gauge)
    column = list(scenario.logger.columns).index(gauge)
    rows = [line.split() for line in path.read_text().splitlines()]
    for r, v in zip(rows, record.data[:, k], strict=True):
        r[column] = f"{v:.3f}"
    bad = tmp_path / path.name
    bad.write_text("\n".join("\t".join(r) for r in rows) + "\n")
    _left_out(load_record(bad, scenario), clean, calibration, gauge, "clipped")


def test_a_gauge_clipped_at_its_resting_reading_is_found(site, truck, tmp_path):
    """The reader's hole (issue 22): s02 clipped at its first reading (a rail at the
    resting level: the file's first sample is the channel's maximum, so the logger
    reader's clipping check passes it), read from the logger file: not flat (it keeps its
    noise below the rail at rest), found ``clipped`` and left out; weighed within 4 % of
    the clean weight (measured: +1.4 %); weighed with it: -12.4 %, with no gauge flag (a
    silent wrong weight)."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    k = [s.name for s in record.sensors].index("s02")
    rail = float(record.data[0, k])
    bad = tmp_path / path.name
    rows = [line.split() for line in path.read_text().splitlines()]
    column = list(scenario.logger.columns).index("s02")
    for r in rows:
        r[column] = f"{min(float(r[column]), rail):.3f}"
    bad.write_text("\n".join("\t".join(r) for r in rows) + "\n")
    record = load_record(bad, scenario)
    assert record.data[0, k] == record.data[:, k].max()
    v = _left_out(record, clean, calibration, "s02", "clipped")
    unchecked = weigh(record, v.vehicle.passage, calibration.lines,
                      combine=calibration.setup.combine, scale=v.drift_factor)
    assert abs(unchecked.gvw / clean.gvw - 1.0) > 0.05


@pytest.mark.parametrize("gauge", ["s02", "s05"])
@pytest.mark.parametrize("shape", ["ramp", "shift"])
def test_a_drifting_gauge_is_named_and_left_out(site, truck, gauge, shape):
    """A gauge's baseline changing by 30 × its noise at rest over the record (the
    simulated site's gauges change by 2 noise σ per event, σ of the simulation): a
    straight ramp over the whole record, or a shift while the truck is on the span (a
    zero shift).  Found as ``drift`` (not as a gain error: a straight line in time
    explains its residual better), left out and flagged; weighed within 2 % of the clean
    weight (measured: -0.6 … +1.4 %; weighed with the drifting gauge: +0.6 … +1.0 %, the
    offsets fitted before and after the truck absorb most of a change on this site).  On
    a 60-event day (seed 31, 64 vehicles and 12 runs, every gauge) the clean changes
    beyond what the others show reach 7.8 × the noise, against the limit 20
    (DRIFT_NOISE); no drift fault there."""
    _, scenario, calibration = site
    path, clean = truck
    record = load_record(path, scenario)
    noise = calibration.lines.channel_noise[[c.name for c in calibration.lines.channels]
                                            .index(gauge)]
    p = clean.vehicle.passage
    x = p.axle_x(record.time)
    x0, x1 = calibration.lines.support
    on = np.flatnonzero(np.any((x >= x0) & (x <= x1), axis=1))
    t_on = record.time[on[[0, -1]]]

    def drift(y, t):
        if shape == "ramp":
            return y + 30.0 * noise * (t - t[0]) / (t[-1] - t[0])
        return y + 30.0 * noise * np.clip((t - t_on[0]) / (t_on[1] - t_on[0]), 0.0, 1.0)

    record = _with(record, gauge, drift)
    health = check_gauges(record, p, calibration.lines, combine=calibration.setup.combine)
    assert [(f.gauge, f.kind) for f in health.faults] == [(gauge, "drift")]
    v = weigh_event(record, calibration).vehicles[0]
    assert v.weighed and _gauge_faults(v.flags) == [f"gauge_fault:{gauge}"]
    assert v.gvw == pytest.approx(clean.gvw, rel=0.02)


@pytest.mark.parametrize("gauge", ["s02", "s05", "s09"])
def test_a_large_drift_is_told_from_a_gain_error(site, truck, gauge):
    """A baseline ramp of 60 × the noise over the record moves the gauge's readings under
    the truck enough that its gain ratio is off as well (the gain check alone calls it
    ``gain``); its residual is a straight line in time rather than a multiple of its
    fitted reading, so it is named ``drift``."""
    _, scenario, calibration = site
    path, clean = truck
    noise = calibration.lines.channel_noise[[c.name for c in calibration.lines.channels]
                                            .index(gauge)]
    record = _with(load_record(path, scenario), gauge,
                   lambda y, t: y + 60.0 * noise * (t - t[0]) / (t[-1] - t[0]))
    health = check_gauges(record, clean.vehicle.passage, calibration.lines,
                          combine=calibration.setup.combine)
    assert [(f.gauge, f.kind) for f in health.faults] == [(gauge, "drift")]


def test_predicted_lines_are_each_channels_line_through_the_others():
    """The prediction of every channel at once (the check's, health_kernels.loo_lines
    with weights snr²) is, byte for byte, the weighted least-squares line through the
    other channels alone (each's own 1-D sums, written out here), and within 1e-9 the
    weighted fit of numpy.polyfit (the reference line); nan for a channel whose others
    have no weight."""
    from bwim.site.health_kernels import loo_lines

    def _predicted(y, values, snr):
        return loo_lines(y, values, snr ** 2, y)

    rng = np.random.default_rng(5)
    for n in (4, 7, 12, 13, 20):
        y = np.sort(rng.uniform(0.0, 12.0, n))
        values, snr = rng.normal(1.0, 0.2, n), rng.uniform(0.5, 30.0, n)
        got = _predicted(y, values, snr)
        for g in range(n):
            x, v, w = np.delete(y, g), np.delete(values, g), np.delete(snr, g) ** 2
            xm, vm = (w * x).sum() / w.sum(), (w * v).sum() / w.sum()
            slope = (w * (x - xm) * (v - vm)).sum() / (w * (x - xm) ** 2).sum()
            assert got[g].tobytes() == (vm + slope * (y[g] - xm)).tobytes()
            fit = np.polyval(np.polyfit(x, v, 1, w=np.sqrt(w)), y[g])
            assert got[g] == pytest.approx(fit, rel=1e-9)
    assert np.isnan(_predicted(np.arange(4.0), np.ones(4), np.array([1.0, 0, 0, 0]))[0])


def test_held_extremes_are_runs_of_the_clipping_length():
    """A channel is a clipping candidate (health._held) exactly when its maximum or its
    minimum repeats over at least CLIP_RUN consecutive samples (a plain scan of the
    runs, the reference), anywhere in the record, the ends included."""
    from bwim.site.health import CLIP_RUN, _held

    def longest(mask):
        best = run = 0
        for m in mask:
            run = run + 1 if m else 0
            best = max(best, run)
        return best

    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(CLIP_RUN, 60))
        r = rng.integers(-3, 4, size=(n, 6)).astype(float)  # coarse: many repeats
        for k in range(6):  # plant runs of random length at the rails
            a, length = int(rng.integers(0, n)), int(rng.integers(1, 8))
            r[a:a + length, k] = r[:, k].max() if k % 2 else r[:, k].min()
        expect = [max(longest(r[:, k] == r[:, k].max()), longest(r[:, k] == r[:, k].min()))
                  >= CLIP_RUN for k in range(6)]
        assert _held(r).tolist() == expect
