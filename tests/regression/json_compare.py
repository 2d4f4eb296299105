#!/usr/bin/env python3
"""Compares two record directories of json_identity.sh to a relative tolerance, for changes that
move numbers at the rounding level: every number field of every JSON summary, and the HDF5
history dumps line by line. Prints each field that differs beyond the tolerance (how many cases,
the worst relative difference and that case) and exits 1 if any does.
  tests/regression/json_compare.py DIR_A DIR_B [--rtol 1e-12] [--ignore rhs_evals,energy_residual_J]
A difference is |a - b| / max(|a|, |b|); fields listed in --ignore (counters, rounding-level
residuals) are reported apart and do not fail the comparison."""
import argparse
import collections
import json
import os
import sys


def walk(x, y, path, case, out, rtol):
    if isinstance(x, dict) and isinstance(y, dict):
        for k in x.keys() | y.keys():
            walk(x.get(k), y.get(k), f"{path}.{k}", case, out, rtol)
    elif isinstance(x, list) and isinstance(y, list) and len(x) == len(y):
        for u, v in zip(x, y):
            walk(u, v, path + "[]", case, out, rtol)
    elif isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
        if x != y:
            r = abs(x - y) / max(abs(x), abs(y))
            if r > rtol and r > out[path][1]:
                out[path][1:] = [r, f"{case}: {x!r} vs {y!r}"]
            if r > rtol:
                out[path][0] += 1
    elif x != y:
        out[path][0] += 1
        out[path][1:] = [float("inf"), f"{case}: {x!r} vs {y!r}"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--rtol", type=float, default=1e-12)
    ap.add_argument("--ignore", default="")
    args = ap.parse_args()
    ignore = {k for k in args.ignore.split(",") if k}
    out = collections.defaultdict(lambda: [0, 0.0, ""])
    n = 0
    for f in sorted(os.listdir(args.a)):
        ta = open(os.path.join(args.a, f)).read()
        tb = open(os.path.join(args.b, f)).read() if os.path.exists(os.path.join(args.b, f)) else None
        n += 1
        if ta == tb:
            continue
        if tb is None:
            out[f][0] += 1
            out[f][1:] = [float("inf"), "missing"]
        elif f.endswith(".json") and ta.strip() and tb.strip():
            walk(json.loads(ta), json.loads(tb), "", f[:-5], out, args.rtol)
        else:  # history dumps: numbers token by token
            for i, (la, lb) in enumerate(zip(ta.split(), tb.split())):
                try:
                    walk(float(la.strip(",")), float(lb.strip(",")), f, f"{f} token {i}", out, args.rtol)
                except ValueError:
                    walk(la, lb, f, f"{f} token {i}", out, args.rtol)
    bad = 0
    for path, (count, worst, example) in sorted(out.items()):
        if count == 0:
            continue
        ignored = path.split(".")[-1] in ignore
        bad += 0 if ignored else 1
        print(f"{'(ignored) ' if ignored else ''}{path}: {count} values beyond {args.rtol:g}, worst {worst:.2e} ({example})")
    print(f"{n} files compared; {bad} fields beyond the tolerance")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
