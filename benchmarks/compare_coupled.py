"""The coupled paper crossing timed across bwim versions, interleaved (issue 15).

Each argument is a directory holding a ``src/bwim`` tree (e.g. an old commit's
``git archive <commit> src | tar -x -C /tmp/old``).  Every round runs each version in a
fresh subprocess (median of 7 crossings after a warm-up), round-robin, so that the load
of a shared machine falls on all versions alike; the per-round times are printed as well
as the medians, with the largest relative difference of the readings and wheel forces
against the second version (the reference, e.g. main).

    python -m benchmarks.compare_coupled /tmp/old /work/main .
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

_CODE = r'''
import json, time, numpy as np
from bwim import paper
from bwim.dynamics import simulate
b, s, t = paper.slab_bridge(), paper.sensors(), paper.truck()
road = paper.road(1, approach=paper.APPROACH)
def go():
    return simulate(b, t, speed=paper.SPEED, lane=paper.LANE, sensors=s, road=road,
                    method="coupled", approach=paper.APPROACH)
rec = go()
ts = []
for _ in range(7):
    t0 = time.perf_counter(); go(); ts.append(time.perf_counter() - t0)
np.savez(OUT, d=rec.data, f=rec.truth.wheel_forces)
print(json.dumps(sorted(ts)[3]))
'''


def main(trees: list[str], rounds: int = 5) -> None:
    tmp = tempfile.mkdtemp()
    outs = [os.path.join(tmp, f"out{i}.npz") for i in range(len(trees))]
    times: list[list[float]] = [[] for _ in trees]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    for _ in range(rounds):
        for i, tree in enumerate(trees):
            env["PYTHONPATH"] = os.path.join(tree, "src")
            run = subprocess.run([sys.executable, "-c", _CODE.replace("OUT", repr(outs[i]))],
                                 env=env, capture_output=True, text=True, check=True)
            times[i].append(json.loads(run.stdout))
    ref = np.load(outs[1] if len(trees) > 1 else outs[0])
    base = statistics.median(times[0])
    for i, tree in enumerate(trees):
        x = np.load(outs[i])
        rel = [np.abs(x[k] - ref[k]).max() / np.abs(ref[k]).max() for k in ("d", "f")]
        med = statistics.median(times[i])
        ratios = " ".join(f"{a / b:.2f}" for a, b in zip(times[0], times[i], strict=True))
        print(f"{tree}: median {1e3 * med:.1f} ms, rounds "
              f"{[round(1e3 * v, 1) for v in times[i]]}, speed-up vs first {base / med:.2f}x "
              f"(per round {ratios}); max rel. diff. vs 2nd: readings {rel[0]:.1e}, "
              f"forces {rel[1]:.1e}")


if __name__ == "__main__":
    main(sys.argv[1:])
