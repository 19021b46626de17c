"""Input paths given on a command line: files, or folders expanded to the files they hold.

Contract
--------
:func:`expand_paths` keeps files as given (a missing one is an :class:`InputError`) and
replaces each folder by its files with one of ``suffixes`` (any file when ``suffixes`` is
None: a logger's exports may have any extension; sorted, hidden files skipped); a folder
with none is an :class:`InputError` naming what was looked for.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from bwim.errors import InputError

__all__ = ["expand_paths"]


def expand_paths(items: Iterable[str | os.PathLike], suffixes: Iterable[str] | None, *,
                 what: str) -> list[Path]:
    """Files named by ``items``, folders expanded to their ``suffixes`` files (any file
    when ``suffixes`` is None)."""
    wanted = None if suffixes is None else {s.lower() for s in suffixes}
    out: list[Path] = []
    for p in map(Path, items):
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file()
                           and not q.name.startswith(".")
                           and (wanted is None or q.suffix.lower() in wanted))
            if not found:
                kinds = "" if wanted is None else f" ({', '.join(sorted(wanted))} files)"
                raise InputError(f"{p}: no {what}{kinds} in this folder")
            out += found
        elif not p.exists():
            raise InputError(f"{p}: no such file")
        else:
            out.append(p)
    return out
