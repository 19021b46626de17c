"""Assembly from unit matrices equals a naive re-integrated assembly; modes are
mass-normalised; parameters rebuild K without re-integration."""

import numpy as np
import pytest
import scipy.linalg as sla

import bwim
from bwim.fe.plate import hermite


def _naive_bfs(a, b, Dx, Dy, nu, mu, n_gauss=5):
    """K_e, M_e by direct 2-D Gauss quadrature of Bᵀ D B and μ Nᵀ N (no unit matrices)."""
    s, w = np.polynomial.legendre.leggauss(n_gauss)
    s, w = 0.5 * (s + 1), 0.5 * w
    D1, Dxy = nu * np.sqrt(Dx * Dy), (1 - nu) * np.sqrt(Dx * Dy) / 2
    D = np.array([[Dx, D1, 0], [D1, Dy, 0], [0, 0, Dxy]])
    K = np.zeros((16, 16))
    M = np.zeros((16, 16))
    for si, wi in zip(s, w, strict=True):
        for sj, wj in zip(s, w, strict=True):
            hx, dhx, d2hx = (v[0] for v in hermite(np.array([si]), a))
            hy, dhy, d2hy = (v[0] for v in hermite(np.array([sj]), b))
            N = np.outer(hx, hy).ravel()
            B = np.stack([-np.outer(d2hx, hy).ravel(), -np.outer(hx, d2hy).ravel(),
                          -2 * np.outer(dhx, dhy).ravel()])
            K += wi * wj * a * b * B.T @ D @ B
            M += wi * wj * a * b * mu * np.outer(N, N)
    return K, M


def _bridge(**kw):
    base = dict(length=6.0, width=4.0, nx=6, ny=4, thickness=0.4, E_x=30e9, E_y=22e9,
                mu=960.0, poisson=0.25, zones=(2, 2))
    base.update(kw)
    return bwim.Bridge.plate(**base)


def test_banded_and_sparse_match_naive_assembly(rng):
    bridge = _bridge().with_params(E_x=rng.uniform(20e9, 40e9, 4), E_y=rng.uniform(20e9, 40e9, 4),
                                   mu=rng.uniform(800, 1200, 4))
    model = bridge.model
    g = model.grid
    n = g.n_dof
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    a, b = g.element_sizes()
    h, nu = model.thickness, model.poisson
    for e, dofs in enumerate(g.element_dofs()):
        z = model.zone_of_element[e]
        Dx = bridge.E_x[z] * h**3 / (12 * (1 - nu**2))
        Dy = bridge.E_y[z] * h**3 / (12 * (1 - nu**2))
        ke, me = _naive_bfs(a[e], b[e], Dx, Dy, nu, bridge.mu[z])
        K[np.ix_(dofs, dofs)] += ke
        M[np.ix_(dofs, dofs)] += me
    free = model.assembler.free
    K, M = K[np.ix_(free, free)], M[np.ix_(free, free)]
    np.testing.assert_allclose(bridge.stiffness_matrix().toarray(), K, rtol=1e-10,
                               atol=1e-10 * abs(K).max())
    np.testing.assert_allclose(bridge.mass_matrix().toarray(), M, rtol=1e-10,
                               atol=1e-12 * abs(M).max())
    ab = bridge.stiffness_banded()
    bw = ab.shape[0] - 1
    dense_from_band = np.zeros_like(K)
    for d in range(bw + 1):
        idx = np.arange(K.shape[0] - d)
        dense_from_band[idx + d, idx] = ab[d, : K.shape[0] - d]
    np.testing.assert_allclose(np.tril(dense_from_band), np.tril(K), atol=1e-10 * abs(K).max())
    assert np.all(np.triu(K, bw + 1) == 0)  # the band holds all of K


def test_numbering_across_short_side_keeps_band_narrow():
    long = bwim.Bridge.plate(length=24.0, width=8.0, nx=24, ny=8, thickness=0.5, E=3e10, mu=1e3)
    wide = bwim.Bridge.plate(length=8.0, width=24.0, nx=8, ny=24, thickness=0.5, E=3e10, mu=1e3)
    # an element spans (nodes across + 1) node numbers: 4 DOF each, plus 3 within the node
    assert long.model.grid.across_first and not wide.model.grid.across_first
    assert long.model.assembler.bandwidth <= 4 * (9 + 1) + 3
    assert wide.model.assembler.bandwidth <= 4 * (9 + 1) + 3


def test_modes_mass_normalised_and_match_dense_eigh():
    bridge = _bridge(nx=12, ny=8)
    m = bridge.modes(8)
    M = bridge.mass_matrix().toarray()
    K = bridge.stiffness_matrix().toarray()
    np.testing.assert_allclose(m.shapes.T @ M @ m.shapes, np.eye(8), atol=1e-9)
    np.testing.assert_allclose(m.shapes.T @ K @ m.shapes, np.diag(m.omega**2), rtol=1e-8,
                               atol=1e-6 * m.omega[-1] ** 2)
    ref = np.sqrt(sla.eigh(K, M, eigvals_only=True, subset_by_index=[0, 7])) / (2 * np.pi)
    np.testing.assert_allclose(m.frequencies, ref, rtol=1e-9)
    assert np.all(np.diff(m.frequencies) >= 0)


def test_with_params_shares_model_and_scales_stiffness():
    bridge = _bridge()
    stiffer = bridge.with_params(E_x=2 * bridge.E_x, E_y=2 * bridge.E_y)
    assert stiffer.model is bridge.model
    np.testing.assert_allclose(stiffer.stiffness_matrix().toarray(),
                               2 * bridge.stiffness_matrix().toarray(), rtol=1e-12)
    # frequencies scale with sqrt(E / mu)
    heavier = stiffer.with_params(mu=2 * bridge.mu)
    np.testing.assert_allclose(heavier.modes(4).frequencies, bridge.modes(4).frequencies,
                               rtol=1e-9)
    assert set(bridge.params) == {"E_x", "E_y", "mu"}
    assert bridge.params["E_x"].shape == (4,)


def test_rayleigh_damping_hits_ratio_at_first_two_modes():
    bridge = _bridge(damping_ratio=0.03)
    w = bridge.modes(3).omega
    ratios = bridge.rayleigh.ratio(w)
    np.testing.assert_allclose(ratios[:2], 0.03, rtol=1e-12)
    assert ratios[2] > 0.03  # stiffness-proportional part grows with frequency
    C = bridge.damping_matrix()
    r = bridge.rayleigh
    np.testing.assert_allclose(
        C.toarray(), r.alpha * bridge.mass_matrix().toarray()
        + r.beta * bridge.stiffness_matrix().toarray())


def test_clamped_stiffer_than_simple():
    load = [bwim.PointLoad(x=3.0, y=2.0, P=1e4)]
    s = [bwim.Sensor(x=3.0, y=2.0, kind="deflection")]
    simple = _bridge(supports="ss-all").static(load, s)[0]
    clamped = _bridge(supports={"x0": "clamped", "x_end": "clamped", "y0": "clamped",
                                "y_end": "clamped"}).static(load, s)[0]
    free_edges = _bridge(supports="ss-free").static(load, s)[0]
    assert 0 < clamped < simple < free_edges


def test_non_uniform_grid_through_required_lines():
    lines = bwim.grid_lines(12.07, 10, through=[1.035, 11.035])
    assert lines.size == 11 and lines[0] == 0 and lines[-1] == pytest.approx(12.07)
    assert np.any(np.isclose(lines, 1.035)) and np.any(np.isclose(lines, 11.035))
    np.testing.assert_allclose(np.diff(lines)[1:-1], 10.0 / 8)


@pytest.mark.parametrize("c", [0.7, 1.3])
def test_scaled_modes_are_the_modes_of_a_uniformly_scaled_mass(c):
    """Reference: eigsh on the bridge with every μ × c.  K φ = ω² c M φ has the
    eigenvectors of K φ = ω² M φ with ω'² = ω²/c; Φ'ᵀ (cM) Φ' = I gives Φ' = Φ/√c
    (fe/modal.py docstring).  Agreement to the eigensolver's round-off (measured:
    1e-15 in ω, 1e-14 in Φ)."""
    from bwim.fe.modal import scaled_modes

    bridge = _bridge(nx=12, ny=8)
    heavier = bridge.with_params(mu=c * bridge.mu)
    ref = heavier.modes(8)
    got = scaled_modes(bridge.modes(8), c)
    np.testing.assert_allclose(got.omega, ref.omega, rtol=1e-14)
    np.testing.assert_allclose(got.frequencies, ref.frequencies, rtol=1e-14)
    scale = np.abs(ref.shapes).max()
    np.testing.assert_allclose(got.shapes, ref.shapes, rtol=0, atol=1e-13 * scale)
    M = heavier.mass_matrix()
    np.testing.assert_allclose(got.shapes.T @ (M @ got.shapes), np.eye(8), atol=1e-12)
