"""Fast smoke version of the detection benchmark (benchmarks/bench_detect.py): it runs and
its rows carry the accuracy the validation tests assert."""

from benchmarks import bench_detect


def test_detect_benchmark_smoke():
    rows = bench_detect.detector_rows(speeds=(20.0,), seeds=range(2), noises=(0.02,))
    assert [r[0] for r in rows] == ["truck, noise 0.02 V", "tridem 1.3 m, 25 m/s"]
    assert rows[0][1] == 2 and rows[1][1] == 2
    # speed within 0.2 %, spacings within 25 mm (tests/validation/test_vehicle_detection.py)
    assert all(float(r[2]) < 0.2 and float(r[4]) < 25.0 for r in rows)
