"""The memory guard: sizes parse, the limit follows the environment, estimates are refused."""

import math

import pytest

from bwim.errors import InputError
from bwim.limits import ENV_VAR, check_memory, format_bytes, memory_limit, parse_size


@pytest.mark.parametrize(("text", "expected"), [
    ("123456", 123456), ("4G", 4 * 1024**3), ("800MiB", 800 * 1024**2),
    ("1.5 GB", 1_500_000_000), ("2k", 2048), ("0.25", None),
])
def test_parse_size(text, expected):
    total = 1000 * 1024**2
    got = parse_size(text, total=total)
    assert got == (total // 4 if expected is None else expected)


@pytest.mark.parametrize("text", ["", "lots", "-3G", "4X", "nan", "0"])
def test_parse_size_rejects(text):
    with pytest.raises(InputError, match=ENV_VAR):
        parse_size(text)


def test_limit_from_environment(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "3M")
    assert memory_limit() == 3 * 1024**2
    with pytest.raises(InputError, match=r"a test array needs about 4 MiB .* 3 MiB"):
        check_memory(4 * 1024**2, "a test array")
    check_memory(2 * 1024**2, "a small array")  # within the limit: no error


def test_default_limit_is_a_fraction_of_the_machine(monkeypatch):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert 0 < memory_limit() < 2**60


def test_unbounded_estimate_refused():
    with pytest.raises(InputError, match="unbounded"):
        check_memory(math.inf, "an endless road", limit=10**9)


def test_format_bytes():
    assert format_bytes(1536) == "1.5 KiB"
    assert format_bytes(3 * 1024**3) == "3 GiB"


def test_a_limit_of_nothing_is_refused():
    """Issue-14 review: a fraction so small that the limit rounds to 0 bytes."""
    with pytest.raises(InputError, match="less than one byte"):
        parse_size("1e-30", total=8 * 1024**3)
