"""Write a simulated B-WIM test day to a folder (see README.md beside this script).

Run: ``python examples/test_day/make_test_day.py OUT_DIR [--site NAME] [--seed N] [--small]
[--wim-grade] [--n-traffic N] [--temperature] [--continuous]``

Progress goes to stderr (a line every few seconds: events done / total, elapsed, ETA).
"""

import argparse
import sys
import time

from bwim.synthetic import SITE_NAMES, make_continuous, make_test_day
from bwim.synthetic.testday import WIM_GRADE_ROUGHNESS

SMALL = {
    "basic-2-lane": {"n_calibration": 4, "n_traffic": 8, "mesh": 0.5},
    "short-span-4-lane": {"n_calibration": 6, "n_traffic": 12,
                          "n_calibration_day_traffic": 4, "mesh": 0.5},
}


class Progress:
    """Prints ``done/total, elapsed, ETA`` to stderr at most every ``every`` seconds."""

    def __init__(self, every: float = 5.0) -> None:
        self.every = every
        self.t0 = time.perf_counter()
        self.last = self.t0

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if now - self.last < self.every and done < total:
            return
        self.last = now
        elapsed = now - self.t0
        eta = elapsed / done * (total - done)
        print(f"event {done}/{total}  {elapsed:.0f} s elapsed  ETA {eta:.0f} s",
              file=sys.stderr, flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", help="new (or empty) folder to write the day to")
    parser.add_argument("--site", choices=SITE_NAMES, default=SITE_NAMES[0],
                        help="site preset (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--small", action="store_true",
                        help="a few events on a 0.5 m data mesh (seconds)")
    parser.add_argument("--wim-grade", action="store_true",
                        help="roads within ISO 8608 class A (a smooth WIM approach) instead "
                        "of class A to B (basic-2-lane; short-span-4-lane's roads are "
                        "that grade already)")
    parser.add_argument("--n-traffic", type=int, default=None,
                        help="traffic events (of the traffic date for short-span-4-lane)")
    parser.add_argument("--temperature", action="store_true",
                        help="write a deck-temperature column temp_C (short-span-4-lane)")
    parser.add_argument("--continuous", action="store_true",
                        help="also the traffic as one continuous recording in OUT_DIR/long, "
                        "and its reference by time, OUT_DIR/reference_by_time.csv "
                        "(short-span-4-lane)")
    args = parser.parse_args(argv)
    kw = dict(SMALL[args.site]) if args.small else {}
    if args.wim_grade:
        kw["roughness"] = WIM_GRADE_ROUGHNESS
    if args.n_traffic is not None:
        kw["n_traffic"] = args.n_traffic
    if args.temperature:
        kw["temperature_channel"] = True
    t0 = time.perf_counter()
    day = make_test_day(args.out_dir, site=args.site, seed=args.seed, progress=Progress(),
                        **kw)
    elapsed = time.perf_counter() - t0
    n_multi = sum(e.n_vehicles > 1 for e in day.events)
    factors = [e.strain_factor for e in day.events]
    print(f"wrote {day.out_dir} ({args.site}) in {elapsed:.1f} s "
          f"({elapsed / len(day.events):.3f} s per event): {len(day.calibration)} calibration "
          f"runs, {len(day.traffic)} traffic events, {n_multi} events with two vehicles")
    if hasattr(day, "calibration_day_traffic"):
        print(f"calibration date {day.calibration_date}: {len(day.calibration_day_traffic)} "
              f"traffic events beside the runs; traffic date {day.traffic_date}")
    print(f"gauge noise sigma {day.noise_sigma / 1e-6:.3f} microstrain "
          f"({day.noise_sigma / day.reference_strain:.0%} of "
          f"{day.reference_strain / 1e-6:.2f}); strain factor {min(factors):.3f} ... "
          f"{max(factors):.3f}")
    print(f"weigh it: bwim weigh {day.scenario} {day.out_dir}/traffic/*.txt "
          f"--calibration-records {day.out_dir}/calibration/*.txt -o OUT")
    if args.continuous:
        long = make_continuous(day.out_dir, day.out_dir / "long",
                               reference=day.out_dir / "reference_by_time.csv")
        print(f"continuous: {long.path} ({long.duration:.0f} s, {len(long.placements)} "
              f"events), reference by time {long.reference}; weigh it with --continuous")


if __name__ == "__main__":
    main()
