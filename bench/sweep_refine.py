#!/usr/bin/python3
"""What a sweep's refinement (sweep.refine) buys, on the analytic limit state of
tests/mpi/sweep_analytic.toml: synthetic runs whose margin is the stall torque drawn as
x + N(0, 1 mN m), so p(x) = Phi(-x / 1 mN m) and the true crossing of 1e-6 is 4.7534 mN m.

  sweep_refine.py --driver build/truss-campaign --repo . [--seeds 20] [--refine 4] [--ranks 2]

For a coarse grid (3 and 6 mN m) and a fine one (4 to 5.5 mN m in steps of 0.5), with and without
the refinement, over the seeds 1..N: in how many the allowable lies on the safe side of the true
crossing (at or above it), in how many its interval holds it, the allowable's mean distance from it
and the mean runs of a sweep."""
import argparse
import math
import os
import subprocess
import tempfile

import h5py
import numpy as np
from scipy.stats import norm

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
TRUTH = -norm.ppf(1e-6) * 1e-3  # N m
GRIDS = {"coarse": ("0.003", "0.006", "2"), "fine": ("0.004", "0.0055", "4")}


def one(args, out, seed, grid, refine):
    a, b, n = GRIDS[grid]
    cmd = ["mpirun", "-np", str(args.ranks), args.driver, os.path.join(args.repo, "tests/mpi/sweep_analytic.toml"),
           "-o", out, "--progress", "none", "--synthetic-run-cost-s", "0"]
    for s in (f"ensemble.master_seed={seed}", f"sweep.refine={refine}", f"sweep.from={a}", f"sweep.to={b}",
              f"sweep.count={n}"):
        cmd += ["--set", s]
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr[-500:]}")
    with h5py.File(out, "r") as f:
        al = f["sweep/allowable"]
        v, lo, hi = (float(al[k][()]) for k in ("value", "lower", "upper"))
        runs = int(f["sweep/runs"][:].sum())
    os.remove(out)
    return v, lo, hi, runs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--refine", type=int, default=4)
    ap.add_argument("--ranks", type=int, default=2)
    args = ap.parse_args()
    print(f"true crossing {TRUTH * 1e3:.4f} mN m; seeds 1..{args.seeds}")
    print("| grid | refine | allowable on the safe side | interval holds the truth | mean distance (mN m) | "
          "mean runs |")
    print("|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as d:
        for grid in GRIDS:
            for refine in (0, args.refine):
                safe = inside = 0
                dist, runs = [], []
                for seed in range(1, args.seeds + 1):
                    v, lo, hi, n = one(args, os.path.join(d, "s.h5"), seed, grid, refine)
                    safe += v >= TRUTH
                    inside += (math.isnan(lo) or lo <= TRUTH) and (math.isnan(hi) or TRUTH <= hi)
                    dist.append(abs(v - TRUTH))
                    runs.append(n)
                print(f"| {grid} | {refine} | {safe}/{args.seeds} | {inside}/{args.seeds} | "
                      f"{1e3 * np.mean(dist):.3f} | {np.mean(runs):.0f} |")


if __name__ == "__main__":
    main()
