"""Vehicle detection from the record itself: axle detectors, or the strain gauges alone.

A logger record has no passage; detection finds each vehicle's speed, axles, spacings,
arrival time and lateral position, and flags what it cannot vouch for (two vehicles on
the span at once, detectors that disagree, strain no detected vehicle explains).  It works
alike on simulated and measured records and needs no bridge model.

    det = detect_axles(record, ("ad1", "ad2"), 3.0, span=influence_line)
    det.single.passage                       # Passage(speed, lane, axle_spacings, delay)
    rec = det.annotate(record)               # the record with the detected passages
    resp = learn_responses(cal_runs, ("ad1", "ad2"), 3.0, truck_spacings)  # wide peaks
    det = detect_axles(record, ("ad1", "ad2"), 3.0, responses=resp)  # merged peaks apart
    det = detect_from_strain(record, influence_line)          # no axle detectors
    det = detect_from_strain(record, il, known_spacings=[3.8, 6.0, 1.3, 1.3])

Contract
--------
* Times in s (record time), distances in m, speeds in m/s.  The passages are in the
  influence-line frame: axle i at ``x = speed (t − delay) − a_i``; with axle detectors,
  the first detector is at ``x = position`` (default 0).
* Results are frozen :class:`Detection` / :class:`VehicleDetection`; a record without a
  detectable vehicle gives a Detection with no vehicles and the reason in ``message``
  (a batch survives); invalid arguments raise :class:`~bwim.errors.InputError`.
* Depends only on the core (records, sensors, errors) and :class:`~bwim.wim.InfluenceLine`.
"""

from bwim.detect.axles import detect_axles
from bwim.detect.lateral import LateralPosition, lateral_position, section_gauges
from bwim.detect.options import DEFAULT_MAX_AXLE_SPACING, DetectOptions
from bwim.detect.response import DetectorResponse, LearnedResponses, learn_responses
from bwim.detect.result import (
    FLAG_COUNT_MISMATCH,
    FLAG_DETECTOR_FAULT,
    FLAG_DETECTOR_SPIKE,
    FLAG_MULTIPLE_PRESENCE,
    FLAG_NO_AXLES,
    FLAG_SINGLE_AXLE,
    FLAG_SPEED_RANGE,
    FLAG_SPEED_VARIES,
    FLAG_STRAIN_ONLY,
    FLAG_TRUNCATED,
    FLAG_UNEXPLAINED_STRAIN,
    Detection,
    VehicleDetection,
)
from bwim.detect.strain import detect_from_strain
from bwim.detect.truck import detect_known_truck

__all__ = [
    "DEFAULT_MAX_AXLE_SPACING",
    "FLAG_COUNT_MISMATCH",
    "FLAG_DETECTOR_FAULT",
    "FLAG_DETECTOR_SPIKE",
    "FLAG_MULTIPLE_PRESENCE",
    "FLAG_NO_AXLES",
    "FLAG_SINGLE_AXLE",
    "FLAG_SPEED_RANGE",
    "FLAG_SPEED_VARIES",
    "FLAG_STRAIN_ONLY",
    "FLAG_TRUNCATED",
    "FLAG_UNEXPLAINED_STRAIN",
    "DetectOptions",
    "Detection",
    "DetectorResponse",
    "LateralPosition",
    "LearnedResponses",
    "VehicleDetection",
    "detect_axles",
    "detect_from_strain",
    "detect_known_truck",
    "lateral_position",
    "learn_responses",
    "section_gauges",
]
