"""The modal oscillator's digital filter of the road-free calibration
(:func:`bwim.calibration.quasistatic.oscillator_filter`), against two references: scipy's
bilinear transform by polynomial arithmetic (another implementation of the same map), and
the oscillator's static gain 1/ω² (the filter's gain at z = 1, which the bilinear
transform keeps exactly: s = 0 maps to z = 1)."""

import numpy as np
import pytest
import scipy.signal

from bwim.calibration.quasistatic import oscillator_filter


@pytest.mark.parametrize("fs", [128.0, 512.0, 2048.0])
@pytest.mark.parametrize("f_n", [2.0, 17.0, 60.0])
@pytest.mark.parametrize("zeta", [0.0, 0.03, 0.2])
def test_the_closed_form_is_scipys_bilinear(fs, f_n, zeta):
    om = 2 * np.pi * f_n
    b, a = oscillator_filter(om, zeta, fs)
    rb, ra = scipy.signal.bilinear([1.0], [1.0, 2 * zeta * om, om * om], fs=fs)
    # measured: 1e-16 relative at most; the tolerance is a few roundings
    np.testing.assert_allclose(b, rb, rtol=1e-13, atol=0)
    np.testing.assert_allclose(a, ra, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("f_n", [2.0, 17.0, 60.0])
def test_the_static_gain_is_one_over_omega_squared(f_n):
    om = 2 * np.pi * f_n
    b, a = oscillator_filter(om, 0.03, 512.0)
    assert b.sum() / a.sum() == pytest.approx(1.0 / om**2, rel=1e-12)
    # and a constant force settles there (a stable filter: poles inside the unit circle)
    assert np.all(np.abs(np.roots(a)) < 1.0)
    n = int(30.0 / (0.03 * om) * 512.0)  # 30 decay times: e^-30 of the transient left
    q = scipy.signal.lfilter(b, a, np.ones(n))
    assert q[-1] == pytest.approx(1.0 / om**2, rel=1e-9)
