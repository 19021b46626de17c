"""Axle detectors of the realistic site (bwim.synthetic, short-span-4-lane) show the
measured facts of the real installation (issue 20), read back from the written files.

Facts (issue 20, a real short-span slab): each axle's peak has a full width at half
maximum of 0.85–1.2 m (35–50 ms at 24 m/s); between axle groups the baseline dips to
−0.3…−0.6 of the largest peak; the steering axle's peak is 0.2–0.55 of the largest; a
lane's two detectors differ in amplitude by about 4×; tridem axles 1.3 m apart give merged
peaks with a shallow dip.  A detector also responds (weakly) to vehicles in other lanes.

One simulated site (12 calibration runs, 40 traffic events, 0.5 m data mesh) is measured
as an analyst would: the detector signals of the files, each less its pre-trigger median,
at the axle times of truth.csv (gauge-line time, speed, spacings, detector x).  Every
statistic is taken over events; the bounds are the facts' ranges.
"""

import csv
import datetime as dt
import tomllib
from collections import defaultdict

import numpy as np
import pytest

from bwim.synthetic import SHORT_SPAN_4_LANE, make_test_day
from bwim.synthetic.detector import DetectorResponse, local_response

FS = 512.0
PRE = 154
LAYOUT = SHORT_SPAN_4_LANE
GAUGE_LINE = 3.0


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    day = make_test_day(tmp_path_factory.mktemp("det") / "site", site="short-span-4-lane",
                        seed=5, n_calibration=12, n_traffic=40, n_calibration_day_traffic=0,
                        mesh=0.5)
    columns = tomllib.loads(day.scenario.read_text())["logger"]["columns"]
    rows = defaultdict(list)
    with open(day.truth, newline="") as f:
        for r in csv.DictReader(f):
            rows[r["record"]].append(r)
    events = {}
    for path in day.calibration + day.traffic:
        events[path.name] = (np.loadtxt(path), rows[path.name])
    return day, columns, events


def _spacings(r):
    return np.array([float(v) for v in r["axle_spacings_m"].split(";")])


def _signal(data, columns, name):
    s = data[:, columns.index(name)]
    return s - np.median(s[:PRE])


def _axle_samples(r, x_d):
    """Sample index of each axle of truth row ``r`` at a detector at x = x_d."""
    v = float(r["speed_m_s"])
    d = 1.0 if r["direction"] == "+x" else -1.0
    t_line = (dt.datetime.fromisoformat(r["time"])
              - dt.datetime.fromisoformat(r["event_start"])).total_seconds()
    offsets = np.concatenate([[0.0], np.cumsum(_spacings(r))])
    return np.round((t_line + d * (x_d - GAUGE_LINE) / v + offsets / v) * FS).astype(int)


def _peaks(s, idx, v):
    """Largest sample within ±0.3 m of each axle: values and indices."""
    w = max(int(0.3 / v * FS), 2)
    js = np.array([i - w + int(np.argmax(s[i - w:i + w + 1])) for i in idx])
    return s[js], js


def _fwhm(s, j, v):
    """Full width at half maximum (linear interpolation) of the peak at sample j, m."""
    half = s[j] / 2
    lo = j
    while s[lo] > half:
        lo -= 1
    hi = j
    while s[hi] > half:
        hi += 1
    left = lo + (half - s[lo]) / (s[lo + 1] - s[lo])
    right = hi - 1 + (s[hi - 1] - half) / (s[hi - 1] - s[hi])
    return (right - left) / FS * v


def _weighed(r):
    """Calibration runs and loaded 5- and 6-axle traffic (the trucks of the facts)."""
    return r["kind"] == "calibration" or (int(r["n_axles"]) in (5, 6)
                                          and float(r["loading"]) > 0.8)


def _single_in_detector_lanes(events):
    for name, (data, rows) in events.items():
        if len(rows) == 1 and int(rows[0]["lane"]) in LAYOUT.detector_lanes:
            yield name, data, rows[0]


def _measure(site):
    """Per event and detector of the vehicle's lane: steer ratio, FWHM of the isolated
    axles, dip between the axle groups, and the lane's amplitude ratio."""
    day, columns, events = site
    out = []
    for name, data, r in _single_in_detector_lanes(events):
        v = float(r["speed_m_s"])
        sp = _spacings(r)
        pair = LAYOUT.lane_detectors(int(r["lane"]))
        gains = [day.detector_gains[LAYOUT.detectors.index(d)] for d in pair]
        bigs = []
        for d, gain in zip(pair, gains, strict=True):
            s = _signal(data, columns, d.name)
            idx = _axle_samples(r, d.x)
            pk, js = _peaks(s, idx, v)
            big = pk.max()
            bigs.append(big)
            gap = int(np.argmax(sp))  # tractor | trailer (or the rigid's wheelbase)
            isolated = [k for k in range(pk.size)
                        if (k == 0 or sp[k - 1] > 2.5) and (k == sp.size or sp[k] > 2.5)]
            out.append({
                "record": name, "weighed": _weighed(r), "detector": d.name,
                "high_gain": gain == max(gains),
                "steer": pk[0] / big,
                "fwhm": [_fwhm(s, js[k], v) for k in isolated],
                "between": s[idx[gap]:idx[gap + 1]].min() / big,
                "tridem": _tridem(s, sp, pk, idx),
            })
        for m in out[-2:]:
            m["pair_ratio"] = max(bigs) / min(bigs)
    return out


def _tridem(s, sp, pk, idx):
    """(dip / smaller adjacent peak) for the pairs of a tridem's axles whose peaks both
    reach 0.2 of the event's largest (visible peaks), or []."""
    for k in range(sp.size - 1):
        if sp[k] < 2.0 and sp[k + 1] < 2.0:
            return [s[idx[k + a]:idx[k + a + 1]].min() / min(pk[k + a], pk[k + a + 1])
                    for a in (0, 1) if min(pk[k + a], pk[k + a + 1]) > 0.2 * pk.max()]
    return []


def test_local_response_is_the_gaussian_kernel_of_each_tyre_closed_form():
    """One wheel, one tyre: the local part is F / 1 kN × exp(−4 ln 2 (u / w)²) ×
    exp(−v² / 2σ²) (the model's closed form, by hand); its full width at half maximum
    along the lane is ``width``; a dual pair splits the force over two tyres 0.35 m apart
    about a wheel centre at the dual track 1.82 m / 2 from the centre line."""
    resp = DetectorResponse()
    u = np.linspace(-2.0, 2.0, 4001)
    x = u[:, None] + 1.5
    f = np.full((u.size, 1), 50e3)
    single = local_response(x, np.array([-1.0]), 5.2, f, ["single"], 1.5, 5.2 - 0.6, resp)
    y_w = 5.2 - 2.05 / 2
    expect = 50.0 * np.exp(-4 * np.log(2) * (u / resp.width) ** 2) * np.exp(
        -(y_w - 4.6) ** 2 / (2 * resp.lateral_sigma**2))
    np.testing.assert_allclose(single, expect, rtol=1e-12)
    above = u[single >= single.max() / 2]
    assert abs(above[-1] - above[0] - resp.width) < 2e-3
    dual = local_response(x, np.array([1.0]), 5.2, f, ["dual"], 1.5, 5.2, resp)
    centre = 5.2 + 1.82 / 2
    ky = np.mean([np.exp(-(centre + o - 5.2) ** 2 / (2 * resp.lateral_sigma**2))
                  for o in (-0.175, 0.175)])
    assert dual.max() == pytest.approx(50.0 * ky, rel=1e-12)


def _iqr_within(values, lo, hi):
    q25, q50, q75 = np.percentile(values, [25, 50, 75])
    return lo <= q25 and q75 <= hi and lo <= q50 <= hi


def test_axle_peaks_are_about_a_metre_wide(site):
    """Facts: FWHM 0.85–1.2 m (35–50 ms at 24 m/s).  On the more sensitive detector of
    the vehicle's lane (the other is 3–5× less sensitive: noise widens its small peaks),
    every axle with no other axle within 2.5 m (steering axles, single drive axles): the
    median and the middle half of the widths lie in the facts' range (measured on this
    site: median 0.98 m, quartiles 0.91 and 1.07 m)."""
    widths = [w for m in _measure(site) if m["high_gain"] for w in m["fwhm"]]
    assert len(widths) > 40
    assert _iqr_within(widths, 0.85, 1.2)


def test_baseline_dips_between_axle_groups(site):
    """Fact: between axle groups the baseline dips to −0.3…−0.6 of the largest peak (the
    slab's global bending).  Between the tractor and the trailer (the largest spacing) of
    the calibration runs and loaded 5-/6-axle trucks: every dip is below zero, and the
    median and the middle half of the dips lie in the facts' range (measured: median
    −0.46, quartiles −0.52 and −0.41, 2 % shallower than −0.3 and 20 % deeper than −0.6;
    with the global share of 0.7 of stop 34: median −0.34, quartiles −0.39 and −0.30,
    the shallow end; docs/realistic_site.md)."""
    dips = np.array([m["between"] for m in _measure(site) if m["weighed"]])
    assert len(dips) > 20
    assert max(dips) < 0
    assert _iqr_within(dips, -0.6, -0.3)


def test_steering_axle_peak_is_small(site):
    """Fact: the steering axle's peak is 0.2–0.55 of the largest (calibration truck and
    loaded 5-/6-axle trucks; empty trucks have relatively heavier steering axles): the
    median and the middle half of the ratios lie in that range (measured: median 0.37,
    quartiles 0.31 and 0.46)."""
    ratios = [m["steer"] for m in _measure(site) if m["weighed"]]
    assert _iqr_within(ratios, 0.2, 0.55)


def test_a_lanes_two_detectors_differ_about_four_times(site):
    """Fact: the two detectors' amplitudes differ by about 4× (largest peaks of the
    calibration runs): median ratio within 3–5 (measured 4.4)."""
    ratios = [m["pair_ratio"] for m in _measure(site)
              if m["record"][0].isdigit() and m["high_gain"]]
    assert len(ratios) >= 6
    assert 3.0 <= np.median(ratios) <= 5.0


def test_tridem_peaks_merge_with_a_shallow_dip(site):
    """Fact: tridem axles 1.3 m apart give merged peaks with a shallow dip (a detector
    that needs separated peaks fails on them).  For adjacent tridem axles whose peaks are
    visible (both over 0.2 of the largest), the dip between them relative to the smaller
    peak: median between 0.5 (not separated at half maximum) and 0.9 (a dip), and at
    least two thirds of the pairs merged at half maximum (measured: median 0.79, 76 %)."""
    ratios = [q for m in _measure(site) if m["weighed"] for q in m["tridem"]]
    assert len(ratios) > 20
    assert 0.5 <= np.median(ratios) <= 0.9
    assert np.mean([q >= 0.5 for q in ratios]) >= 2 / 3


def test_detectors_respond_to_every_lane_weakly_to_far_ones(site):
    """Every detector reacts to a single vehicle in any lane: its signal averaged over
    0.1 s (51 samples, noise σ / √51) reaches 10 of those noise σ; and a lane's detectors
    react more to their own lane's vehicles than to the others' (median largest |signal|
    per unit gain at least 3× larger)."""
    day, columns, events = site
    sigma = LAYOUT.detector_response.noise / np.sqrt(51)
    own, other = defaultdict(list), defaultdict(list)
    for data, rows in events.values():
        if len(rows) != 1:
            continue
        lane = int(rows[0]["lane"])
        for k, d in enumerate(LAYOUT.detectors):
            smooth = np.convolve(_signal(data, columns, d.name), np.ones(51) / 51, "valid")
            assert np.abs(smooth).max() > 10 * sigma
            (own if d.lane == lane else other)[d.name].append(
                np.abs(smooth).max() / day.detector_gains[k])
    for d in LAYOUT.detectors:
        assert np.median(own[d.name]) > 3 * np.median(other[d.name])
