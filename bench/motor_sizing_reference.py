#!/usr/bin/python3
"""An independent reference for campaigns/motor_sizing.toml: P(motorisation_margin <= 0) as a function
of the nominal stall torque T, and the torque where it crosses the target, by conditional Monte Carlo
exact in the stall torque's own scatter.

In velocity mode the motion is prescribed, so a run's required torque T_min does not depend on the
motor, and the torque judged is proportional to the run's stall torque (docs/model-notes.md
"Motorisation check"): a run misses the factors exactly when its stall torque T (1 + d) is at or
below motorisation_stall_torque_Nm, M*, which depends on the other inputs alone. With d ~ N(0, s^2)
(the campaign's relative dispersion of drive.stall_torque_Nm):

    P(T) = E[ Phi((M* / T - 1) / s) ],

averaged over a crude Monte Carlo campaign of the same scene and dispersions (no sweep, no failure
method), with its standard error over the runs. Checked: M* does not move with the stall torque's
draw (their correlation over the runs is printed).

  motor_sizing_reference.py --driver build/truss-campaign --repo . --scratch DIR [--runs 200000 ...]
                            [--seed 7 ...] [--np 2] [--campaign FILE.h5 ...] [--check]

--campaign prints, for a sweep file of the same question (/sweep), each value's estimate, its 95 %
interval and the reference there, whether the interval holds it, the difference in standard
deviations of the difference (the estimate's lognormal s and the reference's standard error), and
the allowable against the reference's crossing. --check also runs the shipped campaign, and exits 1
unless each value of each file lies within 3.29 standard deviations of the reference (two-sided
99.9 %) and the reference's crossing inside the allowable's interval widened by 3.29 of the
reference's own standard deviation there."""
import argparse
import math
import os
import subprocess
import sys
import tomllib

import h5py
import numpy as np
from scipy.stats import norm

CAMPAIGN = "campaigns/motor_sizing.toml"
KEY = "drive.stall_torque_Nm"
Z_CHECK = 3.29  # two-sided 99.9 %: a handful of correlated comparisons a run, none should fail by chance


def write_monte_carlo(args, path):
    """The campaign as crude Monte Carlo: its scene and dispersions, without [sweep], [failure] and the
    rare-failure method's table (a --set cannot remove a table)."""
    drop, lines = False, []
    with open(os.path.join(args.repo, CAMPAIGN)) as f:
        for line in f:
            head = line.strip()
            if head.startswith("["):
                drop = head in ("[sweep]", "[failure]", "[ensemble.subset]", "[ensemble.importance]")
            if drop or head.startswith("method ="):
                continue
            if head.startswith("file ="):  # the scene, relative to the campaign's folder
                scene = tomllib.loads(head)["file"]
                line = f'file = "{os.path.abspath(os.path.join(args.repo, "campaigns", scene))}"\n'
            lines.append(line)
    with open(path, "w") as f:
        f.writelines(lines)


def run_reference(args, runs, seed):
    out = os.path.join(args.scratch, f"motor_reference_{runs}_{seed}.h5")
    if not os.path.exists(out):
        toml = os.path.join(args.scratch, "motor_reference.toml")
        write_monte_carlo(args, toml)
        cmd = ["mpirun", "--oversubscribe", "-np", str(args.np), args.driver, toml, "-o", out, "--progress", "none",
               "--set", f"ensemble.n_runs={runs}", "--set", "ensemble.sampling=monte_carlo",
               "--set", f"ensemble.master_seed={seed}"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
    with h5py.File(out, "r") as f:
        ok = h5py.check_enum_dtype(f["runs/status"].dtype)["ok"]
        status = f["runs/status"][:]
        m_star = f["runs/motorisation_stall_torque_Nm"][:]
        drawn = f["runs/motorisation_available_torque_Nm"][:] / f["runs/motorisation_required_torque_Nm"][:] * m_star
    bad = status != ok  # a run capped by its wall time (a loaded machine) says nothing: left out, counted
    if np.sum(bad) > 1e-4 * status.size or not np.all(np.isfinite(m_star[~bad])):
        raise RuntimeError(f"{np.sum(bad)} runs not ok, {np.sum(~np.isfinite(m_star[~bad]))} ok runs without M*")
    if np.any(bad):
        print(f"{np.sum(bad)} of {status.size} runs not ok (wall-time cap): left out")
    m_star, drawn = m_star[~bad], drawn[~bad]
    return m_star, drawn  # M*, and the run's own stall torque M* T_available / T_min


def calc_p(m_star, spread, torque):
    x = norm.cdf((m_star / torque - 1.0) / spread)
    return x.mean(), x.std(ddof=1) / math.sqrt(x.size)


def find_crossing(m_star, spread, target):
    lo, hi = 0.020, 0.050  # P falls with T: the crossing of the target by bisection on P itself
    while hi - lo > 1e-7:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if calc_p(m_star, spread, mid)[0] > target else (lo, mid)
    return 0.5 * (lo + hi)


def compare(path, m_star, spread, cross):
    """Prints a sweep file's values against the reference; returns what fails the --check (each value
    within Z_CHECK standard deviations of the difference, the crossing inside the allowable's interval
    widened by Z_CHECK of the reference's own uncertainty there)."""
    fails = []
    with h5py.File(path, "r") as f:
        sw = f["sweep"]
        held = 0
        for t, p, cov, lo, hi in zip(sw["values"][:], sw["p"][:], sw["cov"][:], sw["lower"][:], sw["upper"][:]):
            r, se = calc_p(m_star, spread, t)
            ok = lo <= r <= hi
            held += ok
            z = math.log(p / r) / math.sqrt(math.log1p(cov * cov) + (se / r) ** 2)
            print(f"{path}: {1e3 * t:.2f} mN m: p {p:.3g}, 95 % {lo:.3g} - {hi:.3g} (hi/lo {hi / lo:.2f}); reference "
                  f"{r:.3g} +- {100 * se / r:.1f} %: {'holds' if ok else 'MISSES'}; difference {z:+.2f} sd")
            if not abs(z) <= Z_CHECK:
                fails.append(f"{1e3 * t:.2f} mN m: {z:+.2f} standard deviations from the reference")
        a = sw["allowable"]
        v, lo, hi = (float(a[x][()]) for x in ("value", "lower", "upper"))
    print(f"{path}: {held} of {len(sw_values(path))} intervals hold the reference; allowable {1e3 * v:.3f} mN m "
          f"(interval {1e3 * lo:.3f} - {1e3 * hi:.3f}); reference crossing {1e3 * cross:.3f}: "
          f"{'on the safe side' if v >= cross else 'UNSAFE side'}, {'inside' if lo <= cross <= hi else 'OUTSIDE'} "
          f"the interval")
    # The reference crossing's own standard deviation: its ln P's over the slope of ln P there.
    r, se = calc_p(m_star, spread, cross)
    slope = (math.log(calc_p(m_star, spread, cross + 1e-4)[0]) - math.log(r)) / 1e-4
    sd = se / r / abs(slope)
    if not lo - Z_CHECK * sd <= cross <= hi + Z_CHECK * sd:
        fails.append(f"the reference crossing {1e3 * cross:.3f} mN m (sd {1e3 * sd:.3f}) is outside the allowable's "
                     f"interval {1e3 * lo:.3f} - {1e3 * hi:.3f} mN m")
    return fails


def sw_values(path):
    with h5py.File(path, "r") as f:
        return f["sweep/values"][:]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--runs", type=int, nargs="+", default=[200000], help="runs of each reference campaign")
    ap.add_argument("--seed", type=int, nargs="+", default=[7], help="their master seeds (one per --runs)")
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--campaign", nargs="*", default=[], help="sweep files to check against the reference")
    ap.add_argument("--check", action="store_true",
                    help="run the shipped campaign too, and exit 1 unless it and every --campaign file agree")
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    with open(os.path.join(args.repo, CAMPAIGN), "rb") as f:
        c = tomllib.load(f)
    spread = next(d["std"] for d in c["dispersion"] if d["key"] == KEY and d["apply"] == "relative")
    target = c["sweep"]["target_probability"]
    if len(args.runs) != len(args.seed):
        ap.error("one --seed per --runs")
    parts = [run_reference(args, n, s) for n, s in zip(args.runs, args.seed)]
    m_star, drawn = (np.concatenate(x) for x in zip(*parts))
    if args.check:  # a test's reference is made anew each time (about 200 MB a 100,000 runs)
        for n, s in zip(args.runs, args.seed):
            os.remove(os.path.join(args.scratch, f"motor_reference_{n}_{s}.h5"))
    print(f"{m_star.size} runs, M* {1e3 * m_star.mean():.4f} mN m mean, sd {1e3 * m_star.std():.4f} mN m; "
          f"correlation of M* with the drawn stall torque {np.corrcoef(m_star, drawn)[0, 1]:+.4f}")
    for t in np.arange(0.028, 0.0361, 0.0005):
        p, se = calc_p(m_star, spread, t)
        print(f"  T = {1e3 * t:.2f} mN m: P = {p:.4g} (standard error {100 * se / p:.1f} %)")
    cross = find_crossing(m_star, spread, target)
    print(f"crossing of {target:g}: {1e3 * cross:.3f} mN m")
    files = list(args.campaign)
    if args.check:
        out = os.path.join(args.scratch, "motor_sizing.h5")
        subprocess.run(["mpirun", "--oversubscribe", "-np", str(args.np), args.driver,
                        os.path.join(args.repo, CAMPAIGN), "-o", out, "--force", "--progress", "none"],
                       capture_output=True, text=True)  # exit 3: its verdict, FAIL
        files.append(out)
    fails = [f"{path}: {x}" for path in files for x in compare(path, m_star, spread, cross)]
    for x in fails:
        print(f"FAIL: {x}")
    return 1 if args.check and fails else 0


if __name__ == "__main__":
    sys.exit(main())
