"""Fast smoke version of benchmarks/bench_declarations.py (issue 22's declaration and
data-loss cases through ``bwim weigh``, ``report`` and ``demo``), on the session's small
realistic site (tests/conftest.py, ``small_site``: 6 calibration runs, 4 traffic events).
Expected outcomes are the issue's: a mistake refused with its reason, nothing lost."""

from benchmarks import bench_declarations

#: The declaration cases that are refused before the lines are fitted (seconds).
QUICK = ("axle loads in kg, not N", "3-axle truck declared for the 5-axle")


def test_declaration_benchmark_smoke(small_site):
    """The units mistake and the 3-axle declaration refused; ``--resume`` on 2 of the 4
    records keeps every earlier row; each existing output of weigh, report and demo
    refused without --force and left whole."""
    out = bench_declarations.run(small_site.out_dir, QUICK)
    assert [o.case for o in out[:2]] == list(QUICK)
    assert out[0].actual.startswith("refused: the calibration truck's declared axle loads "
                                    "are implausible"), out[0].actual
    assert out[1].actual.startswith("refused"), out[1].actual
    assert out[2].case == "weigh --resume on 2 of 4 records" and out[2].as_expected, \
        out[2].actual
    existing = out[3:]
    assert len(existing) == len(bench_declarations.WEIGH_OUTPUTS) + 2
    assert all(o.as_expected and "exists" in o.actual for o in existing), \
        [o.actual for o in existing if not o.as_expected]
    assert sum(o.silent for o in out) == 0
