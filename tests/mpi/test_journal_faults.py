#!/usr/bin/python3
"""The campaign journal under damage and kill -9.

  test_journal_faults.py --case journal|faults --driver truss-campaign --repo SRC --scratch DIR

journal: crafted journals (records that pass their CRC but make no sense: a run twice, a short
  payload, a run index out of range or from a rank its session did not have, a short heartbeat, NaN,
  negative or backward times, a session on no ranks, a frame before the first session, a round plan
  of 2^62 runs) make --resume exit 2 naming the record and
  leave the journal byte for byte as it was and nothing written; a flipped byte in the middle is
  reported as a damaged middle with the counts of records kept and dropped (counted here by an
  independent parser of the journal format), and stale .NAME.tmp.PID files are removed on --resume.
faults: 10 seeded trials (--trials) of kill -9 (of mpirun, of a worker, of rank 0) at a random moment, each
  followed by --resume: every result equals an uninterrupted campaign's, no temporary file,
  journal or process is left behind.
Campaigns use the hidden --synthetic-run-cost-s (runs sleep, records are a function of the run
index) so that the test is quick and the kill moments spread over the whole campaign.
"""
import argparse
import glob
import os
import random
import signal
import struct
import subprocess
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import ENV, alive, check, datasets, descendants, fresh, same_values  # noqa: E402

TABLE1 = "campaigns/table1_dispersed.toml"
N_RUNS = 600


def run(args, ranks, extra, timeout=300):
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, *extra]
    return subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=timeout)


def campaign_args(args, out, cost):
    return [os.path.join(args.repo, TABLE1), "-o", out, "--set", f"ensemble.n_runs={N_RUNS}",
            "--synthetic-run-cost-s", str(cost), "--flush-interval", "0.02", "--progress", "none"]


# --- the journal format (src/results/journal.hpp), parsed independently of the C++ code ---------
def parse_journal(blob):
    """Header bytes and the frames [(offset, kind, payload)] up to the first bad one: rank 0's
    journal ("TRUSSJNL", the campaign text) or a part journal of another rank ("TRUSSJNP": u32
    version, u32 CRC-32 of the campaign text, i64 session, i32 rank, u32 CRC-32 of those bytes)."""
    if blob[:8] == b"TRUSSJNP":
        version, = struct.unpack_from("<I", blob, 8)
        assert version == 4 and struct.unpack_from("<I", blob, 28)[0] == zlib.crc32(blob[:28])
        at = 32
    else:
        assert blob[:8] == b"TRUSSJNL"
        version, n = struct.unpack_from("<II", blob, 8)
        assert version == 4
        text = blob[16:16 + n]
        (crc,) = struct.unpack_from("<I", blob, 16 + n)
        assert crc == zlib.crc32(text)
        at = 16 + n + 4
    header, frames = blob[:at], []
    while at + 9 <= len(blob):
        kind = blob[at:at + 1]
        size, c = struct.unpack_from("<II", blob, at + 1)
        payload = blob[at + 9:at + 9 + size]
        if len(payload) < size or zlib.crc32(kind + payload) != c:
            break
        frames.append((at, kind, payload))
        at += 9 + size
    return header, frames


def poll_journal_frames(path):
    """The frames of a journal that a live campaign is writing, or [] while its header is not
    complete yet (a poller may open the file between its creation and the header's write)."""
    try:
        blob = open(path, "rb").read()
    except FileNotFoundError:  # a part journal removed at the end
        return []
    if blob[:8] == b"TRUSSJNP":
        return parse_journal(blob)[1] if len(blob) >= 32 else []
    if len(blob) < 16 or len(blob) < 16 + struct.unpack_from("<I", blob, 12)[0] + 4:
        return []
    return parse_journal(blob)[1]


def journal_files(out):
    """Rank 0's journal of the campaign writing `out` and its part journals (OUT.journal.S.R)."""
    d, base = os.path.split(out)
    parts = sorted(glob.glob(os.path.join(d, glob.escape(base) + ".journal.*.*")))
    return [out + ".journal"] * os.path.exists(out + ".journal") + parts


def all_journal_frames(out):
    """Every frame of every journal of `out` that a live campaign is writing."""
    return [fr for path in journal_files(out) for fr in poll_journal_frames(path)]


def frame(kind, payload):
    return kind + struct.pack("<II", len(payload), zlib.crc32(kind + payload)) + payload


def killed_journal(args, d, cost=0.02):
    """A real journal: a campaign killed (whole job, kill -9) once ~1/3 of its runs are on disk. On
    one rank, which owns every chunk: its journal holds the records."""
    out = os.path.join(d, "seed.h5")
    proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", "1", args.driver, *campaign_args(args, out, cost)],
                            env=ENV, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.time()
    while time.time() - t0 < 120:
        if os.path.exists(out + ".journal"):
            frames = poll_journal_frames(out + ".journal")
            if sum(k == b"R" for _, k, _ in frames) >= N_RUNS // 3:
                break
        time.sleep(0.02)
    kill_job(proc)
    blob = open(out + ".journal", "rb").read()
    os.remove(out + ".journal")
    for t in glob.glob(os.path.join(d, ".seed.h5.tmp.*")):
        os.remove(t)
    return blob


def kill_job(proc, victim=None):
    """kill -9 of `victim` (default: the whole job); then of whatever of the job remains."""
    job = [proc.pid] + descendants(proc.pid)
    for pid in ([victim] if victim else job):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=20)  # mpirun notices a dead rank and takes the job down
    except subprocess.TimeoutExpired:
        pass
    t0 = time.time()
    while any(alive(p) for p in job) and time.time() - t0 < 20:
        time.sleep(0.02)
    for pid in job:  # what mpirun did not take down (ranks of a killed mpirun)
        if alive(pid):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    proc.wait()
    while any(alive(p) for p in job):
        time.sleep(0.02)
    return job


# ------------------------------------------------------------------------------------------------
def case_journal(args):
    d = fresh(args, "journal")
    ref = os.path.join(d, "ref.h5")
    p = run(args, 2, campaign_args(args, ref, 0.0))
    check(p.returncode == 0, f"uninterrupted synthetic campaign ({p.stderr.strip()[-200:]})")
    header, frames = parse_journal(killed_journal(args, d))
    blob = header + b"".join(frame(k, pl) for _, k, pl in frames)  # without a torn last record, if any
    header, frames = parse_journal(blob)
    runs = [(at, pl) for at, k, pl in frames if k == b"R"]
    check(len(runs) >= N_RUNS // 3, f"a killed campaign left a journal of {len(runs)} run records ({len(blob)} bytes)")
    at0, rec = runs[0]

    def refused(name, journal, expect):
        sub = os.path.join(d, name)
        os.makedirs(sub)
        out = os.path.join(sub, "out.h5")
        with open(out + ".journal", "wb") as f:
            f.write(journal)
        p = run(args, 2, campaign_args(args, out, 0.0) + ["--resume"])
        left = sorted(os.listdir(sub))
        check(p.returncode == 2 and expect in p.stderr and open(out + ".journal", "rb").read() == journal
              and left == ["out.h5.journal"],
              f"{name}: --resume exits 2 ({p.returncode}) with '{expect}', journal untouched, nothing written "
              f"(files: {left}): {p.stderr.strip()[:160]}")

    index = struct.unpack_from("<q", rec, 0)[0]
    refused("duplicate", blob + frame(b"R", rec), f"run {index} recorded twice")
    refused("short", blob + frame(b"R", rec[:-8]), "not a run record of this campaign")
    refused("out_of_range", blob + frame(b"R", struct.pack("<q", N_RUNS + 7) + rec[8:]),
            f"run index {N_RUNS + 7} out of range")
    refused("short_heartbeat", blob + frame(b"H", b"\0\0\0\0"), "heartbeat record of 4 bytes")
    # Valid CRCs, impossible values: times that are NaN, negative or running backwards, a session on
    # no ranks, a run from a rank its session did not have, a frame before the first session.
    nan = float("nan")
    refused("nan_heartbeat", blob + frame(b"H", struct.pack("<d", nan)), "a heartbeat (session wall time) of nan s")
    refused("negative_heartbeat", blob + frame(b"H", struct.pack("<d", -1.0)), "of -1 s")
    refused("backwards_heartbeat", blob + frame(b"H", struct.pack("<d", 1e4)) + frame(b"H", struct.pack("<d", 5e3)),
            "a heartbeat of 5000 s after one of 10000 s in the same session")
    refused("no_ranks", blob + frame(b"S", struct.pack("<di", time.time(), 0)), "a session on 0 ranks")
    refused("nan_start", blob + frame(b"S", struct.pack("<di", nan, 2)), "a session start at unix time of nan s")
    done = {struct.unpack_from("<q", pl, 0)[0] for _, pl in runs}
    fresh_run = struct.pack("<q", min(set(range(N_RUNS)) - done))
    # Record head (campaign/record.hpp): run i64, round i64, status i8, rank i64 at byte 17, wall f64 at 25.
    refused("rank", blob + frame(b"R", fresh_run + rec[8:17] + struct.pack("<q", 1) + rec[25:]),
            "computed on rank 1 in a session on 1 rank")
    refused("nan_run_wall", blob + frame(b"R", fresh_run + rec[8:25] + struct.pack("<d", nan) + rec[33:]),
            "a wall time of nan s")
    plan = next(pl for _, k, pl in frames if k == b"P")
    refused("before_session", header + frame(b"P", plan), "a record before the first session record")
    # A round plan's digest (i64 round, i64 first_run, i64 n_runs, u32 state length, u32 CRC) of 2^62 runs after
    # round 0's N_RUNS: refused before anything is allocated for its runs.
    huge = struct.pack("<qqqII", 1, N_RUNS, 2 ** 62, 0, 0)
    refused("huge_plan", blob + frame(b"P", huge),
            f"round 1 plans {2 ** 62} runs from run {N_RUNS}, past the campaign's cap of {N_RUNS} runs")

    # A flipped byte inside a run record in the middle: the records before it are kept, the valid
    # ones after it dropped (recomputed), and the message says so with both counts.
    k = len(runs) // 2
    at, pl = runs[k]
    damaged = bytearray(blob)
    damaged[at + 9 + len(pl) // 2] ^= 0x5A
    kept = sum(1 for a, _ in runs if a < at)
    dropped = sum(1 for a, _ in runs if a > at)
    sub = os.path.join(d, "middle")
    os.makedirs(sub)
    out = os.path.join(sub, "out.h5")
    open(out + ".journal", "wb").write(bytes(damaged))
    stale = [os.path.join(sub, ".out.h5.tmp.999999"), os.path.join(sub, ".out.h5.tmp.1")]
    for s in stale:
        open(s, "wb").write(b"left by a killed session")
    other = os.path.join(sub, ".out.h5.tmp.notapid")
    open(other, "wb").write(b"not ours")
    p = run(args, 2, campaign_args(args, out, 0.0) + ["--resume"])
    check(p.returncode == 0, f"damaged middle: --resume finishes ({p.stderr.strip()[-200:]})")
    want = f"damaged in the middle at byte {at}: {kept} records before the damage kept, {dropped} valid records after it dropped"
    check(want in p.stderr, f"reported: '{want}'")
    check(f"{kept} of {N_RUNS} runs restored" in p.stderr, f"{kept} runs restored")
    check(not any(os.path.exists(s) for s in stale) and os.path.exists(other),
          "stale .out.h5.tmp.PID files removed (a non-PID suffix kept)")
    check(all(f"removed {s}" in p.stderr for s in stale), "each removal reported")
    same, why = same_values(datasets(ref), datasets(out))
    check(same, f"the resumed file equals the uninterrupted one {why}")


def splitmix_unit(run, column):
    """parallel/synthetic_run.cpp's pseudo_value, in numpy uint64 arithmetic (wraps mod 2^64)."""
    import numpy as np
    with np.errstate(over="ignore"):
        z = run * np.uint64(0x9E3779B97F4A7C15) + np.uint64(column) * np.uint64(0xD1B54A32D192ED03) + np.uint64(1)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z ^= z >> np.uint64(31)
    return (z >> np.uint64(11)).astype(np.float64) * 2.0 ** -53


# ------------------------------------------------------------------------------------------------
def case_layout(args):
    """The streamed file's storage: chunked by whole rows, shuffled and deflated (or not, with
    --compression 0, same values), dimension scales that netCDF-4 readers turn into named dims."""
    import h5py
    import numpy as np
    d = fresh(args, "layout")
    outs = {}
    for level in (1, 0):
        outs[level] = os.path.join(d, f"c{level}.h5")
        p = run(args, 2, [os.path.join(args.repo, TABLE1), "-o", outs[level], "--set", "ensemble.n_runs=300",
                          "--progress", "none", "--compression", str(level)])
        check(p.returncode == 0, f"--compression {level}: exit 0")
    same, why = same_values(datasets(outs[0]), datasets(outs[1]))
    check(same, f"--compression 0 and 1 store the same values {why}")
    with h5py.File(outs[1], "r") as f:
        nb = int(f.attrs["n_bays_max"])
        per_run = []
        f["runs"].visititems(lambda n, o: per_run.append(o) if isinstance(o, h5py.Dataset) else None)
        check(all(o.chunks is not None and o.chunks[0] == 300 and (o.ndim == 1 or o.chunks[1] == o.shape[1])
                  for o in per_run), f"{len(per_run)} /runs datasets chunked by whole rows")
        check(all(o.compression == "gzip" and (o.shuffle or o.dtype.kind == "O") for o in per_run),
              "all deflated, numeric ones shuffled first")
        check(all(o.dims[0][0].name == "/runs/run_index" for o in per_run if o.name != "/runs/run_index"),
              "/runs/run_index is the row scale of every per-run dataset")
        check(f["runs/bays/lock_time_s"].dims[1][0].name == "/bay" and np.array_equal(f["bay"][:], np.arange(1, nb + 1)),
              "/bay (1..n_bays_max) is the column scale of the per-bay datasets")
        frame_inputs = [o for o in f["runs/inputs"].values() if o.attrs["per"] == "frame"]
        check(frame_inputs and all(o.dims[1][0].name == "/frame" for o in frame_inputs)
              and np.array_equal(f["frame"][:], np.arange(0, nb + 1)), "/frame (0..n_bays_max) on the per-frame inputs")
    with h5py.File(outs[0], "r") as f:
        check(f["runs/peak_drive_force_N"].compression is None, "--compression 0: no filter")
    # Rows land where they belong across chunks (4096 runs each; the second one partial): the
    # synthetic records are splitmix64 values of (run, column), recomputed here. Column order is
    # the field order of RunResult / BayResult: deploy_time_s is the first float64 output, n_bays
    # the first int64 one, entry_time_s the first per-bay one.
    n = 4500
    out = os.path.join(d, "rows.h5")
    p = run(args, 3, [os.path.join(args.repo, TABLE1), "-o", out, "--set", f"ensemble.n_runs={n}", "--progress", "none",
                      "--synthetic-run-cost-s", "0"])
    check(p.returncode == 0, f"{n} synthetic runs on 3 ranks: exit 0")
    with h5py.File(out, "r") as f:
        n_f64 = sum(1 for v in f["runs"].values() if isinstance(v, h5py.Dataset) and v.dtype.kind == "f")
        n_i64 = sum(1 for k, v in f["runs"].items() if isinstance(v, h5py.Dataset) and v.dtype.kind == "i"
                    and k not in ("run_index", "round") and h5py.check_enum_dtype(v.dtype) is None)
        nb = int(f.attrs["n_bays_max"])
        i = np.arange(n, dtype=np.uint64)
        check(np.array_equal(f["runs/deploy_time_s"][:], splitmix_unit(i, 0)), "/runs/deploy_time_s row by row")
        check(np.array_equal(f["runs/n_bays"][:], np.floor(1000.0 * splitmix_unit(i, n_f64)).astype(np.int64)),
              "/runs/n_bays row by row")
        entry = np.stack([splitmix_unit(i, n_f64 + n_i64 + b) for b in range(nb)], axis=1)
        check(np.array_equal(f["runs/bays/entry_time_s"][:], entry), f"/runs/bays/entry_time_s ({n} x {nb}) row by row")
        check(np.array_equal(f["runs/run_index"][:], np.arange(n)), "/runs/run_index 0..n-1")
    import xarray as xr  # scripts/install-deps.sh installs python3-xarray and python3-h5netcdf
    bays = xr.open_dataset(outs[1], group="runs/bays", engine="h5netcdf")
    check(bays["lock_time_s"].dims == ("run_index", "bay"), "xarray opens /runs/bays with dims (run_index, bay)")
    runs = xr.open_dataset(outs[1], group="runs", engine="h5netcdf")
    check(dict(runs.sizes) == {"run_index": 300}, "xarray opens /runs with the one dim run_index")


# ------------------------------------------------------------------------------------------------
def rank_of(pid):
    try:
        env = open(f"/proc/{pid}/environ", "rb").read().split(b"\0")
    except OSError:
        return None
    for e in env:
        if e.startswith(b"OMPI_COMM_WORLD_RANK="):
            return int(e.split(b"=")[1])
    return None


def case_faults(args):
    d = fresh(args, "faults")
    cost = 0.004  # 600 runs x 4 ms on 2 ranks: about 1.5 s of campaign to hit
    ref = os.path.join(d, "ref.h5")
    # How long the journal lives (runs computed; not the MPI start-up): the span to kill within.
    proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", str(args.ranks), args.driver,
                             *campaign_args(args, ref, cost)],
                            env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not os.path.exists(ref + ".journal") and proc.poll() is None:
        time.sleep(0.005)
    t0 = time.time()
    while os.path.exists(ref + ".journal"):
        time.sleep(0.005)
    duration = time.time() - t0
    check(proc.wait() == 0, f"uninterrupted campaign (journal lived {duration:.2f} s)")
    expected = datasets(ref)
    resumed = {}
    rng = random.Random(20261123)
    targets = ["mpirun", "worker", "rank0"]
    for trial in range(args.trials):
        target = targets[trial % 3]
        out = os.path.join(d, f"t{trial}.h5")
        proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", str(args.ranks), args.driver,
                                 *campaign_args(args, out, cost)],
                                env=ENV, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while not os.path.exists(out + ".journal") and proc.poll() is None:
            time.sleep(0.005)
        delay = rng.uniform(0.0, 0.7 * duration)
        time.sleep(delay)
        ranks = {}
        for pid in descendants(proc.pid):
            r = rank_of(pid)
            if r is not None:
                ranks[r] = pid
        victim = {"mpirun": proc.pid, "worker": ranks.get(1), "rank0": ranks.get(0)}[target]
        job = kill_job(proc, victim) if victim else kill_job(proc)
        if os.path.exists(out):
            how = "results written without a resume (the job ended before the kill took effect, or ranks outlived mpirun)"
        else:
            p = run(args, args.ranks, campaign_args(args, out, cost) + ["--resume"])
            errors = [ln for ln in p.stderr.splitlines() if "error" in ln]
            check(p.returncode == 0, f"trial {trial}: --resume after kill -9 of {target} at {delay:.2f} s "
                                     f"({errors[:2] or p.stderr.strip()[-200:]})")
            how = "resumed"
            resumed[target] = resumed.get(target, 0) + 1
        same, why = same_values(expected, datasets(out))
        left = [f for f in os.listdir(d) if f.startswith(f".t{trial}.h5.tmp.") or f.startswith(f"t{trial}.h5.journal")]
        check(same and not left and not any(alive(pid) for pid in job),
              f"trial {trial}: kill -9 of {target} at {delay:.2f} s, {how}: identical datasets {why}, "
              f"no temporary file or journal left {left}, no process of the job alive")
    check(len(resumed) == 3, f"each kind of kill hit a running campaign and was resumed: {resumed}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", required=True)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--trials", type=int, default=10, help="faults: kill -9 trials (10 in CI)")
    ap.add_argument("--ranks", type=int, default=2, help="faults: ranks of the killed and resumed campaigns")
    args = ap.parse_args()
    print(f"case {args.case}:")
    globals()[f"case_{args.case}"](args)


if __name__ == "__main__":
    main()
