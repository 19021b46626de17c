"""Drift of the realistic site (bwim.synthetic.thermal and its use by make_site_days): a
deck-temperature-driven strain factor that differs between the calibration date and the
traffic date, with the within-day range of the real installation (issue 20: the
calibration runs' factor rose steadily from 0.86 at 09:28 to 1.13 at 15:52, a half-range
of about 13 %; the traffic date two days later ran a few per cent below it at the same
clock time).
"""

import csv
import datetime as dt

import numpy as np
import pytest

from bwim.synthetic import make_test_day
from bwim.synthetic.testday import WIM_GRADE_ROUGHNESS
from bwim.synthetic.thermal import DAY_SECONDS, DeckTemperature, ThermalDrift, draw_days

H = 3600.0
FS = 512.0
PRE = 154
WORK = np.linspace(9 * H, 16 * H, 421)  # the working window of the real site's days


@pytest.fixture(scope="module")
def cal_site(tmp_path_factory):
    """12 calibration runs on smooth roads, no traffic, with the temperature channel."""
    return make_test_day(tmp_path_factory.mktemp("drift") / "site", site="short-span-4-lane",
                         seed=4, n_calibration=12, n_traffic=0, n_calibration_day_traffic=0,
                         mesh=0.6, roughness=WIM_GRADE_ROUGHNESS, temperature_channel=True)


def test_deck_temperature_two_half_cosines_closed_form():
    """Minimum at t_min, maximum (minimum + amplitude) at t_max, half-way at the middle
    of the rise and of the fall (the cosine's zero), zero slope at both extremes and
    continuous across midnight (wraps with 24 h)."""
    temp = DeckTemperature(t_min=6 * H, t_max=16 * H, minimum=10.0, amplitude=16.0)
    assert temp.at(6 * H) == pytest.approx(10.0, abs=1e-12)
    assert temp.at(16 * H) == pytest.approx(26.0, abs=1e-12)
    assert temp.at(11 * H) == pytest.approx(18.0, abs=1e-12)
    assert temp.at(16 * H + 7 * H) == pytest.approx(18.0, abs=1e-12)  # 14 h fall, half
    for t in (6 * H, 16 * H):
        slope = (temp.at(t + 1.0) - temp.at(t - 1.0)) / 2.0
        assert abs(slope) < 1e-6
    assert temp.at(6 * H - 1e-6 + DAY_SECONDS) == pytest.approx(temp.at(6 * H), abs=1e-9)
    rise = temp.at(np.linspace(6 * H, 16 * H, 200))
    assert np.all(np.diff(rise) > 0)


def test_factor_is_linear_in_temperature_plus_a_small_sinusoid():
    """f = 1 + k (T − T_ref) + a sin(2π t / P + φ), by hand at three times."""
    temp = DeckTemperature(t_min=6 * H, t_max=16 * H, minimum=10.0, amplitude=16.0)
    drift = ThermalDrift(temperature=temp, coefficient=0.018, t_ref=20.0, nonthermal=0.005,
                         period=5 * H, phase=0.3)
    for t in (7 * H, 12.5 * H, 15 * H):
        expect = (1 + 0.018 * (temp.at(t) - 20.0)
                  + 0.005 * np.sin(2 * np.pi * t / (5 * H) + 0.3))
        assert drift.factor(t) == pytest.approx(expect, rel=1e-14)


def test_drawn_days_have_the_real_sites_drift():
    """Over 500 seeds (the draws only), the facts of issue 20's real site:
    the calibration runs' factor rose from 0.86 at 09:28 to 1.13 at 15:52 (× 1.314),
    steadily; on the traffic date, against the calibration runs' mean, it was −15 % at
    09:45 and +9 % at 15:34, a few per cent below the calibration date at the same clock
    (−2.2 and −2.7 points).  Measured on the draws: the ratio 1.245–1.416 (median 1.329);
    the last hour's rise over the first's ≥ 0.58 (median 0.96); the two dates' factors at
    the same clock differ by a median of 3.2 % over 09:00–16:00 (0.3–6.8 % by day, never
    more than 7.9 %); the traffic date at 09:45 −18.4 … −8.3 % and at 15:34 +7.3 … +18.4 %
    (5–95 %).  The draws before (a day shifted by 0.75–1.25 h, a smaller swing, an
    earlier maximum) fail the ratio's, the steadiness's and the same clock's checks: a
    median ratio of 1.245, a median last-to-first hour of 0.46 and dates a median of
    8.3 % apart."""
    runs = np.linspace((9 + 28 / 60) * H, (15 + 52 / 60) * H, 12)
    t_am, t_pm = 9.75 * H, (15 + 34 / 60) * H
    ratio, steady, gaps, am, pm = [], [], [], [], []
    for seed in range(500):
        cal, traffic = draw_days(np.random.default_rng(seed))
        ratio.append(cal.factor(runs[-1]) / cal.factor(runs[0]))
        steady.append((cal.factor(runs[-1]) - cal.factor(runs[-1] - H))
                      / (cal.factor(runs[0] + H) - cal.factor(runs[0])))
        gaps.append(np.median(np.abs(traffic.factor(WORK) / cal.factor(WORK) - 1)))
        mean = cal.factor(runs).mean()
        am.append(traffic.factor(t_am) / mean - 1)
        pm.append(traffic.factor(t_pm) / mean - 1)
    ratio, steady, gaps = np.array(ratio), np.array(steady), np.array(gaps)
    assert 1.22 <= ratio.min() and ratio.max() <= 1.44
    assert abs(np.median(ratio) - 1.314) < 0.03
    assert steady.min() >= 0.5 and np.median(steady) >= 0.85
    assert 0.02 <= np.median(gaps) <= 0.045 and gaps.max() <= 0.075
    # the real traffic date lies inside the draws' 5–95 % at both times
    assert np.percentile(am, 5) < -0.15 < np.percentile(am, 95)
    assert np.percentile(pm, 5) < 0.09 < np.percentile(pm, 95)


def test_events_carry_the_drift_of_their_date_and_clock_time(cal_site):
    """truth.csv's strain factor and temperature are the date's drift and deck
    temperature at the trigger's gauge-line clock time (to the 6 and 3 decimals
    written); the calibration runs rise steadily (each later run's factor higher, the
    non-thermal term being small)."""
    d = cal_site
    with open(d.truth, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["trigger"] == "true"]
    assert len(rows) == 12
    factors = []
    for r in rows:
        t = dt.datetime.fromisoformat(r["time"])
        day = 0 if t.date() == d.calibration_date else 1
        clock = (t - dt.datetime.combine(t.date(), dt.time())).total_seconds()
        assert float(r["strain_factor"]) == pytest.approx(
            float(d.drift[day].factor(clock)), abs=1e-6)
        assert float(r["temperature_C"]) == pytest.approx(
            float(d.drift[day].temperature.at(clock)), abs=1e-3)
        factors.append(float(r["strain_factor"]))
    assert np.all(np.diff(factors) > 0)


def test_temperature_channel_reads_the_deck_temperature_with_its_noise(cal_site):
    """The temp_C column (last) has the truth's deck temperature as its mean (within 4
    standard errors of σ = 0.1 °C) and a standard deviation of 0.1 °C (within 4 standard
    errors, 1 / sqrt(2 (n − 1)) relative)."""
    d = cal_site
    with open(d.truth, newline="") as f:
        temp = {r["record"]: float(r["temperature_C"]) for r in csv.DictReader(f)}
    for path in d.calibration:
        col = np.loadtxt(path)[:, -1]
        n = col.size
        assert abs(col.mean() - temp[path.name]) < 4 * 0.1 / np.sqrt(n) + 0.005  # 2 decimals
        assert abs(col.std(ddof=1) / 0.1 - 1) < 4 / np.sqrt(2 * (n - 1))


def test_the_factor_scales_every_strain_and_only_strain(cal_site, tmp_path):
    """Algebra of the drift (same model, same seed, so the same noise and dynamics): the
    site with ``drift=False`` has factor 1, and the drifting site's gauges differ from it
    by exactly (f − 1) × gain × strain; the drift-free record less that strain is noise,
    offset and a linear baseline of the requested σ (within 3 standard errors: a factor
    off by 3 % would leave 3 % of the signal in it).  The detectors change only by their
    global part: for the lane-3 pair, whose line (x = 3 m, y = 10.64 m) is gauge s10's
    point, Δad / gain_ad = −global_share × Δs10 / gain_s10 (to the 3 decimals written)."""
    d = cal_site
    flat = make_test_day(tmp_path / "flat", site="short-span-4-lane", seed=4,
                         n_calibration=12, n_traffic=0, n_calibration_day_traffic=0,
                         mesh=0.6, roughness=WIM_GRADE_ROUGHNESS, temperature_channel=True,
                         drift=False)
    assert all(e.strain_factor == 1.0 for e in flat.events)
    gains = np.array(d.gauge_gains) / 1e-6
    share = d.layout.detector_response.global_share
    k = [x.name for x in d.layout.detectors]
    g3, g4 = (d.detector_gains[k.index(n)] for n in ("ad3", "ad4"))
    res = []
    for path_a, path_b, e in zip(flat.calibration, d.calibration, d.events, strict=True):
        a, b = np.loadtxt(path_a), np.loadtxt(path_b)
        np.testing.assert_array_equal(a[:, [0, 17, 18, 19]], b[:, [0, 17, 18, 19]])
        f = e.strain_factor
        if abs(f - 1) < 0.02:  # the 3 written decimals, divided by f − 1, would show
            continue
        clean = (b[:, 3:15] - a[:, 3:15]) / (f - 1) / gains
        assert np.abs(clean).max() > 20 * d.noise_sigma
        ds10 = (b[:, 12] - a[:, 12]) / d.gauge_gains[9]
        for col, gain in ((15, g3), (16, g4)):
            np.testing.assert_allclose((b[:, col] - a[:, col]) / gain, -share * ds10,
                                       atol=2e-3 / gain + 2e-3 * share / d.gauge_gains[9])
        rest = a[:, 3:15] / gains - clean
        t = np.arange(rest.shape[0])
        coef = np.polynomial.polynomial.polyfit(t, rest, 1)
        res.append(rest - np.polynomial.polynomial.polyval(t, coef).T)
    n_runs = len(res)
    assert n_runs >= 8
    res = np.vstack(res)
    n_dof = res.size - 2 * 12 * n_runs
    rms = np.sqrt(np.sum(res**2) / n_dof)
    assert abs(rms / d.noise_sigma - 1) < 3 / np.sqrt(2 * n_dof)
