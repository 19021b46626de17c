"""Run every benchmark and print its tables: ``make bench``."""

from __future__ import annotations

import os
import sys
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks import (  # noqa: E402
    bench_axle_shares,
    bench_batch,
    bench_calibration,
    bench_declarations,
    bench_detect_site,
    bench_drift,
    bench_faults,
    bench_fe,
    bench_logger,
    bench_mfi,
    bench_mfi_static,
    bench_mismatch,
    bench_multirun,
    bench_optimize,
    bench_realsite,
    bench_site,
    bench_site_model,
    bench_speed_budget,
    bench_stream,
    bench_testday,
    bench_vbi,
    bench_wim,
)


def main() -> None:
    print(f"bwim benchmarks on {os.cpu_count()} cores, one BLAS thread")
    bench_fe.main()
    bench_vbi.main()
    bench_mfi.main()
    bench_mfi_static.main()
    bench_batch.main()
    bench_wim.main()
    bench_multirun.main()
    bench_optimize.main()
    bench_calibration.main()
    bench_testday.main()
    bench_logger.main([])
    bench_site.main()
    bench_mismatch.main()
    bench_detect_site.main([])
    bench_stream.main([])
    bench_realsite.main()
    bench_speed_budget.main([])
    bench_drift.main()
    bench_axle_shares.main([])
    bench_faults.main()
    bench_declarations.main()
    bench_site_model.main([])


if __name__ == "__main__":
    main()
