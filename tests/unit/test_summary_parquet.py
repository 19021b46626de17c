"""summary.parquet (issue 21 item 1: Parquet beside CSV, units in the column names): the
rows round-trip exactly, the columns are summary.csv's with types, and a bad file or a
missing pyarrow is one line.  Reference: rows the test makes."""

import dataclasses
from datetime import datetime
from datetime import time as dtime

import pytest

from bwim.errors import InputError
from bwim.io.summary import COLUMNS
from bwim.summary import SummaryRow

pa = pytest.importorskip("pyarrow")
from bwim.io.summary_parquet import read_summary_parquet, write_summary_parquet  # noqa: E402


def _rows(time=datetime(2015, 10, 1, 9, 45, 52, 576123)):
    return [
        SummaryRow(record="PL1_a.txt", vehicle=1, time=time, lane=1, direction="+x",
                   vehicle_class="113", n_axles=5, speed=22.417,
                   axle_spacings=(3.6, 6.01, 1.31, 1.31),
                   axle_weights=(55123.4, 101234.5, 80111.1, 80111.1, 80111.1),
                   gvw=396691.2, group_weights=(55123.4, 101234.5, 240333.3),
                   flags=("outside_calibration_time",), lateral=5.93, lateral_unit="m",
                   group_laterals=(5.812, 6.034, 5.95), confidence=0.97,
                   residual=0.143, quality="warning", method="moses",
                   drift_factor=1.0713, drift_method="traffic"),
        SummaryRow(record="PL1_a.txt", vehicle=2, time=None, lane=3, direction="-x",
                   n_axles=4, speed=21.0, axle_spacings=(3.2, 5.9, 1.3),
                   flags=("multiple_presence",),
                   reason="counted, not weighed: no lines for lane 3 (-x)"),
        SummaryRow(record="broken.txt", status="failed", reason="broken.txt: line 3: empty field"),
    ]


@pytest.mark.parametrize("time", [datetime(2015, 10, 1, 9, 45, 52, 576123),
                                  dtime(9, 45, 52, 576000)])
def test_rows_round_trip_exactly(tmp_path, time):
    rows = _rows(time)
    path = tmp_path / "summary.parquet"
    write_summary_parquet(path, rows)
    back = read_summary_parquet(path)
    assert len(back) == len(rows)
    for a, b in zip(back, rows, strict=True):
        for f in dataclasses.fields(SummaryRow):
            x, y = getattr(a, f.name), getattr(b, f.name)
            if isinstance(y, tuple) and y and isinstance(y[0], float):
                assert x == pytest.approx(y, rel=1e-15), f.name
            elif isinstance(y, float):
                assert x == pytest.approx(y, rel=1e-15), f.name
            else:
                assert x == y, f.name


def test_columns_are_the_csv_ones_typed(tmp_path):
    path = tmp_path / "s.parquet"
    write_summary_parquet(path, _rows())
    table = pa.parquet.read_table(path)
    assert tuple(table.column_names) == COLUMNS
    schema = table.schema
    assert schema.field("gvw_kN").type == pa.float64()
    assert schema.field("axle_weights_kN").type == pa.list_(pa.float64())
    assert schema.field("time").type == pa.timestamp("us")
    assert schema.field("n_axles").type == pa.int32()
    assert table.column("gvw_kN").to_pylist()[0] == pytest.approx(396.6912)
    assert table.column("gvw_kN").to_pylist()[1] is None  # refused: no weight


def test_a_version_1_file_reads_without_the_group_positions(tmp_path):
    """Version 1 (before ``group_laterals``): the same rows, that column not measured."""
    path = tmp_path / "v1.parquet"
    write_summary_parquet(path, _rows())
    table = pa.parquet.read_table(path)
    table = table.drop_columns(["group_laterals"]).replace_schema_metadata(
        {"bwim.columns_version": "1"})
    pa.parquet.write_table(table, path)
    back = read_summary_parquet(path)
    assert [r.group_laterals for r in back] == [(), (), ()]
    assert [r.gvw for r in back] == [r.gvw for r in _rows()]


def test_a_file_that_is_not_a_summary_is_one_line(tmp_path):
    bad = tmp_path / "x.parquet"
    bad.write_text("not parquet")
    with pytest.raises(InputError, match="not a readable Parquet file"):
        read_summary_parquet(bad)
    other = tmp_path / "o.parquet"
    pa.parquet.write_table(pa.table({"a": [1]}), other)
    with pytest.raises(InputError, match="not a bwim summary"):
        read_summary_parquet(other)


def test_the_parquet_file_has_the_usual_permissions(tmp_path):
    """Written through bwim.atomic like every other output: the mode the umask gives a new
    file (0644 under umask 022), not a private temporary file's 0600."""
    import os

    from bwim.io.summary_parquet import write_summary_parquet
    from bwim.summary import SummaryRow

    old = os.umask(0o022)
    try:
        out = tmp_path / "summary.parquet"
        write_summary_parquet(out, [SummaryRow(record="e1.txt", status="failed",
                                               reason="unreadable")])
    finally:
        os.umask(old)
    assert out.stat().st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["summary.parquet"]
