"""Named vehicles with documented parameters.

Sources and choices
-------------------
* The paper (Dowling, OBrien & González 2012, §5.1; docs/paper_cases.md §5.1) gives the
  calibration truck's static axle loads (59.5 kN, 108.6 kN) and spacing (5.5 m) and says
  its tyre and suspension values are "typical values from the literature" without listing
  them.
* The values below are **assumed** within the ranges given for heavy vehicles by Cebon,
  *Handbook of Vehicle–Road Interaction* (Swets & Zeitlinger, 1999), ch. 3–4: leaf-spring
  suspension 0.2–0.6 MN/m per wheel, tyres 0.8–1.8 MN/m per single tyre (about twice for
  a dual pair), body bounce near 1.5–3 Hz and axle hop near 8–15 Hz.  For the paper truck
  they are chosen so that its rigid-road body bounce (≈ 1.4 Hz) and axle hop
  (≈ 12–14 Hz) sit near the 1.2 Hz and 14.3 Hz the paper reports in its axle forces
  (§5.4, Fig. 19); ``tests/unit/test_vehicles.py`` checks those frequencies.
* Inertias follow from the body mass and a uniform-box estimate ``m (a² + b²) / 12``.
"""

from __future__ import annotations

from collections.abc import Callable

from bwim.errors import InputError
from bwim.vehicles.types import TractorSemitrailer, Truck3D

__all__ = ["NAMED_VEHICLES", "named", "three_axle_truck", "tractor_semitrailer",
           "two_axle_truck"]


def two_axle_truck() -> Truck3D:
    """The paper's calibration truck: 59.5 kN + 108.6 kN, 5.5 m spacing, 2.0 m track.

    Unsprung 700 kg (front axle) and 1100 kg (rear axle); suspension 200 / 500 kN/m and
    5 / 10 kN s/m per wheel; tyres 1.75 MN/m (single) / 3.5 MN/m (dual) and 1 kN s/m per
    wheel; pitch inertia 65 t m² (body ≈ 15.3 t over ≈ 7 m), roll 13 t m².  Body mass
    and CG follow from the axle loads.
    """
    return Truck3D.from_axle_loads(
        axle_loads=[59.5e3, 108.6e3],
        axle_spacings=[5.5],
        wheel_mass=[350.0, 550.0],
        pitch_inertia=65.0e3,
        roll_inertia=13.0e3,
        suspension_stiffness=[200e3, 500e3],
        suspension_damping=[5e3, 10e3],
        tyre_stiffness=[1.75e6, 3.5e6],
        tyre_damping=[1e3, 1e3],
        track_width=2.0,
    )


def three_axle_truck() -> Truck3D:
    """A 26 t rigid truck: steer axle and a tandem drive group (4.2 m + 1.35 m).

    Body 23.1 t with its CG 3.65 m behind the steer axle; unsprung 700 kg (steer) and
    1100 kg per drive axle; suspension 250 / 450 kN/m and 6 / 10 kN s/m per wheel; tyres
    1.75 / 3.5 MN/m per wheel.  The tandem makes the static loads statically
    indeterminate: they follow from equilibrium with the springs.
    """
    return Truck3D(
        body_mass=23.1e3, pitch_inertia=156e3, roll_inertia=24e3,
        axle_spacings=[4.2, 1.35], cg_offset=3.65,
        wheel_mass=[350.0, 550.0, 550.0],
        suspension_stiffness=[250e3, 450e3, 450e3],
        suspension_damping=[6e3, 10e3, 10e3],
        tyre_stiffness=[1.75e6, 3.5e6, 3.5e6],
        tyre_damping=[1e3, 1e3, 1e3],
        track_width=2.0,
    )


def tractor_semitrailer() -> TractorSemitrailer:
    """A 5-axle, 40 t tractor–semitrailer (2-axle tractor, tri-axle trailer).

    Axles at 0, 3.6, 9.5, 10.81, 12.12 m; fifth wheel 3.0 m behind the steer axle.
    Tractor body 6.5 t (CG 1.6 m), trailer body 29.3 t (CG 8.6 m): static axle loads
    ≈ 5.7, 10.9, 7.7, 7.8, 7.9 t; unsprung 700 kg
    (steer), 1100 kg (drive), 800 kg per trailer axle; suspension 300 / 600 / 400 kN/m per
    wheel; tyres 1.75 / 3.5 / 2.0 MN/m per wheel (single, dual, wide single).
    """
    return TractorSemitrailer(
        tractor_mass=6.5e3, tractor_pitch_inertia=19.5e3, tractor_roll_inertia=6.8e3,
        tractor_cg_offset=1.6,
        trailer_mass=29.3e3, trailer_pitch_inertia=450e3, trailer_roll_inertia=37.8e3,
        trailer_cg_offset=8.6,
        hitch_offset=3.0, n_tractor_axles=2,
        axle_spacings=[3.6, 5.9, 1.31, 1.31],
        wheel_mass=[350.0, 550.0, 400.0, 400.0, 400.0],
        suspension_stiffness=[300e3, 600e3, 400e3, 400e3, 400e3],
        suspension_damping=[6e3, 10e3, 8e3, 8e3, 8e3],
        tyre_stiffness=[1.75e6, 3.5e6, 2.0e6, 2.0e6, 2.0e6],
        tyre_damping=[1e3, 1e3, 1e3, 1e3, 1e3],
        track_width=2.0,
    )


#: Named vehicles by the names the CLI and scenario files use.
NAMED_VEHICLES: dict[str, Callable[[], object]] = {
    "two_axle_truck": two_axle_truck,
    "three_axle_truck": three_axle_truck,
    "tractor_semitrailer": tractor_semitrailer,
}


def named(name: str):
    """The named vehicle ``name`` (see :data:`NAMED_VEHICLES`)."""
    if name not in NAMED_VEHICLES:
        raise InputError(
            f"unknown vehicle {name!r}; expected one of {', '.join(NAMED_VEHICLES)}"
        )
    return NAMED_VEHICLES[name]()
