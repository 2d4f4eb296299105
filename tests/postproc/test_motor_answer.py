#!/usr/bin/python3
"""One motor answer on both pages, the per-bay design values and the exports beside the PDF, on
small real files: a load-report campaign (table1_dispersed, 300 runs) and the motor-sizing sweep of
the same mast (small: 60 runs a level). Every number is recomputed here from the HDF5 files with
numpy/scipy, independently of truss_report.

Usage:
    test_motor_answer.py --repo REPO --scratch DIR --load LOAD.h5 --sweep SWEEP.h5

1. The two pages refer to each other: the load report (--compare-with SWEEP.h5) and the sweep's
   page (--compare-with LOAD.h5) each show both stall torques, as data-values and as printed text:
   the load report's, the upper 95 % bound of the P99 (--levels 99: 300 runs give it) of the
   file's per-run motorisation_stall_torque_Nm (the binomial rank written out here), and the
   sweep's allowable (/sweep/allowable/value); both name the larger as governing. Without
   --compare-with each page says the other figure is not shown.
2. Files that are not the same mast (a sweep whose base scene has another diagonal stiffness), a
   load report paired with a plain campaign, a sweep paired with a sweep: exit 2, one `error:` line
   naming the file, nothing written.
3. The exports: design_loads.csv, structural_margins.csv, motorisation.csv, bay_loads.csv, sweep.csv
   read back and compared with the page's data-values and with values recomputed from the file;
   verdict.json against the page's verdict and its items.
4. The per-bay table: P99 and its upper bound per bay of lock time, latch energy, pin force and
   entry impulse, recomputed; the motorisation chart's PNG exists.
Prints one line per check; exit 0 when all pass, 1 otherwise.
"""
import argparse
import csv
import html
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib

import h5py
import numpy as np
from scipy.stats import binom

PY = "/usr/bin/python3"
from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)
LEVEL, CONF = 0.99, 0.95
RTOL = 1e-12      # the same float64 values, read back from 17 significant digits or repr


def close(a, b):
    return (np.isnan(a) and np.isnan(b)) or abs(a - b) <= RTOL * max(abs(a), abs(b), 1e-300)


def report(repo, h5, out, *opts):
    shutil.rmtree(out, ignore_errors=True)
    return subprocess.run([PY, os.path.join(repo, "postproc", "report.py"), h5, "-o", out, "--quiet", *opts],
                          capture_output=True, text=True)


def page_values(out):
    """{data-key: data-value} and the visible text of report.html."""
    with open(os.path.join(out, "report.html"), encoding="utf-8") as fh:
        page = fh.read()
    values = {k: v for k, v in re.findall(r"data-key=[\"']([^\"']+)[\"'][^>]*?data-value=[\"']([^\"']*)[\"']", page)}
    body = re.sub(r"<style\b.*?</style>", " ", page, flags=re.S)
    return values, page, " ".join(html.unescape(re.sub(r"<[^>]+>", " ", body)).split())


def upper_bound(x, p=LEVEL, conf=CONF):
    """The one-sided upper bound of the p-quantile: x_(k), k the smallest rank with
    F_Binom(k - 1; n, p) >= conf (the CDF summed here term by term)."""
    x = np.sort(x)
    n = len(x)
    cdf = np.cumsum(binom.pmf(np.arange(n + 1), n, p))
    k = int(np.argmax(cdf >= conf - 1e-14)) + 1
    return float(x[k - 1]) if k <= n and cdf[k - 1] >= conf - 1e-14 else float("nan")


def type7(x, p):
    x = np.sort(x)
    h = (len(x) - 1) * p
    lo = int(np.floor(h))
    return float(x[lo] + (h - lo) * (x[min(lo + 1, len(x) - 1)] - x[lo]))


def stall_needed(load):
    """The load report's figure from the file's per-run columns alone."""
    with h5py.File(load) as f:
        ok = f["runs/status"][:] == 0
        need = f["runs/motorisation_stall_torque_Nm"][:]
        req = f["runs/motorisation_required_torque_Nm"][:]
        avail = f["runs/motorisation_available_torque_Nm"][:]
    sel = ok & np.isfinite(req) & (req > 0) & np.isfinite(avail) & ~np.isnan(need)
    return upper_bound(need[sel])


def shown(text, value_si, unit_factor=1e-3):
    """A torque (N m) printed in mN m on the page, at any of 1 to 5 decimals."""
    return any(f"{value_si / unit_factor:.{d}f} mN m" in text for d in range(0, 6))


def check_pair(a, load_out, sweep_out):
    p1 = report(a.repo, a.load, load_out, "--compare-with", a.sweep, "--levels", "99")
    p2 = report(a.repo, a.sweep, sweep_out, "--compare-with", a.load, "--levels", "99")
    check(p1.returncode in (0, 3, 4) and p2.returncode in (0, 3, 4),
          f"both reports written (exit {p1.returncode}, {p2.returncode}) {p1.stderr[-200:]}{p2.stderr[-200:]}")
    need = stall_needed(a.load)
    with h5py.File(a.sweep) as f:
        allowable = float(f["sweep/allowable/value"][()])
    check(np.isfinite(need) and np.isfinite(allowable), f"both figures defined: {need}, {allowable} N m")
    governs = "load_report" if need >= allowable else "sweep"
    for name, out, stdout in (("load report", load_out, p1.stdout), ("sweep page", sweep_out, p2.stdout)):
        v, page, text = page_values(out)
        check(close(float(v.get("motor_answer.load_report", "nan")), need),
              f"{name}: the load report's stall torque needed {v.get('motor_answer.load_report')} = {need} N m "
              "(upper 95 % bound of the P99 of motorisation_stall_torque_Nm)")
        check(close(float(v.get("motor_answer.sweep", "nan")), allowable),
              f"{name}: the sweep's allowable {v.get('motor_answer.sweep')} = /sweep/allowable/value {allowable}")
        check(shown(text, need) and shown(text, allowable), f"{name}: both figures printed in mN m")
        check(v.get("motor_answer.governs") == governs and "governs" in text,
              f"{name}: the larger figure ({governs}) governs ({v.get('motor_answer.governs')})")
        check("motor answer:" in stdout and "governs" in stdout, f"{name}: the terminal names both figures")
    v1, v2 = page_values(load_out)[0], page_values(sweep_out)[0]
    check(close(float(v1["mech.stall_needed"]), need), "load report: its own ECSS table has the same figure")
    check(close(float(v2["sweep.allowable"]), allowable), "sweep page: its own allowable is the same figure")


def check_alone(a):
    """Without --compare-with each page says the other figure is missing."""
    for name, h5 in (("load report", a.load), ("sweep page", a.sweep)):
        out = os.path.join(a.scratch, f"alone_{name[:4]}")
        p = report(a.repo, h5, out, "--no-pdf")
        v, _, text = page_values(out)
        check(p.returncode in (0, 3, 4) and v.get("motor_answer.governs") == "none" and "--compare-with" in text
              and "motor_answer.sweep" not in v, f"{name} alone: the other figure is said to be missing")


def check_refused(a):
    other = os.path.join(a.scratch, "other_mast.h5")
    shutil.copyfile(a.sweep, other)
    with h5py.File(other, "a") as f:
        scene = f.attrs["base_scene_toml"]
        scene = scene if isinstance(scene, str) else scene.decode()
        k = tomllib.loads(scene)["mast"]["diagonal_stiffness_N_per_m"]
        f.attrs["base_scene_toml"] = re.sub(r"(diagonal_stiffness_N_per_m\s*=\s*)[^\n#]+", rf"\g<1>{2 * k}", scene)
    cases = [("another mast", a.load, other, "diagonal_stiffness_N_per_m"),
             ("a plain campaign for a load report", a.load, a.load, "no /sweep"),
             ("a sweep for a sweep", a.sweep, a.sweep, "load report's campaign")]
    for name, h5, cmp, word in cases:
        out = os.path.join(a.scratch, "refused")
        p = report(a.repo, h5, out, "--compare-with", cmp)
        lines = p.stderr.strip().splitlines()
        check(p.returncode == 2 and len(lines) == 1 and lines[0].startswith("error:") and word in lines[0]
              and not os.path.exists(out), f"refused, {name}: exit {p.returncode}, {lines[-1:]}")


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def num(s):
    return float(s) if s not in ("",) else float("nan")


def check_design_csv(a, out, v):
    head, rows = read_csv(os.path.join(out, "design_loads.csv"))
    check(all("[" in h for h in head if h not in ("load", "label", "unit")), "design_loads.csv: units in the header")
    with h5py.File(a.load) as f:
        ok = f["runs/status"][:] == 0
        for row in rows:
            r = dict(zip(head, row))
            key = r["load"]
            if key in f["runs"] and f["runs"][key].ndim == 1:
                x = f["runs"][key][:]
            else:
                b = f["runs/bays"][key][:]
                x = np.where(np.all(np.isnan(b), axis=1), np.nan, np.nanmax(np.where(np.isnan(b), -np.inf, b), axis=1))
            x = x[ok & np.isfinite(x)]
            est, ub = num(r["P99 [unit]"]), num(r["upper 95 % bound of P99 [unit]"])
            check(close(est, type7(x, LEVEL)) and close(ub, upper_bound(x)) and close(ub, float(v[f"design.{key}.p99.ucb"]))
                  and close(est, float(v[f"design.{key}.p99"])), f"design_loads.csv {key}: P99 and its bound = file, page")


def check_structure_csv(a, out, v):
    head, rows = read_csv(os.path.join(out, "structural_margins.csv"))
    with h5py.File(a.load) as f:
        structure = tomllib.loads(f.attrs["base_scene_toml"])["structure"]
    fos = {"yield": structure.get("yield_factor", 1.1), "ultimate": structure.get("ultimate_factor", 1.25)}
    n = 0
    for row in rows:
        r = dict(zip(head, row))
        allowable = structure.get(f"{r['load']}_{r['limit']}_allowable_{r['unit']}")
        mos = num(r["MoS [1]"])
        want = allowable / (fos[r["limit"]] * num(r["design load [unit]"])) - 1 if allowable else float("nan")
        page = float(v.get(f"structure.{r['load']}.{r['limit']}.mos", "nan")) if not r["bay [1]"] else want
        n += close(mos, want) and close(mos, page)
    check(n == len(rows) and n > 0, f"structural_margins.csv: MoS of {n} of {len(rows)} rows = allowable / (FoS x load) - 1 "
                                    "(and the page's)")


def check_motor_csv(out, v):
    head, rows = read_csv(os.path.join(out, "motorisation.csv"))
    keyed = {r[0]: r for r in rows}
    keyed_num = {k: r for k, r in keyed.items() if k != "motor_answer.governs"}
    same = [k for k in keyed_num if k in v and close(num(keyed[k][3]), float(v[k]))]
    check(head == ["key", "quantity", "unit", "value [unit]"] and len(same) >= 15
          and len(same) == len([k for k in keyed_num if k in v]) and keyed["mech.t_min"][2] == "N m",
          f"motorisation.csv: {len(same)} values = the page's data-values, torques in N m")
    check(keyed["motor_answer.governs"][3] == v["motor_answer.governs"], "motorisation.csv: the governing figure")


def check_bays(a, out, v):
    head, rows = read_csv(os.path.join(out, "bay_loads.csv"))
    bad, n = [], 0
    with h5py.File(a.load) as f:
        ok = f["runs/status"][:] == 0
        for fld in ("lock_time_s", "latch_energy_J", "peak_pin_force_N", "entry_impulse_Ns"):
            b = f["runs/bays"][fld][:][ok]
            for row in rows:
                j = int(row[0])
                x = b[:, j - 1][np.isfinite(b[:, j - 1])]
                r = dict(zip(head, row))
                unit = [h for h in head if h.startswith(f"{fld} P99")][0].split("[")[1][:-1]
                est, ub = num(r[f"{fld} P99 [{unit}]"]), num(r[f"{fld} upper 95 % bound [{unit}]"])
                page = float(v[f"bays.{fld}.bay{j}.ucb"])
                n += 1
                if not (close(est, type7(x, LEVEL)) and close(ub, upper_bound(x)) and close(page, ub)):
                    bad.append((fld, j, est, ub, page))
    check(not bad and n >= 4 * 30, f"per-bay table and bay_loads.csv: {n} P99 bounds recomputed per bay"
                                   + (f"; differ: {bad[:3]}" if bad else ""))
    check(os.path.getsize(os.path.join(out, "motorisation_chart.png")) > 10000, "the motorisation chart is drawn")


def check_sweep_csv(a, out):
    head, rows = read_csv(os.path.join(out, "sweep.csv"))
    with h5py.File(a.sweep) as f:
        x, ub, runs = f["sweep/values"][:], f["sweep/upper_bound"][:], f["sweep/runs"][:]
    got = np.array([[num(r[0]), num(r[5]), num(r[6])] for r in rows])
    check(head[0] == "value [N m]" and len(rows) == len(x) and np.array_equal(got[:, 0], x)
          and np.allclose(got[:, 1], np.clip(ub, 0, 1), rtol=RTOL, equal_nan=True) and np.array_equal(got[:, 2], runs),
          "sweep.csv: values, upper bounds and runs = /sweep")


def check_verdict_json(out, name):
    with open(os.path.join(out, "verdict.json"), encoding="utf-8") as fh:
        doc = json.load(fh)
    v, page, _ = page_values(out)
    words = {"pass": "PASS", "fail": "FAIL", "not_assessed": "NOT ASSESSED"}
    items = re.findall(r"<li data-item='([^']+)' data-kind='([^']+)'>(.*?)</li>", page, flags=re.S)
    want = [(k, words[kind], " ".join(html.unescape(re.sub(r"<[^>]+>", "", t)).split())) for k, kind, t in items]
    got = [(i["item"], i["status"], i["reason"]) for i in doc["items"]]
    check(doc["verdict"] == words[v["verdict"]] and doc["exit_status"] == {"PASS": 0, "FAIL": 3, "NOT ASSESSED": 4}[
        doc["verdict"]] and (got == want if name.startswith("load") else len(got) >= 1),
        f"verdict.json ({name}): {doc['verdict']} with {len(got)} items, as the page")
    check(((doc.get("motor_answer") or {}).get("governs") or "none") == v["motor_answer.governs"],
          f"verdict.json ({name}): the governing figure")


def main():
    ap = argparse.ArgumentParser()
    for k in ("--repo", "--scratch", "--load", "--sweep"):
        ap.add_argument(k, required=True)
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    load_out, sweep_out = os.path.join(a.scratch, "load"), os.path.join(a.scratch, "sweep")
    check_pair(a, load_out, sweep_out)
    check_alone(a)
    check_refused(a)
    v = page_values(load_out)[0]
    check_design_csv(a, load_out, v)
    check_structure_csv(a, load_out, v)
    check_motor_csv(load_out, v)
    check_bays(a, load_out, v)
    check_sweep_csv(a, sweep_out)
    check_verdict_json(load_out, "load")
    check_verdict_json(sweep_out, "sweep")
    check_verdict_json(os.path.join(a.scratch, "alone_load"), "load alone, P99.865: NOT ASSESSED")
    p = subprocess.run([PY, os.path.join(os.path.dirname(os.path.abspath(__file__)), "test_pdf_layout.py"),
                        "--scratch", os.path.join(a.scratch, "pdf"), "--report", load_out, sweep_out],
                       capture_output=True, text=True)
    # The number rule of the sweep's own text (its allowable's message) is test_pdf_layout's own concern.
    layout = [ln for ln in p.stdout.splitlines() if "values of the HTML" in ln or "margins" in ln or "heading" in ln]
    bad = [ln for ln in layout if ln.startswith("FAIL")]
    check(len(layout) == 6 and not bad, "both PDFs hold every value of their HTML, nothing in the margins, no lone "
          "heading" + ("" if not bad else ": " + " | ".join(bad)[:600]))
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
