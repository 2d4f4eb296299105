#!/usr/bin/env python3
"""Benchmark (not a test): IDA's cost per step and per bay on the free stack, one or two builds side by side.

    bench_ida_cost.py BUILD [BUILD_B] [--bays 10,30,100,300,1000] [--repeats 7] [--steps 300]

Each run is the slack free-stack scene (campaigns/scenes/paper_free_slack.toml: velocity drive,
contacts off) at rtol 1e-10, atol 1e-12, with run.integrator = ida and no history, stopped by the
step cap after --steps steps: all of them in the first stage (about 350 steps long at this
tolerance for 10 bays, 280 for 1000) or the start of the second, where every frame above frame 0
moves, so a phase has n (or n - 1) moving frames. The figure
is the CPU time (user + sys, from wait4) of that run minus the CPU time of the same run stopped
after 1 step (start-up: reading the scene, building the mast), per step and per bay: flat in n
when a step costs O(n). CPU time rather than wall time because the machine is shared (a loaded
machine inflates wall time, not the work). Builds and bay counts are interleaved within each
repeat; medians of the repeats. A build whose run of n bays takes more than --max-seconds skips
the larger n (a dense O(n^3) solver).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SCENE = os.path.join(ROOT, "campaigns", "scenes", "paper_free_slack.toml")


def cpu_run(build, n, steps):
    """CPU seconds of one truss-sim run and its JSON summary."""
    cmd = [os.path.join(build, "truss-sim"), SCENE, "--json", "--set", "run.integrator=ida",
           "--set", f"mast.n_bays={n}", "--set", f"run.max_steps={steps}", "--set", "run.output_step_s=0",
           "--set", "run.rtol=1e-10", "--set", "run.atol=1e-12", "--set", "run.max_wall_time_s=3600"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = p.stdout.read()
    _, _, ru = os.wait4(p.pid, 0)
    return ru.ru_utime + ru.ru_stime, json.loads(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("builds", nargs="+")
    p.add_argument("--bays", default="10,30,100,300,1000")
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--max-seconds", type=float, default=30.0)
    a = p.parse_args()
    bays = [int(x) for x in a.bays.split(",")]
    cost = {(b, n): [] for b in a.builds for n in bays}
    info = {}
    skip = {b: None for b in a.builds}  # smallest n a build no longer runs
    for rep in range(a.repeats):
        for n in bays:
            for b in a.builds:
                if skip[b] is not None and n >= skip[b]:
                    continue
                c1, _ = cpu_run(b, n, 1)
                c, d = cpu_run(b, n, a.steps)
                cost[(b, n)].append((c - c1) / ((d["steps"] - 1) * n))
                info[(b, n)] = (d["rhs_evals"] / d["steps"], d["message"])
                if c > a.max_seconds:
                    skip[b] = n + 1
        print(f"repeat {rep + 1} of {a.repeats} done", file=sys.stderr)
    names = [os.path.relpath(b, ROOT) if not os.path.isabs(b) else b for b in a.builds]
    print("| bays | " + " | ".join(f"{nm}: us per step per bay | residuals per step" for nm in names)
          + (" | ratio |" if len(a.builds) == 2 else " |"))
    print("|---:" * (1 + 2 * len(a.builds) + (len(a.builds) == 2)) + "|")
    for n in bays:
        cells, med = [], []
        for b in a.builds:
            if not cost[(b, n)]:
                cells += ["-", "-"]
                med.append(None)
                continue
            med.append(statistics.median(cost[(b, n)]))
            cells += [f"{1e6 * med[-1]:.2f}", f"{info[(b, n)][0]:.1f}"]
        if len(a.builds) == 2:
            cells.append(f"{med[0] / med[1]:.1f}" if None not in med else "-")
        print(f"| {n} | " + " | ".join(cells) + " |")
    for b, nm in zip(a.builds, names):
        flat = [statistics.median(cost[(b, n)]) for n in bays if cost[(b, n)]]
        print(f"{nm}: largest / smallest cost per step per bay over {len(flat)} bay counts: {max(flat) / min(flat):.2f}")
    for (b, n), (_, msg) in sorted(info.items()):  # the first two stages: n and n - 1 moving frames
        if "step cap" not in msg or not (f"(bay {n})" in msg or f"(bay {n - 1})" in msg):
            print(f"note: {b}, {n} bays: the run got past the first two stages: {msg}")


if __name__ == "__main__":
    main()
