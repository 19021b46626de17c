"""Plain decimal fields of a logger file's bytes, read in one compiled pass.

Contract
--------
* :func:`plain_decimals` reads the fields ``a[fs[k]:fe[k]]`` of a byte array (ASCII)
  that are **plain decimals**: an optional leading sign (``+`` or ``-``), 1 to
  :data:`MAX_DIGITS` digits, at most one decimal mark (``.``, or ``,`` with
  ``comma``), nothing else, at most ``MAX_DIGITS + 2`` bytes.  For each field it gives
  its value, whether it is plain (``ok``), and its digits after the mark (``decimals``).
  A field that is not plain has ``ok`` False and its value and decimals undefined: the
  caller reads it another way (as ``float`` does, or refuses it).  The logger reader
  applies the same rule in its own one-pass kernel (:mod:`bwim.io.field_kernels`, tested
  against :func:`plain_decimals` and ``float``).
* **Exactness.**  The digits, with the mark's place counted as a 0 digit, form an
  integer ``r < 10**15 < 2**53`` (exact in a double, built digit by digit); the mantissa
  ``m`` is ``r`` with that 0 taken out (``m = h p + (r − 10 h p)``, ``h = ⌊r / 10p⌋`` the
  digits before the mark, ``p = 10**decimals``: exact integers), and the value
  ``m / p``: both ``m < 2**53`` and ``p ≤ 10**14`` are exact, so the one division rounds
  the exact decimal once and gives the double that ``float`` gives (Clinger's fast path;
  W. D. Clinger, *How to read floating point numbers accurately*, PLDI 1990).  The
  test is against ``float`` itself (tests/unit/test_decimal_fields.py).
* Compiled with numba (one pass over each field's bytes, no temporary arrays); the
  first call in a process compiles it, or loads it from numba's cache.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["MAX_DIGITS", "PlainDecimals", "plain_decimals"]

#: Digits a plain field may have (its integer, mark counted as a digit, stays below 2**53).
MAX_DIGITS = 14


def _powers_of_ten() -> np.ndarray:
    """10**0 … 10**MAX_DIGITS, each exact (products of exact integers below 2**53)."""
    out = np.ones(MAX_DIGITS + 1)
    for i in range(1, out.size):
        out[i] = out[i - 1] * 10.0
    return out


@dataclass(eq=False)
class PlainDecimals:
    """:func:`plain_decimals`' result, one entry per field (the caller fills in the
    fields that are not plain, so the arrays are its to change)."""

    values: np.ndarray      # (k,) float: the numbers, exact where ok
    ok: np.ndarray          # (k,) bool: a plain decimal, read exactly
    decimals: np.ndarray    # (k,) int64: digits after the decimal mark


@numba.njit(cache=True, nogil=True)
def _read(a, fs, fe, mark_byte, max_digits, p10):  # pragma: no cover - compiled
    k = fs.size
    values = np.empty(k)
    ok = np.zeros(k, dtype=np.bool_)
    decimals = np.zeros(k, dtype=np.int64)
    for i in range(k):
        s, e = fs[i], fe[i]
        length = e - s
        if length < 1 or length > max_digits + 2:
            values[i] = np.nan
            continue
        lead = a[s]
        negative = lead == 45
        j0 = s + 1 if (negative or lead == 43) else s
        r = 0.0
        n_digit = 0
        n_mark = 0
        after = 0
        plain = True
        for j in range(j0, e):
            c = a[j]
            if 48 <= c <= 57:
                n_digit += 1
                r = r * 10.0 + (c - 48)
                if n_mark:
                    after += 1
            elif c == mark_byte and n_mark == 0:
                n_mark = 1
                r = r * 10.0  # the mark's place, a 0 digit
            else:
                plain = False
                break
        if not plain or n_digit < 1 or n_digit > max_digits:
            values[i] = np.nan
            continue
        p = p10[after]  # exact
        if n_mark:
            h = np.floor(r / (10.0 * p))  # the digits before the mark (exact)
            m = h * p + (r - h * 10.0 * p)
        else:
            m = r
        v = m / p
        values[i] = -v if negative else v
        ok[i] = True
        decimals[i] = after
    return values, ok, decimals


def plain_decimals(a: np.ndarray, fs: np.ndarray, fe: np.ndarray, comma: bool
                   ) -> PlainDecimals:
    """The plain decimal fields ``a[fs:fe]`` of the bytes ``a`` (uint8), see the module
    docstring; ``comma``: the decimal mark is ``,`` (else ``.``)."""
    values, ok, decimals = _read(np.ascontiguousarray(a, dtype=np.uint8),
                                 np.ascontiguousarray(fs, dtype=np.int64),
                                 np.ascontiguousarray(fe, dtype=np.int64),
                                 44 if comma else 46, MAX_DIGITS, _powers_of_ten())
    return PlainDecimals(values=values, ok=ok, decimals=decimals)
