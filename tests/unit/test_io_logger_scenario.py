"""A real installation's scenario: [logger], [axle_detectors], gauges without positions,
a calibration truck known by its static axle loads, no [bridge] (issue 11's contract)."""

import numpy as np
import pytest

from bwim import scenario as scn
from bwim.errors import InputError
from bwim.scenario.build import build_logger_format, build_sensors, build_vehicle, load_record
from bwim.sensors import SensorKind

GAUGES = [f"s{i:02d}" for i in range(1, 15)]
SITE = f"""
[logger]
columns = ["time", "ad1", "ad2", {", ".join(f'"{g}"' for g in GAUGES)}, "-", "-"]
[[sensors]]
name = [{", ".join(f'"{g}"' for g in GAUGES)}]
kind = "strain_x"
[axle_detectors]
channels = ["ad1", "ad2"]
distance = 3.0
[vehicle]          # the calibration truck
axle_spacings = [3.8, 6.0, 1.3, 1.3]
axle_loads = [61607.0, 108499.0, 90841.0, 69847.0, 70632.0]   # static, N
"""


def _write(tmp_path, text, name="site.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _event(tmp_path, name, delimiter, header, n=300, rate=512.0, t0=36000.0):
    rng = np.random.default_rng(1)
    data = rng.normal(size=(n, 16))
    t = t0 + np.arange(n) / rate
    cols = ["time", "ad1", "ad2", *GAUGES, "temp", "status"]
    lines = [delimiter.join(cols)] if header else []
    for k in range(n):
        fields = [f"{t[k]:.6f}", *(f"{v:.6f}" for v in data[k]), "12.5", "OK"]
        lines.append(delimiter.join(fields))
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return p, t, data


def test_the_issue_scenario_parses_and_builds(tmp_path):
    s = scn.load_scenario(_write(tmp_path, SITE))
    assert s.bridge is None
    sensors = build_sensors(s)
    assert [x.name for x in sensors] == GAUGES
    assert all(x.x is None and x.kind is SensorKind.STRAIN_X for x in sensors)
    truck = build_vehicle(s)
    np.testing.assert_array_equal(truck.axle_spacings, [3.8, 6.0, 1.3, 1.3])
    assert truck.static_axle_loads.sum() == pytest.approx(401426.0)
    fmt = build_logger_format(s)
    assert fmt.kinds["ad1"] is SensorKind.AXLE_DETECTOR
    [pair] = s.axle_detectors  # the single [axle_detectors] table: one lane
    assert pair.distance == 3.0 and pair.channels == ("ad1", "ad2")


@pytest.mark.parametrize(("name", "delimiter", "header"), [
    ("e.txt", "\t", True), ("e.csv", ",", False), ("e.dat", ";", True), ("e.log", " ", False),
])
def test_logger_files_of_any_shape_load(tmp_path, name, delimiter, header):
    s = scn.load_scenario(_write(tmp_path, SITE))
    p, t, data = _event(tmp_path, name, delimiter, header)
    rec = load_record(p, s)
    np.testing.assert_allclose(rec.time, t, rtol=0, atol=1e-6)
    np.testing.assert_allclose(rec.data, data, rtol=0, atol=1e-6)
    assert [x.name for x in rec.sensors] == ["ad1", "ad2", *GAUGES]
    assert rec.passages == ()


def test_scenario_round_trip(tmp_path):
    s = scn.load_scenario(_write(tmp_path, SITE))
    out = tmp_path / "again.toml"
    scn.dump_scenario(s, out)
    assert scn.load_scenario(out) == s


@pytest.mark.parametrize(("change", "message"), [
    (("distance = 3.0", "distance = -3.0"), "distance must be positive"),
    (('channels = ["ad1", "ad2"]', 'channels = ["ad1", "ad1"]'), "two different"),
    (('channels = ["ad1", "ad2"]', 'channels = ["ad1"]'), "two different"),
    (('"-", "-"]', '"-", "s01"]'), "appears twice"),
    (('columns = ["time", ', 'columns = ['), "needs a 'time' column or sampling_rate"),
])
def test_bad_site_scenarios(tmp_path, change, message):
    p = _write(tmp_path, SITE.replace(*change))
    with pytest.raises(InputError, match=message):
        scn.load_scenario(p)


def test_columns_must_match_the_channels(tmp_path):
    s = scn.load_scenario(_write(tmp_path, SITE.replace('"-", "-"]', '"s99", "-"]')))
    with pytest.raises(InputError, match="'s99' is neither a"):
        build_logger_format(s)
    s = scn.load_scenario(_write(tmp_path, SITE.replace('"ad2", ', '"-", ')))
    with pytest.raises(InputError, match="no column for the \\[axle_detectors\\] channel 'ad2'"):
        build_logger_format(s)


def test_a_missing_column_in_the_file_is_one_line(tmp_path):
    s = scn.load_scenario(_write(tmp_path, SITE))
    p, _, _ = _event(tmp_path, "short.txt", "\t", True)
    text = p.read_text().splitlines()
    text[5] = "\t".join(text[5].split("\t")[:-1])
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError) as err:
        load_record(p, s)
    assert "short.txt" in str(err.value) and "\n" not in str(err.value)


def test_named_gauges_with_transverse_positions(tmp_path):
    text = SITE.replace('kind = "strain_x"', 'kind = "strain_x"\ny = [' +
                        ", ".join(f"{0.5 + 0.7 * i:.1f}" for i in range(14)) + "]")
    sensors = build_sensors(scn.load_scenario(_write(tmp_path, text)))
    assert [x.y for x in sensors] == pytest.approx([0.5 + 0.7 * i for i in range(14)])
    assert all(x.x is None for x in sensors)


def test_lines_section_keeps_the_lobes(tmp_path):
    """``[lines] support_lobes`` reaches the site setup, survives a round trip, and is off
    without the section; anything but a boolean is refused in one line."""
    from bwim.scenario import build_site_setup

    assert build_site_setup(scn.load_scenario(_write(tmp_path, SITE))).support_lobes is False
    s = scn.load_scenario(_write(tmp_path, SITE + "[lines]\nsupport_lobes = true\n"))
    assert s.lines.support_lobes is True and build_site_setup(s).support_lobes is True
    out = tmp_path / "again.toml"
    scn.dump_scenario(s, out)
    assert scn.load_scenario(out) == s
    for bad, message in (('support_lobes = "yes"', "support_lobes"),
                         ("lobes = true", "lobes")):
        with pytest.raises(InputError, match=message) as info:
            scn.load_scenario(_write(tmp_path, SITE + f"[lines]\n{bad}\n", name="bad.toml"))
        assert "\n" not in str(info.value)


def test_drift_section_reaches_the_site_setup(tmp_path):
    """``[drift]``'s keys reach :class:`bwim.site.DriftSetup` (kN to N), survive a round
    trip, and keep the setup's defaults when absent; a minimum below 3 is one line."""
    from bwim.scenario import build_site_setup
    from bwim.site import DriftSetup

    assert build_site_setup(scn.load_scenario(_write(tmp_path, SITE))).drift == DriftSetup()
    s = scn.load_scenario(_write(tmp_path, SITE + '[drift]\nmethod = "traffic"\n'
                                 'reference_class = "113"\nreference_kN = 60.0\n'
                                 "min_reference = 10\n"))
    d = build_site_setup(s).drift
    assert (d.method, d.reference_class, d.reference_load, d.min_reference) == \
        ("traffic", "113", 60e3, 10)
    out = tmp_path / "again.toml"
    scn.dump_scenario(s, out)
    assert scn.load_scenario(out) == s
    with pytest.raises(InputError, match="min_reference") as info:
        scn.load_scenario(_write(tmp_path, SITE + "[drift]\nmin_reference = 2\n",
                                 name="bad.toml"))
    assert "\n" not in str(info.value)


def test_trigger_section_reaches_the_trigger_settings(tmp_path):
    """``[trigger]``'s keys reach :class:`bwim.stream.TriggerSettings` (the others keep
    their defaults; without the section, every default), survive a round trip; a bad key
    or value, and settings the trigger refuses together (off not below on), are one line
    naming the section."""
    from bwim.scenario import build_trigger
    from bwim.stream import TriggerSettings

    assert build_trigger(scn.load_scenario(_write(tmp_path, SITE))) == TriggerSettings()
    s = scn.load_scenario(_write(tmp_path, SITE + "[trigger]\non = 8.0\npre = 1.5\n"
                                 "max_duration = 30\nnoise = 0.4\n"
                                 'channels = ["s01", "s02"]\n'))
    assert build_trigger(s) == TriggerSettings(on=8.0, pre=1.5, max_duration=30.0, noise=0.4,
                                               channels=("s01", "s02"))
    out = tmp_path / "again.toml"
    scn.dump_scenario(s, out)
    assert scn.load_scenario(out) == s
    for bad, message in (("on = -1", "on"), ("post = -0.5", "post"), ("gap = 2", "gap"),
                         ('channels = "s01"', "channels")):
        with pytest.raises(InputError, match=message) as info:
            scn.load_scenario(_write(tmp_path, SITE + f"[trigger]\n{bad}\n", name="bad.toml"))
        assert "\n" not in str(info.value)
    s = scn.load_scenario(_write(tmp_path, SITE + "[trigger]\non = 3\n", name="bad.toml"))
    with pytest.raises(InputError, match=r"\[trigger\].*off must be below on") as info:
        build_trigger(s)
    assert "\n" not in str(info.value)


def test_a_pairs_longest_vehicle_is_read_and_checked(tmp_path):
    """``max_length`` in ``[axle_detectors]`` reaches the site's detector lane (25.25 m
    where European Modular System combinations run; 18.75 m without it); zero or less is
    refused in one line naming the table."""
    from bwim.scenario import build_site_setup
    from bwim.site.setup import MAX_WHEELBASE

    [lane] = build_site_setup(scn.load_scenario(_write(tmp_path, SITE))).lanes
    assert lane.max_length == MAX_WHEELBASE == 18.75
    ems = SITE.replace("distance = 3.0\n", "distance = 3.0\nmax_length = 25.25\n")
    [lane] = build_site_setup(scn.load_scenario(_write(tmp_path, ems))).lanes
    assert lane.max_length == 25.25
    bad = SITE.replace("distance = 3.0\n", "distance = 3.0\nmax_length = 0\n")
    with pytest.raises(InputError, match=r"\[axle_detectors\]: max_length must be positive"):
        scn.load_scenario(_write(tmp_path, bad))
