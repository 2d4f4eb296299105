#!/usr/bin/python3
"""truss-campaign against hostile input and a failing machine: resource limits before
any work, messages that name the --set or the campaign line, one campaign at a time on an output,
a full disk while rank 0 writes the results, and the per-run wall-time cap.

  test_hostile_mpi.py --driver truss-campaign --repo SRC --scratch DIR
"""
import argparse
import fcntl
import os
import re
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import datasets, same_values  # noqa: E402

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def mpirun(args, ranks, extra):
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, *extra]
    return subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=300)


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print("  ok:", what)


def first_line(p):
    return (p.stderr.strip().splitlines() or [""])[0][:160]


def resources(args, d):
    """n_runs too large for memory: exit 2 before any work, the estimate in the message, no
    journal and no output (was: std::bad_alloc, exit 134, a journal that blocks the next start)."""
    camp = os.path.join(args.repo, "campaigns/bay_count.toml")
    out = os.path.join(d, "r.h5")
    p = mpirun(args, 2, [camp, "-o", out, "--set", "ensemble.n_runs=100000000000", "--progress", "none"])
    check(p.returncode == 2 and "in memory" in p.stderr and "bytes per run" in p.stderr
          and not os.path.exists(out + ".journal") and not os.path.exists(out),
          f"n_runs = 1e11: exit 2, '{first_line(p)}', nothing written")
    for sampling in ("monte_carlo", "sobol", "latin_hypercube", "saltelli"):
        p = mpirun(args, 2, [camp, "-o", out, "--set", "ensemble.n_runs=9223372036854775807",
                             "--set", f"ensemble.sampling={sampling}", "--progress", "none"])
        check(p.returncode == 2 and p.stderr.count("error:") == 1 and not os.listdir(d),
              f"n_runs = 2^63-1 with {sampling}: exit 2, '{first_line(p)}', nothing written")


def messages(args, d):
    """Each message names where the bad value came from."""
    camp = os.path.join(args.repo, "campaigns/table1_dispersed.toml")
    out = os.path.join(d, "m.h5")
    for s, words in (("campaign.name=1", "--set campaign.name=1: campaign.name"),
                     ("ensemble.n_run=5", "--set ensemble.n_run=5: unknown key"),
                     ("mast.frame_mass_kg=1e308", "--set mast.frame_mass_kg=1e308")):
        p = mpirun(args, 2, [camp, "-o", out, "--set", s])
        check(p.returncode == 2 and words in p.stderr, f"--set {s}: exit 2, '{first_line(p)}'")
    bad = os.path.join(d, "slash.toml")
    open(bad, "w").write('[ensemble]\nn_runs = 4\n\n[scene]\nfile = "/"\n')
    p = mpirun(args, 2, [bad, "-o", out])
    check(p.returncode == 2 and f"{bad}:5: scene.file" in p.stderr, f"file = \"/\": the campaign's line, '{first_line(p)}'")
    zero = os.path.join(d, "zero.toml")
    open(zero, "w").write('[ensemble]\nn_runs = 4\n[scene]\nfile = "/dev/zero"\n')
    p = mpirun(args, 2, [zero, "-o", out])
    check(p.returncode == 2 and "larger than the limit" in p.stderr, "scene file /dev/zero: bounded, exit 2")
    p = mpirun(args, 2, [camp, "-o", out, "--set", "drive.speed_m_per_s=100", "--set", "ensemble.n_runs=2",
                         "--progress", "none"])
    check("warning: --set drive.speed_m_per_s=100" in p.stderr and p.stderr.count("warning:") == 1,
          "plausibility warning printed once (rank 0)")
    for f in os.listdir(d):
        if not f.endswith(".toml"):
            os.remove(os.path.join(d, f))


def in_use(args, d):
    """One campaign at a time on an output (its lock, .NAME.lock): a held lock refuses a start,
    --force and --resume with exit 2 naming the holder, and nothing of the holder's is touched (its
    temporary file, its journal, its lock file); of two mpirun started at the same instant on one
    output, one writes the file (equal to an uninterrupted campaign's) and the other is refused so."""
    camp = os.path.join(args.repo, "campaigns/table1_dispersed.toml")
    out = os.path.join(d, "f.h5")
    lock = os.path.join(d, ".f.h5.lock")
    theirs = [os.path.join(d, ".f.h5.tmp.4242"), out + ".journal"]
    for t in theirs:
        open(t, "wb").write(b"a live session's")
    with open(lock, "w") as held:
        held.write("PID 4242 on testhost\n")
        held.flush()
        fcntl.flock(held, fcntl.LOCK_EX)  # what a running truss-campaign holds
        for extra in ([], ["--force"], ["--resume"]):
            p = mpirun(args, 2, [camp, "-o", out, *extra, "--progress", "none"])
            check(p.returncode == 2 and f"{out} is in use by another truss-campaign (PID 4242 on testhost" in p.stderr
                  and all(open(t, "rb").read() == b"a live session's" for t in theirs)
                  and open(lock).read() == "PID 4242 on testhost\n" and len(os.listdir(d)) == 3,
                  f"{' '.join(extra) or 'a start'} on a held output: exit 2, '{first_line(p)}', the holder's files as "
                  f"they were")
    for f in theirs + [lock]:
        os.remove(f)
    synthetic = ["--set", "ensemble.n_runs=300", "--synthetic-run-cost-s", "0.01", "--progress", "none"]
    ref = os.path.join(d, "ref.h5")
    check(mpirun(args, 2, [camp, "-o", ref, *synthetic]).returncode == 0, "an uninterrupted campaign")
    for trial in range(3):
        out = os.path.join(d, f"two{trial}.h5")
        cmd = ["mpirun", "--oversubscribe", "-np", "2", args.driver, camp, "-o", out, *synthetic]
        procs = [subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                 for _ in range(2)]
        res = sorted((p.wait(timeout=300), p.stderr.read()) for p in procs)
        left = sorted(f for f in os.listdir(d) if f.startswith(f".two{trial}.") or f.startswith(f"two{trial}."))
        same, why = same_values(datasets(ref), datasets(out)) if os.path.exists(out) else (False, "(none written)")
        # The loser names the winner by the PID the winner writes into the lock file right after
        # taking the lock; a loser that comes in between those two steps (seen under the sanitizers)
        # says the holder is just starting (results/lock_file.cpp).
        named = re.search(r"is in use by another truss-campaign \((PID \d+ on |a process that is just starting)",
                          res[1][1])
        check([rc for rc, _ in res] == [0, 2] and named and same and left == [f"two{trial}.h5"],
              f"two starts at once: exits {[rc for rc, _ in res]}, the loser '{res[1][1].splitlines()[0][:120]}', "
              f"the winner's file equals the uninterrupted one {why}, nothing else left {left}")


def tmpfs(path, size):
    """A tmpfs of `size` (mount's syntax) at path; False if this cannot be done here (not root)."""
    os.makedirs(path, exist_ok=True)
    return os.geteuid() == 0 and subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", path]).returncode == 0


def disk_full(args, d):
    """Rank 0's results file on a 1 MiB tmpfs (histories make it too large): exit 3, the system's
    reason, no crash (was: SIGSEGV in HDF5's exit-time cleanup), no temporary file left."""
    full = os.path.join(d, "full")
    if not tmpfs(full, "1m"):
        print("  skip: disk full (needs root and tmpfs)")
        return
    try:
        camp = os.path.join(args.repo, "campaigns/table1_dispersed.toml")
        out = os.path.join(full, "r.h5")
        p = mpirun(args, 2, [camp, "-o", out, "--set", "ensemble.n_runs=4", "--set", "output.history_runs=[0]",
                             "--set", "output.history_step_s=0.0001", "--progress", "none"])
        left = [f for f in os.listdir(full) if not f.startswith("r.h5.journal")]  # rank 0's and the parts
        check(p.returncode == 3 and "No space left on device" in p.stderr and not left,
              f"disk full on rank 0: exit {p.returncode} (3 expected), '{first_line(p)}', left {left}")
    finally:
        subprocess.run(["umount", full])


def disk_full_resume(args, d):
    """The disk fills while a campaign runs: rank 0 removes its temporary file before the job is
    aborted (the journal keeps the finished runs). Once the disk has room again, --resume removes
    the temporary files of killed sessions before its free-space check and counts the journal it
    keeps once: the disk is sized so that it has room for the campaign, but not for the journal
    twice or with a stale temporary file of 1 MiB. The resumed file equals an uninterrupted one's."""
    camp = os.path.join(args.repo, "campaigns/table1_dispersed.toml")
    # Synthetic runs' values do not compress: the file is about its estimate (/runs uncompressed), plus
    # /nominal, kept small by a coarse history step.
    synthetic = ["--set", "ensemble.n_runs=600", "--synthetic-run-cost-s", "0.01", "--progress", "none",
                 "--set", "output.history_step_s=0.1"]
    ref = os.path.join(d, "ref.h5")
    check(mpirun(args, 2, [camp, "-o", ref, *synthetic]).returncode == 0, "an uninterrupted campaign")
    disk = os.path.join(d, "disk")
    if not tmpfs(disk, "64k"):
        print("  skip: disk full (needs root and tmpfs)")
        return
    try:  # the journal's estimate, from the campaign's refusal on a disk too small
        p = mpirun(args, 2, [camp, "-o", os.path.join(disk, "r.h5"), *synthetic])
        sizes = re.findall(r"about ([0-9.]+) MiB", p.stderr)
    finally:
        subprocess.run(["umount", disk])
    check(p.returncode == 2 and len(sizes) == 2, f"the estimates: results file and journal {sizes} MiB")
    journal = float(sizes[1]) * 2**20
    # Room for the file and the journal, 1 % more (the estimates' 4 digits, the lock file, block rounding).
    if not tmpfs(disk, f"{int((os.path.getsize(ref) + journal) * 1.01 / 4096 + 2) * 4}k"):
        return
    try:
        out = os.path.join(disk, "r.h5")
        proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", "2", args.driver, camp, "-o", out, *synthetic],
                                env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        def journals_size():  # rank 0's journal and the parts of the ranks that build chunks
            return sum(os.path.getsize(os.path.join(disk, f)) for f in os.listdir(disk) if f.startswith("r.h5.journal"))
        while proc.poll() is None and journals_size() < 0.4 * journal:
            time.sleep(0.005)
        with open(os.path.join(disk, "filler"), "wb") as f:  # every free byte
            try:
                while True:
                    f.write(b"\0" * 65536)
                    f.flush()
            except OSError:
                pass
        err = proc.communicate(timeout=300)[1]
        left = sorted(os.listdir(disk))
        # Which write meets the full disk first decides how the session ends: rank 0's (it ends in
        # order and lets go of its lock) or a chunk owner's, journal or chunk bytes (that rank aborts
        # the job; rank 0, stopped by mpirun's SIGTERM, lets its lock go, or is killed first and the
        # lock file stays, held by no one, taken over by the next session). Either way the journals
        # (rank 0's and the part journal of rank 1, which owns every chunk on 2 ranks) stay and no
        # temporary file does.
        check(proc.returncode != 0 and "No space left on device" in err
              and [f for f in left if f != ".r.h5.lock"] == ["filler", "r.h5.journal", "r.h5.journal.0.1"],
              f"disk full mid-run: exit {proc.returncode}, '{err.strip().splitlines()[0][:120]}', left {left} (the "
              f"journals, perhaps the lock file of the aborted session: no temporary file)")
        os.remove(os.path.join(disk, "filler"))
        stale = os.path.join(disk, ".r.h5.tmp.999999")
        open(stale, "wb").write(b"\0" * 2**20)
        p = mpirun(args, 2, [camp, "-o", out, *synthetic, "--resume"])
        same, why = same_values(datasets(ref), datasets(out)) if p.returncode == 0 else (False, "")
        check(p.returncode == 0 and f"removed {stale}" in p.stderr and same and os.listdir(disk) == ["r.h5"],
              f"--resume: exit {p.returncode} ({first_line(p)}), the stale file removed, the file equals the "
              f"uninterrupted one {why}, nothing else left {os.listdir(disk)}")
    finally:
        subprocess.run(["umount", disk])


def wall_time(args, d):
    """max_run_wall_time_s holds in a campaign: a cap of 1 microsecond stops every run with the
    named status wall_time_limit (the runs need milliseconds), and the campaign completes."""
    camp = os.path.join(args.repo, "campaigns/table1_dispersed.toml")
    out = os.path.join(d, "w.h5")
    p = mpirun(args, 2, [camp, "-o", out, "--set", "ensemble.n_runs=6", "--set", "ensemble.max_run_wall_time_s=1e-6",
                         "--progress", "none"])
    check(p.returncode == 0, f"campaign with a tiny wall-time cap: exit 0 ({first_line(p)})")
    with h5py.File(out, "r") as f:
        names = [s.decode() for s in f["stats/status_names"][:]]
        status = f["runs/status"][:]
        msgs = [m.decode() if isinstance(m, bytes) else m for m in f["runs/message"][:]]
    w = [i for i, n in enumerate(names) if "wall" in n][0]
    check(np.all(status == w) and all("wall-time cap" in m for m in msgs), "every run: wall_time_limit with its reason")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    for case in (resources, messages, in_use, disk_full, disk_full_resume, wall_time):
        d = os.path.join(args.scratch, case.__name__)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        print(f"{case.__name__}:")
        case(args, d)
    print("passed")


if __name__ == "__main__":
    main()
