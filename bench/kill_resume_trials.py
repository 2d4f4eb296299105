#!/usr/bin/python3
"""kill -9 of a whole campaign job at random moments, then --resume on another rank count and
transport: each resumed file must equal an uninterrupted one value for value and chunk for chunk
(the compressed bytes), everything but /timing.

  kill_resume_trials.py --driver build/truss-campaign --repo . --scratch DIR [--trials 10]
                        [--runs 4000] [--seed 1]

The campaign is campaigns/table1_dispersed.toml with the motor drive (runs that integrate, about
1.3 ms each) and `--flush-interval 0.01`. Trial k starts on ranks[k % 4] of (2, 3, 8, 2) with
(1, 2, 3, 1)[k % 4] statistics ranks (`--statistics-ranks`) over shared memory or TCP (`--mca btl
self,tcp` on odd trials), is killed (mpirun and every rank, SIGKILL)
after a delay drawn uniformly in 5-95 % of the uninterrupted campaign's wall time (the seeded
generator: the same delays for the same --seed), and resumes on (3, 2, 2, 8)[k % 4] ranks over the
other transport. A kill after the last run (the file already written), or in the start-up before
the journal exists (--resume then refuses, exit 2, as it should), is not a trial of the resume.
Exit 1 on any difference.
"""
import argparse
import os
import random
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "mpi"))
from test_campaign_mpi import ENV, datasets, file_difference, kill_job, same_values  # noqa: E402

CAMPAIGN = "campaigns/table1_dispersed.toml"


def launch(args, ranks, tcp, extra):
    mca = ["--mca", "btl", "self,tcp"] if tcp else []
    return ["mpirun", "--oversubscribe", *mca, "-np", str(ranks), args.driver,
            os.path.join(args.repo, CAMPAIGN), *extra]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--runs", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--reencode", help="truss_reencode_chunks: on a chunk difference, which file's chunk the codec writes")
    args = ap.parse_args()
    shutil.rmtree(args.scratch, ignore_errors=True)
    os.makedirs(args.scratch)
    sets = ["--set", f"ensemble.n_runs={args.runs}", "--set", "drive.mode=motor", "--progress", "none"]
    ref = os.path.join(args.scratch, "ref.h5")
    t0 = time.time()
    subprocess.run(launch(args, 2, False, ["-o", ref, *sets]), env=ENV, check=True, capture_output=True)
    t_ref = time.time() - t0
    ref_values = datasets(ref)
    print(f"uninterrupted: {args.runs} runs on 2 ranks in {t_ref:.2f} s")
    rng = random.Random(args.seed)
    bad = 0
    for k in range(args.trials):
        ranks, again, merging = (2, 3, 8, 2)[k % 4], (3, 2, 2, 8)[k % 4], (1, 2, 3, 1)[k % 4]
        tcp = k % 2 == 1
        out = os.path.join(args.scratch, f"trial{k}.h5")
        delay = rng.uniform(0.05, 0.95) * t_ref
        proc = subprocess.Popen(launch(args, ranks, tcp, ["-o", out, *sets, "--flush-interval", "0.01",
                                                          "--statistics-ranks", str(merging)]), env=ENV,
                                start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        finished = proc.poll() is not None
        kill_job(proc)
        where = f"trial {k}: {ranks} ranks ({merging} merging) {'TCP' if tcp else 'shm'}, killed at {delay:.2f} s"
        if finished or os.path.exists(out):
            print(f"{where}: finished before the kill")
            continue
        if not os.path.exists(out + ".journal"):  # killed in the start-up: nothing to resume from
            print(f"{where}: killed before its journal was made")
            continue
        p = subprocess.run(launch(args, again, not tcp, ["-o", out, *sets, "--resume"]), env=ENV,
                           capture_output=True, text=True)
        restored = next((ln.strip() for ln in p.stderr.splitlines() if "restored" in ln), "")
        same, why = (False, f"exit {p.returncode}: {p.stderr.strip()[-300:]}") if p.returncode != 0 else \
            same_values(ref_values, datasets(out))
        why = why or file_difference(ref, out, args.reencode)
        bad += bool(why)
        print(f"{where}; resumed on {again} ranks {'shm' if tcp else 'TCP'}: "
              f"{'DIFFERS ' + why if why else 'identical'} ({restored[:90]})")
    print("all identical" if bad == 0 else f"{bad} trials differ")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
