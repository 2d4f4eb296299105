#!/usr/bin/python3
"""truss-campaign under a real mpirun: reproducibility across rank counts, kill -9 and --resume,
statistics against an independent computation, failed runs, Saltelli indices and bad input.

  test_campaign_mpi.py --case NAME --driver truss-campaign --sim truss-sim --repo SRC --scratch DIR

Cases: ranks, resume, failures, saltelli, bad_input, transports (TCP and shared memory
without single-copy: identical bytes and scheduler efficiency), paths (only rank 0 needs the paths). Each case prints what it checked; any failed
check raises (exit 1).
"""
import argparse
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
import zlib

import h5py
import numpy as np

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def mpirun(args, ranks, extra=(), **kw):
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, *extra]
    return subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600, **kw)


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print("  ok:", what)


def datasets(path, skip=("timing",)):
    """Every dataset of the file outside `skip`, by path, as numpy values."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and name.split("/")[0] not in skip:
                out[name] = obj[()]
        f.visititems(visit)
    return out


def chunks(path, skip=("timing",)):
    """The stored (compressed) bytes and filter mask of every chunk of every chunked dataset of
    /runs and /timing outside `skip`, by path: what a writer of the file put there, before any
    reader's filters."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.chunks and name.split("/")[0] not in skip \
                    and obj.dtype.kind != "O":  # the messages' chunks hold global heap addresses
                ds = obj.id
                offsets = sorted(ds.get_chunk_info(k).chunk_offset for k in range(ds.get_num_chunks()))
                out[name] = [(o, ds.read_direct_chunk(o)) for o in offsets]
        f.visititems(visit)
    return out


def inflated_comparison(ma, ba, mb, bb):
    """Whether two deflated chunks (filter masks ma, mb: 0 = every filter applied) inflate to the
    same bytes: 'equal', 'differ', or why they were not compared."""
    if ma or mb:
        return "not compared (a filter skipped)"
    try:
        return "equal" if zlib.decompress(ba) == zlib.decompress(bb) else "differ"
    except zlib.error as e:
        return f"not compared (a chunk does not inflate: {e})"


def chunk_difference(a, b):
    """'' when the chunk maps a and b (of chunks()) are equal, else the first difference: the
    dataset, the chunk's offset, its filter masks and stored sizes, and whether the inflated bytes
    (what the filters give back) are equal."""
    if set(a) != set(b):
        return f"chunked dataset sets differ: {sorted(set(a) ^ set(b))}"
    for name in sorted(a):
        if len(a[name]) != len(b[name]):
            return f"{name}: {len(a[name])} chunks against {len(b[name])}"
        for (oa, (ma, ba)), (ob, (mb, bb)) in zip(a[name], b[name]):
            if (oa, ma, ba) != (ob, mb, bb):
                first = next((i for i, (x, y) in enumerate(zip(ba, bb)) if x != y), min(len(ba), len(bb)))
                return (f"{name} chunk at {oa} / {ob}: masks {ma} / {mb}, {len(ba)} / {len(bb)} bytes stored, "
                        f"first differing byte {first}, inflated bytes {inflated_comparison(ma, ba, mb, bb)}")
    return ""


def cpu_model():
    with open("/proc/cpuinfo") as fh:
        return next((line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")), "unknown CPU")


def reencoding(tool, *paths):
    """'' when every deflated chunk of each file encodes again, in a fresh process
    (truss_reencode_chunks), to the bytes the file stores; else, per file, what differs, and the CPU.
    Of two files with equal values and a differing chunk, it names the one whose chunk is not what
    the codec writes."""
    said = []
    for path in paths:
        p = subprocess.run([tool, path], capture_output=True, text=True)
        if p.returncode != 0:
            said.append(f"{os.path.basename(path)}: {' / '.join(p.stdout.strip().splitlines()[-3:]) or p.stderr.strip()}")
    return f"{'; '.join(said)} (CPU: {cpu_model()})" if said else ""


def file_difference(ref, out, tool=None):
    """'' when the files' chunks are equal (chunk_difference), else the difference and, given the
    re-encoding tool, which file's chunks re-encode to their stored bytes."""
    diff = chunk_difference(chunks(ref), chunks(out))
    if diff and tool:
        diff += f"; re-encoded in a fresh process: {reencoding(tool, ref, out) or 'both files re-encode to their bytes'}"
    return diff


def same_values(a, b):
    if set(a) != set(b):
        return False, f"dataset sets differ: {sorted(set(a) ^ set(b))}"
    for k in a:
        x, y = np.asarray(a[k]), np.asarray(b[k])
        if x.dtype.kind == "f":
            # Bit for bit: compare the bytes, so that -0.0 / 0.0 and NaN payloads count too.
            eq = x.shape == y.shape and x.tobytes() == y.tobytes()
        else:
            eq = x.shape == y.shape and np.array_equal(x, y)
        if not eq:
            return False, f"{k} differs"
    return True, ""


def descendants(pid):
    children = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = open(f"/proc/{d}/stat").read()
            except OSError:
                continue
            ppid = int(stat[stat.rindex(")") + 2:].split()[1])
            children.setdefault(ppid, []).append(int(d))
    out, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def alive(pid):
    try:
        state = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0]
        return state != "Z"
    except OSError:
        return False


def kill_job(proc):
    """kill -9 of a whole job: mpirun and every rank (Open MPI puts the ranks in their own process
    groups, and a SIGKILLed mpirun cannot take them down); returns once none is alive."""
    job = [proc.pid] + descendants(proc.pid)
    for pid in job:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    proc.wait()
    while any(alive(pid) for pid in job[1:]):
        time.sleep(0.01)


def fresh(args, name):
    d = os.path.join(args.scratch, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


TABLE1 = "campaigns/table1_dispersed.toml"


# ----------------------------------------------------------------------------------------------
def case_ranks(args):
    """Same /runs, /stats, /histories with 1 and 3 (oversubscribed) ranks; stats recomputed."""
    d = fresh(args, "ranks")
    camp = os.path.join(args.repo, TABLE1)
    sets = ["--set", "ensemble.n_runs=90", "--set", "output.history_runs=[0, 7]", "--set", "output.history_step_s=0.05"]
    outs = {}
    for n in (1, 3):
        outs[n] = os.path.join(d, f"r{n}.h5")
        p = mpirun(args, n, [camp, "-o", outs[n], *sets, "--progress", "lines", "--progress-interval", "0.01"])
        check(p.returncode == 0, f"{n} rank(s): exit 0 ({p.stderr.strip()[-300:]})")
        check("runs/s" in p.stderr, f"{n} rank(s): progress lines with a rate on stderr")
        check(not os.path.exists(outs[n] + ".journal"), f"{n} rank(s): journal removed after the file is written")
    a, b = datasets(outs[1]), datasets(outs[3])
    same, why = same_values(a, b)
    check(same, f"1 and 3 ranks give identical datasets outside /timing ({len(a)} datasets) {why}")
    with h5py.File(outs[3], "r") as f:
        check(f.attrs["n_ranks"] == 3 and f.attrs["schema_version"] == 3 and f.attrs["kind"] == "campaign"
              and f.attrs["n_rounds"] == 1 and not f["runs/round"][:].any(),
              "root attributes: n_ranks, schema_version, kind, one round (every /runs/round 0)")
        check(set(np.unique(f["timing/rank"][:])) == {0, 1, 2}, "all 3 ranks computed runs (dynamic scheduling)")
        missing = []
        f.visititems(lambda n, o: missing.append(n) if isinstance(o, h5py.Dataset) and not o.attrs.get("units") else None)
        check(not missing, f"every dataset has a units attribute (missing: {missing[:5]})")
        check("histories/run_7/t_s" in f and np.all(np.diff(f["histories/run_7/t_s"][:]) > 0),
              "history of run 7 stored, time increasing")
        check_stats(f)
        check_final_progress(p.stderr, f, "3 ranks")
    check_nominal(args, d, outs[3])
    check_statistics_ranks(args, d, camp)
    check("[truss-campaign] campaign" in p.stderr and "design values" in p.stderr and " ok" in p.stderr,
          "start banner, outcomes by status name and end summary with design values on stderr")
    # 90 ok runs: every P99.865 of the summary is flagged as standing on too few runs (an upper 95 %
    # bound needs n with 1 - 0.99865^n >= 0.95, n >= 2218).
    flagged = [ln for ln in p.stderr.splitlines() if "P99.865" in ln and "nominal" in ln]
    check(len(flagged) == 6 and all("from 90 ok runs: too few for a P99.865 (its 95 % bound needs 2218)" in ln
                                    for ln in flagged),
          f"end summary: each P99.865 from 90 runs flagged as too few ({flagged[:1]})")


def check_statistics_ranks(args, d, camp):
    """The statistics merged by 1, 2 and 3 ranks (--statistics-ranks, each a range of the columns)
    against one rank merging them all: the same values and stored chunks, /stats equal to numpy's,
    and /timing says how many merged."""
    sets = ["--set", "ensemble.n_runs=3000", "--progress", "none"]
    ref = os.path.join(d, "s_ref.h5")
    p = mpirun(args, 1, [camp, "-o", ref, *sets])
    check(p.returncode == 0, f"3,000 runs on 1 rank: exit 0 ({p.stderr.strip()[-200:]})")
    for n in (1, 2, 3):
        out = os.path.join(d, f"s{n}.h5")
        p = mpirun(args, 4, [camp, "-o", out, *sets, "--statistics-ranks", str(n)])
        check(p.returncode == 0, f"4 ranks, {n} statistics rank(s): exit 0 ({p.stderr.strip()[-200:]})")
        same, why = same_values(datasets(ref), datasets(out))
        diff = file_difference(ref, out, args.reencode)
        check(same and not diff, f"4 ranks, {n} statistics rank(s): the 1-rank file's values and chunks {why}{diff}")
        with h5py.File(out, "r") as f:
            t = f["timing"].attrs
            check(int(t["statistics_ranks"]) == n and float(t["stats_merge_cpu_s"]) > 0,
                  f"/timing: statistics_ranks {int(t['statistics_ranks'])}, stats_merge_cpu_s {float(t['stats_merge_cpu_s']):.4f}")
            if n == 3:
                check_stats(f)


def check_final_progress(stderr, f, what):
    """The last progress line (rank 0's count of the runs computed, from the workers' status counts
    per batch and its own runs) against the file's runs: every run counted once, by status name,
    in the file's status order."""
    names = [s.decode() for s in f["stats/status_names"][:]]
    counts = f["stats/status_counts"][:]
    n = int(f.attrs["n_runs"])
    want = ", ".join(f"{c} {name}" for name, c in zip(names, counts) if c)
    lines = [ln for ln in stderr.splitlines() if "runs/s, done in" in ln]
    m = re.match(r"\[truss-campaign\] (\d+)/(\d+) runs \(100\.0 %\): (.*); \d+ runs/s, done in", lines[-1]) \
        if lines else None
    check(m is not None and int(m.group(1)) == n == int(m.group(2)) and m.group(3) == want,
          f"{what}: the final progress line counts every run by status ({lines[-1:]} against {n}: {want})")


def check_nominal(args, d, path):
    """/nominal against truss-sim run on the file's own base_scene_toml (the single-run program, a
    separate code path): every scalar but wall time, the per-bay values and the history, bit for bit
    (same scene, same code, one process each)."""
    with h5py.File(path, "r") as f:
        scene = os.path.join(d, "base_scene.toml")
        with open(scene, "w") as fh:
            fh.write(f.attrs["base_scene_toml"] if isinstance(f.attrs["base_scene_toml"], str)
                     else f.attrs["base_scene_toml"].decode())
        step = float(f["histories"].attrs["step_s"])
        single = os.path.join(d, "nominal_single.h5")
        p = subprocess.run([args.sim, scene, "-o", single, "--force", "--set", f"run.output_step_s={step}",
                            "--set", "run.max_wall_time_s=10"], capture_output=True, text=True, timeout=300)
        check(p.returncode == 0, f"truss-sim runs the base scene ({p.stderr.strip()[-200:]})")
        n = f["nominal"]
        with h5py.File(single, "r") as g:
            scal = [k for k in g["summary"] if k not in ("wall_time_s",)]
            bad = [k for k in scal if k not in n or np.asarray(n[k][()]).tobytes() != np.asarray(g["summary"][k][()]).tobytes()]
            check(not bad, f"/nominal holds the {len(scal)} summary fields of truss-sim on base_scene_toml ({bad[:4]})")
            nb = int(g["summary/n_bays"][()])
            badb = [k for k in g["bays"] if k != "bay" and not np.array_equal(n["bays"][k][:nb], g["bays"][k][:], equal_nan=True)]
            check(not badb, f"/nominal/bays equal to truss-sim's /bays ({badb[:4]})")
            badh = [k for k in g["history"] if not np.array_equal(n["history"][k][:], g["history"][k][:])]
            check(not badh, f"/nominal/history equal to truss-sim's /history ({badh[:4]})")
            check("wall_time_s" not in n, "/nominal has no wall time (not reproducible)")


def check_stats(f, streamed=True):
    """Every /stats entry against numpy on the ok runs of /runs. streamed: the campaign's runs are
    draws, and every statistic was streamed while they arrived; else (subset simulation's chains,
    whose values drift with the run index) the percentiles of some columns were read back from the
    file at the end, the per-bay ones in groups of columns (results/summary_h5.cpp)."""
    status = f["runs/status"][:]
    ok = status == 0
    names = [s.decode() for s in f["stats/status_names"][:]]
    counts = f["stats/status_counts"][:]
    for i, nm in enumerate(names):
        assert counts[i] == np.count_nonzero(status == i), nm
    check(f["stats"].attrs["n_failed"] == np.count_nonzero(~ok), "status counts and n_failed match /runs/status")
    pct = {"p1": 1, "p5": 5, "p50": 50, "p95": 95, "p99": 99, "p99_865": 99.865}
    n_checked = 0

    def compare(stats_group, x):
        nonlocal n_checked
        x = x[np.isfinite(x)]
        g = stats_group
        assert g["count"][()] == x.size, g.name
        if x.size == 0:
            assert np.isnan(g["mean"][()]), g.name
            return
        # Percentiles, min and max pick or interpolate the same order statistics with the same
        # formula as numpy: equal to the last bit. Mean and std differ only by summation order
        # (numpy sums pairwise): a relative 1e-12 is thousands of times that rounding for n < 1e5.
        for k, q in pct.items():
            assert g[k][()] == np.percentile(x, q), (g.name, k, g[k][()], np.percentile(x, q))
        assert g["min"][()] == x.min() and g["max"][()] == x.max(), g.name
        # For the std, rounding of the mean leaves ~eps |mean| of noise: an absolute floor of
        # 1e-12 |mean| covers constant columns (std 0 up to that noise).
        assert np.isclose(g["mean"][()], x.mean(), rtol=1e-12, atol=0), g.name
        if x.size > 1:
            assert np.isclose(g["std"][()], x.std(ddof=1), rtol=1e-10, atol=1e-12 * abs(x.mean())), g.name
        n_checked += 1

    for k, ds in f["runs"].items():
        # A sweep's design value is the run's label, not an output: no statistics.
        if isinstance(ds, h5py.Dataset) and ds.dtype.kind == "f" and k != "sweep_value":
            compare(f["stats"][k], ds[:][ok])
    nb = f.attrs["n_bays_max"]
    for k, ds in f["runs/bays"].items():
        allv = ds[:][ok]
        for j in range(nb):
            class Row:  # the j-th entry of each per-bay statistic
                name = f"/stats/bays/{k}[{j}]"
                def __getitem__(self, key, k=k, j=j):
                    return f["stats/bays"][k][key][j:j + 1].reshape(())
            compare(Row(), allv[:, j])
    check(n_checked > 50, f"{n_checked} statistics equal numpy's on the ok runs (percentiles exactly)")
    # The statistics were streamed while the runs arrived: no column had to be read back at the
    # end (the read-back is the exact fallback for a column that drifts with the run index).
    rb = int(f["timing"].attrs["stats_columns_read_back"])
    if streamed:
        check(rb == 0, f"/stats streamed: {rb} columns read back at the end")
    else:
        check(rb > 0, f"/stats: {rb} columns read back at the end")


# ----------------------------------------------------------------------------------------------
def case_resume(args):
    """kill -9 of the whole job mid-campaign, a torn record, then --resume: same file as an
    uninterrupted campaign, finished runs not recomputed."""
    d = fresh(args, "resume")
    camp = os.path.join(args.repo, TABLE1)
    # Real runs that integrate (the motor drive, about 1.3 ms each; the velocity drive's closed form
    # takes 20 us, and 5,000 such runs ended 0.3 s after the start, before the poller below could
    # see a flush under CI's load). 4,000 runs put ~19 MB of records on disk in ~2.5 s on 2 ranks,
    # so the kill at ~2 MB comes ~0.3 s into the computing, after ~30 flush intervals. Under the
    # sanitizer stage (scripts/sanitize.sh sets TRUSS_SANITIZED=1) every run costs ~10x: 1,500 runs.
    n = 1500 if os.environ.get("TRUSS_SANITIZED") else 4000
    sets = ["--set", f"ensemble.n_runs={n}", "--set", "drive.mode=motor"]
    ref = os.path.join(d, "ref.h5")
    t_ref = time.time()
    p = mpirun(args, 2, [camp, "-o", ref, *sets, "--progress", "none"])
    t_ref = time.time() - t_ref
    check(p.returncode == 0, "uninterrupted campaign on 2 ranks")

    out = os.path.join(d, "killed.h5")
    journal = out + ".journal"
    part = out + ".journal.0.1"  # rank 1's: on 2 ranks it owns every chunk, so it journals every record
    cmd = ["mpirun", "--oversubscribe", "-np", "2", args.driver, camp, "-o", out, *sets,
           "--flush-interval", "0.01", "--progress", "none"]
    proc = subprocess.Popen(cmd, env=ENV, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.time()
    # Kill once ~2 MB of records (~400 runs of ~4.7 kB) are on disk, well before the end.
    seen = []  # rank 0's journal sizes observed while the job runs
    while time.time() - t0 < 120:
        if os.path.exists(journal):
            seen.append(os.path.getsize(journal))
            if os.path.exists(part) and os.path.getsize(part) > 2_000_000:
                break
        time.sleep(0.01)
    running = proc.poll() is None
    t_kill = time.time() - t0
    kill_job(proc)
    check(not os.path.exists(out), "killed job left no results file")
    check(os.path.exists(journal) and os.path.exists(part), "killed job left its journal and rank 1's part")
    # Rank 0's journal grows while runs are still being computed, by the periodic flush: rank 0
    # appends a heartbeat frame and writes its buffer out every flush interval (the final sync comes
    # after the last run). A size seen while the job ran that ends a heartbeat frame was such a
    # flush. This holds however late the poller was scheduled (the CPU share of a poller beside two
    # busy ranks, under ctest -j2, is not guaranteed).
    from test_journal_faults import parse_journal  # the format parsed independently (imports this module)
    with open(journal, "rb") as fh:
        ends = {at + 9 + len(pl): kind for at, kind, pl in parse_journal(fh.read())[1]}
    beats = sorted({x for x in seen if ends.get(x) == b"H"})
    check(running and beats,
          f"journal flushed while computing: {len(beats)} heartbeat flushes seen (last at {beats[-1] if beats else 0} "
          f"bytes), job {'still running' if running else 'finished'} at the kill after {t_kill:.2f} s "
          f"(uninterrupted: {t_ref:.2f} s)")
    with open(part, "ab") as j:
        j.write(b"R\x10\x00\x00\x00torn")  # a frame cut short by the crash
    size = os.path.getsize(journal)

    p = mpirun(args, 3, [camp, "-o", out, "--resume"])
    check(p.returncode == 2 and "different campaign" in p.stderr and os.path.getsize(journal) == size,
          f"exit {p.returncode}, journal {size} -> {os.path.getsize(journal)} bytes; "

          f"--resume with another campaign (n_runs differs) refused with exit 2, journal untouched ({p.stderr.strip()[:200]})")
    p = mpirun(args, 3, [camp, "-o", out, *sets])
    check(p.returncode == 2 and "--resume" in p.stderr, "a new start over an unfinished journal refused with exit 2")

    p = mpirun(args, 3, [camp, "-o", out, *sets, "--resume", "--progress", "none"])
    check(p.returncode == 0, f"--resume on 3 ranks finishes ({p.stderr.strip()[-300:]})")
    check("torn last record dropped" in p.stderr, "the torn record was detected and dropped")
    same, why = same_values(datasets(ref), datasets(out))
    check(same, f"resumed file equals the uninterrupted one, value for value {why}")
    diff = file_difference(ref, out, args.reencode)
    check(not diff, f"and chunk for chunk: the same compressed bytes {diff}")
    bad = reencoding(args.reencode, ref, out)
    check(not bad, f"every chunk of both files encoded again in another process gives its stored bytes {bad}")
    with h5py.File(out, "r") as f:
        sess = f["timing/session"][:]
        restored = np.count_nonzero(sess == 0)
        check(f.attrs["n_sessions"] == 2 and 0 < restored < 0.8 * n and np.count_nonzero(sess == 1) == n - restored,
              f"{restored} runs kept from the first session, {n - restored} computed after the resume")
        check(f"{restored} of {n} runs restored" in p.stderr, "the resume reports how many runs it restored")
    # Restored chunks are written as they complete, not held: rank 0's memory stays a few chunks
    # (test_collector.cpp restores many chunks' worth).
    m = re.search(r"at most (\d+) chunks of (\d+) runs in a rank's memory", p.stderr)
    check(m and int(m.group(1)) <= 4, f"at most {m.group(1) if m else '?'} chunks of runs in memory")
    p = mpirun(args, 2, [camp, "-o", out, *sets, "--resume"])
    check(p.returncode == 2 and "finished" in p.stderr, "--resume of a finished campaign refused with exit 2")
    before = open(out, "rb").read()
    p = mpirun(args, 2, [camp, "-o", out, *sets])
    check(p.returncode == 2 and "exists" in p.stderr and open(out, "rb").read() == before,
          "existing results file kept without --force (exit 2)")
    check_resume_memory(args, d)


def check_resume_memory(args, d):
    """A resume that restores many complete chunks holds a few at a time: rank 0 replays the
    journals before the other ranks join, so it must merge the restored chunks' statistics itself
    and write each chunk as it completes (merged on rank 1, each restored chunk would wait in
    rank 0's memory for windows no one sends until the replay ends)."""
    out = os.path.join(d, "many.h5")
    part = out + ".journal.0.1"
    # Closed-form runs of the 2-bay mast (velocity drive, ~20 us each, records of ~780 bytes):
    # chunks of 4,096 runs; the kill once 12 chunks' records are on disk (~38 MB), about a quarter
    # of the campaign (half under the sanitizers, where runs cost ~10 times more).
    n = 100_000 if os.environ.get("TRUSS_SANITIZED") else 200_000
    kill_bytes = 12 * 4096 * 780
    sets = ["--set", f"ensemble.n_runs={n}", "--set", "scene.mast.n_bays=2", "--progress", "none"]
    proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", "2", args.driver, os.path.join(args.repo, TABLE1),
                             "-o", out, *sets], env=ENV, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    t0 = time.time()
    while proc.poll() is None and time.time() - t0 < 300 and not (
            os.path.exists(part) and os.path.getsize(part) > kill_bytes):
        time.sleep(0.01)
    running = proc.poll() is None
    kill_job(proc)
    check(running, f"job killed while running, rank 1's part journal at {os.path.getsize(part) / 1e6:.1f} MB")
    p = mpirun(args, 2, [os.path.join(args.repo, TABLE1), "-o", out, *sets, "--resume"])
    check(p.returncode == 0, f"--resume finishes ({p.stderr.strip()[-300:]})")
    r = re.search(r"(\d+) of \d+ runs restored", p.stderr)
    m = re.search(r"at most (\d+) chunks of (\d+) runs in a rank's memory", p.stderr)
    restored_chunks = int(r.group(1)) // 4096 if r else 0
    check(restored_chunks >= 10, f"{restored_chunks} complete chunks restored")
    check(m and int(m.group(2)) == 4096 and int(m.group(1)) <= 8,
          f"at most {m.group(1) if m else '?'} chunks in a rank's memory (a bound of 8: two owners' open chunks "
          f"and backlogs), not the {restored_chunks} restored")


# ----------------------------------------------------------------------------------------------
def case_failures(args):
    """Motor campaign with stalls: failed runs are rows with status and reason, statistics count
    ok runs only, and a stalled row's recorded inputs stall truss-sim too."""
    d = fresh(args, "failures")
    camp = os.path.join(args.repo, "campaigns/motor_torque.toml")
    out = os.path.join(d, "motor.h5")
    p = mpirun(args, 2, [camp, "-o", out, "--set", "ensemble.n_runs=400", "--set", "ensemble.stop=false",
                         "--progress", "lines"])
    check(p.returncode == 0, "motor campaign with stalls exits 0 (failed runs are data)")
    with h5py.File(out, "r") as f:
        status = f["runs/status"][:]
        names = {v: k for k, v in h5py.check_enum_dtype(f["runs/status"].dtype).items()}
        n_stall = np.count_nonzero(status == [k for k, v in names.items() if v == "stall"][0])
        check(0 < n_stall < 400 and np.count_nonzero(status != 0) == n_stall, f"{n_stall} of 400 runs stalled, the rest ok")
        msgs = f["runs/message"].asstr()[:]
        check(all(m.startswith("stall:") for m in msgs[status != 0]) and all(m == "" for m in msgs[status == 0]),
              "every failed row has its reason, ok rows none")
        check(np.all(np.isnan(f["runs/deploy_time_s"][:][status != 0])), "stalled rows have no deployment time (NaN)")
        check(f["stats/deploy_time_s/count"][()] == 400 - n_stall, "statistics count the ok runs only")
        last = [ln for ln in p.stderr.splitlines() if "wrote" in ln][-1]
        check(f"{n_stall} stall" in last and "failed" not in last,
              "the final line counts the stalls by name, not as 'failed'")
        stall_torque = f["runs/inputs/drive.stall_torque_Nm"][:]
        speed = f["runs/inputs/drive.no_load_speed_rad_per_s"][:]
        check(stall_torque[status != 0].max() < stall_torque[status == 0].min(),
              "every stalled run had a weaker motor than every ok run (the stall is physical)")
        check_stats(f)
        check_final_progress(p.stderr, f, "stalls on 2 ranks")
        i = int(np.flatnonzero(status != 0)[0])
        j = int(np.flatnonzero(status == 0)[0])
    # A wall-time cap far below a motor run's cost: runs are stopped and recorded, the campaign goes on.
    capped = os.path.join(d, "capped.h5")
    p = mpirun(args, 2, [camp, "-o", capped, "--set", "ensemble.n_runs=12", "--set", "ensemble.max_run_wall_time_s=0.0002",
                         "--progress", "none"])
    check(p.returncode == 0, "campaign whose runs exceed the wall-time cap completes")
    with h5py.File(capped, "r") as f:
        names = [s.decode() for s in f["stats/status_names"][:]]
        counts = dict(zip(names, f["stats/status_counts"][:]))
        msgs = f["runs/message"].asstr()[:][f["runs/status"][:] == names.index("wall-time limit")]
        check(counts["wall-time limit"] > 0 and all("wall-time cap of 0.0002 s" in m for m in msgs),
              f"runs stopped by the cap are recorded as 'wall-time limit' with the reason ({counts['wall-time limit']} of 12)")
    scene = os.path.join(args.repo, "campaigns/scenes/table1.toml")
    for run, expect in ((i, "stall"), (j, "ok")):
        r = subprocess.run([args.sim, scene, "--json", "--set", "drive.mode=motor",
                            "--set", f"drive.stall_torque_Nm={stall_torque[run]!r}",
                            "--set", f"drive.no_load_speed_rad_per_s={speed[run]!r}"], capture_output=True, text=True)
        check(f'"status": "{expect}"' in r.stdout, f"run {run} rerun alone with truss-sim from its recorded inputs: {expect}")


# ----------------------------------------------------------------------------------------------
SALTELLI = """
[campaign]
name = "saltelli-test"
[ensemble]
n_runs = 160
master_seed = 3
sampling = "saltelli"
[scene.mast]
n_bays = 6
[[dispersion]]
key = "mast.strut_mass_kg"
per = "bay"
distribution = "normal"
std = 0.05
[[dispersion]]
key = "drive.speed_m_per_s"
apply = "relative"
distribution = "uniform"
lower = -0.2
upper = 0.2
"""


def case_saltelli(args):
    """Saltelli design (one factor per dispersion) and Sobol' indices against the estimators."""
    d = fresh(args, "saltelli")
    camp = os.path.join(d, "saltelli.toml")
    open(camp, "w").write(SALTELLI)
    out = os.path.join(d, "s.h5")
    p = mpirun(args, 2, [camp, "-o", out, "--progress", "none"])
    check(p.returncode == 0, f"saltelli campaign runs ({p.stderr.strip()[-300:]})")
    with h5py.File(out, "r") as f:
        G, block = 2, 4
        m = f["runs/inputs/mast.strut_mass_kg"][:]
        v = f["runs/inputs/drive.speed_m_per_s"][:]
        A, B = slice(0, None, block), slice(1, None, block)
        check(np.array_equal(m[2::block], m[B]) and np.array_equal(v[2::block], v[A]),
              "AB_1 rows: strut masses (all bays) from B, speed from A")
        check(np.array_equal(m[3::block], m[A]) and np.array_equal(v[3::block], v[B]),
              "AB_2 rows: strut masses from A, speed from B")
        factors = [s.decode() for s in f["sensitivity/factor"][:]]
        check(factors == ["mast.strut_mass_kg", "drive.speed_m_per_s"], "factors are the dispersions")
        y = f["runs/peak_drive_force_N"][:].reshape(-1, block)
        y = y - np.mean(y[:, :2])  # outputs centred by the mean of f(A) and f(B), as SALib does
        fa, fb = y[:, 0], y[:, 1]
        V = np.var(np.concatenate([fa, fb]))
        s1 = [np.mean(fb * (y[:, 2 + i] - fa)) / V for i in range(G)]
        st = [np.mean((fa - y[:, 2 + i]) ** 2) / 2 / V for i in range(G)]
        g = f["sensitivity/peak_drive_force_N"]
        # Same estimators on the same numbers; only the summation order differs.
        check(np.allclose(g["first_order"][:], s1, rtol=1e-9, atol=1e-12) and np.allclose(g["total"][:], st, rtol=1e-9, atol=1e-12),
              f"first-order {np.round(s1, 3)} and total {np.round(st, 3)} indices match the Saltelli/Jansen estimators")
        check(np.all(g["first_order_lo"][:] <= g["first_order"][:] + 1e-12) and np.all(g["total_hi"][:] >= g["total"][:] - 1e-12),
              "bootstrap intervals bracket the estimates")
        check(st[1] > st[0], "the drive speed matters more than the strut masses for the peak drive force")
    p = mpirun(args, 1, [camp, "-o", os.path.join(d, "bad.h5"), "--set", "ensemble.n_runs=150"])
    check(p.returncode == 2 and "multiple of 4" in p.stderr, "saltelli n_runs not a multiple of the block: exit 2")


# ----------------------------------------------------------------------------------------------
BAD = {
    "unknown_key": ("[ensemble]\nn_runs = 10\nrepeats = 3\n", ":3:", "unknown key"),
    "unknown_table": ("[ensemble]\nn_runs = 10\n[montecarlo]\nx = 1\n", ":3:", "unknown table"),
    "unknown_scene_key": ("[ensemble]\nn_runs = 10\n[[dispersion]]\nkey = \"mast.strut_colour\"\ndistribution = \"normal\"\nstd = 0.1\n",
                          ":3:", "mast.strut_colour"),
    "impossible_distribution": ("[ensemble]\nn_runs = 10\n[[dispersion]]\nkey = \"mast.strut_mass_kg\"\nper = \"bay\"\n"
                                "distribution = \"normal\"\nstd = -0.1\n", ":3:", "std: must be > 0"),
    "negative_count": ("[ensemble]\nn_runs = -5\n", ":2:", "n_runs"),
    "empty_truncation": ("[ensemble]\nn_runs = 10\n[[dispersion]]\nkey = \"rail.x_m\"\napply = \"offset\"\n"
                         "distribution = \"truncated_normal\"\nstd = 0.001\nlower = 1.0\nupper = 2.0\n", ":3:", "excludes all"),
    "inline_scene_key": ("[ensemble]\nn_runs = 10\n[scene.mast]\nn_bays = 6\nstrut_lenght_m = 0.2\n", ":5:", "strut_lenght_m"),
    "inline_scene_value": ("[ensemble]\nn_runs = 10\n[scene.mast]\nn_bays = -6\n", ":4:", "n_bays"),
    "toml_syntax": ("[ensemble\nn_runs = 10\n", ":1:", ""),
    # Implausible dispersions, refused before any run (they would end most runs as invalid input):
    # a percentage typed as a fraction (std = 2: 200 %), and millimetres typed as metres.
    "percent_as_fraction": ("[ensemble]\nn_runs = 300\n[[dispersion]]\nkey = \"mast.strut_mass_kg\"\nper = \"bay\"\n"
                            "apply = \"relative\"\ndistribution = \"normal\"\nstd = 2\n", ":3:",
                            "mast.strut_mass_kg (relative normal) is implausible"),
    "millimetres_as_metres": ("[ensemble]\nn_runs = 300\n[[dispersion]]\nkey = \"mast.frame_side_m\"\nper = \"frame\"\n"
                              "apply = \"offset\"\ndistribution = \"uniform\"\nlower = -0.5\nupper = 0.5\n", ":3:",
                              "mast.frame_side_m (offset uniform) is implausible"),
    # Millimetres typed as metres on a diagonal's free length: every draw a scene the model takes,
    # but the length moved by up to 64 % of its nominal; the message gives the value it would be.
    "mm_as_m_free_length": ("[ensemble]\nn_runs = 300\n[[dispersion]]\nkey = \"mast.diagonal_free_length_m\"\n"
                            "apply = \"offset\"\ndistribution = \"uniform\"\nlower = -0.3\nupper = 0.3\n", ":3:",
                            "its lower end, a draw of -0.3, gives mast.diagonal_free_length_m = "),
    # A failure margin the drive mode never computes: NaN in every run, nothing would ever fail.
    "margin_never_computed": ("[ensemble]\nmethod = \"subset\"\n[failure]\nmargin = \"motor_torque_margin_Nm\"\n"
                              "[scene]\noverrides = { \"drive.mode\" = \"motor\" }\n[[dispersion]]\n"
                              "key = \"drive.stall_torque_Nm\"\ndistribution = \"normal\"\nstd = 0.05\n", ":4:",
                              "failure.margin: \"motor_torque_margin_Nm\" is defined only with drive.mode = \"velocity\""),
}


def case_bad_input(args):
    """Each class of bad campaign file: exit 2 on every rank, file:line and key, reported once,
    nothing written."""
    d = fresh(args, "bad")
    for name, (text, line, words) in BAD.items():
        camp = os.path.join(d, f"{name}.toml")
        open(camp, "w").write(text)
        out = os.path.join(d, f"{name}.h5")
        p = mpirun(args, 3, [camp, "-o", out])
        msg = p.stderr.strip()
        check(p.returncode == 2 and f"{camp}{line}" in msg and words in msg and msg.count("error:") == 1
              and not os.path.exists(out) and not os.path.exists(out + ".journal"),
              f"{name}: exit 2, '{msg.splitlines()[0][:150]}', nothing written")
    for name in ("mm_as_m_free_length", "margin_never_computed"):  # refused by --dry-run as by the run
        p = mpirun(args, 1, [os.path.join(d, f"{name}.toml"), "--dry-run"])
        check(p.returncode == 2 and BAD[name][2] in p.stderr and p.stdout == "",
              f"{name}: --dry-run exits 2 with the same message, prints nothing")
    p = mpirun(args, 2, [os.path.join(args.repo, TABLE1), "-o", os.path.join(d, "x.h5"), "--set", "ensemble.n_runz=3"])
    check(p.returncode == 2 and "n_runz" in p.stderr, "unknown --set key: exit 2")
    p = mpirun(args, 2, [os.path.join(d, "missing.toml"), "-o", os.path.join(d, "x.h5")])
    check(p.returncode == 2 and "missing.toml" in p.stderr, "missing campaign file: exit 2")
    p = mpirun(args, 2, [os.path.join(args.repo, TABLE1), "-o", os.path.join(d, "no_dir", "x.h5")])
    check(p.returncode == 2 and "does not exist" in p.stderr, "output directory missing: exit 2")
    p = mpirun(args, 2, [os.path.join(args.repo, TABLE1), "-o", os.path.join(d, "x.h5"), "--resume"])
    check(p.returncode == 2 and "no journal" in p.stderr, "--resume without a journal: exit 2")
    p = mpirun(args, 3, [os.path.join(args.repo, TABLE1), "-o", os.path.join(d, "x.h5"), "--statistics-ranks", "3"])
    check(p.returncode == 2 and "--statistics-ranks" in p.stderr and "at most 2" in p.stderr
          and p.stderr.count("at most 2") == 1,
          f"--statistics-ranks 3 on 3 ranks: exit 2, said once ({p.stderr.strip()[-160:]})")
    # A file-size limit (ulimit -f) below the journal's size: refused before any run. (Open MPI's
    # PMIx needs PMIX_MCA_gds=hash to start at all under such a limit: docs/campaigns.md.)
    def limit_file_size():
        resource.setrlimit(resource.RLIMIT_FSIZE, (100 * 1024, 100 * 1024))
    p = subprocess.run(["mpirun", "--oversubscribe", "-np", "2", args.driver, os.path.join(args.repo, TABLE1),
                        "-o", os.path.join(d, "x.h5"), "--set", "ensemble.n_runs=300"],
                       env=dict(ENV, PMIX_MCA_gds="hash"), preexec_fn=limit_file_size, capture_output=True,
                       text=True, timeout=600)
    check(p.returncode == 2 and "file-size limit" in p.stderr, "journal beyond the file-size limit: exit 2")
    written = [f for f in os.listdir(d) if not f.endswith(".toml")]
    check(written == [], f"nothing written by any refused run ({written})")


# ----------------------------------------------------------------------------------------------
SINGLE_COPY_OFF = ["--mca", "btl_vader_single_copy_mechanism", "none"]
TCP = ["--mca", "btl", "self,tcp"]


def mpirun_mca(args, ranks, mca, extra):
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), *mca, args.driver, *extra]
    return subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)


def check_rank0_breakdown(path, what):
    """/timing's parts of rank 0's poll time: the MPI calls and the owners' messages are timed
    inside the timed polls, so together they cannot exceed them (sums of steady-clock differences:
    1e-9 relative covers their rounding); rank 0's own chunks are timed apart."""
    with h5py.File(path, "r") as f:
        a = f["timing"].attrs
        parts = {k: float(a[k]) for k in ("rank0_mpi_s", "rank0_result_s", "rank0_write_s")}
        poll = float(a["rank0_poll_s"])
    check(all(np.isfinite(v) and v >= 0 for v in parts.values()), f"{what}: rank 0's time parts finite, >= 0 ({parts})")
    check(parts["rank0_mpi_s"] > 0 and parts["rank0_result_s"] > 0, f"{what}: MPI calls and results timed ({parts})")
    inner = parts["rank0_mpi_s"] + parts["rank0_result_s"]
    check(inner <= poll * (1 + 1e-9), f"{what}: MPI + owners' messages {inner:.6f} s <= poll {poll:.6f} s")


def case_transports(args):
    """The driver over TCP and over shared memory without single-copy (CMA): the same datasets as
    over shared memory, and a scheduler that keeps rank 0 computing. Efficiency uses sleeping
    synthetic runs (--synthetic-run-cost-s), so the CPU load of the machine does not matter."""
    d = fresh(args, "transports")
    camp = os.path.join(args.repo, TABLE1)
    sets = ["--set", "ensemble.n_runs=240", "--progress", "none"]
    ref = os.path.join(d, "shm.h5")
    p = mpirun_mca(args, 2, [], [camp, "-o", ref, *sets])
    check(p.returncode == 0, f"2 ranks over shared memory ({p.stderr.strip()[-300:]})")
    a = datasets(ref)
    for name, ranks, mca in (("single-copy off", 2, SINGLE_COPY_OFF), ("tcp", 3, TCP)):
        out = os.path.join(d, name.replace(" ", "_") + ".h5")
        p = mpirun_mca(args, ranks, mca, [camp, "-o", out, *sets])
        check(p.returncode == 0, f"{ranks} ranks, {name}: exit 0 ({p.stderr.strip()[-300:]})")
        same, why = same_values(a, datasets(out))
        check(same, f"{ranks} ranks, {name}: datasets identical to shared memory outside /timing ({len(a)}) {why}")
        check_rank0_breakdown(out, f"{ranks} ranks, {name}")
    # Sleeping runs of 4 ms: 2 ranks, 600 runs (1.2 s ideal) and 8 ranks, 1600 runs (0.8 s ideal).
    # Measured on this 2-core machine under a load of 3 to 8 (other builds): 0.95 to 0.98. A
    # scheduler whose rank 0 blocks until a computing worker's next MPI call (the old one) gave
    # rank 0 19 % (single-copy off) and 29 % (TCP) of the runs on 2 ranks. Floors: efficiency 0.85,
    # and rank 0 at least 0.6 of an even share (0.8 of it at 8 ranks, where its share is small).
    # --compression 0: this checks the scheduler's progress; the deflate of the file's chunks
    # (rank 0's, about 30 us a result on these incompressible synthetic records) is measured in
    # docs/benchmarks.md.
    for name, mca in (("single-copy off", SINGLE_COPY_OFF), ("tcp", TCP)):
        for ranks, n_runs, floor, share in ((2, 600, 0.85, 0.6), (8, 1600, 0.85, 0.6)):
            out = os.path.join(d, f"synthetic_{ranks}.h5")
            if os.path.exists(out):
                os.remove(out)
            p = mpirun_mca(args, ranks, mca, [camp, "-o", out, "--set", f"ensemble.n_runs={n_runs}", "--progress", "none",
                                             "--synthetic-run-cost-s", "0.004", "--compression", "0"])
            check(p.returncode == 0, f"synthetic, {ranks} ranks, {name}: exit 0 ({p.stderr.strip()[-300:]})")
            with h5py.File(out, "r") as f:
                t = f["timing"]
                run_s = t["run_wall_time_s"][:]
                sched = t.attrs["schedule_wall_s"]
                eff = run_s.sum() / (ranks * sched)
                by0 = int(np.count_nonzero(t["rank"][:] == 0))
                check(t.attrs["synthetic_run_cost_s"] == 0.004 and np.all(run_s >= 0.004),
                      f"synthetic, {ranks} ranks, {name}: every run slept its 4 ms")
            check(eff >= floor, f"synthetic, {ranks} ranks, {name}: efficiency {eff:.3f} >= {floor} "
                                f"(sum of run times / (ranks x schedule wall {sched:.3f} s))")
            check(by0 >= share * n_runs / ranks, f"synthetic, {ranks} ranks, {name}: rank 0 computed {by0} runs "
                                                 f"(>= {share} x {n_runs}/{ranks})")


def case_paths(args):
    """Only rank 0 needs the campaign, scene, output and journal paths (a multi-host run): an MPMD
    job whose other ranks are given paths that do not exist (and a different run count) writes the
    same file as a normal job."""
    d = fresh(args, "paths")
    camp = os.path.join(args.repo, TABLE1)
    sets = ["--set", "ensemble.n_runs=60", "--progress", "none"]
    ref = os.path.join(d, "ref.h5")
    p = mpirun(args, 3, [camp, "-o", ref, *sets])
    check(p.returncode == 0, "reference on 3 ranks")
    out = os.path.join(d, "mpmd.h5")
    cmd = ["mpirun", "--oversubscribe", "-np", "1", *TCP, args.driver, camp, "-o", out, *sets,
           ":", "-np", "2", args.driver, "/nonexistent/campaign.toml", "-o", "/nonexistent/out.h5",
           "--set", "ensemble.n_runs=7"]
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, f"other ranks with nonexistent campaign and output paths: exit 0 ({p.stderr.strip()[-300:]})")
    same, why = same_values(datasets(ref), datasets(out))
    check(same, f"same datasets as the normal job {why}")
    with h5py.File(out, "r") as f:
        check(set(np.unique(f["timing/rank"][:])) == {0, 1, 2}, "the other ranks computed runs")
    check(not os.path.exists("/nonexistent"), "nothing created at the other ranks' paths")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", required=True, choices=["ranks", "resume", "failures", "saltelli", "bad_input", "transports", "paths"])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--sim", required=True)
    ap.add_argument("--reencode", required=True, help="the truss_reencode_chunks program")
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    print(f"case {args.case}:")
    globals()[f"case_{args.case}"](args)
    print("passed")


if __name__ == "__main__":
    main()
