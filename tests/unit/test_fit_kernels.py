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
                  Ginv=np.empty((2, n + q, n + q)), a=np.empty((2, n)), res=np.empty(2 * r),
                  amps=np.empty((n, 2)), gains=np.empty(n))
    K.least_squares(tab.scalars, tab.first, tab.values, t, y, rest_t, taus, v, 2.0, 4.0,
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


def _in_order(products: np.ndarray) -> float:
    """A sum from 0, one term after the other (the kernels' sums): np.add.accumulate."""
    return float(np.add.accumulate(np.concatenate(([0.0], products)))[-1])


def _lu_solve_columns(G: np.ndarray) -> np.ndarray:
    """``G``'s inverse as the kernels make it: LU with partial pivoting (the first
    largest |pivot|), then each column of the identity solved, in plain Python."""
    A = G.copy()
    p = A.shape[0]
    piv = np.zeros(p, dtype=int)
    for k in range(p):
        m = k + int(np.argmax(np.abs(A[k:, k])))
        piv[k] = m
        A[[k, m]] = A[[m, k]]
        for i in range(k + 1, p):
            f = A[i, k] / A[k, k]
            A[i, k] = f
            for j in range(k + 1, p):
                A[i, j] -= f * A[k, j]
    inv = np.empty((p, p))
    for col in range(p):
        b = np.zeros(p)
        b[col] = 1.0
        for k in range(p):
            b[[k, piv[k]]] = b[[piv[k], k]]
        for i in range(p):
            s = b[i]
            for j in range(i):
                s -= A[i, j] * b[j]
            b[i] = s
        for i in range(p - 1, -1, -1):
            s = b[i]
            for j in range(i + 1, p):
                s -= A[i, j] * b[j]
            b[i] = s / A[i, i]
        inv[:, col] = b
    return inv


def _reference(case, k=2.0, step=4.0):
    """The least squares and Jacobian with every term summed, in the kernels' orders
    (plain numpy and Python, no term left out)."""
    t, taus, v, rest_t, y = (case[key] for key in ("t", "taus", "v", "rest_t", "y"))
    n, r = taus.size, t.size
    dtt = t[None, :] - taus[:, None]
    out = dict(dtt=dtt, Mt=[], dXt=[], Ginv=[], a=[], res=[], J=[])
    for c in range(2):
        X, dX = _atoms_of(case, dtt.T, c)
        M = np.column_stack([X, rest_t[c].T])
        p = M.shape[1]
        G = np.array([[_in_order(M[:, i] * M[:, j]) for i in range(p)] for j in range(p)])
        b = np.array([_in_order(M[:, i] * y[c]) for i in range(p)])
        ridge = 1e-12 * (_in_order(np.diag(G)) / p + 1e-300)
        G[np.diag_indices(p)] += ridge
        Ginv = _lu_solve_columns(G)
        coef = np.array([_in_order(Ginv[i] * b) for i in range(p)])
        acc = np.zeros(r)
        for j in range(p):
            acc = acc + M[:, j] * coef[j]
        out["res"].append((y[c] - acc) * k)
        D = [-v * dX[:, j] * coef[j] for j in range(n)]
        dv = np.zeros(r)
        for j in range(n):
            dv = dv + dX[:, j] * dtt[j] * coef[j]
        for Dj in (*D, dv):
            E = np.array([_in_order(M[:, m] * Dj) for m in range(p)])
            F = np.array([_in_order(Ginv[i] * E) for i in range(p)])
            acc = np.zeros(r)
            for m in range(p):
                acc = acc + M[:, m] * F[m]
            out["J"].append((acc - Dj) * k)
        out["Mt"].append(M.T)
        out["dXt"].append(dX.T)
        out["Ginv"].append(Ginv)
        out["a"].append(coef[:n])
    out = {key: np.array(val) if key != "dtt" else val for key, val in out.items()}
    out["res"] = out["res"].reshape(-1)
    out["J"] = np.concatenate([out["J"][:n + 1], out["J"][n + 1:]], axis=1)
    out["amps"] = out["a"].T.copy()
    g = out["a"] ** 2 / np.maximum(out["Ginv"].diagonal(axis1=1, axis2=2)[:, :n], 1e-300)
    out["gains"] = (g[0] + g[1]) * step
    return out


def test_least_squares_and_jacobian_are_every_term_summed_in_order():
    """The kernels leave out the terms of the atoms' zeros (rows beyond a response's
    reach: :func:`~bwim.detect.fit_kernels.zero_reach`): byte for byte the numbers of
    every term summed in their order (plain numpy), on windows the atoms cover, where they
    cover a few rows (r = 400), without the rest, and with the rows' times descending
    (nothing left out then)."""
    for seed, r, q, order in ((3, 150, 3, 1), (5, 400, 3, 1), (6, 400, 0, 1), (8, 300, 2, -1)):
        case = _case(seed=seed, q=q, r=r)
        case["t"] = np.ascontiguousarray(case["t"][::order])
        got = _filled(case)
        ref = _reference(case)
        for key in ("dtt", "Mt", "dXt", "Ginv", "a", "res", "amps", "gains"):
            assert got[key].tobytes() == ref[key].tobytes(), (seed, key)
        J = np.empty((case["taus"].size + 1, 2 * r))
        K.jacobian(got["Mt"], got["Ginv"], got["a"], got["dXt"], got["dtt"], case["v"], 2.0,
                   J)
        assert J.tobytes() == ref["J"].tobytes(), seed
        # what is left out: the atoms' zero rows (some where r = 400)
        flat = np.empty((2, 2), dtype=np.int64)
        fast = K.zero_reach(case["tab"].scalars, case["tab"].first, case["tab"].values,
                            case["t"], case["y"], case["rest_t"], flat)
        assert fast == (order == 1)
        if r == 400:
            assert np.mean(got["Mt"][:, :case["taus"].size] == 0.0) > 0.8


def test_span_dots_leave_out_only_zero_terms():
    """``span_dots`` summing only where both factors may be nonzero: the sums of every
    term in order, byte for byte (rows with spans of their own, empty ones, −0 values)."""
    rng = np.random.default_rng(12)
    r, na = 90, 15  # rows eight, four and one at a time
    A = np.zeros((na, r))
    lo = rng.integers(0, r, na)
    hi = np.minimum(lo + rng.integers(0, 40, na), r)
    lo[3], hi[3] = 0, 0  # a row of zeros
    lo[[0, 9, 13]], hi[[0, 9, 13]] = 0, r  # rows reaching past b's span
    for i in range(na):
        A[i, lo[i]:hi[i]] = rng.standard_normal(hi[i] - lo[i])
    A[5, :lo[5]] = -0.0
    b = np.zeros(r)
    b[20:70] = rng.standard_normal(50)
    out = np.empty(na)
    K.span_dots(A, na, b, 20, 70, lo.astype(np.int64), hi.astype(np.int64), out)
    ref = np.array([_in_order(A[i] * b) for i in range(na)])
    assert out.tobytes() == ref.tobytes()


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
    # the least squares at the start made by the kernel itself (fresh): the same run
    fresh = {key: np.empty_like(val) for key, val in got.items()}
    params_fresh = params.copy()
    cost_fresh = K.levenberg_marquardt(tab.scalars, tab.first, tab.values, t, y,
                                       case["rest_t"], params_fresh, 15, 2.0, 3e-3, 4.0, True,
                                       *fresh.values())
    cost = K.levenberg_marquardt(tab.scalars, tab.first, tab.values, t, y, case["rest_t"],
                                 params, 15, 2.0, 3e-3, 4.0, False, *got.values())
    assert cost_fresh == cost and params_fresh.tobytes() == params.tobytes()
    assert all(fresh[key].tobytes() == got[key].tobytes() for key in got)
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


def test_gram_and_inverse_are_the_plain_loops():
    """The refinement's Gram matrix (rows four by four) is every sum in its order, and the
    least squares' inverse (all columns at once) is each column of the identity solved
    with the LU factors (in plain Python), byte for byte; sizes around the blocks'."""
    rng = np.random.default_rng(21)
    for n in (1, 3, 4, 5, 8, 11, 30):
        A = rng.standard_normal((n, 57))
        G = np.empty((n, n))
        K._gram(A, n, G)
        ref = np.array([[_in_order(A[i] * A[j]) for i in range(n)] for j in range(n)])
        assert G.tobytes() == ref.tobytes()
        S = ref + n * np.eye(n)
        LU, piv = S.copy(), np.empty(n, dtype=np.int64)
        assert K._lu(LU, piv)
        inv = np.empty((n, n))
        K._inverse_columns(LU, piv, inv)
        assert inv.tobytes() == _lu_solve_columns(S).tobytes()


def test_matcher_atoms_are_numpys_interp():
    """The matcher's atoms (``matcher_atom``) are ``np.interp(v m / fs − d, u, k,
    left=0, right=0) × scale`` byte for byte: uneven and even grids, zero ends, samples
    beyond both ends of the grid."""
    import math

    rng = np.random.default_rng(13)
    for trial in range(200):
        n = int(rng.integers(2, 300))
        u = np.linspace(-2.5, 2.7, n) if trial % 3 == 0 else np.sort(rng.uniform(-3, 3, n))
        k = rng.standard_normal(n)
        k[:3], k[-3:] = 0.0, 0.0
        v, fs = rng.uniform(5.0, 40.0), float(rng.choice([256.0, 512.0, 1000.0]))
        d, scale = float(rng.choice([0.0, 3.1])), rng.uniform(0.1, 3.0)
        m_lo = math.floor((u[0] + d) / v * fs) - 1 - int(rng.integers(0, 3))
        m_hi = math.ceil((u[-1] + d) / v * fs) + 1 + int(rng.integers(0, 3))
        ref = np.interp(v * np.arange(m_lo, m_hi + 1) / fs - d, u, k, left=0.0,
                        right=0.0) * scale
        out = np.empty(m_hi - m_lo + 1)
        K.matcher_atom(u, k, scale, v, fs, d, m_lo, out)
        assert out.tobytes() == ref.tobytes()
