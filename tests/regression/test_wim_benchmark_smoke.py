"""Fast smoke version of the static B-WIM benchmark (benchmarks/bench_wim.py): it runs,
its table has one row per method, vehicle and speed (plus "all"), and the GVW errors
against the simulated vehicles' static weights are the size measured on the paper's
bridge: Moses 1.5–2.0 %, MFI with the exact model 0.4 / 1.1 % (two-axle truck /
tractor-semitrailer), printed by ``bench_wim.run`` with these arguments."""

import numpy as np
from benchmarks import bench_wim


def test_wim_benchmark_smoke():
    vehicles = ("two_axle_truck", "tractor_semitrailer")
    rows = bench_wim.run(vehicles=vehicles, speeds=(20.0,), seeds=(1,),
                         calibration_runs=((20.0, 101), (17.0, 102)), approach=20.0)
    n_methods = len(bench_wim.METHODS)
    assert len(rows) == n_methods * len(vehicles) * 2
    assert [r[0] for r in rows[:: 2 * len(vehicles)]] == [m[0] for m in bench_wim.METHODS]
    gvw = {}
    for r in rows:
        assert r[2] in ("20", "all") and r[3] == 1
        n_axles = 2 if r[1] == "two_axle_truck" else 5
        assert len(r[4].split("/")) == n_axles
        assert np.isfinite(float(r[6]))
        gvw[r[0], r[1]] = float(r[7])
    # bounds ≈ 1.5× the largest measured of each kind (Moses 2.0 %, MFI 1.1 %)
    for (method, vehicle), e in gvw.items():
        assert 0.0 <= e < (1.8 if method.startswith("MFI") else 3.0), (method, vehicle, e)
    # MFI with the exact model weighs the whole vehicle best (the paper's premise)
    for vehicle in vehicles:
        mfi = gvw["MFI, exact FE model", vehicle]
        others = [e for (m, v), e in gvw.items() if v == vehicle and not m.startswith("MFI")]
        assert mfi < min(others), (vehicle, mfi, others)
