#!/usr/bin/python3
"""No verdict without evidence, and only declared motors judged: postproc/report.py on real campaign
files and on small variants of them written here with h5py (each the real file with one thing
changed, as a damaged run or a different writer would leave it).

Usage:
    test_evidence.py --repo REPO_ROOT --scratch DIR --sweep SWEEP.h5 --velocity VEL.h5
                     --default-motor BAY.h5 --retract RETRACT.h5

SWEEP.h5: a design sweep whose file verdict is PASS (campaigns/motor_sizing.toml, small: 60 runs a
level, 3 levels, 18 to 30 mN m, a target of 0.05);
VEL.h5: a velocity campaign that declares its motor (table1_dispersed); BAY.h5: a velocity campaign
on the scene's default motor (bay_count); RETRACT.h5: a retraction.

1. The sweep as written: PASS, exit 0. Its stored allowable NaN (verdict PASS kept), every estimate
   NaN, the runs of one design value all capped by their wall time, a FAIL stored while the own value
   lies on the safe side: each NOT ASSESSED, exit 4, the reason on the terminal's first line and in
   the page's banner, no "≥ —" anywhere. An upper bound of 1.002 is shown as at most 1. A value list
   shorter than its columns: one `error:` line naming the file and /sweep, exit 2, nothing written.
2. A campaign on the scene's default motor whose file says the campaign declares none
   (motor_declared_by = ""): the motorisation NOT ASSESSED with the reason, no FAIL, exit 4; the same
   file without the attribute is judged as before (FAIL: the default motor is too weak).
3. An ok run without a value of a load: NOT ASSESSED, naming the load, exit 4.
4. A retraction: braking, holding and back-drive listed as not assessed on the page and the terminal.
Prints one line per check; exit 0 when all pass, 1 otherwise.
"""
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


class Case:
    """A copy of a real file, changed by `edit` (an h5py.File -> None), and its report."""

    def __init__(self, a, source, name, edit=None, *opts):
        self.h5 = os.path.join(a.scratch, f"{name}.h5")
        self.out = os.path.join(a.scratch, name)
        shutil.copyfile(source, self.h5)
        if edit is not None:
            with h5py.File(self.h5, "a") as f:
                edit(f)
        shutil.rmtree(self.out, ignore_errors=True)
        self.p = subprocess.run([PY, os.path.join(a.repo, "postproc", "report.py"), self.h5, "-o", self.out,
                                 "--quiet", "--no-pdf", *opts], capture_output=True, text=True)
        self.first = self.p.stdout.splitlines()[0] if self.p.stdout else ""
        page = os.path.join(self.out, "report.html")
        self.page = open(page, encoding="utf-8").read() if os.path.exists(page) else ""
        self.text = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<style>.*?</style>", " ", self.page, flags=re.S)))

    def verdict(self):
        m = re.search(r"data-key='verdict' data-value='(\w+)'", self.page)
        return m.group(1) if m else None


def replace(f, name, values):
    """Rewrites dataset /name with `values` (same dtype and attributes)."""
    attrs, dtype = dict(f[name].attrs), f[name].dtype
    del f[name]
    f.create_dataset(name, data=np.asarray(values), dtype=dtype)
    f[name].attrs.update(attrs)


def check_sweep(a):
    c = Case(a, a.sweep, "sweep_as_written")
    check(c.p.returncode == 0 and c.first.startswith("VERDICT: PASS") and c.verdict() == "pass",
          f"sweep as written: PASS, exit 0 ({c.first!r}, exit {c.p.returncode})")
    with h5py.File(a.sweep, "r") as f:
        values, n = f["sweep/values"][()], len(f["sweep/values"])
        own, safe = float(f["sweep/allowable/own_value"][()]), f["sweep/allowable"].attrs["safe_side"]
    cases = [
        ("sweep_allowable_nan", lambda f: replace(f, "sweep/allowable/value", np.nan), "allowable is not a number"),
        ("sweep_every_p_nan", lambda f: [replace(f, f"sweep/{k}", np.full(n, np.nan))
                                         for k in ("p", "cov", "upper_bound", "lower", "upper")],
         "no design value has an estimate"),
        ("sweep_capped_runs", lambda f: replace(f, "runs/status", np.where(f["runs/sweep_value"][()] == values[-1], 6,
                                                                             f["runs/status"][()])),
         "gave no result"),
        ("sweep_fail_on_the_safe_side", lambda f: f["sweep/allowable"].attrs.__setitem__("verdict", "FAIL"),
         "names the other side"),
    ]
    for name, edit, reason in cases:
        c = Case(a, a.sweep, name, edit)
        check(c.p.returncode == 4 and c.first.startswith("VERDICT: NOT ASSESSED") and reason in c.first
              and c.verdict() == "not_assessed" and reason in c.text and "≥ —" not in c.text + c.p.stdout,
              f"{name}: NOT ASSESSED, exit 4, '{reason}' on the terminal and the page "
              f"({c.first[:160]!r}, exit {c.p.returncode})")
    c = Case(a, a.sweep, "sweep_upper_above_one", lambda f: replace(f, "sweep/upper", np.r_[1.002, f["sweep/upper"][1:]]))
    shown = [float(v) for v in re.findall(r'data-key="sweep\.upper\d+" data-value="([^"]+)"', c.page)]
    check(len(shown) == n and max(shown) <= 1.0 and shown[0] == 1.0,
          f"an upper bound of 1.002 is shown as 1 (data-values {shown[:2]})")
    c = Case(a, a.sweep, "sweep_short_values", lambda f: replace(f, "sweep/values", f["sweep/values"][:-1]))
    err = c.p.stderr.strip().splitlines()
    check(c.p.returncode == 2 and len(err) == 1 and err[0].startswith(f"error: {c.h5}: /sweep/")
          and "Traceback" not in c.p.stderr and not os.path.exists(c.out),
          f"a /sweep value list shorter than its columns: one line naming the file and /sweep, exit 2, nothing "
          f"written ({err[:1]}, exit {c.p.returncode})")
    check(safe in ("above", "below") and np.isfinite(own), "the sweep's own value and safe side are in the file")


def check_declared_motor(a):
    c = Case(a, a.default_motor, "default_motor_judged",
             lambda f: f.attrs.__delitem__("motor_declared_by") if "motor_declared_by" in f.attrs else None)
    check(c.p.returncode == 3 and "data-item='margin' data-kind='fail'" in c.page,
          f"a file without motor_declared_by is judged against the scene's motor (FAIL, exit {c.p.returncode})")
    c = Case(a, a.default_motor, "default_motor_undeclared", lambda f: f.attrs.__setitem__("motor_declared_by", ""),
             "--levels", "90")
    check(c.p.returncode == 4 and c.verdict() == "not_assessed" and "data-kind='fail'" not in c.page
          and "data-item='margin.undeclared' data-kind='not_assessed'" in c.page
          and "declares no motor" in c.first + c.p.stdout,
          f"an undeclared motor: NOT ASSESSED with the reason, no FAIL, exit 4 ({c.first!r}, exit {c.p.returncode})")
    check("torque needed" in c.p.stdout and "no motor to compare it with" in c.p.stdout,
          "an undeclared motor: the terminal still gives the torque needed")
    c = Case(a, a.velocity, "declared_motor", lambda f: f.attrs.__setitem__("motor_declared_by", "campaign line 28"),
             "--levels", "90")
    check(c.p.returncode == 0 and c.verdict() == "pass", f"a declared motor is judged (PASS, exit {c.p.returncode})")


def check_missing_values(a):
    # A load outside /stats' six outputs, so that the file's stored statistics stay consistent.
    def nan_in_an_ok_run(f):
        x = f["runs/start_drive_impulse_Ns"][()]
        x[int(np.nonzero(f["runs/status"][()] == 0)[0][0])] = np.nan
        replace(f, "runs/start_drive_impulse_Ns", x)
    c = Case(a, a.velocity, "ok_run_without_a_value", nan_in_an_ok_run, "--levels", "90")
    check(c.p.returncode == 4 and "data-item='load_missing.start drive impulse'" in c.page
          and "have no value of the start drive impulse" in c.p.stdout,
          f"an ok run without a value: NOT ASSESSED naming the load, exit 4 (exit {c.p.returncode})")


def check_retraction(a):
    c = Case(a, a.retract, "retraction", None, "--levels", "90")
    items = re.findall(r"data-item='retract\.([\w-]+)' data-kind='not_assessed'", c.page)
    check(items == ["braking", "holding", "back-drive"] and c.p.returncode == 4
          and "nothing fails and every requirement was assessed" not in c.page,
          f"a retraction lists braking, holding, back-drive as not assessed ({items}, exit {c.p.returncode})")
    check(all(f"NOT ASSESSED: {w}:" in c.p.stdout for w in ("braking", "holding", "back-drive")),
          "a retraction: the same three lines on the terminal")


def main():
    ap = argparse.ArgumentParser()
    for k in ("--repo", "--scratch", "--sweep", "--velocity", "--default-motor", "--retract"):
        ap.add_argument(k, required=True)
    a = ap.parse_args()
    shutil.rmtree(a.scratch, ignore_errors=True)
    os.makedirs(a.scratch)
    check_sweep(a)
    check_declared_motor(a)
    check_missing_values(a)
    check_retraction(a)
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
