"""Axle detectors as strain sensors: a local response to nearby tyres less a share of the
slab's global bending.

Contract
--------
A real B-WIM axle detector on a short slab is not a sharp pulse per axle (issue 20): each
axle gives a peak about 1 m wide (along the lane), the peaks sit on a baseline that dips
below zero between axle groups (the slab's global bending), the steering axle's peak is
small, the two detectors of a lane differ several times in gain, and the close axles of a
tridem merge.  :func:`detector_reading` models the channel as

``r(t) = gain × [ Σ_tyres F_tyre(t) / 1 kN × Kx(x_tyre(t) − x_d) × Ky(y_tyre − y_d)
− global_share × ε_g(t) / 1 µε ] + offset + noise``

* **Local part.**  Every tyre near the detector: ``Kx(u) = exp(−4 ln 2 (u / width)²)`` (a
  peak of full width at half maximum ``width`` m along the lane) times a lateral
  sensitivity ``Ky(v) = exp(−v² / (2 lateral_sigma²))``.  A wheel is one tyre or a dual
  pair (two tyres ``dual_spacing`` m apart about the wheel centre, each with half the
  wheel force), at the typical track of its tyre type (:data:`TRACKS`: steering singles
  2.05 m, wide singles 2.04 m, dual pairs 1.82 m between pair centres) about the
  vehicle's centre line; the vehicle models' own wheels are 2.0 m apart, a difference
  well inside the gauges' 0.85 m load spread.  So both wheels of an axle, the lateral
  position of the vehicle (wander) and the tyre type all change an axle's peak: a
  detector on the lane centre line sees the inner tyre of a drive axle's dual pair much
  more than a steering tyre.  Tyre forces are the simulated (dynamic) wheel forces.
* **Global part.**  ``ε_g`` is the slab's soffit strain ``strain_x`` at mid-span under the
  detector's line (x = span / 2, y = y_d; load-spread mean as for the gauges), from the
  same finite-element simulation as the gauges, so it responds to vehicles in every lane
  (weakly to far ones) and carries the day's strain factor.  It enters with a negative
  share: between axle groups, when no tyre is near the detector, the reading dips below
  zero.
* ``gain`` is each detector's own (drawn per site, see :class:`DetectorResponse`), noise
  is white with σ ``noise`` (detector units), ``offset`` uniform in ±``offset`` per event.

The units are a detector's own ("detector units"); nothing downstream may assume them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.conventions import KILONEWTON, MICROSTRAIN
from bwim.errors import InputError

__all__ = ["TRACKS", "TYRES", "DetectorResponse", "detector_reading", "local_response"]

#: Tyre types of a wheel: one tyre at the wheel centre, or a dual pair.
TYRES = ("single", "wide", "dual")
#: m, distance between the wheel centres of an axle by tyre type (typical of EU trucks:
#: steering axles and wide-single trailer axles about 2.05 m, dual-tyred axles about
#: 1.82 m between the centres of the pairs).
TRACKS = {"single": 2.05, "wide": 2.04, "dual": 1.82}


@dataclass(frozen=True, kw_only=True)
class DetectorResponse:
    """The response model of a site's axle detectors (see the module docstring).

    Attributes
    ----------
    width : float
        m, full width at half maximum of the local peak along the lane.
    lateral_sigma : float
        m, lateral sensitivity (σ of the Gaussian ``Ky``).
    dual_spacing : float
        m, centre distance of the two tyres of a dual pair.
    global_share : float
        Detector units per µε of mid-span soffit strain under the detector's line
        (subtracted), for a local sensitivity of 1 unit per kN at the kernel's peak.  The
        default puts the dips between axle groups in the middle of the real range
        (docs/realistic_site.md).
    gain_range : (float, float)
        Range of the gain of the more sensitive detector of a lane.
    pair_ratio : (float, float)
        Range of the ratio of a lane's two gains (the larger over the smaller).
    noise : float
        σ of the white noise, detector units.
    offset : float
        Half-range of the per-event offset, detector units.
    """

    width: float = 1.2
    lateral_sigma: float = 0.65
    dual_spacing: float = 0.35
    global_share: float = 0.9
    gain_range: tuple[float, float] = (0.8, 1.25)
    pair_ratio: tuple[float, float] = (3.0, 5.0)
    noise: float = 0.1
    offset: float = 2.0

    def __post_init__(self) -> None:
        for key in ("width", "lateral_sigma", "dual_spacing"):
            if not getattr(self, key) > 0:
                raise InputError(f"DetectorResponse.{key} must be > 0")
        if self.global_share < 0 or self.noise < 0 or self.offset < 0:
            raise InputError("DetectorResponse global_share, noise and offset must be >= 0")
        lo, hi = self.pair_ratio
        if not 1.0 <= lo <= hi:
            raise InputError(f"DetectorResponse.pair_ratio must be 1 <= low <= high, "
                             f"got {self.pair_ratio}")

    def draw_gains(self, rng: np.random.Generator) -> tuple[float, float]:
        """Gains of a lane's two detectors: one in ``gain_range``, the other that divided
        by a ratio in ``pair_ratio``; which of the two is the larger is random."""
        big = float(rng.uniform(*self.gain_range))
        small = big / float(rng.uniform(*self.pair_ratio))
        return (big, small) if rng.uniform() < 0.5 else (small, big)


def local_response(x_wheel: np.ndarray, side: np.ndarray, lane_y: float, forces: np.ndarray,
                   tyres, x_d: float, y_d: float, response: DetectorResponse) -> np.ndarray:
    """The local part (before gain): ``Σ_tyres F / 1 kN × Kx × Ky``, shape (n_t,).

    ``x_wheel`` (n_t, n_w): wheel positions along the bridge (m); ``side`` (n_w,): −1 for
    a wheel on the low-y side of the vehicle's centre line ``lane_y`` (m), +1 on the
    other; ``forces`` (n_t, n_w): wheel forces (N); ``tyres``: one of :data:`TYRES` per
    wheel, which sets its lateral position (:data:`TRACKS`).
    """
    x_wheel = np.asarray(x_wheel, dtype=float)
    forces = np.asarray(forces, dtype=float)
    c = 4.0 * np.log(2.0) / response.width**2
    out = np.zeros(x_wheel.shape[0])
    for j, kind in enumerate(tyres):
        if kind not in TYRES:
            raise InputError(f"unknown tyre type {kind!r}; expected one of {', '.join(TYRES)}")
        y_wheel = lane_y + side[j] * TRACKS[kind] / 2
        lateral = ([0.0] if kind != "dual"
                   else [-response.dual_spacing / 2, response.dual_spacing / 2])
        ky = np.mean([np.exp(-(y_wheel + o - y_d) ** 2 / (2 * response.lateral_sigma**2))
                      for o in lateral])
        if ky < 1e-12:
            continue
        out += forces[:, j] / KILONEWTON * ky * np.exp(-c * (x_wheel[:, j] - x_d) ** 2)
    return out


def detector_reading(local: np.ndarray, global_strain: np.ndarray, *, gain: float,
                     response: DetectorResponse, rng: np.random.Generator) -> np.ndarray:
    """A detector channel: ``gain × (local − global_share × ε_g / 1 µε)`` plus an offset
    and white noise drawn from ``rng``; ``global_strain`` already carries the day's strain
    factor."""
    clean = gain * (np.asarray(local) - response.global_share * np.asarray(global_strain)
                    / MICROSTRAIN)
    return (clean + rng.uniform(-response.offset, response.offset)
            + response.noise * rng.standard_normal(clean.shape))
