"""Fast smoke version of the static B-WIM benchmark (benchmarks/bench_wim.py): it runs,
its table has one row per method, vehicle and speed (plus "all"), and the errors are the
size static B-WIM gets on the paper's bridge."""

import numpy as np
from benchmarks import bench_wim


def test_wim_benchmark_smoke():
    vehicles = ("two_axle_truck", "tractor_semitrailer")
    rows = bench_wim.run(vehicles=vehicles, speeds=(20.0,), seeds=(1,),
                         calibration_runs=((20.0, 101), (17.0, 102)), approach=20.0)
    n_methods = len(bench_wim.METHODS)
    assert len(rows) == n_methods * len(vehicles) * 2
    assert [r[0] for r in rows[:: 2 * len(vehicles)]] == [m[0] for m in bench_wim.METHODS]
    for r in rows:
        assert r[2] in ("20", "all") and r[3] == 1
        n_axles = 2 if r[1] == "two_axle_truck" else 5
        assert len(r[4].split("/")) == n_axles
        # GVW within 15 % (measured 1.5–2.0 %; typical B-WIM accuracy classes are 5–15 %)
        assert 0.0 <= float(r[7]) < 15.0 and np.isfinite(float(r[6]))
