"""Safe outputs for the command line: no input overwritten, no run replacing another's
results, work kept across interruptions.

Contract
--------
* :func:`refuse_input_overwrite` raises :class:`~bwim.errors.InputError` when an output
  path is one of the inputs (same file by :func:`os.path.samefile`, or the same resolved
  path when the file does not exist yet), naming both.
* :func:`refuse_existing` raises unless the output does not exist yet or ``force`` is true.
* :class:`OutputLock` (a context manager) takes the lock file :data:`LOCK_NAME` in an output
  folder atomically (``O_CREAT | O_EXCL``) and removes it on exit; a second run into the
  same folder fails at once with a one-line message naming the lock (and the process that
  holds it).  A lock whose process is gone (a killed run) is taken over.
* :class:`Manifest` records, per input, what a batch wrote (result file and summary rows),
  keyed by the input's resolved path, size and modification time (an input changed since
  replaces its entry), and what the batch was (``meta``: the scenario, the calibration),
  in :data:`MANIFEST_NAME` in the output folder; it is rewritten atomically after each input
  (or, with ``record(..., save=False)`` and :meth:`Manifest.save`, in batches), so an
  interrupted run can be resumed: inputs already done (and unchanged) are skipped.
* :func:`signals_as_interrupt` (a context manager) makes SIGTERM (and SIGHUP) raise
  :class:`KeyboardInterrupt` in the main thread, so that ``with``/``finally`` blocks run
  (atomic writers remove their temporary files, worker pools are shut down) as on Ctrl-C.
* Exit codes of batch commands: 0 all inputs done, 1 some inputs failed (each has a
  summary row with its reason), 2 bad input or usage (nothing done).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import threading
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from bwim.atomic import atomic_open
from bwim.errors import InputError

__all__ = ["EXIT_FAILED", "EXIT_OK", "EXIT_USAGE", "LOCK_NAME", "MANIFEST_NAME", "Manifest",
           "OutputLock", "file_key", "refuse_existing", "refuse_input_overwrite",
           "refuse_output_in_inputs", "signals_as_interrupt"]

EXIT_OK = 0  #: every input processed
EXIT_FAILED = 1  #: some inputs failed (their summary rows say why)
EXIT_USAGE = 2  #: bad input or usage; nothing done

LOCK_NAME = ".bwim.lock"  #: the lock file of an output folder
MANIFEST_NAME = "manifest.json"  #: what a batch has written, per input


def _same(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except (OSError, ValueError):
        return False


def refuse_input_overwrite(outputs: Iterable[str | os.PathLike],
                           inputs: Iterable[str | os.PathLike]) -> None:
    """Raise :class:`InputError` if any output path is one of the input files."""
    ins = [Path(p) for p in inputs]
    for out in (Path(p) for p in outputs):
        for src in ins:
            if _same(out, src):
                raise InputError(f"the output {out} is the input {src}; refusing to "
                                 "overwrite an input (choose another output)")


def refuse_output_in_inputs(folder: str | os.PathLike,
                            inputs: Iterable[str | os.PathLike]) -> None:
    """Raise :class:`InputError` if the output ``folder`` is one of the input folders
    (a folder of records is expanded to the files it holds, not its subfolders): its
    outputs would sit among the records and be read as records by the next command given
    that folder."""
    out = Path(folder)
    try:
        out_real = out.resolve()
    except (OSError, ValueError):
        return
    for src in (Path(p) for p in inputs):
        if not src.is_dir():
            continue
        try:
            src_real = src.resolve()
        except (OSError, ValueError):
            continue
        if out_real == src_real:
            raise InputError(f"the output folder {out} is the input folder {src}: its "
                             "outputs would be read as records next time (choose another "
                             "output folder, e.g. a subfolder)")


def refuse_existing(path: str | os.PathLike, *, force: bool) -> Path:
    """``path`` as a Path; :class:`InputError` if it exists and ``force`` is false."""
    p = Path(path)
    if not force and (p.exists() or p.is_symlink()):
        raise InputError(f"{p} exists; use --force to overwrite it")
    return p


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


class OutputLock:
    """An exclusive lock on an output folder for one run (see the module docstring)."""

    def __init__(self, folder: str | os.PathLike) -> None:
        self.path = Path(folder) / LOCK_NAME
        self._held = False

    def _create(self) -> None:
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        with os.fdopen(fd, "w") as f:
            f.write(f"{os.getpid()}\n")

    def acquire(self) -> OutputLock:
        try:
            self._create()
        except FileExistsError:
            try:
                pid = int(self.path.read_text().split()[0])
            except (OSError, ValueError, IndexError):
                pid = None
            if pid is not None and not _pid_alive(pid):  # a killed run's lock: take it over
                with contextlib.suppress(OSError):
                    self.path.unlink()
                return self.acquire()
            who = f" by process {pid}" if pid is not None else ""
            raise InputError(f"{self.path.parent} is in use{who} (lock file {self.path}); "
                             "wait for that run, or remove the lock if no run is "
                             "active") from None
        except OSError as exc:
            raise InputError(f"cannot lock {self.path.parent}: "
                             f"{(exc.strerror or str(exc)).lower()}") from None
        self._held = True
        return self

    def release(self) -> None:
        if self._held:
            with contextlib.suppress(OSError):
                self.path.unlink()
            self._held = False

    def __enter__(self) -> OutputLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def file_key(path: str | os.PathLike) -> str:
    """A file's identity for a batch: its resolved path, size and modification time."""
    p = Path(path)
    st = p.stat()
    return f"{p.resolve()}|{st.st_size}|{st.st_mtime_ns}"


_key = file_key


class Manifest:
    """Per-input results of a batch in ``folder/manifest.json`` (see the module docstring).

    ``entries`` maps an input's key to ``{"result": name or None, "rows": [...],
    "error": reason or None}``; only successful entries count as done.
    """

    def __init__(self, folder: str | os.PathLike, *, fresh: bool = False) -> None:
        self.path = Path(folder) / MANIFEST_NAME
        self.entries: dict[str, dict[str, Any]] = {}
        self.meta: dict[str, Any] = {}
        if not fresh and self.path.exists():
            try:
                data = json.loads(self.path.read_text(encoding="utf-8"))
                entries = data["entries"]
                meta = data.get("batch", {})
                if not isinstance(entries, dict) or not isinstance(meta, dict):
                    raise TypeError
                for e in entries.values():  # each entry as record() writes it
                    if not (isinstance(e, dict) and isinstance(e.get("source"), str)
                            and isinstance(e.get("rows"), list)
                            and all(isinstance(c, dict) and isinstance(c.get("record"), str)
                                    for c in e["rows"])):
                        raise TypeError
            except (OSError, ValueError, KeyError, TypeError):
                raise InputError(f"{self.path}: damaged manifest; remove it (or use "
                                 "--force) to start the batch afresh") from None
            self.entries = entries
            self.meta = meta

    def belongs_to(self, sources: Sequence[Path]) -> bool:
        """Whether every entry is one of ``sources`` (unchanged): a rerun of the same batch,
        which may resume, rather than another batch, which must not overwrite it."""
        keys = set()
        for p in sources:
            try:
                keys.add(_key(p))
            except OSError:
                continue
        return all(k in keys for k in self.entries)

    def done(self, source: Path) -> dict[str, Any] | None:
        """The entry of an input already processed successfully (and unchanged), or None."""
        try:
            entry = self.entries.get(_key(source))
        except OSError:
            return None
        if entry is None or entry.get("error") is not None:
            return None
        result = entry.get("result")
        if result is not None and not (self.path.parent / result).exists():
            return None
        return entry

    def record(self, source: Path, *, result: str | None, rows: list, error: str | None,
               save: bool = True) -> None:
        """Note an input's outcome and (unless ``save`` is false: a caller that saves
        in batches, see :meth:`save`) rewrite the manifest atomically."""
        key = _key(source)
        resolved = str(Path(source).resolve())
        for old in [k for k, e in self.entries.items()
                    if k != key and k.rpartition("|")[0].rpartition("|")[0] == resolved]:
            del self.entries[old]  # the same file, changed since: its old entry is stale
        self.entries[key] = {"source": str(source), "result": result, "rows": rows,
                             "error": error}
        if save:
            self.save()

    def save(self) -> None:
        """Rewrite the manifest atomically."""
        with atomic_open(self.path) as f:
            json.dump({"batch": self.meta, "entries": self.entries}, f, indent=1)


@contextlib.contextmanager
def signals_as_interrupt() -> Iterator[None]:
    """SIGTERM and SIGHUP raise KeyboardInterrupt in the main thread while the block runs
    (a no-op outside the main thread).  A signal whose KeyboardInterrupt Python swallowed
    (it arrived while a weak reference's callback or a ``__del__`` ran, where exceptions
    are only printed) still ends the block with KeyboardInterrupt when it completes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []

    def interrupt(signum: int, frame: object) -> None:
        received.append(signum)
        raise KeyboardInterrupt(f"signal {signum}")

    names = [s for s in ("SIGTERM", "SIGHUP") if hasattr(signal, s)]
    old = {s: signal.signal(getattr(signal, s), interrupt) for s in names}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(getattr(signal, s), handler)
    if received:  # the block ended normally although a signal came: it was swallowed
        raise KeyboardInterrupt(f"signal {received[0]}")
