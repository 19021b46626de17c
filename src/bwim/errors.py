"""Exceptions raised by bwim.

Contract
--------
* :class:`BwimError` is the base of every exception bwim raises on purpose.
* :class:`InputError` means the caller gave something bwim cannot use: a non-positive
  dimension, an unknown option, a sensor off the deck.  Its message names the argument and
  the value, so that a command-line user can fix the input without reading a traceback.
* :class:`NumericalError` means the input was valid but the numerics failed (for example a
  stiffness matrix that is not positive definite because the supports leave a mechanism).

Input is validated at the edges with these exceptions, never with ``assert``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from enum import Enum
from typing import TypeVar

import numpy as np

__all__ = [
    "DATA_ERRORS",
    "BwimError",
    "InputError",
    "NumericalError",
    "as_floats",
    "parse_enum",
    "require_axis",
    "require_choice",
    "require_columns",
    "require_finite",
    "require_instance",
    "require_positive",
    "require_range",
]


class BwimError(Exception):
    """Base class of all bwim errors."""


class InputError(BwimError, ValueError):
    """An argument or input file that bwim cannot use; the message names it."""


class NumericalError(BwimError, ArithmeticError):
    """Valid input on which the numerics failed (singular system, no convergence)."""


#: What computing on one record, run or vehicle may raise that ends that computation and
#: not the caller's: bwim's own errors and the numerical failures of degenerate data (a
#: batch goes on to the next record, a lane's detection to the next lane).
DATA_ERRORS = (BwimError, ArithmeticError, ValueError, np.linalg.LinAlgError)


def _fmt(value: object) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return repr(value)


def require_finite(name: str, value: float) -> float:
    """Return ``float(value)`` or raise :class:`InputError` if it is not a finite number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {_fmt(value)}") from None
    if not math.isfinite(v):
        raise InputError(f"{name} must be finite, got {_fmt(value)}")
    return v


def require_positive(name: str, value: float) -> float:
    """Return ``float(value)`` or raise :class:`InputError` unless it is finite and > 0."""
    v = require_finite(name, value)
    if v <= 0.0:
        raise InputError(f"{name} must be positive, got {_fmt(value)}")
    return v


def require_range(
    name: str, value: float, low: float, high: float, *, closed: bool = False
) -> float:
    """Return ``float(value)`` or raise unless ``low < value < high`` (``<=`` if closed)."""
    v = require_finite(name, value)
    ok = (low <= v <= high) if closed else (low < v < high)
    if not ok:
        br = ("[", "]") if closed else ("(", ")")
        raise InputError(
            f"{name} must lie in {br[0]}{_fmt(low)}, {_fmt(high)}{br[1]}, got {_fmt(value)}"
        )
    return v


def require_choice(name: str, value: object, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices`` or raise :class:`InputError` (plain
    string options; an enum's are :func:`parse_enum`'s)."""
    options = list(choices)
    if not isinstance(value, str) or value not in options:
        raise InputError(f"unknown {name} {_fmt(value)}; expected one of {', '.join(options)}")
    return value


T = TypeVar("T")


def require_instance(name: str, value: object, cls: type[T]) -> T:
    """Return ``value`` if it is a ``cls`` or raise :class:`InputError` ("``name`` must be
    a bwim ``cls``")."""
    if not isinstance(value, cls):
        raise InputError(f"{name} must be a bwim {cls.__name__}, got {type(value).__name__}")
    return value


E = TypeVar("E", bound=Enum)


def parse_enum(enum: type[E], value: object, name: str, *, context: str = "") -> E:
    """``enum(value)``, or raise :class:`InputError` naming ``name`` and listing the options.

    ``context`` follows the value in the message (e.g. ``" for edge x0"``).
    """
    try:
        return enum(value)
    except ValueError:
        options = ", ".join(str(m.value) for m in enum)
        raise InputError(
            f"unknown {name} {_fmt(value)}{context}; expected one of {options}"
        ) from None


def as_floats(name: str, values, *, ndmin: int = 0) -> np.ndarray:
    """``values`` as a float array (no copy of a float array; at least ``ndmin``
    dimensions), else InputError naming ``name`` (text, None, a ragged list)."""
    import numpy as np

    try:  # no copy of an array that is already float
        a = np.asarray(values, dtype=float)
        return a.reshape((1,) * (ndmin - a.ndim) + a.shape) if a.ndim < ndmin else a
    except (TypeError, ValueError):
        raise InputError(f"{name} must be numbers, got {type(values).__name__}") from None


def require_axis(name: str, values, what: str = "samples") -> np.ndarray:
    """``values`` as a float array: 1-D, at least two ``what``, finite and strictly
    increasing (a time or position axis), else InputError naming ``name``."""
    a = as_floats(name, values)
    if a.ndim != 1 or a.size < 2:
        raise InputError(f"{name} must be a 1-D array of at least two {what}")
    if not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
        raise InputError(f"{name} must be finite and strictly increasing")
    return a


def require_columns(name: str, values, shape: tuple[int, int], labels: str) -> np.ndarray:
    """``values`` as a float table of ``shape`` (a 1-D array is one column), else
    InputError naming ``name`` and the expected ``labels``, e.g. ``"(n_t, n_sensors)"``."""
    a = as_floats(name, values)
    if a.ndim == 1:
        a = a[:, None]
    if a.shape != tuple(shape):
        raise InputError(f"{name} must have shape {labels} = {tuple(shape)}, got {a.shape}")
    return a
