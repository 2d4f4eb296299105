#!/usr/bin/python3
"""Coverage and width of subset simulation's 95 % intervals on analytic limit states whose
failure probability is known exactly: the linear limit state g(z) = beta - sum_j z_j / sqrt(d)
(p = Phi(-beta)) and the outside of a sphere (chi-square), over many master seeds, for each
Markov proposal and each CoV the summary gives.

  subset_coverage.py --tool build/tests/truss_subset_analytic [--seeds 200] [--jobs 2]
                     [--dims 2 10 100] [--p 1e-3 1e-5 1e-7] [--n 500 2000]
                     [--proposals modified_metropolis adaptive_conditional] [--cache DIR] [--markdown]

For each case and CoV rule it prints the share of seeds whose two-sided interval
p^ exp(-+1.96 s), s^2 = ln(1 + cov^2), holds the exact p, the same for the one-sided 95 % upper
bound p^ exp(1.645 s), the median ratio of the interval's ends (exp(2 1.96 s)) and the spread
sd(ln p^) over the seeds. Binomial criterion: with n seeds and a true coverage of 95 %, the count
of covering seeds falls below n (0.95 - 2.33 sqrt(0.0475 / n)) (200 seeds: 91.4 %) with
probability 1 %; a rule below that in a case misses its confidence there.
"""
import argparse
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

Z2 = 1.959963984540054   # two-sided 95 %
Z1 = 1.6448536269514722  # one-sided 95 %


def run_case(tool, case, size, dims, n, proposal, seeds, first_seed, cache):
    key = f"{case}_{size:.6f}_d{dims}_n{n}_{proposal}_s{first_seed}_{seeds}.jsonl"
    path = os.path.join(cache, key) if cache else None
    if path and os.path.exists(path):
        with open(path) as f:
            return [json.loads(line) for line in f]
    out = subprocess.run([tool, "--case", case, "--size", repr(size), "--dims", str(dims), "--n", str(n),
                          "--proposal", proposal, "--seed", str(first_seed), "--seeds", str(seeds)],
                         check=True, capture_output=True, text=True).stdout
    if path:
        with open(path, "w") as f:
            f.write(out)
    return [json.loads(line) for line in out.splitlines()]


def rules(r):
    """The CoV of each interval rule for one run."""
    return {"cov_bound": r["cov_bound"], "cov (Au & Beck)": r["cov"], "cov_lineage": r["cov_lineage"],
            "cov_lag1": r["cov_lag"][1], "cov_interval": r["cov_interval"]}


def summarise(runs):
    exact = runs[0]["exact_p"]
    ok = [r for r in runs if r["p"] > 0 and math.isfinite(r["p"])]
    e = [math.log(r["p"] / exact) for r in ok]
    mean = sum(e) / len(e)
    spread = math.sqrt(sum((x - mean) ** 2 for x in e) / (len(e) - 1))
    ratio = [r["p"] / exact for r in ok]
    rmean = sum(ratio) / len(ratio)
    rse = math.sqrt(sum((x - rmean) ** 2 for x in ratio) / (len(ratio) - 1) / len(ratio))
    runs_mean = sum(r["runs"] for r in runs) / len(runs)
    out = {"exact": exact, "seeds": len(runs), "usable": len(ok), "spread": spread, "bias": mean,
           "mean_ratio": rmean, "mean_ratio_se": rse, "runs": runs_mean, "work": spread ** 2 * runs_mean,
           "rules": {}}
    names = rules(ok[0]).keys()
    for name in names:
        cover = upper = 0
        widths = []
        for r, x in zip(ok, e):
            c = rules(r)[name]
            s = math.sqrt(math.log1p(c * c)) if math.isfinite(c) else math.inf
            cover += abs(x) <= Z2 * s
            upper += -x <= Z1 * s
            widths.append(math.exp(2 * Z2 * s) if math.isfinite(s) else math.inf)
        widths.sort()
        out["rules"][name] = (cover / len(runs), upper / len(runs), widths[len(widths) // 2])
    return out


def print_markdown(jobs):
    """Today's rule (modified Metropolis, cov_bound) beside the new one (aCS, cov_interval), a row per case."""
    done = {c: summarise([r for f in futs for r in f.result()]) for c, futs in jobs}
    print("\n| case | d | N | p | runs | sd(ln p^): MM / aCS | cov_bound (MM): two-sided, upper, hi/lo "
          "| cov_interval (aCS): two-sided, upper, hi/lo |")
    print("|---|---:|---:|---:|---:|---|---|---|")
    for c in done:
        if c[4] != "modified_metropolis":
            continue
        a = done.get((c[0], c[1], c[2], c[3], "adaptive_conditional"))
        m = done[c]
        if a is None:
            continue
        b, i = m["rules"]["cov_bound"], a["rules"]["cov_interval"]
        print(f"| {c[0]} | {c[2]} | {c[3]} | {m['exact']:.1e} | {a['runs']:,.0f} | {m['spread']:.2f} / "
              f"{a['spread']:.2f} | {100 * b[0]:.1f} %, {100 * b[1]:.1f} %, {b[2]:.1f} | {100 * i[0]:.1f} %, "
              f"{100 * i[1]:.1f} %, {i[2]:.1f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tool", required=True)
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--dims", type=int, nargs="+", default=[2, 10, 100])
    ap.add_argument("--p", type=float, nargs="+", default=[1e-3, 1e-5, 1e-7])
    ap.add_argument("--n", type=int, nargs="+", default=[500, 2000])
    ap.add_argument("--proposals", nargs="+", default=["modified_metropolis", "adaptive_conditional"])
    ap.add_argument("--sphere", action="store_true", help="also the outside of a sphere (d = 10, p ~ 1e-4)")
    ap.add_argument("--cache", default="")
    ap.add_argument("--markdown", action="store_true",
                    help="one table: modified Metropolis with cov_bound beside adaptive conditional sampling with "
                         "cov_interval (needs both proposals)")
    args = ap.parse_args()
    if args.cache:
        os.makedirs(args.cache, exist_ok=True)
    from scipy.stats import norm
    cases = [("linear", -norm.ppf(p), d, n, prop) for p in args.p for d in args.dims for n in args.n
             for prop in args.proposals]
    if args.sphere:
        cases += [("sphere", 5.963, 10, n, prop) for n in args.n for prop in args.proposals]
    chunk = max(1, args.seeds // (2 * args.jobs))
    jobs = []
    with ThreadPoolExecutor(args.jobs) as pool:
        for c in cases:
            parts = [(s, min(chunk, args.first_seed + args.seeds - s))
                     for s in range(args.first_seed, args.first_seed + args.seeds, chunk)]
            jobs.append((c, [pool.submit(run_case, args.tool, *c, k, s, args.cache) for s, k in parts]))
        floor = 0.95 - 2.33 * math.sqrt(0.0475 / args.seeds)
        print(f"{args.seeds} seeds per case; binomial floor of the two-sided coverage: {100 * floor:.1f} %")
        if args.markdown:
            print_markdown(jobs)
            return
        for c, futs in jobs:
            runs = [r for f in futs for r in f.result()]
            s = summarise(runs)
            print(f"\n{c[0]} d={c[2]} N={c[3]} {c[4]}: p={s['exact']:.3g}, mean runs {s['runs']:.0f}, "
                  f"spread sd(ln p^) {s['spread']:.3f} (x sqrt(runs/1000): {math.sqrt(s['work'] / 1000):.3f}), "
                  f"mean p^/p {s['mean_ratio']:.3f} +- {s['mean_ratio_se']:.3f}")
            for name, (cov, up, w) in s["rules"].items():
                flag = " <" if cov < floor else ""
                print(f"   {name:34s} two-sided {100 * cov:5.1f} %{flag:2s} upper bound {100 * up:5.1f} %  "
                      f"median hi/lo {w:7.2f}")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
