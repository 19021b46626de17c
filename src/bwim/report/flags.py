"""The flag vocabulary in words: what each flag of a summary row means.

Contract
--------
* :data:`FLAG_TABLE` holds the rows of the flag tables of ``docs/flags.md``, in its
  order: ``(group, flags, meaning, what to look at)`` with ``group`` ``"hard"`` (the
  weights are not used, quality ``reject``), ``"soft"`` (kept, quality ``warning``) or
  ``"detection"`` (:mod:`bwim.detect`).  The text is the document's, without its
  Markdown back-quotes; a test checks that every row of the document is here word for
  word, so the document and the report cannot drift apart (a flag added to the document
  must be added here).
* :func:`explain` gives one flag's :class:`FlagMeaning` (a flag with a subject,
  ``gauge_fault:NAME``, the meaning of its stem ``gauge_fault``); a flag not in the
  vocabulary gets group ``"unknown"`` and a meaning that says so (a report never fails on one).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

__all__ = ["FLAG_GROUPS", "FLAG_TABLE", "FlagMeaning", "explain", "flag_meanings"]

#: What each group means for the weights.
FLAG_GROUPS = {
    "hard": "the weights are not used (quality reject; the row is refused)",
    "soft": "the weights are kept (quality warning)",
    "detection": "raised by the vehicle detection",
    "unknown": "not in bwim's vocabulary (docs/flags.md)",
}

#: The rows of docs/flags.md's tables: (group, flags, meaning, what to look at).
FLAG_TABLE: tuple[tuple[str, tuple[str, ...], str, str], ...] = (
    ("hard", ("undetermined",),
     "the weights are not determined by the data (a rank-deficient fit: e.g. two axles "
     "the record cannot tell apart)", "the axle detection; the record's length"),
    ("hard", ("negative_axle_weight", "negative_group_weight"),
     "an axle or axle group came out below zero",
     "a wrong axle position or speed; a second vehicle"),
    ("hard", ("axle_weight_high", "axle_weight_low"),
     "an axle above 250 kN or below 1 kN (bwim.plausibility.Limits)",
     "units of the calibration truck's loads; a faulty gauge"),
    ("hard", ("gvw_high", "gvw_low"),
     "a gross weight above 1000 kN or below 5 kN", "as above"),
    ("hard", ("residual_high",),
     "the fit of the measured strains is much worse than the calibration runs' fits (the "
     "misfit limit of the calibration)",
     "another vehicle on the bridge, a wrong passage, a faulty gauge"),
    ("hard", ("truncated_start", "truncated_end"),
     "an axle is already (still) on the lines' support at the record's first (last) "
     "sample: the record does not hold the whole crossing",
     "the logger's pre- and post-trigger"),
    ("hard", ("no_baseline",),
     "too few samples without an axle on the bridge to find the gauges' offsets",
     "the logger's pre-trigger"),
    ("hard", ("lateral_outlier",),
     "the vehicle's lateral position lies more than 3.5 robust standard deviations from "
     "its lane's traffic of the day (bwim.site.wander): its strain's centre is pulled by "
     "a vehicle beside it that no axle detector saw, or it drove out of its lane; the "
     "lines would weigh both as one",
     "the lane's spread printed by bwim weigh; another vehicle in the record"),
    ("hard", ("unconfirmed_gauge_fault",),
     "a gauge disagreed with the others in this vehicle (it was left out) but agrees "
     "in most of the vehicles weighed nearest it in time (bwim.site.unconfirmed): the "
     "gauge is healthy and another vehicle that no detector saw loaded it, whose strain "
     "the other gauges carry into the weights",
     "another vehicle in the record; gauge_health.csv for the gauge"),
    ("hard", ("group_off_path",),
     "one of the vehicle's axle groups lies off the wheel path of its other groups, "
     "further than 6 robust standard deviations of its lane's traffic of the day "
     "(bwim.site.wheelpath): an axle of a vehicle in the next lane was counted as this "
     "vehicle's, or a vehicle no detector saw drove beside some of its axles; the lines "
     "would weigh both as one",
     "the spread printed by bwim weigh; the group_laterals column; another vehicle in "
     "the record"),
    ("hard", ("split_across_records",),
     "the vehicle's first (last) axle follows (leads) the axles of a vehicle of its lane "
     "and direction in another record closer than two vehicles following each other can, "
     "2.4 m + 0.5 s × speed between axles (bwim.site.split): the logger closed one file "
     "between the axles of one vehicle (a truck and its drawbar trailer on a short span) "
     "or two files hold the same axles; each part looks whole, so neither is weighed",
     "the logger's post-trigger; the two records' clocks"),
    ("hard", ("negative_force",),
     "moving force identification: an identified axle force is tensile where it is "
     "weighed", "the model, the regularisation"),
    ("hard", ("open_at_start", "open_at_end"),
     "bwim weigh --continuous: the long recording begins (ends) within this event, or "
     "less than the trigger's merge gap before (after) it: the vehicle may go on beyond "
     "the recording (a tractor without its trailer), so its weights cannot be whole",
     "the recording's start and end; the long files before and after it"),
    ("hard", ("max_duration",),
     "bwim weigh --continuous: the trigger was closed at its max_duration with the "
     "signal still up (a queue on the span, or a step of the gauges' baseline): a vehicle "
     "may go on beyond the event",
     "the trigger's max_duration (docs/streams.md); the gauges' baseline in the long "
     "file"),
    ("soft", ("outside_calibration_time",),
     "the event's clock time lies outside the span of the calibration runs (with the "
     "traffic method, before the date's first reference vehicle or after its last): the "
     "drift correction there is the nearest measured one's, not a measured one", ""),
    ("soft", ("temperature_extrapolated",),
     "the event's deck temperature lies beyond the range of the calibration runs' "
     "temperatures by more than a quarter of that range: the temperature drift there is "
     "extrapolated", ""),
    ("soft", ("temperature_missing",),
     "the temperature drift was asked for but the event's temperature channel has no "
     "reading (every sample a gap): the time-of-day drift was used instead", ""),
    ("soft", ("no_clock",),
     "the event has no clock (none in its file name or columns) and its time column "
     "is not the clock time of day (it starts within a minute of 0 s, as a record time "
     "does, or beyond the day), so it "
     "cannot be placed in the day: the time-of-day drift correction "
     "was not applied, the calibration's mean factor was used", ""),
    ("soft", ("no_drift",),
     "a drift correction was asked for but none could be made for this vehicle: the "
     "calibration runs give no drift over the day (they have no clocks, or too few to fit "
     "one) and no temperature or traffic reference applied: the calibration's mean factor "
     "was used", ""),
    ("soft", ("drift_traffic_thin",),
     'the day-by-day drift from the traffic ([drift] method = "traffic") had too few '
     "weighed vehicles on this date to measure the day's factor: the calibration's factor "
     "was kept", ""),
    ("soft", ("lateral_extrapolated",),
     "the vehicle's lateral position lies outside the range the calibration runs "
     "covered: its lines are extrapolated", ""),
    ("soft", ("ill_conditioned",),
     "the fit's condition number is large (closely spaced axles): the individual axle "
     "weights are less certain than their sum", ""),
    ("soft", ("gauge_fault",),
     "a gauge was found faulty in this event and left out: the vehicle was weighed with "
     "the healthy gauges (also when it is weighed by MFI). Written gauge_fault:NAME, one "
     "per faulty gauge. Faulty: flat, clipped, silent, reversed, off in gain or drifting "
     "(the kinds of gauge fault below; bwim.site.health). When the healthy gauges are not "
     "more than half of "
     'them, the vehicle is refused ("too few healthy gauges"); with another vehicle on '
     "the span, a gauge that disagrees refuses the vehicle instead (its strain cannot be "
     "told from a faulty gauge)", ""),
    ("detection", ("multiple_presence",),
     "two vehicles were on the instrumented span at once: they are never weighed as "
     "one; two travelling the same way (or one beside gauge activity no detector saw) "
     "are each refused, while a vehicle with one of the other direction on the span is "
     "weighed and flagged (quality warning; the fit's residual check still refuses a "
     "weighing the other vehicle spoils; bwim.site.event)", ""),
    ("detection", ("axle_count_mismatch",),
     "the two axle detectors saw different numbers of axles", ""),
    ("detection", ("detector_fault",),
     "the pair's readings show that one of its axle detectors changed gain (their peaks "
     "more than a factor 2 off the learned gain ratio; bwim.detect.faults): the axles it "
     "still matches are not the vehicle's layout, and the vehicle is refused with both "
     "detectors named", ""),
    ("detection", ("detector_spike",),
     "isolated spikes (one or two samples far off their neighbours) were taken out of an "
     "axle detector's readings before the detection (its responses are much wider than a "
     "spike); the vehicle is weighed", ""),
    ("detection", ("no_axles",), "no axle was found in the record", ""),
    ("detection", ("single_axle",),
     'a "vehicle" of one axle (an isolated peak, or a vehicle split by a long gap): '
     "refused by the site chain", ""),
    ("detection", ("speed_out_of_range",),
     "the vehicle's fitted speed lies outside the detection's speed range: its axles are "
     "not trusted, and the vehicle is refused", ""),
    ("detection", ("speed_varies",),
     "the per-axle speeds of one vehicle differ by more than the tolerance", ""),
    ("detection", ("strain_only",),
     "found from the strain gauges alone (no axle detectors): lower confidence", ""),
    ("detection", ("truncated",),
     "the vehicle's time on the span starts before or ends after the record, or the "
     "gauges end the record away from where they started (it was cut with a vehicle on "
     "the bridge; after a quiet start, only an end on the side the crossing loaded the "
     "gauges counts: one on the other side is the gauges' baseline drifting): the "
     "vehicle is refused", ""),
    ("detection", ("unexplained_strain",),
     "strain activity outside the time on the span of every detected vehicle: e.g. a "
     "vehicle in a lane the axle detectors do not cover", ""),
)


@dataclass(frozen=True, kw_only=True)
class FlagMeaning:
    """One flag in words: its group (see :data:`FLAG_GROUPS`), meaning and what to check
    (``""`` when the document gives nothing)."""

    flag: str
    group: str
    meaning: str
    look_at: str = ""


def flag_meanings() -> dict[str, FlagMeaning]:
    """Every flag of :data:`FLAG_TABLE` by name (``"as above"`` resolved to the text of
    the row above)."""
    out: dict[str, FlagMeaning] = {}
    previous = ""
    for group, flags, meaning, look_at in FLAG_TABLE:
        look = previous if look_at == "as above" else look_at
        previous = look
        for f in flags:
            out[f] = FlagMeaning(flag=f, group=group, meaning=meaning, look_at=look)
    return out


def explain(flag: str) -> FlagMeaning:
    """The meaning of ``flag`` (group ``"unknown"`` for a flag outside the vocabulary)."""
    meanings = flag_meanings()
    known = meanings.get(flag)
    if known is not None:
        return known
    stem, _, name = flag.partition(":")  # a flag with a subject: gauge_fault:NAME
    if name and stem in meanings:
        return dataclasses.replace(meanings[stem], flag=flag)
    return FlagMeaning(flag=flag, group="unknown",
                       meaning="not a flag of bwim's vocabulary (docs/flags.md)")
