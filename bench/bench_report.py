#!/usr/bin/python3
"""The report a user waits for: postproc/report.py on one results file, with and without its PDF,
this tree's against another revision's, side by side in one run (alternating, medians of the
repeats), its time split into phases.

Usage:
    bench/bench_report.py RESULTS.h5 [--base REV] [--repeats 5] [--csv] [--no-pdf-only]
                          [--scratch DIR]

The main job's report (scripts/run_main.sh): the default campaign's file, `--csv`, with its PDF.
REV (default HEAD; `main` for the main branch) is checked out with `git archive` into the scratch
directory. Each repeat runs every (tree, with or without PDF) report once, in an order that
alternates from one repeat to the next. A report runs as report.py does (a new interpreter, the
tree's package imported, `cli.main`), with timers wrapped around the package's phase functions
(the names both revisions share):

    start      interpreter, imports, the file's kind and SHA-256, up to reading
    reading    cli.read_file: the HDF5 file read and checked
    judging    cli.judge_campaign: statistics, design loads, margins, verdict
    page       cli.campaign_report less the judging: the sections' HTML, and handing the figures
               to the drawing processes (waiting for a free one when both are busy)
    figures    Page.finish: waiting for the last figures; its CPU is every figure process's
               (os.wait4 of each), whenever they ran
    csv        the runs.csv process's CPU (it runs beside the others; its wait is in "rest")
    html+rest  writing report.html, moving the files, the terminal lines
    pdf layout cli.write_pdf: importing WeasyPrint, HTML.render (the layout)
    pdf write  weasyprint's Document.write_pdf (the figures re-encoded, the fonts subset)

Wall is each phase's span in the report's own process; CPU is that process's user + system time
in the span (time.process_time), plus the children's for figures and csv. "total" is measured
from outside (wall around the process, CPU = its user + system and that of the children it waited
for). On a shared machine the wall time moves with the load; the CPU time and the ratio of the
two trees are what to compare.
"""
import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.abspath(__file__)
REPO = os.path.dirname(os.path.dirname(HERE))
PHASES = ("start", "reading", "judging", "page", "figures", "csv", "html+rest", "pdf layout",
          "pdf write")


def checkout(rev, scratch):
    dest = os.path.join(scratch, f"postproc_{rev}")
    shutil.rmtree(dest, ignore_errors=True)
    os.makedirs(dest)
    archive = subprocess.run(["git", "-C", REPO, "archive", rev, "postproc"], check=True, capture_output=True)
    subprocess.run(["tar", "-x", "-C", dest], input=archive.stdout, check=True)
    return os.path.join(dest, "postproc")


class Clock:
    """Wall and CPU (this process) spent inside wrapped functions, by phase; nested spans are
    charged to the innermost one only."""

    def __init__(self):
        self.wall = dict.fromkeys(PHASES, 0.0)
        self.cpu = dict.fromkeys(PHASES, 0.0)
        self.stack = []

    def wrap(self, phase, fn):
        def timed(*args, **kwargs):
            t0, c0 = time.monotonic(), time.process_time()
            self.stack.append([0.0, 0.0])      # time of the nested spans
            try:
                return fn(*args, **kwargs)
            finally:
                dw, dc = time.monotonic() - t0, time.process_time() - c0
                inner_w, inner_c = self.stack.pop()
                self.wall[phase] += dw - inner_w
                self.cpu[phase] += dc - inner_c
                if self.stack:
                    self.stack[-1][0] += dw
                    self.stack[-1][1] += dc
        return timed


def child(tree, argv, t_exec):
    """One report in this process (report.py's way), its phases timed; prints them as JSON."""
    sys.path.insert(0, tree)
    from truss_report import cli                 # noqa: PLC0415 - the tree's, chosen at run time
    from truss_report.page import render          # noqa: PLC0415
    t_main = time.time()
    clock, child_cpu, csv_pids = Clock(), {"figures": 0.0, "csv": 0.0}, set()
    waitpid = os.waitpid

    def wait4(pid, options):       # every child reaped through here: its own CPU, by kind
        if options != 0:
            return waitpid(pid, options)
        pid_, status, ru = os.wait4(pid, 0)
        child_cpu["csv" if pid_ in csv_pids else "figures"] += ru.ru_utime + ru.ru_stime
        return pid_, status
    os.waitpid = wait4
    start_csv = cli.start_csv

    def start_csv_noted(*args):
        proc = start_csv(*args)
        csv_pids.add(proc.pid)
        return proc
    cli.start_csv = start_csv_noted
    cli.file_sha256 = clock.wrap("start", cli.file_sha256)
    cli.read_kind = clock.wrap("start", cli.read_kind)
    cli.read_file = clock.wrap("reading", cli.read_file)
    cli.judge_campaign = clock.wrap("judging", cli.judge_campaign)
    cli.campaign_report = clock.wrap("page", cli.campaign_report)
    render.Page.finish = clock.wrap("figures", render.Page.finish)
    write_pdf = cli.write_pdf

    def write_pdf_timed(*args):    # WeasyPrint is imported there (--no-pdf runs without it)
        import weasyprint                         # noqa: PLC0415
        if not hasattr(weasyprint.HTML.render, "timed"):
            weasyprint.HTML.render = clock.wrap("pdf layout", weasyprint.HTML.render)
            weasyprint.HTML.render.timed = True
            weasyprint.document.Document.write_pdf = clock.wrap(
                "pdf write", weasyprint.document.Document.write_pdf)
        return write_pdf(*args)
    cli.write_pdf = clock.wrap("pdf layout", write_pdf_timed)
    main = clock.wrap("html+rest", cli.main)
    sys.stdout = open(os.devnull, "w")
    rc = main(argv)
    if rc not in (0, 3, 4):
        sys.exit(f"error: the report exited {rc}")
    # The start: the interpreter and the imports up to cli.main (its CPU: the outside total
    # less the phases, median_phases).
    clock.wall["start"] = t_main - t_exec
    for k, v in child_cpu.items():
        clock.cpu[k] += v
    sys.stdout = sys.__stdout__
    print(json.dumps({"wall": clock.wall, "cpu": clock.cpu}))


def run(tree, h5, out, extra):
    """Runs one report in a new interpreter: (wall, CPU, phases) of it."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    p = subprocess.run(["/usr/bin/python3", HERE, "--child", tree, repr(time.time()), h5, "-o", out,
                        "--force", "--quiet", *extra], capture_output=True, text=True)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit(f"error: report of {tree} exited {p.returncode}: {p.stderr[-800:]}")
    phases = json.loads(p.stdout.strip().splitlines()[-1])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, phases


def median_phases(samples):
    """Per phase, the medians of wall and CPU over the repeats; the start's CPU is what the
    total has beyond the phases measured inside (interpreter and imports)."""
    out = {}
    for ph in PHASES:
        out[ph] = (statistics.median(s[2]["wall"][ph] for s in samples),
                   statistics.median(s[2]["cpu"][ph] for s in samples))
    rest_cpu = statistics.median(s[1] - sum(v for k, v in s[2]["cpu"].items() if k != "start")
                                 for s in samples)
    out["start"] = (out["start"][0], rest_cpu)
    out["total"] = (statistics.median(s[0] for s in samples), statistics.median(s[1] for s in samples))
    return out


def print_table(results, trees, modes):
    cols = [(t, m) for m in modes for t in trees]
    head = " | ".join(f"{t}, {m}: wall / CPU (s)" for t, m in cols)
    print(f"| phase | {head} |")
    print("|---|" + "---:|" * len(cols))
    for ph in PHASES + ("total",):
        cells = []
        for key in cols:
            w, c = results[key][ph]
            cells.append(f"{w:.2f} / {c:.2f}")
        print(f"| {ph} | " + " | ".join(cells) + " |")


def main():
    if len(sys.argv) > 3 and sys.argv[1] == "--child":
        t_exec = float(sys.argv[3])
        return child(sys.argv[2], sys.argv[4:], t_exec)
    ap = argparse.ArgumentParser()
    ap.add_argument("h5")
    ap.add_argument("--base", default="HEAD")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--csv", action="store_true", help="also write runs.csv, as the main job does")
    ap.add_argument("--no-pdf-only", action="store_true", help="only the reports without their PDF")
    ap.add_argument("--scratch", default=None)
    a = ap.parse_args()
    scratch = a.scratch or tempfile.mkdtemp(prefix="bench_report.")
    trees = {"this tree": os.path.join(REPO, "postproc"), a.base: checkout(a.base, scratch)}
    modes = ["no PDF"] if a.no_pdf_only else ["PDF", "no PDF"]
    csv = ["--csv"] if a.csv else []
    keys = [(t, m) for m in modes for t in trees]
    samples = {k: [] for k in keys}
    for i in range(a.repeats):
        for t, m in (keys if i % 2 == 0 else keys[::-1]):
            extra = csv + (["--no-pdf"] if m == "no PDF" else [])
            samples[(t, m)].append(run(trees[t], a.h5, os.path.join(scratch, "out"), extra))
    print(f"{os.path.basename(a.h5)}{' + runs.csv' if a.csv else ''}, {a.repeats} repeats (medians), "
          f"{time.strftime('%Y-%m-%d %H:%M %Z')}, load average {os.getloadavg()[0]:.1f}:")
    results = {k: median_phases(v) for k, v in samples.items()}
    print_table(results, list(trees), modes)
    for m in modes:
        (w1, c1), (w0, c0) = results[("this tree", m)]["total"], results[(a.base, m)]["total"]
        print(f"{m}: this tree / {a.base}: wall {w1 / w0:.2f}, CPU {c1 / c0:.2f}")
    if not a.scratch:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
