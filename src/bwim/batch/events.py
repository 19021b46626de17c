"""Many events: weigh or identify each, on any executor, as an iterator of outcomes.

Contract
--------
* :func:`weigh_events` weighs every item (a logger file's path, read with ``read``, or a
  :class:`~bwim.Record`) with a site's calibration (:func:`bwim.site.weigh_event`: Moses
  with the multi-run lines, or MFI with ``bridge``); :func:`identify_records` identifies
  the moving forces of every item (:func:`bwim.identify_forces`) with ``bridge``,
  writing each item's result to its ``target`` when given; :func:`weigh_records` weighs
  records that carry their passages by Moses' algorithm with one influence line.
* Both yield one :class:`Outcome` per item as it finishes (any order; ``index`` is its
  place in the input), on the executor given (:mod:`bwim.batch.executors`; default
  :class:`~bwim.batch.executors.Serial`).  An outcome's ``rows`` are its summary rows
  (:class:`~bwim.summary.SummaryRow`, one per vehicle): ``bwim.accuracy.assess`` takes
  them as they are.  A weighing's outcome also carries what each vehicle's gauges did
  (``gauges``, :mod:`bwim.batch.gauges`), for the day's table of gauge health.
* A bad item never ends the batch: an unreadable file, or a record the method cannot
  process, gives one row of status ``"failed"`` with the reason; a vehicle that is seen
  but not weighed gives a ``"refused"`` row with the reason.  No weight leaves without its
  plausibility checks (:class:`~bwim.summary.SummaryRow` refuses it).
* ``keep=True`` (the default) keeps each item's full result on its outcome (``event`` /
  ``identification``); a batch of thousands of records that only needs the rows passes
  ``keep=False`` (less to send back from worker processes).
* Items are read where they run: in the worker for local processes, here for a dask
  cluster (whose workers need not see this file system).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bwim.batch.executors import Executor, Serial, Task
from bwim.errors import DATA_ERRORS, BwimError, InputError
from bwim.records import Record
from bwim.summary import SummaryRow, failed_row

__all__ = ["Item", "Outcome", "identify_records", "items_of", "weigh_events", "weigh_records"]

#: What processing one record may raise without ending a batch: bwim's own errors and the
#: numerical failures of a degenerate record.
BATCH_ERRORS = DATA_ERRORS


def reason_of(exc: BaseException) -> str:
    """An exception as one line (bwim's own messages as they are; others with their type)."""
    text = " ".join(str(exc).split())
    if isinstance(exc, BwimError):
        return text or type(exc).__name__
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


@dataclass(frozen=True)
class Item:
    """One input of a batch: its ``name`` (the summary's ``record``), the ``source`` (a
    path or a Record) and, for identification with an output folder, the result file's
    ``target`` path."""

    name: str
    source: Any
    target: Path | None = None


def _display_name(path: Path) -> str:
    """A file name as text that can be printed and written (odd bytes as U+FFFD)."""
    return os.fsencode(path.name).decode("utf-8", "replace")


def items_of(sources: Iterable[Item | str | os.PathLike | Record], *,
             names: Sequence[str] | None = None) -> list[Item]:
    """Items of paths (named by file name) or records (named ``names[i]`` or
    ``record_<i>``, from 1); an :class:`Item` stays as it is."""
    out = []
    for i, src in enumerate(sources):
        if isinstance(src, Item):
            out.append(src)
            continue
        if names is not None:
            name = names[i]
        elif isinstance(src, Record):
            name = f"record_{i + 1}"
        else:
            name = _display_name(Path(src))
        out.append(Item(name=name, source=src if isinstance(src, Record) else Path(src)))
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class Outcome:
    """One item's result (see the module docstring).

    Attributes
    ----------
    index : int
        The item's place in the input.
    name : str
        The summary's ``record``.
    rows : tuple of SummaryRow
        One per vehicle (one ``"failed"`` row for a record that failed).
    event : EventWeighing or None
        :func:`weigh_events` with ``keep=True``.
    identification : ForceIdentification or None
        :func:`identify_records` with ``keep=True``.
    result : str or None
        The file written for the item (identification into an output folder).
    gauges : tuple of VehicleGauges
        :func:`weigh_events`: what the gauges of each judged vehicle did
        (:func:`bwim.batch.gauges.vehicle_gauges`; small, kept with ``keep=False`` too).
    """

    index: int
    name: str
    rows: tuple[SummaryRow, ...]
    event: Any = None
    identification: Any = None
    result: str | None = None
    gauges: tuple = ()

    @property
    def failed(self) -> bool:
        """True when the record could not be read or processed."""
        return self.rows[0].status == "failed"

    @property
    def reason(self) -> str:
        """Why the record failed ("" otherwise)."""
        return self.rows[0].reason if self.failed else ""


# --- the work of one item (top-level functions: they run in worker processes) --------------
@dataclass(frozen=True, eq=False)
class WeighJob:
    """What every worker of :func:`weigh_events` needs (sent once)."""

    calibration: Any
    read: Callable[[Path], Record] | None
    bridge: Any = None
    options: Mapping[str, Any] | None = None
    keep: bool = True


@dataclass(frozen=True, eq=False)
class IdentifyJob:
    """What every worker of :func:`identify_records` needs (sent once)."""

    bridge: Any
    read: Callable[[Path], Record] | None
    options: Mapping[str, Any] | None = None
    keep: bool = True


@dataclass(frozen=True, eq=False)
class StaticJob:
    """What every worker of :func:`weigh_records` needs (sent once)."""

    influence: Any
    read: Callable[[Path], Record] | None
    keep: bool = True


def _failure(item: Item, reason: str) -> Outcome:
    return Outcome(index=-1, name=item.name, rows=(failed_row(item.name, reason),))


def _is_failure(obj: Any) -> bool:
    return isinstance(obj, Outcome)


def _read(read: Callable[[Path], Record] | None, item: Item) -> Record | Outcome:
    """The item's record, or its failure outcome."""
    if isinstance(item.source, Record):
        return item.source
    if read is None:
        raise InputError("items given as paths need a reader (read=...)")
    try:
        return read(item.source)
    except BATCH_ERRORS as exc:
        return _failure(item, reason_of(exc))


def load_for_weighing(job_read: Callable[[Path], Record] | None, item: Item) -> Item | Outcome:
    """An item with its record read here (for executors whose workers cannot read it)."""
    rec = _read(job_read, item)
    return rec if isinstance(rec, Outcome) else Item(item.name, rec, item.target)


def weigh_item(job: WeighJob, item: Item) -> Outcome:
    """Weigh one item (see :func:`weigh_events`)."""
    from bwim.batch.gauges import vehicle_gauges
    from bwim.site import weigh_event

    rec = _read(job.read, item)
    if isinstance(rec, Outcome):
        return rec
    try:
        ev = weigh_event(rec, job.calibration, bridge=job.bridge,
                         identify_options=job.options)
        rows = ev.to_summary_rows(item.name)
        gauges = vehicle_gauges(rec, ev, job.calibration)
    except BATCH_ERRORS as exc:
        return _failure(item, reason_of(exc))
    return Outcome(index=-1, name=item.name, rows=rows, event=ev if job.keep else None,
                   gauges=gauges)


def identify_item(job: IdentifyJob, item: Item) -> Outcome:
    """Identify the forces of one item, writing its result file (see
    :func:`identify_records`)."""
    from bwim.mfi import identify_forces

    rec = _read(job.read, item)
    if isinstance(rec, Outcome):
        return rec
    try:
        ident = identify_forces(job.bridge, rec, **dict(job.options or {}))
        rows = ident.to_summary_rows(item.name)
    except BATCH_ERRORS as exc:
        return _failure(item, reason_of(exc))
    result = None
    if item.target is not None:
        from bwim.io import write_identification

        write_identification(ident, item.target)
        result = item.target.name
    return Outcome(index=-1, name=item.name, rows=rows, result=result,
                   identification=ident if job.keep else None)


def static_item(job: StaticJob, item: Item) -> Outcome:
    """Weigh one record that carries its passage by Moses' algorithm, writing its
    weights (see :func:`weigh_records`)."""
    from bwim.wim import weigh_static

    rec = _read(job.read, item)
    if isinstance(rec, Outcome):
        return rec
    try:
        w = weigh_static(rec, job.influence)
        row = w.to_summary_row(item.name)
    except BATCH_ERRORS as exc:
        return _failure(item, reason_of(exc))
    result = None
    if item.target is not None and row.weighed:
        from bwim.io import write_static_weights

        write_static_weights(w, item.target)
        result = item.target.name
    return Outcome(index=-1, name=item.name, rows=(row,), result=result,
                   event=w if job.keep else None)


# --- the iterators ----------------------------------------------------------------------
def _run(task: Task, items: list[Item], shared: Any, executor: Executor | None
         ) -> Iterator[Outcome]:
    for i, out in (executor or Serial()).map(task, items, shared):
        yield Outcome(index=i, name=out.name, rows=out.rows, event=out.event,
                      identification=out.identification, result=out.result,
                      gauges=out.gauges)


def weigh_events(items: Iterable[Item | str | os.PathLike | Record], calibration, *,
                 read: Callable[[Path], Record] | None = None, bridge=None,
                 identify_options: Mapping[str, Any] | None = None,
                 executor: Executor | None = None, keep: bool = True) -> Iterator[Outcome]:
    """Weigh every event (see the module docstring).

    Parameters
    ----------
    items : iterable of Item, path or Record
        The events: logger files (read with ``read``) or records.
    calibration : SiteCalibration
        The site's lines (:func:`bwim.site.calibrate_site`).
    read : callable, optional
        ``read(path) -> Record``, a top-level function or a ``functools.partial`` of one
        (it is sent to worker processes), e.g. ``partial(bwim.scenario.load_record,
        scenario=site_scenario)``.  Needed for paths.
    bridge : Bridge, optional
        Weigh by moving force identification with this calibrated model.
    identify_options : mapping, optional
        Options of :func:`bwim.identify_forces` (with ``bridge``).
    executor : Executor, optional
        Default: this process, in order.
    keep : bool
        Keep each event's :class:`~bwim.site.EventWeighing` on its outcome.

    Yields
    ------
    Outcome
    """
    job = WeighJob(calibration=calibration, read=read, bridge=bridge,
                   options=identify_options, keep=keep)
    task = Task(run=weigh_item, load=_loader(read), is_failure=_is_failure)
    yield from _run(task, items_of(items), job, executor)


def identify_records(items: Iterable[Item | str | os.PathLike | Record], bridge, *,
                     read: Callable[[Path], Record] | None = None,
                     options: Mapping[str, Any] | None = None,
                     executor: Executor | None = None, keep: bool = True
                     ) -> Iterator[Outcome]:
    """Identify the moving forces of every record (see the module docstring).

    ``items`` with a ``target`` path write their result there (HDF5,
    :func:`bwim.io.write_identification`).  Other parameters as :func:`weigh_events`;
    ``options`` are those of :func:`bwim.identify_forces`.
    """
    job = IdentifyJob(bridge=bridge, read=read, options=options, keep=keep)
    task = Task(run=identify_item, load=_loader(read), is_failure=_is_failure)
    yield from _run(task, items_of(items), job, executor)


def weigh_records(items: Iterable[Item | str | os.PathLike | Record], influence, *,
                  read: Callable[[Path], Record] | None = None,
                  executor: Executor | None = None, keep: bool = True) -> Iterator[Outcome]:
    """Weigh records that carry their passages (simulated ones, or a scenario's ``[run]``)
    by Moses' algorithm with one influence line (:func:`bwim.weigh_static`); items with a
    ``target`` path write their :class:`~bwim.StaticWeights` there when weighed.  The
    outcome's ``event`` is the StaticWeights (``keep=True``).  Other parameters as
    :func:`weigh_events`."""
    job = StaticJob(influence=influence, read=read, keep=keep)
    task = Task(run=static_item, load=_loader(read), is_failure=_is_failure)
    yield from _run(task, items_of(items), job, executor)


@dataclass(frozen=True)
class _Loader:
    read: Callable[[Path], Record] | None

    def __call__(self, item: Item) -> Item | Outcome:
        return load_for_weighing(self.read, item)


def _loader(read: Callable[[Path], Record] | None) -> _Loader:
    return _Loader(read)
