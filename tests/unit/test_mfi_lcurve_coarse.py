"""The L-curve search when the coarse problem's corner lies above the model's (issue 23,
item 2): a half fine grid whose static weights agree is not extended towards smaller λ.

References: the corner rule on a dense log grid of the record's model (where the corner
is), and the same search without ``weigh`` (the full fine grid with its extensions: the
answer the static weights must keep).
"""

import numpy as np
import pytest

import bwim
import bwim.mfi.lcurve as lcurve
from bwim import paper
from bwim.mfi import build_model, identify_forces
from bwim.mfi import identify as ident_mod
from bwim.mfi.dp import sweep
from bwim.mfi.lcurve import CoarseProblem, _corner, lcurve_search
from bwim.mfi.statespace import ForceUnknowns, Order

LAM_RANGE = (1e-6, 1e3)


def _passes(monkeypatch):
    """Record the number of λ of every stacked pass the search runs."""
    calls = []
    inner = lcurve.sweep

    def counted(model, d, lams, *args, **kw):
        calls.append(np.atleast_1d(lams).size)
        return inner(model, d, lams, *args, **kw)

    monkeypatch.setattr(lcurve, "sweep", counted)
    return calls


@pytest.fixture(scope="module")
def fast_crossing():
    """The paper truck crossing the paper slab in 1 s (20 m/s), clean readings of its own
    12 × 8 model at 1 kHz: the case of ``benchmarks/bench_mfi.py`` whose bracket misses
    (same-model data: this checks the search, not the identification's accuracy)."""
    bridge = paper.slab_bridge()
    truck = paper.truck()
    rec = bwim.simulate(bridge, truck, speed=bridge.length + truck.length, lane=paper.LANE,
                        sensors=paper.sensors(), road=paper.road(1), sampling_rate=1000.0,
                        approach=20.0)
    return bridge, rec


def test_flat_half_grid_below_the_corner_is_not_extended(fast_crossing, monkeypatch):
    """The coarse problem (5 modes at 250 Hz) puts the corner above the model's (14
    modes): the dense grid's corner (73 λ over the range on the model; measured log10 λ
    −2.69) lies below every λ of the half grid.  The half grid's weights agree within
    FLAT_TOL, so the search stops after one pass on the model at its smallest λ; the
    weights are those of the full fine grid's answer (the same search without ``weigh``,
    which extends the grid to the corner) within 1e-4 of the largest (measured 2.1e-6)."""
    bridge, rec = fast_crossing
    calls = _passes(monkeypatch)
    half = identify_forces(bridge, rec)
    assert half.n_modes > 5  # the coarse problem has fewer modes than the model
    assert len(calls) == 2 and calls[1] == 4  # the coarse pass and one pass of 4 λ
    # the answer is the smallest λ solved on the model
    assert half.lam_scaled == pytest.approx(half.lcurve.lam_scaled.min(), rel=1e-12)
    # the reference corner lies below it (by more than half the half grid's spacing)
    scale = float(np.abs(rec.data).max())
    model = build_model(bridge, bridge.modes(half.n_modes), rec, scale,
                        unknowns=half.unknowns, order=half.order)
    t = np.linspace(np.log(LAM_RANGE[0]), np.log(LAM_RANGE[1]), 73)
    sw = sweep(model, rec.data / scale, np.exp(t))  # all admissible (clean, compressive)
    _, t_dense = _corner(t, sw.residual_norm, sw.seminorm)
    assert t_dense / np.log(10) < np.log10(half.lam_scaled) - 0.25  # measured 0.47 decade
    inner = ident_mod.lcurve_search

    def full_grid(*args, **kw):
        return inner(*args, **{**kw, "weigh": None})

    monkeypatch.setattr(ident_mod, "lcurve_search", full_grid)
    full = identify_forces(bridge, rec)
    assert full.lcurve.lam.size > 8  # extended towards the corner
    np.testing.assert_allclose(half.axle_weights, full.axle_weights, rtol=0,
                               atol=1e-4 * np.abs(full.axle_weights).max())


def test_half_grid_whose_weights_disagree_is_extended(fast_crossing, monkeypatch):
    """The same record with ``flat_tol=0`` (no two weights agree): the half grid is
    extended towards the corner and the other half solved, as before; the answer is the
    full fine grid's (reference: the search without ``weigh``): the same λ to round-off."""
    bridge, rec = fast_crossing
    inner = ident_mod.lcurve_search

    def with_options(**options):
        def search(*args, **kw):
            return inner(*args, **{**kw, **options})
        return search

    monkeypatch.setattr(ident_mod, "lcurve_search", with_options(weigh=None))
    full = identify_forces(bridge, rec)
    monkeypatch.setattr(ident_mod, "lcurve_search", with_options(flat_tol=0.0))
    calls = _passes(monkeypatch)
    strict = identify_forces(bridge, rec)
    assert len(calls) > 2
    assert strict.lam_scaled == pytest.approx(full.lam_scaled, rel=1e-12)
    np.testing.assert_allclose(strict.axle_weights, full.axle_weights, rtol=1e-12)


def _mean_forces(forces):
    """A stand-in for the static weights: each force's mean over the record."""
    return forces.mean(axis=1)


def test_half_grid_is_still_extended_towards_larger_lambda(monkeypatch):
    """Two axle forces crossing a 10 m beam at 12 m/s (three sensors, 1 kHz, 5 % noise),
    its 6-mode model bracketed on its 2-mode model with the data weighted 100×: the half
    grid's corner sits at its top, and even with weights that agree (``flat_tol=inf``) the
    grid is extended there, by λ above it (the weights move with λ above the corner).
    A check of the search's mechanics on the model's own data."""
    beam = bwim.Bridge.beam(length=10.0, n_elements=10, E=3e10, I=0.5, mu=5e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x) for x in (2.5, 5.0, 7.5)]
    rec = bwim.simulate(beam, bwim.MovingForces(axle_loads=[5e4, 8e4], axle_spacings=[3.0]),
                        speed=12.0, sensors=sensors, sampling_rate=1000.0, approach=0.0)
    rec = rec.with_noise(0.05, seed=3)
    scale = float(np.abs(rec.data).max())
    opts = {"unknowns": ForceUnknowns.AXLE, "order": Order.FIRST}
    model = build_model(beam, beam.modes(6), rec, scale, **opts)
    d = rec.data / scale
    coarse = CoarseProblem(model=build_model(beam, beam.modes(2), rec, scale, **opts), d=d,
                           weights=100.0 * np.ones(model.n_s))
    calls = _passes(monkeypatch)
    found = lcurve_search(model, d, np.ones(model.n_s), LAM_RANGE, coarse=coarse,
                          weigh=_mean_forces, flat_tol=np.inf)
    assert calls[1:] == [4, 2]
    first = np.sort(found.curve.lam_scaled)[:4]
    added = np.sort(found.curve.lam_scaled)[4:]
    assert np.all(added > first.max())
