"""Worker processes that end with the process that started them.

Contract
--------
* :func:`die_with_parent`, run at a worker's start (a pool's ``initializer``), ends the
  worker within :data:`WATCH_PARENT_EVERY` seconds of its parent's end, however the parent
  ends (``kill -9`` included), so that no batch or calibration leaves orphans computing.
* No state: each call starts one daemon thread in the calling process.
"""

from __future__ import annotations

import os
import threading
import time

__all__ = ["WATCH_PARENT_EVERY", "die_with_parent"]

#: Seconds between a worker's checks that the process that started it is alive.
WATCH_PARENT_EVERY = 0.5


def die_with_parent(every: float = WATCH_PARENT_EVERY) -> None:
    """Make this (worker) process end when the process that started it ends, however it
    ends (``kill -9`` included): a daemon thread checks every ``every`` seconds that its
    parent is still the same process (once the parent is gone the worker is handed to
    another, so ``os.getppid()`` changes) and ends the worker at once (``os._exit``).

    Linux's ``prctl(PR_SET_PDEATHSIG)`` is not used: it fires when the *thread* that
    started the worker ends, and the pool starts workers from whichever feeding thread
    submits, so a worker busy with another thread's item would be killed.
    """
    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(every)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="bwim-watch-parent", daemon=True).start()
