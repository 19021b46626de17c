"""The folder a simulated day is written to, and the small pieces both day writers share.

Contract
--------
* :func:`prepare_folder` makes ``out_dir`` (parents too) or accepts an empty existing
  folder, writable; anything else (a file, a folder with content, no permission) is an
  :class:`~bwim.errors.InputError` naming it: a simulation never writes over files.
* :func:`checked_count` checks an integer argument (not a bool) at least ``minimum``.
* :func:`joined` writes numbers ``;``-separated in a format (the truth files' lists).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from bwim.errors import InputError

__all__ = ["checked_count", "joined", "prepare_folder"]


def checked_count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def prepare_folder(out_dir) -> Path:
    out = Path(out_dir)
    if out.exists():
        if not out.is_dir():
            raise InputError(f"out_dir {out} exists and is not a folder")
        if any(out.iterdir()):
            raise InputError(f"out_dir {out} is not empty; refusing to overwrite it")
    else:
        try:
            out.mkdir(parents=True)
        except OSError as exc:
            raise InputError(f"out_dir {out} cannot be created: {exc.strerror}") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise InputError(f"out_dir {out}: no permission to write in it")
    return out


def joined(values, fmt: str) -> str:
    return ";".join(format(float(v), fmt) for v in values)
