"""Batch scaling of ``bwim identify`` (issue 15): vehicles per second on 1 and 2 local
processes (``--jobs``) and on a dask ``LocalCluster`` of 1, 2 and 4 worker processes
(``--scheduler``), the speed-ups, and the wall time of a day of 10,000 trucks on 2 cores
projected from the measured time per vehicle (as loaded, and on free cores from the CPU
time).

The batch: 20 records (60 for a second, local-only table) of the paper slab
(examples/paper_slab.toml, 10 m approach), 2- and 3-axle trucks at 15–23 m/s over 20 road
seeds, 1 kHz, about 1 s each, written by ``bwim simulate`` into a temporary folder. Each
configuration runs the whole command (``main([...])``: reading, identification, writing
every result, summary and manifest) with ``--force``; the configurations are interleaved
over the repeats and the median is shown, with the 1-minute load average before each run
(the machine is shared: a load above the cores in use slows the parallel runs first). So
each run's CPU time is also measured (this process and every process under it): the
CPU-bound speed-up, ``min(processes, cores) × CPU(1) / CPU(n)``, is what free cores would
give, short of the wait for the last record (at most one record's time); local runs only
(the CPU of dask's workers is not all seen from here). A dask cluster is started for each
of its runs (and its workers have imported bwim) before the clock starts; its start-up is
shown apart. Targets: ``--jobs 2`` ≥ 1.7× ``--jobs 1`` on two free cores; a day in ≤ 1 h
on 2 cores.
"""

from __future__ import annotations

import contextlib
import io
import os
import statistics
import tempfile
import time
from pathlib import Path

from benchmarks._timing import print_table
from bwim.cli import main as bwim_main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_slab.toml"
N_RECORDS = 20
DAY = 10_000  #: trucks in the projected day


def _quiet(argv) -> int:
    with contextlib.redirect_stdout(io.StringIO()):
        return bwim_main([str(a) for a in argv])


def make_records(folder: Path, n: int = N_RECORDS) -> tuple[Path, Path]:
    """``n`` simulated records in ``folder/records`` and the scenario that reads them."""
    recs = folder / "records"
    recs.mkdir()
    text = EXAMPLE.read_text(encoding="utf-8").replace("approach = 100.0", "approach = 10.0")
    scenario = folder / "scenario.toml"
    for k in range(n):
        t = text.replace("speed = 20.0", f"speed = {15.0 + 2.0 * (k % 5)}")
        t = t.replace("seed = 1", f"seed = {k + 1}")
        if k % 2:
            t = t.replace('"two_axle_truck"', '"three_axle_truck"')
        path = folder / f"s{k:02d}.toml"
        path.write_text(t, encoding="utf-8")
        if k == 0:
            scenario.write_text(t, encoding="utf-8")
        assert _quiet(["simulate", path, "-o", recs / f"r{k:02d}.h5"]) == 0
    return scenario, recs


def _cpu() -> float:
    """CPU seconds of this process and every process under it (workers, dask nannies)."""
    import psutil

    me = psutil.Process()
    total = 0.0
    for p in [me, *me.children(recursive=True)]:
        with contextlib.suppress(psutil.Error):
            t = p.cpu_times()
            total += t.user + t.system
    return total


def _timed(argv) -> tuple[float, float, float]:
    """Wall time, CPU time (all processes) and the load average before the run."""
    load = os.getloadavg()[0]
    c0, t0 = _cpu(), time.perf_counter()
    assert _quiet(argv) == 0
    return time.perf_counter() - t0, _cpu() - c0, load


def _start_cluster(n_workers: int):
    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    with Client(cluster) as client:
        client.run(__import__, "bwim.cli")
    return cluster, time.perf_counter() - t0


def run(repeat: int = 3, workers=(1, 2, 4), n_records: int = N_RECORDS) -> list[list]:
    """Rows: configuration, median wall (s), vehicles/s, speed-up, load averages."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        scenario, recs = make_records(folder, n_records)
        base = ["identify", scenario, recs, "--force"]
        configs = {f"--jobs {j}": [*base, "-o", folder / f"jobs{j}", "--jobs", j]
                   for j in (1, 2)}
        for w in workers:
            configs[f"dask, {w} worker{'s' if w > 1 else ''}"] = [
                *base, "-o", folder / f"dask{w}", "--scheduler", w]
        _quiet(configs["--jobs 2"])  # warm: this process's imports, loky workers
        samples: dict[str, list[tuple[float, float, float]]] = {k: [] for k in configs}
        start: dict[int, list[float]] = {w: [] for w in workers}
        for _ in range(repeat):
            for name, argv in configs.items():
                if "--scheduler" not in argv:
                    samples[name].append(_timed(argv))
                    continue
                w = argv[-1]  # a cluster per run: no idle cluster loads the other runs
                cluster, t = _start_cluster(w)
                start[w].append(t)
                try:
                    samples[name].append(_timed([*argv[:-1], cluster.scheduler_address]))
                finally:
                    cluster.close()
    rows = []
    med = {k: (statistics.median(w for w, _, _ in s), statistics.median(c for _, c, _ in s))
           for k, s in samples.items()}
    t1, c1 = med["--jobs 1"]
    d1, e1 = med.get(next((k for k in samples if "dask" in k), None), (t1, c1))
    cores = os.cpu_count() or 1
    for name, s in samples.items():
        wall, cpu = med[name]
        n = next((w for w in workers if name.startswith(f"dask, {w} ")), None)
        ref, cref = (d1, e1) if n else (t1, c1)
        procs = n if n else int(name.split()[-1])
        rows.append([name, f"{wall:.2f}", f"{n_records / wall:.2f}", f"{ref / wall:.2f}×",
                     *(["", ""] if n else  # dask's worker CPU is not all seen here
                       [f"{cpu / n_records:.3f}", f"{min(procs, cores) * cref / cpu:.2f}×"]),
                     " ".join(f"{ld:.1f}" for _, _, ld in s),
                     f"{statistics.median(start[n]):.1f}" if n else ""])
    per_vehicle = med["--jobs 2"][0] / n_records
    free = med["--jobs 2"][1] / n_records / min(2, cores)
    rows.append([f"day of {DAY:,} trucks, --jobs 2", f"{DAY * per_vehicle:.0f}",
                 f"{1 / per_vehicle:.2f}", f"{DAY * per_vehicle / 3600:.2f} h",
                 f"free: {DAY * free / 3600:.2f} h", "", "", ""])
    return rows


def main() -> None:
    columns = ["run", "wall (s)", "vehicles/s", "speed-up", "CPU s/vehicle",
               "CPU-bound speed-up", "load avg before runs", "cluster start (s)"]
    for n, workers in ((N_RECORDS, (1, 2, 4)), (3 * N_RECORDS, ())):
        print_table(f"bwim identify, {n} records of 1 s at 1 kHz (paper slab), on "
                    f"{os.cpu_count()} cores: median of 3 interleaved runs; speed-up against "
                    "--jobs 1" + (" (dask: against 1 worker)" if workers else "")
                    + "; target --jobs 2 ≥ 1.7× on two free cores, a day ≤ 1 h (the workers' "
                    "start-up, about 1 s, weighs less in a longer batch)",
                    columns, run(workers=workers, n_records=n))


if __name__ == "__main__":
    main()
