#!/usr/bin/python3
"""Every shipped campaign (campaigns/*.toml) run small on 2 ranks and its report built (HTML and
PDF), once, for the tests that read them (ctest fixture shipped_reports: postproc_verdicts reads
the pages for "NaN" and units, postproc_pdf_layout compares each PDF with its HTML).

Usage:
    shipped_reports.py --repo REPO --scratch DIR --campaign TRUSS_CAMPAIGN [--mpiexec MPIEXEC]

Writes DIR/<name>.h5 and DIR/report_<name>/ (report.html, report.pdf) for each campaign;
report_dirs() names them for the readers, and fails for a campaign whose report is missing.
Prints one line per check; exit 0 when every campaign ran and every report was built, 1 otherwise.
"""
import argparse
import glob
import os
import shutil
import subprocess
import sys

from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)

PY = "/usr/bin/python3"
# Few runs per shipped campaign: enough for every section of its report to have data, cheap on 2
# cores. A campaign not named here runs with 20 runs.
SMALL = {"table1_sensitivity": ["--set", "ensemble.n_runs=40"],     # 4 blocks of 8 + 2
         # importance sampling, the free length lowered so that a few hundred runs reach the miss
         "free_rail_miss_rare": ["--set", "mast.diagonal_free_length_m=0.483", "--set", "ensemble.importance.n_per_level=100",
                                 "--set", "ensemble.importance.max_levels=3", "--set", "ensemble.importance.n_final=200"],
         "motor_torque": ["--set", "ensemble.n_runs=16", "--set", "ensemble.stop=false"],
         # design sweeps: one small importance-sampling campaign reweighted to every value
         "motor_sizing": ["--set", "ensemble.importance.n_per_level=40", "--set", "ensemble.importance.max_levels=2",
                          "--set", "ensemble.importance.n_final=100"],
         "tolerance_allocation": ["--set", "ensemble.importance.n_per_level=40",
                                  "--set", "ensemble.importance.max_levels=2", "--set", "ensemble.importance.n_final=100"]}
# Exit statuses: truss-campaign 0 ok, 1 some runs not ok, 6 a sweep NOT ASSESSED (a few runs per
# value give no allowable); postproc/report.py 0 PASS, 3 FAIL, 4 NOT ASSESSED.
CAMPAIGN_EXITS = (0, 1, 6)
REPORT_EXITS = (0, 3, 4)


def shipped_names(repo):
    return [os.path.basename(t)[:-5] for t in sorted(glob.glob(os.path.join(repo, "campaigns", "*.toml")))]


def report_dirs(repo, scratch):
    """(name, DIR/report_<name>) for every shipped campaign; a check fails for each one missing."""
    out = []
    for name in shipped_names(repo):
        d = os.path.join(scratch, f"report_{name}")
        if check(os.path.exists(os.path.join(d, "report.html")), f"{name}: its report built by shipped_reports.py"):
            out.append((name, d))
    return out


def run_campaign(a, name, out, extra):
    """campaigns/<name>.toml run on 2 ranks into `out` with the options `extra`; checked written."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    cmd = [a.mpiexec, "-np", "2", a.campaign, os.path.join(a.repo, "campaigns", f"{name}.toml"),
           "-o", out, "--force", "--progress", "none", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    return check(p.returncode in CAMPAIGN_EXITS and os.path.exists(out),
                 f"{name}: campaign written (exit {p.returncode}) {p.stderr.strip()[-300:]}")


def build(a, name):
    h5 = os.path.join(a.scratch, f"{name}.h5")
    if not run_campaign(a, name, h5, SMALL.get(name, ["--set", "ensemble.n_runs=20"])):
        return
    out = os.path.join(a.scratch, f"report_{name}")
    p = subprocess.run([PY, os.path.join(a.repo, "postproc", "report.py"), h5, "-o", out, "--force", "--quiet"],
                       capture_output=True, text=True)
    check(p.returncode in REPORT_EXITS and os.path.exists(os.path.join(out, "report.pdf")),
          f"{name}: report and PDF written (exit {p.returncode}) {p.stderr.strip()[-300:]}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign", required=True, help="the truss-campaign program")
    ap.add_argument("--mpiexec", default="mpirun")
    a = ap.parse_args()
    shutil.rmtree(a.scratch, ignore_errors=True)
    os.makedirs(a.scratch)
    for name in shipped_names(a.repo):
        build(a, name)
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
