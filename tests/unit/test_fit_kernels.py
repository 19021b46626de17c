"""The compiled kernels of bwim.detect.fit_kernels against their equations written out in
plain numpy on random cases (references, not the kernels' own code): the atoms byte for
byte (element-wise operations in the same order), the least squares, Jacobian, pursuit
trial and matcher to rounding (numpy's BLAS sums in other orders)."""

import numpy as np
from scipy.ndimage import maximum_filter1d

from bwim.detect import fit_kernels as K


def _grids(rng):
    """Two random response grids (zero at their last two ordinates each end, as the
    padded grids: no slope beyond them), their table, shifts and weights."""
    grids, steps = [], []
    for n, lo in ((61, -1.5), (47, -1.2)):
        u = np.linspace(lo, -lo, n)
        k = np.exp(-4 * np.log(2) * (u / 1.1) ** 2) * rng.uniform(0.5, 2.0)
        k[[0, 1, -2, -1]] = 0.0
        grids.append((u, k, None))
        steps.append(np.append(np.diff(k), 0.0))
    shift, w = (0.0, 3.0), np.array([0.7, 2.5])
    return grids, steps, shift, w, K.grid_table(grids, steps, shift, w)


def _atoms_numpy(grids, steps, shift, w, v, dt, c):
    """Detector c's atoms and slopes at dt: K linear between its ordinates (numpy)."""
    u, k, _ = grids[c]
    du = u[1] - u[0]
    x = (v * dt - (shift[c] + u[0])) * (1.0 / du)
    x = np.clip(x, 0.0, u.size - 1.000001)
    j = x.astype(np.intp)
    x -= j
    return (k[j] + x * steps[c][j]) * w[c], steps[c][j] * (w[c] / du)


def _case(seed=3, n=4, q=3, r=150) -> dict:
    """A random least-squares case: grids, rows' times, axles, speed, rest, readings."""
    rng = np.random.default_rng(seed)
    grids, steps, shift, w, tab = _grids(rng)
    return dict(rng=rng, grids=grids, steps=steps, shift=shift, w=w, tab=tab,
                t=np.arange(r) / 128.0, taus=np.sort(rng.uniform(0.2, 0.6, n)), v=19.0,
                rest_t=rng.standard_normal((2, q, r)), y=rng.standard_normal((2, r)))


def _atoms_of(case, dt, c, v=None):
    return _atoms_numpy(case["grids"], case["steps"], case["shift"], case["w"],
                        case["v"] if v is None else v, dt, c)


def test_atoms_are_the_linear_interpolation_byte_for_byte():
    case = _case()
    tab = case["tab"]
    dt = case["rng"].uniform(-0.4, 0.6, (1, 90, 5))
    dt[0, 0, :2] = (-1e3, 1e3)  # clipped at both ends
    out, der = np.empty((2, 90, 5)), np.empty((2, 90, 5))
    K.grid_atoms(tab.scalars, tab.first, tab.values, 21.0, dt, out, der)
    for c in range(2):
        a, s = _atoms_of(case, dt[0], c, 21.0)
        assert out[c].tobytes() == a.tobytes() and der[c].tobytes() == s.tobytes()


def _filled(case, slopes=True):
    tab, t, taus, v, rest_t, y = (case[k] for k in ("tab", "t", "taus", "v", "rest_t", "y"))
    n, q, r = taus.size, rest_t.shape[1], t.size
    arrays = dict(dtt=np.empty((n, r)), Mt=np.empty((2, n + q, r)),
                  dXt=np.empty((2, n, r)) if slopes else np.empty((0, 0, 0)),
                  Ginv=np.empty((2, n + q, n + q)), a=np.empty((2, n)), res=np.empty(2 * r))
    K.least_squares(tab.scalars, tab.first, tab.values, t, y, rest_t, taus, v, 2.0,
                    *arrays.values())
    return arrays


def test_least_squares_and_jacobian_match_numpy():
    case = _case()
    t, taus, v, rest_t, y = (case[k] for k in ("t", "taus", "v", "rest_t", "y"))
    got = _filled(case)
    n, r = taus.size, t.size
    J = np.empty((n + 1, 2 * r))
    K.jacobian(got["Mt"], got["Ginv"], got["a"], got["dXt"], got["dtt"], v, 2.0, J)
    dt = t[:, None] - taus[None, :]
    Jref = []
    for c in range(2):
        X, dX = _atoms_of(case, dt, c)
        M = np.column_stack([X, rest_t[c].T])
        G = M.T @ M
        G[np.diag_indices_from(G)] += 1e-12 * (np.trace(G) / G.shape[0] + 1e-300)
        Ginv = np.linalg.inv(G)
        coef = Ginv @ (M.T @ y[c])
        lstsq = np.linalg.lstsq(M, y[c], rcond=None)[0]
        np.testing.assert_allclose(coef, lstsq, rtol=0, atol=3e-10 * np.abs(lstsq).max())
        np.testing.assert_allclose(got["Mt"][c], M.T, rtol=0, atol=0)
        np.testing.assert_allclose(got["Ginv"][c], Ginv, rtol=2e-14,
                                   atol=2e-15 * np.abs(Ginv).max())
        np.testing.assert_allclose(got["a"][c], coef[:n], rtol=1.5e-14, atol=0)
        res = (y[c] - M @ coef) * 2.0
        np.testing.assert_allclose(got["res"][c * r:(c + 1) * r], res, rtol=0,
                                   atol=2e-15 * np.abs(y).max())
        # Kaufman: (M (MᵀM)⁻¹ Mᵀ − I) D, D the atoms' derivatives times their amplitudes
        D = np.column_stack([-v * dX * coef[:n], (dX * dt) @ coef[:n]])
        Jref.append((M @ (Ginv @ (M.T @ D)) - D) * 2.0)
    Jref = np.vstack(Jref)
    np.testing.assert_allclose(J.T, Jref, rtol=0, atol=4e-15 * np.abs(Jref).max())
    # without slopes: the same least squares
    plain = _filled(case, slopes=False)
    assert plain["res"].tobytes() == got["res"].tobytes()


def test_levenberg_marquardt_finds_the_model_s_times():
    """Readings made of the model itself (no noise): the refinement from times 3 ms off
    and a speed 2 % off returns the true ones (to its stop: the misfit falling by less
    than 0.3 % of itself; measured 1 µs, 3e-6 of the speed, a misfit 1.2e-10 of the
    readings' and amplitudes to 2.4e-6).  Tolerances elsewhere here: a few times the
    largest deviation measured on these cases under OpenBLAS's Haswell, Sandybridge,
    Nehalem, Prescott, SkylakeX and Zen kernels (rounding in other summation orders)."""
    case = _case(seed=5, n=3, q=0, r=200)
    tab, t, v = case["tab"], case["t"], case["v"]
    truth = np.array([0.30, 0.42, 0.61])
    dt = t[:, None] - truth[None, :]
    amps = np.array([[3.0, 5.0, 4.0], [2.0, 6.0, 3.5]])
    y = np.array([_atoms_of(case, dt, c)[0] @ amps[c] for c in range(2)])
    case.update(y=y, taus=truth + 0.003, v=1.02 * v)
    got = _filled(case)
    params = np.append(truth + 0.003, 1.02 * v)
    cost = K.levenberg_marquardt(tab.scalars, tab.first, tab.values, t, y, case["rest_t"],
                                 params, 15, 2.0, 3e-3, *got.values())
    np.testing.assert_allclose(params[:-1], truth, rtol=0, atol=5e-6)
    assert abs(params[-1] / v - 1) < 1.5e-5
    assert cost < 1e-9 * float(np.sum(y**2))
    np.testing.assert_allclose(got["a"], amps, rtol=1e-5)
    # what it leaves is the least squares at its result
    again = _filled({**case, "taus": params[:-1].copy(), "v": params[-1]})
    assert all(again[key].tobytes() == got[key].tobytes() for key in got)


def test_pursuit_trial_and_match_match_numpy():
    case = _case(seed=7, r=300)
    rng, tab, t, v, y = (case[k] for k in ("rng", "tab", "t", "v", "y"))
    n_t = t.size
    Q = np.array([np.linalg.qr(rng.standard_normal((n_t, 3)))[0] for _ in range(2)])
    Qt = np.ascontiguousarray(Q.transpose(0, 2, 1))
    yp = np.array([y[c] - Q[c] @ (Q[c].T @ y[c]) for c in range(2)])
    Xt, G = np.empty((2, 5, n_t)), np.empty((2, 5, 5))
    taken = [(0.5, 0.52), (1.1, 1.08)]
    for p, (tk, tk2) in enumerate(taken):
        amps, res = np.empty((p + 1, 2)), np.empty((n_t, 2))
        chi = K.pursuit_trial(tab.scalars, tab.first, tab.values, t, tk, tk2, v, Qt, yp, Xt,
                              G, p, amps, res)
    ref_chi = 0.0
    for c in range(2):
        X = np.column_stack([_atoms_of(case, t - tt[c], c)[0] for tt in taken])
        X = X - Q[c] @ (Q[c].T @ X)
        coef = np.linalg.lstsq(X, yp[c], rcond=None)[0]
        np.testing.assert_allclose(amps[:, c], coef, rtol=5e-12)
        np.testing.assert_allclose(res[:, c], yp[c] - X @ coef, rtol=0, atol=1e-12)
        np.testing.assert_allclose(G[c, :2, :2], X.T @ X, rtol=5e-15)
        ref_chi += float(np.sum((yp[c] - X @ coef) ** 2))
    assert abs(chi - ref_chi) <= 5e-15 * ref_chi
    # the matcher: correlations, the second's best within the slack, the score's argmax
    pad, slack = 40, 5
    buf = np.zeros((2, n_t + 2 * pad))
    buf[:, pad:pad + n_t] = res.T
    atoms = rng.standard_normal((2, 30))
    lo, length = np.array([-12, 3]), np.array([30, 21])
    excluded = np.zeros(n_t, dtype=bool)
    excluded[100:120] = True
    corr, picked = np.empty((2, n_t)), np.zeros(2, dtype=np.int64)
    K.best_match(buf, atoms, lo, length, pad, slack, 2.5, excluded, corr, picked)
    ref = [np.correlate(buf[c, pad + lo[c]:pad + n_t + lo[c] + length[c] - 1],
                        atoms[c, :length[c]], mode="valid") for c in range(2)]
    np.testing.assert_allclose(corr, np.array(ref), rtol=0, atol=2e-14)
    c2 = maximum_filter1d(corr[1], 2 * slack + 1, mode="constant", cval=-np.inf)
    score = np.maximum(corr[0] + c2, 0.0) ** 2 / 2.5
    score[excluded] = 0.0
    m = int(score.argmax())
    a = max(m - slack, 0)
    assert picked[0] == m and picked[1] == a + int(corr[1][a:m + slack + 1].argmax())


def test_symmetric_pinv_is_numpy_s():
    rng = np.random.default_rng(11)
    for rank in (6, 5, 3):
        B = rng.standard_normal((rank, rank)) + 3.0 * np.eye(rank)
        G = np.zeros((6, 6))  # symmetric, of that rank (exact zeros beyond)
        G[:rank, :rank] = B @ B.T
        out = np.empty((6, 6))
        K.symmetric_pinv(G, out)
        ref = np.linalg.pinv(G)
        np.testing.assert_allclose(out, ref, rtol=0, atol=4e-14 * np.abs(ref).max())
