"""A long logger file read in blocks (bwim.stream.chunks): the blocks continue one another
and equal the file read whole by bwim.io.read_logger (the reference: the same parser on
the whole text), and the events cut from the blocks equal those cut from the whole record,
also for an event that straddles a block edge."""

import math

import numpy as np
import pytest

from bwim.errors import InputError
from bwim.io import LoggerFormat, read_logger
from bwim.stream import cut_events, cut_file, read_chunks

FS = 512.0
COLUMNS = ("time", "g1", "g2", "-", "ad1")
FMT = LoggerFormat(columns=COLUMNS, kinds={"ad1": "axle_detector"}, sampling_rate=FS)
NAME = "PL1_2026-04-17-12-15-14-417.txt"


def _rows(total: float, pulses, seed=0) -> np.ndarray:
    """Time, two gauges (offsets 30, −12, σ 0.5) with half-sine pulses (t0, D, A), a
    status column and a detector."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(total * FS)) / FS
    s = np.zeros_like(t)
    for t0, d, a in pulses:
        on = (t >= t0) & (t <= t0 + d)
        s += np.where(on, a * np.sin(math.pi * (t - t0) / d), 0.0)
    g1 = 30.0 + 0.6 * s + 0.5 * rng.standard_normal(t.size)
    g2 = -12.0 + 0.4 * s + 0.5 * rng.standard_normal(t.size)
    return np.column_stack([t, g1, g2, np.ones_like(t), rng.standard_normal(t.size)])


def _write(path, rows, *, header=None, preamble=(), time=True):
    with open(path, "w") as f:
        f.writelines(f"{line}\n" for line in preamble)
        if header:
            f.write("\t".join(header) + "\n")
        for r in rows:
            cells = ([f"{r[0]:.9f}"] if time else []) + [f"{r[1]:.3f}", f"{r[2]:.3f}", "1",
                                                          f"{r[4]:.3f}"]
            f.write("\t".join(cells) + "\n")
    return path


def test_blocks_continue_and_equal_the_whole_file(tmp_path):
    path = _write(tmp_path / NAME, _rows(10.0, [(4.0, 1.0, 100.0)]),
                  header=("t", "a", "b", "s", "d"), preamble=("logger 7", "# site"))
    fmt = LoggerFormat(columns=COLUMNS, kinds={"ad1": "axle_detector"}, sampling_rate=FS,
                       skip_lines=1)
    whole = read_logger(path, fmt)
    blocks = list(read_chunks(path, fmt, rows=1000))
    assert [b.time.size for b in blocks] == [999, 1000, 1000, 1000, 1000, 121]
    np.testing.assert_array_equal(np.concatenate([b.time for b in blocks]), whole.time)
    np.testing.assert_array_equal(np.concatenate([b.data for b in blocks]), whole.data)
    assert whole.clock is not None
    assert all(b.clock == whole.clock for b in blocks)
    assert [s.kind.value for s in blocks[-1].sensors] == ["strain_x", "strain_x",
                                                          "axle_detector"]


def test_a_last_block_of_one_row_joins_the_one_before(tmp_path):
    path = _write(tmp_path / NAME, _rows(2001 / FS, []))
    assert [b.time.size for b in read_chunks(path, FMT, rows=1000)] == [1000, 1001]


def test_without_a_time_column_the_time_counts_on(tmp_path):
    fmt = LoggerFormat(columns=COLUMNS[1:], kinds={"ad1": "axle_detector"},
                       sampling_rate=FS)
    path = _write(tmp_path / NAME, _rows(5.0, []), time=False)
    blocks = list(read_chunks(path, fmt, rows=700))
    np.testing.assert_array_equal(np.concatenate([b.time for b in blocks]),
                                  np.arange(2560) / FS)


def test_an_event_across_a_block_edge_is_cut_as_from_the_whole_file(tmp_path):
    """Blocks of 3000 rows: the second pulse (about 5.6–6.6 s, rows 2870–3380) straddles
    the first edge (row 3000); the third starts just after the second (row 6000)."""
    pulses = [(2.0, 1.0, 80.0), (5.6, 1.0, 150.0), (11.8, 0.8, 60.0), (16.0, 1.2, 100.0)]
    path = _write(tmp_path / NAME, _rows(20.0, pulses, seed=2))
    whole = cut_events(read_logger(path, FMT)).events
    streamed = list(cut_file(path, FMT, rows=3000))
    assert len(whole) == len(streamed) == 4
    assert whole[1].start_index < 3000 < whole[1].stop_index
    for w, s in zip(whole, streamed, strict=True):
        assert (w.start_index, w.stop_index, w.on, w.off, w.peak, w.flags) == \
            (s.start_index, s.stop_index, s.on, s.off, s.peak, s.flags)
        assert w.record.clock == s.record.clock
        np.testing.assert_array_equal(w.record.time, s.record.time)
        np.testing.assert_array_equal(w.record.data, s.record.data)


def test_a_bad_line_is_named_in_the_long_file(tmp_path):
    rows = _rows(5.0, [])
    path = _write(tmp_path / NAME, rows)
    lines = path.read_text().splitlines()
    lines[2345] = lines[2345].replace("\t1\t", "\tx\t", 1).replace("\t", "\t?", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        list(read_chunks(path, FMT, rows=1000))
    msg = str(info.value)
    assert msg.startswith(f"{path}: line 2346") and "'?" in msg


def test_a_dropped_sample_at_a_block_edge_is_refused(tmp_path):
    rows = np.delete(_rows(5.0, []), 1000, axis=0)
    path = _write(tmp_path / NAME, rows)
    with pytest.raises(InputError, match=r"time steps 0.00390625 s between line 1000 and "
                                         r"line 1001"):
        list(read_chunks(path, FMT, rows=1000))


def test_a_file_that_is_not_utf8(tmp_path):
    path = tmp_path / NAME
    path.write_bytes(b"0.0\t1\t2\t1\t0\n0.001953125\t\xff\t2\t1\t0\n")
    with pytest.raises(InputError, match="not UTF-8 text"):
        list(read_chunks(path, FMT))


def test_bad_arguments(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        list(read_chunks(tmp_path / "none.txt", FMT))
    with pytest.raises(InputError, match="not a regular file"):
        list(read_chunks(tmp_path, FMT))
    with pytest.raises(InputError, match="rows must be an integer >= 2"):
        list(read_chunks(tmp_path / "none.txt", FMT, rows=1))
