"""Checks shared by the site-model tests."""

import csv
import dataclasses

from bwim.scenario import load_record
from bwim.site import weigh_event


def lane1_truck_error(day, scenario, site, model) -> float:
    """The traffic date's first lane-1 reference truck weighed by MFI with ``model``
    (taken as accepted: these models skip the self-check to save time): its GVW's error
    against the static weight in ``reference.csv`` (fraction) times the drift the
    correction left in it (the event's true strain factor, truth.csv, over the factor
    applied): the model's error, not the drift method's (the traffic date's factor
    differs from the calibration date's at the same clock time); it must be weighed."""
    with open(day.reference, newline="") as f:
        ref = next(r for r in csv.DictReader(f) if r["lane"] == "1")
    ev = weigh_event(load_record(day.out_dir / "traffic" / ref["record"], scenario), site,
                     bridge=dataclasses.replace(model, accepted=True))
    assert ev.weighed, ev.reason
    return ev.gvw / (float(ref["gvw_kN"]) * 1e3 * drift_left(day, ref["record"], ev)) - 1


def drift_left(day, record: str, ev) -> float:
    """What the drift correction left in an event's weights: the event's true strain
    factor (truth.csv, its trigger row) over the factor applied (1 when none was)."""
    with open(day.truth, newline="") as f:
        true = next(float(r["strain_factor"]) for r in csv.DictReader(f)
                    if r["record"] == record and r["trigger"] == "true")
    return true / (ev.drift_factor or 1.0)
