"""The report page of a standalone importance-sampling campaign (page/sections_importance.py) on real
files of the shipped campaigns/free_rail_miss_rare.toml, made small:

- an estimate that stands (the diagonals' free length lowered to 0.483 m, so that the miss is some
  2.5 standard deviations away and a few hundred runs reach it): p, the interval's ends, the upper
  bound, the ESS and the runs on the page are the file's /importance, read here with h5py; the
  interval is the lognormal one of p and the CoV, p exp(+-z s), s^2 = ln(1 + cov^2), computed here;
  the input the failure needs moved (the free length) comes first, with its value at the density's
  mean, 0.483 m + 0.005 m mu (its normal offset dispersion, std 5 mm), mu read from
  /importance/final_mean; the document block says there is no verdict; the report exits 0;
- a refused estimate (the nominal 0.49 m, one level of 40 runs, 50 final runs: no final run
  reaches the miss): the page says the estimate is refused, with the file's reason, and not to be
  used; the report still exits 0 (a page, no verdict);
- a /importance without p: exit 2 naming the file and the member, nothing written.

  test_importance_page.py --repo SRC --scratch DIR --campaign truss-campaign [--mpiexec mpirun]
"""
import argparse
import html as htmllib
import math
import os
import re
import shutil
import subprocess
import sys

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import FAILS, check  # noqa: E402

PY = "/usr/bin/python3"
CAMPAIGN = os.path.join("campaigns", "free_rail_miss_rare.toml")
Z95 = 1.959963984540054
# Values are kept in data-value as repr(float): exact. The interval recomputed here from p and cov
# agrees to rounding of exp / log1p (a few ulp): 1e-12 relative.
REL = 1e-12


def run_campaign(a, out, sets):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    cmd = [a.mpiexec, "-np", "2", a.campaign, os.path.join(a.repo, CAMPAIGN), "-o", out, "--force",
           "--progress", "none"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    check(os.path.exists(out), f"campaign written (exit {p.returncode}; {p.stderr.strip()[-300:]})")
    return p.returncode


def report(a, h5, out):
    p = subprocess.run([PY, os.path.join(a.repo, "postproc", "report.py"), h5, "-o", out, "--force", "--no-pdf",
                        "--quiet"], capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, f"report exits 0 (a page, no verdict): exit {p.returncode} {p.stderr.strip()[-300:]}")
    path = os.path.join(out, "report.html")
    return (open(path, encoding="utf-8").read() if os.path.exists(path) else ""), p.stdout


def value(page, key):
    m = re.search(r'data-key="' + re.escape(key) + r'" data-value="([^"]+)"', page)
    check(m is not None, f"the page has {key}")
    return float(m.group(1)) if m else float("nan")


def close(a, b):
    return abs(a - b) <= REL * max(abs(a), abs(b))


def text_of(page):
    return htmllib.unescape(re.sub(r"</?(b|code|i|span)\b[^>]*>", "", re.sub(r"<(?!/?(b|code|i|span)\b)[^>]+>", " ", page)))


def check_standing(a):
    h5 = os.path.join(a.scratch, "importance_ok.h5")
    rc = run_campaign(a, h5, ["mast.diagonal_free_length_m=0.483", "ensemble.importance.n_per_level=200",
                              "ensemble.importance.n_final=400", "ensemble.importance.max_levels=4"])
    check(rc == 0, f"campaign exit 0 (an estimate that stands), got {rc}")
    with h5py.File(h5, "r") as f:
        g = f["importance"]
        want = {k: float(g[k][()]) for k in ("p", "cov", "lower", "upper", "upper_bound", "ess", "runs",
                                            "final_runs", "failures")}
        refused = g.attrs["refused"]
        mu = g["final_mean"][()]
        n_levels = len(g["levels/threshold"])
        n_runs = len(f["runs/status"])
    refused = refused.decode() if isinstance(refused, bytes) else str(refused)
    check(refused == "" and want["failures"] > 0, f"the file's estimate stands ({refused!r}, "
                                                  f"{want['failures']:.0f} failing final runs)")
    check(want["runs"] == n_runs, f"/importance/runs = the file's {n_runs} runs")
    page, out = report(a, h5, os.path.join(a.scratch, "importance_ok"))
    for key, k in (("importance.p", "p"), ("importance.p.ci_lo", "lower"), ("importance.p.ci_hi", "upper"),
                   ("importance.p.upper_bound", "upper_bound"), ("importance.ess", "ess"),
                   ("importance.runs", "runs"), ("importance.final_runs", "final_runs"),
                   ("importance.failures", "failures")):
        got = value(page, key)
        check(got == want[k], f"page {key} = /importance/{k} ({got!r} vs {want[k]!r})")
    s = math.sqrt(math.log1p(want["cov"] ** 2))
    lo, hi = want["p"] * math.exp(-Z95 * s), want["p"] * math.exp(Z95 * s)
    check(close(value(page, "importance.p.ci_lo"), lo) and close(value(page, "importance.p.ci_hi"), hi),
          f"the interval is p exp(+-1.96 s) of the CoV: [{lo:.6g}, {hi:.6g}]")
    check(value(page, "importance.levels") == n_levels, f"{n_levels} cross-entropy levels on the page")
    # The inputs: the free length first (the miss needs it moved), its value at mu in metres.
    keys = re.findall(r'data-key="importance\.mu\.([^"]+)\.shift"', page)
    check(keys[:1] == ["mast.diagonal_free_length_m"] and len(keys) == 5,
          f"the free length drives the failure, listed first of 5 inputs ({keys})")
    x = value(page, "importance.mu.mast.diagonal_free_length_m.value")
    check(close(x, 0.483 + 0.005 * float(mu[0])) and float(mu[0]) < -1.0,
          f"its value at the density's mean: 0.483 m + 5 mm x mu ({float(mu[0]):.3g}) = {x:.6g} m")
    t = text_of(page)
    check("none: a failure-probability estimate, p = " in t and "design loads" not in t.lower(),
          "the document block: no verdict, an estimate; no design loads")
    check("estimate is refused" not in t and "not to be used" not in t, "an estimate that stands is not called refused")
    check("IMPORTANCE SAMPLING" in out, "the terminal lines name the estimate")


def check_refused(a):
    h5 = os.path.join(a.scratch, "importance_refused.h5")
    rc = run_campaign(a, h5, ["ensemble.importance.n_per_level=40", "ensemble.importance.max_levels=1",
                              "ensemble.importance.n_final=50"])
    with h5py.File(h5, "r") as f:
        reason = f["importance"].attrs["refused"]
    reason = reason.decode() if isinstance(reason, bytes) else str(reason)
    check(reason != "" and rc == 5, f"the file's estimate is refused ({reason!r}), campaign exit 5 (got {rc})")
    page, out = report(a, h5, os.path.join(a.scratch, "importance_refused"))
    t = " ".join(text_of(page).split())
    check("The estimate is refused: " + " ".join(reason.split()) in t,
          f"the page says the estimate is refused, with the file's reason ({reason!r})")
    check("not to be used" in t and "refused, not to be used" in t,
          "the page and its document block say it is not to be used")
    check("REFUSED" in out, "the terminal lines say refused")


def check_malformed(a):
    """A file whose /importance lacks p: the report's one error line naming the file and the member,
    exit 2, nothing written."""
    src = os.path.join(a.scratch, "importance_ok.h5")
    h5 = os.path.join(a.scratch, "importance_no_p.h5")
    shutil.copyfile(src, h5)
    with h5py.File(h5, "r+") as f:
        del f["importance/p"]
    out = os.path.join(a.scratch, "importance_no_p")
    shutil.rmtree(out, ignore_errors=True)
    p = subprocess.run([PY, os.path.join(a.repo, "postproc", "report.py"), h5, "-o", out, "--no-pdf", "--quiet"],
                       capture_output=True, text=True, timeout=300)
    check(p.returncode == 2 and h5 in p.stderr and "/importance/p" in p.stderr and not os.path.exists(out),
          f"a /importance without p: exit 2 naming the file and the member, nothing written "
          f"(exit {p.returncode}: {p.stderr.strip()[-200:]})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign", required=True)
    ap.add_argument("--mpiexec", default="mpirun")
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    check_standing(a)
    check_refused(a)
    check_malformed(a)
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
