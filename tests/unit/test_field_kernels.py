"""bwim.io.field_kernels: the compiled scan of a logger chunk (rows, fields, plain decimals).

References: Python's ``float`` (the correctly rounded reading of a decimal string, the
reference of the logger reader's contract) for the numbers; ``str.split`` and
``str.strip`` (the line-by-line reader's rules) for the rows and fields, written out by
hand for each case; the logger's line-by-line path for whole files
(tests/unit/test_io_logger_fast.py).
"""

import math

import numpy as np
import pytest

from bwim.io.field_kernels import GAP, MAX_DIGITS, SKIP, TIME, Scan, scan_rows


def _scan(text, columns, *, delimiter="\t", gaps=(), comma=False, max_line=4096,
          max_field=64, max_rows=10**6, first_line=1):
    """scan_rows on ``text`` for ``columns`` ("time", "-" or a channel name)."""
    slots, k = [], 0
    for c in columns:
        if c == "time":
            slots.append(TIME)
        elif c == "-":
            slots.append(SKIP)
        else:
            slots.append(k)
            k += 1
    return scan_rows(text.encode(), n_chars=len(text), delimiter=delimiter,
                     slots=np.array(slots, dtype=np.int64),
                     gaps=np.array([GAP if c in gaps else 0 for c in columns], dtype=np.uint8),
                     n_channels=k, has_time="time" in columns, comma=comma,
                     max_line=max_line, max_field=max_field, max_rows=max_rows,
                     first_line=first_line)


def _plain_fields(rng, n):
    out = []
    for _ in range(n):
        digits = "".join(rng.choice(list("0123456789"), size=int(rng.integers(1, MAX_DIGITS + 1))))
        mark = int(rng.integers(0, len(digits) + 1))
        s = digits if rng.random() < 0.2 else digits[:mark] + "." + digits[mark:]
        out.append(str(rng.choice(["", "-", "+"])) + s)
    return out


def test_plain_decimals_read_exactly_as_float():
    """Reference: ``float(s)``.  12 000 random plain decimals (1 to 14
    digits, the mark anywhere, signs, -0) in a time column and three channels, bit for
    bit; the time column's most digits after the mark."""
    rng = np.random.default_rng(11)
    fields = _plain_fields(rng, 12000)
    fields[:8] = ["-0", "+0.0", "0.0000000000001", "99999999999999", "-9999999.9999999",
                  "+.5", "5.", "-.0"]
    rows = np.array(fields).reshape(-1, 4)
    text = "".join("\t".join(r) + "\n" for r in rows)
    got = _scan(text, ("time", "a", "b", "c"))
    assert got.status is Scan.OK and got.bad.shape == (0, 4)
    want = np.array([float(s) for s in fields]).reshape(-1, 4)
    assert got.time.view(np.int64).tolist() == want[:, 0].view(np.int64).tolist()
    assert np.array_equal(got.values.view(np.int64), want[:, 1:].view(np.int64))
    assert np.signbit(got.time[0]) and got.time[0] == 0.0               # -0 kept
    assert got.decimals == max(len(s) - s.index(".") - 1 if "." in s else 0
                               for s in rows[:, 0])


def test_a_decimal_comma():
    got = _scan("0,5;-12,25;3,\n1,5;+,5;-0,0\n", ("time", "a", "b"), delimiter=";",
                comma=True)
    assert got.status is Scan.OK and got.bad.size == 0
    assert got.time.tolist() == [0.5, 1.5] and got.decimals == 1
    assert got.values.tolist() == [[-12.25, 3.0], [0.5, -0.0]]
    got = _scan("0.5;1.5\n", ("time", "a"), delimiter=";", comma=True)  # '.' not a mark
    assert got.bad.tolist() == [[0, 0, 0, 3], [0, 1, 4, 7]]


@pytest.mark.parametrize("field", ["1e5", "-1.5E-3", " 2", "2 ", '"3"', "", "nan", "inf",
                                   "1.2.3", ".", "-", "+", "--1", "+-1", "0x10", "1,5",
                                   "1" * (MAX_DIGITS + 1), "0." + "1" * MAX_DIGITS,
                                   "0.1234567890123456", "1_0", "é", "#", "\x7f"])
def test_fields_that_are_not_plain_are_listed_for_the_caller(field):
    """Row, column and byte span of each numeric field that is not a plain decimal (the
    caller reads those as float does, or refuses them); a skipped column is never read."""
    text = f"0.5;{field};{field};7\n"
    got = _scan(text, ("time", "a", "-", "b"), delimiter=";")
    assert got.status is Scan.OK
    s = 4
    e = s + len(field.encode())
    assert got.bad.tolist() == [[0, 1, s, e]]
    assert text.encode()[s:e].decode() == field
    assert got.values[0, 1] == 7.0 and got.time[0] == 0.5


def test_gaps_of_a_temperature_column_are_nan():
    """Empty, blank and NaN fields (any case, signs, blanks around) of a gap column are
    NaN, the same NaN as ``math.nan`` bit for bit (the line-by-line path's); the same
    fields of another column, and a quoted NaN anywhere, are left to the caller."""
    gaps = ["", " ", "nan", "NaN", " -nan\t", "+-NAN", "nAn"]
    text = "".join(f"{k}.5;{g};{g}\n" for k, g in enumerate(gaps)) + '9.5;"nan";1\n'
    got = _scan(text, ("time", "temp", "a"), delimiter=";", gaps=("temp",))
    assert got.status is Scan.OK
    nan_bits = np.array([math.nan]).view(np.int64)[0]
    assert got.values[:len(gaps), 0].view(np.int64).tolist() == [nan_bits] * len(gaps)
    assert [(r, j) for r, j, _, _ in got.bad.tolist()] == [
        *[(k, 2) for k in range(len(gaps))], (len(gaps), 1)]


def test_rows_lines_comments_and_blank_lines():
    """Line numbers count every line (from ``first_line``); comments (``#`` first
    non-blank), empty lines and lines of spaces and tabs are skipped, the latter counted
    apart; the file's last line may lack its newline."""
    text = "# head\n1;2\n\n  \t\n  # note\n3;4\n \n5;6"
    got = _scan(text, ("time", "a"), delimiter=";", first_line=10)
    assert got.status is Scan.OK
    assert got.lines.tolist() == [11, 15, 17] and got.n_lines == len(text.split("\n")) == 8
    assert got.time.tolist() == [1.0, 3.0, 5.0] and got.values[:, 0].tolist() == [2, 4, 6]
    assert got.space_lines == 2
    empty = _scan("# only\n\n", ("time", "a"), delimiter=";")
    assert empty.status is Scan.OK and empty.lines.size == 0 and empty.n_lines == 2


def test_whitespace_delimiter_and_field_spans():
    """Runs of spaces and tabs separate fields, blanks at either end are ignored; a tab
    or comma delimiter keeps blanks inside a field (left to the caller), and one empty
    field past the last column is a trailing delimiter.  ``edges``: the first and the
    last row's field spans (clock columns)."""
    text = "  0.5 \t 1\t\t2  \n1.5 3 4\n"
    got = _scan(text, ("time", "a", "b"), delimiter=" ")
    assert got.status is Scan.OK and got.bad.size == 0
    assert got.values.tolist() == [[1, 2], [3, 4]]
    b = text.encode()
    first = [b[s:e].decode() for s, e in zip(got.edges[0], got.edges[1], strict=True)]
    last = [b[s:e].decode() for s, e in zip(got.edges[2], got.edges[3], strict=True)]
    assert first == ["0.5", "1", "2"] and last == ["1.5", "3", "4"]
    got = _scan("0.5,1,2,\n1.5,3,4\n", ("time", "a", "b"), delimiter=",")
    assert got.status is Scan.OK and got.values.tolist() == [[1, 2], [3, 4]]
    got = _scan("0.5\t 1\t2\n", ("time", "a", "b"))
    assert got.bad.tolist() == [[0, 1, 4, 6]]
    got = _scan("09:00;0.5;1\n09:01;1.5;2\n", ("clock", "time", "a"), delimiter=";")
    assert got.values[:, 1].tolist() == [1, 2]  # (a clock column is column 0, skipped)


@pytest.mark.parametrize(
    ("text", "columns", "kw", "status"),
    [
        ("0.5;1\n" + "#" * 50 + "\n", ("time", "a"), {"max_line": 40}, Scan.LONG_LINE),
        ("0.5;1" + " " * 50 + "\n", ("time", "-"), {"max_line": 40, "max_field": 60},
         Scan.LONG_LINE),
        ("0.5;1\n1.5\n", ("time", "a"), {}, Scan.FIELD_COUNT),                 # too few
        ("0.5;1;2\n", ("time", "a"), {}, Scan.FIELD_COUNT),                    # too many
        ("0.5;1;;\n", ("time", "a"), {}, Scan.FIELD_COUNT),
        ("0.5;1; \n", ("time", "a"), {}, Scan.FIELD_COUNT),   # (blank: line by line)
        ("0.5 1 2\n", ("time", "a"), {"delimiter": " "}, Scan.FIELD_COUNT),
        ("0.5 \n", ("time", "a"), {"delimiter": " "}, Scan.FIELD_COUNT),
        ("0.5;12345\n", ("time", "a"), {"max_field": 4}, Scan.LONG_FIELD),
        ("0.5;1\n1.5;2\n2.5;3\n", ("time", "a"), {"max_rows": 2}, Scan.MANY_ROWS),
        ("0.5;1\x0b\n", ("time", "a"), {}, Scan.UNUSUAL),
        ("\x0c0.5;1\n", ("time", "a"), {}, Scan.UNUSUAL),
        ("0.5;1\r\n", ("time", "a"), {}, Scan.UNUSUAL),
        ("\u00a0# note\n0.5;1\n", ("time", "a"), {}, Scan.UNUSUAL),
        ("0.5 1\u2003\n", ("time", "a"), {"delimiter": " "}, Scan.UNUSUAL),
        ("".join(f"{k};1e1;1e1;1e1\n" for k in range(100)), ("time", "a", "b", "c"), {},
         Scan.OTHERS),
    ],
)
def test_what_it_leaves_to_the_line_by_line_path(text, columns, kw, status):
    kw = {"delimiter": ";", **kw}
    got = _scan(text, columns, **kw)
    assert got.status is status
    assert got.lines.size == 0 and got.bad.size == 0


def test_non_ascii_text_it_can_read():
    """Non-ASCII in a comment, in a skipped column and in a numeric field (listed) with a
    one-byte delimiter: read, byte offsets into the UTF-8 text."""
    text = "# température °C\n0.5;1;ok°\n1.5;2µ;x\n"
    got = _scan(text, ("time", "a", "-"), delimiter=";")
    assert got.status is Scan.OK and got.lines.tolist() == [2, 3]
    (r, j, s, e), = got.bad.tolist()
    assert (r, j) == (1, 1) and text.encode()[s:e].decode() == "2µ"


def test_densest_rows_fit():
    """Rows as short as a row can be (one character per column, newline counted, the
    last without one) fit the arrays sized from the character count."""
    for text, columns, delimiter in [("1\n" * 99 + "1", ("a",), ";"),
                                     (";;1\n" * 50 + ";;1", ("-", "-", "a"), ";"),
                                     ("1 2\n" * 50 + "1 2", ("time", "a"), " ")]:
        got = _scan(text, columns, delimiter=delimiter)
        assert got.status is Scan.OK and got.lines.size == text.count("\n") + 1
