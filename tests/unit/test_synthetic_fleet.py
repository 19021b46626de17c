"""The realistic site's heavy traffic (bwim.synthetic.fleet): the vehicles' static loads,
the class mix, and a steering-axle load of the reference class (5-axle tractor–
semitrailers) nearly independent of payload, as WIM data show.

Sources for the steering axle (see the fleet module): 5-axle semitrailers averaged
49.4 kN on the steering axle both in the normal and in the overloaded state
(Mathematical Problems in Engineering 2014, article 273693, Table 2); static steer-axle
loads of bobtail on-highway tractors about 46.7–51.2 kN (trucknews.com, "Spring Loaded").
"""

import numpy as np
import pytest

from bwim.conventions import GRAVITY
from bwim.errors import InputError
from bwim.synthetic.detector import TYRES
from bwim.synthetic.fleet import FLEET_KINDS, FLEET_MIX, GVW_RANGE, draw_kind, traffic_vehicle
from bwim.vehicles import TractorSemitrailer


def _mass(v):
    bodies = (v.tractor_mass + v.trailer_mass if isinstance(v, TractorSemitrailer)
              else v.body_mass)
    return bodies + 2.0 * float(np.sum(v.wheel_mass))


def _sample(kind, n, seed):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        tv = traffic_vehicle(kind, rng)
        out.append((tv, tv.vehicle.model().static_axle_loads))
    return out


def test_every_kind_stands_on_positive_axle_loads_summing_to_its_weight():
    """For 50 vehicles of every kind: the static axle loads of the vehicle model are
    positive and sum to the vehicle's mass × g (static equilibrium: the model's closed
    form); the gross mass lies in the kind's range (up to 105 % of full); one tyre type
    per axle, steering axles single."""
    for kind in FLEET_KINDS:
        empty, full = GVW_RANGE[kind]
        for tv, loads in _sample(kind, 50, seed=FLEET_KINDS.index(kind)):
            assert np.all(loads > 0)
            mass = _mass(tv.vehicle)
            assert abs(loads.sum() - mass * GRAVITY) < 1e-6 * loads.sum()
            assert empty * 1e3 - 1e-6 <= mass <= (empty + 1.05 * (full - empty)) * 1e3 + 1e-6
            assert len(tv.tyres) == tv.vehicle.n_axles and set(tv.tyres) <= set(TYRES)
            assert tv.tyres[0] == "single"


def test_steering_axle_of_the_reference_class_is_nearly_independent_of_payload():
    """artic_2+3 (400 vehicles): the steering axle averages 46–60 kN (the sources: 49.4 kN
    for 5-axle semitrailers, 46.7–51.2 kN for bobtail tractors; European forward-control
    tractors are front-heavier) with a coefficient of variation under 10 %, and it takes
    less than 4 % of the payload (full − empty mean steer load over full − empty mean
    gross weight; measured about 2 %) while a 2-axle rigid truck's front axle takes 15–40 %
    (its front share falls from about 0.6 empty to 0.39 full; measured 24 %)."""
    sample = _sample("artic_2+3", 400, seed=1)
    steer = np.array([loads[0] for _, loads in sample]) / 1e3
    gvw = np.array([loads.sum() for _, loads in sample]) / 1e3
    loading = np.array([tv.loading for tv, _ in sample])
    assert 46.0 <= steer.mean() <= 60.0
    assert steer.std() / steer.mean() < 0.10
    full, empty = loading > 0.8, loading < 0.1
    share = (steer[full].mean() - steer[empty].mean()) / (gvw[full].mean() - gvw[empty].mean())
    assert 0 < share < 0.04
    rigid = _sample("rigid_2", 400, seed=2)
    front = np.array([loads[0] for _, loads in rigid])
    total = np.array([loads.sum() for _, loads in rigid])
    r_load = np.array([tv.loading for tv, _ in rigid])
    f, e = r_load > 0.8, r_load < 0.1
    rigid_share = (front[f].mean() - front[e].mean()) / (total[f].mean() - total[e].mean())
    assert 0.15 < rigid_share < 0.40


def test_kinds_are_drawn_in_the_mix():
    """5000 draws: each kind's frequency is its FLEET_MIX share within 4 binomial standard
    errors; with min_axles=4 only 4-axle or longer kinds come."""
    rng = np.random.default_rng(3)
    n = 5000
    drawn = [draw_kind(rng) for _ in range(n)]
    for kind, share in zip(FLEET_KINDS, FLEET_MIX, strict=True):
        freq = drawn.count(kind) / n
        assert abs(freq - share) < 4 * np.sqrt(share * (1 - share) / n)
    long = {draw_kind(rng, min_axles=4) for _ in range(500)}
    assert long and all(traffic_vehicle(k, rng).vehicle.n_axles >= 4 for k in long)
    with pytest.raises(InputError, match="unknown vehicle kind"):
        traffic_vehicle("bus", rng)
