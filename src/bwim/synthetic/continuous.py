"""A continuous recording made of a simulated site's event files: one long logger file.

Contract
--------
:func:`make_continuous` takes the event files of one folder of a simulated site
(:func:`bwim.synthetic.make_site_days`: ``traffic/`` by default) in the order of the
clocks in their names and writes them one after another into a single logger file in the
same layout (the site's ``[logger] columns``, tab-separated, no header, the site's
sampling rate), with quiet gaps between them:

* ``time`` runs from 0 over the whole file (s, ``k / sampling_rate`` written with 9
  decimals); the clock is in the name, ``<name>_YYYY-MM-DD-HH-MM-SS-mmm.txt``: the first
  event file's clock less the lead gap, to the millisecond below.  The events are not at
  their own clock times (hours apart on the site): each one's clock in the long file is
  the file's clock plus its start (:class:`Placement`).
* Gauge and axle-detector channels run on one continuous baseline per channel: each
  event's samples less its own start level (the median of its first 0.25 s, before any
  axle is on the bridge), plus the baseline ``b_j(t) = L_j + r_j t`` (``L_j`` the first
  event's start level, ``r_j`` normal with σ ``drift`` noise σ per minute).  A gap goes
  linearly from the level where the event before it ended (its own baseline change over
  the event) to the baseline, plus Gaussian noise of the channel's σ (the median over the
  events of the standard deviation of their first 0.25 s).  The event samples themselves
  differ from their files by one constant per channel.
* A temperature channel keeps its values; a gap interpolates it linearly between the
  event before and the event after, plus its noise σ.  Status columns (``"-"``) keep the
  values of the first event's first row.
* Gaps are drawn uniformly in ``gap`` (s) before the first event, between events and
  after the last; every random draw comes from ``seed``.
* With ``reference``, the site's statically weighed vehicles of those events
  (``reference.csv``) are written there **by time**, as an operator would give them for
  a long recording whose events the trigger names (:func:`bwim.accuracy.assess`): each
  row's ``time`` moved to the long file's clock (its time less its file's clock, plus
  the file's place), ``record`` left out, the other columns as they are.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from bwim.errors import InputError
from bwim.io import name_timestamp
from bwim.io.atomic import atomic_open
from bwim.sensors import SensorKind

__all__ = ["ContinuousRecording", "Placement", "make_continuous"]

QUIET = 0.25  #: s at the start of an event file with no axle on the bridge (its level)
END = 0.1  #: s at the end of an event file whose median is where it ended


@dataclass(frozen=True, kw_only=True)
class Placement:
    """Where one event file lies in the long file."""

    source: Path  #: the event file
    start_index: int  #: its first sample's index in the long file
    n_samples: int
    start: float  #: record time of its first sample in the long file, s
    clock: datetime  #: clock time of its first sample in the long file
    original_clock: datetime  #: the clock in its own file name

    @property
    def stop_index(self) -> int:
        return self.start_index + self.n_samples


@dataclass(frozen=True, kw_only=True)
class ContinuousRecording:
    """What :func:`make_continuous` wrote."""

    path: Path
    clock: datetime  #: clock time of the first sample (in the name)
    sampling_rate: float
    n_samples: int
    placements: tuple[Placement, ...]
    reference: Path | None = None  #: the reference by time, when asked for

    @property
    def duration(self) -> float:
        return self.n_samples / self.sampling_rate


def _stamp(moment: datetime) -> str:
    return moment.strftime("%Y-%m-%d-%H-%M-%S-") + f"{moment.microsecond // 1000:03d}"


def make_continuous(site: str | os.PathLike, out_dir: str | os.PathLike, *,
                    folder: str = "traffic", gap: tuple[float, float] = (3.0, 8.0),
                    drift: float = 0.5, seed: int = 0, name: str = "continuous",
                    reference: str | os.PathLike | None = None) -> ContinuousRecording:
    """Write the event files of ``site/folder`` as one continuous logger file in
    ``out_dir`` (see the module docstring).

    Parameters
    ----------
    site : path
        A folder written by :func:`bwim.synthetic.make_site_days` (its ``scenario.toml``
        gives the columns and the sampling rate).
    out_dir : path
        Folder of the long file (created).
    folder : str
        The site's subfolder of event files.
    gap : (float, float)
        Range of the quiet gaps, s (0 < low <= high).
    drift : float
        σ of each channel's baseline slope, in its noise σ per minute (>= 0).
    seed : int
        Seed of the gaps, slopes and noise.
    name : str
        Start of the long file's name.
    reference : path, optional
        Where to write the site's reference of these events by time (a CSV file; not in
        ``out_dir``, whose files are the recordings).
    """
    from bwim.scenario import build_logger_format, load_scenario

    root = Path(site)
    if not (root / "scenario.toml").is_file():
        raise InputError(f"{root}: no scenario.toml (a folder of bwim.synthetic."
                         "make_site_days)")
    try:
        lo, hi = (float(g) for g in gap)
    except (TypeError, ValueError):
        raise InputError(f"gap must be two durations in s, got {gap!r}") from None
    if not 0 < lo <= hi:
        raise InputError(f"gap must satisfy 0 < low <= high s, got {gap!r}")
    if not isinstance(drift, (int, float)) or not 0 <= drift < 1e3:
        raise InputError(f"drift must be >= 0 noise σ per minute, got {drift!r}")
    if not isinstance(name, str) or not name or "/" in name:
        raise InputError(f"name must be a file-name start, got {name!r}")
    if reference is not None and Path(reference).resolve().parent == Path(out_dir).resolve():
        raise InputError(f"reference must not be in out_dir ({out_dir}): its files are read "
                         "as recordings")
    fmt = build_logger_format(load_scenario(root / "scenario.toml"))
    fs = fmt.sampling_rate
    files = []
    for p in sorted((root / folder).glob("*.txt")):
        stamp = name_timestamp(p.name)
        if stamp is not None:
            files.append((stamp.instant, p))
    if not files:
        raise InputError(f"{root / folder}: no event file with a clock in its name")
    files.sort()
    events = [np.loadtxt(p, delimiter="\t", ndmin=2) for _, p in files]
    columns = fmt.columns
    for (_, p), e in zip(files, events, strict=True):
        if e.shape[1] != len(columns) or e.shape[0] < round((QUIET + END) * fs):
            raise InputError(f"{p}: {e.shape[1]} columns and {e.shape[0]} rows; the site's "
                             f"columns are {list(columns)}")
    role = ["time" if c == "time" else "-" if c == "-" else
            "temperature" if fmt.kind_of(c) is SensorKind.TEMPERATURE else "level"
            for c in columns]
    level = np.array([r == "level" for r in role])
    temp = np.array([r == "temperature" for r in role])
    q, m = round(QUIET * fs), round(END * fs)
    starts = np.array([np.median(e[:q], axis=0) for e in events])
    ends = np.array([np.median(e[-m:], axis=0) for e in events])
    sigma = np.median([np.std(e[:q], axis=0) for e in events], axis=0)
    sigma[~(level | temp)] = 0.0
    rng = np.random.default_rng(seed)
    rate = np.where(level, drift * sigma / 60.0 * rng.standard_normal(len(columns)), 0.0)
    base0 = starts[0]
    status = events[0][0]
    gaps = [round(rng.uniform(lo, hi) * fs) for _ in range(len(events) + 1)]
    clock = files[0][0] - timedelta(seconds=gaps[0] / fs)
    clock = clock.replace(microsecond=clock.microsecond // 1000 * 1000)
    fmts = ["%.9f" if r == "time" else "%d" if r == "-" else
            "%.2f" if r == "temperature" else "%.3f" for r in role]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}_{_stamp(clock)}.txt"
    placements = []
    k = 0

    def block(n: int, values: np.ndarray, f) -> None:
        nonlocal k
        t = (k + np.arange(n)) / fs
        if "time" in role:
            values[:, role.index("time")] = t
        for j, r in enumerate(role):
            if r == "-":
                values[:, j] = status[j]
        np.savetxt(f, values, fmt=fmts, delimiter="\t", newline="\n")
        k += n

    with atomic_open(path, newline="") as f:
        for i in range(len(events) + 1):
            n = gaps[i]
            t = (k + np.arange(n)) / fs
            u = (np.arange(n) + 1.0) / (n + 1.0)
            values = base0 + np.outer(t, rate) + rng.standard_normal((n, len(columns))) * sigma
            if i > 0:  # from where the event before ended
                values[:, level] += np.outer(1.0 - u, (ends[i - 1] - starts[i - 1])[level])
            prev_t = ends[i - 1] if i > 0 else starts[i]
            next_t = starts[i] if i < len(events) else ends[i - 1]
            values[:, temp] = (np.outer(1.0 - u, prev_t) + np.outer(u, next_t))[:, temp] \
                + rng.standard_normal((n, int(temp.sum()))) * sigma[temp]
            block(n, values, f)
            if i == len(events):
                break
            e = events[i]
            t = (k + np.arange(e.shape[0])) / fs
            values = e.copy()
            values[:, level] += (base0 - starts[i] + np.outer(t, rate))[:, level]
            placements.append(Placement(
                source=files[i][1], start_index=k, n_samples=e.shape[0], start=k / fs,
                clock=clock + timedelta(seconds=k / fs), original_clock=files[i][0]))
            block(e.shape[0], values, f)
    ref = None if reference is None else _reference_by_time(root, Path(reference),
                                                            placements)
    return ContinuousRecording(path=path, clock=clock, sampling_rate=fs, n_samples=k,
                               placements=tuple(placements), reference=ref)


def _reference_by_time(root: Path, target: Path, placements: list[Placement]) -> Path:
    """The site's reference rows of the placed events, by their time in the long file."""
    import csv

    source = root / "reference.csv"
    with open(source, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    if rows and "time" not in rows[0]:
        raise InputError(f"{source}: no time column: the reference cannot be given by time")
    where = {p.source.name: p for p in placements}
    columns = [c for c in (rows[0] if rows else ()) if c != "record"]
    with atomic_open(target, newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            p = where.get(r["record"])
            if p is None:
                continue
            t = p.clock + (datetime.fromisoformat(r["time"]) - p.original_clock)
            w.writerow([t.isoformat(timespec="microseconds") if c == "time" else r[c]
                        for c in columns])
    return target
