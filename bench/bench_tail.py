#!/usr/bin/python3
"""The end of a campaign, driver against driver: what rank 0 does after the last run (the last
chunks, /stats with the columns read back, the method's results, the file's commit), measured
side by side (not a test; see docs/benchmarks.md, "The end of a sweep").

Runs each driver on the same campaign, interleaved (A B C, A B C, ...) so that machine noise hits
all alike, REPEATS times each, and prints medians of: the whole mpirun command's wall time, the
tail's wall and CPU time as the driver prints them ("statistics and file: W s, C s CPU") and the
columns /stats read back (/timing stats_columns_read_back). Checks that every driver writes the
same values (scripts/compare_campaign_h5.py on each file against the first driver's): a faster
tail that changes a number is not one.

  bench/bench_tail.py --driver NAME=PATH [--driver NAME=PATH ...] [--campaign C] [--ranks 2]
                      [--repeats 5] [--set KEY=VALUE ...]

The default: the motor-sizing sweep by subset simulation at each value (8 stall torques, refine 3,
2,000 samples a level: 89,800 runs), whose chains drift with the run index, so /stats reads columns
back and each value's subset simulation reads its failure samples' inputs.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import h5py

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
SWEEP = ["ensemble.method=subset", "ensemble.importance=false", "sweep.from=0.028", "sweep.to=0.036",
         "sweep.count=5", "sweep.refine=3", "ensemble.subset.max_levels=9", "ensemble.subset.n_per_level=2000"]
TAIL = re.compile(r"statistics and file: ([0-9.e+-]+) s, ([0-9.e+-]+) s CPU")


def run(driver, args, out):
    if os.path.exists(out):
        os.remove(out)
    cmd = ["mpirun", "--oversubscribe", "-np", str(args.ranks), driver, args.campaign, "-o", out, "--progress", "none"]
    for s in args.set:
        cmd += ["--set", s]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    m = TAIL.search(p.stderr)
    if p.returncode not in (0, 3, 6) or not m:  # 3: a FAIL verdict, 6: NOT ASSESSED; the file is written
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr[-2000:]}")
    with h5py.File(out, "r") as f:
        read_back = int(f["timing"].attrs["stats_columns_read_back"])
    return wall, float(m.group(1)), float(m.group(2)), read_back


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--driver", action="append", required=True, help="NAME=PATH of a truss-campaign")
    ap.add_argument("--campaign", default=os.path.join(REPO, "campaigns", "motor_sizing.toml"))
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--set", action="append", default=None, help="KEY=VALUE (default: the subset sweep)")
    args = ap.parse_args()
    args.set = SWEEP if args.set is None else args.set
    drivers = [d.split("=", 1) for d in args.driver]
    rows = {name: [] for name, _ in drivers}
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.repeats):
            for name, path in drivers:
                rows[name].append(run(path, args, os.path.join(tmp, f"{name}_{rep}.h5")))
        first = drivers[0][0]
        for name, _ in drivers[1:]:
            p = subprocess.run([sys.executable, os.path.join(REPO, "scripts", "compare_campaign_h5.py"),
                                os.path.join(tmp, f"{first}_0.h5"), os.path.join(tmp, f"{name}_0.h5")],
                               capture_output=True, text=True)
            print(f"{name} against {first}: {'the same values' if p.returncode == 0 else 'DIFFERENT'}"
                  f" ({p.stdout.strip().splitlines()[-1] if p.stdout.strip() else p.stderr.strip()[-200:]})")
    print(f"{args.ranks} ranks, {args.repeats} repeats each, interleaved; medians")
    print(f"{'driver':<12} {'command s':>10} {'tail s':>8} {'tail CPU s':>11} {'read back':>10}")
    for name, _ in drivers:
        r = rows[name]
        med = [statistics.median(x[k] for x in r) for k in range(3)]
        print(f"{name:<12} {med[0]:10.3f} {med[1]:8.3f} {med[2]:11.3f} {r[0][3]:10d}")


if __name__ == "__main__":
    main()
