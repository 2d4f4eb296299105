#!/usr/bin/python3
"""Width of the rare-failure methods' 95 % intervals on a shipped campaign, side by side on several
master seeds (the same seeds for each): subset simulation with modified Metropolis and cov_bound, with
adaptive conditional sampling and cov_interval (the same samples a level), and cross-entropy
importance sampling (standalone, or a sweep reweighting one set of runs to every value).

  subset_campaign_widths.py --driver build/truss-campaign --repo . --scratch DIR \\
      --campaign campaigns/free_rail_miss_rare.toml --seeds 26 1 2 3 [--np 2] [--set KEY=VALUE ...]
      [--subset-set KEY=VALUE ...] [--importance-set KEY=VALUE ...] [--variants ...]

Each variant sets ensemble.method (and removes the other method's table), so either kind of
campaign file serves all three; --subset-set / --importance-set add --set pairs to those variants
alone (their level sizes; a sweep's refine, which importance refuses). For a standalone campaign one
row per seed and variant: p, the 95 % interval (subset: lognormal, p exp(+-1.96 s), s^2 =
ln(1 + cov^2), the CoV /subset's interval_cov names; importance: /importance's lower and upper), the
ratio of its ends, the runs and the CPU time (user + system of mpirun and its ranks). For a sweep the
same per design value (/sweep, and /sweep/inner/<k>/subset), and the allowable with its interval.
With --reference P the share of rows whose interval holds P. Results also as JSON (--json).
"""
import argparse
import json
import math
import os
import resource
import subprocess

import h5py
import numpy as np

SUBSET = ["--set", "ensemble.method=subset", "--set", "ensemble.importance=false"]
VARIANTS = {"MM + cov_bound": SUBSET + ["--set", "ensemble.subset.proposal=modified_metropolis",
                                        "--set", "ensemble.subset.interval_cov=cov_bound"],
            "aCS + cov_interval": SUBSET + ["--set", "ensemble.subset.proposal=adaptive_conditional",
                                            "--set", "ensemble.subset.interval_cov=cov_interval"],
            "importance": ["--set", "ensemble.method=importance", "--set", "ensemble.subset=false"]}
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


def read_importance(g, k=None, runs=None):
    """A weighted estimate: /importance (k None), or value k of /sweep with its /sweep/importance."""
    if k is None:
        p, cov, lo, hi = (float(g[x][()]) for x in ("p", "cov", "lower", "upper"))
        ess, refused, runs = float(g["ess"][()]), text(g.attrs["refused"]), int(g["runs"][()])
        h = g
    else:
        p, cov, lo, hi = (float(g[x][k]) for x in ("p", "cov", "lower", "upper"))
        h = g["importance"]
        ess, refused = float(h["ess"][k]), text(h["refused"][k])
    return {"p": p, "cov": cov, "lo": lo, "hi": hi, "ratio": hi / lo if lo > 0 else math.nan, "runs": runs,
            "status": text(h.attrs["status"]) + (f", refused: {refused}" if refused else ""),
            "levels": int(h["levels/threshold"].size), "ess": ess}


def run_one(args, seed, name, out):
    cmd = ["mpirun", "--oversubscribe", "-np", str(args.np), args.driver, os.path.join(args.repo, args.campaign),
           "-o", out, "--force", "--progress", "none", "--set", f"ensemble.master_seed={seed}"] + VARIANTS[name]
    for kv in args.set + (args.importance_set if name == "importance" else args.subset_set):
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
            one = read_subset(f["subset"]) if "subset" in f else read_importance(f["importance"])
            return {"cpu_s": cpu, "values": [dict(one, value=None)]}
        sw = f["sweep"]
        values = []
        for i, (k, x) in enumerate(zip(sw["index"][:], sw["values"][:])):
            one = read_subset(sw[f"inner/{int(k)}/subset"]) if "importance" not in sw else \
                read_importance(sw, i, int(sw["runs"][i]))
            values.append(dict(one, value=float(x)))
        a = sw["allowable"]
        allowable = {"value": float(a["value"][()]), "lower": float(a["lower"][()]), "upper": float(a["upper"][()]),
                     "status": text(a.attrs["status"]), "verdict": text(a.attrs["verdict"])}
        runs = int(sw["importance/runs"][()]) if "importance" in sw else int(np.sum(sw["runs"][:]))  # shared runs
        return {"cpu_s": cpu, "values": values, "allowable": allowable, "runs": runs}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], help="a further --set for every run")
    ap.add_argument("--subset-set", action="append", default=[], help="a further --set for the subset variants")
    ap.add_argument("--importance-set", action="append", default=[], help="a further --set for importance")
    ap.add_argument("--reference", type=float, help="a reference p the intervals should hold (standalone)")
    ap.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=list(VARIANTS),
                    help="the variants to run (default all)")
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--keep", action="store_true", help="keep the results files (else each is removed once read)")
    args = ap.parse_args()
    os.makedirs(args.scratch, exist_ok=True)
    results = []
    for seed in args.seeds:
        for name in args.variants:
            out = os.path.join(args.scratch, f"s{seed}_{name.split()[0]}.h5")
            r = run_one(args, seed, name, out)
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
        if not rows:
            continue
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
