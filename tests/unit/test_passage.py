"""Passage kinematics: axle and wheel positions against the closed form
x_i(t) = v (t − delay) − a_i (records.py contract), worked by hand."""

import numpy as np

from bwim import Passage


def test_axle_x_closed_form():
    # v = 12.5 m/s, delay 0.4 s, spacings 3.2 and 1.3 m: offsets a = 0, 3.2, 4.5 m
    p = Passage(speed=12.5, lane=3.0, axle_spacings=[3.2, 1.3], track_width=1.8, delay=0.4)
    t = np.array([0.4, 0.76, 1.2])
    # hand values: 12.5 (t − 0.4) = 0, 4.5, 10 minus each offset
    expected = np.array([[0.0, -3.2, -4.5],
                         [4.5, 1.3, 0.0],
                         [10.0, 6.8, 5.5]])
    np.testing.assert_allclose(p.axle_x(t), expected, atol=1e-12)
    # the two wheels of each axle share its position (right wheel first)
    np.testing.assert_allclose(p.wheel_x(t), np.repeat(expected, 2, axis=1), atol=1e-12)


def test_axle_x_agrees_with_entry_and_exit_times():
    p = Passage(speed=23.0, axle_spacings=[4.1, 1.35, 6.0], delay=1.7)
    length = 31.0
    on = p.axle_times_on(length)  # (n_axles, 2)
    for i in range(p.n_axles):
        x = p.axle_x(on[i])[:, i]
        np.testing.assert_allclose(x, [0.0, length], atol=1e-9)


def test_axle_offsets_are_numpys_running_sums():
    """The offsets of float spacings (summed as Python floats) are numpy's cumsum after a
    0, bit for bit; other inputs (lists, integers) as before."""
    from bwim.records import axle_offsets

    rng = np.random.default_rng(4)
    for _ in range(3000):
        sp = rng.uniform(0.01, 20.0, int(rng.integers(0, 30))) * 10.0 ** rng.uniform(-3, 3)
        got = axle_offsets(sp)
        assert got.dtype == np.float64
        assert np.array_equal(got, np.concatenate([[0.0], np.cumsum(sp)]))
    assert np.array_equal(axle_offsets([3.2, 1.3]), [0.0, 3.2, 4.5])
    assert np.array_equal(axle_offsets(np.array([2, 3])), [0.0, 2.0, 5.0])
    p = Passage(speed=10.0, axle_spacings=[3.2, 1.3])
    assert np.array_equal(p.axle_offsets, np.concatenate([[0.0], np.cumsum([3.2, 1.3])]))


def test_spacings_must_be_finite_and_positive():
    import pytest

    from bwim.errors import InputError

    for bad in ([3.0, 0.0], [-1.0], [np.nan], [np.inf, 2.0], [2.0, -np.inf], [[1.0, 2.0]]):
        with pytest.raises(InputError, match="axle_spacings must be positive distances"):
            Passage(speed=10.0, axle_spacings=bad)
    for good in ([], [1e-300], [5.0, 1.3, 1e300]):
        assert Passage(speed=10.0, axle_spacings=good).n_axles == len(good) + 1
