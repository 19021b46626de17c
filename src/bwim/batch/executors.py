"""Where a batch's items run: this process, local worker processes, or a dask cluster.

Contract
--------
* An executor runs a :class:`Task` on a sequence of items and yields
  ``(index, result)`` as each item finishes (not in input order).  ``task.run(shared,
  item)`` must be a top-level function that never raises for a bad item (it returns a
  failure result): one bad record never ends a batch.  ``shared`` (the site's
  calibration, a bridge model) is sent to each worker once.
* :class:`Serial` runs every item here, in order.
* :class:`Processes` runs ``jobs`` items at a time: this process and ``jobs − 1`` loky
  worker processes of the run's own (shut down when the run ends, killed on an
  interrupt), each fed the next item the moment it is free.  ``shared`` is pickled once
  (cloudpickle, as loky and dask do),
  and again after this process's first item (so that the workers receive its warm
  caches: modes, matrices).  Each process gets its share of the cores for BLAS (two
  processes with a BLAS thread per core would oversubscribe them).  A worker ends
  within a second of its parent process, also when the parent is killed (``kill -9``:
  :func:`die_with_parent`).
* :class:`Dask` runs items on a ``dask.distributed`` scheduler.  Items are read here
  (``task.load``; the workers need not see this file system) and sent, at most two per
  worker thread ahead, so a day of records is never all in memory.
* :func:`executor_for` picks one from the command line's ``--jobs`` / ``--scheduler``.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from bwim.errors import InputError
from bwim.orphans import die_with_parent

__all__ = ["Dask", "Executor", "Processes", "Serial", "Task", "executor_for"]


@dataclass(frozen=True)
class Task:
    """What to do with each item (every callable top-level, hence picklable).

    ``run(shared, item)`` processes one item (a path or a record) and returns its result,
    never raising for a bad item.  ``load(item)`` reads an item here for executors whose
    workers cannot (:class:`Dask`): it returns the object ``run`` accepts, or the failure
    result itself (recognised by ``is_failure``).
    """

    run: Callable[[Any, Any], Any]
    load: Callable[[Any], Any] | None = None
    is_failure: Callable[[Any], bool] | None = None


class Executor:
    """Runs a task over items: ``(index, result)`` as each finishes."""

    def map(self, task: Task, items: Sequence[Any], shared: Any) -> Iterator[tuple[int, Any]]:
        raise NotImplementedError


class Serial(Executor):
    """Every item in this process, in order."""

    def map(self, task: Task, items: Sequence[Any], shared: Any) -> Iterator[tuple[int, Any]]:
        for i, item in enumerate(items):
            yield i, task.run(shared, item)


def _cores() -> int:
    return os.cpu_count() or 1


@dataclass(frozen=True)
class Processes(Executor):
    """``jobs`` processes: this one and ``jobs − 1`` loky workers (-1: one per core)."""

    jobs: int

    def __post_init__(self) -> None:
        if isinstance(self.jobs, bool) or not isinstance(self.jobs, int) or (
                self.jobs < 1 and self.jobs != -1):
            raise InputError(f"jobs must be a positive number or -1 (all cores), got "
                             f"{self.jobs!r}")

    @property
    def n_processes(self) -> int:
        return _cores() if self.jobs == -1 else self.jobs

    def map(self, task: Task, items: Sequence[Any], shared: Any) -> Iterator[tuple[int, Any]]:
        n = len(items)
        workers = min(self.n_processes, n) - 1
        nxt = iter(range(n))
        lock = threading.Lock()

        def take() -> int | None:
            with lock:
                return next(nxt, None)

        if workers <= 0:
            while (i := take()) is not None:
                yield i, task.run(shared, items[i])
            return

        import cloudpickle
        from joblib.externals.loky import ProcessPoolExecutor
        from threadpoolctl import threadpool_limits

        threads = max(1, _cores() // (workers + 1))
        executor = ProcessPoolExecutor(max_workers=workers, initializer=die_with_parent,
                                       env={name: str(threads) for name in (
                                           "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                           "MKL_NUM_THREADS")})
        limits = threadpool_limits(limits=threads)
        stop = threading.Event()
        finished: queue.Queue = queue.Queue()
        blob = [cloudpickle.dumps(shared, protocol=pickle.HIGHEST_PROTOCOL)]

        def feed() -> None:
            try:
                while not stop.is_set() and (i := take()) is not None:
                    fut = executor.submit(_run_pickled, task, blob[0], items[i])
                    finished.put((i, fut.result()))
            except BaseException as exc:  # handed to the main thread
                finished.put((None, exc))
            finally:
                finished.put((None, None))

        try:
            first = take()
            feeders = [threading.Thread(target=feed, daemon=True) for _ in range(workers)]
            for t in feeders:
                t.start()
            alive = workers
            yield first, task.run(shared, items[first])
            blob[0] = cloudpickle.dumps(shared, protocol=pickle.HIGHEST_PROTOCOL)  # warm caches

            def ready(block: bool) -> Iterator[tuple[int, Any]]:
                nonlocal alive
                while alive:
                    try:
                        i, value = finished.get(block=block)
                    except queue.Empty:
                        return
                    if i is not None:
                        yield i, value
                    elif value is None:
                        alive -= 1
                    else:
                        raise value

            while (i := take()) is not None:
                yield from ready(False)
                yield i, task.run(shared, items[i])
            yield from ready(True)
        except BaseException:
            stop.set()
            with contextlib.suppress(Exception):
                executor.shutdown(wait=False, kill_workers=True)
            raise
        finally:
            stop.set()
            limits.restore_original_limits()
            with contextlib.suppress(Exception):
                executor.shutdown(wait=False)


def _run_pickled(task: Task, blob: bytes, item: Any) -> Any:
    """``task.run`` with ``shared`` unpickled from the same bytes for every item (no
    pickling per item; the parent's warm caches travel with it)."""
    return task.run(pickle.loads(blob), item)


@dataclass(frozen=True)
class Dask(Executor):
    """A ``dask.distributed`` scheduler at ``address`` (e.g. ``tcp://host:8786``)."""

    address: str
    timeout: float = 10.0

    def map(self, task: Task, items: Sequence[Any], shared: Any) -> Iterator[tuple[int, Any]]:
        try:
            from distributed import Client, as_completed
        except ImportError:  # pragma: no cover - the dask extra is not installed
            raise InputError("a dask scheduler needs the 'dask' extra: "
                             "pip install 'bwim[dask]'") from None
        try:
            client = Client(self.address, timeout=self.timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"cannot reach the dask scheduler {self.address}: {exc}"
                             ) from None
        try:
            [remote] = client.scatter([shared], broadcast=True)
            ahead = 2 * max(1, sum(client.nthreads().values())) + 2
            running = as_completed()
            index: dict[str, int] = {}
            for i, item in enumerate(items):
                obj = item if task.load is None else task.load(item)
                if task.is_failure is not None and task.is_failure(obj):
                    yield i, obj
                    continue
                fut = client.submit(task.run, remote, obj, pure=False)
                index[fut.key] = i
                running.add(fut)
                while running.count() >= ahead:
                    fut = next(running)
                    yield index.pop(fut.key), fut.result()
            for fut in running:
                yield index.pop(fut.key), fut.result()
        finally:
            client.close()


def executor_for(jobs: int | None = 1, scheduler: str | None = None) -> Executor:
    """The executor of ``--jobs N`` (1: :class:`Serial`) or ``--scheduler ADDRESS``."""
    if scheduler:
        return Dask(scheduler)
    if jobs is None or jobs == 1:
        return Serial()
    return Processes(jobs)
