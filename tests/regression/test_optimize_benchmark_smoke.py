"""Fast smoke version of the optimiser benchmark: it runs, every method reaches the
target on a small sphere, and the table has the expected rows."""

from benchmarks import bench_optimize


def test_optimize_benchmark_smoke():
    problems = [bench_optimize.sphere_problem(4), bench_optimize.rosenbrock_problem(2)]
    rows = bench_optimize.run(problems, seeds=(0,), budget=60_000)
    assert [r[:3] for r in rows] == [
        ["sphere 4-D", "f ≤ 1e-10", "CE"],
        ["sphere 4-D", "f ≤ 1e-10", "CE sub-structured"],
        ["sphere 4-D", "f ≤ 1e-10", "CMA-ES"],
        ["Rosenbrock 2-D", "f ≤ 1e-6", "CE"],
        ["Rosenbrock 2-D", "f ≤ 1e-6", "CMA-ES"],
    ]
    assert all(r[4] == "1/1" for r in rows), rows


def test_nlc_benchmark_problem_smoke():
    problem = bench_optimize.nlc_problem(0)
    assert problem.x0.shape == (48,) and problem.neighbours.shape == (9, 48)
    assert problem.neighbours.sum(axis=1).tolist() == [12] * 9
    rows = bench_optimize.run([problem], seeds=(0,), budget=20_000,
                              methods=("CE sub-structured",))
    assert rows[0][2:5] == ["CE sub-structured", "4,200", "1/1"]
