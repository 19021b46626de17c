"""The span as the detection reads it (bwim.detect.presence.resolve_span) and the axle
groups' shares (bwim.wim.moses.group_share): a pair of floats read without numpy, the
shares built from Python lists, the same values and errors as before."""

from __future__ import annotations

import numpy as np
import pytest

from bwim.detect.presence import resolve_span
from bwim.errors import InputError
from bwim.wim.moses import group_share


def test_a_pair_of_floats_is_read_as_any_pair():
    for pair in ((0.0, 31.5), (-2.25, 7.0), (np.float64(-1.0), np.float64(3.0))):
        got = resolve_span(pair)
        assert got == resolve_span(list(pair)) == resolve_span(np.array(pair))
        assert all(type(v) is float for v in got)
    assert resolve_span(12.0) == (0.0, 12.0)
    assert resolve_span((1, 4)) == (1.0, 4.0)  # integers: numpy's reading
    for bad, match in (((3.0, 1.0), "x_start < x_end"), ((0.0, float("nan")), "span\\[1\\]"),
                       ((float("inf"), 1.0), "span\\[0\\]"), ((1.0, 2.0, 3.0), "a pair")):
        with pytest.raises(InputError, match=match):
            resolve_span(bad)


def test_group_shares_are_each_groups_equal_share():
    for groups, n in ((((0,), (1, 2), (3, 4, 5)), 6), (None, 4), ([[0, 1]], 2), ((), 0)):
        g = group_share(groups, n)
        ref = np.zeros((n, len(g.groups)))
        for k, axles in enumerate(g.groups):
            ref[list(axles), k] = 1.0 / len(axles)
        assert g.share.shape == ref.shape and np.array_equal(g.share, ref)
        assert g.share.dtype == np.float64 and g.share.flags.c_contiguous
