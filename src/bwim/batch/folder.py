"""A batch into an output folder: the summary, the manifest and the one resume rule.

Contract
--------
* :class:`BatchFolder` keeps a batch's results in its folder: ``manifest.json`` (per
  input file, keyed by its path, size and modification time: its summary rows or why it
  failed, and the result file written for it; :class:`bwim.io.outputs.Manifest`) and
  ``summary.csv`` (:mod:`bwim.io.summary`) rewritten from it, both atomically, at most
  every :attr:`BatchFolder.save_every` seconds (or 20 times the last save's duration)
  and when the batch ends, also on an interrupt.  With a day-level ``finalize`` the
  periodic saves write the manifest only: the summary is written when the batch ends,
  through ``finalize``, and never holds rows that it has not judged (an interrupt
  during ``finalize``, or a killed process, leaves the summary of the last whole run, or
  none; ``--resume`` goes on from the manifest).
* **Names**: the summary names each input by its item's name; an input whose name is
  already the record of another file's rows in the folder (a resume given a copy from
  another folder) is refused (:class:`~bwim.errors.InputError`, nothing processed): the
  summary would hold two rows of one record.
* **The resume rule** (both commands): with ``resume``, an input is skipped when the
  manifest holds it unchanged, its rows are not ``"failed"`` and its result file (if any)
  still exists; every other input is processed again, so a failed record is retried
  once it is repaired.  The rows of inputs that a rerun does not name again are kept
  (the summary lists the inputs given, in order, then the others by file name): a resume
  never loses a row.  A folder that holds another batch (another scenario, calibration or
  model: the manifest's ``meta``) is refused.  Without ``resume`` (or with it but no
  manifest in the folder: nothing to resume), an existing summary or manifest is refused
  unless ``force`` (then the batch starts afresh).
* **Gauge health** (``gauge_table``, a path, set by the caller once the calibration is
  known, with ``gauge_names``, the calibration's gauges): the manifest keeps, per input,
  what each of its judged vehicles' gauges did (:class:`bwim.batch.gauges.VehicleGauges`,
  an outcome's ``gauges``), and the final save writes the day's table over every input
  the folder holds (resumed ones included) to ``gauge_table`` atomically
  (:func:`bwim.io.gauge_health.write_gauge_health`).  Whether it may be replaced is the
  caller's to check, as for the other outputs of the command.
* :func:`run_into` drains an iterator of :class:`~bwim.batch.events.Outcome` into a
  folder with a progress callback and returns a :class:`BatchReport`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bwim.batch.events import Item, Outcome
from bwim.batch.gauges import VehicleGauges, tally_gauges
from bwim.errors import InputError
from bwim.io.gauge_health import write_gauge_health
from bwim.io.outputs import MANIFEST_NAME, Manifest, file_key, refuse_existing
from bwim.io.summary import from_cells, to_cells, write_summary
from bwim.io.summary_parquet import require_pyarrow, write_summary_parquet
from bwim.summary import SummaryRow

__all__ = ["BatchFolder", "BatchReport", "run_into"]


class BatchFolder:
    """A batch's summary and manifest in ``folder`` (see the module docstring).

    Parameters
    ----------
    folder : path
        The output folder (it exists).
    meta : mapping
        What the batch is (plain JSON values): a resumed folder must hold the same.
    resume : bool
        Keep what an earlier run of the same batch did (the resume rule).
    force : bool
        Without ``resume``: start afresh over existing outputs.
    summary : path, optional
        The summary file (default ``folder/summary.csv``).
    finalize : callable, optional
        ``finalize(rows) -> rows``: a day-level step applied to every row before the
        summary is written (e.g. the traffic's own drift correction,
        :func:`bwim.site.correct_drift`); the manifest keeps the rows as they came.
    parquet : bool
        Also write the final summary as ``summary.parquet`` beside it
        (:mod:`bwim.io.summary_parquet`; refused like the summary when it exists).  A
        resume of a batch that wrote one keeps it up to date without being asked (a stale
        Parquet summary beside the CSV one would disagree with it); a fresh start refuses
        an existing one without ``force``, with it deletes it when not writing one.
    """

    save_every = 1.0

    def __init__(self, folder: str | Path, *, meta: dict[str, Any], resume: bool,
                 force: bool, summary: str | Path | None = None,
                 finalize: Callable[[list[SummaryRow]], list[SummaryRow]] | None = None,
                 parquet: bool = False) -> None:
        self.folder = Path(folder)
        self.summary = Path(summary) if summary is not None else self.folder / "summary.csv"
        earlier = (resume and (self.folder / MANIFEST_NAME).exists()
                   and self.summary.with_suffix(".parquet").exists())
        self.parquet = self.summary.with_suffix(".parquet") if parquet or earlier else None
        if self.parquet is not None:
            require_pyarrow()
        if not resume or not (self.folder / MANIFEST_NAME).exists():
            # nothing to resume: an existing summary is another run's (no manifest of it)
            refuse_existing(self.summary, force=force)
            refuse_existing(self.folder / MANIFEST_NAME, force=force)
            old = refuse_existing(self.summary.with_suffix(".parquet"), force=force)
            if self.parquet is None and (old.exists() or old.is_symlink()):
                old.unlink()  # (--force) another run's: it would disagree with the summary
        self.manifest = Manifest(self.folder, fresh=not resume)
        if resume and self.manifest.entries and self.manifest.meta != meta:
            raise InputError(f"{self.folder} holds the results of another batch (another "
                             "scenario, calibration or model); resume it with the same "
                             "inputs, or use another folder (or --force without --resume)")
        self.manifest.meta = dict(meta)
        self.finalize = finalize
        self.gauge_table: Path | None = None
        self.gauge_names: tuple[str, ...] = ()
        self._order: list[Path] = []
        self._last = time.perf_counter()
        self._cost = 0.0

    def done(self, source: Path) -> tuple[SummaryRow, ...] | None:
        """The rows of an input that the resume rule skips, or None (process it)."""
        entry = self.manifest.done(source)
        if entry is None:
            return None
        rows = tuple(from_cells(c) for c in entry["rows"])
        return rows or None

    def forget(self, sources: Sequence[Path]) -> None:
        """Drop what the manifest holds of these inputs (files that no longer exist: a
        long recording's events that a new cut of it does not hold); their rows go."""
        gone = {str(Path(p).resolve()) for p in sources}
        for key in [k for k, e in self.manifest.entries.items()
                    if str(Path(e["source"]).resolve()) in gone]:
            del self.manifest.entries[key]

    def check_names(self, items: Sequence[Item]) -> None:
        """Refuse an item whose name is already the record of another input's rows in
        the folder (see the module docstring)."""
        owner: dict[str, str] = {}
        for entry in self.manifest.entries.values():
            for cells in entry["rows"]:
                owner.setdefault(cells["record"], entry["source"])
        for it in items:
            other = owner.get(it.name)
            if other is not None and not _same_file(other, it.source):
                raise InputError(f"{it.source}: the summary in {self.folder} already holds "
                                 f"record {it.name!r} from {other}: rename one, or weigh "
                                 "it into another folder")

    def order(self, sources: Sequence[Path]) -> None:
        """The inputs of this run, in the summary's order."""
        self._order = [Path(p) for p in sources]

    def add(self, source: Path, outcome: Outcome) -> None:
        """Note an input's outcome (saved with the next save)."""
        self.manifest.record(source, result=outcome.result,
                             rows=[to_cells(r) for r in outcome.rows],
                             error=outcome.reason or None, save=False)
        if outcome.gauges:
            self.manifest.entries[file_key(source)]["gauges"] = [
                g.to_json() for g in outcome.gauges]
        self.maybe_save()

    def vehicle_gauges(self) -> list[VehicleGauges]:
        """What the judged vehicles' gauges did, over every input the folder holds."""
        return [VehicleGauges.from_json(g) for entry in self.manifest.entries.values()
                for g in entry.get("gauges", ())]

    def rows(self) -> list[SummaryRow]:
        """Every row the folder holds: the inputs of this run in order, then the others;
        through ``finalize`` when given."""
        out = self.raw_rows()
        return out if self.finalize is None else list(self.finalize(out))

    def raw_rows(self) -> list[SummaryRow]:
        """Every row as its input's processing gave it (the manifest's)."""
        by_source: dict[str, dict[str, Any]] = {}
        for entry in self.manifest.entries.values():
            by_source[str(Path(entry["source"]).resolve())] = entry
        out: list[SummaryRow] = []
        for p in self._order:
            entry = by_source.pop(str(p.resolve()), None)
            if entry is not None:
                out.extend(from_cells(c) for c in entry["rows"])
        for key in sorted(by_source):
            out.extend(from_cells(c) for c in by_source[key]["rows"])
        return out

    def save(self, final: bool = False) -> None:
        """Rewrite the manifest and the summary (atomically); a day-level ``finalize``
        runs on the final save only (it needs every row)."""
        t = time.perf_counter()
        self.manifest.save()
        if not final and self.finalize is not None:  # rows not yet judged by the day
            self._last = time.perf_counter()
            self._cost = self._last - t
            return
        rows = self.rows() if final else self.raw_rows()
        write_summary(self.summary, rows)
        if final and self.parquet is not None:
            write_summary_parquet(self.parquet, rows)
        if final and self.gauge_table is not None:
            write_gauge_health(self.gauge_table, [
                t.as_row() for t in tally_gauges(self.gauge_names, self.vehicle_gauges())])
        self._last = time.perf_counter()
        self._cost = self._last - t

    def maybe_save(self) -> None:
        if time.perf_counter() - self._last >= max(self.save_every, 20 * self._cost):
            self.save()


def _same_file(a: str | Path, b: str | Path) -> bool:
    return Path(a).resolve() == Path(b).resolve()


@dataclass(frozen=True, kw_only=True)
class BatchReport:
    """What a batch did.

    Attributes
    ----------
    n_inputs : int
    n_done_before : int
        Inputs skipped by the resume rule.
    rows : tuple of SummaryRow
        The summary's rows, in its order.
    failures : tuple of (str, str)
        ``(record, reason)`` of every input that failed in this run.
    elapsed : float
        Wall time of this run, s.
    """

    n_inputs: int
    n_done_before: int
    rows: tuple[SummaryRow, ...]
    failures: tuple[tuple[str, str], ...]
    elapsed: float

    def count(self, status: str) -> int:
        """Rows of a status (``"weighed"``, ``"refused"``, ``"failed"``)."""
        return sum(1 for r in self.rows if r.status == status)


def run_into(folder: BatchFolder, items: Sequence[Item],
             run: Callable[[list[Item]], Iterable[Outcome]], *,
             progress: Callable[[int], None] | None = None) -> BatchReport:
    """Process ``items`` (file paths as their ``source``) into ``folder``.

    ``run(todo)`` yields the outcomes of the items left by the resume rule (e.g. a
    partial of :func:`~bwim.batch.weigh_events`); ``progress(n)`` is called with the
    number of items finished so far (skipped ones included).
    """
    t0 = time.perf_counter()
    sources = [Path(it.source) for it in items]
    folder.check_names(items)
    folder.order(sources)
    todo = [it for it, src in zip(items, sources, strict=True) if folder.done(src) is None]
    skipped = len(items) - len(todo)
    failures: list[tuple[str, str]] = []
    finished = skipped
    if progress is not None:
        progress(finished)
    try:
        for out in run(todo):
            folder.add(Path(todo[out.index].source), out)
            if out.failed:
                failures.append((out.name, out.reason))
            finished += 1
            if progress is not None:
                progress(finished)
    finally:  # an interrupted run keeps what it finished (rerun with --resume)
        folder.save(final=True)
    return BatchReport(n_inputs=len(items), n_done_before=skipped, rows=tuple(folder.rows()),
                       failures=tuple(failures), elapsed=time.perf_counter() - t0)
