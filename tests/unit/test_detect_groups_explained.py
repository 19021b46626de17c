"""The axle groups' hypotheses (:func:`bwim.detect.groups.explained`, both detectors'
systems solved as one stack since issue 21 item 6) against explicit least squares.

Reference (closed form): for axles at grid points ``m_1 … m_k`` with one response ``h``
each, the misfit that least squares removes from a signal ``z`` is ``‖z‖² − ‖z − D a‖²``
with ``D`` the shifted responses and ``a`` their least-squares amplitudes (here by
``numpy.linalg.lstsq``), per detector, summed over both.  ``explained`` gets it from the
correlations ``Dᵀz`` and the response's autocorrelation alone (with a ridge of 1e-12 of
the zero lag, which moves close axles' amplitudes by about 1e-12): measured agreement
9.4e-13 of the signals' energy for the misfits and 1.25e-12 of the largest amplitude
for the amplitudes (tolerance 5e-12 for both).

The counts chosen for every segment at once (:func:`~bwim.detect.groups.evenly_explained`,
:func:`~bwim.detect.groups.group_counts`, issue 21 item 6: speed) against the same explicit
least squares and against the plain per-segment loop of their definition."""

import numpy as np
import pytest

from bwim.detect.groups import explained, hypotheses

TOL = 5e-12  # of the signals' energy (misfits) or the largest amplitude; see the docstring


def test_explained_is_the_explicit_least_squares():
    rng = np.random.default_rng(5)
    n = 200
    hs = [np.exp(-0.5 * ((np.arange(31) - 15) / 5.0) ** 2),  # two detectors' responses
          1.3 * np.exp(-0.5 * ((np.arange(25) - 12) / 4.0) ** 2)]
    truth = [(40, 1.0), (58, 0.8), (76, 0.9)]
    zs = []
    for h in hs:
        z = 0.05 * rng.standard_normal(n + h.size)
        for m, a in truth:
            z[m:m + h.size] += a * h
        zs.append(z)
    corr = [np.correlate(z, h, mode="valid")[:n] for z, h in zip(zs, hs, strict=True)]
    auto = [np.concatenate([np.correlate(h, h, mode="full")[h.size - 1:], np.zeros(n)])
            for h in hs]
    for k in (1, 2, 3, 4):
        hyp = hypotheses(20, 120, k, 10, 25)[::7]
        gained, amps = explained(hyp, corr, auto)
        assert gained.shape == (hyp.shape[0],) and amps.shape == (*hyp.shape, 2)
        for i, ms in enumerate(hyp):
            _check_against_lstsq(ms, zs, hs, gained[i], amps[i])


def _check_against_lstsq(ms, zs, hs, gained, amps):
    """One hypothesis (axles at samples ``ms``) against explicit least squares
    (``numpy.linalg.lstsq`` on the shifted responses ``hs``) of the readings ``zs``, one
    per detector: the misfit removed within TOL of the energy, the amplitudes within TOL
    of the largest."""
    ref, ref_amps, energy = 0.0, [], 0.0
    for z, h in zip(zs, hs, strict=True):
        energy += float(z @ z)
        D = np.zeros((z.size, len(ms)))
        for j, m in enumerate(ms):
            D[m:m + h.size, j] = h
        a = np.linalg.lstsq(D, z, rcond=None)[0]
        ref += float(z @ z - (z - D @ a) @ (z - D @ a))
        ref_amps.append(a)
    assert abs(gained - ref) <= TOL * energy
    scale = max(np.abs(ref_amps).max(), 1.0)
    np.testing.assert_allclose(amps, np.column_stack(ref_amps), rtol=0, atol=TOL * scale)


def test_evenly_spaced_hypotheses_of_many_segments_at_once():
    """:func:`evenly_explained` (each spacing's system inverted once, every segment's
    hypotheses at once) against explicit least squares (``numpy.linalg.lstsq`` on the
    shifted responses) of each hypothesis of each segment, k = 2, 3, 4, and it makes
    exactly :func:`hypotheses` of each segment, in that order; a segment too short for k
    axles has none.  Tolerance as above (measured: 1.6e-13 of the energy for the misfits,
    5.2e-13 of the largest amplitude)."""
    from bwim.detect.groups import evenly_explained

    rng = np.random.default_rng(8)
    hs = [np.exp(-0.5 * ((np.arange(31) - 15) / 5.0) ** 2),
          1.3 * np.exp(-0.5 * ((np.arange(25) - 12) / 4.0) ** 2)]
    lengths = np.array([60, 9, 45])  # grid points of each segment (the second: short)
    s_min, s_max = 10, 25
    signals = [[0.05 * rng.standard_normal(n + h.size) for n in lengths] for h in hs]
    for c, h in enumerate(hs):  # axles in the first and last segments
        for z, axles in zip(signals[c], ([(5, 1.0), (20, 0.7)], [], [(3, 0.9), (30, 0.6)]),
                            strict=True):
            for m, a in axles:
                z[m:m + h.size] += a * h
    corr = [np.concatenate([np.correlate(z, h, mode="valid")[:n]
                            for z, n in zip(signals[c], lengths, strict=True)])
            for c, h in enumerate(hs)]
    auto = [np.concatenate([np.correlate(h, h, mode="full")[h.size - 1:], np.zeros(200)])
            for h in hs]
    for k in (2, 3, 4):
        hyp, owner, gained, amps = evenly_explained(lengths, k, s_min, s_max, corr, auto)
        for seg, n in enumerate(lengths):
            mine = hyp[owner == seg]
            np.testing.assert_array_equal(mine, hypotheses(0, n - 1, k, s_min, s_max))
        assert np.all(np.diff(owner) >= 0) and not np.any(owner == 1)
        for i, (ms, seg) in enumerate(zip(hyp, owner, strict=True)):
            _check_against_lstsq(ms, [signals[c][seg] for c in range(len(hs))], hs,
                                 gained[i], amps[i])


def _counts_loop(ref, corr, auto, lengths, outside, energies, limit, n_samples, s_min,
                 s_max):
    """The choice of :func:`bwim.detect.groups.group_counts` as a plain loop over the
    segments and counts with :func:`hypotheses` and :func:`explained` (its first form,
    one segment and one count at a time): the reference."""
    from bwim.detect.groups import GROUP_AXLES, LEVEL_GAIN, RARE_GROUP

    out, off = [], 0
    for n, outer, energy in zip(lengths, outside, energies, strict=True):
        seg = [corr[0][off:off + n], corr[1][off:off + n]]
        off += n
        best = None
        for k in range(1, GROUP_AXLES + 1):
            hyp = hypotheses(0, n - 1, k, s_min, s_max)
            if hyp.shape[0] == 0:
                break
            gained, amps = explained(hyp, seg, auto)
            positive = np.all(amps > 0, axis=(1, 2))
            with np.errstate(divide="ignore", invalid="ignore"):
                lr = np.log(amps[..., 1] / (ref.ratio * amps[..., 0]))
            valid = positive & np.all(np.abs(np.where(positive[:, None], lr, np.inf))
                                      <= ref.bound, axis=1)
            if not valid.any():
                break
            j = int(np.argmax(np.where(valid, gained, -np.inf)))
            if best is not None:
                gain = gained[j] - best[0]
                level = (outer + (energy - best[0])) / n_samples
                rare = RARE_GROUP if k > 3 else 1.0
                if gain < limit or gain < LEVEL_GAIN * rare * level:
                    break
            best = (float(gained[j]), hyp[j])
        out.append(best)
    return out


def test_group_counts_equal_their_loop_definition():
    """Every segment's axle count chosen at once (:func:`group_counts`) equals the plain
    loop of its definition, one segment and one count at a time: the same grid points
    chosen (exactly) with the same misfit removed (to rounding, 1e-9), on segments of
    one to four axles 1.0-1.8 response widths apart, of noise, and too short for two,
    with thresholds from none to prohibitive; each count (none, 1 … 4) is chosen.  And a
    fourth axle whose gain lies between the level and RARE_GROUP times it is not."""
    from types import SimpleNamespace

    from bwim.detect.groups import group_counts

    rng = np.random.default_rng(21)
    hs = [np.exp(-0.5 * ((np.arange(31) - 15) / 5.0) ** 2),
          0.3 * np.exp(-0.5 * ((np.arange(25) - 12) / 4.0) ** 2)]
    auto = [np.concatenate([np.correlate(h, h, mode="full")[h.size - 1:], np.zeros(200)])
            for h in hs]
    s_min, s_max = 8, 20
    chosen = set()
    for trial in range(40):
        lengths, corr = [], ([], [])
        for n_axles in (0, 1, 2, 3, 4, 2):
            n = 7 if trial % 4 == 3 and n_axles == 2 else int(rng.integers(50, 90))
            spacing = int(rng.integers(10, 18))
            for c, h in enumerate(hs):
                z = 0.02 * rng.standard_normal(n + h.size)
                for i in range(n_axles if n > 7 else 0):
                    m = 4 + i * spacing
                    if m + h.size <= z.size:
                        z[m:m + h.size] += rng.uniform(0.6, 1.0) * h
                corr[c].append(np.correlate(z, h, mode="valid")[:n])
            lengths.append(n)
        corr = [np.concatenate(corr[0]), np.concatenate(corr[1])]
        lengths = np.array(lengths)
        outside = list(rng.uniform(0.0, 2.0, lengths.size))
        energies = list(rng.uniform(5.0, 30.0, lengths.size))
        ref = SimpleNamespace(ratio=0.3, bound=(0.4, 3.0)[trial % 2])
        limit = (0.0, 0.05, 0.5, 1e3)[trial % 4]
        n_samples = int(np.exp(rng.uniform(np.log(100), np.log(5000))))
        mine = group_counts(ref, corr, auto, lengths, outside, energies, limit, n_samples,
                            s_min, s_max)
        expect = _counts_loop(ref, corr, auto, lengths, outside, energies, limit,
                              n_samples, s_min, s_max)
        for a, b in zip(mine, expect, strict=True):
            assert (a is None) == (b is None)
            if a is not None:
                np.testing.assert_array_equal(a[1], b[1])
                assert a[0] == pytest.approx(b[0], rel=1e-9)
            chosen.add(0 if a is None else a[1].size)
    assert chosen == {0, 1, 2, 3, 4}
    # a fourth axle that passes the level but not the rarer fourth's (1.25 x the level:
    # between 1 and RARE_GROUP): three chosen
    from bwim.detect.groups import LEVEL_GAIN, RARE_GROUP

    assert 1.25 < RARE_GROUP
    z = [0.02 * rng.standard_normal(80 + h.size) for h in hs]
    for c, h in enumerate(hs):
        for i in range(4):
            z[c][4 + 14 * i:4 + 14 * i + h.size] += (1.0, 0.9, 0.9, 0.5)[i] * h
    corr = [np.correlate(z[c], h, mode="valid")[:80] for c, h in enumerate(hs)]
    ref = SimpleNamespace(ratio=0.3, bound=3.0)
    free = _counts_loop(ref, corr, auto, [80], [1.0], [20.0], 0.0, 10**12, s_min, s_max)[0]
    three = explained(free[1][None, :3], corr, auto)[0][0]
    n_samples = LEVEL_GAIN * 1.25 * (1.0 + 20.0 - three) / (free[0] - three)
    got = group_counts(ref, corr, auto, np.array([80]), [1.0], [20.0], 0.0, n_samples,
                       s_min, s_max)[0]
    assert free[1].size == 4 and got[1].size == 3
