"""Axle detection on wide detector responses: responses learned from a calibration
truck's runs, then sparse deconvolution (bwim.detect.response, bwim.detect.pursuit).

No inverse crime: the detectors here follow this suite's own model (tests/detect_data.py
``wide_pulse``: a local peak of about 1 m at half height seen through a lateral
sensitivity, less the span's bending, the steering axle seen at 0.45 of its load, gains
4x apart, offsets, drift, 1 % noise), which bwim never assumes: it learns a response
from the runs and detects traffic with it.  References: the simulated layouts and speeds.
"""

import numpy as np
import pytest

from bwim.detect import detect_axles
from bwim.detect.response import learn_responses
from bwim.errors import InputError

from tests.detect_data import CAL_LOADS, CAL_SPACINGS, DISTANCE, FS, wide_record

#: (spacings m, loads N) of traffic trucks: 2+1 rigid, 2+3 artic, 3+3 artic, 2-axle, 2+2
TRUCKS = (((3.6, 1.35), (60e3, 90e3, 90e3)),
          ((3.5, 6.5, 1.31, 1.31), (65e3, 110e3, 80e3, 80e3, 80e3)),
          ((3.2, 1.35, 5.9, 1.3, 1.3), (70e3, 95e3, 95e3, 75e3, 75e3, 75e3)),
          ((5.0,), (50e3, 90e3)),
          ((3.8, 5.5, 1.3), (60e3, 100e3, 70e3, 70e3)))


def _runs(n=8, seed=1, distance=DISTANCE):
    rng = np.random.default_rng(seed)
    runs, speeds = [], []
    for k in range(n):
        v, lat = rng.uniform(15, 25), rng.uniform(-0.3, 0.3)
        runs.append(wide_record([(v, CAL_SPACINGS, CAL_LOADS, 0.4, lat)],
                                duration=0.7 + (sum(CAL_SPACINGS) + 6) / v, seed=k))
        speeds.append(v)
    return runs, np.array(speeds)


@pytest.fixture(scope="module")
def learned():
    runs, speeds = _runs()
    return learn_responses(runs, ("ad1", "ad2"), DISTANCE, CAL_SPACINGS, loads=CAL_LOADS), speeds


def test_learned_responses_time_the_runs(learned):
    """Each run's speed within 0.1 % (measured ≤ 0.03 %) and first axle within 1 ms; the
    local responses peak at u = 0 and are about a metre wide (the model's 1.0 m half-height
    width, high-pass aside: measured 0.9-1.0 m); the steering axle is seen weakest (the
    model: 0.45 × its load's share, i.e. 0.26 of the drive axle)."""
    L, speeds = learned
    np.testing.assert_allclose(L.speeds, speeds, rtol=1e-3)
    np.testing.assert_allclose(L.first_axle_times, 0.4, atol=1e-3)
    for r in L.responses:
        assert r.k[np.argmin(np.abs(r.u))] == pytest.approx(1.0, abs=0.02)
        assert 0.7 < r.fwhm < 1.2
    f = L.amplitudes[:, 0] / L.amplitudes[:, 0].max()
    assert np.argmin(f) == 0 and f[0] < 0.4
    assert abs(L.distance_offset) < 0.03 and not any(L.reasons)


@pytest.mark.parametrize("k", range(10))
def test_traffic_axles_from_merged_peaks(learned, k):
    """Every axle count right (tandems and tridems 1.3 m apart merge into one wide peak),
    spacings within 0.1 m and speed within 0.5 % (the issue's targets; measured ≤ 2.2 cm
    and ≤ 0.38 %), at 12-28 m/s and ±0.4 m lateral wander."""
    L, _ = learned
    rng = np.random.default_rng(100 + k)
    spacings, loads = TRUCKS[k % len(TRUCKS)]
    v, lat = rng.uniform(12, 28), rng.uniform(-0.4, 0.4)
    rec = wide_record([(v, spacings, loads, 0.4, lat)], duration=0.7 + (sum(spacings) + 6) / v,
                      seed=200 + k)
    det = detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L)
    veh = det.single
    assert veh.n_axles == len(loads)
    np.testing.assert_allclose(veh.axle_spacings, spacings, atol=0.1)
    assert veh.speed == pytest.approx(v, rel=5e-3)
    assert veh.confidence > 0.9 and det.method == "learned responses"


def test_peak_detection_fails_where_pursuit_does_not(learned):
    """The reference point of the issue: a detector that needs separated peaks miscounts
    the merged tridem of a 2+3 artic; the learned responses do not."""
    L, _ = learned
    spacings, loads = TRUCKS[1]
    rec = wide_record([(22.0, spacings, loads, 0.4, 0.0)], duration=1.6, seed=7)
    peaks = detect_axles(rec, ("ad1", "ad2"), DISTANCE)
    assert peaks.n_vehicles != 1 or peaks.vehicles[0].n_axles != 5
    assert detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L).single.n_axles == 5


def test_two_vehicles_one_lane(learned):
    """A 2-axle truck 14 m behind an artic at the same speed: two vehicles, each right."""
    L, _ = learned
    (s1, l1), (s2, l2) = TRUCKS[1], TRUCKS[3]
    v = 20.0
    gap = (sum(s1) + 14.0) / v
    rec = wide_record([(v, s1, l1, 0.4, 0.0), (v, s2, l2, 0.4 + gap, 0.2)], duration=2.4,
                      seed=9)
    det = detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=L)
    assert [vh.n_axles for vh in det.vehicles] == [5, 2]


def test_a_wrong_detector_distance_is_refused():
    """Declared 2.5 m where the detectors are 3 m apart: the truck's known spacings say
    otherwise, and the message says by how much (measured 3.0 m)."""
    runs, _ = _runs(n=5)
    with pytest.raises(InputError, match=r"distance of 2\.5 m contradicts.*give 3\.0"):
        learn_responses(runs, ("ad1", "ad2"), 2.5, CAL_SPACINGS, loads=CAL_LOADS)


# --- the pieces of the fit (algebra: same-model data, references are plain least squares) --
def _gaussian_responses(gauges=()):
    """Two detectors with Gaussian responses of 1.2 m at half height (K(0) = 1), gains
    4 apart, levels 1: a LearnedResponses assembled by hand (not learned)."""
    from bwim.detect.response import DetectorResponse, LearnedResponses

    u = np.linspace(-1.5, 1.5, 61)
    k = np.exp(-4 * np.log(2) * (u / 1.2) ** 2)
    k[[0, -1]] = 0.0
    n_g = len(gauges)
    resp = tuple(DetectorResponse(channel=c, u=u, k=k, noise=1.0, misfit=1.0,
                                  bending=-0.2 * np.ones(n_g)) for c in ("ad1", "ad2"))
    return LearnedResponses(responses=resp, distance=DISTANCE, amplitudes=np.ones((2, 2)),
                            speeds=np.ones(2), first_axle_times=np.zeros(2),
                            residuals=np.zeros(2), reasons=("", ""), distance_offset=0.0,
                            nit=1, gauges=tuple(gauges), gain_ratio=0.25,
                            amplitude_spread=0.1)


def _same_model(taus, v, amps, n=700, seed=0):
    """Readings of the model itself: responses at ``taus`` (detector 1) and ``v``,
    amplitudes (n, 2) in reading units, a bending of 12 random-walk gauges read with
    weights −0.2, offsets; no noise."""
    from bwim.detect.vehicle_fit import make_problem

    t = np.arange(n) / FS
    learned = _gaussian_responses([f"g{j}" for j in range(12)])
    g = np.random.default_rng(seed).standard_normal((n, 12)).cumsum(axis=0)
    pb = make_problem(t, np.zeros((n, 2)), g, learned, v)
    y = np.column_stack([X @ amps[:, c] for c, X in enumerate(pb.atoms(taus, v))]) / pb.w
    y = y + (g - g.mean(axis=0)) @ np.full((12, 1), -0.2) + np.array([3.0, -1.0])
    return t, y, g, learned


def test_group_misfit_from_correlations():
    """The misfit a group hypothesis removes, from the readings' correlation with one
    response and the response's autocorrelation, equals least squares on the explicit
    shifted responses (np.linalg.lstsq), k = 1, 2, 3, both detectors."""
    from bwim.detect.groups import explained

    rng = np.random.default_rng(3)
    h = [np.exp(-0.5 * ((np.arange(31) - 15) / 5.0) ** 2), np.hanning(25)]
    z = [rng.standard_normal(200), rng.standard_normal(200)]
    corr = [np.correlate(z[c], h[c], mode="valid") for c in range(2)]
    auto = [np.concatenate([np.correlate(x, x, mode="full")[x.size - 1:], np.zeros(200)])
            for x in h]
    for hyp in (np.array([[40]]), np.array([[30, 52], [60, 70]]), np.array([[10, 33, 56]])):
        total, amps = explained(hyp, corr, auto)
        for j, row in enumerate(hyp):
            expect = 0.0
            for c in range(2):
                X = np.zeros((200, row.size))
                for i, m in enumerate(row):
                    X[m:m + h[c].size, i] = h[c]
                a, *_ = np.linalg.lstsq(X, z[c], rcond=None)
                np.testing.assert_allclose(amps[j, :, c], a, rtol=1e-8, atol=1e-10)
                expect += float(z[c] @ z[c] - np.sum((z[c] - X @ a) ** 2))
            assert total[j] == pytest.approx(expect, rel=1e-9)


def test_removal_costs_and_refinement():
    """Same-model readings (algebra): each axle's removal cost equals the misfit of an
    explicit refit without it, and the variable-projection Levenberg-Marquardt recovers
    the axle times (< 0.05 ms) and speed (< 1e-4) from a start 4 ms and 2 % off, with the
    rest (the bending of 12 gauges, offsets, drift) fitted."""
    from bwim.detect.vehicle_fit import make_problem, refine, solve

    v = 21.0
    taus = 0.3 + np.array([0.0, 3.6, 9.6, 10.9]) / v
    amps = np.array([[20.0, 5.5], [40.0, 9.0], [25.0, 7.0], [24.0, 5.0]])
    t, y, g, learned = _same_model(taus, v, amps)
    pb = make_problem(t, y, g, learned, v)
    rows = np.arange(t.size)
    res, _, a, costs = solve(pb, taus, v, rows, False)
    assert float(res @ res) < 1e-16 * float(np.sum(pb.y**2))
    np.testing.assert_allclose(a, amps, rtol=1e-6)
    for i in range(taus.size):
        r_i = solve(pb, np.delete(taus, i), v, rows, False)[0]
        assert costs[i] == pytest.approx(float(r_i @ r_i - res @ res), rel=1e-6)
    fit = refine(pb, taus + 0.004, 1.02 * v)
    np.testing.assert_allclose(fit.taus, taus, atol=5e-5)
    assert fit.v == pytest.approx(v, rel=1e-4)


def test_pursuit_counts_same_model_axles():
    """Same-model readings of a 2+3 artic with a tridem 1.3 m apart (algebra): the whole
    chain (pursuit, groups, refinement) finds the five axles and the speed."""
    from bwim.detect.pursuit import pursue_axles

    v = 23.0
    offs = np.array([0.0, 3.5, 9.5, 10.8, 12.1])
    amps = np.array([[15.0, 4.0], [40.0, 10.0], [22.0, 5.5], [22.0, 5.5], [22.0, 5.5]])
    t, y, g, learned = _same_model(0.3 + offs / v, v, amps, n=800)
    out = pursue_axles(t, y, learned, speed_range=(5.0, 40.0), min_axle_spacing=0.8,
                         max_axle_spacing=12.0, snr_threshold=6.0, min_height=0.1, gauges=g)
    assert len(out) == 1 and out[0].times.size == 5
    np.testing.assert_allclose((out[0].times - out[0].times[0]) * out[0].speed, offs,
                               atol=1e-3)
    assert out[0].speed == pytest.approx(v, rel=1e-4)


def test_learned_gauges_must_be_in_the_record():
    """Responses learned with gauges need them in the record: a one-line InputError."""
    learned = _gaussian_responses(["s01", "s02"])
    rec = wide_record([(20.0, (3.6,), (60e3, 90e3), 0.4, 0.0)], duration=1.0)
    with pytest.raises(InputError, match=r"learned with gauges \['s01', 's02'\]"):
        detect_axles(rec, ("ad1", "ad2"), DISTANCE, responses=learned)


def test_gauge_names_checked():
    """learn_responses' gauges: an unknown channel or an axle detector is refused."""
    runs, _ = _runs(n=3)
    with pytest.raises(InputError, match="no channel 'x1'"):
        learn_responses(runs, ("ad1", "ad2"), DISTANCE, CAL_SPACINGS, gauges=["x1"])
    with pytest.raises(InputError, match="is an axle detector"):
        learn_responses(runs, ("ad1", "ad2"), DISTANCE, CAL_SPACINGS, gauges=["ad1"])


def _segments_loop(pb, local, v, margin, st):
    """The axle groups' definition of :func:`bwim.detect.groups.segments` as a plain loop
    over neighbouring peaks and parts (its first, unvectorised form): the reference."""
    import itertools

    from scipy.signal import find_peaks

    from bwim.detect.groups import GROUP_DIP, GROUP_EXTENT, PEAK_FLOOR

    lag = round(pb.shift[1] / v * pb.fs)
    e = np.zeros(local[0].size)
    for c, r in enumerate(pb.grids):
        z = np.maximum(local[c] * np.sign(r[1][int(np.argmax(np.abs(r[1])))]), 0.0)
        top = float(z.max())
        if top > 0:
            shift = lag if c else 0
            e[:e.size - shift] += z[shift:] / top
    floor = PEAK_FLOOR * float(e.max())
    peaks, _ = find_peaks(e, height=floor, prominence=floor)
    cuts = [0]
    for a, b in itertools.pairwise(peaks):
        m = a + int(np.argmin(e[a:b + 1]))
        if e[m] < GROUP_DIP * min(e[a], e[b]):
            cuts.append(m)
    cuts.append(e.size - 1)
    out = []
    for a, b in itertools.pairwise(cuts):
        part = e[a:b + 1]
        above = np.flatnonzero(part >= GROUP_EXTENT * float(part.max()))
        out.append((max(a + int(above[0]) - margin, a) // st,
                    min(a + int(above[-1]) + margin, b) // st))
    return out


def test_segments_equal_their_loop_definition():
    """The vectorised axle groups (cuts at the dips between neighbouring peaks, extents
    where each part exceeds its share of its highest) equal the plain loop of their
    definition, on bumpy noise with plateaus and near-equal dips (exactly: same integers)."""
    from bwim.detect.groups import segments
    from bwim.detect.vehicle_fit import make_problem

    v = 21.0
    t, y, g, learned = _same_model(np.array([0.3]), v, np.array([[20.0, 5.0]]))
    pb = make_problem(t, y, g, learned, v)
    rng = np.random.default_rng(5)
    for trial in range(30):
        local = [np.convolve(rng.standard_normal(t.size), np.hanning(9), mode="same")
                 for _ in range(2)]
        if trial % 3 == 0:  # plateaus and repeated values
            local = [np.round(x, 1) for x in local]
        for st, margin in ((1, 0), (3, 5)):
            assert segments(pb, local, v, margin, st) == _segments_loop(pb, local, v,
                                                                        margin, st)


def test_a_window_shorter_than_the_detectors_lag_gives_the_first_detectors_groups():
    """A vehicle's window shorter than the lag between the detectors (in samples) holds
    nothing of the second detector's readings moved back by the lag: its groups are the
    first detector's alone (what the loop definition gives with the second's readings
    zero), where an error used to refuse the whole event."""
    from bwim.detect.groups import segments
    from bwim.detect.vehicle_fit import make_problem

    v = 21.0
    t, y, g, learned = _same_model(np.array([0.3]), v, np.array([[20.0, 5.0]]))
    pb = make_problem(t, y, g, learned, v)
    lag = round(pb.shift[1] / v * pb.fs)
    n = lag - 3
    bump = np.exp(-0.5 * ((np.arange(n) - n / 2) / 4.0) ** 2)
    local = [bump, bump[::-1].copy()]
    got = segments(pb, local, v, 2, 1)
    assert got == _segments_loop(pb, [bump, np.zeros(n)], v, 2, 1)
    assert len(got) == 1


def test_noise_segments_skipped_only_where_no_axle_fits():
    """choose_groups skips a segment without axles when no grid point of it passes a
    widened one-axle test made once over the window: every grid point where the exact
    test on a segment (its own correlation, amplitudes positive at both detectors, log
    gain ratio within the bound) passes is kept by the widened one; and it does skip."""
    from types import SimpleNamespace

    from bwim.detect.groups import GROUP_AXLES, GROUP_SPACING, one_axle_may_fit, templates
    from bwim.detect.vehicle_fit import make_problem

    v = 21.0
    t, y, g, learned = _same_model(np.array([0.3]), v, np.array([[20.0, 5.0]]))
    pb = make_problem(t, y, g, learned, v)
    tpl = templates(pb, v)
    st = 3
    s_max = int(np.floor(GROUP_SPACING / v * pb.fs / st))
    auto = [np.concatenate([r[::st], np.zeros(max(0, s_max * GROUP_AXLES - r[::st].size
                                                  + 1))]) for _, _, r in tpl]
    rng = np.random.default_rng(11)
    n_rows = 400
    n_grid = (n_rows - 1) // st + 1
    kept = skipped = 0
    for bound in (0.3, 1.1, 3.0):
        ref = SimpleNamespace(ratio=0.25, bound=bound)
        for _ in range(10):
            resid = rng.standard_normal((2, n_rows)) * np.array([[1.0], [0.25]])
            bare = one_axle_may_fit(ref, resid, tpl, auto, st, n_grid)
            maybe = np.diff(bare).astype(bool)
            # the exact test, on one segment per grid point
            for m in range(n_grid):
                b = []
                for c, (j0, h, _) in enumerate(tpl):
                    q = st * m + j0
                    b.append(float(resid[c][q:q + h.size] @ h)
                             if 0 <= q <= n_rows - h.size else 0.0)
                a = np.array(b) / np.array([auto[0][0], auto[1][0]])
                ok = bool(a[0] > 0 and a[1] > 0
                          and abs(np.log(a[1] / (ref.ratio * a[0]))) <= ref.bound)
                if ok:
                    assert maybe[m], (bound, m)
                    kept += 1
                skipped += int(not maybe[m])
    assert kept > 0 and skipped > 0


def test_refinement_keeps_its_last_least_squares():
    """Same-model readings (algebra): the least squares a refinement keeps
    (``VehicleFit.solution``) is the one at its result, byte for byte what a fresh
    solve there gives (amplitudes, removal costs, residual, Jacobian); ``solution``
    reuses a start only at the same times, speed and window (a start on other rows is
    made again), and a refinement from a reused start gives the numbers of one without."""
    from bwim.detect.vehicle_fit import Rows, Solution, make_problem, refine, solution, window

    v = 21.0
    taus = 0.3 + np.array([0.0, 3.6, 9.6, 10.9]) / v
    amps = np.array([[20.0, 5.5], [40.0, 9.0], [25.0, 7.0], [24.0, 5.0]])
    t, y, g, learned = _same_model(taus, v, amps)
    pb = make_problem(t, y, g, learned, v)
    start = taus + 0.004
    fit = refine(pb, start, 1.02 * v)
    kept = fit.solution
    assert np.array_equal(kept.taus, fit.taus) and kept.v == fit.v
    fresh = Solution(pb, fit.taus, fit.v, kept.w, True)
    for a, b in ((kept.res, fresh.res), (kept.amps, fresh.amps), (kept.gains, fresh.gains),
                 (kept.jacobian(), fresh.jacobian()), (fit.amps, fresh.amps)):
        assert a.tobytes() == b.tobytes()
    first = solution(pb, start, 1.02 * v)
    assert solution(pb, start, 1.02 * v, first) is first
    other = Solution(pb, start, 1.02 * v, Rows(pb, window(pb, start, v)), True)  # other rows
    assert not np.array_equal(other.w.rows, first.w.rows)
    assert solution(pb, start, 1.02 * v, other) is not other
    again = refine(pb, start, 1.02 * v, start=first)
    assert again.taus.tobytes() == fit.taus.tobytes() and again.chi == fit.chi


def test_pursuit_steps_are_least_squares_and_skip_taken_times():
    """The pursuit's steps (algebra on noisy readings of the model itself, 1 % noise):
    each trial's amplitudes and misfit equal explicit least squares (np.linalg.lstsq on
    the responses at the axles' times, the second detector's at its own, and the rest's
    columns, per detector: amplitudes within 1e-11 of the largest, measured 1.4e-12, the
    ridge of 1e-12; misfits within 2e-15, measured 2.7e-16); the matcher picks the argmax
    of the score written out sample by sample (Σ residual × atom at both detectors, the
    second's best within the slack, and where that best is), and never a time within the
    gap of one taken (exactly those excluded)."""
    from bwim.detect.pursuit import _Matcher, _Pursuit
    from bwim.detect.vehicle_fit import make_problem

    v = 21.0
    taus = np.array([0.30, 0.45, 0.52, 0.80])
    amps = np.array([[20.0, 5.0], [30.0, 8.0], [28.0, 7.5], [25.0, 6.0]])
    t, y, g, learned = _same_model(taus, v, amps)
    y = y + 0.01 * np.abs(amps).max() * np.random.default_rng(2).standard_normal(y.shape)
    pb = make_problem(t, y, g, learned, v)
    gap = 0.4
    slack = 6
    matcher = _Matcher(pb, v, slack, gap)
    omp = _Pursuit(pb, v, matcher.pad)
    n = t.size
    picked, picked2 = [], []
    for _ in range(4):
        # the matcher's choice against the score written out
        res = omp.res[:, matcher.pad:matcher.pad + n]
        corr = []
        for c, (m_lo, _, atom) in enumerate(matcher.parts):
            corr.append(np.array([sum(res[c, m + m_lo + i] * atom[i] for i in range(atom.size)
                                      if 0 <= m + m_lo + i < n) for m in range(n)]))
        c2 = np.array([corr[1][max(m - slack, 0):m + slack + 1].max() for m in range(n)])
        score = np.maximum(corr[0] + c2, 0.0) ** 2
        for tk in picked:
            score[np.abs(t - tk) < gap / v] = 0.0
        tk, tk2 = matcher.best(omp.res)
        m = int(np.argmax(score))
        assert tk == t[m] and all(abs(tk - p) >= gap / v for p in picked)
        a = max(m - slack, 0)  # the second detector's own best near it
        assert tk2 == t[a + int(np.argmax(corr[1][a:m + slack + 1]))]
        picked.append(tk)
        picked2.append(tk2)
        got, chi, state = omp.trial(tk, tk2)
        ref_chi, ref = 0.0, []
        for c in range(2):
            X = np.column_stack([pb.atoms(np.array(picked if c == 0 else picked2), v)[c],
                                 pb.rest[c]])
            coef = np.linalg.lstsq(X, pb.y[:, c], rcond=None)[0]
            ref_chi += float(np.sum((pb.y[:, c] - X @ coef) ** 2))
            ref.append(coef[:len(picked)])
        np.testing.assert_allclose(got, np.column_stack(ref), rtol=0,
                                   atol=1e-11 * np.abs(ref).max())
        assert chi == pytest.approx(ref_chi, rel=2e-15)
        matcher.exclude(tk)
        np.testing.assert_array_equal(matcher.excluded, np.any(
            np.abs(t[:, None] - np.array(picked)[None, :]) < gap / v, axis=1))
        omp.accept(tk, tk2, chi, state)
    # greedy picks on merged peaks: near the axles (measured ≤ 0.23 m of travel)
    assert np.abs(np.sort(picked) - taus).max() * v < 0.3


def test_the_smallest_spacing_is_sparrows_limit():
    """Reference: two equal Gaussian peaks of standard deviation σ, ``d`` apart, show a
    dip at their midpoint (a local minimum of their sum) exactly when d > 2σ, and
    FWHM = 2σ √(2 ln 2) (closed forms; the sum's second derivative at the midpoint is
    proportional to d² / 4 − σ²).  The pursuit's smallest spacing is that limit in
    widths: just beyond it the sum dips, just within it the sum is one peak."""
    from bwim.detect.pursuit import MIN_SPACING_WIDTH

    sigma = 0.5
    fwhm = 2.0 * sigma * np.sqrt(2.0 * np.log(2.0))
    x = np.linspace(-0.05, 0.05, 2001)  # about the midpoint, 50 µm steps

    def two(d):
        return np.exp(-(x - d / 2) ** 2 / (2 * sigma**2)) + np.exp(-(x + d / 2) ** 2
                                                                   / (2 * sigma**2))

    limit = MIN_SPACING_WIDTH * fwhm
    assert limit == pytest.approx(2.0 * sigma, rel=1e-12)
    below, above = two(limit * (1 - 1e-3)), two(limit * (1 + 1e-3))
    assert below.argmax() == x.size // 2  # one peak at the midpoint
    assert above.argmin() == x.size // 2  # a dip at the midpoint


def test_python_float_steps_are_numpy_s():
    """The per-axle tests the pursuit makes in Python floats give numpy's numbers: the
    log gain ratios (special values too: zero, negative, NaN and infinite amplitudes) and
    who is seen by both detectors, the shares below the smallest height, argmins (the
    first NaN, else the first smallest)."""
    import warnings

    from bwim.detect.pursuit import _argmin, _low, _weakest
    from bwim.detect.vehicle_fit import make_problem, relative

    v = 21.0
    taus = np.array([0.30, 0.45])
    t, y, g, learned = _same_model(taus, v, np.array([[20.0, 5.0], [30.0, 8.0]]))
    pb = make_problem(t, y, g, learned, v)
    rng = np.random.default_rng(5)
    special = np.array([0.0, -0.0, -3.0, np.nan, np.inf, 1e-310, 1e300])
    for n in (1, 2, 5, 9, 17):
        for _ in range(40):
            amps = rng.standard_normal((n, 2)) * 10.0 ** rng.integers(-3, 3, (n, 2))
            mask = rng.random((n, 2)) < 0.3
            amps[mask] = rng.choice(special, mask.sum())
            with warnings.catch_warnings():  # numpy's overflow in the quotient
                warnings.simplefilter("ignore", RuntimeWarning)
                ref = pb.log_ratio(amps)
                seen = pb.seen_by_both(amps)
                share = relative(amps)
                low = np.minimum(share[:, 0], share[:, 1]) < 0.3
            assert np.array(pb.log_ratios(amps)).tobytes() == ref.tobytes()
            assert pb.seen(amps) == seen.tolist()
            assert _low(amps, 0.3) == low.tolist()
            gains = amps[:, 0].copy()
            assert _argmin(gains.tolist()) == int(gains.argmin())
            weak = (amps[:, 1] > 0).tolist()
            assert _weakest(weak, gains.tolist()) == int(np.where(weak, gains, np.inf).argmin())


@pytest.mark.parametrize("gauges", [True, False])
def test_compiled_pursuit_is_the_steps_one_by_one(gauges):
    """The compiled pursuit (``_Pursuit.pursue``: its trials over the atoms' reach alone,
    the products with the readings kept) takes the axles the steps one by one take
    (``_Matcher.best``, ``_Pursuit.trial``, ``_Matcher.exclude``, ``_acceptable``,
    ``_Pursuit.accept``, written out as the pursuit ran them), byte for byte: times,
    strongest fall, misfit, residual; with and without gauges (the rest projected out or
    none); noisy readings, a height that turns some axles down."""
    from bwim.detect.pursuit import MAX_AXLES, PURSUIT_SHARE, _acceptable, _Matcher, _Pursuit
    from bwim.detect.vehicle_fit import make_problem

    v = 21.0
    taus = np.array([0.30, 0.45, 0.52, 0.80, 1.4])
    amps = np.array([[20.0, 5.0], [30.0, 8.0], [28.0, 7.5], [25.0, 6.0], [13.5, 3.6]])
    t, y, g, learned = _same_model(taus, v, amps)
    y = y + 0.02 * np.abs(amps).max() * np.random.default_rng(3).standard_normal(y.shape)
    pb = make_problem(t, y, g if gauges else None, learned, v)
    thr2, min_height = 4.0, 0.5  # the last axle (0.45 of the largest) turned down
    runs = []
    for compiled in (True, False):
        matcher = _Matcher(pb, v, 6, 0.4)
        omp = _Pursuit(pb, v, matcher.pad)
        if compiled:
            first = omp.pursue(matcher, thr2, min_height)
        else:
            first = 0.0
            for _ in range(2 * MAX_AXLES):
                tk, tk2 = matcher.best(omp.res)
                a, chi_new, state = omp.trial(tk, tk2)
                gain = omp.chi - chi_new
                first = max(first, gain)
                if gain < max(thr2, PURSUIT_SHARE * first) or omp.taus.size >= MAX_AXLES:
                    break
                matcher.exclude(tk)
                if not _acceptable(pb, a, min_height):
                    continue
                omp.accept(tk, tk2, chi_new, state)
        runs.append((omp.taus.tobytes(), omp.taus2.tobytes(), first, omp.chi,
                     omp.res.tobytes(), matcher.excluded.tobytes()))
    assert runs[0] == runs[1]
    assert len(runs[0][0]) >= 4 * 8


def test_compiled_searches_are_numpy_s():
    """``search_sorted`` is ``numpy.searchsorted`` (both sides, equal values, NaN last,
    keys beyond either end) and the grid atoms at ascending times (an axle's rows beyond
    its reach not evaluated) are those at the same times in any order, byte for byte."""
    from bwim.detect import fit_kernels as K

    rng = np.random.default_rng(9)
    t = np.sort(np.round(rng.uniform(0, 10, 60), 1))
    t[-3:] = np.nan
    for x in (*rng.uniform(-1, 11, 40), 0.0, 5.0, t[10], t[11], np.nan, np.inf):
        for right in (False, True):
            assert K.search_sorted(t, x, right) == t.searchsorted(x, "right" if right else "left")
    u = np.linspace(-1.5, 1.5, 61)
    k = np.exp(-4 * np.log(2) * (u / 1.1) ** 2)
    k[[0, 1, -2, -1]] = 0.0
    grids = [(u, k, None), (u, 2 * k, None)]
    steps = [np.append(np.diff(kk), 0.0) for _, kk, _ in grids]
    tab = K.grid_table(grids, steps, (0.0, 3.0), np.array([0.7, 2.5]))
    rows = np.arange(400) / 128.0
    dt = rows[:, None] - np.array([0.5, 1.1, 2.0])[None, :]  # ascending: reach only
    order = rng.permutation(400)  # the same times in no order: every one evaluated
    out, der = np.empty((2, 400, 3)), np.empty((2, 400, 3))
    out2, der2 = np.empty((2, 400, 3)), np.empty((2, 400, 3))
    K.grid_atoms(tab.scalars, tab.first, tab.values, 19.0, dt[None], out, der)
    K.grid_atoms(tab.scalars, tab.first, tab.values, 19.0, dt[order][None], out2, der2)
    assert out[:, order].tobytes() == out2.tobytes() and der[:, order].tobytes() == der2.tobytes()
    assert np.mean(out == 0.0) > 0.5
