"""A batch's reader of one scenario's logger files (:func:`bwim.scenario.build.
record_reader`, issue 21 item 6: the sensors and format built once) gives the records of
:func:`bwim.scenario.load_record`, and goes to worker processes (pickle)."""

import pickle
from pathlib import Path

import numpy as np

from bwim.scenario import load_record, load_scenario
from bwim.scenario.build import record_reader

SCENARIO = """
[logger]
columns = ["time", "ad1", "s01", "s02", "-"]
sampling_rate = 100.0

[[sensors]]
name = ["s01", "s02"]
kind = "strain_x"
y = [1.5, 3.0]

[[axle_detectors]]
lane = 1
direction = "+x"
channels = ["ad1", "ad2"]
distance = 3.0
"""


def _same(a, b):
    assert np.array_equal(a.time, b.time) and np.array_equal(a.data, b.data)
    assert a.sensors == b.sensors and a.clock == b.clock and a.settings == b.settings


def test_the_reader_gives_load_records_records(tmp_path: Path):
    (tmp_path / "scenario.toml").write_text(SCENARIO.replace(
        'columns = ["time", "ad1", "s01", "s02", "-"]',
        'columns = ["time", "ad1", "ad2", "s01", "s02", "-"]'))
    scenario = load_scenario(tmp_path / "scenario.toml")
    rows = "\n".join(f"{k / 100:.2f}\t{k % 7}\t{k % 5}.5\t{-k}.25\t{k * 2}\tok"
                     for k in range(50))
    paths = []
    for name in ("PL1_2026-07-22-06-00-18-365.txt", "event.csv"):
        (tmp_path / name).write_text(rows + "\n")
        paths.append(tmp_path / name)
    reader = record_reader(scenario)
    again = pickle.loads(pickle.dumps(reader))  # a worker's copy
    for p in paths:
        ref = load_record(p, scenario)
        _same(reader(p), ref)
        _same(again(p), ref)
        assert [s.y for s in reader(p).sensors if s.name.startswith("s")] == [1.5, 3.0]
    assert reader(paths[0]).clock is not None and reader(paths[1]).clock is None
