"""``bwim weigh --parquet`` (issue 21 item 1): summary.parquet beside summary.csv with the
same rows; refused like every output when it exists.  Data: a small realistic day."""

import pytest

from bwim.cli import main
from bwim.io.summary import read_summary

pytest.importorskip("pyarrow")
from bwim.io.summary_parquet import read_summary_parquet


@pytest.fixture(scope="module")
def day(small_site):
    return small_site


def _argv(day, out, *extra):
    return ["weigh", str(day.scenario), str(day.traffic[0].parent), "--calibration-records",
            str(day.calibration[0].parent), "-o", str(out), *extra]


def test_parquet_holds_the_summarys_rows(day, tmp_path):
    out = tmp_path / "out"
    assert main(_argv(day, out, "--parquet")) == 0
    csv_rows = read_summary(out / "summary.csv")
    pq_rows = read_summary_parquet(out / "summary.parquet")
    assert [(r.record, r.vehicle, r.status, r.lane, r.flags) for r in pq_rows] == \
        [(r.record, r.vehicle, r.status, r.lane, r.flags) for r in csv_rows]
    assert any(r.weighed for r in pq_rows)
    for a, b in zip(pq_rows, csv_rows, strict=True):
        assert (a.gvw is None) == (b.gvw is None)
        if a.gvw is not None:  # the CSV holds kN to 2 decimals
            assert a.gvw == pytest.approx(b.gvw, abs=5.0)


def test_an_existing_parquet_is_not_replaced_without_force(day, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.parquet").write_text("precious")
    assert main(_argv(day, out, "--parquet")) == 2
    err = capsys.readouterr().err.strip()
    assert "summary.parquet" in err and "--force" in err and "\n" not in err
    assert (out / "summary.parquet").read_text() == "precious"
    assert not (out / "summary.csv").exists()


def test_a_resume_keeps_the_parquet_summary_up_to_date(day, tmp_path):
    """A batch weighed with ``--parquet`` on its first two files, resumed on all four
    without it: summary.parquet holds the four files' rows, as summary.csv does (review
    of stop 32: it kept the first run's rows)."""
    import shutil

    records = tmp_path / "traffic"
    records.mkdir()
    names = sorted(p.name for p in day.traffic[0].parent.iterdir())
    for name in names[:2]:
        shutil.copy(day.traffic[0].parent / name, records / name)
    out = tmp_path / "out"
    argv = ["weigh", str(day.scenario), str(records), "--calibration-records",
            str(day.calibration[0].parent), "-o", str(out)]
    assert main([*argv, "--parquet"]) == 0
    for name in names[2:]:
        shutil.copy(day.traffic[0].parent / name, records / name)
    assert main([*argv, "--resume"]) == 0
    csv_keys = [(r.record, r.vehicle) for r in read_summary(out / "summary.csv")]
    assert len({k[0] for k in csv_keys}) == len(names) == 4
    assert [(r.record, r.vehicle) for r in read_summary_parquet(out / "summary.parquet")] \
        == csv_keys


def test_force_without_parquet_leaves_no_stale_parquet(day, tmp_path, capsys):
    """A run with --parquet, then a fresh run with --force but no --parquet on one file:
    the earlier run's summary.parquet goes (review of stop 33: it stayed, 7 rows beside a
    summary of 1); without --force the new run is refused for it."""
    out = tmp_path / "out"
    assert main(_argv(day, out, "--parquet")) == 0
    one = ["weigh", str(day.scenario), str(day.traffic[0]), "--calibration-records",
           str(day.calibration[0].parent), "-o", str(out)]
    assert main([*one, "--force"]) == 0
    assert not (out / "summary.parquet").exists()
    assert {r.record for r in read_summary(out / "summary.csv")} == {day.traffic[0].name}
    assert main(_argv(day, out, "--parquet", "--force")) == 0
    for f in out.iterdir():  # an earlier run's summary.parquet alone
        if f.name != "summary.parquet":
            f.unlink()
    capsys.readouterr()
    assert main(one) == 2 and "summary.parquet" in capsys.readouterr().err


def test_mixed_clocks_keep_their_microseconds(tmp_path):
    """Dated clocks and clock times of day in one summary are stored as ISO text: to the
    microsecond, as the contract says (review of stop 33: cut at milliseconds)."""
    from datetime import datetime, time

    from bwim.io.summary_parquet import write_summary_parquet
    from bwim.summary import SummaryRow

    rows = [SummaryRow(record="a", time=datetime(2026, 1, 1, 9, 0, 0, 123456)),
            SummaryRow(record="b", time=time(9, 0, 0, 654321))]
    write_summary_parquet(tmp_path / "s.parquet", rows)
    assert [r.time for r in read_summary_parquet(tmp_path / "s.parquet")] == \
        [r.time for r in rows]
