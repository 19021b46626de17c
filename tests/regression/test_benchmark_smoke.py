"""Fast smoke versions of the benchmarks: they run, and their fast paths agree with the
baselines they are timed against (each benchmark checks that before timing)."""

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


def test_calibration_benchmark_smoke():
    """The calibration benchmark runs; it checks the dynamic objective (scaled modes)
    against a plain simulation of the same trial before timing."""
    from benchmarks import bench_calibration

    rows = bench_calibration.run_objectives(approach=5.0, repeat=1, number=2)
    assert [r[0].split()[0] for r in rows] == ["static", "dynamic,", "dynamic,"]
