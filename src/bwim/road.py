"""Road profiles: ISO 8608 random roughness, measured profiles, the tyre-patch filter.

Contract
--------
* A :class:`RoadProfile` is elevation ``z`` (m, **up** positive) against ``x`` (m, from the
  bridge's first support, negative on the approach), for one track (a "carpet": both
  wheel tracks identical) or two tracks (right, left).  Between samples it is linear.
* :meth:`RoadProfile.iso8608` draws a profile with the displacement PSD
  ``G_d(n) = G_d(n₀) (n / n₀)^(−w)``, ``n₀ = 0.1`` cycle/m (ISO 8608:2016), by a sum of
  harmonics with seeded random phases evaluated by an inverse FFT (Cebon & Newland 1983;
  docs/theory.md §2.2).
  Roughness is given as ``G_d(n₀)`` in m³/cycle or as an ISO class ``"A"`` … ``"H"``
  (geometric-mean values 16, 64, 256, … × 10⁻⁶ m³).  The paper's "class C" profile has
  ``G_d(n₀) = 65 × 10⁻⁶``, which is ISO class B's mean: pass the number.
* :meth:`RoadProfile.smoothed` is a centred moving average over a tyre contact length.
* :meth:`RoadProfile.at` returns the elevation under wheels; a wheel right of the centre
  line (lateral offset < 0) runs on the right track, left of it on the left track.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bwim.errors import InputError, require_axis, require_positive, require_range
from bwim.limits import check_memory

__all__ = ["ISO_CLASSES", "RoadProfile"]

#: ISO 8608 geometric-mean displacement PSD at n₀ = 0.1 cycle/m, m³/cycle.
ISO_CLASSES = {c: 16e-6 * 4.0**i for i, c in enumerate("ABCDEFGH")}
N0 = 0.1  #: reference spatial frequency, cycle/m
_FLAT_EXTENT = 1e9


@dataclass(frozen=True, kw_only=True, eq=False)
class RoadProfile:
    """Road elevation along the wheel paths.

    Parameters
    ----------
    x : array_like, shape (n,)
        Strictly increasing positions, m (negative on the approach).
    elevation : array_like, shape (n,) or (n, 2)
        Elevation, m, up positive: one carpet track or (right, left) tracks.
    """

    x: np.ndarray
    elevation: np.ndarray

    def __post_init__(self) -> None:
        x = require_axis("road x", self.x, "positions")
        z = np.asarray(self.elevation, dtype=float)
        if z.shape not in ((x.size,), (x.size, 2)):
            raise InputError(
                f"road elevation must have shape ({x.size},) or ({x.size}, 2), got {z.shape}"
            )
        if not np.all(np.isfinite(z)):
            raise InputError("road elevation must be finite")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "elevation", z)

    # --- constructors ------------------------------------------------------------------
    @classmethod
    def flat(cls) -> RoadProfile:
        """A perfectly smooth road of unlimited extent."""
        return cls(x=np.array([-_FLAT_EXTENT, _FLAT_EXTENT]), elevation=np.zeros(2))

    @classmethod
    def iso8608(
        cls,
        roughness: float | str,
        *,
        length: float,
        seed: int | np.random.Generator | None,
        start: float | None = None,
        dx: float = 0.05,
        band: tuple[float, float] = (0.011, 2.83),
        waviness: float = 2.0,
        track_correlation: float = 1.0,
    ) -> RoadProfile:
        """A random profile with an ISO 8608 displacement PSD.

        Parameters
        ----------
        roughness : float or str
            ``G_d(n₀)`` in m³/cycle (e.g. ``65e-6``) or an ISO class letter.
        length : float
            Profile length, m.
        seed : int or Generator
            Random phases come only from here.
        start : float, optional
            x of the first sample, m (default ``−0.75 × length``: three quarters of the
            profile are approach, the last quarter carries the bridge and the exit).
        dx : float
            Sample spacing, m.
        band : (float, float)
            Spatial-frequency band, cycle/m (ISO 8608's 0.011 … 2.83 by default).
        waviness : float
            PSD exponent w (ISO: 2).
        track_correlation : float
            1 (default): a carpet, both tracks identical; 0: independent tracks; in
            between, the left track is ``c z_right + sqrt(1 − c²) z_independent``
            (coherence c² at every wavelength).
        """
        if isinstance(roughness, str):
            if roughness.upper() not in ISO_CLASSES:
                raise InputError(
                    f"unknown ISO 8608 class {roughness!r}; expected one of "
                    f"{', '.join(ISO_CLASSES)} or a number G_d(n0) in m^3/cycle"
                )
            gd0 = ISO_CLASSES[roughness.upper()]
        else:
            gd0 = require_positive("roughness", roughness)
        length = require_positive("length", length)
        dx = require_positive("dx", dx)
        c = require_range("track_correlation", track_correlation, 0.0, 1.0, closed=True)
        n_lo, n_hi = band
        if not 0 < n_lo < n_hi:
            raise InputError(f"band must be 0 < low < high cycle/m, got {band}")
        x0 = -0.75 * length if start is None else float(start)
        check_memory(length / dx * 8.0 * 12, f"an ISO 8608 road profile of {length:g} m at "
                     f"dx = {dx:g} m")
        n = int(np.ceil(length / dx)) + 1
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed < 0:
            raise InputError(f"seed must be a non-negative integer, got {seed}")
        rng = np.random.default_rng(seed)
        right = _harmonic_sum(n, dx, gd0, waviness, n_lo, n_hi, rng)
        x = x0 + dx * np.arange(n)
        if c == 1.0:
            return cls(x=x, elevation=right)
        other = _harmonic_sum(n, dx, gd0, waviness, n_lo, n_hi, rng)
        left = c * right + np.sqrt(1.0 - c * c) * other
        return cls(x=x, elevation=np.stack([right, left], axis=1))

    # --- operations --------------------------------------------------------------------
    @property
    def n_tracks(self) -> int:
        return 1 if self.elevation.ndim == 1 else 2

    @property
    def extent(self) -> tuple[float, float]:
        return float(self.x[0]), float(self.x[-1])

    def smoothed(self, length: float) -> RoadProfile:
        """Centred moving average over ``length`` m (the tyre contact patch).

        Exact for the piecewise-linear profile; the result is shorter by ``length`` (half
        at each end) so that no value is made up beyond the data.
        """
        length = require_positive("length", length)
        if self.x[-1] - self.x[0] <= length:
            raise InputError(f"profile of {self.x[-1] - self.x[0]:g} m is too short to "
                             f"smooth over {length:g} m")
        z = self.elevation.reshape(self.x.size, -1)
        area = np.concatenate(
            [np.zeros((1, z.shape[1])),
             np.cumsum(0.5 * (z[1:] + z[:-1]) * np.diff(self.x)[:, None], axis=0)]
        )
        h = length / 2
        lo, hi = self.x[0] + h, self.x[-1] - h
        inner = self.x[(self.x > lo) & (self.x < hi)]
        xs = np.concatenate([[lo], inner, [hi]])
        out = np.stack([
            (_integral(self.x, z[:, k], area[:, k], xs + h)
             - _integral(self.x, z[:, k], area[:, k], xs - h)) / length
            for k in range(z.shape[1])
        ], axis=1)
        return RoadProfile(x=xs, elevation=out[:, 0] if self.n_tracks == 1 else out)

    def covers(self, lo: float, hi: float) -> bool:
        return self.x[0] <= lo and hi <= self.x[-1]

    def at(self, x: np.ndarray, lateral: np.ndarray | float = 0.0) -> np.ndarray:
        """Elevation (m, up) at positions ``x`` for wheels at lateral offsets (m, + left).

        Shapes broadcast; a wheel on the centre line (offset 0) of a two-track profile
        reads the mean of the tracks.
        """
        x = np.asarray(x, dtype=float)
        if self.n_tracks == 1:
            return np.interp(x, self.x, self.elevation)
        lat = np.broadcast_to(np.asarray(lateral, dtype=float), x.shape)
        right = np.interp(x, self.x, self.elevation[:, 0])
        left = np.interp(x, self.x, self.elevation[:, 1])
        return np.where(lat < 0, right, np.where(lat > 0, left, 0.5 * (right + left)))


def _harmonic_sum(n, dx, gd0, w, n_lo, n_hi, rng) -> np.ndarray:
    """Σ_k A_k cos(2π n_k x + φ_k), A_k = sqrt(2 G_d(n_k) Δn), by one inverse real FFT."""
    dn = 1.0 / (n * dx)
    k = np.arange(n // 2 + 1)
    nk = k * dn
    in_band = (nk >= n_lo) & (nk <= n_hi) & (k > 0) & (k < (n + 1) // 2)
    amp = np.zeros(k.size)
    amp[in_band] = np.sqrt(2.0 * gd0 * (nk[in_band] / N0) ** (-w) * dn)
    phase = rng.uniform(0.0, 2 * np.pi, k.size)
    spectrum = 0.5 * n * amp * np.exp(1j * phase)
    return np.fft.irfft(spectrum, n=n)


def _integral(x, z, area, at):
    """∫ from x[0] to ``at`` of the piecewise-linear z (``area`` = cumulative at nodes)."""
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    t = at - x[i]
    slope = (z[i + 1] - z[i]) / (x[i + 1] - x[i])
    return area[i] + z[i] * t + 0.5 * slope * t * t
