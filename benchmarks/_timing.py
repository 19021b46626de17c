"""Small timing helpers shared by the benchmarks (median of repeats, printed tables)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from bwim.tables import Table


def median_time(fn: Callable[[], object], *, repeat: int = 7, min_time: float = 0.05) -> float:
    """Median wall time of ``fn()`` in seconds, each sample looping until ``min_time``."""
    fn()  # warm up (imports, caches)
    samples = []
    for _ in range(repeat):
        n = 0
        t0 = time.perf_counter()
        while True:
            fn()
            n += 1
            elapsed = time.perf_counter() - t0
            if elapsed >= min_time:
                break
        samples.append(elapsed / n)
    samples.sort()
    return samples[len(samples) // 2]


def print_table(title: str, header: Sequence[str], rows: Sequence[Sequence[object]]) -> None:
    """Print a plain-text table with right-aligned columns (:class:`bwim.tables.Table`)."""
    print("\n" + Table(title, header, rows).render())
