#!/usr/bin/python3
"""A design sweep's verdict said once: the file's /sweep/allowable@verdict and @reason (truss-campaign
decides them), the campaign's terminal line "VERDICT: <word> — <reason>" and exit status, and the
report page's verdict (data-key='verdict': data-value and data-reason) and exit status say the same.

  test_sweep_verdict_agree.py --repo SRC --scratch DIR --campaign truss-campaign

- assessed: campaigns/motor_sizing.toml as subset simulation at each value, few runs per level, a target of 1e-3 its values
  reach: every run ok, so no value is untrusted; the verdict PASS or FAIL, exits 0 (report: 0 or 3).
- capped: campaigns/tolerance_allocation.toml with run.max_steps = 1000 (a free deployment takes
  tens of thousands of steps): every run ends step_limit (/runs/status counted here), so every
  value's runs are all unusable and every estimate untrusted: NOT ASSESSED, campaign exit 6,
  report exit 4, no allowable (NaN) in the file.
- wall: the same sweep with ensemble.max_run_wall_time_s = 1e-5 s (no run deploys in 10 us): the
  same NOT ASSESSED with exit 6.
Every probability bound the file writes lies in [0, 1]."""
import argparse
import html
import os
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

PY = "/usr/bin/python3"
from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)
WORDS = {"pass": "PASS", "fail": "FAIL", "not_assessed": "NOT ASSESSED"}
REPORT_EXIT = {"PASS": 0, "FAIL": 3, "NOT ASSESSED": 4}


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def run_campaign(a, name, h5, extra):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [a.campaign, os.path.join(a.repo, "campaigns", f"{name}.toml"), "-o", h5, "--force",
           "--progress", "none", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    lines = [x for x in p.stderr.splitlines() if x.startswith("[truss-campaign] VERDICT: ")]
    return p.returncode, lines, p.stderr


def read_file(h5):
    with h5py.File(h5, "r") as f:
        a = f["sweep/allowable"]
        g = f["sweep"]
        cols = {k: g[k][()] for k in ("runs", "unusable", "upper_bound", "lower", "upper")}
        cols["untrusted"] = [text(x) for x in g["untrusted"][()]]
        ok = int(np.sum(f["runs/status"][()] == 0))
        return (text(a.attrs["verdict"]), text(a.attrs["reason"]), float(a["value"][()]), cols, ok,
                len(f["runs/status"]))


def read_page(out):
    with open(os.path.join(out, "report.html"), encoding="utf-8") as fh:
        m = re.search(r"data-key='verdict' data-value='([a-z_]+)' data-reason='([^']*)'", fh.read())
    return (WORDS.get(m.group(1), m.group(1)), html.unescape(m.group(2))) if m else ("", "")


def one_case(a, label, name, extra, want_not_assessed):
    h5 = os.path.join(a.scratch, f"{label}.h5")
    out = os.path.join(a.scratch, f"{label}_report")
    rc, lines, err = run_campaign(a, name, h5, extra)
    if not check(os.path.exists(h5) and len(lines) == 1,
                 f"{label}: file written, one terminal verdict line ({err.strip()[-300:]})"):
        return
    verdict, reason, allowable, cols, n_ok, n = read_file(h5)
    term = lines[0][len("[truss-campaign] VERDICT: "):]
    check(term == f"{verdict} — {reason}", f"{label}: terminal '{term[:120]}' = file '{verdict} — {reason[:80]}'")
    shutil.rmtree(out, ignore_errors=True)
    r = subprocess.run([PY, os.path.join(a.repo, "postproc", "report.py"), h5, "-o", out, "--quiet", "--no-pdf"],
                       capture_output=True, text=True)
    page_verdict, page_reason = read_page(out)
    check(page_verdict == verdict and page_reason == reason,
          f"{label}: page {page_verdict!r} ({page_reason[:60]!r}) = file {verdict!r}")
    check(r.returncode == REPORT_EXIT.get(verdict, -1), f"{label}: report exit {r.returncode} for {verdict}")
    for k in ("upper_bound", "lower", "upper"):
        x = cols[k][np.isfinite(cols[k])]
        check(bool(np.all((x >= 0) & (x <= 1))), f"{label}: /sweep/{k} in [0, 1] ({x.tolist()})")
    if want_not_assessed:
        check(n_ok == 0, f"{label}: every run capped ({n_ok} of {n} ok in /runs/status)")
        check(verdict == "NOT ASSESSED" and rc == 6, f"{label}: NOT ASSESSED, exit 6 (got {verdict}, {rc})")
        check(np.array_equal(cols["unusable"], cols["runs"]) and all(cols["untrusted"]),
              f"{label}: every value's runs unusable ({cols['unusable'].tolist()} of {cols['runs'].tolist()}), "
              f"every value untrusted")
        check(np.isnan(allowable) and "no usable result" in reason, f"{label}: no allowable; reason {reason[:100]!r}")
    else:
        check(n_ok == n and not any(cols["untrusted"]) and int(np.sum(cols["unusable"])) == 0,
              f"{label}: every run ok ({n_ok} of {n}), no value untrusted")
        check(verdict in ("PASS", "FAIL") and rc == 0, f"{label}: PASS or FAIL, exit 0 (got {verdict}, {rc})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign", required=True, help="the truss-campaign program")
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    one_case(a, "assessed", "motor_sizing",
             ["--set", "ensemble.method=subset", "--set", "ensemble.importance=false",
              "--set", "ensemble.subset.n_per_level=200", "--set", "ensemble.subset.max_levels=4",
              "--set", "sweep.from=0.028", "--set", "sweep.to=0.036", "--set", "sweep.count=5",
              "--set", "sweep.refine=0", "--set", "sweep.target_probability=1e-3"], False)
    small = ["--set", "ensemble.importance.n_per_level=100", "--set", "ensemble.importance.max_levels=3",
             "--set", "ensemble.importance.n_final=100"]
    one_case(a, "capped", "tolerance_allocation", small + ["--set", "run.max_steps=1000"], True)
    one_case(a, "wall", "tolerance_allocation", small + ["--set", "ensemble.max_run_wall_time_s=1e-5"], True)
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
