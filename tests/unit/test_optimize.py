"""Unit tests of bwim.optimize: sampling, elite updates, sub-structuring, injection, stop
rules, results, reproducibility, checkpoints, parallel evaluation and bad input.

The expected elite statistics are computed here independently of the implementation (sort
the values, take the first ⌈ρk⌉ rows, NumPy mean/std); the sub-structured union follows
the worked example of Dowling, OBrien & González (2012) §4.1, Fig. 3.
"""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from bwim.errors import InputError
from bwim.optimize import (
    CEResult,
    CrossEntropy,
    StopReason,
    evaluate,
    load_checkpoint,
    minimize_ce,
    parameter_elite_masks,
    save_checkpoint,
)
from bwim.optimize.substructure import elite_mask, part_elite_masks

C3 = np.array([1.0, -2.0, 3.0])


def _sphere(x):
    return float(np.sum((np.asarray(x) - C3) ** 2))


def _sphere_rows(X):
    return np.sum((np.asarray(X) - C3) ** 2, axis=-1)


def _run(opt, fun, n_iter=None):
    """Drive ask/tell for n_iter iterations (or to the end)."""
    i = 0
    while not opt.should_stop() and (n_iter is None or i < n_iter):
        X = opt.ask()
        opt.tell(X, fun(X))
        i += 1
    return opt


def _same_result(a: CEResult, b: CEResult) -> None:
    """Bitwise equality of two results, history included."""
    assert np.array_equal(a.x, b.x)
    assert a.fun == b.fun and a.nfev == b.nfev and a.nit == b.nit
    assert a.stop_reasons == b.stop_reasons and a.message == b.message
    assert a.convergence_iterations == b.convergence_iterations
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.std, b.std)
    for name in ("mean", "std", "best", "best_ever", "nfev", "converged"):
        assert np.array_equal(getattr(a.history, name), getattr(b.history, name)), name


# -- sampling ---------------------------------------------------------------------------
def test_ask_shape_and_default_std():
    opt = CrossEntropy([2.0, -4.0, 10.0], population=50, seed=1)
    X = opt.ask()
    assert X.shape == (50, 3)
    np.testing.assert_array_equal(opt.std, 0.3 * np.abs([2.0, -4.0, 10.0]))
    assert opt.n_elite == 3  # ⌈0.05 · 50⌉
    assert CrossEntropy([1.0], population=200).n_elite == 10  # not 11 from 0.05·200 rounding


def test_unbounded_samples_are_normal():
    opt = CrossEntropy([5.0, -1.0], std=[2.0, 0.5], population=20000, seed=3)
    X = opt.ask()
    for i, (m, s) in enumerate(((5.0, 2.0), (-1.0, 0.5))):
        assert stats.kstest(X[:, i], stats.norm(m, s).cdf).pvalue > 1e-3


def test_truncated_samples_follow_truncated_normal():
    """Reference: scipy.stats.truncnorm with a = (lo − m)/σ, b = (hi − m)/σ."""
    m, s, lo, hi = 1.0, 2.0, 0.5, 6.0
    opt = CrossEntropy([m, m], std=s, bounds=([lo, m], [hi, m + 0.1]), population=20000,
                       seed=4)
    X = opt.ask()
    ref = stats.truncnorm((lo - m) / s, (hi - m) / s, loc=m, scale=s)
    assert stats.kstest(X[:, 0], ref.cdf).pvalue > 1e-3
    assert X[:, 0].min() >= lo and X[:, 0].max() <= hi
    # mean on the lower bound, narrow interval: half-normal truncated at 0.05σ
    assert X[:, 1].min() >= m and X[:, 1].max() <= m + 0.1
    # an interval far narrower than σ: (nearly) uniform, not a few quantised values
    opt = CrossEntropy([1.0], std=1e9, bounds=(1.0 - 1e-6, 1.0 + 1e-6), population=20000,
                       seed=5)
    X = opt.ask()[:, 0]
    assert stats.kstest(X, stats.uniform(1.0 - 1e-6, 2e-6).cdf).pvalue > 1e-3
    assert np.unique(X).size > 19000


@settings(max_examples=60, deadline=None)
@given(
    lo=st.floats(-1e6, 1e6),
    width=st.floats(1e-6, 1e6),
    frac=st.floats(0.0, 1.0),
    std=st.floats(1e-9, 1e9),
    seed=st.integers(0, 2**32 - 1),
)
def test_samples_never_leave_bounds(lo, width, frac, std, seed):
    hi = lo + width
    if not hi > lo:
        return
    mean = min(max(lo + frac * width, lo), hi)
    opt = CrossEntropy([mean, 0.5], std=[std, 1.0], bounds=([lo, -np.inf], [hi, np.inf]),
                       population=64, seed=seed)
    for _ in range(3):
        X = opt.ask()
        assert np.all(np.isfinite(X))
        assert np.all((X[:, 0] >= lo) & (X[:, 0] <= hi))
        # a rugged objective drives the mean towards the bounds
        opt.tell(X, -np.abs(X[:, 0] - mean) + X[:, 1] ** 2)
        if opt.should_stop():
            break


def test_evaluated_trials_never_leave_bounds():
    lo, hi = np.array([0.5, -1.0, 2.9]), np.array([2.0, 0.0, 3.2])
    seen = []

    def fun(x):
        seen.append(x.copy())
        return _sphere(x)

    # the optimum (1, −2, 3) lies outside the box: the mean is pushed onto a bound, and
    # variance is injected there again and again
    res = minimize_ce(fun, [1.0, -0.5, 3.0], std=5.0, bounds=(lo, hi), population=40,
                      seed=0, max_evals=4000, convergences=1000)
    X = np.array(seen)
    assert X.shape[0] == res.nfev == 4000 and res.convergences > 10
    assert np.all((X >= lo) & (X <= hi))
    np.testing.assert_allclose(res.x, [1.0, -1.0, 3.0], atol=1e-2)  # measured 1.5e-3


# -- updates ----------------------------------------------------------------------------
def test_plain_update_is_elite_mean_and_std():
    opt = CrossEntropy([1.0, 2.0], population=40, elite_fraction=0.1, seed=2)
    X = opt.ask()
    values = _sphere_rows(np.c_[X, np.zeros(40)])
    opt.tell(X, values)
    elite = X[np.argsort(values, kind="stable")[:4]]
    np.testing.assert_allclose(opt.mean, elite.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(opt.std, elite.std(axis=0), rtol=1e-12)
    np.testing.assert_allclose(opt.result.elite_std, elite.std(axis=0), rtol=1e-12)


def test_smoothing_weights():
    m0, s0 = np.array([1.0, 2.0]), np.array([0.5, 0.4])
    opt = CrossEntropy(m0, s0, population=40, elite_fraction=0.1, seed=2,
                       smoothing=(0.7, 0.2))
    X = opt.ask()
    values = np.sum(X**2, axis=1)
    opt.tell(X, values)
    elite = X[np.argsort(values)[:4]]
    np.testing.assert_allclose(opt.mean, 0.7 * elite.mean(0) + 0.3 * m0, rtol=1e-14)
    np.testing.assert_allclose(opt.std, 0.2 * elite.std(0) + 0.8 * s0, rtol=1e-12)


def test_nonfinite_values_rank_last_and_never_win():
    opt = CrossEntropy([1.0, 1.0], population=20, elite_fraction=0.2, seed=5)
    X = opt.ask()
    values = np.sum(X**2, axis=1)
    order = np.argsort(values)
    bad = order[:3]  # the three best trials fail
    told = values.copy()
    told[bad] = [np.nan, np.inf, -np.inf]
    opt.tell(X, told)
    elite = X[order[3:7]]
    np.testing.assert_allclose(opt.mean, elite.mean(0), rtol=1e-14)
    assert opt.best_fun == values[order[3]]
    np.testing.assert_array_equal(opt.best_x, X[order[3]])
    # a population with no finite value leaves the distribution unchanged
    m, s = opt.mean, opt.std
    X = opt.ask()
    opt.tell(X, np.full(20, np.nan))
    np.testing.assert_array_equal(opt.mean, m)
    np.testing.assert_array_equal(opt.std, s)
    assert opt.history.best[-1] == np.inf
    assert elite_mask(np.array([np.nan, 2.0, 1.0, np.inf]), 3).tolist() == [
        False, True, True, False]


def test_substructured_union_follows_paper_figure_3():
    """Paper §4.1, Fig. 3: trials 1, 2, 5 are best for O3 and 2, 3, 5 for O5; x2
    neighbours O3 and O5, so its elite set is {1, 2, 3, 5} (1-based)."""
    k = 6
    V = np.full((k, 5), 10.0)
    V[[0, 1, 4], 2] = [1.0, 2.0, 3.0]  # O3 best: trials 1, 2, 5
    V[[1, 2, 4], 4] = [1.0, 2.0, 3.0]  # O5 best: trials 2, 3, 5
    V[[5, 3, 0], 0] = [1.0, 2.0, 3.0]  # O1 best: trials 6, 4, 1
    neighbours = np.zeros((5, 3), dtype=bool)
    neighbours[[2, 4], 1] = True  # x2 ↔ O3, O5
    neighbours[0, 0] = True  # x1 ↔ O1; x3 has no neighbouring part
    mask = parameter_elite_masks(V, neighbours, 3)
    assert np.flatnonzero(mask[1]).tolist() == [0, 1, 2, 4]
    assert np.flatnonzero(mask[0]).tolist() == [0, 3, 5]
    # x3 falls back to the global elite set by the sum of the parts
    assert np.flatnonzero(mask[2]).tolist() == np.sort(np.argsort(V.sum(1))[:3]).tolist()
    assert part_elite_masks(V, 3).shape == (5, 6)


def test_substructured_update_uses_each_parameters_elite():
    neighbours = np.array([[True, False], [False, True]])
    opt = CrossEntropy([1.0, 1.0], population=20, elite_fraction=0.1, seed=6,
                       neighbours=neighbours)
    X = opt.ask()
    V = np.c_[(X[:, 0] - 2.0) ** 2, (X[:, 1] - 0.5) ** 2]
    opt.tell(X, V)
    e0, e1 = X[np.argsort(V[:, 0])[:2], 0], X[np.argsort(V[:, 1])[:2], 1]
    np.testing.assert_allclose(opt.mean, [e0.mean(), e1.mean()], rtol=1e-14)
    np.testing.assert_allclose(opt.std, [e0.std(), e1.std()], rtol=1e-12)
    i = int(np.argmin(V.sum(1)))
    assert opt.best_fun == V[i].sum()
    np.testing.assert_array_equal(opt.result.fun_parts, V[i])


def test_answer_is_best_trial_ever_not_last_mean():
    res = minimize_ce(_sphere, [1.3, -1.5, 2.5], population=30, seed=0, max_iter=15)
    h = res.history
    assert res.fun == h.best.min() == h.best_ever[-1]
    assert _sphere(res.x) == res.fun
    assert np.all(np.diff(h.best_ever) <= 0)
    assert _sphere(res.mean) != res.fun
    assert h.mean.shape == h.std.shape == (15, 3)
    assert h.nfev.tolist() == list(range(30, 451, 30))


# -- convergence and variance injection ------------------------------------------------
def test_convergence_and_injection_schedule():
    """A flat objective converges every second iteration; σ is reset to c_j |m| with
    c_j from the schedule, the last entry repeating."""
    opt = CrossEntropy([2.0, -3.0], population=40, seed=7, convergences=4,
                       injection=(0.5, 0.2))
    stds = []
    while not opt.should_stop():
        X = opt.ask()
        opt.tell(X, np.ones(40))
        stds.append(opt.std)
    res = opt.result
    assert res.convergence_iterations == (2, 4, 6, 8)
    assert res.history.converged.tolist() == [False, True] * 4
    assert res.stop_reasons == (StopReason.CONVERGED,) and res.success
    h = res.history
    for it, c in ((2, 0.5), (4, 0.2), (6, 0.2)):
        np.testing.assert_allclose(stds[it - 1], c * np.abs(h.mean[it]), rtol=1e-15)
        np.testing.assert_array_equal(h.std[it], stds[it - 1])  # drawn from injected σ
    # the last convergence stops without injecting
    assert not np.allclose(stds[7], 0.2 * np.abs(res.mean))


def test_relative_tolerance_and_injection_scale():
    opt = CrossEntropy([1.0], population=40, tol=0.1, seed=0, injection=(0.3,),
                       injection_scale=[4.0], convergences=2)
    for value, conv in ((100.0, False), (95.0, True), (50.0, False), (44.0, False)):
        X = opt.ask()
        opt.tell(X, np.full(40, value))
        assert opt.history.converged[-1] == conv
    assert opt.std[0] != 0.3 * 4.0  # after iteration 2's injection, updated again
    assert opt.history.std[2, 0] == pytest.approx(1.2)


# -- stop rules -------------------------------------------------------------------------
def test_stop_max_evals_never_exceeded():
    res = minimize_ce(_sphere, [1.3, -1.5, 2.5], population=30, max_evals=100, seed=0)
    assert res.nfev == 90 and res.nit == 3
    assert res.stop_reasons == (StopReason.MAX_EVALS,) and not res.success
    assert "evaluation budget" in res.message


def test_stop_max_iter_and_target():
    res = minimize_ce(_sphere, [1.3, -1.5, 2.5], max_iter=4, seed=0)
    assert res.stop_reasons == (StopReason.MAX_ITER,) and res.nit == 4
    res = minimize_ce(_sphere, [1.3, -1.5, 2.5], target=1e-3, seed=0)
    assert res.stop_reasons == (StopReason.TARGET,) and res.fun <= 1e-3 and res.success
    assert res.history.best_ever[-2] > 1e-3 and res.nit > 2


def test_stop_std_collapsed_and_several_reasons():
    opt = CrossEntropy([1.0, 2.0], population=10, seed=0, max_iter=1)
    X = np.tile([1.0, 2.0], (10, 1))
    opt.tell(X, np.arange(10.0))
    assert opt.result.stop_reasons == (StopReason.MAX_ITER, StopReason.STD_COLLAPSED)
    assert opt.should_stop()
    with pytest.raises(InputError, match=r"ask\(\) called after the optimiser stopped "
                                         r"\(max_iter, std_collapsed\)"):
        opt.ask()
    with pytest.raises(InputError, match=r"tell\(\) called after"):
        opt.tell(X, np.arange(10.0))


def test_result_before_any_evaluation():
    opt = CrossEntropy([1.0, 2.0], seed=0)
    res = opt.result
    assert not opt.should_stop() and res.stop_reasons == () and not res.success
    np.testing.assert_array_equal(res.x, [1.0, 2.0])
    assert res.fun == np.inf and res.nfev == res.nit == 0 and res.fun_parts is None
    assert res.history.mean.shape == (0, 2) and res.message == "No population evaluated yet."
    assert np.all(np.isnan(res.elite_std))


# -- reproducibility and checkpoints -----------------------------------------------------
def test_same_seed_same_result_other_seed_differs():
    a = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], seed=11, vectorized=True)
    b = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], seed=11, vectorized=True)
    c = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], seed=12, vectorized=True)
    _same_result(a, b)
    assert not np.array_equal(a.x, c.x)
    rng = np.random.default_rng(11)  # a Generator is used as given
    d = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], seed=rng, vectorized=True)
    _same_result(a, d)


@pytest.mark.parametrize("sub", [False, True])
@pytest.mark.parametrize("between", ["tell_ask", "ask_tell"])
def test_pickle_resume_is_bitwise_identical(sub, between):
    neighbours = np.array([[1, 1, 0], [0, 1, 1]], dtype=bool) if sub else None

    def fun(X):
        V = np.c_[(X[:, 0] - 1.0) ** 2 + 0.1 * X[:, 1] ** 2, (X[:, 2] + 2.0) ** 2 + X[:, 1] ** 2]
        return V if sub else V.sum(1)

    def make():
        return CrossEntropy([2.0, 1.0, -1.0], population=40, seed=3, neighbours=neighbours,
                            smoothing=(0.9, 0.8), bounds=(-5.0, 5.0), max_evals=4000)

    full = _run(make(), fun).result
    half = _run(make(), fun, n_iter=7)
    if between == "ask_tell":
        X = half.ask()
        resumed = pickle.loads(pickle.dumps(half))
        resumed.tell(X, fun(X))
    else:
        resumed = pickle.loads(pickle.dumps(half))
    _same_result(_run(resumed, fun).result, full)


def test_checkpoint_resumes_an_interrupted_run(tmp_path):
    path = tmp_path / "ce.pkl"
    kw = dict(seed=5, population=30, max_evals=1500, vectorized=True)
    full = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], **kw)

    class Crash(Exception):
        pass

    def crash_at_6(result):
        if result.nit == 6:
            raise Crash

    with pytest.raises(Crash):
        minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], checkpoint=path, callback=crash_at_6, **kw)
    assert load_checkpoint(path).nit == 6
    resumed = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], checkpoint=path, **kw)
    _same_result(resumed, full)
    # a finished checkpoint returns its result without evaluating anything
    again = minimize_ce(lambda X: pytest.fail("evaluated"), [1.3, -1.5, 2.5],
                        checkpoint=path, **kw)
    _same_result(again, full)
    assert [p.name for p in tmp_path.iterdir()] == ["ce.pkl"]  # no temporary files left


class _Unpicklable(CrossEntropy):
    def __reduce__(self):
        raise pickle.PicklingError("no")


def test_checkpoint_bad_files(tmp_path):
    other = tmp_path / "other.pkl"
    other.write_bytes(pickle.dumps({"not": "an optimiser"}))
    with pytest.raises(InputError, match="does not hold a CrossEntropy checkpoint"):
        load_checkpoint(other)
    path = tmp_path / "ce.pkl"
    save_checkpoint(CrossEntropy([1.0, 2.0]), path)
    with pytest.raises(InputError, match="holds a run with 2 parameters"):
        minimize_ce(_sphere, [1.0, 2.0, 3.0], checkpoint=path)
    with pytest.raises(InputError, match="save_checkpoint needs a CrossEntropy"):
        save_checkpoint("x", path)
    # the one atomic writer (bwim.atomic): an unwritable path names its folder, and a
    # failed write leaves neither a temporary file nor a damaged checkpoint
    with pytest.raises(InputError, match="does not exist"):
        save_checkpoint(CrossEntropy([1.0, 2.0]), tmp_path / "no" / "ce.pkl")
    before = path.read_bytes()
    with pytest.raises(pickle.PicklingError):
        save_checkpoint(_Unpicklable([1.0, 2.0]), path)
    assert path.read_bytes() == before and sorted(tmp_path.iterdir()) == [path, other]


# -- minimize_ce modes ------------------------------------------------------------------
def test_parts_without_neighbours_is_plain_ce_on_the_sum():
    def parts(X):
        return (np.asarray(X) - C3) ** 2

    a = minimize_ce(parts, [1.3, -1.5, 2.5], parts=True, vectorized=True, seed=2)
    b = minimize_ce(_sphere_rows, [1.3, -1.5, 2.5], vectorized=True, seed=2)
    _same_result(a, b)
    c = minimize_ce(parts, [1.3, -1.5, 2.5], parts=True, neighbours=np.eye(3, dtype=bool),
                    vectorized=True, seed=2)
    assert c.fun_parts.shape == (3,) and c.fun == pytest.approx(c.fun_parts.sum())
    assert c.nfev < b.nfev  # a linear-combination problem: sub-structuring pays


def test_args_are_passed():
    res = minimize_ce(lambda x, c: float(np.sum((x - c) ** 2)), [2.0, 1.0], args=([1.0, 2.0],),
                      seed=0, max_iter=30)
    np.testing.assert_allclose(res.x, [1.0, 2.0], atol=1e-3)


# -- parallel evaluation ----------------------------------------------------------------
def _objectives():
    """Closures (pickled by value) for the worker processes."""
    c = C3.copy()

    def scalar(x):
        return float(np.sum((x - c) ** 2))

    def parts(x):
        return (x - c) ** 2

    return scalar, parts


def test_evaluate_serial_joblib_and_chunks_agree():
    scalar, parts = _objectives()
    X = np.random.default_rng(0).normal(size=(23, 3))
    ref = np.array([scalar(x) for x in X])
    np.testing.assert_array_equal(evaluate(scalar, X), ref)
    np.testing.assert_array_equal(evaluate(scalar, X, n_jobs=2), ref)
    np.testing.assert_array_equal(evaluate(scalar, X, n_jobs=2, chunk_size=4), ref)
    np.testing.assert_array_equal(evaluate(parts, X, n_jobs=2, chunk_size=5),
                                  (X - C3) ** 2)
    np.testing.assert_array_equal(evaluate(_sphere_rows, X, vectorized=True, chunk_size=7),
                                  _sphere_rows(X))


def test_minimize_ce_parallel_equals_serial():
    scalar, _ = _objectives()
    kw = dict(population=40, seed=9, max_evals=800)
    serial = minimize_ce(scalar, [1.3, -1.5, 2.5], **kw)
    _same_result(minimize_ce(scalar, [1.3, -1.5, 2.5], n_jobs=2, **kw), serial)


def test_dask_client_equals_serial():
    distributed = pytest.importorskip("distributed")
    scalar, parts = _objectives()
    kw = dict(population=40, seed=9, max_evals=400)
    serial = minimize_ce(scalar, [1.3, -1.5, 2.5], **kw)
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=2,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        _same_result(minimize_ce(scalar, [1.3, -1.5, 2.5], client=client, **kw), serial)
        X = np.random.default_rng(1).normal(size=(11, 3))
        np.testing.assert_array_equal(evaluate(parts, X, client=client, chunk_size=3),
                                      (X - C3) ** 2)


# -- bad input --------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "pattern"),
    [
        (dict(population=0), r"population must be an integer >= 2, got 0"),
        (dict(population=-5), r"population must be an integer >= 2, got -5"),
        (dict(population=10.5), r"population must be an integer, got 10.5"),
        (dict(elite_fraction=0.0), r"elite_fraction must lie in \(0, 1\], got 0"),
        (dict(elite_fraction=1.5), r"elite_fraction must lie in \(0, 1\], got 1.5"),
        (dict(elite_fraction=np.nan), r"elite_fraction must be finite, got nan"),
        (dict(std=0.0), r"std must be finite and > 0, got 0.0"),
        (dict(std=[1.0, -1.0]), r"std must be finite and > 0, got \[1.0, -1.0\]"),
        (dict(std=[1.0, 1.0, 1.0]), r"std must be a number or an array of shape \(2,\)"),
        (dict(bounds=(1.0, 1.0)), r"bounds need lo < hi, got lo\[0\] = 1 >= hi\[0\] = 1"),
        (dict(bounds=([0, 3], [2, 2])), r"lo\[1\] = 3 >= hi\[1\] = 2"),
        (dict(bounds=(2.0, 5.0)), r"mean\[0\] = 1 lies outside bounds \[2, 5\]"),
        (dict(bounds=(0.0,)), r"bounds must be a pair \(lo, hi\)"),
        (dict(neighbours=np.ones((3, 3), bool)),
         r"neighbours must be a bool array of shape \(n_parts, n_params\) = \(n_parts, 2\)"),
        (dict(neighbours=np.ones(2, bool)), r"got shape \(2,\)"),
        (dict(neighbours=[[0, 2]]), r"neighbours must hold booleans"),
        (dict(smoothing=0.0), r"smoothing alpha must lie in \(0, 1\], got 0"),
        (dict(smoothing=(1.0, 2.0)), r"smoothing beta must lie in \(0, 1\], got 2"),
        (dict(tol=-0.1), r"tol and atol must be >= 0"),
        (dict(convergences=0), r"convergences must be an integer >= 1, got 0"),
        (dict(injection=()), r"injection must be a non-empty sequence of factors > 0"),
        (dict(injection=(0.3, -0.1)), r"injection must be .* got \[0.3, -0.1\]"),
        (dict(injection_scale=0.0), r"injection_scale must be finite and > 0"),
        (dict(max_evals=100), r"max_evals must be an integer >= 200, got 100"),
        (dict(max_iter=0), r"max_iter must be an integer >= 1, got 0"),
        (dict(target=np.inf), r"target must be finite, got inf"),
    ],
)
def test_constructor_rejects(kw, pattern):
    with pytest.raises(InputError, match=pattern):
        CrossEntropy([1.0, 2.0], **kw)


def test_mean_rejects():
    with pytest.raises(InputError, match="mean must be a non-empty 1-D array"):
        CrossEntropy([])
    with pytest.raises(InputError, match="mean must be a non-empty 1-D array"):
        CrossEntropy([[1.0, 2.0]])
    with pytest.raises(InputError, match=r"mean must be finite, got \[1.0, nan\]"):
        CrossEntropy([1.0, np.nan])
    with pytest.raises(InputError, match="std must be given when mean has zero entries"):
        CrossEntropy([1.0, 0.0])


def test_tell_rejects():
    opt = CrossEntropy([1.0, 2.0], population=10, seed=0)
    X = opt.ask()
    with pytest.raises(InputError, match=r"X must have shape \(population, n_params\) = "
                                         r"\(10, 2\), got \(9, 2\)"):
        opt.tell(X[:9], np.ones(9))
    with pytest.raises(InputError, match=r"values must have shape \(population,\) = \(10,\), "
                                         r"got \(10, 1\)"):
        opt.tell(X, np.ones((10, 1)))
    with pytest.raises(InputError, match="X must be finite"):
        opt.tell(np.full((10, 2), np.nan), np.ones(10))
    bounded = CrossEntropy([1.0, 2.0], population=10, bounds=(0.0, 3.0))
    with pytest.raises(InputError, match="X leaves the bounds in parameter 1"):
        bounded.tell(np.tile([1.0, 3.5], (10, 1)), np.ones(10))
    sub = CrossEntropy([1.0, 2.0], population=10, neighbours=np.eye(2, dtype=bool))
    with pytest.raises(InputError, match=r"values must have shape \(population, n_parts\) = "
                                         r"\(10, 2\), got \(10,\)"):
        sub.tell(sub.ask(), np.ones(10))
    assert opt.nit == 0  # nothing was told


def test_minimize_and_evaluate_reject():
    with pytest.raises(InputError, match="neighbours needs parts=True"):
        minimize_ce(_sphere, [1.0, 2.0, 3.0], neighbours=np.eye(3, dtype=bool))
    with pytest.raises(InputError, match=r"with parts=True the objective must return"):
        minimize_ce(_sphere, [1.0, 2.0, 3.0], parts=True)
    with pytest.raises(InputError, match="n_jobs must be a non-zero integer, got 0"):
        evaluate(_sphere, np.ones((4, 3)), n_jobs=0)
    with pytest.raises(InputError, match="chunk_size must be an integer >= 1, got 0"):
        evaluate(_sphere, np.ones((4, 3)), chunk_size=0)
    with pytest.raises(InputError, match=r"X must have shape \(population, n_params\)"):
        evaluate(_sphere, np.ones(3))
    with pytest.raises(InputError, match="must return a float"):
        evaluate(lambda x: np.ones((2, 2)), np.ones((4, 3)))
    with pytest.raises(InputError, match="values of different shapes"):
        evaluate(lambda x: np.ones(int(x[0])), np.array([[1.0], [2.0]]))
    with pytest.raises(InputError, match="seed must be None, an integer"):
        CrossEntropy([1.0], seed="abc")
    with pytest.raises(InputError, match="returned 3 values for 4 trials"):
        evaluate(lambda X: np.ones(3), np.ones((4, 3)), vectorized=True)
