"""Issue 14: hypothesis fuzzing of the TOML scenario reader (and the builders it feeds) and
of the HDF5 record reader: whatever the input, the outcome is a value or an InputError,
never another exception.  Reference: the readers' contracts (bwim.scenario, _hdf5)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import bwim
from bwim.errors import InputError
from bwim.io import read_record, write_record
from bwim.limits import ENV_VAR
from bwim.scenario import build_bridge, build_road, build_sensors, build_vehicle, load_scenario

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = (ROOT / "examples" / "beam.toml").read_text(encoding="utf-8")
SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])


@pytest.fixture(autouse=True)
def small_limit(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "64M")


def _scenario_outcome(text: str) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "s.toml"
        p.write_text(text, encoding="utf-8", errors="surrogatepass")
        try:
            s = load_scenario(p)
            if s.bridge is not None:
                b = build_bridge(s)
                build_sensors(s) and b.sensor_matrix(build_sensors(s))
            if s.vehicle is not None:
                build_vehicle(s)
            if s.road is not None and s.bridge is not None:
                build_road(s)
        except InputError as exc:
            assert str(exc)


VALUES = st.one_of(
    st.integers(-10**12, 10**12).map(str), st.floats(allow_nan=True).map(
        lambda v: "nan" if v != v else ("inf" if v == float("inf") else
                                        "-inf" if v == -float("inf") else repr(v))),
    st.sampled_from(['"A"', '"x"', "true", "[]", "[1, 2]", "{}", '"../../etc/passwd"',
                     "1e300", "-1", "0", "[[1,2],[3]]", '""']),
)


@SETTINGS
@given(data=st.data())
def test_scenario_values_fuzzed(data):
    """Each ``key = value`` line of the example gets an arbitrary TOML value."""
    lines = EXAMPLE.splitlines()
    keyed = [i for i, ln in enumerate(lines) if " = " in ln and not ln.startswith("#")]
    for i in data.draw(st.lists(st.sampled_from(keyed), min_size=1, max_size=3)):
        key = lines[i].split(" = ")[0]
        lines[i] = f"{key} = {data.draw(VALUES)}"
    _scenario_outcome("\n".join(lines) + "\n")


@SETTINGS
@given(cut=st.integers(0, len(EXAMPLE)), junk=st.text(max_size=40))
def test_scenario_text_fuzzed(cut, junk):
    """Arbitrary text spliced into the example (broken syntax, stray characters)."""
    _scenario_outcome(EXAMPLE[:cut] + junk + EXAMPLE[cut:])


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    bridge = bwim.Bridge.beam(length=20.0, n_elements=10, E=3e10, I=1.0, mu=1e4,
                              z_bottom=0.5)
    truck = bwim.MovingForces(axle_loads=[50e3, 100e3], axle_spacings=[4.0])
    rec = bwim.simulate(bridge, truck, speed=20.0, sensors=[bwim.Sensor(x=10.0)],
                        sampling_rate=100.0, approach=0.0)
    p = tmp_path_factory.mktemp("h5") / "r.h5"
    write_record(rec, p)
    return p


def _items(f: h5py.File) -> list[str]:
    names: list[str] = []
    f.visit(names.append)
    return names


ODD = st.one_of(
    st.just(np.zeros((0,))), st.just(np.array([np.nan, 1.0])), st.just(np.array(["a", "b"],
                                                                              dtype="S")),
    st.just(np.ones((2, 3, 4))), st.just(np.array([1, 2], dtype=np.int8)),
    st.just(np.array(1.5)), st.just(np.array([True])), st.just(np.array([b"\xff\xfe"])),
)


@SETTINGS
@given(data=st.data())
def test_hdf5_record_structure_fuzzed(record_file, data):
    """Datasets replaced by odd arrays, items deleted, attributes changed."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "r.h5"
        shutil.copy(record_file, p)
        with h5py.File(p, "a") as f:
            names = _items(f)
            for _ in range(data.draw(st.integers(1, 3))):
                name = data.draw(st.sampled_from(names))
                if name not in f:
                    continue
                action = data.draw(st.sampled_from(["delete", "replace", "attr"]))
                if action == "delete":
                    del f[name]
                elif action == "replace":
                    del f[name]
                    f.create_dataset(name, data=data.draw(ODD))
                else:
                    obj = f[name]
                    keys = list(obj.attrs) or ["x"]
                    obj.attrs[data.draw(st.sampled_from(keys))] = data.draw(ODD)
            if data.draw(st.booleans()):
                f.attrs["bwim_format_version"] = data.draw(st.sampled_from(
                    [np.array([1, 2]), "one", 10**6, -1]))
        try:
            read_record(p)
        except InputError:
            pass


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pos=st.lists(st.integers(0, 10**6), min_size=1, max_size=8),
       byte=st.integers(0, 255))
@example(pos=[112], byte=0)  # found by this test: a damaged object header (KeyError)
def test_hdf5_record_bytes_fuzzed(record_file, pos, byte):
    """Bytes of the file overwritten (a damaged disk or transfer)."""
    raw = bytearray(record_file.read_bytes())
    for k in pos:
        raw[k % len(raw)] = byte
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "r.h5"
        p.write_bytes(bytes(raw))
        try:
            read_record(p)
        except InputError:
            pass


