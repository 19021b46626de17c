"""An axle group off its vehicle's wheel path (bwim.site.wheelpath).

References:
* ``group_laterals``: readings symmetric about a load on gauges symmetric about it give
  the load's position exactly (the contract of bwim.detect.lateral); here each axle
  group loads a 6 m simply supported span (the mid-span bending influence line of a
  simply supported beam, a triangle of half-length 3 m: zero beyond it) with a Gaussian
  transverse spread, on gauges every 0.5 m, so each group's position is known exactly
  and its neighbours (more than 3 m away when it crosses) add nothing.
* ``refuse_off_path``: the median and the normal-scaled median absolute deviation are
  scipy's (``scipy.stats.median_abs_deviation(scale="normal")``), the modified z-score
  Iglewicz & Hoaglin's (1993), with the limit OFF_PATH_Z.  The day's rows are built here (the
  statistic is algebra); its use on the realistic site is measured in
  benchmarks/bench_realsite.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bwim
from bwim.errors import InputError
from bwim.records import Passage
from bwim.site import finish_day
from bwim.site.wheelpath import (
    FLAG_GROUP_OFF_PATH,
    OFF_PATH_Z,
    deviations,
    group_laterals,
    refuse_off_path,
)
from bwim.summary import SummaryRow

GAUGES_Y = 3.0 + 0.5 * np.arange(12)  # 3.0 ... 8.5 m
HALF_SPAN = 3.0


def _record(passage: Passage, ys: list[float], loads: list[float], *, fs: float = 512.0,
            duration: float = 3.0, half_span: float = HALF_SPAN) -> bwim.Record:
    """Each axle i at lateral ys[i] with load loads[i]; gauges at x = 0 (the frame's
    gauge line), readings = triangle(x_i) × Gaussian(y_gauge − y_i)."""
    t = np.arange(0.0, duration, 1.0 / fs)
    x = passage.speed * (t[:, None] - passage.delay) - passage.axle_offsets[None, :]
    tri = np.clip(1.0 - np.abs(x) / half_span, 0.0, None)  # (n_t, n_axles)
    spread = np.exp(-0.5 * ((GAUGES_Y[None, :] - np.asarray(ys)[:, None]) / 0.7) ** 2)
    data = (tri * np.asarray(loads)[None, :]) @ spread  # (n_t, n_gauges)
    sensors = tuple(bwim.Sensor(x=0.0, y=float(y), name=f"g{k}")
                    for k, y in enumerate(GAUGES_Y))
    return bwim.Record(time=t, data=data, sensors=sensors)


def test_each_group_is_measured_where_it_drives():
    # a 5-axle vehicle (steering axle, drive axle, tridem) whose drive axle is 1 m aside:
    # gauge positions 0.5 m apart and every group centred on a gauge or midway
    p = Passage(speed=20.0, axle_spacings=[3.5, 6.0, 1.3, 1.3], delay=0.8)
    ys = [5.0, 6.0, 5.25, 5.25, 5.25]
    rec = _record(p, ys, [60e3, 100e3, 80e3, 80e3, 80e3])
    got = group_laterals(rec, p, gauge_line=0.0, window=(0.5, 2.5))
    assert got == pytest.approx([5.0, 6.0, 5.25], abs=1e-9)


def test_the_gauge_line_places_the_windows():
    # the gauges' line declared 3 m after where it is (at the span's end): the drive
    # axle's window opens when it is leaving the span and the rear axle (y = 7, 6 m
    # behind) is arriving, and the rear axle pulls the drive axle's position towards it
    p = Passage(speed=20.0, axle_spacings=[3.5, 6.0], delay=0.8)
    rec = _record(p, [5.0, 6.0, 7.0], [60e3, 100e3, 80e3])
    right = group_laterals(rec, p, gauge_line=0.0)
    assert right == pytest.approx([5.0, 6.0, 7.0], abs=1e-9)
    wrong = group_laterals(rec, p, gauge_line=3.0)
    assert wrong[1] > 6.0 + 0.1


def test_on_a_long_span_a_group_off_the_path_is_pulled_back_never_further():
    """A 30 m span: every group is on the gauges while each crosses, so the positions
    measured are pulled towards each other: a vehicle on one path measures one path, and
    a group 1 m aside measures less than 1 m aside (the check loses power, it does not
    refuse more)."""
    p = Passage(speed=20.0, axle_spacings=[3.5, 6.0, 1.3, 1.3], delay=1.5)
    loads = [60e3, 100e3, 80e3, 80e3, 80e3]
    kw = {"duration": 5.0, "half_span": 15.0}
    aligned = group_laterals(_record(p, [5.5] * 5, loads, **kw), p, gauge_line=0.0)
    assert aligned == pytest.approx([5.5, 5.5, 5.5], abs=1e-9)
    ys = [5.5, 6.5, 5.5, 5.5, 5.5]
    true = [d for _, d in deviations([5.5, 6.5, 5.5])]  # -0.5, +1.0, -0.5: the 6 m span's
    short = group_laterals(_record(p, ys, loads, duration=5.0), p, gauge_line=0.0)
    assert [d for _, d in deviations(short)] == pytest.approx(true, abs=1e-9)
    long = group_laterals(_record(p, ys, loads, **kw), p, gauge_line=0.0)
    measured = [d for _, d in deviations(long)]
    assert all(abs(m) < abs(t) for m, t in zip(measured, true, strict=True))


def test_a_group_outside_the_record_is_not_measured():
    p = Passage(speed=20.0, axle_spacings=[3.5, 6.0], delay=2.5)
    rec = _record(p, [5.0, 5.0, 5.0], [60e3, 100e3, 80e3])
    assert group_laterals(rec, p, gauge_line=0.0) == ()


def test_bad_arguments_are_input_errors():
    p = Passage(speed=20.0, axle_spacings=[3.5], delay=0.8)
    rec = _record(p, [5.0, 5.0], [60e3, 100e3])
    with pytest.raises(InputError, match="gauge_line"):
        group_laterals(rec, p, gauge_line=float("nan"))
    with pytest.raises(InputError, match="passage"):
        group_laterals(rec, "p", gauge_line=0.0)
    with pytest.raises(InputError, match="group_spacing"):
        group_laterals(rec, p, gauge_line=0.0, group_spacing=0.0)


def test_deviations_are_each_group_against_the_mean_of_the_others():
    got = deviations([5.0, 5.0, 6.5])
    assert [r for r, _ in got] == ["first", "middle", "last"]
    assert [d for _, d in got] == pytest.approx([5.0 - 5.75, 5.0 - 5.75, 6.5 - 5.0])
    assert deviations([5.0]) == ()
    assert [r for r, _ in deviations([1.0, 2.0, 3.0, 4.0])] == \
        ["first", "middle", "middle", "last"]


def _row(k: int, paths: tuple[float, ...], *, lane: int = 1, weighed: bool = True
         ) -> SummaryRow:
    lateral = float(np.mean(paths)) if paths else None
    common = {"record": f"e{k:04d}.txt", "lane": lane, "direction": "+x",
              "n_axles": len(paths) or 2, "lateral": lateral,
              "lateral_unit": "m" if lateral is not None else "", "group_laterals": paths}
    if weighed:
        n = len(paths) or 2
        return SummaryRow(axle_weights=(50e3,) * n, group_weights=(50e3,) * n,
                          gvw=50e3 * n, quality="ok", method="moses", **common)
    return SummaryRow(status="refused", reason="two vehicles", **common)


@pytest.fixture
def day(rng):
    """200 three-group vehicles: the steering group 0.12 m right of the others (its
    single tyres), spread 0.1 m at the normal quantiles (none beyond 2.9 σ), shuffled."""
    q = rng.permutation(stats.norm.ppf((np.arange(200) + 0.5) / 200))
    y = 5.9 + 0.3 * rng.standard_normal(200)
    return [_row(k, (y[k] - 0.12 + 0.1 * q[k], y[k], y[k]))
            for k in range(200)]


def test_spreads_are_the_median_and_normal_scaled_mad_per_role(day):
    check = refuse_off_path(day)
    assert [(s.lane, s.role, s.n) for s in check.spreads] == \
        [(1, "first", 200), (1, "middle", 200), (1, "last", 200)]
    first = np.array([deviations(r.group_laterals)[0][1] for r in day])
    s = check.spreads[0]
    assert s.median == pytest.approx(np.median(first), abs=1e-12)
    assert s.sigma == pytest.approx(stats.median_abs_deviation(first, scale="normal"),
                                    rel=1e-12)
    assert check.refused == ()
    assert all(a is b for a, b in zip(check.rows, day, strict=True))


def test_an_axle_of_the_next_lane_is_refused_and_the_vehicle_alone_kept(day):
    # the next lane's steering axle counted as this vehicle's first group: 2 m aside
    merged = _row(900, (7.9, 5.9, 5.9))
    # a vehicle alone whose first group lies within the spread (2.5 σ of 0.1 m)
    alone = _row(901, (5.9 - 0.18 + 0.25, 5.9, 5.9))
    check = refuse_off_path([*day, merged, alone])
    assert check.refused == ((merged.record, 1),)
    refused = check.rows[-2]
    assert refused.status == "refused" and refused.gvw is None
    assert refused.axle_weights == () and refused.group_weights == ()
    assert refused.quality == "reject" and FLAG_GROUP_OFF_PATH in refused.flags
    assert refused.group_laterals == merged.group_laterals
    assert "axle group 1" in refused.reason and "beside it" in refused.reason
    assert check.rows[-1] is alone


def test_the_limit_is_the_modified_z_score(day):
    s = refuse_off_path(day).spreads[0]
    # the steering group 0.3 σ inside and outside the limit (the two added rows move the
    # median and MAD a little: judged as the check measures them)
    inside = _row(900, (6.0 + s.median + (OFF_PATH_Z - 0.4) * s.sigma, 6.0, 6.0))
    outside = _row(901, (6.0 + s.median - (OFF_PATH_Z + 0.4) * s.sigma, 6.0, 6.0))
    check = refuse_off_path([*day, inside, outside])
    assert check.refused == ((outside.record, 1),)
    assert refuse_off_path([*day, outside], limit=10.0).refused == ()


def test_thin_lanes_unmeasured_rows_and_refused_rows_are_left_alone(day):
    few = [_row(1000 + k, (9.0, 9.0 + 0.1 * k), lane=2) for k in range(10)]
    odd = _row(2000, (9.0, 15.0), lane=2)
    unmeasured = _row(2001, ())
    not_weighed = _row(2002, (5.0, 8.0), weighed=False)
    rows = [*day, *few, odd, unmeasured, not_weighed]
    check = refuse_off_path(rows)
    assert {s.lane for s in check.spreads} == {1}
    assert check.refused == ()
    assert all(a is b for a, b in zip(check.rows, rows, strict=True))
    # with a lower minimum the thin lane is measured and its odd vehicle refused
    assert refuse_off_path(rows, min_vehicles=10).refused == ((odd.record, 1),)


def test_bad_arguments(day):
    with pytest.raises(InputError, match="limit"):
        refuse_off_path(day, limit=0.0)
    with pytest.raises(InputError, match="min_vehicles"):
        refuse_off_path(day, min_vehicles=2)


def test_finish_day_runs_the_check_after_the_lanes_spread(day, small_site_calibrated):
    merged = _row(900, (7.9, 5.9, 5.9))
    result = finish_day([*day, merged], small_site_calibrated[-1])
    assert result.wander.refused == ()  # its load centre lies inside the lane's spread
    assert result.paths.refused == ((merged.record, 1),)
    assert result.rows[-1].status == "refused"
    assert [r.record for r in result.rows] == [r.record for r in [*day, merged]]
    assert "PathCheck(" in repr(result)


def _group_laterals_reference(record, passage, gauge_line, window, gauges=None):
    """group_laterals as written before it read the gauges once per vehicle: each
    group's window from numpy's mean of its offsets, lateral_position per group."""
    from bwim.detect.lateral import lateral_position
    from bwim.wim import group_axles

    t = record.time
    offsets = passage.axle_offsets
    groups = [list(g) for g in group_axles(passage, 2.0)]
    quiet = None
    if window is not None:
        quiet = (t < window[0]) | (t > window[1])
        if quiet.sum() < max(3, t.size // 10):
            quiet = None
    out = []
    for k, g in enumerate(groups):
        centre = float(np.mean(offsets[g]))
        gaps = []
        if k > 0:
            gaps.append(offsets[g[0]] - offsets[groups[k - 1][-1]])
        if k + 1 < len(groups):
            gaps.append(offsets[groups[k + 1][0]] - offsets[g[-1]])
        half = min([0.6, *(0.25 * gp for gp in gaps)]) / passage.speed
        tg = passage.delay + (gauge_line + centre) / passage.speed
        if tg - half < t[0] or tg + half > t[-1]:
            return ()
        y = lateral_position(record, window=(tg - half, tg + half), quiet=quiet,
                             gauges=gauges).value
        if not np.isfinite(y):
            return ()
        out.append(float(y))
    return tuple(out)


def test_group_laterals_are_the_per_group_formula():
    """One read of the gauges and their quiet levels per vehicle, the groups' centres as
    Python sums: the numbers of the per-group formula bit for bit (groups of one to
    nine axles, windows with and without quiet samples, no window)."""
    rng = np.random.default_rng(8)
    n = 0
    for trial in range(60):
        spacings = rng.choice([1.3, 1.35, 3.2, 5.9, 1.25], size=int(rng.integers(1, 9)))
        if trial % 10 == 0:
            # one group of nine axles: numpy's pairwise mean (another number than the
            # values summed one after the other for these)
            spacings = np.array([1.3, 1.35] * 4)
        p = Passage(speed=float(rng.uniform(12, 25)), axle_spacings=spacings,
                    delay=float(rng.uniform(0.3, 0.9)))
        ys = rng.uniform(4.0, 7.5, p.n_axles).tolist()
        rec = _record(p, ys, rng.uniform(40e3, 100e3, p.n_axles).tolist(), duration=4.0)
        for window in ((0.4, 2.6), (0.05, 3.98), None):
            got = group_laterals(rec, p, gauge_line=0.1, window=window)
            assert got == _group_laterals_reference(rec, p, 0.1, window), (trial, window)
            n += len(got) > 0
    assert n > 60
