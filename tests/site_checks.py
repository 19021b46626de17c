"""Checks shared by the site-model tests."""

import csv
import dataclasses

from bwim.scenario import load_record
from bwim.site import weigh_event


def lane1_truck_error(day, scenario, site, model) -> float:
    """The traffic date's first lane-1 reference truck weighed by MFI with ``model``
    (taken as accepted: these models skip the self-check to save time): its GVW's error
    against the static weight in ``reference.csv`` (fraction); it must be weighed."""
    with open(day.reference, newline="") as f:
        ref = next(r for r in csv.DictReader(f) if r["lane"] == "1")
    ev = weigh_event(load_record(day.out_dir / "traffic" / ref["record"], scenario), site,
                     bridge=dataclasses.replace(model, accepted=True))
    assert ev.weighed, ev.reason
    return ev.gvw / (float(ref["gvw_kN"]) * 1e3) - 1
