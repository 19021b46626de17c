"""Vehicles from two axle detectors a known distance apart.

Contract
--------
* Input: a :class:`~bwim.records.Record` with two axle-detector channels, named in the
  order traffic meets them, ``distance`` m apart, each giving a short pulse per axle (any
  sign, any offset or slow drift; the pulse shape need not be known).  Time in s.
* Each channel loses its baseline (running median over ``baseline_window`` s) and its
  axles are the peaks (:func:`scipy.signal.find_peaks`) higher than ``snr_threshold``
  robust noise standard deviations (1.4826 MAD of the high-passed channel; step / √12
  for a quantised channel sitting mostly on one level) and
  ``min_height`` × the channel's largest peak, rising at least half that above their
  neighbourhood (prominence), at least ``min_axle_spacing / max speed`` apart.  Each peak
  is timed to a fraction of a sample by the parabola through its top three samples.
* Matching: traffic does not overtake between the detectors, so an axle reaches the second
  detector ``distance / v`` after the first.  The lag (within ``speed_range``) that pairs
  the most peaks is taken, its pairs accepted, and the search repeated on the peaks left
  (a second vehicle at another speed).  Pairs are cut into vehicles where consecutive
  axles are more than ``max_axle_spacing`` apart or their lags differ.
* Speed: for each vehicle, the lag that maximises the cross-correlation of the two
  high-passed channels over the vehicle's axles, refined by a parabola through the three
  largest values: every sample of every pulse contributes, and detector gains need not
  agree.  ``speed = distance / lag``.
* Axle times at the first detector are the mean of the two detectors' peak times (the
  second shifted back by the lag); spacings = time differences × speed.  The passage's
  ``delay`` = first axle's time at the first detector − ``position / speed``, where
  ``position`` is the first detector's x in the influence-line frame (axle i is at
  ``x = speed (t − delay) − a_i``).
* An axle seen by one detector only is kept (a detector missing a light axle is likelier
  than a peak of pure noise above the threshold) and the vehicle flagged
  ``axle_count_mismatch``.

Confidence of a vehicle = ``c_snr × c_match × c_spacing × c_axles`` with
``c_snr = clip(snr / (2 snr_threshold), 0.5, 1)`` (snr: its weakest peak; half confidence
at the detection threshold, full at twice it), ``c_match`` = fraction of its axles seen by
both detectors, ``c_spacing = exp(−½ (d / 0.1 m)²)`` with d the RMS difference of the
spacings measured at each detector (0.1 m is the spacing accuracy aimed at), and
``c_axles = 0.5`` for a one-axle vehicle (1 otherwise).

With learned responses (``responses=``, :mod:`bwim.detect.pursuit`): spikes are first
taken out of the two channels (:func:`bwim.detect.signals.despike`) when the narrowest
response at the top speed is :data:`SPIKE_WIDTH` samples wide or more (the vehicles then
flagged ``detector_spike``); the pursuit's vehicles are flagged ``single_axle`` (one
axle), ``speed_out_of_range`` (a refined speed outside ``speed_range``) and, when the
pair's readings show a detector's gain changed (:func:`bwim.detect.faults.diagnose`; a
record a vehicle is cut in excepted), ``detector_fault``, naming both in
:attr:`~bwim.detect.result.Detection.fault`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.signal import find_peaks

from bwim.errors import InputError, require_finite, require_instance, require_positive
from bwim.records import Record

from .assemble import SectionReadings, VehicleEstimate, assemble_detection, checked_section
from .faults import diagnose
from .lateral import section_gauges
from .options import DetectOptions
from .presence import resolve_span
from .pursuit import pursue_axles
from .response import LearnedResponses
from .result import (
    FLAG_COUNT_MISMATCH,
    FLAG_DETECTOR_FAULT,
    FLAG_DETECTOR_SPIKE,
    FLAG_NO_AXLES,
    FLAG_SINGLE_AXLE,
    FLAG_SPEED_RANGE,
    FLAG_SPEED_VARIES,
    FLAG_TRUNCATED,
    Detection,
)
from .signals import (
    channel_data,
    despike,
    median,
    parabolic_vertex,
    remove_baseline,
    robust_sigma,
)

__all__ = ["SPIKE_WIDTH", "detect_axles"]

#: Learned detection takes spikes out of the detectors' readings when its narrowest
#: response, at the top of the speed range, is at least this many samples wide at half
#: height (a one- or two-sample spike is then no axle; bwim.detect.signals.despike).
SPIKE_WIDTH = 6.0
#: Detector matching tolerance: ± this many samples plus ``_TOL_REL`` × the lag.
_TOL_SAMPLES = 2.0
_TOL_REL = 0.01
#: Spacing accuracy aimed at, m (sets the spacing-agreement confidence factor).
_SPACING_SCALE = 0.1


def _noise(y: np.ndarray) -> float:
    """Robust noise standard deviation; for a quantised channel whose samples mostly sit
    on one level (MAD 0), the quantisation noise step / √12."""
    sig = robust_sigma(y)
    if sig > 0:
        return sig
    steps = np.abs(np.diff(y))
    steps = steps[steps > 0]
    return float(steps.min() / np.sqrt(12.0)) if steps.size else np.finfo(float).tiny


def _channel_peaks(y: np.ndarray, sigma: float, snr_threshold: float, min_height: float,
                   min_sep: int) -> dict[str, np.ndarray]:
    top = float(y.max()) if y.size else 0.0
    height = max(snr_threshold * sigma, min_height * top)
    idx, props = find_peaks(y, height=height, prominence=0.5 * height, distance=min_sep,
                            width=0)
    return {"index": idx, "frac": parabolic_vertex(y, idx), "height": y[idx],
            "width": props["widths"] if idx.size else np.zeros(0)}


def _match(t1: np.ndarray, t2: np.ndarray, distance: float, lag_lo: float, lag_hi: float,
           dt: float, max_gap: float) -> list[tuple[int, int]]:
    """Pairs (i, j), sorted: peak i of the first detector is peak j of the second."""
    free1 = np.ones(t1.size, dtype=bool)
    free2 = np.ones(t2.size, dtype=bool)
    pairs: list[tuple[int, int]] = []
    slack = _TOL_SAMPLES * dt
    while free1.any() and free2.any():
        i1, j2 = np.flatnonzero(free1), np.flatnonzero(free2)
        D = t2[j2][None, :] - t1[i1][:, None]
        cand = D[(D >= lag_lo * (1 - _TOL_REL) - slack) & (D <= lag_hi * (1 + _TOL_REL) + slack)]
        best_score: tuple[int, float] = (0, 0.0)
        found: list[tuple[int, int]] = []
        for lag in cand:
            dev = np.abs(D - lag)
            col = dev.argmin(axis=1)
            dmin = dev[np.arange(i1.size), col]
            chosen: dict[int, tuple[float, int]] = {}
            for r in np.flatnonzero(dmin <= slack + _TOL_REL * lag):
                c = int(col[r])
                if c not in chosen or dmin[r] < chosen[c][0]:
                    chosen[c] = (float(dmin[r]), int(r))
            score = (len(chosen), -sum(d for d, _ in chosen.values()))
            if score > best_score:
                best_score = score
                found = sorted((int(i1[r]), int(j2[c])) for c, (_, r) in chosen.items())
        if not found:
            break
        if pairs and len(found) == 1:
            # a lone pair after the first round is a vehicle of its own or nothing: keep
            # it only if it is farther than an axle spacing from every axle matched so far
            i, j = found[0]
            done = np.array([a for a, _ in pairs])
            gap = np.abs(t1[done] - t1[i]).min() * distance / (t2[j] - t1[i])
            if gap <= max_gap:
                break
        pairs.extend(found)
        for a, b in found:
            free1[a] = False
            free2[b] = False
    return sorted(pairs)


def _xcorr_lag(y1: np.ndarray, y2: np.ndarray, a: int, b: int, lag0: float) -> float | None:
    """Sub-sample lag (samples) maximising Σ_{n=a}^{b-1} y1[n] y2[n + L] near ``lag0``;
    None if the maximum is not inside the searched lags."""
    n = y1.size
    L0 = round(lag0)
    lags = np.arange(L0 - 3, L0 + 4)
    r = np.full(lags.size, -np.inf)
    for k, L in enumerate(lags):
        lo, hi = max(a, -L), min(b, n - L)
        if hi - lo > 0:
            r[k] = y1[lo:hi] @ y2[lo + L:hi + L]
    k = int(np.argmax(r))
    if k == 0 or k == lags.size - 1 or not np.isfinite(r[k - 1:k + 2]).all():
        return None
    return float(lags[0] + parabolic_vertex(r, np.array([k]))[0])


def detect_axles(
    record: Record,
    detectors: Sequence[str] = ("ad1", "ad2"),
    distance: float = 3.0,
    *,
    position: float = 0.0,
    snr_threshold: float = 6.0,
    min_height: float = 0.05,
    baseline_window: float = 0.25,
    polarity: int | None = None,
    speed_tolerance: float = 0.02,
    responses: LearnedResponses | None = None,
    section: SectionReadings | None = None,
    **options: Any,
) -> Detection:
    """Vehicles (speed, axles, spacings, arrival, lateral position) from two axle detectors.

    Parameters
    ----------
    record : Record
        A measured or simulated record holding both detector channels.
    detectors : (str, str)
        Channel names of the detectors, in the order traffic meets them.
    distance : float
        Distance between the detectors, m.
    position : float
        x of the first detector in the influence-line frame, m: ``delay`` = time the first
        axle passes the first detector − ``position / speed``.
    snr_threshold : float
        A peak must exceed this many robust noise standard deviations.
    min_height : float
        ... and this fraction of the channel's largest peak (against ringing).
    baseline_window : float
        Running-median window of the baseline, s (several pulse widths).
    polarity : +1, −1 or None
        Sign of the detector pulses; None: the sign of the larger excursion.
    speed_tolerance : float
        Per-axle speeds of one vehicle differing by more (relative standard deviation)
        flag ``speed_varies``.
    responses : LearnedResponses, optional
        The detectors' responses learned from the calibration runs
        (:func:`bwim.detect.learn_responses`): axles are then found by sparse
        deconvolution (:mod:`bwim.detect.pursuit`), which resolves merged peaks and uses
        both detectors together (and, if the responses were learned with gauges, those
        gauges of the record for the span's bending); ``baseline_window`` and
        ``polarity`` do not apply.
    section : SectionReadings, optional
        The record's section gauges (those the options name) already read
        (:func:`bwim.detect.assemble.section_readings`: one read for every detector pair
        of a record); the same numbers as without.
    **options
        The keywords of :class:`~bwim.detect.options.DetectOptions`: ``speed_range``
        (bounds the lag between the detectors), ``min_axle_spacing`` (peaks closer than
        this at the highest speed merge), ``max_axle_spacing``, ``span`` (None: not
        checked), ``gauges``, ``lateral_threshold``, ``unexplained_fraction``.

    Returns
    -------
    Detection
        ``method="axle detectors"``; no vehicles (flag ``no_axles``, reason in
        ``message``) when no axle pair was found.  Confidence: see the module docstring.
    """
    require_instance("record", record, Record)
    opts = DetectOptions(**options)
    if isinstance(detectors, str) or len(detectors) != 2 or detectors[0] == detectors[1]:
        raise InputError(f"detectors must name two different channels, got {detectors!r}")
    names = [s.name for s in record.sensors]
    for d in detectors:
        if d not in names:
            raise InputError(f"detectors: no channel {d!r} in this record; channels: {names}")
    dist = require_positive("distance", distance)
    pos = require_finite("position", position)
    v_lo, v_hi = opts.speed_range
    snr_thr = require_positive("snr_threshold", snr_threshold)
    rel = require_finite("min_height", min_height)
    if not 0.0 <= rel < 1.0:
        raise InputError(f"min_height must lie in [0, 1), got {min_height!r}")
    min_sp, max_sp = opts.min_axle_spacing, opts.max_axle_spacing
    bw = require_positive("baseline_window", baseline_window)
    if polarity not in (None, 1, -1):
        raise InputError(f"polarity must be +1, -1 or None, got {polarity!r}")
    sp_tol = require_positive("speed_tolerance", speed_tolerance)
    span_x = resolve_span(opts.span)
    gauge_sens = section_gauges(record, opts.gauges, exclude=detectors)
    section = checked_section(section, record, [s.name for s in gauge_sens])

    if responses is not None:
        return _detect_learned(record, detectors, dist, responses, position=pos,
                               span=span_x, gauges=gauge_sens, opts=opts,
                               snr_threshold=snr_thr, min_height=rel, section=section)
    t = record.time
    fs = record.sampling_rate
    dt = 1.0 / fs
    n = t.size
    samples = np.arange(n, dtype=float)
    raw = record.channels(list(detectors)).data
    y = np.column_stack([remove_baseline(raw[:, c], round(bw * fs)) for c in range(2)])
    if polarity is None:
        both = y.sum(axis=1)
        polarity = 1 if both.max() >= -both.min() else -1
    y = polarity * y
    sig = np.array([_noise(y[:, c]) for c in range(2)])
    min_sep = max(1, int(np.floor(min_sp / v_hi * fs)))
    pk = [_channel_peaks(y[:, c], sig[c], snr_thr, rel, min_sep) for c in range(2)]
    times = [np.interp(p["frac"], samples, t) for p in pk]
    n1, n2 = times[0].size, times[1].size
    method = "axle detectors"
    if n1 == 0 or n2 == 0:
        if n1 == n2:
            msg = (f"no axle found: no peak above {snr_thr:g} noise standard deviations on "
                   f"{detectors[0]} or {detectors[1]}")
            return Detection(flags=(FLAG_NO_AXLES,), message=msg, method=method)
        seen, blind = (detectors[0], detectors[1]) if n1 else (detectors[1], detectors[0])
        msg = (f"{seen} saw {max(n1, n2)} axle(s) but {blind} none: no speed can be measured"
               f" (is {blind} working?)")
        return Detection(flags=(FLAG_COUNT_MISMATCH, FLAG_NO_AXLES), message=msg,
                         method=method)

    lag_lo, lag_hi = dist / v_hi, dist / v_lo
    pairs = _match(times[0], times[1], dist, lag_lo, lag_hi, dt, max_sp)
    if not pairs:
        msg = (f"{detectors[0]} saw {n1} and {detectors[1]} saw {n2} axle(s) but none "
               f"arrives {lag_lo:.3g}–{lag_hi:.3g} s later at {detectors[1]} (speed range "
               f"{v_lo:g}–{v_hi:g} m/s)")
        return Detection(flags=(FLAG_COUNT_MISMATCH, FLAG_NO_AXLES), message=msg,
                         method=method)
    i1 = np.array([p[0] for p in pairs])
    j2 = np.array([p[1] for p in pairs])
    lag = times[1][j2] - times[0][i1]
    tol = _TOL_SAMPLES * dt + _TOL_REL * lag
    v_pair = dist / lag
    gaps = np.diff(times[0][i1]) * 0.5 * (v_pair[1:] + v_pair[:-1])
    cut = (gaps > max_sp) | (np.abs(np.diff(lag)) > 2 * np.maximum(tol[1:], tol[:-1]))
    groups = np.split(np.arange(len(pairs)), np.flatnonzero(cut) + 1)

    # peaks seen by one detector only: to the vehicle whose axles they lie among
    extent = [(times[0][i1[g]].min(), times[0][i1[g]].max(), float(np.mean(lag[g])),
               float(np.mean(v_pair[g]))) for g in groups]
    extra: list[list[tuple[int, int]]] = [[] for _ in groups]
    orphans = 0
    for c, used in ((0, set(i1.tolist())), (1, set(j2.tolist()))):
        for k in range(times[c].size):
            if k in used:
                continue
            best, best_d = None, np.inf
            for g, (a, b, lg, vg) in enumerate(extent):
                tk = times[c][k] - (lg if c == 1 else 0.0)
                d = max(a - tk, tk - b, 0.0) * vg
                if d <= max_sp and d < best_d:
                    best, best_d = g, d
            if best is None:
                orphans += 1
            else:
                extra[best].append((c, k))

    vehicles: list[VehicleEstimate] = []
    for g, members in zip(groups, extra, strict=True):
        a_idx = pk[0]["index"][i1[g]]
        extra1 = [pk[0]["index"][k] for c, k in members if c == 0]
        all_idx = np.concatenate([a_idx, np.asarray(extra1, dtype=int)])
        margin = int(np.ceil(2.0 * max(pk[0]["width"][i1[g]].max(),
                                       pk[1]["width"][j2[g]].max()))) + 2
        lag_s = _xcorr_lag(y[:, 0], y[:, 1], max(0, int(all_idx.min()) - margin),
                           min(n, int(all_idx.max()) + margin + 1), float(np.mean(lag[g])) * fs)
        lag_v = float(np.mean(lag[g])) if lag_s is None else lag_s * dt
        speed = dist / lag_v
        rows = [(0.5 * (times[0][i] + times[1][j] - lag_v), times[0][i], times[1][j],
                 pk[0]["height"][i] / sig[0], pk[1]["height"][j] / sig[1],
                 pk[0]["height"][i], pk[1]["height"][j])
                for i, j in zip(i1[g], j2[g], strict=True)]
        n_matched = len(rows)
        for c, k in sorted(members, key=lambda m: times[m[0]][m[1]]):
            tk = times[c][k] - (lag_v if c == 1 else 0.0)
            if min(abs(tk - r[0]) for r in rows) < _TOL_SAMPLES * dt + _TOL_REL * lag_v:
                continue
            h = pk[c]["height"][k]
            rows.append((tk, times[0][k] if c == 0 else np.nan,
                         times[1][k] if c == 1 else np.nan,
                         h / sig[0] if c == 0 else np.nan, h / sig[1] if c == 1 else np.nan,
                         h if c == 0 else np.nan, h if c == 1 else np.nan))
        rows.sort(key=lambda r: r[0])
        arr = np.array(rows, dtype=float)
        t_axle = arr[:, 0]
        snr = float(np.nanmin(arr[:, 3:5]))
        amp = np.nanmean(arr[:, 5:7] / np.nanmax(arr[:, 5:7], axis=0), axis=1)
        flags: list[str] = []
        if len(rows) != n_matched:
            flags.append(FLAG_COUNT_MISMATCH)
        if len(rows) == 1:
            flags.append(FLAG_SINGLE_AXLE)
        spread = float(np.std(v_pair[g]) / speed) if g.size > 1 else 0.0
        if spread > sp_tol:
            flags.append(FLAG_SPEED_VARIES)
        both = np.isfinite(arr[:, 1]) & np.isfinite(arr[:, 2])
        if both.sum() >= 2:
            d12 = np.diff(arr[both, 1]) - np.diff(arr[both, 2])
            disagreement = float(np.sqrt(np.mean((d12 * speed) ** 2)))
            c_sp = float(np.exp(-0.5 * (disagreement / _SPACING_SCALE) ** 2))
        else:
            disagreement, c_sp = float("nan"), 1.0
        conf = (float(np.clip(snr / (2.0 * snr_thr), 0.5, 1.0)) * n_matched / len(rows)
                * c_sp * (0.5 if len(rows) == 1 else 1.0))
        vehicles.append(VehicleEstimate(
            times=t_axle, speed=speed, confidence=conf, flags=tuple(flags), amplitudes=amp,
            snr=snr, speed_spread=spread, spacing_disagreement=disagreement,
            detector_times=arr[:, 1:3]))
    return assemble_detection(
        record, vehicles, method=method, position=pos, span=span_x, gauges=gauge_sens,
        lateral_threshold=opts.lateral_threshold, unexplained_fraction=opts.unexplained_fraction,
        flags=(FLAG_COUNT_MISMATCH,) if orphans else (),
        notes=_count_note(detectors, n1, n2, orphans), section=section)


def _detect_learned(record: Record, detectors: Sequence[str], distance: float,
                    responses: LearnedResponses, *, position: float, span, gauges, opts,
                    snr_threshold: float, min_height: float,
                    section: SectionReadings | None = None) -> Detection:
    """:func:`detect_axles` with learned responses (matching pursuit)."""
    if not isinstance(responses, LearnedResponses):
        raise InputError(f"responses must be LearnedResponses, got {type(responses).__name__}")
    if tuple(detectors) != responses.channels:
        raise InputError(f"the responses were learned for {list(responses.channels)}, not "
                         f"{list(detectors)}")
    if abs(distance - responses.distance) > 1e-9 * distance:
        raise InputError(f"the responses were learned for detectors {responses.distance:g} m "
                         f"apart, not {distance:g} m")
    method = "learned responses"
    y = channel_data(record, detectors)
    # a spike cannot be an axle where the narrowest response at the top speed is wider
    # than SPIKE_WIDTH samples: take spikes out first (their energy would otherwise set
    # the vehicle's residual level, and with it every axle group's count)
    # Record.sampling_rate's number, 1 / the median step
    if record.time.size < 2:
        fs = 0.0
    else:
        fs = 1.0 / (median(np.diff(record.time)) if section is None else section.step)
    width = min(r.fwhm for r in responses.responses) / opts.speed_range[1] * fs
    spiked = False
    if width >= SPIKE_WIDTH:
        cleaned = despike(y)
        y, spiked = cleaned.values, cleaned.any
    g = None
    if responses.gauges:
        names = {s.name for s in record.sensors}
        missing = [n for n in responses.gauges if n not in names]
        if missing:
            raise InputError(f"the responses were learned with gauges {missing} that this "
                             "record does not have")
        g = channel_data(record, responses.gauges)
    estimates = pursue_axles(record.time, y, responses, speed_range=opts.speed_range,
                             min_axle_spacing=opts.min_axle_spacing,
                             max_axle_spacing=opts.max_axle_spacing,
                             snr_threshold=snr_threshold, min_height=max(min_height, 0.1),
                             gauges=g)
    diagnosis = diagnose(y, responses)
    fault = diagnosis.message
    if not estimates:
        return Detection(flags=(FLAG_NO_AXLES,), method=method, fault=fault,
                         message=f"no axle found: nothing on {detectors[0]} and "
                         f"{detectors[1]} fits their learned responses above "
                         f"{snr_threshold:g} noise standard deviations"
                         + (f"; {fault}" if fault else ""))
    lo, hi = opts.speed_range
    marked = []
    for e in estimates:  # what the pursuit's own tests do not see
        extra = [FLAG_SINGLE_AXLE] if len(e.times) == 1 else []
        if not lo <= e.speed <= hi:  # a refinement may leave the range
            extra.append(FLAG_SPEED_RANGE)
        if spiked:
            extra.append(FLAG_DETECTOR_SPIKE)
        marked.append(dataclasses.replace(e, flags=(*e.flags, *extra)) if extra else e)
    det = assemble_detection(
        record, marked, method=method, position=position, span=span, gauges=gauges,
        lateral_threshold=opts.lateral_threshold, unexplained_fraction=opts.unexplained_fraction,
        section=section)
    # axles found in both detectors' responses: only a gain change can still hide behind
    # them (a record cut with a vehicle on it has no level at rest to judge by)
    if diagnosis.kind != "gain" or any(FLAG_TRUNCATED in v.flags for v in det.vehicles):
        return det
    # one detector off in gain: the axles it still matches are not the vehicle's layout
    vehicles = tuple(dataclasses.replace(v, flags=(*v.flags, FLAG_DETECTOR_FAULT))
                     for v in det.vehicles)
    return dataclasses.replace(
        det, vehicles=vehicles, fault=fault,
        flags=tuple(sorted({*det.flags, FLAG_DETECTOR_FAULT})),
        message="; ".join(m for m in (det.message, fault) if m))


def _count_note(detectors: Sequence[str], n1: int, n2: int, orphans: int) -> list[str]:
    notes = []
    if n1 != n2:
        notes.append(f"{detectors[0]} saw {n1} axle(s), {detectors[1]} saw {n2}")
    if orphans:
        notes.append(f"{orphans} peak(s) seen by one detector far from any vehicle ignored")
    return notes
