#!/usr/bin/python3
"""Scaling benchmark of truss-campaign (not a test; see docs/benchmarks.md).

Runs, side by side and interleaved (so machine noise hits all alike), REPEATS times each:
  bare    bench_campaign_bare: the same runs in one process without MPI, journal or HDF5;
  1 rank, 2 ranks, 4 ranks (oversubscribed on a 2-core machine: marked as such).
Prints medians: wall time of the whole mpirun command and the campaign's own wall time (root
attribute wall_time_s: from the start of the driver to the file on disk), throughput (runs/s),
parallel efficiency E(p) = T(1) / (p T(p)), and the driver's overhead against the bare simulator.

  bench/bench_campaign.py BUILD_DIR [--campaign campaigns/table1_dispersed.toml] [--runs N] [--repeats R]
"""
import argparse
import resource
import os
import statistics
import subprocess
import sys
import tempfile
import time

import h5py

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def children_cpu_s():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_campaign(build, campaign, runs, ranks, out):
    if os.path.exists(out):
        os.remove(out)
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), os.path.join(build, "truss-campaign"), campaign, "-o", out,
           "--progress", "none"]
    if runs:
        cmd += ["--set", f"ensemble.n_runs={runs}"]
    t0, c0 = time.perf_counter(), children_cpu_s()
    subprocess.run(cmd, env=ENV, check=True, stdout=subprocess.DEVNULL)
    wall, cpu = time.perf_counter() - t0, children_cpu_s() - c0
    with h5py.File(out, "r") as f:
        inner = float(f.attrs["wall_time_s"])
        n = int(f.attrs["n_runs"])
        sim = float(f["timing/run_wall_time_s"][:].sum())
    return {"cmd": wall, "inner": inner, "n": n, "sim_sum": sim, "cpu": cpu}


def run_bare(build, campaign, runs):
    cmd = [os.path.join(build, "bench", "bench_campaign_bare"), campaign] + ([str(runs)] if runs else [])
    c0 = children_cpu_s()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    kv = {k: float(v) for k, v in (x.split("=") for x in out.split())}
    kv["cpu"] = children_cpu_s() - c0  # includes the record-path pass: compare with time fields only
    return kv


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("--campaign", default=os.path.join(REPO, "campaigns/table1_dispersed.toml"))
    ap.add_argument("--runs", type=int, default=0, help="override ensemble.n_runs (default: the campaign's)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--ranks", default="1,2,4")
    a = ap.parse_args()
    ranks = [int(r) for r in a.ranks.split(",")]
    cores = os.cpu_count()
    res = {"bare": []} | {r: [] for r in ranks}
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(a.repeats):
            res["bare"].append(run_bare(a.build, a.campaign, a.runs))
            for r in ranks:
                res[r].append(run_campaign(a.build, a.campaign, a.runs, r, os.path.join(tmp, f"r{r}.h5")))
            print(f"repeat {rep + 1}/{a.repeats} done", file=sys.stderr)
    med = statistics.median
    bare_total = med(x["total_s"] for x in res["bare"])
    bare_sim = med(x["simulate_s"] for x in res["bare"])
    n = res[ranks[0]][0]["n"]
    print(f"# truss-campaign scaling: {os.path.relpath(a.campaign, REPO)}, {n} runs, {cores} cores, "
          f"median of {a.repeats} interleaved repeats\n")
    print(f"bare simulator (1 process, no MPI/journal/HDF5): {bare_total:.3f} s = {n / bare_total:.0f} runs/s "
          f"(simulate alone {bare_sim:.3f} s, sampling and dispersion {bare_total - bare_sim:.3f} s)\n")
    if "uniforms_s" in res["bare"][0]:  # the per-run split (thread CPU time, bench_campaign_bare)
        us = {k: 1e6 * med(x[k] for x in res["bare"]) / n
              for k in ("uniforms_s", "inputs_s", "simulate_s", "encode_s", "record_path_s")}
        print("a run's path, CPU us a run: " + ", ".join(f"{k[:-2]} {v:.1f}" for k, v in us.items())
              + f"; record path / simulate = {us['record_path_s'] / us['simulate_s']:.3f}\n")
    print("| ranks | campaign wall (s) | mpirun wall (s) | runs/s | efficiency | note |")
    print("| ----- | ----------------- | --------------- | ------ | ---------- | ---- |")
    t1 = med(x["inner"] for x in res[ranks[0]]) if ranks[0] == 1 else None
    for r in ranks:
        inner = med(x["inner"] for x in res[r])
        cmd = med(x["cmd"] for x in res[r])
        eff = f"{t1 / (r * inner):.2f}" if t1 else "-"
        note = f"oversubscribed ({r} ranks on {cores} cores)" if r > cores else ""
        print(f"| {r} | {inner:.3f} | {cmd:.3f} | {n / inner:.0f} | {eff} | {note} |")
    if t1:
        print(f"\ndriver overhead on 1 rank: campaign wall / bare sample+simulate = {t1 / bare_total:.3f} "
              f"({100 * (t1 / bare_total - 1):+.1f} %); against simulate alone {100 * (t1 / bare_sim - 1):+.1f} %")
        print("per-repeat ratios (1-rank campaign / bare, same repeat): "
              + ", ".join(f"{x['inner'] / b['total_s']:.3f}" for x, b in zip(res[1], res["bare"])))
        rec = med(x["record_path_s"] / x["total_s"] for x in res["bare"])
        print(f"same process, same runs: the driver's per-run path (record, bytes, table) / bare sample+simulate = "
              f"{rec:.3f} (median of per-repeat ratios)")
        # CPU time is less sensitive than wall time to other load on a shared machine.
        cpu1 = med(x["cpu"] for x in res[1])
        print(f"1-rank campaign CPU time (mpirun and rank, user + sys): {cpu1:.3f} s; "
              f"against bare sample+simulate {bare_total:.3f} s: {100 * (cpu1 / bare_total - 1):+.1f} %; "
              f"per run {1e6 * cpu1 / n:.1f} us = {cpu1 / bare_sim:.3f} x simulate alone")


if __name__ == "__main__":
    main()
