"""The road-free fit with the logger's unknowns (bwim.calibration.logger): algebra.

Same-model data, so these check the algebra only (the variable projection, the gains'
fit, the offsets, the frame shift), not the method's accuracy on real data; that is
``tests/validation/test_site_model.py`` (data from a finer mesh, gauge spread, dynamics,
noise, drift).  Reference: the parameters the readings were made with.
"""

import dataclasses

import numpy as np
import pytest

from bwim.calibration import calibrate_logger
from bwim.calibration.quasistatic import moving_force_columns
from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.records import Passage, Record
from bwim.sensors import Sensor

FS = 256.0
LOADS = np.array([60e3, 110e3, 90e3])
SPACINGS = (3.5, 5.0)
ORIGIN, LATERAL, RATIO = 1.2, -0.3, 0.8  # the truth the readings are made with


def _start():
    return Bridge.plate(length=8.0, width=6.0, nx=8, ny=6, thickness=0.5, mu=1200.0,
                        E=30e9, poisson=0.2, damping_ratio=0.03)


def _sensors():
    return tuple(Sensor(x=4.0, y=y, kind="strain_x", name=f"g{k}")
                 for k, y in enumerate((1.0, 2.0, 3.0, 4.0, 5.0)))


def _records(gains, rng, truth=None):
    """Crossings at three lateral positions on the true model (default the start's mesh
    with E_y = RATIO E_x), quasi-static, in logger units with offsets and slopes; passages
    in a frame ORIGIN behind the model's and LATERAL to the side."""
    truth = _start().with_params(E_y=RATIO * 30e9) if truth is None else truth
    out = []
    for speed, lane in ((18.0, 2.2), (22.0, 2.8), (20.0, 3.4)):
        detected = Passage(speed=speed, lane=lane - LATERAL, axle_spacings=SPACINGS,
                           track_width=1.8, delay=0.4)
        t = np.arange(int(2.2 * FS)) / FS
        x = detected.wheel_x(t) + ORIGIN
        y = np.broadcast_to(detected.wheel_y + LATERAL, x.shape)
        P = np.repeat(LOADS / 2, 2)
        fun = np.ones((t.size, 3, 1))
        cols = moving_force_columns(truth, _sensors(), x, y, P, detected.wheel_axle, fun,
                                    fs=FS, n_modes=0)
        strain = cols[:, :, 0].sum(axis=1)
        offset = rng.uniform(-50, 50, 5) + rng.normal(0, 5, 5) * (t[:, None] - t.mean())
        data = strain * gains[None, :] + offset
        out.append(Record(time=t, data=data, sensors=_sensors(), passages=(detected,)))
    return out


@pytest.mark.parametrize("mode", ["common", "per_channel"])
def test_recovers_gains_frame_and_ratio_from_same_model_readings(mode):
    """Noise-free same-model readings: the fit returns the parameters they were made with
    (measured: every parameter within 3e-7 relative; tolerance 1e-5)."""
    rng = np.random.default_rng(3)
    gains = (np.full(5, 2.5e5) if mode == "common"
             else 2.5e5 * np.array([1.0, 0.95, 1.08, 1.02, 0.9]))
    # noise-free readings still need a noise estimate: add a tiny one
    records = [dataclasses.replace(r, data=r.data + 1e-6 * rng.standard_normal(r.data.shape))
               for r in _records(gains, rng)]
    cal = calibrate_logger(_start(), records, LOADS, origin=1.0, lateral=0.0, gains=mode,
                           n_basis=2, inertia_modes=0, mass=False)
    assert cal.success, cal.message
    assert cal.origin == pytest.approx(ORIGIN, abs=1e-5)
    assert cal.lateral == pytest.approx(LATERAL, abs=1e-5)
    assert cal.params["E_y"] / 30e9 == pytest.approx(RATIO, rel=1e-5)
    np.testing.assert_allclose(cal.gains, gains, rtol=1e-5)
    assert np.all(cal.explained > 1 - 1e-8)


def test_a_parameter_at_its_bound_is_no_success():
    """A frame the data cannot reach (the truth 1.7 m beyond the searched ± 1.5 m): the
    origin stops at its bound and the fit says so."""
    rng = np.random.default_rng(4)
    records = [dataclasses.replace(r, data=r.data + 1e-6 * rng.standard_normal(r.data.shape))
               for r in _records(np.full(5, 2.5e5), rng)]
    cal = calibrate_logger(_start(), records, LOADS, origin=ORIGIN - 1.7, gains="common",
                           n_basis=2, inertia_modes=0, mass=False)
    assert not cal.success
    assert "origin" in cal.at_bound and "bound" in cal.message


def test_inputs_refused_with_one_line_messages():
    rng = np.random.default_rng(5)
    records = _records(np.full(5, 2.5e5), rng)
    with pytest.raises(InputError, match="gains must be one of"):
        calibrate_logger(_start(), records, LOADS, gains="each")
    with pytest.raises(InputError, match="scale reference"):
        calibrate_logger(_start(), records, LOADS, unknowns=("E_x",))
    with pytest.raises(InputError, match="3 axles, the loads give 2"):
        calibrate_logger(_start(), records, LOADS[:2])
    no_x = [dataclasses.replace(r, sensors=tuple(dataclasses.replace(s, x=None)
                                                 for s in r.sensors)) for r in records]
    with pytest.raises(InputError, match="position"):
        calibrate_logger(_start(), no_x, LOADS)


def test_the_mesh_correction_fits_the_bisected_models_parameters():
    """Readings made on the start's mesh bisected once (16 × 12), fitted with the 8 × 6
    model.  Without the correction the coarse mesh biases the fit (measured: the E_y
    ratio off by 5.3e-2, x₀ by 3.0 mm, the gain by 4.2e-3).  With ``mesh_correction=1``
    the passes' fixed point is the finer model's own calibration (Stetter 1978: the
    corrected normal equations are the finer model's; exact when it fits the data, as
    here), so the fit returns the parameters the readings were made with (measured:
    within 2.3e-6; tolerance 2e-5) and the model it reports is the bisected one."""
    from bwim.fe.convergence import refine

    rng = np.random.default_rng(5)
    gains = np.full(5, 2.5e5)
    truth = refine(_start().with_params(E_y=RATIO * 30e9))
    records = [dataclasses.replace(r, data=r.data + 1e-6 * rng.standard_normal(r.data.shape))
               for r in _records(gains, rng, truth=truth)]
    kw = {"origin": 1.0, "lateral": 0.0, "n_basis": 2, "inertia_modes": 0, "mass": False}
    plain = calibrate_logger(_start(), records, LOADS, **kw)
    fixed = calibrate_logger(_start(), records, LOADS, mesh_correction=1, **kw)
    assert plain.mesh_correction is None
    assert abs(plain.params["E_y"] / 30e9 / RATIO - 1) > 1e-2  # the bias it removes
    assert fixed.success and fixed.mesh_correction.converged, fixed.message
    assert fixed.mesh_correction.mesh == (16, 12)
    grid = fixed.bridge.model.grid
    assert (grid.nx, grid.ny) == (16, 12)
    assert fixed.params["E_y"] / 30e9 == pytest.approx(RATIO, rel=2e-5)
    assert fixed.origin == pytest.approx(ORIGIN, abs=2e-5)
    assert fixed.lateral == pytest.approx(LATERAL, abs=2e-5)
    np.testing.assert_allclose(fixed.gains, gains, rtol=2e-5)


def test_auto_mesh_correction_follows_the_mesh_check():
    """``"auto"`` bisects as often as the mesh check of the start at the gauges asks
    (:func:`bwim.fe.convergence.check_mesh` at 5 %, the reference, called here on the
    truck's wheel loads at mid-span): the same fit as that many bisections asked for; a
    wrong value is a one-line InputError."""
    from bwim.fe.convergence import check_mesh
    from bwim.loads import PointLoad

    rng = np.random.default_rng(6)
    records = [dataclasses.replace(r, data=r.data + 1e-6 * rng.standard_normal(r.data.shape))
               for r in _records(np.full(5, 2.5e5), rng)]
    wheels = [PointLoad(x=x, y=y, P=p / 2) for x, p in zip((0.5, 4.0, 9.0), LOADS,
                                                           strict=True) for y in (2.3, 4.1)]
    mc = check_mesh(_start(), records[0].sensors, [w for w in wheels if 0 < w.x < 8.0],
                    tol=0.05, max_levels=3)
    levels = mc.meshes.index(mc.adequate) if mc.adequate else 2
    kw = {"origin": 1.0, "lateral": 0.0, "n_basis": 2, "inertia_modes": 0, "mass": False}
    auto = calibrate_logger(_start(), records, LOADS, mesh_correction="auto", **kw)
    asked = calibrate_logger(_start(), records, LOADS, mesh_correction=levels, **kw)
    assert levels >= 1 and auto.mesh_correction.levels == levels
    np.testing.assert_array_equal(auto.x, asked.x)
    for bad in ("fine", 7, -1):
        with pytest.raises(InputError, match="mesh_correction"):
            calibrate_logger(_start(), records, LOADS, mesh_correction=bad, **kw)
