"""A logger file's wall clock (bwim.io.clock, issue 20 item 3): from the file name in the
common forms or a pattern, or from clock columns; Record.clock at record time 0.

References: the dates and times written by hand in each file name or column (the
expected datetimes are read off the text, not from the code); the rule of the contract
``Record.clock = clock of the first row − time[0]``.
"""

import re
from datetime import datetime, timedelta

import numpy as np
import pytest

from bwim.errors import InputError
from bwim.io.clock import ClockRow, ClockSpec, logger_clock, name_timestamp
from bwim.io.logger import LoggerFormat, read_logger

FS = 512.0


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("2015-09-29-09-28-46-125.txt", datetime(2015, 9, 29, 9, 28, 46, 125000)),
        ("PL1_2015-10-01-09-45-52-576.txt", datetime(2015, 10, 1, 9, 45, 52, 576000)),
        ("2015-10-01-09-45-52.txt", datetime(2015, 10, 1, 9, 45, 52)),
        ("site3_20151001_094552.dat", datetime(2015, 10, 1, 9, 45, 52)),
        ("20151001_094552.576.txt", datetime(2015, 10, 1, 9, 45, 52, 576000)),
        ("20151001T094552,5.txt", datetime(2015, 10, 1, 9, 45, 52, 500000)),
        ("ev_2015-10-01T09:45:52.576.csv", datetime(2015, 10, 1, 9, 45, 52, 576000)),
        ("ev_2015-10-01T09-45-52.576.csv", datetime(2015, 10, 1, 9, 45, 52, 576000)),
        ("ev_2015-10-01T094552.csv", datetime(2015, 10, 1, 9, 45, 52)),
        ("2015-10-01_09-45-52_run7.txt", datetime(2015, 10, 1, 9, 45, 52)),
        ("2015-12-31-23-59-59-999999.txt", datetime(2015, 12, 31, 23, 59, 59)),  # ms: 3
        ("a_2015-10-01-09-45-52-1234.txt", datetime(2015, 10, 1, 9, 45, 52)),  # not ms
        ("20151001T094552.1234567.txt", datetime(2015, 10, 1, 9, 45, 52, 123456)),  # cut
    ],
)
def test_default_name_forms(name, expected):
    stamp = name_timestamp(name)
    assert stamp is not None and stamp.instant == expected and stamp.has_time


@pytest.mark.parametrize("name", [
    "cal_01_093012.txt", "evt_0001_093012.txt", "event.txt", "2015-10-01.txt",
    "2015-13-01-09-45-52.txt",     # month 13: not a date
    "2015-02-30-09-45-52.txt",     # 30 February
    "12015-10-01-09-45-52.txt",    # a longer run of digits
    "20151001094552.txt",          # no separator between date and time
    "2015-10-01T25:00:00.txt",     # hour 25
])
def test_names_without_a_timestamp(name):
    assert name_timestamp(name) is None


def test_leftmost_timestamp_wins():
    stamp = name_timestamp("20151001_094552_copy_of_2015-09-29-09-28-46.txt")
    assert stamp.instant == datetime(2015, 10, 1, 9, 45, 52)
    stamp = name_timestamp("2015-09-29-09-28-46_copy_of_20151001_094552.txt")
    assert stamp.instant == datetime(2015, 9, 29, 9, 28, 46)


def test_patterns():
    stamp = name_timestamp("bridge_01.10.2015_0945h.txt", "%d.%m.%Y_%H%Mh")
    assert stamp.instant == datetime(2015, 10, 1, 9, 45) and stamp.has_time
    stamp = name_timestamp("x_2015-274_12-00-00-5.txt", "%Y-%j_%H-%M-%S-%f")
    assert stamp.instant == datetime(2015, 10, 1, 12, 0, 0, 500000)
    stamp = name_timestamp("day_2015-10-01.txt", "%Y-%m-%d")
    assert stamp.instant == datetime(2015, 10, 1) and not stamp.has_time
    assert name_timestamp("day_2015-10-01.txt", "%Y%m%d") is None
    assert name_timestamp("d_2015-10-01_x.txt", "%y-%m-%d") is None   # inside 2015: digits
    # the first candidate is not a valid date: the next one is taken
    stamp = name_timestamp("2015-13-01_2015-10-01.txt", "%Y-%m-%d")
    assert stamp.instant == datetime(2015, 10, 1)


@pytest.mark.parametrize(
    ("kw", "reason"),
    [
        (dict(pattern="%H%M%S"), "must hold a year (%Y or %y) and a month and day"),
        (dict(pattern="%Y-%m"), "must hold a year (%Y or %y) and a month and day"),
        (dict(pattern="%Y%q"), "%q is not supported"),
        (dict(pattern="%Y-%m-%d%"), "a lone % is not supported"),
        (dict(pattern=" %Y"), "must be a non-empty text without surrounding spaces"),
        (dict(pattern="%Y-%m-%d", from_name=False), "a pattern reads the file name"),
        (dict(date_column="d"), "date_column needs the column of the time of day"),
        (dict(column="c", date_column="c"), "must be another column"),
        (dict(format="%H:%M"), "format reads the text of a clock column"),
        (dict(column="time", format="%H:%M"), "format reads the text of a clock column"),
        (dict(column="c", format="%Y-%m-%d"), "must hold a time of day"),
        (dict(column="c", date_column="d", format="%H:%M"), "it must hold the date too"),
        (dict(column="-"), "cannot be '-'"),
        (dict(from_name="yes"), "from_name must be true or false"),
    ],
)
def test_bad_specs(kw, reason):
    with pytest.raises(InputError) as exc:
        ClockSpec(**kw)
    assert reason in str(exc.value) and "\n" not in str(exc.value)


# --- through read_logger ------------------------------------------------------------------

def _write(path, time, extra=None, *, sep="\t", header=True):
    """A logger file: time, two channels, and optional text columns ``extra`` (a list of
    (name, per-row texts)) after them."""
    extra = extra or []
    rng = np.random.default_rng(1)
    data = rng.normal(size=(len(time), 2)).round(3)
    rows = []
    if header:
        rows.append(sep.join(["time", "a", "b", *[n for n, _ in extra]]))
    for k in range(len(time)):
        rows.append(sep.join([f"{time[k]:.6f}", f"{data[k, 0]:.3f}", f"{data[k, 1]:.3f}",
                              *[v[k] for _, v in extra]]))
    path.write_text("\n".join(rows) + "\n")
    return data


def test_name_clock_is_record_time_zero(tmp_path):
    """Time column from 0, clock in the name: Record.clock is the name's instant (the
    contract's rule with time[0] = 0); an old-style name gives None."""
    p = tmp_path / "PL1_2015-10-01-09-45-52-576.txt"
    _write(p, np.arange(100) / FS)
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    assert r.clock == datetime(2015, 10, 1, 9, 45, 52, 576000)
    assert r.clock_at(1.0) == datetime(2015, 10, 1, 9, 45, 53, 576000)
    q = tmp_path / "evt_0001_094552.txt"
    _write(q, np.arange(100) / FS)
    assert read_logger(q, LoggerFormat(columns=("time", "a", "b"))).clock is None
    off = LoggerFormat(columns=("time", "a", "b"), clock=ClockSpec(from_name=False))
    assert read_logger(p, off).clock is None


def test_name_clock_with_a_time_of_day_column(tmp_path):
    """A time column of clock time (09:45:52.5 = 35152.5 s since midnight) and the same
    instant in the name: Record.clock is that midnight, clock_seconds() of the first
    sample is the name's instant."""
    p = tmp_path / "2015-10-01-09-45-52-500.txt"
    _write(p, 35152.5 + np.arange(100) / FS)
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    assert r.clock == datetime(2015, 10, 1)
    assert r.clock_at() == datetime(2015, 10, 1, 9, 45, 52, 500000)


def test_pattern_mismatch_and_date_only_pattern(tmp_path):
    p = tmp_path / "station7_2015-10-01_0945.txt"
    _write(p, np.arange(50) / FS)
    f = LoggerFormat(columns=("time", "a", "b"), clock=ClockSpec(pattern="%Y%m%d_%H%M%S"))
    with pytest.raises(InputError) as exc:
        read_logger(p, f)
    msg = str(exc.value)
    assert msg == (f"{p}: the file name has no clock time in the pattern '%Y%m%d_%H%M%S'")
    f = LoggerFormat(columns=("time", "a", "b"), clock=ClockSpec(pattern="%Y-%m-%d_%H%M"))
    assert read_logger(p, f).clock == datetime(2015, 10, 1, 9, 45)
    f = LoggerFormat(columns=("time", "a", "b"), clock=ClockSpec(pattern="%Y-%m-%d"))
    assert read_logger(p, f).clock == datetime(2015, 10, 1)     # time column = time of day


def test_clock_columns(tmp_path):
    """Clock in the file: s since midnight (date from the name), ISO text, a date and a
    time column, a strptime format, the time column as the time of day; the text columns
    sit among numeric channels and the header is still detected."""
    t = np.arange(600) / FS                         # 1.17 s from 0
    sod = [f"{34200.25 + k / FS:.4f}" for k in range(600)]              # 09:30:00.25
    iso = [(datetime(2015, 10, 1, 9, 30, 0, 250000) + timedelta(seconds=k / FS))
           .isoformat(timespec="milliseconds") for k in range(600)]
    day = ["2015-10-01"] * 600
    tod = [s[11:] for s in iso]
    eu = [f"01.10.2015 {s}" for s in tod]
    p = tmp_path / "run_2015-10-01-09-30-00.txt"
    data = _write(p, t, [("sod", sod), ("iso", iso), ("day", day), ("tod", tod), ("eu", eu)])
    cols = ("time", "a", "b", "sod", "iso", "day", "tod", "eu")
    expected = datetime(2015, 10, 1, 9, 30, 0, 250000)
    for spec in (ClockSpec(column="sod"), ClockSpec(column="iso"),
                 ClockSpec(column="tod", date_column="day"), ClockSpec(column="tod"),
                 ClockSpec(column="eu", format="%d.%m.%Y %H:%M:%S.%f"),
                 ClockSpec(column="tod", date_column="day", format="%Y-%m-%d %H:%M:%S.%f")):
        used = ("time", "a", "b", *spec.columns)
        f = LoggerFormat(columns=tuple(c if c in used else "-" for c in cols), clock=spec)
        r = read_logger(p, f)
        assert r.clock == expected, spec
        assert np.array_equal(r.data, data) and f.channels == ("a", "b")
    f = LoggerFormat(columns=("time", "a", "b", "-", "-", "day", "-", "-"),
                     clock=ClockSpec(column="time", date_column="day"))
    assert read_logger(p, f).clock == datetime(2015, 10, 1)


def test_clock_column_past_midnight_and_rows_with_other_offset(tmp_path):
    """A time of day that wraps past midnight goes on to the next day; the clock of the
    first row minus its record time (time column from 0.5 s)."""
    t = 0.5 + np.arange(1024) / FS                  # 2 s
    tod = [f"{86399.0 + k / FS:.4f}" if 86399.0 + k / FS < 86400 else
           f"{86399.0 + k / FS - 86400:.4f}" for k in range(1024)]
    p = tmp_path / "x_2015-12-31.txt"
    _write(p, t, [("tod", tod)])
    f = LoggerFormat(columns=("time", "a", "b", "tod"),
                     clock=ClockSpec(column="tod", pattern="%Y-%m-%d"))
    r = read_logger(p, f)
    assert r.clock == datetime(2015, 12, 31, 23, 59, 58, 500000)
    assert r.clock_at(r.time[-1]) == datetime(2016, 1, 1, 0, 0, 0, 998047)


@pytest.mark.parametrize(
    ("col", "spec", "reason"),
    [
        (["12:00:00"] * 50, ClockSpec(column="c"),
         "the clock column 'c' gives the time of day, but no date column is set and the "
         "file name has no date"),
        (["soon"] * 50, ClockSpec(column="c"), "line 2, column 'c': 'soon' is not a clock "
         "time"),
        (["2015-10-01"] * 50, ClockSpec(column="c"), "'2015-10-01' is a date, not a clock"),
        (["99999"] * 50, ClockSpec(column="c"), "'99999' is not a time of day"),
        (["2015-10-01T12:00:00"] * 49 + ["2015-10-01T12:05:00"], ClockSpec(column="c"),
         "the clock column 'c' runs 300 s from line 2 to line 51, but the record's time "
         "0.095703 s"),
        (["1/10/2015 12:00"] * 50, ClockSpec(column="c", format="%d.%m.%Y %H:%M"),
         "'1/10/2015 12:00' does not fit the clock format"),
    ],
)
def test_bad_clock_columns(tmp_path, col, spec, reason):
    p = tmp_path / "event.txt"
    _write(p, np.arange(50) / FS, [("c", col)])
    with pytest.raises(InputError) as exc:
        read_logger(p, LoggerFormat(columns=("time", "a", "b", "c"), clock=spec))
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{p}: ") and reason in msg, msg


def test_format_checks_the_clock_columns():
    with pytest.raises(InputError, match=re.escape("LoggerFormat.clock: the column 'clk' is "
                                                   "not one of the columns")):
        LoggerFormat(columns=("time", "a"), clock=ClockSpec(column="clk"))
    with pytest.raises(InputError, match="needs a 'time' column"):
        LoggerFormat(columns=("a", "b"), sampling_rate=FS, clock=ClockSpec(column="time"))
    with pytest.raises(InputError, match="names no channel"):
        LoggerFormat(columns=("time", "clk"), clock=ClockSpec(column="clk"))
    with pytest.raises(InputError, match=re.escape("LoggerFormat.clock must be a bwim.io.clock")):
        LoggerFormat(columns=("time", "a"), clock="%Y")
    with pytest.raises(InputError, match=re.escape("LoggerFormat.kinds: 'clk' is not a channel")):
        LoggerFormat(columns=("time", "a", "clk"), clock=ClockSpec(column="clk"),
                     kinds={"clk": "strain_x"})


def test_logger_clock_without_a_file():
    """The function alone: rows given by hand (no time column: time k / fs)."""
    first = ClockRow(line=3, time=0.0, fields={"c": "2015-10-01 12:00:00.5"})
    last = ClockRow(line=12, time=9.0, fields={"c": "2015-10-01 12:00:09.5"})
    assert logger_clock(ClockSpec(column="c"), "a.txt", first, last) == \
        datetime(2015, 10, 1, 12, 0, 0, 500000)
    assert logger_clock(None, "a.txt", first, last) is None
    assert logger_clock(None, "2015-10-01-12-00-00.txt", first, last) == \
        datetime(2015, 10, 1, 12)


@pytest.mark.parametrize(("name", "first_row", "expected"), [
    # the trigger at 00:00:00.2 on 2 Oct, 0.5 s of pre-trigger from 1 Oct 23:59:59.7
    ("ev_2015-10-02-00-00-00-200.txt", 86400.0 - 0.3, datetime(2015, 10, 1, 23, 59, 59, 700000)),
    # the mirror: named 1 Oct 23:59:59.9, its first row 2 Oct 00:00:00.1
    ("ev_2015-10-01-23-59-59-900.txt", 0.1, datetime(2015, 10, 2, 0, 0, 0, 100000)),
    ("ev_2015-10-01-12-00-00-000.txt", 43199.5, datetime(2015, 10, 1, 11, 59, 59, 500000)),
])
@pytest.mark.parametrize("column", ["clock", "time"])
def test_a_time_of_day_takes_the_names_date_nearest_its_time(tmp_path, name, first_row,
                                                            expected, column):
    """A clock time of day in a column (or the time column itself) takes its date from
    the file name: the date that puts it within 12 h of the name's own time (review of
    stop 33: a file named just after midnight whose pre-trigger began before it landed a
    day late, and the mirror case a day early)."""
    from bwim.io import LoggerFormat, read_logger
    from bwim.io.clock import ClockSpec

    t = np.arange(20) * 0.1
    path = tmp_path / name
    with open(path, "w") as f:
        f.write("time,clock,s1\n")
        for tk in t:
            c = (first_row + tk) % 86400.0
            h, r = divmod(c, 3600.0)
            m, s = divmod(r, 60.0)
            # the time column in clock time counts on past midnight (it must increase)
            tcol = f"{first_row + tk:.3f}" if column == "time" else f"{tk:.3f}"
            f.write(f"{tcol},{int(h):02d}:{int(m):02d}:{s:06.3f},0.0\n")
    fmt = LoggerFormat(columns=("time", "clock", "s1") if column == "clock"
                       else ("time", "-", "s1"), clock=ClockSpec(column=column))
    rec = read_logger(path, fmt)
    assert abs((rec.clock_at(rec.time[0]) - expected).total_seconds()) < 1e-6


def test_a_compact_hhmmss_clock_is_not_taken_for_seconds():
    """'083000' in a clock column: 08:30:00 written HHMMSS, or 83000 s (23:03:20)
    zero-padded: refused with the format that reads the first (review of stop 33: it was
    read as 23:03:20 without a word); given that format, it is 08:30:00."""
    first = ClockRow(line=3, time=0.0, fields={"c": "083000"})
    last = ClockRow(line=12, time=1.0, fields={"c": "083001"})
    with pytest.raises(InputError, match="reads as HHMMSS or as seconds since midnight"):
        logger_clock(ClockSpec(column="c"), "ev_2015-10-01-08-30-00-000.txt", first, last)
    assert logger_clock(ClockSpec(column="c", format="%H%M%S"), "ev_2015-10-01-08-30-00-000.txt",
                        first, last) == datetime(2015, 10, 1, 8, 30)
    plain = [ClockRow(line=3, time=0.0, fields={"c": "30600"}),
             ClockRow(line=12, time=1.0, fields={"c": "30601"})]  # 08:30:00 in s
    assert logger_clock(ClockSpec(column="c"), "ev_2015-10-01-08-30-00-000.txt", *plain) == \
        datetime(2015, 10, 1, 8, 30)
