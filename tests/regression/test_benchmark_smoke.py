"""Fast smoke versions of the benchmarks: they run, and their fast paths agree with the
baselines they are timed against (each benchmark checks that before timing)."""

import csv

from benchmarks import bench_fe


def test_fe_benchmark_smoke():
    rows = bench_fe.run(meshes=((6, 4),), repeat=1, min_time=0.0)
    assert [r[1] for r in rows] == ["assemble K(p)", "factor + 18 solves", "lowest 20 modes"]


def test_vbi_benchmark_smoke():
    from benchmarks import bench_vbi

    rows, _ = bench_vbi.run(approach=5.0, repeat=1, full=False)
    assert [r[1] for r in rows] == ["coupled", "iterative"]


def test_mfi_benchmark_smoke():
    from benchmarks import bench_mfi

    rows = bench_mfi.run(durations=(0.3,), batch_durations=(0.02,), repeat=1)
    assert len(rows) == 2 and rows[1][5].endswith("×")


def test_mfi_search_benchmark_smoke():
    """The L-curve-against-one-sweep table and the stacked-λ table run on a short record;
    each checks its timed answers against a one-λ sweep before timing (the L-curve's
    forces are the trajectory of the λ it chose; the stacked λ equal the single ones)."""
    from benchmarks import bench_mfi

    rows = bench_mfi.run_sweep_ratio(durations=(0.4,), repeat=1)
    assert len(rows) == 1 and rows[0][-1].startswith("≤ 3×")
    stacked = bench_mfi.run_stacked(durations=(0.4,), n_lams=(1, 2), repeat=1)
    assert len(stacked) == 1 and stacked[0][-1].endswith("×)")


def test_mfi_breakdown_benchmark_smoke():
    """The L-curve search's time breakdown runs on a short record: its stacked passes and
    the rest, in sweeps, add up to its ratio (to rounding of the printed parts)."""
    from benchmarks import bench_mfi

    (row,) = bench_mfi.run_breakdown(durations=(0.4,), repeat=1)
    parts = [float(p.split(": ")[1]) for p in row[3].split(" + ")]
    assert parts and abs(sum(parts) + float(row[4]) - float(row[5])) < 0.02 * len(parts) + 0.02


def test_calibration_benchmark_smoke():
    """The calibration benchmark runs; it checks the dynamic objective (scaled modes)
    against a plain simulation of the same trial before timing."""
    from benchmarks import bench_calibration

    rows = bench_calibration.run_objectives(approach=5.0, repeat=1, number=2)
    assert [r[0].split()[0] for r in rows] == ["static", "dynamic,", "dynamic,"]


def test_site_model_benchmark_smoke(small_site):
    """The site-model benchmark runs on the session's small site (both weighings of its
    traffic date, the model accepted)."""
    from benchmarks import bench_site_model

    out = bench_site_model.run_folder(small_site.out_dir, 4, jobs=1)
    assert out["model"].accepted and len(out["results"]) == 4
    assert all(res.n_reference >= 1 for res in out["results"].values())


def test_mfi_static_benchmark_smoke():
    """The static-weight study runs on one crossing; MFI's windowed mean tracks the true
    forces' windowed mean (the paper truck: +0.33 against +0.41 %)."""
    from benchmarks import bench_mfi_static

    rows = bench_mfi_static.run(n_cases=1)
    assert len(rows) == 1 and abs(rows[0][3] - rows[0][4]) < 0.25


def test_drift_benchmark_smoke(tmp_path):
    """The drift-methods benchmark runs on a small site with its temperature channel: each
    method weighs the reference truck; one row per thinning of the traffic."""
    from benchmarks import bench_drift

    from bwim.synthetic import make_test_day

    day = make_test_day(tmp_path / "day", site="short-span-4-lane", seed=4, n_calibration=6,
                        n_traffic=6, n_calibration_day_traffic=0, mesh=0.6,
                        temperature_channel=True)
    out = bench_drift.run(day.out_dir, jobs=1)
    assert set(out["methods"]) == set(bench_drift.METHODS)
    assert all(res.n_reference >= 1 for res, _ in out["methods"].values())
    assert len(out["thin"]) == len(bench_drift.THINNING)


def test_axle_shares_benchmark_smoke(small_site):
    """The axle-shares study runs on the session's small site (its quick variants: the
    lines refitted with the true calibration passages)."""
    from benchmarks import bench_axle_shares

    rows = bench_axle_shares.study(bench_axle_shares.load_day(small_site.out_dir),
                                   quick=True)
    assert rows[0][0] == "chain (drift corrected)" and len(rows) >= 4
    weighed = {r[0]: int(r[2]) for r in rows}
    # the chain and the summed-gauge line weigh the day's one lane-1 truck (a lateral
    # model from the small site's 3 used runs may not)
    assert weighed["chain (drift corrected)"] == weighed["summed gauges (Moses)"] == 1


def test_stream_benchmark_smoke():
    """The continuous-recording benchmark runs on a short file: it checks that the streamed
    and the whole cut find the same events (raising otherwise) before timing, and both
    find the file's crossings (one every 10 s)."""
    from benchmarks import bench_stream

    rows = bench_stream.rows(0.5)
    assert [r[1] for r in rows[:3]] == ["streamed (cut_file)",
                                        "whole (read_logger + cut_events)",
                                        "trigger alone (in memory)"]
    assert rows[0][-1] == rows[1][-1] == "3"


def test_realsite_benchmark_smoke(small_site, capsys):
    """The realistic-site benchmark weighs the session's small site as bwim weigh does and
    prints its tables: the five weighings of the traffic date's lane-1 trucks, the
    detection table with every column, the speed table and where the time goes (the
    thin-traffic table needs a day of 15 trucks or more, and is left out)."""
    from benchmarks import bench_realsite

    d = bench_realsite.weigh_day(small_site.out_dir, 4)
    assert list(d["results"]) == ["bwim", "time of day", "no drift", "Moses", "oracle"]
    assert d["n_events"] == 4 and d["thin"] == {}
    with open(small_site.out_dir / "reference.csv", newline="") as f:
        lane1 = [r for r in csv.DictReader(f) if r["lane"] == "1"]
    assert d["n_ref"] == len(lane1) >= 1
    assert d["results"]["bwim"].n_reference == len(lane1)
    bench_realsite.print_days([d])
    out = capsys.readouterr().out
    assert "Realistic site, seed 4" in out and "axle group off path" in out
    assert "left out by speed" in out and "Speed of bwim weigh" in out
    assert "lane-1 trucks beside one the other way" in out
    assert 0 <= d["beside"][0] <= d["beside"][1]
    assert "Where an event's CPU time goes" in out
    # both timed (their ratio on 4 events is the machine's load, not a check: detection
    # alone, timed after the batch, once took 0.056 s against the batch's 0.052 s)
    assert d["t_detect"] > 0 and d["t_weigh"] > 0
    assert "A thin traffic date" not in out
