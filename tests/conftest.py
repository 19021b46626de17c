"""Test configuration: one BLAS thread, a seeded RNG, the Agg backend."""

import os

# Before numpy/scipy load BLAS: one thread, so timings and results are repeatable.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: tests are deterministic."""
    return np.random.default_rng(20121122)


# Property-based tests (hypothesis) run the same examples on every run: the suite is
# deterministic, as the rest of bwim is.  Explore more with HYPOTHESIS_PROFILE=explore.
from hypothesis import settings as _hypothesis_settings  # noqa: E402

_hypothesis_settings.register_profile("deterministic", derandomize=True, database=None)
_hypothesis_settings.register_profile("explore", derandomize=False)
_hypothesis_settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))


@pytest.fixture(scope="session")
def small_site(tmp_path_factory):
    """A small realistic site (``short-span-4-lane``, seed 4: six calibration runs, half
    with a lane-3 vehicle crossing, four traffic events, a 0.6 m mesh; a few seconds),
    made once per session: tests read its files and write nowhere in it."""
    from bwim.synthetic import make_test_day

    return make_test_day(tmp_path_factory.mktemp("small_site") / "day",
                         site="short-span-4-lane", seed=4, n_calibration=6, n_traffic=4,
                         n_calibration_day_traffic=0, mesh=0.6)


@pytest.fixture(scope="session")
def small_site_calibrated(small_site):
    """The small site's day, scenario, calibration runs (records) and their calibration
    (``bwim.calibrate_site``), made once per session; tests only read them."""
    from bwim.scenario import build_site_setup, load_record, load_scenario
    from bwim.site import calibrate_site

    scenario = load_scenario(small_site.scenario)
    records = [load_record(p, scenario) for p in small_site.calibration]
    return small_site, scenario, records, calibrate_site(records, build_site_setup(scenario))


@pytest.fixture(scope="session")
def small_site_truck(small_site_calibrated):
    """The small site's calibration and its one single-vehicle lane-1 traffic truck's
    record (6 axles), for tests that break the truck's record."""
    import csv

    from bwim.scenario import load_record

    day, scenario, _, site = small_site_calibrated
    with open(day.reference, newline="") as f:
        ref = next(r for r in csv.DictReader(f) if r["lane"] == "1")
    return site, load_record(day.out_dir / "traffic" / ref["record"], scenario)


@pytest.fixture(scope="session")
def seed31_site(tmp_path_factory):
    """Seed 31's short-span-4-lane day with one traffic file (the bench_realsite site:
    twelve calibration runs, six of them with a lane-3 vehicle crossing; a 0.5 m mesh;
    about 5 s), made once per session: tests read its files and write nowhere in it."""
    from bwim.synthetic import make_test_day

    return make_test_day(tmp_path_factory.mktemp("seed31") / "day", site="short-span-4-lane",
                         seed=31, n_traffic=1, n_calibration_day_traffic=0, mesh=0.5)
