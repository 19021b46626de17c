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
"""

import numpy as np

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
            ref, ref_amps, energy = 0.0, [], 0.0
            for z, h in zip(zs, hs, strict=True):
                energy += float(z @ z)
                D = np.zeros((z.size, k))
                for j, m in enumerate(ms):
                    D[m:m + h.size, j] = h
                a = np.linalg.lstsq(D, z, rcond=None)[0]
                ref += float(z @ z - (z - D @ a) @ (z - D @ a))
                ref_amps.append(a)
            assert abs(gained[i] - ref) <= TOL * energy
            scale = max(np.abs(ref_amps).max(), 1.0)
            np.testing.assert_allclose(amps[i], np.column_stack(ref_amps), rtol=0,
                                       atol=TOL * scale)
