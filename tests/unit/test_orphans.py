"""The calibration's worker processes end with the process that started them (issue 22:
after ``kill -9`` of a parallel run its workers went on computing for minutes).
``bwim.optimize.parallel.evaluate(n_jobs=2)`` is the calibration's population pool."""

import os
import subprocess
import sys
import time

import pytest

_CHILD = """
import os, sys, time
from pathlib import Path
import numpy as np
from bwim.optimize.parallel import evaluate

def slow(x):
    (Path(sys.argv[1]) / f"{os.getpid()}.pid").write_text("")
    time.sleep(120)
    return float(x.sum())

if __name__ == "__main__":
    (Path(sys.argv[1]) / f"{os.getpid()}.pid").write_text("")
    evaluate(slow, np.ones((2, 2)), n_jobs=2)
"""


def test_evaluate_workers_die_with_their_parent(tmp_path):
    psutil = pytest.importorskip("psutil")
    script = tmp_path / "child.py"
    script.write_text(_CHILD)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, str(script), str(tmp_path)], env=env)
    try:
        deadline = time.time() + 60
        while time.time() < deadline and len(list(tmp_path.glob("*.pid"))) < 3:
            time.sleep(0.1)
        pids = {int(p.stem) for p in tmp_path.glob("*.pid")}
        workers = pids - {proc.pid}
        assert proc.pid in pids and len(workers) == 2, pids
        proc.kill()
        proc.wait()
        deadline = time.time() + 5
        alive = set(workers)
        while alive and time.time() < deadline:
            for pid in list(alive):
                try:
                    if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                        alive.discard(pid)
                except psutil.NoSuchProcess:
                    alive.discard(pid)
            time.sleep(0.1)
        for pid in alive:
            psutil.Process(pid).kill()
        assert not alive, f"{len(alive)} worker(s) outlived their parent by 5 s"
    finally:
        if proc.poll() is None:
            proc.kill()
