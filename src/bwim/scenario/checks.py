"""The scenario files' value checkers: strict types, one-line messages naming where.

Contract
--------
* A check is a function ``(value, at) -> converted value`` that raises
  :class:`~bwim.errors.InputError` with a one-line message naming the file, the section
  and the key (:class:`At`): ``"scenario.toml: [bridge] nx: expected an integer, got
  12.5"``.  Integers are accepted where numbers are expected; booleans never are.
* :func:`req` / :func:`opt` declare a spec dataclass field with its check (and the
  bridge kinds it applies to); :func:`parse_table` checks a TOML table against such a
  dataclass (unknown keys, missing keys, wrong types) and builds it; :func:`tables` and
  :func:`subtable` do the same for arrays of tables and nested tables.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from bwim.errors import InputError

__all__ = ["At", "Check", "at_least", "boolean", "choice", "choices", "increasing_pair",
           "int_from", "int_grid", "int_or_ints", "int_or_pair", "int_or_pair_from",
           "integer", "is_number", "jobs", "keys", "non_negative", "number",
           "number_or_numbers", "number_or_string", "numbers", "opt", "pair", "parse_table",
           "positive", "req", "show", "string", "strings", "subtable", "tables"]


@dataclass(frozen=True)
class At:
    src: str
    section: str
    key: str | None = None

    def __str__(self) -> str:
        return f"{self.src}: {self.section}" + (f" {self.key}" if self.key else "")

    def error(self, message: str) -> InputError:
        return InputError(f"{self}: {message}")

    def expected(self, what: str, value: Any) -> InputError:
        return self.error(f"expected {what}, got {show(value)}")


def show(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        text = repr(value)
        return text if len(text) <= 40 else "a list"
    return repr(value)


# --- value checkers: (value, at) -> converted value ---------------------------------------
Check = Callable[[Any, At], Any]


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def number(v: Any, at: At) -> float:
    if not is_number(v):
        raise at.expected("a number", v)
    if not math.isfinite(v):
        raise at.expected("a finite number", v)
    return float(v)


def at_least(low: float, *, strict: bool, high: float | None = None) -> Check:
    """A finite number > low (``strict``) or >= low, and <= high if given."""
    def check(v: Any, at: At) -> float:
        x = number(v, at)
        if (x <= low if strict else x < low) or (high is not None and x > high):
            rng = f"{'>' if strict else '>='} {low:g}" + (
                f" and <= {high:g}" if high is not None else "")
            raise at.error(f"must be {rng}, got {show(v)}")
        return x
    return check


positive = at_least(0.0, strict=True)
non_negative = at_least(0.0, strict=False)


def int_from(low: int) -> Check:
    def check(v: Any, at: At) -> int:
        n = integer(v, at)
        if n < low:
            raise at.error(f"must be an integer >= {low}, got {show(v)}")
        return n
    return check


def int_or_pair_from(low: int) -> Check:
    def check(v: Any, at: At) -> int | tuple[int, int]:
        out = int_or_pair(v, at)
        if any(n < low for n in (out if isinstance(out, tuple) else (out,))):
            raise at.error(f"must be integers >= {low}, got {show(v)}")
        return out
    return check


def jobs(v: Any, at: At) -> int:
    n = integer(v, at)
    if n < 1 and n != -1:
        raise at.error(f"must be a positive integer or -1 (all cores), got {show(v)}")
    return n


def increasing_pair(v: Any, at: At) -> tuple[float, float]:
    lo, hi = pair(v, at)
    if not 0.0 < lo < hi:
        raise at.error(f"must be [low, high] with 0 < low < high, got {show(v)}")
    return lo, hi


def integer(v: Any, at: At) -> int:
    if not isinstance(v, int) or isinstance(v, bool):
        raise at.expected("an integer", v)
    return v


def boolean(v: Any, at: At) -> bool:
    if not isinstance(v, bool):
        raise at.expected("true or false", v)
    return v


def string(v: Any, at: At) -> str:
    if not isinstance(v, str):
        raise at.expected("a string", v)
    return v


def numbers(v: Any, at: At) -> tuple[float, ...]:
    if not isinstance(v, list) or not v or not all(is_number(e) for e in v):
        raise at.expected("a non-empty list of numbers", v)
    return tuple(float(e) for e in v)


def number_or_numbers(v: Any, at: At) -> float | tuple[float, ...]:
    if isinstance(v, list):
        return numbers(v, at)
    if not is_number(v):
        raise at.expected("a number or a list of numbers", v)
    return float(v)


def choice(*options: str) -> Check:
    def check(v: Any, at: At) -> str:
        v = string(v, at)
        if v not in options:
            raise at.error(f"unknown value {v!r}; expected one of {', '.join(options)}")
        return v
    return check


def choices(*options: str) -> Check:
    one = choice(*options)

    def check(v: Any, at: At) -> str | tuple[str, ...]:
        if isinstance(v, list):
            if not v:
                raise at.expected("a non-empty list", v)
            return tuple(one(e, at) for e in v)
        return one(v, at)
    return check


def strings(v: Any, at: At) -> tuple[str, ...]:
    if not isinstance(v, list) or not v or not all(isinstance(e, str) for e in v):
        raise at.expected("a non-empty list of strings", v)
    return tuple(v)


def int_or_ints(v: Any, at: At) -> int | tuple[int, ...]:
    if isinstance(v, list):
        if not v or not all(isinstance(e, int) and not isinstance(e, bool) for e in v):
            raise at.expected("an integer or a list of integers", v)
        return tuple(v)
    return integer(v, at)


def int_grid(v: Any, at: At) -> tuple:
    def ints(row: Any) -> bool:
        return isinstance(row, list) and bool(row) and all(
            isinstance(e, int) and not isinstance(e, bool) for e in row)

    if ints(v):
        return tuple(v)
    if isinstance(v, list) and v and all(ints(r) for r in v):
        if len({len(r) for r in v}) != 1:
            raise at.error("the rows of the zone map have different lengths")
        return tuple(tuple(r) for r in v)
    raise at.expected("a list of integers or a list of rows of integers", v)


def pair(v: Any, at: At) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2 or not all(is_number(e) for e in v):
        raise at.expected("two numbers [low, high]", v)
    return float(v[0]), float(v[1])


def int_or_pair(v: Any, at: At) -> int | tuple[int, int]:
    if isinstance(v, list):
        if len(v) != 2 or not all(isinstance(e, int) and not isinstance(e, bool) for e in v):
            raise at.expected("an integer or two integers", v)
        return v[0], v[1]
    return integer(v, at)


def number_or_string(v: Any, at: At) -> float | str:
    if isinstance(v, str):
        return v
    if not is_number(v):
        raise at.expected("a number or a string", v)
    return float(v)


def subtable(cls: type, name: str) -> Check:
    def check(v: Any, at: At) -> Any:
        _, entry, n = at.section.rpartition(" entry ")
        owner = f" of entry {n}" if entry else ""
        return parse_table(cls, v, At(at.src, f"[{name}]{owner}"))
    return check


def tables(cls: type, name: str) -> Check:
    def check(v: Any, at: At) -> tuple:
        if isinstance(v, dict):
            v = [v]
        if not isinstance(v, list) or not all(isinstance(e, dict) for e in v):
            raise InputError(f"{at.src}: {name} must be an array of tables [[{name}]], "
                             f"got {show(v)}")
        return tuple(parse_table(cls, e, At(at.src, f"[[{name}]] entry {i + 1}"))
                     for i, e in enumerate(v))
    return check


# --- fields -------------------------------------------------------------------------------
def req(check: Check, kinds: tuple[str, ...] | None = None) -> Any:
    """A required key (only for ``kinds`` of bridge when given)."""
    meta = {"check": check, "kinds": kinds, "required": True}
    return field(metadata=meta) if kinds is None else field(default=None, metadata=meta)


def opt(check: Check, default: Any = None, kinds: tuple[str, ...] | None = None) -> Any:
    """An optional key with its default."""
    return field(default=default, metadata={"check": check, "kinds": kinds, "required": False})


def keys(cls: type, kind: str | None) -> list[str]:
    return [f.name for f in fields(cls) if "check" in f.metadata
            and (kind is None or f.metadata["kinds"] is None or kind in f.metadata["kinds"])]


def parse_table(cls: type, table: Any, at: At, *, kind: str | None = None,
           extra: Mapping[str, Any] | None = None) -> Any:
    """Check a table against the fields of ``cls`` and build it."""
    if not isinstance(table, dict):
        raise InputError(f"{at.src}: {at.section} must be a table, got {show(table)}")
    allowed = keys(cls, kind)
    for key in table:
        if key not in allowed:
            note = f" for kind = {kind!r}" if kind is not None and key in keys(cls, None) \
                else ""
            raise InputError(f"{at.src}: unknown key {key!r} in {at.section}{note}; "
                             f"allowed keys: {', '.join(allowed)}")
    spec = {f.name: f for f in fields(cls)}
    kwargs = {k: spec[k].metadata["check"](v, At(at.src, at.section, k))
              for k, v in table.items()}
    for name in allowed:
        if name not in kwargs and spec[name].metadata["required"]:
            raise InputError(f"{at.src}: {at.section} is missing the key {name!r}")
    return cls(**kwargs, **(extra or {}))


