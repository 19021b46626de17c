"""Resource limits: refuse work whose memory would exceed a bound, before allocating it.

Contract
--------
* :func:`memory_limit` is the number of bytes one bwim computation may allocate for its
  large arrays.  It is read at call time (no module state) from the environment variable
  ``BWIM_MEMORY_LIMIT`` when set: a number of bytes, a size with a unit (``"800M"``,
  ``"4G"``, ``"512MiB"``), or a fraction of the machine's memory (``"0.25"``).  Unset, it
  is :data:`DEFAULT_FRACTION` of the machine's physical memory.
* :func:`check_memory` raises :class:`~bwim.errors.InputError` with a one-line message
  ("<what> needs about 25.3 GiB, more than the memory limit of 12 GiB ...") when an
  estimate exceeds the limit.  Callers estimate **before** they allocate, from the sizes
  the arguments imply (samples × channels, degrees of freedom × band width, ...), so a
  hostile or mistyped input (``approach = 1e7``, ``nx = 1e5``, a file that declares a
  5e8 × 3 dataset) ends with a message, not with the host's memory exhausted.
* Estimates are deliberately rough (within a factor of about two): the limit is a guard
  rail against inputs that are wrong by orders of magnitude, not an accountant.
"""

from __future__ import annotations

import math
import os
import re

from bwim.errors import InputError

__all__ = ["DEFAULT_FRACTION", "ENV_VAR", "check_memory", "format_bytes", "memory_limit",
           "parse_size"]

#: Share of the machine's physical memory one computation may use by default.
DEFAULT_FRACTION = 0.5
#: The environment variable that overrides the limit.
ENV_VAR = "BWIM_MEMORY_LIMIT"

_UNITS = {"": 1, "b": 1, "k": 1024, "kb": 1000, "kib": 1024, "m": 1024**2, "mb": 1000**2,
          "mib": 1024**2, "g": 1024**3, "gb": 1000**3, "gib": 1024**3, "t": 1024**4,
          "tb": 1000**4, "tib": 1024**4}
_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([a-zA-Z]*)\s*$")


def _physical_memory() -> int:
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):  # not POSIX: assume a modest machine
        return 8 * 1024**3


def parse_size(text: str, *, total: int | None = None) -> int:
    """Bytes from ``"4G"``, ``"800MiB"``, ``"123456"`` or a fraction ``"0.25"`` of ``total``.

    Raises
    ------
    InputError
        Not a size, or not positive.
    """
    m = _SIZE.match(str(text))
    unit = m.group(2).lower() if m else ""
    if m is None or unit not in _UNITS:
        raise InputError(f"{ENV_VAR}: not a size: {text!r} (use bytes, e.g. 4G, or a "
                         "fraction of the machine's memory, e.g. 0.5)")
    value = float(m.group(1))
    if not math.isfinite(value) or value <= 0:
        raise InputError(f"{ENV_VAR}: the size must be positive, got {text!r}")
    size = (int(value * (_physical_memory() if total is None else total))
            if unit == "" and value < 1.0 else int(value * _UNITS[unit]))
    if size < 1:
        raise InputError(f"{ENV_VAR}: {text!r} is less than one byte")
    return size


def memory_limit() -> int:
    """The memory limit in bytes (see the module docstring)."""
    text = os.environ.get(ENV_VAR, "").strip()
    if text:
        return parse_size(text)
    return int(DEFAULT_FRACTION * _physical_memory())


def format_bytes(n: float) -> str:
    """``n`` bytes as a short human-readable size (``"1.5 GiB"``)."""
    for unit, size in (("TiB", 1024**4), ("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def check_memory(n_bytes: float, what: str, *, limit: int | None = None) -> None:
    """Raise :class:`InputError` if ``n_bytes`` (an estimate) exceeds the memory limit.

    Parameters
    ----------
    n_bytes : float
        Estimated bytes the computation will allocate (may be huge or non-finite: an
        overflowing estimate is refused too).
    what : str
        What needs the memory, for the message (``"a 5e8 × 3 record"``).
    limit : int, optional
        Bytes; default :func:`memory_limit`.
    """
    cap = memory_limit() if limit is None else int(limit)
    if not math.isfinite(n_bytes) or n_bytes > cap:
        need = "an unbounded amount" if not math.isfinite(n_bytes) else format_bytes(n_bytes)
        raise InputError(f"{what} needs about {need} of memory, more than the limit of "
                         f"{format_bytes(cap)} (set {ENV_VAR} to change it)")
