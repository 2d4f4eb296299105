#!/usr/bin/python3
"""Subset simulation against crude Monte Carlo on the simulator: the free-stack rail miss of
campaigns/free_rail_miss_rare.toml with the diagonals' mean free length lowered so that p is near
1e-3 (the same dispersions; 4 bays by default, whose pins miss at the same free length as 30 bays,
about 0.4704 m, at a tenth of the cost), estimated both ways through truss-campaign under mpirun.

  subset_vs_mc.py --driver build/truss-campaign --repo . --scratch DIR [--mc-runs 100000]
                  [--n-per-level 1000] [--mean-free-length 0.4855] [--bays 4] [--ranks 2] [--check]

Prints both estimates with their 95 % intervals (crude MC: Clopper-Pearson; subset: lognormal with
its lineage CoV), the runs and wall times. --check exits 1 unless they agree:
|ln(p_ss / p_mc)| <= 2 sqrt(cov_ss^2 + cov_mc^2), cov_mc = sqrt((1 - p) / (n p)) (two standard
deviations of the difference of two independent estimates, on the log scale where subset
simulation's estimate is closer to normal). The reduced version is ctest mpi_subset_vs_mc."""
import argparse
import math
import os
import subprocess
import sys
import time

import h5py
import numpy as np
from scipy.stats import beta as beta_dist

DISPERSIONS = """
[[dispersion]]
key = "mast.diagonal_free_length_m"
apply = "offset"
distribution = "normal"
std = 0.005
[[dispersion]]
key = "mast.diagonal_stiffness_N_per_m"
apply = "relative"
distribution = "normal"
std = 0.05
[[dispersion]]
key = "mast.strut_mass_kg"
apply = "relative"
distribution = "normal"
std = 0.03
[[dispersion]]
key = "mast.frame_mass_kg"
apply = "relative"
distribution = "normal"
std = 0.03
[[dispersion]]
key = "rail.x_m"
apply = "offset"
distribution = "normal"
std = 0.0005
"""


def campaign_text(args, ensemble):
    scene = os.path.join(os.path.abspath(args.repo), "campaigns/scenes/paper_free.toml")
    return (f"[ensemble]\nmax_run_wall_time_s = 30.0\n{ensemble}\n\n[scene]\nfile = \"{scene}\"\n"
            f"overrides = {{ \"run.output_step_s\" = 0.0, \"stack.contacts\" = false, "
            f"\"mast.diagonal_free_length_m\" = {args.mean_free_length}, \"mast.n_bays\" = {args.bays} }}\n"
            + DISPERSIONS)


def run_campaign(args, name, ensemble):
    path = os.path.join(args.scratch, name + ".toml")
    out = os.path.join(args.scratch, name + ".h5")
    with open(path, "w") as fh:
        fh.write(campaign_text(args, ensemble))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    t0 = time.time()
    p = subprocess.run(["mpirun", "--oversubscribe", "-np", str(args.ranks), args.driver, path, "-o", out, "--force",
                        "--progress", "none"], env=env, capture_output=True, text=True)
    wall = time.time() - t0
    if p.returncode != 0:
        sys.exit(f"{name}: exit {p.returncode}: {p.stderr[-500:]}")
    return out, wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--mc-runs", type=int, default=100000)
    ap.add_argument("--n-per-level", type=int, default=1000)
    ap.add_argument("--mean-free-length", type=float, default=0.4855)
    ap.add_argument("--bays", type=int, default=4)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    ss_out, ss_wall = run_campaign(args, "subset", f"method = \"subset\"\nmaster_seed = 31\n\n"
                                   f"[ensemble.subset]\nn_per_level = {args.n_per_level}\np0 = 0.1\nmax_levels = 6\n\n"
                                   "[failure]\nmargin = \"rail_margin_m\"")
    mc_out, mc_wall = run_campaign(args, "crude", f"n_runs = {args.mc_runs}\nmaster_seed = 32\nsampling = \"monte_carlo\"")
    with h5py.File(ss_out, "r") as f:
        g = f["subset"]
        p_ss, cov_ss, runs_ss = float(g["p"][()]), float(g["cov_lineage"][()]), int(g["runs"][()])
        status = g.attrs["status"]
    with h5py.File(mc_out, "r") as f:
        m = f["runs/rail_margin_m"][:]
        n = m.size
        k = int(np.count_nonzero(m <= 0))
    p_mc = k / n
    lo_mc = beta_dist.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
    hi_mc = beta_dist.ppf(0.975, k + 1, n - k) if k < n else 1.0
    s = math.sqrt(math.log1p(cov_ss ** 2))
    cov_mc = math.sqrt((1 - p_mc) / (n * p_mc)) if k > 0 else math.inf
    print(f"subset simulation: p = {p_ss:.4g}, 95 % [{p_ss * math.exp(-1.96 * s):.4g}, {p_ss * math.exp(1.96 * s):.4g}], "
          f"CoV {cov_ss:.3g}, {runs_ss} runs, {ss_wall:.1f} s on {args.ranks} ranks ({status})")
    print(f"crude Monte Carlo: p = {p_mc:.4g} ({k} of {n}), 95 % [{lo_mc:.4g}, {hi_mc:.4g}], CoV {cov_mc:.3g}, "
          f"{mc_wall:.1f} s on {args.ranks} ranks")
    dev = abs(math.log(p_ss / p_mc)) if p_ss > 0 and k > 0 else math.inf
    limit = 2 * math.sqrt(cov_ss ** 2 + cov_mc ** 2)
    print(f"|ln(p_ss / p_mc)| = {dev:.3g}, 2 sd of the difference = {limit:.3g}: "
          f"{'agree' if dev <= limit else 'DISAGREE'}")
    if args.check and not (status == "converged" and dev <= limit):
        sys.exit(1)


if __name__ == "__main__":
    main()
