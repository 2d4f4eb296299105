#!/usr/bin/env python3
"""Benchmark (not a test): the cost of a run from Python against its C++ cost, side by side.

The Table-1 velocity deployment (30 bays, no histories) timed, in each of R interleaved rounds, as
  C++               bench_run_cost: sim::simulate(scene) in a C++ loop (what truss-sim runs)
  simulate()        truss_deploy.simulate(scene) in a Python loop
  many, scenes      simulate_many([scene] * N, threads=1)
  many, overrides   simulate_many(base, {"mast.diagonal_stiffness_N_per_m": [20.0] * N}, threads=1)
  many, 2 threads   simulate_many([scene] * N, threads=2)
each as wall time / N for N runs; the medians over the rounds and their ratios to C++ (overhead
target: under 5 % for simulate_many) and 1 thread / 2 threads (target: at least 1.8x on 2 cores).
Then resident memory over 100,000 calls of simulate() (--leak-calls), read every 10,000.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py build [--runs 2000] [--rounds 7]
"""
import argparse
import os
import statistics
import subprocess
import sys
import time


def rss_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("build", help="the build folder (bench/bench_run_cost, python/truss_deploy)")
    ap.add_argument("--runs", type=int, default=2000, help="runs per timing (N)")
    ap.add_argument("--rounds", type=int, default=7, help="interleaved rounds (R); medians over them")
    ap.add_argument("--leak-calls", type=int, default=100_000)
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(a.build, "python"))
    import truss_deploy as td

    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = os.path.join(repo, "campaigns", "scenes", "table1.toml")
    scene = td.Scene.from_toml(path).with_(**{"run.output_step_s": 0})  # simulate() computes none either
    n = a.runs
    scenes = [scene] * n
    overrides = {"mast.diagonal_stiffness_N_per_m": [20.0] * n}
    cpp = os.path.join(a.build, "bench", "bench_run_cost")

    def per_run(fn):
        t0 = time.perf_counter()
        fn()
        return (time.perf_counter() - t0) / n

    cases = {
        "C++": lambda: float(subprocess.run([cpp, path, str(n), "run.output_step_s=0"], capture_output=True,
                                            text=True, check=True).stdout.split()[0]),
        "simulate()": lambda: per_run(lambda: [td.simulate(scene) for _ in range(n)]),
        "many, scenes": lambda: per_run(lambda: td.simulate_many(scenes, threads=1)),
        "many, overrides": lambda: per_run(lambda: td.simulate_many(scene, overrides, threads=1)),
        "many, 2 threads": lambda: per_run(lambda: td.simulate_many(scenes, threads=2)),
    }
    times = {k: [] for k in cases}
    for _ in range(a.rounds):
        for k, fn in cases.items():
            times[k].append(fn())
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"## Table-1 velocity deployment, 30 bays: cost per run ({n} runs, median of {a.rounds} rounds)\n")
    print("| path | per run (ms) | / C++ |\n|---|---:|---:|")
    for k, v in med.items():
        print(f"| {k} | {1e3 * v:.4f} | {v / med['C++']:.3f} |")
    print(f"\nsimulate_many on 2 threads: {med['many, scenes'] / med['many, 2 threads']:.2f}x the speed of 1 thread")
    ratios = [s / c for s, c in zip(times["many, scenes"], times["C++"])]
    print(f"simulate_many / C++ per round: {', '.join(f'{r:.3f}' for r in ratios)}")

    small = scene.with_(**{"mast.n_bays": 1})
    print(f"\n## Resident memory over {a.leak_calls:,} calls of simulate() (1 bay)\n")
    print("| calls | RSS (MiB) |\n|---:|---:|")
    for i in range(a.leak_calls):
        if i % 10_000 == 0:
            print(f"| {i:,} | {rss_mib():.2f} |")
        td.simulate(small).peak_drive_force_N
    print(f"| {a.leak_calls:,} | {rss_mib():.2f} |")


if __name__ == "__main__":
    main()
