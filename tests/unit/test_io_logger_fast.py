"""The vectorised logger reader against its line-by-line path (issue 21, reading speed).

References: Python's ``float`` (correctly rounded decimal to double) for every number the
vectorised path reads; the line-by-line path of the same reader (the reader's semantics
before the vectorised path existed, kept for the precise messages) for every outcome: the
same record bit for bit, or the same one-line message, on random files built from tricky
fields, also across chunk boundaries (a tiny ``CHUNK``).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bwim.errors import InputError
from bwim.io import logger
from bwim.io.logger import LoggerFormat, read_logger


def _outcome(path, fmt, **kw):
    try:
        r = read_logger(path, fmt, **kw)
    except InputError as exc:
        return ("error", str(exc))
    return ("ok", r.time.tobytes(), r.data.tobytes(), r.data.shape)


def _line_by_line(path, fmt, **kw):
    return _outcome(path, fmt, vectorised=False, **kw)


def test_plain_decimals_read_exactly_as_float(tmp_path, monkeypatch):
    """Reference: ``float(s)``.  20 000 random plain decimals (1 to 14 digits, the mark
    anywhere, signs, leading and trailing zeros, -0) read bit for bit, and the vectorised
    path did read them (no field fell back to the line-by-line path)."""
    rng = np.random.default_rng(7)
    n = 5000
    fields = []
    for _ in range(4 * n):
        digits = "".join(rng.choice(list("0123456789"), size=rng.integers(1, 15)))
        dot = rng.integers(-1, len(digits) + 1)
        s = digits if dot < 0 else digits[:dot] + "." + digits[dot:]
        fields.append(rng.choice(["", "-", "+"]) + s)
    fields[:6] = ["-0", "0.00000000000001", "99999999999999", "-9999999.9999999", "+.5", "5."]
    rows = np.array(fields).reshape(n, 4)
    text = "".join(f"{k * 0.001:.3f}\t" + "\t".join(r) + "\n" for k, r in enumerate(rows))
    p = tmp_path / "plain.txt"
    p.write_text(text)
    slow_calls = []
    original = logger._Parser._slow
    monkeypatch.setattr(logger._Parser, "_slow",
                        lambda self, *a: slow_calls.append(a) or original(self, *a))
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b", "c", "d")), clip_run=None)
    expected = np.array([[float(s) for s in row] for row in rows])
    assert r.data.tobytes() == expected.tobytes()
    assert np.signbit(r.data[0, 0]) and r.data[0, 0] == 0.0
    assert slow_calls == []


@pytest.mark.parametrize(
    ("text", "fmt"),
    [
        ("time\ta\tb\n" + "".join(f"{k}.5\t{k}\t-{k}.25\n" for k in range(50)),
         LoggerFormat(columns=("time", "a", "b"))),
        ("".join(f"{k}.5;{k};-{k}.25;\r\n" for k in range(50)),            # CRLF, trailing ;
         LoggerFormat(columns=("time", "a", "b"))),
        ("".join(f"  {k}.5 \t {k}\t\t-{k}.25  \n" for k in range(50)),     # runs of blanks
         LoggerFormat(columns=("time", "a", "b"), delimiter=" ")),
        ("# logger v2\n\ntime,a,b\n" + "".join(f"{k}.5,{k},-{k}.25\n" + ("# mark\n\n"
                                                                        if k % 7 == 0 else "")
                                                for k in range(50)),
         LoggerFormat(columns=("time", "a", "b"))),
        ("".join(f"{k},5;{k};-{k},25;ok\n" for k in range(50)),             # decimal comma
         LoggerFormat(columns=("time", "a", "b", "-"), decimal=",")),
    ],
)
def test_common_layouts_stay_on_the_vectorised_path(tmp_path, monkeypatch, text, fmt):
    """Tabs, CRLF, a trailing delimiter, runs of spaces and tabs, comments and blank
    lines between rows, a decimal comma: read without the line-by-line path (the speed
    contract), to the same record as it."""
    p = tmp_path / "e.txt"
    p.write_bytes(text.encode())
    reference = _line_by_line(p, fmt)
    original = logger._Parser._slow
    calls = []
    monkeypatch.setattr(logger._Parser, "_slow",
                        lambda self, *a: calls.append(a) or original(self, *a))
    assert _outcome(p, fmt) == reference and reference[0] == "ok"
    assert calls == []


def test_long_and_exponent_numbers_are_read_one_by_one(tmp_path):
    """Reference: ``float(s)``.  17-digit reprs and exponents (outside the vectorised
    forms) in the same file as plain decimals."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(300, 2)) * 10.0 ** rng.integers(-8, 8, size=(300, 2))
    lines = [f"{k / 512!r};{float(v[k, 0])!r};{v[k, 1]:.4f}" for k in range(300)]
    p = tmp_path / "mixed.csv"
    p.write_text("\n".join(lines))
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    assert r.time.tobytes() == (np.arange(300) / 512).tobytes()
    assert r.data[:, 0].tobytes() == v[:, 0].tobytes()
    assert r.data[:, 1].tobytes() == np.array([float(f"{x:.4f}") for x in v[:, 1]]).tobytes()


TRICKY = ["1", "-0", "+.5", "5.", "007.50", "12345678901234", "123456789012345", "1e5",
          "-1.5E-3", "0.1234567890123456", " 2 ", '"3"', "", "nan", "inf", "1_0", "\u0661",
          "0x10", "--1", "1.2.3", ".", "-", "+", "1,5", "1.5e", "e5", "1 2", "\t", "9" * 70,
          "é", "#"]
FORMATS = [
    LoggerFormat(columns=("time", "a", "b", "-")),
    LoggerFormat(columns=("a", "-", "b"), sampling_rate=100.0, decimal=","),
    LoggerFormat(columns=("time", "a", "b"), delimiter=" "),
    LoggerFormat(columns=("time", "a", "b", "-"), delimiter="\t", header=True),
]


@st.composite
def files(draw):
    k = draw(st.integers(0, len(FORMATS) - 1))
    fmt = FORMATS[k]
    sep = fmt.delimiter or draw(st.sampled_from([",", ";", "\t", " "]))
    if fmt.decimal == "," and sep == ",":
        sep = ";"
    n_rows = draw(st.integers(1, 40))
    style = draw(st.sampled_from(["{:.2f}", "{!r}", "{:.6e}", "{:.5f}"]))
    rows = []
    if fmt.header or draw(st.booleans()):
        rows.append(sep.join(["t", "a", "b", "n"][:len(fmt.columns)]))
    for r in range(n_rows):
        fields = []
        for c in fmt.columns:
            if c == "time":
                fields.append(style.format(1000.0 + 0.01 * r))
            elif c == "-":
                fields.append(draw(st.sampled_from(["ok", "", "x y", "1"])))
            else:
                v = draw(st.floats(-1e4, 1e4, allow_nan=False, width=32))
                fields.append(draw(st.sampled_from([f"{v:.3f}", repr(v), f"{v:.1f}"]))
                              .replace(".", "," if fmt.decimal == "," else "."))
        line = sep.join(fields)
        if draw(st.integers(0, 9)) == 0:
            line += sep                              # a trailing delimiter
        rows.append(line)
        extra = draw(st.integers(0, 12))
        if extra == 0:
            rows.append("# a comment")
        elif extra == 1:
            rows.append("")
        elif extra == 2:
            rows.append("   ")
    for _ in range(max(0, draw(st.integers(-2, 2)))):   # a few tricky fields anywhere
        i = draw(st.integers(0, len(rows) - 1))
        parts = rows[i].split(sep)
        j = draw(st.integers(0, len(parts) - 1))
        parts[j] = draw(st.sampled_from(TRICKY))
        rows[i] = sep.join(parts)
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    return fmt, newline.join(rows) + draw(st.sampled_from(["", newline, newline * 2]))


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=files(), chunk=st.sampled_from([16, 64, 2**16]))
def test_same_outcome_as_line_by_line(tmp_path, monkeypatch, case, chunk):
    """Random files of plain, long and exponent numbers with tricky fields, comments,
    blank and whitespace lines, trailing delimiters and CRLF, read in chunks of 16, 64 or
    65 536 characters: the same record bit for bit, or the same message, as the
    line-by-line path."""
    fmt, text = case
    p = tmp_path / "case.txt"
    p.write_bytes(text.encode())
    monkeypatch.setattr(logger, "CHUNK", chunk)
    kw = dict(max_field=40, clip_run=3)
    assert _outcome(p, fmt, **kw) == _line_by_line(p, fmt, **kw)


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cells=st.lists(st.text(alphabet="0123456789.,+-eE x", max_size=18), min_size=2,
                      max_size=30), comma=st.booleans())
def test_any_field_text_same_as_line_by_line(tmp_path, cells, comma):
    """Random field texts of digits, marks, signs, exponents, spaces and letters in one
    column (a valid time column beside it): the same numbers bit for bit or the same
    message as the line-by-line path."""
    fmt = LoggerFormat(columns=("time", "a"), delimiter=";", header=False,
                       decimal="," if comma else ".")
    p = tmp_path / "cells.txt"
    p.write_text("".join(f"{k}.5;{c}\n" for k, c in enumerate(cells)))
    kw = dict(clip_run=None)
    assert _outcome(p, fmt, **kw) == _line_by_line(p, fmt, **kw)


@pytest.mark.parametrize(
    ("extra", "outcome"),
    [("x", "line 2 has 4 fields, the format has 3 columns (delimiter ';')"),
     (" ", None), ("", None)],
)
def test_every_row_with_one_more_field(tmp_path, extra, outcome):
    """Every data row with a fourth field: text is refused at the first row (the
    line-by-line rule), blank is a trailing delimiter and dropped."""
    p = tmp_path / "e.txt"
    p.write_text("time;a;b\n" + "".join(f"{k}.5;1;2;{extra}\n" for k in range(20)))
    fmt = LoggerFormat(columns=("time", "a", "b"))
    result = _outcome(p, fmt)
    assert result == _line_by_line(p, fmt)
    if outcome is None:
        assert result[0] == "ok" and result[3] == (20, 2)
    else:
        assert result == ("error", f"{p}: {outcome}")


@pytest.mark.parametrize("ws", ["\x0b", "\x0c", "\x1c", "\u00a0", "\u2003"])
def test_unusual_whitespace_with_the_whitespace_delimiter(tmp_path, ws):
    """Whitespace that str.split() splits at but the vectorised path does not: inside a
    field, at its edges, and as the whole separator."""
    fmt = LoggerFormat(columns=("time", "a", "b"), delimiter=" ")
    p = tmp_path / "e.txt"
    for row in (f"{{}} 1{ws}2 3", f"{{}} 1{ws} 2", f"{{}}{ws}1 2", f"{ws}{{}} 1 2{ws}"):
        p.write_text("".join(row.format(f"{k}.5") + "\n" for k in range(10)),
                     encoding="utf-8")
        assert _outcome(p, fmt) == _line_by_line(p, fmt)


@pytest.mark.parametrize("chunk", [32, 100, 2**16])
def test_errors_name_the_right_line_across_chunks(tmp_path, monkeypatch, chunk):
    """A bad field at line 150 after comments and blank lines in the earlier chunks: the
    message names line 150 (counted by hand: 1 header, 2 comments every 10 rows)."""
    rows = ["time,a,b"]
    for r in range(200):
        rows.append(f"{r / 512!r},{r}.5,-{r}")
        if r % 10 == 9:
            rows += ["# comment", ""]
    lines = rows[:]
    lines[149] = lines[149].split(",")[0] + ",oops,1"
    p = tmp_path / "e.txt"
    p.write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(logger, "CHUNK", chunk)
    with pytest.raises(InputError, match="line 150, column 'a': 'oops' is not a number"):
        read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    p.write_text("\n".join(rows) + "\n")
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    assert r.data.shape == (200, 2) and r.data[199, 0] == 199.5


def test_vectorised_must_be_a_bool(tmp_path):
    p = tmp_path / "e.txt"
    p.write_text("0;1\n1;2\n")
    with pytest.raises(InputError, match="vectorised must be true or false, got 'no'"):
        read_logger(p, LoggerFormat(columns=("time", "a")), vectorised="no")


def _record(path, fmt, **kw):
    """The whole outcome, clock and NaN bits included."""
    try:
        r = read_logger(path, fmt, **kw)
    except InputError as exc:
        return ("error", str(exc))
    return ("ok", r.time.tobytes(), r.data.tobytes(), r.data.shape, r.clock,
            tuple(s.name for s in r.sensors))


def _no_line_by_line(monkeypatch):
    calls = []
    original = logger._Parser._slow
    monkeypatch.setattr(logger._Parser, "_slow",
                        lambda self, *a: calls.append(a) or original(self, *a))
    return calls


def test_gaps_clock_columns_and_unicode_stay_on_the_vectorised_path(tmp_path, monkeypatch):
    """Reference: the line-by-line path.  A temperature column with empty and NaN gaps, a
    clock column (ISO text, quoted), a skipped column and comments with non-ASCII text,
    rows with and without a trailing delimiter: the same record bit for bit (NaN, clock),
    read without the line-by-line path."""
    from bwim.io.clock import ClockSpec

    fmt = LoggerFormat(columns=("clock", "time", "a", "temp", "-"),
                       kinds={"temp": "temperature"}, clock=ClockSpec(column="clock"))
    rows = ["# Température °C, état", "clock;time;a;temp;état"]
    gaps = ["21.5", "", "NaN", " nan ", "-NaN", "21.7", '"nan"', "21.6"]
    for k in range(300):
        stamp = f"2015-10-01T09:45:{52 + k // 100:02d}.{(k % 100) * 10:03d}"
        row = f'"{stamp}";{k / 100:.2f};{np.sin(k / 9):.6f};{gaps[k % len(gaps)]};ok°'
        rows.append(row + (";" if k % 3 == 0 else ""))
        if k % 50 == 0:
            rows.append("# µ-strain, remarque")
    p = tmp_path / "g.txt"
    p.write_text("\n".join(rows) + "\n", encoding="utf-8")
    reference = _record(p, fmt, vectorised=False)
    calls = _no_line_by_line(monkeypatch)
    got = _record(p, fmt)
    assert got == reference and reference[0] == "ok" and reference[4] is not None
    assert calls == []
    data = np.frombuffer(reference[2]).reshape(reference[3])
    assert np.isnan(data[1::len(gaps), 1]).all() and np.isfinite(data[::len(gaps), 1]).all()


@pytest.mark.parametrize("chunk", [40, 2**16])
@pytest.mark.parametrize(
    "text",
    ["time;a\n" + "".join(f"{k}.5;{k}\n" + ("   \n" if k % 4 == 0 else "") for k in range(60)),
     "".join(f"{k}.5;{k}\n" + (" \t \n" if k % 9 == 0 else "") + ("# c\n" if k == 30 else "")
             for k in range(60)),
     "".join(f"{k}.5;{k};\n\n" for k in range(60))],
)
@pytest.mark.parametrize("max_samples", [59, 60, 62, 10**6])
def test_memory_estimates_as_line_by_line(tmp_path, monkeypatch, text, chunk, max_samples):
    """Reference: the line-by-line path.  Lines of spaces, comments and empty lines, a
    max_samples at and around the row count, small and large chunks: the same memory
    estimates checked (the same rows, so the same message at a limit), the same record or
    message."""
    p = tmp_path / "m.txt"
    p.write_text(text)
    fmt = LoggerFormat(columns=("time", "a"))
    monkeypatch.setattr(logger, "CHUNK", chunk)
    out = {}
    for vectorised in (False, True):
        checks = []
        monkeypatch.setattr(logger, "check_memory",
                            lambda n, what, checks=checks: checks.append((n, what)))
        out[vectorised] = (_record(p, fmt, max_samples=max_samples, vectorised=vectorised),
                           checks)
    assert out[True] == out[False]
    assert out[True][1] or out[True][0][0] == "error"   # (refused before any estimate)
