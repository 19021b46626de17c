"""Many events at once: weigh or identify a day of records on any executor, resumably.

Contract
--------
* :func:`weigh_events` and :func:`identify_records` (:mod:`bwim.batch.events`) are
  iterators of :class:`Outcome` over records or paths, on one executor abstraction
  (:mod:`bwim.batch.executors`: :class:`Serial`, :class:`Processes` with BLAS limits, a
  :class:`Dask` scheduler).  Each outcome's ``rows`` are summary rows
  (:class:`bwim.summary.SummaryRow`) that :func:`bwim.accuracy.assess` takes directly::

      from functools import partial
      rows = [r for out in bwim.batch.weigh_events(paths, site,
                                                   read=partial(load_record, scenario=sc))
              for r in out.rows]
      bwim.accuracy.assess(rows, reference)

* :class:`BatchFolder` and :func:`run_into` (:mod:`bwim.batch.folder`) write a batch into
  a folder with the one resume rule: failed records are retried, done ones skipped, no
  row is ever dropped.
* Layering: above the site chain (:mod:`bwim.site`, :mod:`bwim.mfi`) and the file formats
  (:mod:`bwim.io`); the scenario (:mod:`bwim.scenario`) comes in only as the ``read``
  callable the caller passes.
"""

from bwim.batch.events import (
    Item,
    Outcome,
    identify_records,
    items_of,
    weigh_events,
    weigh_records,
)
from bwim.batch.executors import Dask, Executor, Processes, Serial, Task, executor_for
from bwim.batch.folder import BatchFolder, BatchReport, run_into

__all__ = [
    "BatchFolder",
    "BatchReport",
    "Dask",
    "Executor",
    "Item",
    "Outcome",
    "Processes",
    "Serial",
    "Task",
    "executor_for",
    "identify_records",
    "items_of",
    "run_into",
    "weigh_events",
    "weigh_records",
]
