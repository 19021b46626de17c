"""bwim.io.decimal_fields against Python's float (the correctly rounded reading of a
decimal string, the reference the logger reader's contract names)."""

import numpy as np
import pytest

from bwim.io.decimal_fields import MAX_DIGITS, plain_decimals


def _read(fields: list[str], comma: bool = False):
    text = "\n" + "\n".join(fields) + "\n"
    a = np.frombuffer(text.encode(), dtype=np.uint8)
    ends = np.flatnonzero(a == 10)
    return plain_decimals(a, ends[:-1] + 1, ends[1:], comma)


def _random_fields(rng: np.random.Generator, n: int) -> list[str]:
    out = []
    for _ in range(n):
        size = int(rng.integers(1, MAX_DIGITS + 1))
        digits = "".join(rng.choice(list("0123456789"), size=size))
        mark = int(rng.integers(0, len(digits) + 1))
        s = digits if rng.random() < 0.2 else digits[:mark] + "." + digits[mark:]
        out.append(str(rng.choice(["", "-", "+"])) + s)
    return out


def test_plain_decimals_read_as_float_does():
    rng = np.random.default_rng(7)
    fields = [*_random_fields(rng, 20000), "-0.0", "0", ".5", "-.5", "5.", "+7",
              "99999999999999", "0.0000000000001", "-9999999.999999"]
    got = _read(fields)
    assert got.ok.all()
    want = np.array([float(s) for s in fields])
    assert np.array_equal(got.values.view(np.int64), want.view(np.int64))  # bit for bit, -0.0 too
    after = [len(s) - s.index(".") - 1 if "." in s else 0 for s in fields]
    assert got.decimals.tolist() == after


def test_a_decimal_comma_is_read_with_comma_only():
    got = _read(["-12,25", "3,5"], comma=True)
    assert got.ok.all() and got.values.tolist() == [-12.25, 3.5]
    assert not _read(["-12,25"]).ok.any()
    assert not _read(["-12.25"], comma=True).ok.any()


@pytest.mark.parametrize("field", ["", "-", "+", ".", "-.", "1.2.3", "1-2", "--1", "+-1", "1e5",
                                   "1E-5", "nan", "inf", " 1", "1 ", "0x10", "1,5",
                                   "1" * (MAX_DIGITS + 1), "0." + "1" * MAX_DIGITS])
def test_fields_that_are_not_plain_decimals_are_left_to_the_caller(field):
    assert not _read([field]).ok[0]
