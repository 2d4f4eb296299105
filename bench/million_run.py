#!/usr/bin/python3
"""A 1,000,000-run campaign of a cheap scene (the Table-1 campaign on a 2-bay mast): rank 0's peak
memory, wall time, file size and tail, uninterrupted and killed with kill -9 about a third of the way
then resumed. The resumed file must equal the uninterrupted one (datasets outside /timing).

  bench/million_run.py --driver build/truss-campaign --repo . --dir /tmp/million [--ranks 2] [--runs 1000000]

Prints one line per measurement; docs/benchmarks.md records the numbers.
"""
import argparse
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "mpi"))
from test_campaign_mpi import ENV, datasets, kill_job, same_values  # noqa: E402


def command(a, out, extra=()):
    # /usr/bin/time around each rank: its peak resident set (kB) on stderr, rank 0's line first
    # in practice; the line with the larger RSS is rank 0's (it holds the store).
    return ["mpirun", "--oversubscribe", "-np", str(a.ranks), "/usr/bin/time", "-f", "RSS_kB %M user_s %U",
            a.driver, os.path.join(a.repo, "campaigns/table1_dispersed.toml"), "-o", out,
            "--set", f"ensemble.n_runs={a.runs}", "--set", "scene.mast.n_bays=2", "--progress", "none", *extra]


def journals(out):
    """Rank 0's journal and the part journals of every session: `out`.journal*."""
    d, name = os.path.split(os.path.abspath(out))
    return [os.path.join(d, f) for f in os.listdir(d) if f.startswith(name + ".journal")]


def journal_bytes(out):
    return sum(os.path.getsize(f) for f in journals(out) if os.path.exists(f))


def report(tag, p, wall, out):
    rss = [int(x) for x in re.findall(r"RSS_kB (\d+)", p.stderr)]
    line = [l for l in p.stderr.splitlines() if "wrote" in l]
    print(f"{tag}: exit {p.returncode}, wall {wall:.1f} s, peak RSS per rank {rss} kB, "
          f"file {os.path.getsize(out) / 1e6 if os.path.exists(out) else 0:.1f} MB")
    print(f"{tag}: {line[-1] if line else p.stderr[-500:]}")
    sys.stdout.flush()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--dir", required=True)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1_000_000)
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    ref, out = os.path.join(a.dir, "uninterrupted.h5"), os.path.join(a.dir, "killed.h5")
    for f in [ref, out, *journals(out)]:
        if os.path.exists(f):
            os.remove(f)
    t0 = time.time()
    p = subprocess.run(command(a, ref), env=ENV, capture_output=True, text=True)
    report("uninterrupted", p, time.time() - t0, ref)

    # kill -9 of the whole job once the journals hold 0.7 times the uninterrupted file's bytes: about
    # a third of the runs (a journal's records take about twice the compressed file's bytes).
    proc = subprocess.Popen(command(a, out), env=ENV, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    target = 0.7 * os.path.getsize(ref)
    t0 = time.time()
    while proc.poll() is None and journal_bytes(out) <= target:
        time.sleep(0.05)
    finished = proc.poll() is not None
    kill_job(proc)
    if finished:
        sys.exit("the campaign finished before the kill: nothing to resume")
    print(f"killed: kill -9 of the job after {time.time() - t0:.1f} s, journals {journal_bytes(out) / 1e6:.1f} MB, "
          f"temporary files {[f for f in os.listdir(a.dir) if '.tmp.' in f]}")
    t0 = time.time()
    p = subprocess.run(command(a, out, ["--resume"]), env=ENV, capture_output=True, text=True)
    report("resumed", p, time.time() - t0, out)
    print("resumed:", [l for l in p.stderr.splitlines() if "restored" in l or "removed" in l or "torn" in l])
    same, why = same_values(datasets(ref), datasets(out))
    print(f"resumed file equals the uninterrupted one: {same} {why}; "
          f"temporary files left: {[f for f in os.listdir(a.dir) if '.tmp.' in f or f.endswith('.journal')]}")


if __name__ == "__main__":
    main()
