#!/usr/bin/python3
"""The report a user waits for: postproc/report.py on one results file, this tree's against
another revision's, side by side in one run (alternating, medians of the repeats).

Usage:
    bench/bench_report.py RESULTS.h5 [--base REV] [--repeats 5] [--no-pdf] [--scratch DIR]

REV (default HEAD) is checked out with `git archive` into the scratch directory. Each repeat
runs both reports once, in alternating order; the wall time and the CPU time (user + system of
the report and the children it waits for: the figures, the CSV) are read around each run. Prints
the medians and the ratio this tree / REV. On a shared machine the wall time moves with the
load; the CPU time and the ratio are what to compare.
"""
import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def checkout(rev, scratch):
    dest = os.path.join(scratch, f"postproc_{rev}")
    shutil.rmtree(dest, ignore_errors=True)
    os.makedirs(dest)
    archive = subprocess.run(["git", "-C", REPO, "archive", rev, "postproc"], check=True, capture_output=True)
    subprocess.run(["tar", "-x", "-C", dest], input=archive.stdout, check=True)
    return os.path.join(dest, "postproc", "report.py")


def run(script, h5, out, extra):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    p = subprocess.run(["/usr/bin/python3", script, h5, "-o", out, "--force", "--quiet", *extra],
                       capture_output=True, text=True)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode not in (0, 3, 4):
        sys.exit(f"error: {script} exited {p.returncode}: {p.stderr[-500:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("h5")
    ap.add_argument("--base", default="HEAD")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-pdf", action="store_true")
    ap.add_argument("--scratch", default=None)
    a = ap.parse_args()
    scratch = a.scratch or tempfile.mkdtemp(prefix="bench_report.")
    scripts = {"this tree": os.path.join(REPO, "postproc", "report.py"), a.base: checkout(a.base, scratch)}
    extra = ["--no-pdf"] if a.no_pdf else []
    times = {k: [] for k in scripts}
    for i in range(a.repeats):
        order = list(scripts) if i % 2 == 0 else list(scripts)[::-1]
        for k in order:
            times[k].append(run(scripts[k], a.h5, os.path.join(scratch, "out"), extra))
    print(f"{os.path.basename(a.h5)}, {'HTML' if a.no_pdf else 'HTML + PDF'}, {a.repeats} repeats (medians):")
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in times.items()}
    for k, (w, c) in med.items():
        print(f"  {k:>12}: wall {w:6.2f} s, CPU {c:6.2f} s")
    (w1, c1), (w0, c0) = med["this tree"], med[a.base]
    print(f"  this tree / {a.base}: wall {w1 / w0:.2f}, CPU {c1 / c0:.2f}")
    if not a.scratch:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
