#!/usr/bin/python3
"""A method of two rounds through the engine under a real mpirun (the toy method of
tests/methods/two_round.hpp, a row added to the method table by the driver tests/mpi/two_round_main.cpp,
chosen by --set ensemble.method=two_round): round 1 adds runs when round 0's 95 % interval of the
mean peak drive force is wider than the method's own option ensemble.two_round.rel_half_width of
the mean.

  test_rounds_mpi.py --case rounds|resume --driver truss_campaign_two_round --repo SRC --scratch DIR

rounds: the number of runs round 1 adds, recomputed here from round 0's rows of the file; the file's
  rounds (/runs/round, n_rounds); the same datasets on 1, 2 and 3 ranks; one round when round 0 is
  enough; the same with real runs (a 4-bay Table-1 campaign) on 1 and 2 ranks.
resume: kill -9 of the whole job in the middle of round 1, then --resume on 3 ranks: the same
  datasets as the uninterrupted campaign; a journal whose round 1 the method (run with another
  target, TRUSS_TWO_ROUND_TARGET: the same campaign) does not propose again is refused with exit 2
  and left as it was.
toy_sweep: the toy method with a [failure] event of tests/methods/toy_failure.hpp (its file and one
  row, added by the same driver) run by a [sweep] at each stall torque: the synthetic runs' failure
  column is the run's dispersed stall torque x + N(0, 1 mN m), failing at or below 3.5 mN m; each
  value's p is its failing share of its rows and its bounds Clopper-Pearson (scipy), its own
  results (/sweep/inner/<k>/toy) its runs and failures; the refinement places its values; the same
  datasets on 1 and 3 ranks.
Synthetic runs (--synthetic-run-cost-s: they sleep; their outputs are pseudo-random in [0, 1),
their inputs the dispersions' values at each run's point) keep it quick.
"""
import argparse
import math
import os
import subprocess
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import ENV, check, datasets, fresh, same_values  # noqa: E402
from test_journal_faults import kill_job, all_journal_frames  # noqa: E402

TABLE1 = "campaigns/table1_dispersed.toml"
N0 = 200


def method_sets(target=None):
    """The campaign's method: two_round, with the target as its option (default 0.02)."""
    sets = ["--set", "ensemble.method=two_round"]
    return sets + (["--set", f"ensemble.two_round.rel_half_width={target}"] if target is not None else [])


def run(args, ranks, extra, target=None, env_target=None, **kw):
    env = dict(ENV, TRUSS_TWO_ROUND_TARGET=str(env_target)) if env_target is not None else ENV
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, *extra, *method_sets(target)]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300, **kw)


# Runs whose histories the file holds (at most n_runs: round 0's, the round a resume restores below).
HISTORY_RUNS = (7, 150)


def synthetic(args, out, cost=0.0):
    return [os.path.join(args.repo, TABLE1), "-o", out, "--set", f"ensemble.n_runs={N0}", "--progress", "none",
            "--synthetic-run-cost-s", str(cost), "--flush-interval", "0.02",
            "--set", f"output.history_runs=[{HISTORY_RUNS[0]}, {HISTORY_RUNS[1]}]"]


def expected_round1(y, status, n0, rel):
    """Round 1's runs by the method's rule, computed here from round 0's rows."""
    ok = (status == 0) & np.isfinite(y)
    x = y[ok]
    n = x.size
    half = 1.96 * x.std(ddof=1) / math.sqrt(n)
    target = rel * abs(x.mean())
    if half <= target:
        return 0
    return int(min(max(math.ceil(n * (half / target) ** 2 - n), 1), 3 * n0))


def check_rounds(path, rel, what):
    with h5py.File(path, "r") as f:
        rounds = f["runs/round"][:]
        y = f["runs/peak_drive_force_N"][:]
        status = f["runs/status"][:]
        n0 = int((rounds == 0).sum())
        n1 = expected_round1(y[:n0], status[:n0], n0, rel)
        n = n0 + n1
        check(n0 == N0 and rounds.size == n and np.array_equal(rounds, np.repeat([0, 1], [n0, n1])),
              f"{what}: round 0 has {n0} runs, round 1 the {n1} that the rule gives from round 0's rows")
        check(int(f.attrs["n_rounds"]) == (2 if n1 else 1) and int(f.attrs["n_runs"]) == n
              and np.array_equal(f["runs/run_index"][:], np.arange(n)), f"{what}: n_rounds, n_runs, run_index 0..{n - 1}")
        check(int(f["stats/peak_drive_force_N/count"][()]) == int(((status == 0) & np.isfinite(y)).sum()),
              f"{what}: the statistics count the ok runs of both rounds")
    return n1


def case_rounds(args):
    d = fresh(args, "rounds")
    outs = {}
    for ranks in (1, 2, 3):
        outs[ranks] = os.path.join(d, f"r{ranks}.h5")
        p = run(args, ranks, synthetic(args, outs[ranks]))
        check(p.returncode == 0, f"{ranks} rank(s): exit 0 ({p.stderr.strip()[-300:]})")
    n1 = check_rounds(outs[2], 0.02, "synthetic, 2 ranks")
    check(n1 > 0 and "in 2 rounds" in p.stderr, f"round 1 ran ({n1} runs)")
    for ranks in (1, 3):
        same, why = same_values(datasets(outs[2]), datasets(outs[ranks]))
        check(same, f"{ranks} rank(s): the same datasets as 2 ranks outside /timing {why}")
    # The inputs of round 1 are not those of the same run indices in a plain Monte Carlo
    # continuation: its points depend on round 0's outputs (the round's state keys them).
    with h5py.File(outs[2], "r") as f:
        speed = f["runs/inputs/rail.x_m"][:]
    one = os.path.join(d, "one_round.h5")
    p = run(args, 2, synthetic(args, one) + ["--set", f"ensemble.n_runs={N0 + n1}"], target=10.0)
    check(p.returncode == 0, f"a target round 0 meets: exit 0 ({p.stderr.strip()[-300:]})")
    with h5py.File(one, "r") as f:
        plain = f["runs/inputs/rail.x_m"][:]
        check(int(f.attrs["n_rounds"]) == 1 and plain.size == N0 + n1 and not f["runs/round"][:].any(),
              "a target round 0 meets: one round")
    check(np.array_equal(speed[:N0], plain[:N0]) and not np.array_equal(speed[N0:], plain[N0:]),
          "round 0's points are plain Monte Carlo's; round 1's are keyed by round 0's outputs")
    # Real runs: a 4-bay Table-1 campaign (a tight target, so that round 1 runs).
    real = {}
    for ranks in (1, 2):
        real[ranks] = os.path.join(d, f"real{ranks}.h5")
        p = run(args, ranks, [os.path.join(args.repo, TABLE1), "-o", real[ranks], "--set", f"ensemble.n_runs={N0}",
                              "--set", "mast.n_bays=4", "--progress", "none"], target=0.0002)
        check(p.returncode == 0, f"real runs, {ranks} rank(s): exit 0 ({p.stderr.strip()[-300:]})")
    check(check_rounds(real[2], 0.0002, "real runs") > 0, "real runs: round 1 ran")
    same, why = same_values(datasets(real[1]), datasets(real[2]))
    check(same, f"real runs: 1 and 2 ranks give the same datasets {why}")
    # The method's option refused out of range, named by its --set: exit 2, nothing written.
    bad = os.path.join(d, "bad.h5")
    p = run(args, 2, synthetic(args, bad), target=-1)
    check(p.returncode == 2 and "--set ensemble.two_round.rel_half_width=-1: ensemble.two_round.rel_half_width: must "
          "be positive" in p.stderr and not os.path.exists(bad) and not os.path.exists(bad + ".journal"),
          f"rel_half_width = -1: exit {p.returncode} ({p.stderr.strip()[-200:]})")


def killed_in_round1(args, out, cost):
    """Starts the campaign and kills the whole job once a third of round 1's records are journaled."""
    proc = subprocess.Popen(["mpirun", "--oversubscribe", "-np", "2", args.driver, *synthetic(args, out, cost),
                             *method_sets()],
                            env=ENV, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0, seen = time.time(), (0, 0)
    while time.time() - t0 < 120 and proc.poll() is None:
        frames = all_journal_frames(out)  # rank 0's journal (the plans) and rank 1's part (the records)
        plans = [pl for _, k, pl in frames if k == b"P"]
        in_round1 = sum(1 for _, k, pl in frames if k == b"R" and int.from_bytes(pl[8:16], "little") == 1)
        seen = (len(plans), in_round1)
        if len(plans) == 2 and in_round1 >= 100:
            break
        time.sleep(0.01)
    kill_job(proc)
    return seen


def case_resume(args):
    d = fresh(args, "rounds_resume")
    cost = 0.004
    ref = os.path.join(d, "ref.h5")
    p = run(args, 2, synthetic(args, ref, cost))
    check(p.returncode == 0, "uninterrupted campaign of two rounds")
    n1 = check_rounds(ref, 0.02, "uninterrupted")
    out = os.path.join(d, "killed.h5")
    plans, in_round1 = killed_in_round1(args, out, cost)
    check(plans == 2 and 100 <= in_round1 < n1 and not os.path.exists(out),
          f"killed in round 1: its plan and {in_round1} of its {n1} records journaled, no results file")
    p = run(args, 3, synthetic(args, out, cost) + ["--resume"])
    check(p.returncode == 0, f"--resume on 3 ranks finishes ({p.stderr.strip()[-300:]})")
    same, why = same_values(datasets(ref), datasets(out))
    check(same, f"the resumed file equals the uninterrupted one, value for value {why}")
    with h5py.File(out, "r") as f:
        check(all(f"histories/run_{r}/t_s" in f for r in HISTORY_RUNS),
              f"the histories of runs {HISTORY_RUNS}, runs of the restored round")
        session = f["timing/session"][:]
        check(f.attrs["n_sessions"] == 2 and session[:N0].max() == 0 and (session[N0:] == 1).any(),
              "round 0 restored from the journal, the rest of round 1 computed after the resume")
    # Another target: the method does not propose the journaled round 1 again: refused, untouched.
    other = os.path.join(d, "other.h5")
    killed_in_round1(args, other, cost)
    before = open(other + ".journal", "rb").read()
    p = run(args, 2, synthetic(args, other, cost) + ["--resume"], env_target=10.0)
    check(p.returncode == 2 and "round 1 of the journal is not the round the method proposes" in p.stderr
          and open(other + ".journal", "rb").read() == before and not os.path.exists(other),
          f"a journal whose rounds the method does not propose again: exit {p.returncode}, journal untouched "
          f"({p.stderr.strip()[:200]})")


TOY_SWEEP = """
[campaign]
name = "toy-sweep"
[ensemble]
method = "toy"
n_runs = 2000
master_seed = 5
[ensemble.toy]
first_share = 0.25
[failure]
column = "motor_torque_margin_Nm"
below = 0.0035
unit = "Nm"
[sweep]
key = "drive.stall_torque_Nm"
values = [0.004, 0.0045, 0.005, 0.0055]
target_probability = 0.05
refine = 2
safe_side = "above"
[[dispersion]]
key = "drive.stall_torque_Nm"
apply = "offset"
distribution = "normal"
std = 0.001
"""


def case_toy_sweep(args):
    from scipy.stats import beta as beta_dist
    d = fresh(args, "toy_sweep")
    camp = os.path.join(d, "toy.toml")
    open(camp, "w").write(TOY_SWEEP)
    outs = {}
    for ranks in (1, 3):
        outs[ranks] = os.path.join(d, f"toy{ranks}.h5")
        cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, camp, "-o", outs[ranks], "--progress",
               "none", "--synthetic-run-cost-s", "0"]
        p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=300)
        check(p.returncode == 0, f"toy sweep, {ranks} rank(s): exit 0 ({p.stderr.strip()[-300:]})")
    with h5py.File(outs[3], "r") as f:
        g = f["sweep"]
        v, y = f["runs/sweep_value"][:], f["runs/motor_torque_margin_Nm"][:]
        check(g.attrs["inner_method"] == "toy", "/sweep's inner method is the toy")
        placed = int(np.sum(g["refinement"][:]))
        check(placed == 2, f"the refinement placed {placed} values (2)")
        for k, x in enumerate(g["values"][:]):
            rows = y[v == x]
            n, kf = rows.size, int(np.sum(rows <= 0.0035))
            lo = beta_dist.ppf(0.025, kf, n - kf + 1) if kf > 0 else 0.0
            hi = beta_dist.ppf(0.975, kf + 1, n - kf) if kf < n else 1.0
            ub = beta_dist.ppf(0.95, kf + 1, n - kf)
            own = f[f"sweep/inner/{g['index'][k]}/toy"]
            check(n == 2000 and g["runs"][k] == n and g["failures"][k] == kf and g["p"][k] == kf / n
                  and math.isclose(g["lower"][k], lo, rel_tol=1e-9) and math.isclose(g["upper"][k], hi, rel_tol=1e-9)
                  and math.isclose(g["upper_bound"][k], ub, rel_tol=1e-9)
                  and own["runs"][()] == n and own["failures"][()] == kf,
                  f"toy value {x:.6g}: p = {kf}/{n} with its Clopper-Pearson bounds, from its rows and its own group")
        check(g["allowable"].attrs["status"] == "found" and g["allowable"].attrs["safe_side"] == "above",
              f"the allowable is found, p falling as the stall torque grows ({g['allowable'].attrs['message']})")
    same, why = same_values(datasets(outs[1]), datasets(outs[3]))
    check(same, f"toy sweep: 1 and 3 ranks give the same datasets {why}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", required=True, choices=["rounds", "resume", "toy_sweep"])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    print(f"case {args.case}:")
    globals()[f"case_{args.case}"](args)
    print("passed")


if __name__ == "__main__":
    main()
