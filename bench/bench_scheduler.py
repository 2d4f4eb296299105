#!/usr/bin/python3
"""Scheduler benchmark of truss-campaign (not a test; see docs/benchmarks.md, "Scheduler").

real:       the Table-1 campaign (campaigns/table1_dispersed.toml) on 1 rank and on 2 ranks over
            three transports: shared memory (Linux CMA single-copy on), shared memory with
            single-copy off (btl_vader_single_copy_mechanism none), TCP (btl self,tcp).
            Interleaved repeats, medians. Efficiency E(2) = T(1) / (2 T(2)) on the campaign's own
            wall time (root attribute wall_time_s). E is about the ratio of two factors, both
            against 1 rank: the share of the ranks' time spent in runs, sum of run times /
            (2 x schedule wall) (the scheduler), over the mean run time (the machine: cores that
            slow each other down).
synthetic:  P oversubscribed ranks whose runs sleep COST seconds (hidden --synthetic-run-cost-s:
            no physics, records of the real size), under shared memory and TCP. Efficiency
            E = sum of run times / (P x schedule wall time) (/timing/run_wall_time_s,
            /timing@schedule_wall_s), rank 0's per-result cost h = (time rank 0 spends matching,
            receiving, storing, journalling and answering) / results, and the model's prediction.
compare:    this build against another binary (--driver), 2 ranks, single-copy off and TCP, the
            two interleaved in every repeat: rank 0's per-result and per-run CPU, the journal's
            and the tick's wall time per result.

Model (rank 0 computes runs and handles every result, serially): with per-run cost c and rank
0's per-result cost h, the P - 1 workers deliver (P - 1)/c results per second, which take rank 0
a fraction u = (P - 1) h / c of its time; it computes its own runs (cost c + h each) in the rest.
  u < 1: throughput X = (P - 1)/c + (1 - u)/(c + h);   u >= 1: X = 1/h (rank 0 saturated)
  E(P) = X c / P.
So E stays near 1 - h/c up to P ~ c/h and falls as c/(P h) beyond. Rank 0's write thread (w a
result, beside h): on a core of its own it caps X at 1/w; on the ranks' cores it takes X w of
their time (--w; docs/benchmarks.md, "Tenth step").

  bench/bench_scheduler.py BUILD_DIR real [--runs 4000] [--repeats 3] [--driver BEFORE_BINARY]
  bench/bench_scheduler.py BUILD_DIR synthetic [--ranks 32] [--cost 0.002] [--runs 20000] [--repeats 3] [--driver OLD]
  bench/bench_scheduler.py BUILD_DIR compare --driver OLD/truss-campaign [--runs 20000] [--repeats 3]
  bench/bench_scheduler.py model --c C --h H [--w W] [--ranks 2 16 32 64]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import h5py

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TABLE1 = os.path.join(REPO, "campaigns", "table1_dispersed.toml")
TRANSPORTS = {
    "shm (CMA)": [],
    "shm, single-copy off": ["--mca", "btl_vader_single_copy_mechanism", "none"],
    "tcp": ["--mca", "btl", "self,tcp"],
}


def model_efficiency(P, c, h, w=0.0, spare_core=True):
    """E(P) of the model; w > 0: rank 0's write thread spends w a result beside it, on a core of
    its own (spare_core: throughput at most 1/w) or on the ranks' cores (its CPU, X w per second,
    is taken from them: the model with P - X w ranks, solved by fixed-point iteration)."""
    def throughput(ranks):
        u = (ranks - 1) * h / c
        return (ranks - 1) / c + (1 - u) / (c + h) if u < 1 else 1 / h
    X = throughput(P)
    if w > 0 and not spare_core:
        for _ in range(200):
            X = throughput(P - X * w)
    if w > 0:
        X = min(X, 1 / w)
    return min(1.0, X * c / P)


def run(driver, ranks, mca, out, sets, extra=()):
    if os.path.exists(out):
        os.remove(out)
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), *mca, driver, TABLE1, "-o", out, "--progress", "none",
           *[a for s in sets for a in ("--set", s)], *extra]
    p = subprocess.run(cmd, env=ENV, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=3600,
                       text=True)
    # The end after the last result (the last chunk, /stats, close, sync, rename): the summary line.
    tail = re.search(r"statistics and file: ([0-9.e+-]+) s, ([0-9.e+-]+) s CPU", p.stderr)
    with h5py.File(out, "r") as f:
        t = f["timing"]
        a = dict(t.attrs)
        runs = t["run_wall_time_s"][:]
        n = runs.size
        handled = a.get("rank0_poll_s", float("nan")) + a.get("rank0_tick_s", 0.0) + a.get("rank0_write_s", 0.0)
        r0 = max(1, int(a.get("runs_by_rank0", 1)))
        return {
            "tail": float(tail.group(1)) if tail else float("nan"),
            "tail_cpu": float(tail.group(2)) if tail else float("nan"),
            "h_cpu": a.get("rank0_handle_cpu_s", float("nan")) / n,
            # rank 0's write thread (returned chunks written, statistics merged): beside h, not in it
            "w_cpu": a.get("rank0_write_thread_cpu_s", 0.0) / n,
            "c_cpu": a.get("rank0_compute_cpu_s", float("nan")) / r0,
            "wall": float(f.attrs["wall_time_s"]),
            "sched": float(a.get("schedule_wall_s", float("nan"))),
            "rank0_runs": int((t["rank"][:] == 0).sum()),
            "n": n,
            "run_sum": float(runs.sum()),
            "h": handled / n,
            # Parts of rank 0's time per result (wall, s): MPI calls, storing results (of which the
            # journal), writing the chunks and merging their statistics (an older build's
            # rank0_job_output_s: writing worker-encoded chunks).
            **{k: a.get(f"rank0_{k}_s", float("nan")) / n for k in ("mpi", "result", "journal")},
            "write": a.get("rank0_write_s", a.get("rank0_job_output_s", float("nan"))) / n,
            "tick": a.get("rank0_tick_s", float("nan")) / n,
        }


def med(rows, key):
    return statistics.median(r[key] for r in rows)


def bench_real(a):
    """1 rank and 2 ranks over the three transports; with --driver, that build ("before") and this
    one ("after") interleaved in every repeat, each build's efficiency against its own 1-rank time."""
    load0 = os.getloadavg()
    drivers = {"": os.path.join(a.build, "truss-campaign")}
    if a.driver:
        drivers = {"before": a.driver, "after": drivers[""]}
    sets = [f"ensemble.n_runs={a.runs}"]
    names = ["1 rank", *TRANSPORTS]
    rows = {(k, b): [] for b in drivers for k in names}
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "r.h5")
        for rep in range(a.repeats):
            for k in names:
                for b, drv in drivers.items():
                    rows[(k, b)].append(run(drv, 1 if k == "1 rank" else 2, TRANSPORTS.get(k, []), out, sets))
            print(f"repeat {rep + 1}/{a.repeats} done", file=sys.stderr)
    for b, drv in drivers.items():
        print(f"{b or 'driver'}: {drv}")
    print(f"{a.runs} runs, {a.repeats} repeats (medians); load average before / after: {load0} / {os.getloadavg()}\n")
    # The efficiency T(1) / (P T(P)) is about the ratio of two factors, both against 1 rank: how
    # much longer a run's simulation takes when every core computes (the machine: shared caches and
    # memory bandwidth, the VM's vCPUs) and the share of the ranks' time spent in simulations,
    # sum of run_wall_time_s / (P schedule_wall_s) (the scheduler: rank 0's per-result work,
    # waiting, the start and the tail; on 1 rank it is below 1 by the file's chunk writes and each
    # run's sampling and record outside the simulation).
    print("| ranks | transport | build | campaign wall (s) | efficiency | run time vs 1 rank | time in runs vs 1 rank "
          "| runs by rank 0 | rank 0 per result, wall (us) | rank 0 per result, CPU (us) | rank 0 per run, CPU (us) "
          "| h / c (CPU) | tail wall / CPU (s) |")
    print("|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for k in names:
        for b in drivers:
            rs, one = rows[(k, b)], rows[("1 rank", b)]
            t1, c = med(one, "wall"), statistics.median(r["run_sum"] / r["n"] for r in one)
            busy1 = statistics.median(r["run_sum"] / r["sched"] for r in one)
            P = 1 if k == "1 rank" else 2
            w = med(rs, "wall")
            h, hc, cc = med(rs, "h"), med(rs, "h_cpu"), med(rs, "c_cpu")
            slow = statistics.median(r["run_sum"] / r["n"] for r in rs) / c
            busy = statistics.median(r["run_sum"] / (P * r["sched"]) for r in rs) / busy1
            print(f"| {P} | {'-' if P == 1 else k} | {b or '-'} | {w:.3f} | {t1 / (P * w):.3f} | {slow:.3f} | {busy:.3f} "
                  f"| {med(rs, 'rank0_runs'):.0f} | {h * 1e6:.1f} | {hc * 1e6:.1f} | {cc * 1e6:.1f} | {hc / cc * 100:.2f} % "
                  f"| {med(rs, 'tail'):.3f} / {med(rs, 'tail_cpu'):.3f} |")
    print("\nWhere rank 0's per-result wall time goes (us a result, medians; /timing's rank0_*_s over the results):\n")
    print("| ranks | transport | build | MPI calls | storing results | of which journal | chunk writes + statistics "
          "| tick (journal sync, progress) |")
    print("|---:|---|---|---:|---:|---:|---:|---:|")
    for k in names:
        for b in drivers:
            rs = rows[(k, b)]
            print(f"| {1 if k == '1 rank' else 2} | {'-' if k == '1 rank' else k} | {b or '-'} | " +
                  " | ".join(f"{med(rs, x) * 1e6:.1f}" for x in ("mpi", "result", "journal", "write", "tick")) + " |")


def bench_synthetic(a):
    load0 = os.getloadavg()
    drivers = {"": os.path.join(a.build, "truss-campaign")}
    if a.driver:  # another build, interleaved with this one in every repeat
        drivers = {"before": a.driver, "after": drivers[""]}
    sets = [f"ensemble.n_runs={a.runs}"]
    extra = ["--synthetic-run-cost-s", str(a.cost)]
    rows = {(t, b): [] for t in ("shm (CMA)", "tcp") for b in drivers}
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "s.h5")
        for rep in range(a.repeats):
            for (name, b) in rows:
                rows[(name, b)].append(run(drivers[b], a.ranks, TRANSPORTS[name], out, sets, extra))
            print(f"repeat {rep + 1}/{a.repeats} done", file=sys.stderr)
    P = a.ranks
    print(f"{P} ranks, {a.runs} sleeping runs of {a.cost * 1e3:g} ms, {a.repeats} repeats (medians); "
          f"load average before / after: {load0} / {os.getloadavg()}")
    for b, drv in drivers.items():
        print(f"{b or 'driver'}: {drv}")
    print("\n| transport | build | schedule wall (s) | mean run (ms) | efficiency | runs by rank 0 | rank 0 per result, wall (us) "
          "| rank 0 per result, CPU (us) | write thread per result, CPU (us) | model E (wall h) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for (name, b), rs in rows.items():
        E = statistics.median(r["run_sum"] / (P * r["sched"]) for r in rs)
        c = statistics.median(r["run_sum"] / r["n"] for r in rs)
        h = med(rs, "h")
        print(f"| {name} | {b or '-'} | {med(rs, 'sched'):.3f} | {c * 1e3:.3f} | {E:.3f} | {med(rs, 'rank0_runs'):.0f} "
              f"| {h * 1e6:.1f} | {med(rs, 'h_cpu') * 1e6:.1f} | {med(rs, 'w_cpu') * 1e6:.1f} | {model_efficiency(P, c, h):.3f} |")


def bench_compare(a):
    """Two builds side by side: 2 ranks, single-copy off and TCP, the builds interleaved within each
    repeat; medians of rank 0's per-result CPU h, h / c, the journal's and the tick's wall time."""
    drivers = {"before": a.driver, "after": os.path.join(a.build, "truss-campaign")}
    sets = [f"ensemble.n_runs={a.runs}"]
    mcas = {k: TRANSPORTS[k] for k in ("shm, single-copy off", "tcp")}
    rows = {}
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "c.h5")
        for rep in range(a.repeats):
            for t, mca in mcas.items():
                for b, drv in drivers.items():
                    rows.setdefault((t, b), []).append(run(drv, 2, mca, out, sets))
            print(f"repeat {rep + 1}/{a.repeats} done", file=sys.stderr)
    print(f"before: {drivers['before']}\nafter: {drivers['after']}\n{a.runs} runs, 2 ranks, {a.repeats} repeats (medians)\n")
    print("| transport | build | wall (s) | rank 0 per result, CPU (us) | write thread per result, CPU (us) "
          "| per run, CPU (us) | h / c | (h + write thread) / c | journal (us, wall) | tick (us, wall) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for (t, b), rs in rows.items():
        hc = statistics.median(r["h_cpu"] / r["c_cpu"] for r in rs)
        tc = statistics.median((r["h_cpu"] + r["w_cpu"]) / r["c_cpu"] for r in rs)
        print(f"| {t} | {b} | {med(rs, 'wall'):.2f} | {med(rs, 'h_cpu') * 1e6:.2f} | {med(rs, 'w_cpu') * 1e6:.2f} "
              f"| {med(rs, 'c_cpu') * 1e6:.1f} | {hc * 100:.2f} % | {tc * 100:.2f} % | {med(rs, 'journal') * 1e6:.2f} "
              f"| {med(rs, 'tick') * 1e6:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build", help="build directory, or 'model'")
    ap.add_argument("what", nargs="?", choices=["real", "synthetic", "compare"])
    ap.add_argument("--runs", type=int)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--driver", help="real, compare, synthetic: another truss-campaign binary (the 'before' one), "
                                     "interleaved with this build's in every repeat")
    ap.add_argument("--ranks", type=int, nargs="+", default=[32])
    ap.add_argument("--cost", type=float, default=0.002)
    ap.add_argument("--c", type=float, help="model: per-run cost (s)")
    ap.add_argument("--h", type=float, help="model: rank 0's per-result cost (s)")
    ap.add_argument("--w", type=float, default=0.0, help="model: rank 0's write thread's per-result cost (s)")
    a = ap.parse_args()
    if a.build == "model":
        for P in a.ranks:
            line = f"P = {P:4d}: E = {model_efficiency(P, a.c, a.h):.3f}"
            if a.w > 0:
                line += (f"; with the write thread on a spare core {model_efficiency(P, a.c, a.h, a.w, True):.3f},"
                         f" on the ranks' cores {model_efficiency(P, a.c, a.h, a.w, False):.3f}")
            print(line)
        return
    if a.what == "real":
        a.runs = a.runs or 4000
        bench_real(a)
    elif a.what == "compare":
        if not a.driver:
            ap.error("compare needs --driver (the build to compare against)")
        a.runs = a.runs or 20000
        bench_compare(a)
    else:
        a.runs = a.runs or 20000
        a.ranks = a.ranks[0]
        bench_synthetic(a)


if __name__ == "__main__":
    main()
