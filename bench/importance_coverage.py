#!/usr/bin/python3
"""Coverage and width of cross-entropy importance sampling's 95 % intervals, reweighted to the laws of
a sweep, on analytic cases whose p is exact (tests/numeric/importance_cases.hpp): one normal input
(or every input, as a per-bay dispersion) whose spread or nominal the sweep changes, a linear limit
state, one set of runs for all the sweep's laws.

  importance_coverage.py --tool build/tests/truss_importance_analytic [--seeds 200] [--jobs 2]
                         [--cache DIR] [--cases TEXT] [--final-mixture]

Per case and law: the share of seeds whose two-sided lognormal interval holds the exact p, the same
for the one-sided 95 % upper bound, the median ratio of the interval's ends, the spread sd(ln p^),
the median effective sample size of the failing runs; without refusals and with the shipped ones
(reweighting.hpp: ESS >= 30, Pareto k <= 0.7; importance_sampling.hpp: the density's mean noise
<= 0.3), the share refused and the coverage of the estimates that stand. Binomial criterion: with n seeds at a true
coverage of 95 %, fewer than n (0.95 - 2.33 sqrt(0.0475 / n)) covering seeds (200 seeds: 91.4 %; 2,000: 93.9 %) happen
with probability 1 %; "<" marks a coverage below it.
"""
import argparse
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

Z2 = 1.959963984540054
Z1 = 1.6448536269514722

# name, beta, all_dims, dims, means, stds, adapt to the mixture
CASES = [
    ("spread, one input, p 1e-3", 3.0902, False, 10, [0.0], [0.7, 0.85, 1.0, 1.2], False),
    ("spread, one input, p 1e-5", 4.2649, False, 10, [0.0], [0.7, 0.85, 1.0, 1.2], False),
    ("spread, one input, p 1e-7", 5.1993, False, 10, [0.0], [0.7, 0.85, 1.0, 1.2], False),
    ("spread, one input, p 1e-7, d 100", 5.1993, False, 100, [0.0], [0.7, 0.85, 1.0, 1.2], False),
    ("spread, one input, p 1e-7, mixture", 5.1993, False, 10, [0.0], [0.7, 0.85, 1.0, 1.2], True),
    ("nominal, one input, p 1e-5", 4.2649, False, 10, [-1.0, -0.5, 0.0, 0.5], [1.0], False),
    ("spread, every input, p 1e-5, d 2", 4.2649, True, 2, [0.0], [0.85, 1.0, 1.15], False),
    ("spread, every input, p 1e-5, d 10", 4.2649, True, 10, [0.0], [0.85, 1.0, 1.15], False),
    ("spread, every input, p 1e-5, d 10, mixture", 4.2649, True, 10, [0.0], [0.85, 1.0, 1.15], True),
    ("spread, every input, p 1e-5, d 30", 4.2649, True, 30, [0.0], [0.85, 1.0, 1.15], False),
    # A sweep as the campaign runs it: the runs at the widest spread (1.15, here the unit law) and
    # the density adapted to the mixture of the values' laws (methods/importance_sweep.hpp).
    ("widest spread's runs, every input, d 2", 3.70861, True, 2, [0.0], [0.73913, 0.86957, 1.0], True),
    ("widest spread's runs, every input, d 10", 3.70861, True, 10, [0.0], [0.73913, 0.86957, 1.0], True),
    ("widest spread's runs, every input, d 30", 3.70861, True, 30, [0.0], [0.73913, 0.86957, 1.0], True),
    ("spread, every input, p 1e-5, d 100", 4.2649, True, 100, [0.0], [0.85, 1.0, 1.15], False),
]


def run(tool, case, seed, count, n, n_final, cache, final_mixture):
    name, beta, all_dims, dims, means, stds, mixture = case
    final_mixture = final_mixture and len(stds) > 1  # a spread sweep's final density (law_mixture.hpp)
    key = f"{name}_{n}_{n_final}_{seed}_{count}{'_fm' if final_mixture else ''}".replace(" ", "_").replace(",", "")
    path = os.path.join(cache, key + ".jsonl") if cache else None
    if path and os.path.exists(path):
        with open(path) as f:
            return [json.loads(line) for line in f]
    cmd = [tool, "--beta", str(beta), "--dims", str(dims), "--n", str(n),
           "--n-final", str(n_final), "--seed", str(seed), "--seeds", str(count),
           "--means", *map(str, means), "--stds", *map(str, stds)]
    if all_dims:
        cmd.append("--all-dims")
    if mixture:
        cmd.append("--adapt-mixture")
    if final_mixture:
        cmd.append("--final-mixture")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    if path:
        with open(path, "w") as f:
            f.write(out)
    return [json.loads(line) for line in out.splitlines()]


def summarise(runs, k):
    """Per law: the spread, the median ESS, and per rule (every estimate with a CoV; the shipped
    refusals) the share refused, the two coverages among the rest, the median interval ratio."""
    laws = [r["laws"][k] for r in runs]
    exact = laws[0]["exact_p"]
    n = len(laws)
    out = {"exact": exact, "mean": laws[0]["mean"], "std": laws[0]["std"]}
    ok = [x for x in laws if x["p"] > 0 and x["cov"] > 0]
    e = [math.log(x["p"] / exact) for x in ok]
    m = sum(e) / len(e) if e else math.nan
    out["spread"] = math.sqrt(sum((v - m) ** 2 for v in e) / (len(e) - 1)) if len(e) > 1 else math.nan
    out["ess"] = sorted(x["ess"] for x in laws)[n // 2]
    out["rules"] = {}
    for rule in ("none", "shipped"):
        kept = [x for x in ok if rule == "none" or not x["refused"]]
        cover = upper = 0
        widths = []
        for x in kept:
            s = math.sqrt(math.log1p(x["cov"] ** 2))
            d = math.log(x["p"] / exact)
            cover += abs(d) <= Z2 * s
            upper += -d <= Z1 * s
            widths.append(math.exp(2 * Z2 * s))
        widths.sort()
        out["rules"][rule] = (1 - len(kept) / n, cover / max(len(kept), 1), upper / max(len(kept), 1),
                              widths[len(widths) // 2] if widths else math.nan)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tool", required=True)
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--n-final", type=int, default=2000)
    ap.add_argument("--cache", default="")
    ap.add_argument("--cases", default="", help="only the cases whose name holds this text")
    ap.add_argument("--final-mixture", action="store_true",
                    help="a spread sweep's final runs from the mixture of its laws at the mean, as campaigns draw "
                         "them (else from N(mu, I))")
    args = ap.parse_args()
    if args.cache:
        os.makedirs(args.cache, exist_ok=True)
    chunk = max(1, args.seeds // (2 * args.jobs))
    floor = 0.95 - 2.33 * math.sqrt(0.0475 / args.seeds)
    print(f"{args.seeds} seeds a case, N = {args.n} a level, {args.n_final} final runs; "
          f"binomial floor {100 * floor:.1f} %; coverage among the estimates not refused")
    with ThreadPoolExecutor(args.jobs) as pool:
        jobs = [(c, [pool.submit(run, args.tool, c, s, min(chunk, args.seeds + 1 - s), args.n, args.n_final,
                                 args.cache, args.final_mixture) for s in range(1, args.seeds + 1, chunk)]) for c in CASES
                if args.cases in c[0]]
        for c, futs in jobs:
            runs = [r for f in futs for r in f.result()]
            mean_runs = sum(r["runs"] for r in runs) / len(runs)
            print(f"\n{c[0]} (d {c[3]}): mean runs {mean_runs:.0f}, "
                  f"{sum(r['status'] != 'converged' for r in runs)} adaptations not converged")
            for k in range(len(runs[0]["laws"])):
                s = summarise(runs, k)
                def cover(r, i):  # "<": below the binomial floor (where any estimate stands)
                    return f"{100 * r[i]:5.1f}{'<' if r[0] < 1 and r[i] < floor else ' '}"
                rules = "  ".join(f"{t}: refused {100 * r[0]:4.1f} % cover {cover(r, 1)}{cover(r, 2)} hi/lo {r[3]:5.2f}"
                                  for t, r in s["rules"].items())
                print(f"   law N({s['mean']:g}, {s['std']:g}^2) p {s['exact']:.3g}: sd(ln p^) {s['spread']:.3f}, "
                      f"median ESS {s['ess']:.0f} | {rules}")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
