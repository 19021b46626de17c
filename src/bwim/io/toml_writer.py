"""A small TOML writer for the plain data of scenario and bridge files.

Contract
--------
* :func:`to_toml` turns a mapping of strings to values into TOML 1.0 text that
  :mod:`tomllib` reads back to an equal mapping.  Values may be ``bool``, ``int``,
  ``float`` (written with :func:`repr`, so every float reads back bit for bit; ``inf``
  and ``nan`` as TOML's ``inf`` / ``nan``), ``str``, NumPy scalars, sequences of these
  (arrays, nested to any depth), mappings (tables) and sequences of mappings (arrays of
  tables).  ``None`` values are left out (TOML has no null).
* Within a table, plain keys come first, then sub-tables and arrays of tables, each in
  the mapping's order.  Long arrays are wrapped one element (or row) per line.
* Anything else (a mapping inside a plain array, an array mixing tables and values, a
  non-string key) raises :class:`TypeError`: it is a programming error, not bad input.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["to_toml"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
            "\r": "\\r"}
_WIDTH = 92  # wrap arrays whose inline form would be longer than this


def _string(s: str) -> str:
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _key(k: Any) -> str:
    if not isinstance(k, str):
        raise TypeError(f"TOML keys must be strings, got {k!r}")
    return k if _BARE_KEY.fullmatch(k) else _string(k)


def _is_table(v: Any) -> bool:
    return isinstance(v, Mapping)


def _is_array(v: Any) -> bool:
    return isinstance(v, np.ndarray) or (
        isinstance(v, Sequence) and not isinstance(v, (str, bytes))
    )


def _is_table_array(v: Any) -> bool:
    return _is_array(v) and len(v) > 0 and all(_is_table(e) for e in v)


def _scalar(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        if math.isnan(f):
            return "nan"
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(f)
    if isinstance(v, str):
        return _string(v)
    raise TypeError(f"cannot write {type(v).__name__} {v!r} to TOML")


def _value(v: Any, indent: str = "") -> str:
    if not _is_array(v):
        if _is_table(v):
            raise TypeError("a table inside a plain array cannot be written")
        return _scalar(v)
    items = list(v)
    if any(_is_table(e) for e in items):
        raise TypeError("an array mixing tables and values cannot be written")
    inner = [_value(e, indent + "    ") for e in items]
    inline = "[" + ", ".join(inner) + "]"
    if len(inline) + len(indent) <= _WIDTH and "\n" not in inline:
        return inline
    pad = indent + "    "
    if not any(_is_array(e) for e in items):  # a long flat array: fill lines
        lines, line = [], ""
        for s in inner:
            piece = s + ","
            if line and len(pad) + len(line) + 1 + len(piece) > _WIDTH:
                lines.append(line)
                line = piece
            else:
                line = f"{line} {piece}" if line else piece
        lines.append(line)
        return "[\n" + "\n".join(pad + ln for ln in lines) + "\n" + indent + "]"
    return "[\n" + "".join(f"{pad}{s},\n" for s in inner) + indent + "]"


def _table(path: list[str], table: Mapping, out: list[str], header: str | None) -> None:
    if header is not None:
        out.append(header)
    nested = []
    for k, v in table.items():
        if _is_table(v) or _is_table_array(v):
            nested.append((k, v))
        elif v is not None:
            out.append(f"{_key(k)} = {_value(v)}")
    for k, v in nested:  # after every plain key, which would otherwise join the last table
        sub = [*path, _key(k)]
        name = ".".join(sub)
        for entry, head in ([(v, f"[{name}]")] if _is_table(v)
                            else [(e, f"[[{name}]]") for e in v]):
            if out:
                out.append("")
            _table(sub, entry, out, head)


def to_toml(doc: Mapping[str, Any], *, header: str = "") -> str:
    """TOML text of a mapping (see the module docstring).

    Parameters
    ----------
    doc : mapping
        The document: string keys, values as listed in the module docstring.
    header : str
        Text written first as ``#`` comment lines (may contain newlines).

    Returns
    -------
    str
        The document, ending with a newline.
    """
    if not _is_table(doc):
        raise TypeError(f"a TOML document is a mapping, got {type(doc).__name__}")
    out: list[str] = []
    for line in header.splitlines():
        out.append(f"# {line}".rstrip())
    if out:
        out.append("")
    _table([], doc, out, None)
    text = "\n".join(out).strip("\n")
    while "\n\n\n" in text:  # no value spans lines with blank ones, so this is safe
        text = text.replace("\n\n\n", "\n\n")
    return text + "\n"
