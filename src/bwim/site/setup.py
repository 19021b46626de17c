"""What a B-WIM installation knows: its lanes, their axle detectors, its calibration truck,
and how detection, weighing and drift correction are to be done.

Contract
--------
* A :class:`DetectorLane` is one lane's pair of axle detectors: the two channels in the
  order that lane's traffic meets them, their ``distance`` (m), the lane's ``number`` and
  travel ``direction`` (``"+x"``: the bridge frame's own, ``"-x"``: the other way), the
  detectors' lateral position ``y`` (m, when known), ``position``: the x (m) of the
  first detector that lane's traffic meets, in the frame of the influence lines, the
  largest axle spacing within one vehicle ``max_spacing`` (m; default the detection's)
  and ``max_length``: the longest vehicle's spread from first to last axle (m,
  :data:`MAX_WHEELBASE` by default; 25.25 where European Modular System combinations
  run).  That
  frame is the calibration lane's: its first detector is at x = 0 unless its position
  says otherwise.  Default positions: 0 for a lane that travels like the calibration
  lane (its pair is assumed across from the calibration pair), ``distance`` of the
  calibration pair for a lane that travels the other way (the same two cross-sections,
  met in the other order).
* A :class:`Lane` is a traffic lane without detectors known by its centre line (``y``,
  m) and direction: a vehicle found at that lateral position (by the gauges) is given its
  number.
* :class:`SiteSetup` holds the calibration truck's static axle loads (N) and spacings
  (m), the detector lanes (none: vehicles are found from the strain alone), the
  calibration truck's lane (``calibration_lane``; default the first detector lane's),
  the other lanes, and the choices: ``detection`` (:data:`DETECTION_METHODS`),
  ``combine`` and ``lateral`` of the weighing (:func:`bwim.wim.weigh`) and the drift
  correction (:class:`~bwim.site.drift.DriftSetup`).  The single-pair arguments
  ``detectors``, ``distance``, ``position``, ``max_spacing`` describe one lane, as
  before.
* Units: N, m.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bwim.errors import InputError, require_finite, require_positive
from bwim.site.drift import DriftSetup

__all__ = ["DETECTION_METHODS", "DIRECTIONS", "MAX_WHEELBASE", "DetectorLane", "Lane",
           "SiteSetup"]

#: m: no vehicle's first and last axles are further apart than the longest standard
#: combination on European roads (18.75 m overall, a road train: Council Directive
#: 96/53/EC, Annex I); axles spread over more are vehicles following each other, or a
#: longer combination where a member state admits one (25.25 m, the European Modular
#: System: Art. 4(4)-(5) of the Directive), which a pair's ``max_length`` then allows.
MAX_WHEELBASE = 18.75

#: Travel directions in the bridge frame.
DIRECTIONS = ("+x", "-x")
#: How vehicles are found with axle detectors: ``"learned"`` (each detector's response
#: learned from the calibration runs, then sparse deconvolution, :mod:`bwim.detect.pursuit`:
#: wide, merged peaks), ``"peaks"`` (separate sharp peaks, :func:`bwim.detect.detect_axles`)
#: or ``"auto"`` (learned, falling back to peaks when the runs cannot teach a response).
DETECTION_METHODS = ("auto", "learned", "peaks")


def _direction(value: object) -> str:
    if value not in DIRECTIONS:
        raise InputError(f"direction must be '+x' or '-x', got {value!r}")
    return str(value)


def _lane_number(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputError(f"a lane number must be a positive integer, got {value!r}")
    return int(value)


@dataclass(frozen=True, kw_only=True)
class DetectorLane:
    """One lane's pair of axle detectors (see the module docstring)."""

    channels: tuple[str, str]
    distance: float
    lane: int = 1
    direction: str = "+x"
    position: float | None = None
    y: float | None = None
    max_spacing: float | None = None
    max_length: float = MAX_WHEELBASE

    def __post_init__(self) -> None:
        ch = tuple(self.channels)
        if len(ch) != 2 or ch[0] == ch[1] or not all(isinstance(c, str) and c for c in ch):
            raise InputError(f"detectors must be two different channels, got {self.channels!r}")
        object.__setattr__(self, "channels", (ch[0], ch[1]))
        object.__setattr__(self, "distance", require_positive("distance", self.distance))
        object.__setattr__(self, "lane", _lane_number(self.lane))
        object.__setattr__(self, "direction", _direction(self.direction))
        for name in ("position", "y"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, require_finite(name, getattr(self, name)))
        if self.max_spacing is not None:
            object.__setattr__(self, "max_spacing",
                               require_positive("max_spacing", self.max_spacing))
        object.__setattr__(self, "max_length", require_positive("max_length", self.max_length))

    @property
    def sign(self) -> int:
        """+1 for traffic in +x, −1 in −x."""
        return 1 if self.direction == "+x" else -1


@dataclass(frozen=True, kw_only=True)
class Lane:
    """A traffic lane by its centre line (m) and direction."""

    number: int
    y: float
    direction: str = "+x"

    def __post_init__(self) -> None:
        object.__setattr__(self, "number", _lane_number(self.number))
        object.__setattr__(self, "y", require_finite("lane y", self.y))
        object.__setattr__(self, "direction", _direction(self.direction))


@dataclass(frozen=True, kw_only=True, eq=False)
class SiteSetup:
    """What a B-WIM installation knows (see the module docstring).

    Parameters
    ----------
    calibration_loads : sequence of float
        The calibration truck's static axle loads, N.
    calibration_spacings : sequence of float
        Its axle spacings, m.
    lanes : sequence of DetectorLane
        The lanes with axle detectors (empty: detect from the strain alone).
    traffic_lanes : sequence of Lane
        Every lane's centre line and direction (those with detectors too, optional).
    calibration_lane : int, optional
        The lane the calibration truck drives (default: the first detector lane's).
    detectors, distance, position, max_spacing
        One lane's pair, as before ``lanes`` (lane 1, +x): made into ``lanes``, these
        then read None (``position`` 0); without ``detectors`` they are refused (with
        ``lanes`` each :class:`DetectorLane` has its own).
    combine : str
        How the gauges are combined (:func:`bwim.wim.weigh`): ``"auto"``, ``"gls"``,
        ``"blue"`` or ``"sum"``.
    lateral : str or None
        ``"linear"``: lines linear in the lateral position (in metres: every gauge needs
        its ``y``, else :func:`~bwim.site.calibrate_site` refuses it); None: one line per
        gauge.
    support_lobes : bool
        The lines keep a lobe beyond their first zeros (a slab continuous over its
        supports: :func:`bwim.wim.calibrate_lines`' ``support_lobes``); a record may end
        on that lobe without being truncated.  Off by default.
    detection : str
        :data:`DETECTION_METHODS`.
    drift : DriftSetup or str
        The drift correction (a method name is a DriftSetup of that method).
    """

    calibration_loads: np.ndarray
    calibration_spacings: np.ndarray
    lanes: tuple[DetectorLane, ...] = ()
    traffic_lanes: tuple[Lane, ...] = ()
    calibration_lane: int | None = None
    detectors: tuple[str, str] | None = None
    distance: float | None = None
    position: float = 0.0
    max_spacing: float | None = None
    combine: str = "auto"
    lateral: str | None = None
    support_lobes: bool = False
    detection: str = "auto"
    drift: DriftSetup = field(default_factory=DriftSetup)

    def __post_init__(self) -> None:
        loads = np.array(self.calibration_loads, dtype=float, ndmin=1)
        spacings = np.array(self.calibration_spacings, dtype=float, ndmin=1)
        if loads.ndim != 1 or not np.all(np.isfinite(loads)) or np.any(loads <= 0):
            raise InputError("calibration_loads must be positive axle loads, N")
        if spacings.ndim != 1 or spacings.size != loads.size - 1 or not np.all(
                np.isfinite(spacings)) or np.any(spacings <= 0):
            raise InputError(f"calibration_spacings must be {loads.size - 1} positive "
                             f"distances for {loads.size} axle loads, got {spacings.tolist()}")
        object.__setattr__(self, "calibration_loads", loads)
        object.__setattr__(self, "calibration_spacings", spacings)
        lanes = tuple(self.lanes)
        if self.detectors is not None:
            if lanes:
                raise InputError("give lanes or detectors, not both")
            if self.distance is None:
                raise InputError("two axle detectors need their distance, m")
            lanes = (DetectorLane(channels=tuple(self.detectors), distance=self.distance,
                                  position=require_finite("position", self.position),
                                  max_spacing=self.max_spacing),)
            # the shorthand lives on in ``lanes`` alone: a setup is then one the lanes form
            # gives, and dataclasses.replace of it does not give both
            for name, value in (("detectors", None), ("distance", None), ("position", 0.0),
                                ("max_spacing", None)):
                object.__setattr__(self, name, value)
        elif self.distance is not None or self.position != 0.0 or self.max_spacing is not None:
            # (also dataclasses.replace of a one-pair setup, whose pair is in lanes now)
            raise InputError("distance, position and max_spacing go with detectors= (one "
                             "pair); with lanes, give them to each DetectorLane")
        for k, ln in enumerate(lanes):
            if not isinstance(ln, DetectorLane):
                raise InputError(f"lanes[{k}] must be a DetectorLane, got {type(ln).__name__}")
        numbers = [ln.lane for ln in lanes]
        if len(set(numbers)) != len(numbers):
            raise InputError(f"two detector pairs for one lane: lanes {numbers}")
        channels = [c for ln in lanes for c in ln.channels]
        if len(set(channels)) != len(channels):
            raise InputError(f"a channel belongs to two detector pairs: {channels}")
        cal = self.calibration_lane
        if cal is not None:
            cal = _lane_number(cal)
            if lanes and cal not in numbers:
                raise InputError(f"calibration_lane {cal} has no axle detectors (lanes "
                                 f"{numbers})")
        elif lanes:
            cal = lanes[0].lane
        object.__setattr__(self, "calibration_lane", cal)
        object.__setattr__(self, "lanes", self._positioned(lanes, cal))
        traffic = tuple(self.traffic_lanes)
        for k, ln in enumerate(traffic):
            if not isinstance(ln, Lane):
                raise InputError(f"traffic_lanes[{k}] must be a Lane, got {type(ln).__name__}")
        numbers = [ln.number for ln in traffic]
        if len(set(numbers)) < len(numbers):
            raise InputError(f"a lane appears twice in traffic_lanes: {numbers}")
        pairs = {ln.lane: ln.direction for ln in self.lanes}
        for ln in traffic:
            if pairs.get(ln.number, ln.direction) != ln.direction:
                raise InputError(f"lane {ln.number} travels {ln.direction} in traffic_lanes "
                                 f"but {pairs[ln.number]} at its axle detectors")
        object.__setattr__(self, "traffic_lanes", traffic)
        if self.combine not in ("auto", "gls", "blue", "sum"):
            raise InputError(f"combine must be auto, gls, blue or sum, got {self.combine!r}")
        if self.lateral not in (None, "linear"):
            raise InputError(f"lateral must be None or 'linear', got {self.lateral!r}")
        if self.detection not in DETECTION_METHODS:
            raise InputError(f"detection must be one of {', '.join(DETECTION_METHODS)}, got "
                             f"{self.detection!r}")
        drift = DriftSetup(method=self.drift) if isinstance(self.drift, str) else self.drift
        if not isinstance(drift, DriftSetup):
            raise InputError(f"drift must be a DriftSetup or a method name, got {self.drift!r}")
        object.__setattr__(self, "drift", drift)

    @staticmethod
    def _positioned(lanes: Sequence[DetectorLane], cal: int | None
                    ) -> tuple[DetectorLane, ...]:
        """The lanes with their default positions filled in (see the module docstring)."""
        if not lanes:
            return ()
        ref = next(ln for ln in lanes if ln.lane == cal)
        out = []
        for ln in lanes:
            if ln.position is None:
                pos = 0.0 if ln.direction == ref.direction else ref.distance
                ln = dataclasses.replace(ln, position=pos)
            out.append(ln)
        return tuple(out)

    @property
    def calibration_pair(self) -> DetectorLane | None:
        """The calibration truck's lane's detectors (None without detectors)."""
        return next((ln for ln in self.lanes if ln.lane == self.calibration_lane), None)

    def lane_of(self, y: float, direction: str | None = None) -> int | None:
        """The number of the lane whose centre line is nearest ``y`` (m) among the lanes
        of that direction (every lane when None; detector lanes by their ``y``, and
        ``traffic_lanes``); None without any."""
        centres = self.centres(direction)
        if not centres or not np.isfinite(y):
            return None
        return min(centres, key=lambda n: abs(centres[n][0] - y))

    def direction_of(self, lane: int) -> str | None:
        """A lane's direction (None for a lane the setup does not know)."""
        hit = self.centres(None).get(lane)
        if hit is not None:
            return hit[1]
        return next((ln.direction for ln in self.lanes if ln.lane == lane), None)

    def centres(self, direction: str | None = None) -> dict[int, tuple[float, str]]:
        """Known lane centre lines (m) and directions by lane number."""
        centres = {ln.number: (ln.y, ln.direction) for ln in self.traffic_lanes
                   if direction in (None, ln.direction)}
        for ln in self.lanes:
            if direction in (None, ln.direction) and ln.y is not None:
                centres.setdefault(ln.lane, (ln.y, ln.direction))
        return centres
