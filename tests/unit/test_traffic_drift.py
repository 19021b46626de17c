"""The traffic's own drift correction (bwim.site.drift.traffic_drift, issue 20 item 4b) on
rows made by the test: the reference class's steering axles carry a known strain-to-load
factor that differs between the calibration date and the traffic date.

Reference: the factor curves the test draws (closed form): the calibration date's factor
``1 + 0.12 sin(...)`` known to the runs' time-of-day trend, the traffic date's a curve of
another phase and size.  The steering loads are right-skewed (lognormal) and each is
weighed with 5 % noise, as a truck's own dynamics scatter it.
"""

import datetime as dt

import numpy as np
import pytest

from bwim.site.drift import (
    DriftSetup,
    TimeOfDayDrift,
    apply_traffic_drift,
    seconds_of_day,
    traffic_drift,
)
from bwim.summary import SummaryRow
from bwim.wim import ScaleTrend

CAL_DATE, DAY = dt.date(2026, 4, 1), dt.date(2026, 4, 3)
H = 3600.0


def cal_factor(t):
    return 1.0 + 0.12 * np.sin((t / H - 9.0) / 7.0 * np.pi - np.pi / 2)


def day_factor(t):
    return 0.97 + 0.09 * np.sin((t / H - 8.0) / 9.0 * np.pi - np.pi / 2)


def _rows(date, factor, n, rng, start=0):
    """``n`` reference trucks (class 113) over 06:00-20:00 of ``date``, weighed with the
    calibration day's time-of-day factor (what the per-event weighing applies)."""
    t = np.sort(rng.uniform(6 * H, 20 * H, n))
    steer = 52e3 * rng.lognormal(0.0, 0.08, n)  # right-skewed loads, N
    rows, truth = [], []
    for k in range(n):
        applied = float(cal_factor(t[k]))
        weighed = steer[k] * factor(t[k]) * (1 + 0.05 * rng.standard_normal()) / applied
        axles = (weighed, 100e3 / applied, 80e3 / applied, 80e3 / applied, 80e3 / applied)
        rows.append(SummaryRow(
            record=f"e{start + k}", time=dt.datetime.combine(date, dt.time())
            + dt.timedelta(seconds=float(t[k])), lane=1, vehicle_class="113", n_axles=5,
            axle_spacings=(3.6, 6.0, 1.3, 1.3), axle_weights=axles, gvw=sum(axles),
            drift_factor=applied, drift_method="time_of_day"))
        truth.append(steer[k])
    return rows, np.array(truth)


@pytest.fixture(scope="module")
def batch():
    rng = np.random.default_rng(7)
    knots = np.linspace(9 * H, 16 * H, 12)
    tod = TimeOfDayDrift(trend=ScaleTrend.fit(knots, cal_factor(knots), bandwidth=0.0),
                         dates=(CAL_DATE,))
    cal_rows, cal_truth = _rows(CAL_DATE, cal_factor, 400, rng)
    day_rows, day_truth = _rows(DAY, day_factor, 400, rng, start=400)
    return tod, cal_rows + day_rows, np.concatenate([cal_truth, day_truth])


def test_the_traffic_dates_factor_is_recovered(batch):
    """The traffic date's factor from its own reference trucks: RMS error over the day
    within 2.5 % and within 4 % everywhere between 08:00 and 18:00 (the ends, thinner,
    wander more), the steering axles unbiased within 1.5 %.  Measured over rng seeds 7, 1,
    2, 3: RMS 1.7, 1.5, 0.8, 1.9 %; largest 2.7, 2.2, 1.3, 3.3 %; steering bias −0.5,
    −1.4, +0.4, +1.3 % (400 trucks a day of 9 % scatter: a local mean over an hour holds
    about 30 of them, ±1.7 %).  Without the correction the factor is off by up to 15 %."""
    tod, rows, truth = batch
    fit = traffic_drift(rows, DriftSetup(method="traffic"), calibration=tod,
                        calibration_span=tod.trend.span)
    assert fit is not None and fit.reference_class == "113"
    assert fit.nominal_source == "calibration day traffic"
    out = apply_traffic_drift(rows, fit)
    day = [(r, s) for r, s in zip(out, truth, strict=True) if r.time.date() == DAY]
    t = np.array([seconds_of_day(r.time) for r, _ in day])
    err = np.array([r.drift_factor for r, _ in day]) / day_factor(t) - 1
    assert np.sqrt(np.mean(err**2)) < 0.025
    assert np.max(np.abs(err[(t > 8 * H) & (t < 18 * H)])) < 0.04
    steer = np.array([r.axle_weights[0] / s for r, s in day])
    assert abs(np.mean(steer) - 1) < 0.015
    assert all(r.drift_method == "traffic" for r, _ in day)


def test_a_thin_date_keeps_its_factor_and_is_flagged(batch):
    tod, rows, _ = batch
    thin = [r for r in rows if r.time.date() == CAL_DATE] + [
        r for r in rows if r.time.date() == DAY][:5]
    fit = traffic_drift(thin, DriftSetup(method="traffic"), calibration=tod,
                        calibration_span=tod.trend.span)
    out = apply_traffic_drift(thin, fit)
    late = [r for r in out if r.time.date() == DAY]
    assert all("drift_traffic_thin" in r.flags and r.drift_method == "time_of_day"
               for r in late)


def test_fifteen_trucks_alone_track_a_day_unlike_the_calibration_day():
    """A thin traffic date as on the real installation: 15 trucks alone, no traffic of the
    calibration date, the steering axle's nominal load given (``reference_load``) and
    ``min_reference`` lowered to 8.  On a date whose factor runs 10 % below the curve the
    test draws for it, the calibration day's time of day is off by 13-15 % RMS at the
    trucks, the traffic method by 3.6-4.8 % (measured over rng seeds 7, 1, 2, 3, 4, 5;
    15 steering axles of 9 % scatter give about ± 2.3 % on a mean).  A nominal load 5 %
    high scales every factor by 1 / 1.05 exactly (the trend is linear in the ratios)."""
    rng = np.random.default_rng(7)
    rows, _ = _rows(DAY, lambda t: 0.9 * day_factor(t), 400, rng, start=400)
    sub = [rows[k] for k in np.sort(rng.choice(400, 15, replace=False))]
    t = np.array([seconds_of_day(r.time) for r in sub])
    true = 0.9 * day_factor(t)
    nominal = 52e3 * np.exp(0.08**2 / 2)  # the lognormal steering loads' mean

    def factors(load):
        fit = traffic_drift(sub, DriftSetup(method="traffic", reference_load=load,
                                            min_reference=8))
        assert fit is not None and fit.nominal_source == "scenario"
        out = apply_traffic_drift(sub, fit)
        assert all(r.drift_method == "traffic" for r in out)
        return np.array([r.drift_factor for r in out])

    rms = lambda f: float(np.sqrt(np.mean((f / true - 1) ** 2)))  # noqa: E731
    tod = np.array([r.drift_factor for r in sub])
    right = factors(nominal)
    assert rms(tod) > 0.12 and rms(right) < 0.05
    np.testing.assert_allclose(factors(1.05 * nominal), right / 1.05, rtol=1e-12)
