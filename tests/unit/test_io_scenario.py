"""Scenario TOML files: examples, equality with bwim.paper, round trips, strict errors."""

import math
import re
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import bwim
from bwim import io, paper
from bwim import scenario as scn
from bwim.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

PLATE = """
[bridge]
kind = "plate"
length = 12.0
width = 8.0
nx = 6
ny = 4
thickness = 0.65
E = 35e9
mu = 1560.0
"""


def write(tmp_path: Path, text: str, name: str = "scenario.toml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text), encoding="utf-8")
    return p


def load(tmp_path: Path, text: str) -> scn.Scenario:
    return scn.load_scenario(write(tmp_path, text))


def raises(match_exact: str):
    return pytest.raises(InputError, match="^" + re.escape(match_exact) + "$")


def same_sensors(a, b) -> bool:
    return len(a) == len(b) and all(
        (s.name, s.x, s.y, s.kind) == (t.name, t.x, t.y, t.kind) for s, t in zip(a, b, strict=True)
    )


def same_bridge(a: bwim.Bridge, b: bwim.Bridge) -> bool:
    pa, pb = a.params, b.params
    return (
        pa.keys() == pb.keys()
        and all(np.array_equal(pa[k], pb[k]) for k in pa)
        and a.damping_ratio == b.damping_ratio
        and a.model.supports == b.model.supports
        and np.array_equal(a.model.zone_of_element, b.model.zone_of_element)
        and a.n_zones == b.n_zones
        and abs(a.stiffness_matrix() - b.stiffness_matrix()).max() == 0.0
        and abs(a.mass_matrix() - b.mass_matrix()).max() == 0.0
    )


# --- examples --------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "n_sensors", "vehicle"),
    [("paper_slab", 18, bwim.Truck3D), ("vransko", 27, bwim.Truck3D),
     ("beam", 3, bwim.TractorSemitrailer)],
)
def test_examples_load_and_build(name, n_sensors, vehicle):
    s = scn.load_scenario(EXAMPLES / f"{name}.toml")
    bridge = scn.build_bridge(s)
    sensors = scn.build_sensors(s)
    assert len(sensors) == n_sensors
    assert isinstance(scn.build_vehicle(s), vehicle)
    road = scn.build_road(s)
    passage = scn.build_passage(s)
    # the road covers the whole run: approach behind the last axle to the exit
    veh = scn.build_vehicle(s)
    assert road.covers(-(s.run.approach + veh.length), bridge.length + veh.length)
    assert passage.speed == s.run.speed
    assert bridge.sensor_matrix(sensors).shape == (n_sensors, bridge.n_free)
    assert s.title


def test_paper_slab_example_is_the_paper_bridge():
    s = scn.load_scenario(EXAMPLES / "paper_slab.toml")
    assert same_bridge(scn.build_bridge(s), paper.slab_bridge())
    assert same_sensors(scn.build_sensors(s), paper.sensors())
    road, ref = scn.build_road(s), paper.road(1)
    assert np.array_equal(road.x, ref.x) and np.array_equal(road.elevation, ref.elevation)
    truck = scn.build_vehicle(s)
    assert np.array_equal(truck.static_axle_loads, paper.truck().static_axle_loads)
    p = scn.build_passage(s)
    assert (p.speed, p.lane, p.track_width) == (paper.SPEED, paper.LANE, paper.TRACK_WIDTH)
    assert (s.run.sampling_rate, s.run.approach) == (paper.SAMPLING_RATE, paper.APPROACH)


def test_vransko_example_is_the_paper_bridge():
    s = scn.load_scenario(EXAMPLES / "vransko.toml")
    bridge = scn.build_bridge(s)
    ref = paper.vransko_bridge()
    assert same_bridge(bridge, ref)
    assert bridge.model.girders == ref.model.girders
    assert same_sensors(scn.build_sensors(s), paper.vransko_sensors())


@pytest.mark.parametrize("name", ["paper_slab", "vransko", "beam"])
def test_examples_dump_and_load_back_equal(tmp_path, name):
    s = scn.load_scenario(EXAMPLES / f"{name}.toml")
    out = tmp_path / "again.toml"
    scn.dump_scenario(s, out, header="written by a test")
    again = scn.load_scenario(out)
    assert again == s
    assert out.read_text().startswith("# written by a test\n")
    assert tomllib.loads(out.read_text()) == scn.scenario_to_dict(s)


def test_simulate_scenario_beam_with_noise_is_seeded(tmp_path):
    text = (EXAMPLES / "beam.toml").read_text().replace("tail = 0.5", "tail = 0.0\nnoise = 0.02")
    s = load(tmp_path, text)
    a = scn.simulate_scenario(s)
    b = scn.simulate_scenario(s)
    clean = scn.simulate_scenario(load(tmp_path, text.replace("noise = 0.02", "")))
    assert a.data.shape[1] == 3 and [c.name for c in a.sensors] == ["quarter", "mid",
                                                                   "three_quarter"]
    assert np.array_equal(a.data, b.data)
    assert not np.array_equal(a.data, clean.data)
    assert a.truth.static_axle_loads.size == 5


# --- bridges -------------------------------------------------------------------------------
def test_orthotropic_zoned_plate_and_supports_table(tmp_path):
    s = load(tmp_path, """
        [bridge]
        kind = "plate"
        length = 12.0
        width = 8.0
        nx = 12
        ny = 8
        thickness = 0.65
        E_x = [30e9, 31e9, 32e9, 33e9]
        E_y = 20e9
        mu = 1560
        zones = [2, 2]
        [bridge.supports]
        x0 = "clamped"
        x_end = "simple"
    """)
    b = scn.build_bridge(s)
    ref = bwim.Bridge.plate(length=12.0, width=8.0, nx=12, ny=8, thickness=0.65,
                            E_x=[30e9, 31e9, 32e9, 33e9], E_y=20e9, mu=1560.0, zones=(2, 2),
                            supports={"x0": "clamped", "x_end": "simple"})
    assert same_bridge(b, ref)


def test_girders_with_explicit_section_values(tmp_path):
    s = load(tmp_path, PLATE + """
        [[bridge.girders]]
        y = 2.0
        I = 0.1
        z_bottom = 0.8
        E = 35e9
        mu = 1000
        J = 0.01
    """)
    b = scn.build_bridge(s)
    assert b.model.girders == (bwim.Girder(y=2.0, I=0.1, z_bottom=0.8, E=35e9, mu=1000.0,
                                           J=0.01),)


def test_beam_with_x_through_and_zones(tmp_path):
    s = load(tmp_path, """
        [bridge]
        kind = "beam"
        length = 20.0
        n_elements = 9
        x_through = [7.3]
        E = [3e10, 3.1e10, 3.2e10]
        I = 1.0
        mu = 1e4
        z_bottom = 0.5
        zones = 3
    """)
    b = scn.build_bridge(s)
    assert 7.3 in b.model.grid.x_lines
    ref = bwim.Bridge.beam(length=20.0, x_lines=bwim.grid_lines(20.0, 9, through=[7.3]),
                           E=[3e10, 3.1e10, 3.2e10], I=1.0, mu=1e4, z_bottom=0.5, zones=3)
    assert same_bridge(b, ref)


# --- sensors -------------------------------------------------------------------------------
def test_sensor_grid_and_single_entries_in_file_order(tmp_path):
    s = load(tmp_path, PLATE + """
        [[sensors]]
        x = 6.0
        y = 4.0
        kind = "deflection"
        name = "w_mid"
        [[sensors]]
        x = [3.0, 9.0]
        y = 2.0
        kind = ["strain_x", "strain_y"]
        name = "{short}{i}@{x:g}"
        [[sensors]]
        x = 1.0
        y = 1.0
    """)
    got = [(q.name, q.x, q.y, q.kind.value) for q in scn.build_sensors(s)]
    assert got == [
        ("w_mid", 6.0, 4.0, "deflection"),
        ("x0@3", 3.0, 2.0, "strain_x"), ("x1@9", 9.0, 2.0, "strain_x"),
        ("y2@3", 3.0, 2.0, "strain_y"), ("y3@9", 9.0, 2.0, "strain_y"),
        ("strain_x@1,1", 1.0, 1.0, "strain_x"),
    ]


# --- vehicles ------------------------------------------------------------------------------
def test_moving_forces_and_sprung_mass(tmp_path):
    s = load(tmp_path, PLATE + """
        [vehicle]
        type = "moving_forces"
        axle_loads = [59.5e3, 108.6e3]
        axle_spacings = [5.5]
        track_width = 1.8
    """)
    v = scn.build_vehicle(s)
    assert isinstance(v, bwim.MovingForces)
    assert np.array_equal(v.axle_loads, [59.5e3, 108.6e3]) and v.track_width == 1.8
    s = load(tmp_path, PLATE + """
        [vehicle]
        type = "sprung_mass"
        mass = 5750
        stiffness = 1595e3
    """)
    v = scn.build_vehicle(s)
    assert isinstance(v, bwim.SprungMass) and (v.mass, v.stiffness, v.damping) == (
        5750.0, 1595e3, 0.0)


def test_truck3d_from_axle_loads_equals_the_paper_truck(tmp_path):
    s = load(tmp_path, PLATE + """
        [vehicle]
        type = "truck3d"
        axle_loads = [59.5e3, 108.6e3]
        axle_spacings = [5.5]
        wheel_mass = [350.0, 550.0]
        pitch_inertia = 65.0e3
        roll_inertia = 13.0e3
        suspension_stiffness = [200e3, 500e3]
        suspension_damping = [5e3, 10e3]
        tyre_stiffness = [1.75e6, 3.5e6]
        tyre_damping = [1e3, 1e3]
        track_width = 2.0
    """)
    v, ref = scn.build_vehicle(s).model(), paper.truck().model()
    for name in ("mass", "stiffness", "damping", "static_forces"):
        assert np.array_equal(getattr(v, name), getattr(ref, name))


def test_tractor_semitrailer_and_half_car_by_parameters(tmp_path):
    ref = bwim.vehicles.tractor_semitrailer()
    lines = ['[vehicle]', 'type = "tractor_semitrailer"']
    for f in ("tractor_mass", "tractor_pitch_inertia", "tractor_roll_inertia",
              "tractor_cg_offset", "trailer_mass", "trailer_pitch_inertia",
              "trailer_roll_inertia", "trailer_cg_offset", "hitch_offset", "track_width"):
        lines.append(f"{f} = {getattr(ref, f)!r}")
    lines.append(f"n_tractor_axles = {ref.n_tractor_axles}")
    for f in ("axle_spacings", "wheel_mass", "suspension_stiffness", "suspension_damping",
              "tyre_stiffness", "tyre_damping"):
        lines.append(f"{f} = {getattr(ref, f).tolist()!r}")
    v = scn.build_vehicle(load(tmp_path, PLATE + "\n".join(lines)))
    assert np.array_equal(v.static_axle_loads, ref.static_axle_loads)
    s = load(tmp_path, PLATE + """
        [vehicle]
        type = "half_car"
        body_mass = 10000
        pitch_inertia = 40000
        axle_spacings = [4.0]
        cg_offset = 2.0
        wheel_mass = 500
        suspension_stiffness = 4e5
        suspension_damping = 1e4
        tyre_stiffness = 1.75e6
    """)
    v = scn.build_vehicle(s)
    assert isinstance(v, bwim.HalfCar) and v.n_axles == 2
    assert np.isclose(v.static_axle_loads.sum(), (10000 + 2 * 500) * 9.81)


# --- roads ---------------------------------------------------------------------------------
def test_roads_flat_iso_class_and_csv_profile(tmp_path):
    assert scn.build_road(load(tmp_path, PLATE)).covers(-1e6, 1e6)
    flat = scn.build_road(load(tmp_path, PLATE + "[road]\nflat = true\n"))
    assert np.all(flat.elevation == 0)
    iso = scn.build_road(load(tmp_path, PLATE + """
        [road]
        roughness = "B"
        length = 50.0
        start = -40.0
        seed = 4
        track_correlation = 0.5
    """))
    ref = bwim.RoadProfile.iso8608("B", length=50.0, start=-40.0, seed=4,
                                   track_correlation=0.5)
    assert np.array_equal(iso.elevation, ref.elevation) and iso.n_tracks == 2
    (tmp_path / "profiles").mkdir()
    (tmp_path / "profiles" / "road.csv").write_text(
        "x,elevation\n-200,0.0\n0,0.001\n50,0.0\n100,0.002\n")
    p = write(tmp_path, PLATE + '[road]\nprofile = "profiles/road.csv"\nsmoothing = 1.0\n',
              name="sub.toml")
    road = scn.build_road(scn.load_scenario(p))
    assert road.extent == (-199.5, 99.5)
    (tmp_path / "two.csv").write_text("x,right,left\n-200,0,0\n200,0.001,0.002\n")
    road = scn.build_road(load(tmp_path, PLATE + f'[road]\nprofile = "{tmp_path / "two.csv"}"\n'))
    assert road.n_tracks == 2


# --- bridge files --------------------------------------------------------------------------
def _check_bridge_file(tmp_path, bridge):
    path = tmp_path / "bridge.toml"
    scn.save_bridge(bridge, path, title="calibrated")
    again = scn.load_bridge(path)
    assert same_bridge(again, bridge)
    assert again.model.grid.x_lines.tolist() == bridge.model.grid.x_lines.tolist()
    return path


def test_save_load_bridge_zoned_plate_with_calibrated_params(tmp_path):
    rng = np.random.default_rng(3)
    b = paper.slab_bridge(zones=(4, 4)).with_params(
        E_x=35e9 * rng.uniform(0.8, 1.2, 16), E_y=35e9 * rng.uniform(0.8, 1.2, 16),
        mu=1560 * rng.uniform(0.9, 1.1, 16)).with_damping(0.021)
    path = _check_bridge_file(tmp_path, b)
    assert "zones = [4, 4]" in path.read_text()
    assert scn.load_scenario(path).title == "calibrated"


def test_save_load_bridge_with_girders(tmp_path):
    b = paper.vransko_bridge()
    b = b.with_params(E_girder=b.E_girder * [1.0, 0.9, 1.1, 1.05, 0.95], mu=600.0)
    _check_bridge_file(tmp_path, b)


def test_save_load_bridge_irregular_zone_map_and_beam(tmp_path):
    grid_zones = np.arange(12 * 8).reshape(12, 8) % 5
    b = bwim.Bridge.plate(length=12.0, width=8.0, nx=12, ny=8, thickness=0.6, E=3e10,
                          mu=1500.0, zones=grid_zones)
    b = b.with_params(E_x=[3e10, 3.1e10, 3.2e10, 2.9e10, 2.8e10])
    path = _check_bridge_file(tmp_path, b)
    assert "zone_map" in path.read_text()
    beam = bwim.Bridge.beam(length=20.0, x_lines=[0.0, 3.0, 7.5, 12.0, 20.0], E=[3e10, 3.3e10],
                            I=1.2, mu=9000.0, z_bottom=0.6, zones=[0, 0, 1, 1],
                            supports="clamped")
    _check_bridge_file(tmp_path, beam)


def test_save_load_bridge_keeps_an_empty_zone(tmp_path):
    # non-uniform lines: the zone grid (3, 1) leaves zone 2 without elements
    b = bwim.Bridge.plate(length=10.0, width=2.0, x_lines=[0.0, 0.1, 0.2, 10.0], ny=2,
                          thickness=0.5, E=[3e10, 3.1e10, 3.2e10], mu=1000.0, zones=(3, 1))
    assert b.n_zones == 3
    _check_bridge_file(tmp_path, b)


def test_zone_map_with_an_unused_label_round_trips(tmp_path):
    s = load(tmp_path, """
        [bridge]
        kind = "plate"
        length = 4.0
        width = 2.0
        nx = 4
        ny = 2
        thickness = 0.5
        E_x = [3e10, 3.1e10, 3.2e10]
        E_y = 2e10
        mu = 1000.0
        zone_map = [[0, 0], [0, 1], [1, 1], [1, 1]]
        n_zones = 3
    """)
    b = scn.build_bridge(s)
    assert b.n_zones == 3 and b.model.zone_of_element.tolist() == [0, 0, 0, 1, 1, 1, 1, 1]
    path = _check_bridge_file(tmp_path, b)
    assert "n_zones = 3" in path.read_text()
    bad = write(tmp_path, path.read_text().replace("n_zones = 3", "n_zones = 1"))
    with raises(f"{bad}: [bridge]: zone_map labels must lie in [0, 0], got 0 … 1"):
        scn.load_bridge(bad)
    bad = write(tmp_path, path.read_text().replace("n_zones = 3", ""))
    with raises(f"{bad}: [bridge]: E_x must be a scalar or have shape (2,), got shape (3,)"):
        scn.load_bridge(bad)


# --- strict errors -------------------------------------------------------------------------
def test_malformed_toml_names_line_and_column(tmp_path):
    p = write(tmp_path, '[bridge]\nkind = "plate"\nlength = 12 m\n')
    with raises(f"{p}: line 3, column 13: Expected newline or end of document after a "
                "statement"):
        scn.load_scenario(p)
    p = write(tmp_path, "[bridge]\nkind = plate\n")
    with raises(f"{p}: line 2, column 8: Invalid value"):
        scn.load_scenario(p)


def test_missing_file(tmp_path):
    with raises(f"{tmp_path / 'nope.toml'}: no such file"):
        scn.load_scenario(tmp_path / "nope.toml")


def test_unknown_key_names_key_section_and_allowed_keys(tmp_path):
    p = write(tmp_path, PLATE + "lenght = 12.0\n")
    with raises(
        f"{p}: unknown key 'lenght' in [bridge]; allowed keys: kind, length, width, "
        "thickness, nx, ny, x_lines, y_lines, x_through, y_through, E, E_x, E_y, mu, "
        "poisson, damping_ratio, supports, zones, zone_map, n_zones, joints, girders"
    ):
        scn.load_scenario(p)
    p = write(tmp_path, """
        [bridge]
        kind = "beam"
        length = 20.0
        n_elements = 10
        ny = 4
        E = 3e10
        I = 1.0
        mu = 1e4
    """)
    with raises(
        f"{p}: unknown key 'ny' in [bridge] for kind = 'beam'; allowed keys: kind, length, "
        "n_elements, x_lines, x_through, E, mu, I, z_bottom, damping_ratio, supports, zones, "
        "zone_map, n_zones"
    ):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + "[run]\nspeed = 20.0\nlanes = 2.0\n")
    with raises(
        f"{p}: unknown key 'lanes' in [run]; allowed keys: speed, lane, sampling_rate, "
        "approach, tail, method, delay, n_modes, max_frequency, full_system, "
        "static_correction, noise, seed"
    ):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + "[[sensors]]\nx = 1.0\n[[sensors]]\nx = 2.0\nz = 0.0\n")
    with raises(f"{p}: unknown key 'z' in [[sensors]] entry 2; allowed keys: x, y, kind, name"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + "[runs]\nspeed = 20.0\n")
    with raises(f"{p}: unknown key 'runs' at the top level; allowed keys: title, bridge, "
                "sensors, logger, axle_detectors, lanes, drift, lines, trigger, vehicle, "
                "road, run, identify, calibrate"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + '[vehicle]\ntype = "sprung_mass"\nmass = 1.0\nstiffnes = 1.0\n')
    with raises(f"{p}: unknown key 'stiffnes' in [vehicle] for type = 'sprung_mass'; allowed "
                "keys: type, mass, stiffness, damping, unsprung_mass, tyre_stiffness, "
                "tyre_damping"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + "[bridge.supports]\nx0 = \"simple\"\nx1 = \"free\"\n")
    with raises(f"{p}: unknown key 'x1' in [bridge.supports]; allowed keys: x0, x_end, y0, "
                "y_end"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE + """
        [[bridge.girders]]
        y = 2.0
        E = 35e9
        mu = 1000
        [bridge.girders.section]
        girder_area = 0.5
        girder_inertia = 0.1
        girder_depth = 1.0
        slab_width = 2.0
        depth = 1.0
    """)
    with raises(f"{p}: unknown key 'depth' in [bridge.girders.section] of entry 1; allowed keys: "
                "girder_area, girder_inertia, girder_depth, slab_width, "
                "girder_centroid_height, slab_thickness, modular_ratio, exclude_slab_bending"):
        scn.load_scenario(p)


@pytest.mark.parametrize(("line", "message"), [
    ("nx = 12.5", "[bridge] nx: expected an integer, got 12.5"),
    ('length = "12"', "[bridge] length: expected a number, got '12'"),
    ("damping_ratio = true", "[bridge] damping_ratio: expected a number, got true"),
    ('E = ["a"]', "[bridge] E: expected a non-empty list of numbers, got ['a']"),
    ('kind = "slab"', "[bridge] kind: unknown value 'slab'; expected one of plate, beam"),
    ("zones = 4", "[bridge]: zones for a plate must be [nzx, nzy], got 4"),
    ("zone_map = [[0, 1], [1]]", "[bridge] zone_map: the rows of the zone map have different "
     "lengths"),
])
def test_wrong_types(tmp_path, line, message):
    key = line.split(" = ")[0]
    text = "\n".join(ln for ln in textwrap.dedent(PLATE).splitlines()
                     if not ln.startswith(f"{key} ")) + f"\n{line}\n"
    p = write(tmp_path, text)
    with raises(f"{p}: {message}"):
        scn.load_scenario(p)


def test_missing_keys_and_sections(tmp_path):
    p = write(tmp_path, PLATE.replace("length = 12.0\n", ""))
    with raises(f"{p}: [bridge] is missing the key 'length'"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE.replace('kind = "plate"\n', ""))
    with raises(f"{p}: [bridge] is missing the key 'kind' (\"plate\" or \"beam\")"):
        scn.load_scenario(p)
    p = write(tmp_path, "[run]\nspeed = 20.0\n")
    s = scn.load_scenario(p)  # valid without a bridge (weighing with influence lines) ...
    with raises(f"{p}: no [bridge] section"):
        scn.build_bridge(s)  # ... until a builder needs one
    p = write(tmp_path, PLATE + '[vehicle]\ntype = "sprung_mass"\nmass = 1.0\n')
    with raises(f"{p}: [vehicle] type = 'sprung_mass' is missing the key 'stiffness'"):
        scn.load_scenario(p)
    p = write(tmp_path, PLATE)
    s = scn.load_scenario(p)
    with raises(f"{p}: no [vehicle] section"):
        scn.build_vehicle(s)
    with raises(f"{p}: no [run] section"):
        scn.simulate_scenario(s)
    p = write(tmp_path, PLATE + "[run]\nspeed = 20.0\n")
    with raises(f"{p}: no [[sensors]] section"):
        scn.simulate_scenario(scn.load_scenario(p))


_GIRDER = "[[bridge.girders]]\ny = 2.0\nE = 35e9\nmu = 1000\n"
_BEAM = (EXAMPLES / "beam.toml").read_text() + '\n[[sensors]]\nx = 3.0\nkind = "strain_y"\n'
_STAGES = {
    "load": lambda s: s,
    "bridge": scn.build_bridge, "vehicle": scn.build_vehicle, "sensors": scn.build_sensors,
    "road": scn.build_road, "passage": scn.build_passage,
}


# (scenario text, the step that must refuse it, the exact message after "<path>: "); the
# library's own messages are kept, prefixed with the file and section
@pytest.mark.parametrize(("text", "stage", "message"), [
    (PLATE.replace("E = 35e9", "E = -35e9"), "bridge",
     "[bridge]: E_x must be positive, got -3.5e+10"),
    (PLATE.replace("E = 35e9", "E_x = [35e9, -1.0]\nE_y = 35e9") + "zones = [2, 1]\n",
     "bridge", "[bridge]: E_x must be positive, got -1"),
    (PLATE + _GIRDER + "I = -0.1\nz_bottom = 0.8\n", "bridge",
     "[[bridge.girders]] entry 1: Girder.I must be positive, got -0.1"),
    (PLATE + _GIRDER, "bridge",
     "[[bridge.girders]] entry 1: give I and z_bottom, or a [bridge.girders.section] table"),
    (PLATE + '[vehicle]\nname = "lorry"\n', "load",
     "[vehicle] name: unknown value 'lorry'; expected one of two_axle_truck, "
     "three_axle_truck, tractor_semitrailer"),
    (PLATE + '[vehicle]\ntype = "bus"\n', "load",
     "[vehicle] type: unknown value 'bus'; expected one of moving_forces, sprung_mass, "
     "half_car, truck3d, tractor_semitrailer"),
    (PLATE + '[vehicle]\nname = "two_axle_truck"\nspeed = 3\n', "load",
     "unknown key 'speed' in [vehicle] with a name; allowed keys: name"),
    (PLATE + '[vehicle]\ntype = "moving_forces"\naxle_loads = [1e5, -1e4]\n'
     "axle_spacings = [4.0]\n", "vehicle", "[vehicle]: axle_loads must be positive, got -10000"),
    (PLATE + "[[sensors]]\nx = [6.0, 13.0]\ny = 2.0\nname = \"s{x:g}\"\n", "sensors",
     "[[sensors]] entry 1: sensor 's13' at x = 13 m, y = 2 m is off the deck (12 m × 8 m)"),
    (PLATE + '[[sensors]]\nx = 6.0\nname = "a"\n[[sensors]]\nx = 7.0\nname = "a"\n',
     "sensors", "[[sensors]] entry 2: sensor name 'a' is already used by entry 1"),
    (PLATE + '[[sensors]]\nx = 6.0\nname = "{z}"\n', "sensors",
     "[[sensors]] entry 1 name: bad template '{z}' ('z'); fields are kind, short, x, y, i"),
    (PLATE + '[[sensors]]\nx = 6.0\nkind = "strain_z"\n', "load",
     "[[sensors]] entry 1 kind: unknown value 'strain_z'; expected one of strain_x, "
     "strain_y, deflection, temperature"),
    (_BEAM, "sensors",
     "[[sensors]] entry 4: sensor 'strain_y@3,0': strain_y is not available on a beam"),
    (PLATE + "zones = [2, 2]\nzone_map = [[0]]\n", "load",
     "[bridge]: give zones or zone_map, not both"),
    (PLATE + "zone_map = [[0, 1], [1, 0]]\n", "bridge",
     "[bridge]: zone_map must have shape (nx, ny) = (6, 4), got (2, 2)"),
    (PLATE + "[road]\nflat = true\nroughness = 1e-6\n", "load",
     "[road]: a flat road takes no other keys, got 'roughness'"),
    (PLATE + "[road]\nseed = 3\n", "load",
     "[road]: needs roughness (ISO 8608), profile (a CSV file) or flat = true"),
    (PLATE + '[road]\nroughness = "Z"\nlength = 10.0\n', "road",
     "[road]: unknown ISO 8608 class 'Z'; expected one of A, B, C, D, E, F, G, H or a "
     "number G_d(n0) in m^3/cycle"),
    (PLATE + '[run]\nspeed = 20.0\nmethod = "exact"\n', "load",
     "[run] method: unknown value 'exact'; expected one of coupled, iterative"),
    (PLATE + '[run]\nspeed = 20.0\n[vehicle]\nname = "two_axle_truck"\n', "passage",
     "[run] needs lane on a plate bridge"),
])
def test_inconsistent_scenarios_are_refused_naming_file_and_section(tmp_path, text, stage,
                                                                   message):
    p = write(tmp_path, text)
    with raises(f"{p}: {message}"):
        _STAGES[stage](scn.load_scenario(p))


def test_missing_road_profile_names_the_file(tmp_path):
    p = write(tmp_path, PLATE + '[road]\nprofile = "missing.csv"\n')
    with raises(f"{tmp_path / 'missing.csv'}: no such file"):
        scn.build_road(scn.load_scenario(p))


def test_scenario_from_dict_uses_the_source_name():
    with raises("my-run: [bridge] length: expected a number, got None"):
        scn.scenario_from_dict({"bridge": {"kind": "beam", "length": None}}, source="my-run")


def test_vehicle_spec_and_lam_are_checked(tmp_path):
    with raises("unknown vehicle 'lorry'; expected one of two_axle_truck, three_axle_truck, "
                "tractor_semitrailer"):
        scn.VehicleSpec(name="lorry")
    with raises("a vehicle spec needs either a name or a type"):
        scn.VehicleSpec()
    p = write(tmp_path, PLATE + '[identify]\nlam = "corner"\n')
    with raises(f"{p}: [identify] lam: unknown value 'corner'; expected one of lcurve, gcv"):
        scn.load_scenario(p)


def test_identify_and_calibrate_options(tmp_path):
    s = load(tmp_path, PLATE + """
        [identify]
        lam = "gcv"
        n_modes = 12
        [calibrate]
        unknowns = ["E_x", "mu"]
        population = [200, 40]
        seed = 3
    """)
    assert s.identify.kwargs() == {"lam": "gcv", "n_modes": 12}
    assert s.calibrate.kwargs() == {"unknowns": ("E_x", "mu"), "population": (200, 40),
                                    "seed": 3}
    s = load(tmp_path, PLATE + '[calibrate]\nweights = "noise"\nmesh_check = 0.05\n'
             'mesh_correction = "auto"\n')
    assert s.calibrate.kwargs() == {"weights": "noise", "mesh_check": 0.05,
                                    "mesh_correction": "auto"}
    s = load(tmp_path, PLATE + '[calibrate]\nmass = "dynamic"\n')
    assert s.calibrate.kwargs() == {"mass": "dynamic"}
    p = write(tmp_path, PLATE + '[calibrate]\nmass = "heavy"\n')
    with pytest.raises(InputError, match=r"\[calibrate\] mass: .*'heavy'"):
        scn.load_scenario(p)
    for bad, shown in (("4", "4"), ("-1", "-1"), ('"fine"', "'fine'"), ("true", "true")):
        p = write(tmp_path, PLATE + f"[calibrate]\nmesh_correction = {bad}\n")
        with raises(f'{p}: [calibrate] mesh_correction: must be an integer from 0 to 3 or '
                    f'"auto", got {shown}'):
            scn.load_scenario(p)


# --- the TOML writer -----------------------------------------------------------------------
_scalars = st.one_of(
    st.booleans(), st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=False), st.text(max_size=12),
)
_arrays = st.lists(_scalars, max_size=6) | st.lists(st.lists(st.integers(), max_size=4),
                                                    max_size=4)
_keys = st.text(min_size=1, max_size=8)
_tables = st.recursive(
    st.dictionaries(_keys, _scalars | _arrays, max_size=5),
    lambda inner: st.dictionaries(_keys, _scalars | _arrays | inner
                                  | st.lists(inner, min_size=1, max_size=3), max_size=5),
    max_leaves=25,
)


@settings(max_examples=150, deadline=None)
@given(_tables)
def test_toml_writer_round_trips(doc):
    assert tomllib.loads(io.to_toml(doc)) == doc


def test_toml_writer_floats_are_exact_and_special_values():
    values = [0.1, 1 / 3, 1e-300, 5e-324, 1.7976931348623157e308, -0.0, 35e9, math.pi]
    back = tomllib.loads(io.to_toml({"v": values, "i": float("inf"), "n": float("nan")}))
    assert back["v"] == values and all(math.copysign(1, a) == math.copysign(1, b)
                                       for a, b in zip(back["v"], values, strict=True))
    assert back["i"] == float("inf") and math.isnan(back["n"])
    with pytest.raises(TypeError):
        io.to_toml({"a": [{"b": 1}, 2]})
