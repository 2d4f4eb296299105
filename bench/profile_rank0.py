#!/usr/bin/python3
"""Where rank 0's per-result time goes (not a test; docs/benchmarks.md).

Runs the Table-1 campaign on 2 ranks with rank 0 under `perf record --call-graph dwarf` and
splits rank 0's samples: runs (inside append_run_record, its own runs' CRC included), its own
records on their way to their owners (sent and tested between its runs, counted with its runs),
and the per-result path (everything else under the round loop: receiving, scheduling, placing the
chunks), the last broken down by the function the round's loop called (and the one that called),
and by leaf function.

  bench/profile_rank0.py BUILD_DIR [--runs 100000] [--mca single-copy-off|tcp|cma] [--freq 1000]
"""
import argparse
import collections
import os
import re
import subprocess
import tempfile

MCA = {"single-copy-off": ["--mca", "btl_vader_single_copy_mechanism", "none"],
       "tcp": ["--mca", "btl", "self,tcp"], "cma": []}
COMPUTE = ("append_run_record", "seal_frame", "calc_uniforms")
# Frames of the simulation: a deep solver stack is cut by perf's 8 kB copy before append_run_record.
# Rank 0's round loop: Rank0Round::run, or with its callers inlined (LTO) the engine's run.
LOOP = ("Rank0Round::run", "Engine::run")
# Called by the loop itself between rank 0's runs (Node::poll's calls are the per-result path): its
# records gathered and sent, and their sends tested (Node::progress_records).
OWN_RECORDS = ("Node::route", "Node::flush_records", "Node::test_sends", "Node::progress_records")
SIMULATION = ("truss::stages::", "truss::model::", "truss::sim::", "truss::numerics::", "truss::integrators::")


def split(script):
    """(counts by category, per-result path by callee of run_schedule, by leaf) from `perf script`."""
    cat, callee, leaf = collections.Counter(), collections.Counter(), collections.Counter()
    two = collections.Counter()
    for sample in script.split("\n\n"):
        lines = [l.strip() for l in sample.strip().split("\n") if l.strip()]
        if len(lines) < 2:
            continue
        frames = [re.sub(r"^[0-9a-f]+ ", "", l) for l in lines[1:]]  # leaf first
        stack = " | ".join(frames)
        if any(k in stack for k in COMPUTE) or any(k in stack for k in SIMULATION):
            cat["runs"] += 1
        elif any(m in stack for m in LOOP):
            i = max(k for k, f in enumerate(frames) if any(m in f for m in LOOP))
            if i > 0 and any(m in frames[i - 1] for m in OWN_RECORDS):
                cat["rank 0's own records to their owners (with its runs)"] += 1
                continue
            cat["per-result path"] += 1
            callee[frames[i - 1][:70] if i > 0 else "Rank0Round::run"] += 1
            two[" > ".join(f[:50] for f in frames[max(0, i - 2):i][::-1]) or "Rank0Round::run"] += 1
            leaf[frames[0][:70]] += 1
        else:
            cat["other (start-up, the tail, MPI threads)"] += 1
    return cat, callee, two, leaf


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("--runs", type=int, default=100000)
    ap.add_argument("--mca", choices=sorted(MCA), default="single-copy-off")
    ap.add_argument("--freq", type=int, default=1000)
    a = ap.parse_args()
    repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    with tempfile.TemporaryDirectory() as d:
        data = os.path.join(d, "rank0.data")
        wrap = os.path.join(d, "wrap.sh")
        with open(wrap, "w") as f:
            f.write('#!/bin/bash\nif [ "$OMPI_COMM_WORLD_RANK" = 0 ]; then exec perf record -q --call-graph dwarf,8192 '
                    f'-F {a.freq} -o {data} "$@"; else exec "$@"; fi\n')
        os.chmod(wrap, 0o755)
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        cmd = ["mpirun", "--oversubscribe", "-np", "2", *MCA[a.mca], wrap, os.path.join(a.build, "truss-campaign"),
               os.path.join(repo, "campaigns/table1_dispersed.toml"), "-o", os.path.join(d, "out.h5"),
               "--set", f"ensemble.n_runs={a.runs}", "--progress", "none"]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
        print(next((l for l in out.stderr.splitlines() if " wrote " in l), ""))
        script = subprocess.run(["perf", "script", "-i", data, "-F", "tid,ip,sym"], capture_output=True, text=True,
                                check=True).stdout
    cat, callee, two, leaf = split(script)
    total, path = sum(cat.values()), cat["per-result path"]
    print(f"{total} samples of rank 0 ({a.runs} runs, 2 ranks, {a.mca})")
    for k, v in cat.most_common():
        print(f"  {v:6d}  {100 * v / total:5.1f} %  {k}")
    for title, c in (("per-result path by the function the round's loop called", callee),
                     ("... and the one that called", two), ("per-result path by leaf", leaf)):
        print(f"{title} ({path} samples):")
        for k, v in c.most_common(15):
            print(f"  {v:6d}  {100 * v / max(path, 1):5.1f} %  {k}")


if __name__ == "__main__":
    main()
