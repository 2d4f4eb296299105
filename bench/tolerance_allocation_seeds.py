#!/usr/bin/python3
"""campaigns/tolerance_allocation.toml over several seeds against the independent reference of
bench/rail_miss_reference.py (for each of --draws draws of the other four inputs, the miss boundary
in l_0 by bisection on the run's status alone; P(sigma) = mean of Phi((l* - 0.49) / sigma), exact in
l_0, with its standard error).

  tolerance_allocation_seeds.py --driver build/truss-campaign --sim build/truss-sim --repo . \\
      --scratch DIR [--seeds 1 2 ... 10] [--draws 100] [--jobs 2]

Per seed (mpirun -np 2, --set ensemble.master_seed=N): the allowable, its estimate and the interval
of the crossing, whether that interval holds the reference's crossing of the target, the verdict
and safe side, the largest CoV of the values, the runs, CPU seconds (user + system of mpirun and its
ranks). Over all seeds and values: how many 95 % intervals hold the reference p, and how many
estimates agree with it within both uncertainties (|ln(p / ref)| <= 1.96 sqrt(s^2 + (se / ref)^2),
s^2 = ln(1 + CoV^2)); per value the spread of ln p over the seeds beside the CoVs the file states."""
import argparse
import math
import os
import resource
import subprocess
import sys
import types
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np
from scipy.optimize import brentq
from scipy.stats import norm

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rail_miss_reference as ref_mod  # noqa: E402

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def run_seed(a, seed):
    out = os.path.join(a.scratch, f"seed{seed}.h5")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(["mpirun", "-np", "2", a.driver, os.path.join(a.repo, "campaigns/tolerance_allocation.toml"),
                        "-o", out, "--force", "--progress", "none", "--set", f"ensemble.master_seed={seed}"],
                       env=ENV, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode not in (0, 6):
        raise RuntimeError(f"seed {seed}: exit {p.returncode}: {p.stderr[-400:]}")
    return out, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--sim", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 11)))
    ap.add_argument("--draws", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    files = [(s, *run_seed(a, s)) for s in a.seeds]
    args = types.SimpleNamespace(sim=a.sim, repo=a.repo, tol_m=2e-6)
    with ThreadPoolExecutor(a.jobs) as pool:
        lstar = np.array(list(pool.map(lambda t: ref_mod.find_boundary(args, t), ref_mod.draws(a.draws, 7))))

    def ref(sigma):
        return ref_mod.reference(lstar, sigma)

    with h5py.File(files[0][1], "r") as f:
        target = float(f["sweep"].attrs["target_probability"])
        values = f["sweep/values"][:]
    cross = brentq(lambda s: math.log(ref(s)[0] / target), values[0] * 0.5, values[-1] * 2)
    print(f"reference ({a.draws} draws): crossing of {target:g} at {cross * 1e3:.3f} mm; "
          + ", ".join(f"{v * 1e3:.1f} mm {ref(v)[0]:.3g} +- {ref(v)[1]:.2g}" for v in values))
    held = agree = total = 0
    ps, covs = [], []
    for seed, path, cpu in files:
        with h5py.File(path, "r") as f:
            s = f["sweep"]
            al = s["allowable"]
            att = al.attrs
            lo, hi = float(al["lower"][()]), float(al["upper"][()])
            p, cov = s["p"][:], s["cov"][:]
            ps.append(p)
            covs.append(cov)
            for v, pv, c, l, u in zip(values, p, cov, s["lower"][:], s["upper"][:]):
                r, se = ref(v)
                total += 1
                held += bool(l <= r <= u)
                agree += bool(abs(math.log(pv / r)) <= 1.96 * math.hypot(math.sqrt(math.log1p(c * c)), se / r))
            print(f"seed {seed:3d}: allowable {float(al['value'][()]) * 1e3:.3f} mm, estimate "
                  f"{float(al['estimate'][()]) * 1e3:.3f}, crossing's interval [{lo * 1e3:.3f}, {hi * 1e3:.3f}] "
                  f"{'holds' if lo <= cross <= hi else 'MISSES'} the reference's; {att['verdict']}, safe side "
                  f"{att['safe_side']}; largest CoV {cov.max():.3f}; {int(s['runs'][0])} runs, {cpu:.1f} s CPU")
    print(f"95 % intervals holding the reference: {held} of {total}; within both uncertainties: {agree} of {total}")
    ps, covs = np.array(ps), np.array(covs)
    for j, v in enumerate(values if len(files) > 1 else []):  # a spread over seeds needs two
        print(f"  {v * 1e3:.1f} mm: p {np.median(ps[:, j]):.3g} (median), sd of ln p over seeds "
              f"{np.std(np.log(ps[:, j]), ddof=1):.3f}, stated CoV {covs[:, j].min():.3f}-{covs[:, j].max():.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
