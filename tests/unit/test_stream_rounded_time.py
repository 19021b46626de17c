"""A long file whose time column is written rounded (a 600 Hz logger writing 4 decimals:
steps of 1.6 and 1.7 ms), cut in blocks of any size (review of stop 33: the trigger
refused the blocks' junctions, one rounded step away from one sample step, and
``bwim weigh --continuous`` lost the rest of the hour).  Reference: the same file read
whole and cut by :func:`bwim.stream.cut_events` (the contract: the events do not depend
on how the stream is split), and the pulse the test writes."""

from __future__ import annotations

import numpy as np
import pytest

from bwim.io import LoggerFormat, read_logger
from bwim.stream import cut_events, cut_file

FS = 600.0


@pytest.fixture(scope="module")
def long_file(tmp_path_factory):
    rng = np.random.default_rng(0)
    n = int(FS * 40)
    x = rng.normal(0.0, 1.0, n)
    x[int(FS * 20):int(FS * 22)] += 50.0 * np.sin(np.linspace(0.0, np.pi, int(FS * 2)))
    path = tmp_path_factory.mktemp("rounded") / "r600.txt"
    with open(path, "w") as f:
        f.write("time;ch1\n")
        f.writelines(f"{k / FS:.4f};{v:.3f}\n" for k, v in enumerate(x))
    return path


@pytest.mark.parametrize("rows", [997, 4023, 5000])
def test_blocks_of_any_size_give_the_whole_files_events(long_file, rows):
    fmt = LoggerFormat(columns=("time", "ch1"))
    whole = read_logger(long_file, fmt)
    assert whole.sampling_rate == pytest.approx(FS, rel=1e-6)  # not the 588 Hz of 1.7 ms
    expected = [(e.start_index, e.stop_index) for e in cut_events(whole).events]
    assert len(expected) == 1 and 19.5 < expected[0][0] / FS < 20.0
    got = [(e.start_index, e.stop_index) for e in cut_file(long_file, fmt, rows=rows)]
    assert got == expected
