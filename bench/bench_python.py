#!/usr/bin/env python3
"""Benchmark (not a test): the cost of a run from Python against its C++ cost, side by side.

The Table-1 velocity deployment (30 bays, no histories) timed, in each of R interleaved rounds, as
  C++               bench_run_cost: sim::simulate(scene) in a C++ loop (what truss-sim runs)
  simulate()        truss_deploy.simulate(scene) in a Python loop
  many, scenes      simulate_many([scene] * N, threads=1)
  many, overrides   simulate_many(base, {"mast.diagonal_stiffness_N_per_m": [20.0] * N}, threads=1)
  many, 2 threads   simulate_many([scene] * N, threads=2)
each as wall time and process CPU time / N for N runs; the medians over the rounds and their
ratios to C++ (overhead target: under 5 % for simulate_many; CPU time is the steadier figure on a
shared machine) and 1 thread / 2 threads in wall time (target: at least 1.8x on 2 idle cores).
Then resident memory over 100,000 calls of simulate() (--leak-calls), read every 20,000.

--instructions: the instructions each path executes per run instead (valgrind's callgrind, the
difference between 300 and 100 runs, so that start-up and imports cancel): a count that the other
programs of a shared machine do not change, for the overhead when wall and CPU times are too noisy.

    /usr/bin/python3 bench/bench_python.py build [--runs 1000] [--rounds 9] [--instructions]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import time


SCENE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "campaigns", "scenes", "table1.toml")


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def child(build, mode, n):
    """One path, n runs, in a process of its own (--instructions)."""
    sys.path.insert(0, os.path.join(build, "python"))
    import truss_deploy as td
    scene = td.Scene.from_toml(SCENE).with_(**{"run.output_step_s": 0})
    td.simulate_many([scene] * 2, threads=1)  # imports and first calls: the same in both counts
    if mode == "many, scenes":
        td.simulate_many([scene] * n, threads=1)
    elif mode == "many, overrides":
        td.simulate_many(scene, {"mast.diagonal_stiffness_N_per_m": [20.0] * n}, threads=1)
    else:
        for _ in range(n):
            td.simulate(scene)


def instructions(build):
    def count(cmd):
        p = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *cmd],
                           capture_output=True, text=True, check=True)
        return int(re.search(r"Collected : (\d+)", p.stderr).group(1))

    cpp = [os.path.join(build, "bench", "bench_run_cost"), SCENE]
    print("## Instructions per run (callgrind, 300 runs minus 100 runs, / 200)\n")
    print("| path | instructions per run | / C++ |\n|---|---:|---:|")
    ref = None
    for mode in ("C++", "simulate()", "many, scenes", "many, overrides"):
        def cmd(n):
            if mode == "C++":
                return [*cpp, str(n), "run.output_step_s=0"]
            return [sys.executable, os.path.abspath(__file__), build, "--child", mode, str(n)]
        per_run = (count(cmd(300)) - count(cmd(100))) / 200
        ref = ref or per_run
        print(f"| {mode} | {per_run:,.0f} | {per_run / ref:.4f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("build", help="the build folder (bench/bench_run_cost, python/truss_deploy)")
    ap.add_argument("--runs", type=int, default=1000, help="runs per timing (N)")
    ap.add_argument("--rounds", type=int, default=9, help="interleaved rounds (R); medians over them")
    ap.add_argument("--leak-calls", type=int, default=100_000)
    ap.add_argument("--instructions", action="store_true", help="count instructions per run (valgrind)")
    ap.add_argument("--child", nargs=2, metavar=("PATH", "RUNS"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        return child(a.build, a.child[0], int(a.child[1]))
    if a.instructions:
        return instructions(a.build)
    sys.path.insert(0, os.path.join(a.build, "python"))
    import truss_deploy as td

    path = SCENE
    scene = td.Scene.from_toml(path).with_(**{"run.output_step_s": 0})  # simulate() computes none either
    n = a.runs
    scenes = [scene] * n
    overrides = {"mast.diagonal_stiffness_N_per_m": [20.0] * n}
    cpp = os.path.join(a.build, "bench", "bench_run_cost")

    def cpp_run():
        out = subprocess.run([cpp, path, str(n), "run.output_step_s=0"], capture_output=True, text=True, check=True)
        wall, cpu, _ = out.stdout.split()
        return float(wall), float(cpu)

    def per_run(fn):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        return (time.perf_counter() - w0) / n, (time.process_time() - c0) / n

    cases = {
        "C++": cpp_run,
        "simulate()": lambda: per_run(lambda: [td.simulate(scene) for _ in range(n)]),
        "many, scenes": lambda: per_run(lambda: td.simulate_many(scenes, threads=1)),
        "many, overrides": lambda: per_run(lambda: td.simulate_many(scene, overrides, threads=1)),
        "many, 2 threads": lambda: per_run(lambda: td.simulate_many(scenes, threads=2)),
    }
    td.simulate_many(scenes[:10])  # pandas imported, caches warm
    wall = {k: [] for k in cases}
    cpu = {k: [] for k in cases}
    for _ in range(a.rounds):
        for k, fn in cases.items():
            w, c = fn()
            wall[k].append(w)
            cpu[k].append(c)
    mw = {k: statistics.median(v) for k, v in wall.items()}
    mc = {k: statistics.median(v) for k, v in cpu.items()}
    print(f"## Table-1 velocity deployment, 30 bays: cost per run ({n} runs, median of {a.rounds} rounds)\n")
    print("| path | wall (ms) | / C++ | CPU (ms) | / C++ |\n|---|---:|---:|---:|---:|")
    for k in cases:
        print(f"| {k} | {1e3 * mw[k]:.4f} | {mw[k] / mw['C++']:.3f} | {1e3 * mc[k]:.4f} | {mc[k] / mc['C++']:.3f} |")
    speedups = [a / b for a, b in zip(wall["many, scenes"], wall["many, 2 threads"])]
    print(f"\nsimulate_many on 2 threads: {mw['many, scenes'] / mw['many, 2 threads']:.2f}x the speed of 1 thread "
          f"(wall time; per round: {', '.join(f'{x:.2f}' for x in speedups)})")
    print("simulate_many / C++, CPU time per round: "
          + ", ".join(f"{s / c:.3f}" for s, c in zip(cpu["many, scenes"], cpu["C++"])))

    small = scene.with_(**{"mast.n_bays": 1})
    print(f"\n## Resident memory over {a.leak_calls:,} calls of simulate() (1 bay)\n")
    print("| calls | RSS (MiB) |\n|---:|---:|")
    for i in range(a.leak_calls):
        if i % 20_000 == 0:
            print(f"| {i:,} | {rss_mib():.2f} |")
        td.simulate(small).peak_drive_force_N
    print(f"| {a.leak_calls:,} | {rss_mib():.2f} |")


if __name__ == "__main__":
    main()
