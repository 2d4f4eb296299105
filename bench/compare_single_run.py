#!/usr/bin/env python3
"""Side-by-side benchmark of two builds of bench_single_run (before/after a change): runs them
interleaved REPEATS times on this machine and prints the median wall time of each row and the
ratio after/before. Usage: compare_single_run.py BEFORE_BIN AFTER_BIN [--repeats 3]"""
import argparse
import re
import statistics
import subprocess


def parse(text):
    d = {}
    for line in text.splitlines():
        m = re.match(r"\| (\d+) \| ([\d.]+) \|", line)
        if m:
            d[f"velocity, {m.group(1)} bays"] = float(m.group(2))
        m = re.match(r"\| (dopri54|cvode) \| ([\de.-]+) \| ([\d.]+) \|", line)
        if m:
            d[f"motor 30 bays, {m.group(1)} rtol {m.group(2)}"] = float(m.group(3))
    return d


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    runs = {"before": [], "after": []}
    for _ in range(a.repeats):
        for k, exe in (("before", a.before), ("after", a.after)):
            runs[k].append(parse(subprocess.run([exe], capture_output=True, text=True, check=True).stdout))
    print(f"| case | before (ms) | after (ms) | after/before |  (medians of {a.repeats} interleaved runs)")
    print("|---|---:|---:|---:|")
    for key in runs["before"][0]:
        b = statistics.median(r[key] for r in runs["before"])
        t = statistics.median(r[key] for r in runs["after"])
        print(f"| {key} | {b:.4f} | {t:.4f} | {t / b:.3f} |")


if __name__ == "__main__":
    main()
