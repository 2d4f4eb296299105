#!/usr/bin/python3
"""The reweighted sweep (ensemble.method = "importance" with [sweep], methods/importance_sweep.hpp)
through the engine under a real mpirun, on real free-stack runs: campaigns/tolerance_allocation.toml
made small (100 runs a cross-entropy level, at most 3 levels, 300 final runs: at most 600 runs of
~20 ms), its diagonals' mean free length lowered to 0.483 m so that the miss (l_0 below about
0.4704 m) is reached within the levels.

  test_importance_mpi.py --driver truss-campaign --repo SRC --scratch DIR

- Each value's p recomputed here from the file's rows alone: the final runs are the last n_final
  rows; a run's standard normal point is its inputs' (x - nominal) / std for the offset normal draws
  and (x / nominal - 1) / std for the relative ones (nominal: a run's value at a zero draw is not
  stored, so the nominals are read from the resolved campaign via --dry-run). The final runs are
  drawn from the mixture of the values' laws at the mean mu = /sweep/importance/final_mean: the
  density q(z) = phi(z - mu) (1/K) sum_m (1 / c_m) exp(-n^2 (1 / c_m^2 - 1) / 2), n = z_0 - mu_0 the
  free length's deviation, c_m = the value's std over the base's (component m draws n from
  N(0, c_m^2)); a run's weight for value k is phi(z) / q(z) times the normal density ratio of its
  free-length draw at the value's std to the base's; p = mean of the failing runs' weights.
  A wrong likelihood ratio in the method fails this.
- The same datasets on 1 and 3 ranks (the adaptation reads the margins in run order, never in the
  order they arrive).
- kill -9 of the whole job after the second round is planned, then --resume on 2 ranks: the same
  datasets as the uninterrupted campaign.
"""
import argparse
import os
import subprocess
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import ENV, check, datasets, fresh, same_values  # noqa: E402
from test_journal_faults import all_journal_frames, kill_job  # noqa: E402

CAMPAIGN = "campaigns/tolerance_allocation.toml"
L0 = 0.483
SETS = ["ensemble.method=importance", "ensemble.subset=false", "ensemble.importance.n_per_level=100",
        "ensemble.importance.n_final=300", "ensemble.importance.max_levels=3", f"mast.diagonal_free_length_m={L0}",
        "sweep.values=[0.004, 0.0045, 0.005]", "sweep.target_probability=1e-3"]


def command(args, out, ranks):
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, os.path.join(args.repo, CAMPAIGN), "-o", out,
           "--progress", "none", "--flush-interval", "0.02"]
    for s in SETS:
        cmd += ["--set", s]
    return cmd


def run(args, out, ranks, extra=()):
    return subprocess.run(command(args, out, ranks) + list(extra), env=ENV, capture_output=True, text=True,
                          timeout=600)


# The campaign's dispersions, in layout order: key, how applied, std (tolerance_allocation.toml).
DISPERSIONS = [("mast.diagonal_free_length_m", "offset", None), ("mast.diagonal_stiffness_N_per_m", "relative", 0.05),
               ("mast.strut_mass_kg", "relative", 0.03), ("mast.frame_mass_kg", "relative", 0.03),
               ("rail.x_m", "offset", 0.0005)]


def nominals(args):
    """The base scene's value of each dispersed key, from the resolved campaign (--dry-run)."""
    p = subprocess.run([args.driver, os.path.join(args.repo, CAMPAIGN), "--dry-run"] + sum([["--set", s] for s in SETS], []),
                       capture_output=True, text=True, timeout=60)
    check(p.returncode == 0, f"--dry-run ({p.stderr.strip()[-200:]})")
    out, table = {}, ""
    for line in p.stdout.splitlines():
        line = line.strip()
        if line.startswith("["):
            table = "" if line.startswith("[[") else line.strip("[]").removeprefix("scene.")
        elif "=" in line.split("#")[0] and table:
            k, v = (x.strip() for x in line.split("#")[0].split("=", 1))
            out[f"{table}.{k}"] = v
    return {key: float(out[key]) for key, _, _ in DISPERSIONS}


def check_against_rows(args, path):
    nom = nominals(args)
    with h5py.File(path, "r") as f:
        s, g = f["sweep"], f["sweep/importance"]
        n_final = int(g.attrs["n_final"])
        values = s["values"][:]
        base = values[int(g.attrs["base_index"])]
        mu = g["final_mean"][:]
        margin = f["runs/rail_margin_m"][:]
        x = {key: f[f"runs/inputs/{key}"][:] for key, _, _ in DISPERSIONS}
        p_file, cov_file = s["p"][:], s["cov"][:]
        check(int(g["runs"][()]) == margin.size, f"/sweep/importance/runs = the file's {margin.size} rows")
    rows = slice(margin.size - n_final, margin.size)
    z = []
    for key, how, std in DISPERSIONS:
        std = base if std is None else std
        v = x[key][rows]
        z.append((v - nom[key]) / std if how == "offset" else (v / nom[key] - 1.0) / std)
    z = np.array(z).T
    check(z.shape[1] == mu.size, f"{mu.size} sampling dimensions, one per dispersion")
    n = z[:, 0] - mu[0]
    c = values / base
    mixture = np.mean([np.exp(-n * n * (1.0 / cm**2 - 1.0) / 2.0) / cm for cm in c], axis=0)
    log_w = 0.5 * mu @ mu - z @ mu - np.log(mixture)
    d = x["mast.diagonal_free_length_m"][rows] - nom["mast.diagonal_free_length_m"]
    m = margin[rows]
    fails = m <= 0  # a run fails when its margin says so, whatever its status (NaN: cannot say)
    check(fails.any(), f"{fails.sum()} failing final runs")
    for k, sd in enumerate(values):
        ratio = np.log(base / sd) - 0.5 * d * d * (1.0 / sd**2 - 1.0 / base**2)
        w = np.where(fails, np.exp(log_w + ratio), 0.0)
        p = w.mean()
        cov = np.sqrt(w.var(ddof=1) / w.size) / p
        # The file's p sums the same terms in another order: equal to ~1e-12 relative.
        check(abs(p_file[k] / p - 1) < 1e-9 and abs(cov_file[k] / cov - 1) < 1e-9,
              f"std {sd * 1e3:.2f} mm: p {p_file[k]:.6g} (rows: {p:.6g}), CoV {cov_file[k]:.4g} (rows: {cov:.4g})")


def killed_after(args, out, plans_wanted):
    proc = subprocess.Popen(command(args, out, 2), env=ENV, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    t0, seen = time.time(), (0, 0)
    while time.time() - t0 < 300 and proc.poll() is None:
        frames = all_journal_frames(out)
        plans = sum(1 for _, k, _ in frames if k == b"P")
        in_last = sum(1 for _, k, pl in frames if k == b"R" and int.from_bytes(pl[8:16], "little") == plans - 1)
        seen = (plans, in_last)
        if plans >= plans_wanted and in_last >= 2:
            break
        time.sleep(0.005)
    kill_job(proc)
    return seen


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    d = fresh(args, "importance")
    outs = {}
    for ranks in (3, 1):
        outs[ranks] = os.path.join(d, f"r{ranks}.h5")
        p = run(args, outs[ranks], ranks)
        check(p.returncode in (0, 6) and "sweep of mast.diagonal_free_length_m std" in p.stderr,
              f"{ranks} rank(s): results written and the sweep printed ({p.stderr.strip()[-300:]})")
    check_against_rows(args, outs[3])
    same, why = same_values(datasets(outs[3]), datasets(outs[1]))
    check(same, f"1 and 3 ranks: the same datasets outside /timing {why}")
    for attempt in range(3):
        out = os.path.join(d, f"killed{attempt}.h5")
        plans, in_last = killed_after(args, out, 2)
        if plans >= 2 and in_last >= 2 and not os.path.exists(out):
            break
        print(f"  (attempt {attempt + 1}: not caught in round 1: {plans} rounds planned, {in_last} records; again)")
    check(plans >= 2 and in_last >= 2 and not os.path.exists(out),
          f"killed in round {plans - 1}: {in_last} records of it journaled, no results file")
    p = run(args, out, 2, ["--resume"])
    check(p.returncode in (0, 6), f"--resume finishes ({p.stderr.strip()[-300:]})")
    same, why = same_values(datasets(outs[3]), datasets(out))
    check(same, f"the resumed file equals the uninterrupted one, value for value {why}")
    print("passed")


if __name__ == "__main__":
    main()
