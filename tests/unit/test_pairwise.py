"""bwim.pairwise against numpy.sum itself: the same double, bit for bit, for every length
(numpy's blocks of 8 and 128, its halves beyond), an offset start, and signed zeros."""

import numpy as np

from bwim.pairwise import numpy_sum, pairwise_sum


def _bits(x) -> bytes:
    return np.float64(x).tobytes()


def test_the_sum_is_numpys_for_every_length():
    rng = np.random.default_rng(3)
    for n in [*range(0, 300), 511, 1000, 4097, 70001]:
        a = rng.normal(size=n) * 10.0 ** rng.uniform(-6, 6, n)
        assert _bits(numpy_sum(a)) == _bits(np.sum(a)), n


def test_an_offset_slice_is_summed_as_numpy_sums_it():
    rng = np.random.default_rng(1)
    for n in [*range(0, 140), 255, 1000, 4097]:
        x = rng.standard_normal(n + 2) * 10.0 ** rng.integers(-8, 9, n + 2)
        assert _bits(pairwise_sum(x, 2, n)) == _bits(x[2:].sum()), n


def test_negative_zeros_sum_to_numpys_zero():
    for n in (1, 7, 9, 200):
        assert _bits(numpy_sum(-np.zeros(n))) == _bits(np.sum(-np.zeros(n))), n
