"""The L-curve's λ search and the stacked sweep it runs (issue 23, item 2).

References: the corner rule applied on a dense log grid of the same model (the search
must find that corner within its fine spacing), and a fresh sweep at the chosen λ (the
search's answer is the trajectory of a λ it solved).
"""

import dataclasses

import numpy as np
import pytest

import bwim
from bwim.errors import InputError
from bwim.limits import ENV_VAR
from bwim.mfi import build_model, identify_forces
from bwim.mfi.dp import sweep, sweep_bytes
from bwim.mfi.lcurve import CoarseProblem, _corner, _lowest_admissible, lcurve_search
from bwim.mfi.statespace import ForceUnknowns, Order

LAM_RANGE = (1e-6, 1e3)


@pytest.fixture(scope="module")
def crossing():
    """Two axle forces crossing a 10 m beam at 12 m/s, three strain sensors, 1 kHz."""
    beam = bwim.Bridge.beam(length=10.0, n_elements=10, E=3e10, I=0.5, mu=5e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x) for x in (2.5, 5.0, 7.5)]
    rec = bwim.simulate(beam, bwim.MovingForces(axle_loads=[5e4, 8e4], axle_spacings=[3.0]),
                        speed=12.0, sensors=sensors, sampling_rate=1000.0, approach=0.0)
    return beam, rec


def _axle_model(crossing):
    """The crossing's first-order, per-axle model (3 modes) and its scaled readings."""
    beam, rec = crossing
    scale = float(np.abs(rec.data).max())
    model = build_model(beam, beam.modes(3), rec, scale, unknowns=ForceUnknowns.AXLE,
                        order=Order.FIRST)
    return model, rec.data / scale


def _dense_corner(beam, rec, ident):
    """log λ (scaled) of the corner rule (maximum spline curvature among admissible λ)
    on a grid of 73 λ over the range (eight per decade) of the record's model."""
    scale = float(np.abs(rec.data).max())
    model = build_model(beam, beam.modes(ident.n_modes), rec, scale,
                        unknowns=ForceUnknowns.AXLE, order=Order.FIRST)
    t = np.linspace(np.log(LAM_RANGE[0]), np.log(LAM_RANGE[1]), 73)
    sw = sweep(model, rec.data / scale, np.exp(t), keep_forces=True)
    weighed = np.stack([(rec.time >= lo) & (rec.time <= hi) for lo, hi in ident.axle_windows],
                       axis=1)
    ok = np.all((sw.forces > 0) | ~weighed[None], axis=(1, 2))
    return _corner(t, sw.residual_norm, sw.seminorm, _lowest_admissible(t, ok))[1], model


@pytest.mark.parametrize(("noise", "seed"), [(0.0, 0), (0.05, 3), (0.05, 5)])
def test_search_finds_the_dense_grid_corner(crossing, noise, seed):
    """identify_forces' two-pass search (bracket on every 4th sample; this model has at
    most 3 modes, so its fine grid is 17 λ over two coarse spacings either side) lands
    within one fine spacing (0.29 decade) of the dense grid's corner: half a spacing from
    snapping to a solved λ, plus the grid dependence of the spline and of the
    admissibility bound.  Measured: 0.09 (clean), 0.25 (seed 3) and 0.13 decade (seed 5)."""
    beam, rec = crossing
    rec = rec.with_noise(noise, seed=seed) if noise else rec
    ident = identify_forces(beam, rec)
    t_dense, _ = _dense_corner(beam, rec, ident)
    assert abs(np.log10(ident.lam_scaled) - t_dense / np.log(10)) < 0.3


def test_search_recovers_from_a_wrong_bracket(crossing):
    """A coarse problem whose corner is two decades off (the same model with its data
    weighted 100×: its corner moves by that factor) leaves the corner outside the first
    fine window; the search extends the fine grid until it brackets the model's corner.
    Measured: 0.19 decade from the dense corner (one fine spacing is 0.29) after one
    extension."""
    beam, rec = crossing
    rec = rec.with_noise(0.05, seed=3)
    ident = identify_forces(beam, rec)
    t_dense, model = _dense_corner(beam, rec, ident)
    d = rec.data / float(np.abs(rec.data).max())
    wrong = CoarseProblem(model=model, d=d, weights=100.0 * np.ones(model.n_s))
    search = lcurve_search(model, d, np.ones(model.n_s), LAM_RANGE, coarse=wrong)
    assert search.curve.lam.size > 8  # extended
    assert abs(np.log10(search.curve.corner_scaled) - t_dense / np.log(10)) < 0.3


def test_chosen_lambda_is_solved_not_reused(crossing):
    """The L-curve's forces are those of a fresh sweep at the chosen λ (the search returns
    the kept trajectory of that λ, not a neighbour's): equal to round-off."""
    beam, rec = crossing
    rec = rec.with_noise(0.05, seed=5)
    ident = identify_forces(beam, rec)
    fixed = identify_forces(beam, rec, lam=ident.lam, n_modes=ident.n_modes)
    assert ident.lam_scaled == pytest.approx(fixed.lam_scaled, rel=1e-12)
    np.testing.assert_allclose(ident.axle_forces, fixed.axle_forces, rtol=0,
                               atol=1e-9 * np.abs(fixed.axle_forces).max())
    np.testing.assert_allclose(ident.fitted, fixed.fitted, rtol=0,
                               atol=1e-9 * np.abs(fixed.fitted).max())


def test_sweep_splits_lambdas_by_the_memory_limit(crossing, monkeypatch):
    """With a memory limit that holds two λ at a time the sweep runs in three chunks for
    five λ and gives the same answers as in one chunk (to round-off: measured 8e-16
    in X, 6e-14 in ρ, relative); a limit below one λ is refused."""
    from bwim.mfi import dp

    model, d = _axle_model(crossing)
    lams = np.geomspace(1e-3, 10.0, 5)
    whole = sweep(model, d, lams, keep=True)
    chunks = []
    inner = dp._sweep_chunk

    def counted(model, lams, *args):
        chunks.append(lams.size)
        return inner(model, lams, *args)

    monkeypatch.setattr(dp, "_sweep_chunk", counted)
    limit = sweep_bytes(model, 2, keep=True) / dp.SWEEP_MEMORY_SHARE * 1.001
    monkeypatch.setenv(ENV_VAR, str(int(limit)))
    parts = sweep(model, d, lams, keep=True)
    assert chunks == [2, 2, 1]
    # round-off only (the batched products may take other paths for other batch sizes)
    np.testing.assert_allclose(parts.residual_norm, whole.residual_norm, rtol=1e-12)
    np.testing.assert_allclose(parts.X, whole.X, rtol=0, atol=1e-10 * np.abs(whole.X).max())
    monkeypatch.setenv(ENV_VAR, str(int(0.5 * sweep_bytes(model, 1, keep=True))))
    with pytest.raises(InputError, match="memory"):
        sweep(model, d, lams, keep=True)


def test_kept_trajectories_and_the_searchs_copy(crossing):
    """A one-chunk sweep hands out its trajectories as views of the pass's arrays, in λ
    order: each equals a fresh one-λ sweep at that λ (reference; round-off only, measured
    5e-15 of the peak state).  The search's solution is a contiguous copy of the chosen
    λ's trajectory, not a view that would keep every λ's arrays alive."""
    from bwim.mfi.lcurve import _solution

    model, d = _axle_model(crossing)
    lams = np.geomspace(1e-3, 10.0, 4)
    sw = sweep(model, d, lams, keep=True)
    peak = np.abs(sw.X).max()
    for i, lam in enumerate(lams):
        one = sweep(model, d, [lam], keep=True)
        np.testing.assert_allclose(sw.X[i], one.X[0], rtol=0, atol=5e-14 * peak)
        np.testing.assert_allclose(sw.r[i], one.r[0], rtol=0, atol=5e-14 * peak)
    sol = _solution(sw, 2)
    assert sol.X.flags.c_contiguous and not np.shares_memory(sol.X, sw.X)
    assert not np.shares_memory(sol.r, sw.r)
    np.testing.assert_array_equal(sol.X, sw.X[2])


def _six_mode_search(crossing, admissible=None, **kw):
    """lcurve_search on the crossing's 6-mode model (more than SMALL_MODEL_MODES: one fine
    window of 8 λ) bracketed on every 4th sample with 2 modes, 5 % noise; ``admissible``
    restricts the corner on the model only."""
    beam, rec = crossing
    rec = rec.with_noise(0.05, seed=3)
    scale = float(np.abs(rec.data).max())
    opts = {"unknowns": ForceUnknowns.AXLE, "order": Order.FIRST}
    model = build_model(beam, beam.modes(6), rec, scale, **opts)
    sub = dataclasses.replace(rec, time=rec.time[::4], data=rec.data[::4], truths=())
    coarse = CoarseProblem(model=build_model(beam, beam.modes(2), sub, scale, **opts),
                           d=sub.data / scale, weights=np.ones(model.n_s))
    d, w = rec.data / scale, np.ones(model.n_s)
    return (lcurve_search(model, d, w, LAM_RANGE, coarse=coarse, admissible=admissible, **kw),
            model, d, rec)


def _mean_forces(forces):
    """A stand-in for the static weights: each force's mean over the record."""
    return forces.mean(axis=1)


def test_search_without_flat_weights_is_the_full_fine_grid(crossing):
    """When the half grid's static weights disagree (``flat_tol=0``), the search solves the
    rest of the fine grid and gives the full grid's answer: the same λ (to round-off) and
    trajectory as the search without ``weigh`` (reference; round-off only, measured
    0 and 4e-16 of the peak state)."""
    full, _, _, _ = _six_mode_search(crossing)
    both, _, _, _ = _six_mode_search(crossing, weigh=_mean_forces, flat_tol=0.0)
    assert both.curve.corner_scaled == pytest.approx(full.curve.corner_scaled, rel=1e-12)
    np.testing.assert_allclose(both.curve.lam_scaled, full.curve.lam_scaled, rtol=1e-12)
    np.testing.assert_allclose(both.solution.X, full.solution.X, rtol=0,
                               atol=1e-12 * np.abs(full.solution.X).max())


def test_search_with_flat_weights_solves_every_other_fine_lambda(crossing):
    """When they agree (``flat_tol=inf``), only every other λ of the full fine grid is
    solved (the reference: the full search's grid, minus its extensions), plus
    extensions at twice its spacing; the answer is a solved λ within half that spacing of
    the corner located on them, and a fresh sweep there gives its trajectory."""
    full, model, d, _ = _six_mode_search(crossing)
    half, _, _, _ = _six_mode_search(crossing, weigh=_mean_forces, flat_tol=np.inf)
    t_full = np.log(full.curve.lam_scaled)
    t_half = np.log(half.curve.lam_scaled)
    h = np.diff(t_full).min()
    assert t_half.size < t_full.size
    # every half-grid λ is a full-grid node or an extension at twice the spacing
    steps = (t_half - t_full[1]) / (2 * h)
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    chosen = np.log(half.curve.corner_scaled)
    assert np.min(np.abs(t_half - chosen)) < 1e-9
    fresh = sweep(model, d, [half.curve.corner_scaled], keep=True)
    np.testing.assert_allclose(half.solution.X, fresh.X[0], rtol=0,
                               atol=1e-9 * np.abs(fresh.X).max())


def test_clean_record_weights_do_not_hang_on_the_half_grid(monkeypatch):
    """identify_forces on a clean 2 s crossing of the paper slab (its own 12 × 8 model, 18
    modes): the static weights agree within 0.01 % over the half fine grid, so only it is
    solved; the weights are those of the full fine grid's answer (reference: the same
    search without ``weigh``) within 0.01 % of the largest (measured 1.5e-4 %), though
    the chosen λ differs (measured 0.86 decade)."""
    from bwim import paper
    from bwim.mfi import identify as ident_mod

    bridge = paper.slab_bridge()
    truck = paper.truck()
    rec = bwim.simulate(bridge, truck, speed=(bridge.length + truck.length) / 2.0,
                        lane=paper.LANE, sensors=paper.sensors(), road=paper.road(1),
                        sampling_rate=1000.0, approach=20.0)
    half = identify_forces(bridge, rec)
    inner = ident_mod.lcurve_search

    def full_grid(*args, **kw):
        return inner(*args, **{**kw, "weigh": None})

    monkeypatch.setattr(ident_mod, "lcurve_search", full_grid)
    full = identify_forces(bridge, rec)
    assert half.n_modes == full.n_modes > 4
    assert half.lcurve.lam.size < full.lcurve.lam.size
    np.testing.assert_allclose(half.axle_weights, full.axle_weights, rtol=0,
                               atol=1e-4 * np.abs(full.axle_weights).max())

