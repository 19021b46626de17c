"""Atomic output files: write beside the target, then rename over it.

This is bwim's one atomic-write primitive.  It sits below every layer that writes files
(:mod:`bwim.io` for results and records, :mod:`bwim.optimize` for checkpoints) and
imports nothing of bwim but :mod:`bwim.errors`.

Contract
--------
* :func:`atomic_output` yields a temporary path in the destination folder.  When the
  ``with`` block ends normally the temporary file is flushed to disk and renamed over the
  target with :func:`os.replace` (atomic within one file system); when the block raises,
  the temporary file is removed and the target is left as it was.  A reader therefore sees
  the old file or the complete new one, never a half-written output.
* An output path that cannot be written (its folder does not exist, a folder is in the
  way, no permission, a NUL byte in the path) raises :class:`~bwim.errors.InputError`
  naming the path before any work is done; an operating-system error while writing (a
  full disk) raises :class:`~bwim.errors.InputError` naming the path too.
* :func:`atomic_open` is the same for a text file, yielding the open file (the io
  layer's text writers use it).
* The temporary file is created with the usual permissions (``0o666`` less the umask), so
  the output has the permissions of any file the user creates.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from bwim.errors import InputError

__all__ = ["atomic_open", "atomic_output", "check_writable"]


def _reason(exc: OSError) -> str:
    return (exc.strerror or str(exc)).lower()


def check_writable(path: str | os.PathLike) -> Path:
    """Raise :class:`InputError` unless a file can be created at ``path``.

    Parameters
    ----------
    path : str or path-like
        The output file.

    Returns
    -------
    Path
        ``path`` as a :class:`~pathlib.Path`.
    """
    target = Path(path)
    if "\x00" in str(target):
        shown = str(target).replace("\x00", "\\x00")
        raise InputError(f"cannot write {shown}: the path holds a NUL byte")
    folder = target.parent
    if not folder.is_dir():
        raise InputError(f"cannot write {target}: the folder {folder} does not exist")
    if target.is_dir():
        raise InputError(f"cannot write {target}: it is a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {target}: no permission to write in {folder}")
    return target


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path that becomes ``path`` when the block succeeds.

    Parameters
    ----------
    path : str or path-like
        The output file; its folder must exist.

    Yields
    ------
    Path
        An empty temporary file in the same folder, to be written (and closed) inside the
        block.

    Raises
    ------
    InputError
        The path cannot be written; nothing is left behind.
    """
    target = check_writable(path)
    tmp = target.parent / f".{target.name}.{secrets.token_hex(6)}.tmp"
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except OSError as exc:
        raise InputError(f"cannot write {target}: {_reason(exc)}") from None
    os.close(fd)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise InputError(f"cannot write {target}: {_reason(exc)}") from exc
        raise


@contextlib.contextmanager
def atomic_open(
    path: str | os.PathLike, *, encoding: str = "utf-8", newline: str | None = None
) -> Iterator[IO[str]]:
    """Open a text file for writing that appears at ``path`` only when the block succeeds.

    Parameters
    ----------
    path : str or path-like
        The output file.
    encoding, newline
        As for :func:`open`.
    """
    with atomic_output(path) as tmp, open(tmp, "w", encoding=encoding, newline=newline) as f:
        yield f
