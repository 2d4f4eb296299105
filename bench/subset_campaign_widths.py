#!/usr/bin/python3
"""Width of subset simulation's 95 % intervals on a shipped campaign, the two Markov proposals side
by side at the same samples a level: modified Metropolis with cov_bound against adaptive conditional
sampling with cov_interval, on several master seeds (the same seeds for both).

  subset_campaign_widths.py --driver build/truss-campaign --repo . --scratch DIR \\
      --campaign campaigns/free_rail_miss_rare.toml --seeds 26 1 2 3 [--np 2] [--set KEY=VALUE ...]

For a standalone subset campaign one row per seed and proposal: p, the 95 % interval (lognormal,
p exp(+-1.96 s), s^2 = ln(1 + cov^2), the interval's CoV as /subset's interval_cov names it), the
ratio of its ends, the runs and the CPU time (user + system of mpirun and its ranks). For a sweep the
same per design value (/sweep/inner/<k>/subset), and the allowable with its interval. With --reference
P the share of rows whose interval holds P. Results also as JSON (--json).
"""
import argparse
import json
import math
import os
import resource
import subprocess

import h5py
import numpy as np

VARIANTS = {"MM + cov_bound": ("modified_metropolis", "cov_bound"),
            "aCS + cov_interval": ("adaptive_conditional", "cov_interval")}
Z = 1.959963984540054  # the standard normal's 97.5 % quantile


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def read_subset(g):
    rule = text(g.attrs["interval_cov"])
    p, cov = float(g["p"][()]), float(g[rule][()])
    s = math.sqrt(math.log1p(cov * cov))
    return {"p": p, "cov": cov, "lo": p * math.exp(-Z * s), "hi": p * math.exp(Z * s), "ratio": math.exp(2 * Z * s),
            "runs": int(g["runs"][()]), "status": text(g.attrs["status"]), "levels": int(g["levels/threshold"].size),
            "cov_bound": float(g["cov_bound"][()]), "cov_interval": float(g["cov_interval"][()])}


def run_one(args, seed, proposal, rule, out):
    cmd = ["mpirun", "--oversubscribe", "-np", str(args.np), args.driver, os.path.join(args.repo, args.campaign),
           "-o", out, "--force", "--progress", "none", "--set", f"ensemble.master_seed={seed}",
           "--set", f"ensemble.subset.proposal={proposal}", "--set", f"ensemble.subset.interval_cov={rule}"]
    for kv in args.set:
        cmd += ["--set", kv]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if not os.path.exists(out):  # a campaign that did not finish: reported, the others still run
        print(f"{' '.join(cmd)}: exit {p.returncode}, no file\n{p.stderr[-2000:]}", flush=True)
        return {"cpu_s": cpu, "values": [], "failed": p.stderr[-2000:]}
    with h5py.File(out, "r") as f:
        if "sweep" not in f:
            return {"cpu_s": cpu, "values": [dict(read_subset(f["subset"]), value=None)]}
        sw = f["sweep"]
        values = []
        for k, x in zip(sw["index"][:], sw["values"][:]):
            values.append(dict(read_subset(sw[f"inner/{int(k)}/subset"]), value=float(x)))
        a = sw["allowable"]
        allowable = {"value": float(a["value"][()]), "lower": float(a["lower"][()]), "upper": float(a["upper"][()]),
                     "status": text(a.attrs["status"]), "verdict": text(a.attrs["verdict"])}
        return {"cpu_s": cpu, "values": values, "allowable": allowable, "runs": int(np.sum(sw["runs"][:]))}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], help="a further --set for every run")
    ap.add_argument("--reference", type=float, help="a reference p the intervals should hold (standalone)")
    ap.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=list(VARIANTS),
                    help="the proposals to run (default both)")
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--keep", action="store_true", help="keep the results files (else each is removed once read)")
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    results = []
    for seed in args.seeds:
        for name in args.variants:
            proposal, rule = VARIANTS[name]
            out = os.path.join(args.scratch, f"s{seed}_{proposal}.h5")
            r = run_one(args, seed, proposal, rule, out)
            r.update(seed=seed, variant=name)
            results.append(r)
            if not args.keep and os.path.exists(out):
                os.remove(out)
            for v in r["values"]:
                at = "" if v["value"] is None else f" at {v['value']:.6g}"
                print(f"seed {seed}, {name}{at}: p {v['p']:.3g}, 95 % {v['lo']:.2g} - {v['hi']:.2g} (factor "
                      f"{v['ratio']:.1f}), {v['runs']} runs, {v['levels']} levels, {v['status']}", flush=True)
            if "allowable" in r:
                a = r["allowable"]
                print(f"seed {seed}, {name}: allowable {a['value']:.6g} ({a['lower']:.6g} - {a['upper']:.6g}), "
                      f"{a['status']}, {a['verdict']}, {r['runs']} runs", flush=True)
            print(f"seed {seed}, {name}: CPU {r['cpu_s']:.1f} s", flush=True)
    failed = [f"seed {r['seed']} ({r['variant']})" for r in results if "failed" in r]
    if failed:
        print(f"campaigns that did not finish: {', '.join(failed)}")
    for name in args.variants:
        rows = [v for r in results if r["variant"] == name for v in r["values"]]
        ratios = [v["ratio"] for v in rows]
        line = f"{name}: median interval factor {np.median(ratios):.2f} over {len(rows)} estimates, mean runs " \
               f"{np.mean([v['runs'] for v in rows]):.0f}, median CPU " \
               f"{np.median([r['cpu_s'] for r in results if r['variant'] == name]):.1f} s a campaign"
        if args.reference is not None:
            held = sum(v["lo"] <= args.reference <= v["hi"] for v in rows)
            line += f"; intervals holding {args.reference:.3g}: {held} of {len(rows)}"
        print(line)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
