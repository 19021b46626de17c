"""ISO 8608 road profiles, the tyre-patch filter and track models."""

import numpy as np
import pytest
from scipy.signal import welch

from bwim.errors import InputError
from bwim.road import ISO_CLASSES, RoadProfile


def test_iso_psd_matches_target():
    # ISO 8608: G_d(n) = G_d(n0) (n / 0.1)^-2; Welch's one-sided PSD of a long profile
    road = RoadProfile.iso8608(65e-6, length=4000.0, seed=3, dx=0.05)
    f, p = welch(road.elevation, fs=1 / 0.05, nperseg=8192)
    band = (f > 0.05) & (f < 2.0)
    ratio = p[band] / (65e-6 * (f[band] / 0.1) ** -2)
    assert 0.9 < np.median(ratio) < 1.1


def test_variance_is_the_band_integral_and_classes():
    n = np.linspace(0.011, 2.83, 100001)
    road = RoadProfile.iso8608("C", length=20000.0, seed=0, dx=0.05)
    expected = np.trapezoid(ISO_CLASSES["C"] * (n / 0.1) ** -2, n)
    assert abs(road.elevation.var() / expected - 1) < 0.1
    assert ISO_CLASSES["B"] == pytest.approx(64e-6)
    assert ISO_CLASSES["D"] == pytest.approx(4 * ISO_CLASSES["C"])


def test_seeded_and_extent():
    a = RoadProfile.iso8608(65e-6, length=200.0, seed=1)
    b = RoadProfile.iso8608(65e-6, length=200.0, seed=1)
    c = RoadProfile.iso8608(65e-6, length=200.0, seed=2)
    np.testing.assert_array_equal(a.elevation, b.elevation)
    assert not np.allclose(a.elevation, c.elevation)
    assert a.extent == pytest.approx((-150.0, 50.0))
    assert RoadProfile.iso8608(65e-6, length=50.0, seed=1, start=-40.0).extent[0] == -40.0


def test_track_models():
    carpet = RoadProfile.iso8608(65e-6, length=500.0, seed=4)
    assert carpet.n_tracks == 1
    np.testing.assert_array_equal(carpet.at([1.0, 2.0], -1.0), carpet.at([1.0, 2.0], 1.0))
    indep = RoadProfile.iso8608(65e-6, length=5000.0, seed=4, track_correlation=0.0)
    mixed = RoadProfile.iso8608(65e-6, length=5000.0, seed=4, track_correlation=0.7)
    assert abs(np.corrcoef(indep.elevation.T)[0, 1]) < 0.15
    assert abs(np.corrcoef(mixed.elevation.T)[0, 1] - 0.7) < 0.1
    x = np.array([3.0])
    right, left = mixed.at(x, -1.0)[0], mixed.at(x, 1.0)[0]
    assert mixed.at(x, 0.0)[0] == pytest.approx(0.5 * (right + left))


def test_smoothed_is_a_moving_average():
    x = np.linspace(-10, 10, 2001)  # 1 cm spacing
    z = np.sin(3 * x) + 0.1 * x
    road = RoadProfile(x=x, elevation=z)
    s = road.smoothed(0.24)
    # closed form of the centred average of sin(3x) + 0.1x over ±0.12
    expected = np.sin(3 * s.x) * np.sin(3 * 0.12) / (3 * 0.12) + 0.1 * s.x
    np.testing.assert_allclose(s.elevation, expected, atol=2e-4)
    assert s.x[0] >= -10 + 0.12 - 1e-12 and s.x[-1] <= 10 - 0.12 + 1e-12


def test_flat_and_custom():
    flat = RoadProfile.flat()
    assert flat.covers(-1e6, 1e6)
    assert np.all(flat.at(np.linspace(-100, 100, 7)) == 0)
    assert np.all(flat.smoothed(0.24).elevation == 0)


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        (dict(roughness="Z", length=100.0, seed=1), "unknown ISO 8608 class 'Z'"),
        (dict(roughness=-1e-6, length=100.0, seed=1), "roughness must be positive"),
        (dict(roughness=6e-5, length=0.0, seed=1), "length must be positive"),
        (dict(roughness=6e-5, length=10.0, seed=1, track_correlation=1.5),
         r"track_correlation must lie in \[0, 1\]"),
    ],
)
def test_bad_iso_input(kwargs, pattern):
    with pytest.raises(InputError, match=pattern):
        RoadProfile.iso8608(kwargs.pop("roughness"), **kwargs)


def test_bad_custom_profile():
    with pytest.raises(InputError, match="strictly increasing"):
        RoadProfile(x=[0.0, 2.0, 1.0], elevation=[0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="must be finite"):
        RoadProfile(x=[0.0, 1.0], elevation=[0.0, np.nan])
