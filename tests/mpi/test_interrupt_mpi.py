#!/usr/bin/python3
"""Ctrl-C of a campaign and the resume it names.

  test_interrupt_mpi.py --case ctrl_c|run_main --driver truss-campaign --repo SRC --build BUILD --scratch DIR

ctrl_c:   SIGINT to mpirun (what a terminal's Ctrl-C sends it; mpirun then sends the ranks SIGTERM)
          in the middle of a campaign: one line from the campaign says how many runs were kept and
          the command that resumes, nothing of Open MPI's follows it, the output's lock and the
          temporary results file are gone, the journals stay; that command run as printed finishes
          the campaign, and the file equals an uninterrupted campaign's, value and chunk for chunk.
run_main: Ctrl-C (SIGINT to the whole foreground process group) of scripts/run_main.sh while its
          campaign runs: exit 130 and, as its last line, how to resume; scripts/run_main.sh
          --resume finishes that campaign in the same folder (no new one) with the --set options it
          was started with, and writes the report.
"""
import argparse
import glob
import os
import re
import shlex
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import ENV, alive, check, datasets, descendants, file_difference, fresh, same_values  # noqa: E402
from test_journal_faults import all_journal_frames  # noqa: E402

TABLE1 = "campaigns/table1_dispersed.toml"
SETS = ["--set", "ensemble.n_runs=4000", "--set", "drive.mode=motor"]  # motor runs: about 1.3 ms each
MOTOR = "campaigns/motor_torque.toml"  # motor runs in rounds until its stop rule holds (2,855 of them)
MOTOR_SETS = ["--set", "ensemble.master_seed=7"]


def wait_for_records(out, n, proc, timeout=120):
    """Until the journals of `out` hold n run records (or the job ended)."""
    t0 = time.time()
    while time.time() - t0 < timeout and proc.poll() is None:
        if sum(k == b"R" for _, k, _ in all_journal_frames(out)) >= n:
            return True
        time.sleep(0.02)
    return False


def case_ctrl_c(args):
    d = fresh(args, "ctrl_c")
    camp = os.path.join(args.repo, TABLE1)
    ref = os.path.join(d, "ref.h5")
    p = subprocess.run(["mpirun", "-np", "2", args.driver, camp, "-o", ref, *SETS, "--progress", "none"], env=ENV,
                       capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, "uninterrupted campaign on 2 ranks")
    out = os.path.join(d, "c.h5")
    proc = subprocess.Popen(["mpirun", "-np", "2", args.driver, camp, "-o", out, *SETS, "--progress", "none"],
                            env=ENV, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    started = wait_for_records(out, 400, proc)
    job = descendants(proc.pid)
    os.kill(proc.pid, signal.SIGINT)  # mpirun only: a terminal's Ctrl-C reaches it, not the ranks (own groups)
    _, err = proc.communicate(timeout=60)
    t0 = time.time()
    while any(alive(pid) for pid in job) and time.time() - t0 < 20:
        time.sleep(0.02)
    check(started and proc.returncode != 0, f"interrupted after its first records: mpirun exits {proc.returncode}")
    lines = [ln for ln in err.splitlines() if "interrupted" in ln]
    check(len(lines) == 1, f"one line about the interruption ({len(lines)}): {lines}; stderr: {err[-1500:]}")
    m = re.match(r"\[truss-campaign\] interrupted \(SIGTERM\) after (\d+) of (\d+) runs: their records are kept in the "
                 r"journal (\S+) \(those still on their way to their chunk's rank, at most a batch per rank, are computed again\); resume with: (.*)$",
                 lines[0])
    check(m is not None and int(m.group(2)) == 4000 and 0 < int(m.group(1)) < 4000 and m.group(3) == out + ".journal",
          f"it says what was kept and where: {lines[0][:160]}")
    after = err.splitlines()[err.splitlines().index(lines[0]) + 1:]
    check(not any(ln.strip() for ln in after), f"nothing of Open MPI's after it ({after[:3]})")
    left = sorted(os.listdir(d))
    check(not any(f.startswith(".c.h5") for f in left) and "c.h5.journal" in left and "c.h5" not in left,
          f"no lock, no temporary results file; the journals stay ({left})")
    check(not any(alive(pid) for pid in job), "no process of the job left")
    cmd = shlex.split(m.group(4))
    check(cmd[:3] == ["mpirun", "-np", "2"] and cmd[3] == args.driver and cmd[-1] == "--resume",
          f"the command to resume: {m.group(4)[:160]}")
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, f"the printed command finishes the campaign ({p.stderr.strip()[-200:]})")
    restored = re.search(r"resuming: (\d+) of 4000 runs restored", p.stderr)
    # The line counts the runs rank 0 had heard of; the chunk owners' part journals may hold more
    # (written before rank 0 heard of them), and the records still on their way, at most a batch
    # per rank, are computed again. The largest batch (engine.hpp, guided): the first,
    # 4000 / (batches_per_rank 4 x 2 ranks) = 500 runs (under max_batch and a chunk, 1024 runs).
    check(restored and int(m.group(1)) - 500 * 2 <= int(restored.group(1)) <= 4000,
          f"it restored at least the runs the line counted ({restored.group(1) if restored else '?'} of {m.group(1)})")
    same, why = same_values(datasets(ref), datasets(out))
    why = why or file_difference(ref, out, args.reencode)
    check(not why, f"the file equals the uninterrupted one, value and chunk for chunk {why}")
    check(sorted(os.listdir(d)) == ["c.h5", "ref.h5"], f"nothing else left ({sorted(os.listdir(d))})")


def case_run_main(args):
    d = fresh(args, "run_main")
    out_dir = os.path.join(d, "out")
    env = dict(ENV, OUT_DIR=out_dir, BUILD_DIR=args.build)
    script = os.path.join(args.repo, "scripts", "run_main.sh")
    proc = subprocess.Popen([script, MOTOR, *MOTOR_SETS, "--progress", "none"], env=env, cwd=args.repo,
                            start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    folder = os.path.join(out_dir, "motor_torque")
    results = os.path.join(folder, "motor_torque.h5")
    t0 = time.time()
    while not os.path.exists(results + ".journal") and proc.poll() is None and time.time() - t0 < 600:
        time.sleep(0.05)
    started = wait_for_records(results, 400, proc)
    os.killpg(proc.pid, signal.SIGINT)  # a terminal's Ctrl-C: the foreground process group (bash, mpirun)
    _, err = proc.communicate(timeout=120)
    last = err.strip().splitlines()[-1] if err.strip() else ""
    check(started and proc.returncode == 130, f"run_main.sh interrupted while its campaign ran: exit {proc.returncode}")
    check(last.startswith("[main] the campaign stopped") and
          last.endswith(f"resume with: scripts/run_main.sh {MOTOR} --resume"), f"its last line says how to resume: {last}")
    proc = subprocess.run([script, MOTOR, "--resume"], env=env, cwd=args.repo, capture_output=True, text=True,
                          timeout=1200)
    check(proc.returncode == 0, f"run_main.sh --resume finishes ({proc.stderr.strip()[-300:]})")
    check(f"[main] resuming the campaign in {folder}" in proc.stdout, "it resumed the interrupted folder")
    check(sorted(os.listdir(out_dir)) == ["motor_torque"], f"no new folder ({sorted(os.listdir(out_dir))})")
    check(os.path.exists(results) and os.path.exists(os.path.join(folder, "report", "report.html"))
          and os.path.exists(os.path.join(folder, "summary.txt")), "the results file, the report and the summary")
    ref = os.path.join(d, "ref.h5")
    p = subprocess.run(["mpirun", "-np", "2", args.driver, os.path.join(args.repo, MOTOR), "-o", ref, *MOTOR_SETS,
                        "--progress", "none"], env=ENV, capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, "an uninterrupted campaign with the same --set options")
    same, why = same_values(datasets(ref), datasets(results))
    check(same, f"the resumed campaign used the options it was started with: the same file {why}")
    check(not glob.glob(os.path.join(folder, "*.journal*")) and not glob.glob(os.path.join(folder, ".motor*")),
          "no journal, lock or temporary file left")
    p = subprocess.run([script, MOTOR, "--resume"], env=env, cwd=args.repo, capture_output=True, text=True,
                       timeout=600)
    check(p.returncode == 2 and "no interrupted campaign" in p.stderr, "nothing left to resume: exit 2")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", required=True, choices=["ctrl_c", "run_main"])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--reencode", required=True, help="the truss_reencode_chunks program")
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    print(f"case {args.case}:")
    globals()[f"case_{args.case}"](args)


if __name__ == "__main__":
    main()
