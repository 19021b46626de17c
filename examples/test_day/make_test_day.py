"""Write a simulated B-WIM test day to a folder (see README.md beside this script).

Run: ``python examples/test_day/make_test_day.py OUT_DIR [--seed N] [--small] [--wim-grade]``
"""

import argparse
import time

from bwim.synthetic import make_test_day
from bwim.synthetic.testday import WIM_GRADE_ROUGHNESS


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", help="new (or empty) folder to write the day to")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--small", action="store_true",
                        help="4 calibration runs, 8 traffic events, 0.5 m data mesh")
    parser.add_argument("--wim-grade", action="store_true",
                        help="roads within ISO 8608 class A (a smooth WIM approach) instead "
                        "of class A to B")
    args = parser.parse_args(argv)
    kw = {"n_calibration": 4, "n_traffic": 8, "mesh": 0.5} if args.small else {}
    if args.wim_grade:
        kw["roughness"] = WIM_GRADE_ROUGHNESS
    t0 = time.perf_counter()
    day = make_test_day(args.out_dir, seed=args.seed, **kw)
    elapsed = time.perf_counter() - t0
    n_multi = sum(e.n_vehicles > 1 for e in day.events)
    print(f"wrote {day.out_dir} in {elapsed:.1f} s: {len(day.calibration)} calibration runs, "
          f"{len(day.traffic)} traffic events ({n_multi} with two trucks)")
    print(f"gauge noise sigma {day.noise_sigma / 1e-6:.3f} microstrain "
          f"(2 % of {day.reference_strain / 1e-6:.2f}); strain factor "
          f"{min(e.strain_factor for e in day.events):.3f} ... "
          f"{max(e.strain_factor for e in day.events):.3f}")
    print(f"weigh it: bwim weigh {day.scenario} {day.out_dir}/traffic/*.txt "
          f"--calibration-records {day.out_dir}/calibration/*.txt -o OUT")


if __name__ == "__main__":
    main()
