#!/usr/bin/python3
"""Scaling benchmark of truss-campaign (not a test): strong and weak scaling of a Table-1 campaign
and of a design sweep, from the results files' /timing. Meant for a cluster (docs/benchmarks.md,
"Scaling on a cluster", has the Slurm job script); on a workstation, --synthetic-run-cost-s gives
runs that sleep, so that more ranks than cores still measure the scheduler.

  bench/bench_scaling.py --driver [NAME=]build/truss-campaign ... --campaign table1|sweep --mode strong|weak
                         --ranks 1 2 4 8 [--runs N] [--launch "mpirun -np {ranks}"] [--repeats R]
                         [--synthetic-run-cost-s C] [--scratch DIR] [-- extra truss-campaign options]

--driver:  one build, or several (NAME=PATH each) compared side by side: their campaigns interleaved
           in each repeat, one table with a row per build and rank count. PATH may carry the build's
           own options: "s4=build/truss-campaign --statistics-ranks 4".

--campaign table1: campaigns/table1_dispersed.toml (the Table-1 velocity runs, about 80 us each);
           --runs: strong, the runs of every campaign (default 100,000); weak, the runs per rank
           (default 20,000).
--campaign sweep:  campaigns/motor_sizing.toml run as a design sweep of subset simulations of motor
           runs over 8 stall torques (28-36 mN m, refine = 3; its rounds the values' Markov steps
           side by side), not as the file's one reweighted importance campaign; --runs is
           ensemble.subset.n_per_level: strong, the same for every campaign (default 2,000: 95,200
           runs), weak, per rank (default 200).
--launch:  how a campaign on {ranks} ranks is started; on Slurm "srun --mpi=pmix -n {ranks}" (or
           "mpirun -np {ranks}", which reads the allocation).

For each rank count, the medians over the repeats of:
  wall            /timing schedule_wall_s: first batch handed out to the last record in (the MPI start,
                  the nominal run and the tail apart: they do not grow with the ranks);
  efficiency      strong: T(P0) P0 / (T(P) P), weak: T(P0) / T(P), P0 the smallest rank count given;
  busy            the share of the ranks' time inside runs, sum of /timing/run_wall_time_s / (P wall):
                  the efficiency without a baseline (what the scheduler loses);
  rank 0 h        rank 0's CPU outside its own runs per result, /timing rank0_handle_cpu_s / n, and
                  its inverse, the results absorbed a second of rank 0's CPU;
  a run c         rank 0's CPU per run it computed, rank0_compute_cpu_s / runs_by_rank0;
  h / c, P sat    rank 0's share, and the rank count at which it would be busy all the time with
                  results alone, 1 + c / h (docs/benchmarks.md, "Efficiency model");
  statistics      the statistics ranks S (/timing statistics_ranks; --statistics-ranks after `--`), the
                  largest one's CPU merging per result (stats_merge_cpu_s / n: h_s; rank 0's, inside h,
                  on one rank), and the rank count at which it would be busy merging alone, 1 + c / h_s.
"""
import argparse
import os
import shlex
import statistics
import subprocess
import sys
import tempfile

import h5py

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CAMPAIGNS = {"table1": "campaigns/table1_dispersed.toml", "sweep": "campaigns/motor_sizing.toml"}
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def size_sets(a, ranks):
    """The --set options that size one campaign of the benchmark on `ranks` ranks."""
    per = ranks if a.mode == "weak" else 1
    if a.campaign == "table1":
        return ["--set", f"ensemble.n_runs={a.runs * per}"]
    # the file's sweep as subset simulation at each of its 8 stall torques (its rounds: Markov steps)
    subset = ["ensemble.method=subset", "ensemble.importance=false", "sweep.from=0.028", "sweep.to=0.036",
              "sweep.count=5", "sweep.refine=3", "ensemble.subset.max_levels=9",
              f"ensemble.subset.n_per_level={a.runs * per}"]
    return [x for kv in subset for x in ("--set", kv)]


def run_once(a, driver, ranks, out):
    if os.path.exists(out):
        os.remove(out)
    program, *own = shlex.split(driver)
    cmd = [*shlex.split(a.launch.format(ranks=ranks)), program, os.path.join(REPO, CAMPAIGNS[a.campaign]), "-o", out,
           "--progress", "none", *size_sets(a, ranks), *own, *a.extra]
    if a.synthetic_run_cost_s is not None:
        cmd += ["--synthetic-run-cost-s", str(a.synthetic_run_cost_s)]
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True)
    if p.returncode not in (0, 4, 5, 6):  # 4-6: the file is written (most runs invalid, no result, NOT ASSESSED)
        sys.exit(f"error: {' '.join(cmd)} exited {p.returncode}:\n{p.stderr[-2000:]}")
    with h5py.File(out, "r") as f:
        t = f["timing"]
        n = int(f.attrs["n_runs"])
        wall = float(t.attrs["schedule_wall_s"])
        return {
            "n": n,
            "wall": wall,
            "busy": float(t["run_wall_time_s"][:].sum()) / (ranks * wall),
            "h": float(t.attrs["rank0_handle_cpu_s"]) / n,
            "c": float(t.attrs["rank0_compute_cpu_s"]) / max(1, int(t.attrs["runs_by_rank0"])),
            "S": float(t.attrs.get("statistics_ranks", float("nan"))),
            "hs": float(t.attrs.get("stats_merge_cpu_s", float("nan"))) / n,
        }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--driver", required=True, nargs="+", help="PATH, or NAME=PATH for each build compared")
    ap.add_argument("--campaign", choices=CAMPAIGNS, default="table1")
    ap.add_argument("--mode", choices=["strong", "weak"], default="strong")
    ap.add_argument("--ranks", type=int, nargs="+", required=True)
    ap.add_argument("--runs", type=int, help="see above (defaults by campaign and mode)")
    ap.add_argument("--launch", default="mpirun -np {ranks}")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--synthetic-run-cost-s", type=float)
    ap.add_argument("--scratch", help="where the results files go (default: a temporary folder)")
    ap.add_argument("extra", nargs="*", help="more truss-campaign options (after --)")
    a = ap.parse_args()
    if a.runs is None:
        a.runs = {("table1", "strong"): 100000, ("table1", "weak"): 20000, ("sweep", "strong"): 2000,
                  ("sweep", "weak"): 200}[(a.campaign, a.mode)]
    ranks = sorted(a.ranks)
    builds = dict(d.split("=", 1) if "=" in d else (d, d) for d in a.driver)
    rows = {(b, P): [] for b in builds for P in ranks}
    with tempfile.TemporaryDirectory(dir=a.scratch) as d:
        for _ in range(a.repeats):  # the builds interleaved: a drift of the machine's speed hits them alike
            for P in ranks:
                for b, path in builds.items():
                    rows[(b, P)].append(run_once(a, path, P, os.path.join(d, "scaling.h5")))
    med = {key: {k: statistics.median(r[k] for r in rs) for k in rs[0]} for key, rs in rows.items()}
    p0 = ranks[0]
    what = "runs per rank" if a.mode == "weak" and a.campaign == "table1" else \
        "n_per_level per rank" if a.mode == "weak" else "runs" if a.campaign == "table1" else "n_per_level"
    print(f"{a.mode} scaling, {CAMPAIGNS[a.campaign]}, {a.runs} {what}, launched as '{a.launch}'"
          f"{f', runs sleeping {a.synthetic_run_cost_s} s' if a.synthetic_run_cost_s is not None else ''}; "
          f"medians of {a.repeats}\n")
    print("| build | ranks | runs | wall (s) | efficiency | busy | rank 0 per result, CPU (us) | results a second of "
          "rank 0's CPU | a run on rank 0, CPU (us) | h / c | P at which rank 0 saturates | statistics ranks | "
          "a statistics rank's merge per result, CPU (us) | P at which it saturates |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for b in builds:
        for P in ranks:
            m, m0 = med[(b, P)], med[(b, p0)]
            eff = (m0["wall"] / m["wall"]) if a.mode == "weak" else (m0["wall"] * p0) / (m["wall"] * P)
            hc = m["h"] / m["c"] if m["c"] > 0 else float("nan")
            print(f"| {b} | {P} | {m['n']:.0f} | {m['wall']:.3f} | {eff:.3f} | {m['busy']:.3f} | {m['h'] * 1e6:.2f} "
                  f"| {1 / m['h'] if m['h'] > 0 else float('inf'):,.0f} | {m['c'] * 1e6:.1f} | {hc * 100:.2f} % "
                  f"| {1 + 1 / hc if hc > 0 else float('inf'):.0f} | {m['S']:.0f} | {m['hs'] * 1e6:.2f} "
                  f"| {1 + m['c'] / m['hs'] if m['hs'] > 0 else float('inf'):.0f} |")

if __name__ == "__main__":
    main()
