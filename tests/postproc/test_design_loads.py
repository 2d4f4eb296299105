#!/usr/bin/python3
"""Test of the top of the campaign report: verdict, design-load table, ECSS margins,
the pandas reader and the run table CSV, against values recomputed here from the HDF5 file; the
loads' labels and definitions for the campaign's direction (deploy or retract).

Usage:
    test_design_loads.py --repo REPO_ROOT --scratch DIR --campaign-h5 PATH [--campaign-h5 ...]

Independent of the report's code: h5py and plain Python/numpy only; the percentile is written
out here (type 7: h = (n - 1) p, x[floor h] + (h - floor h)(x[floor h + 1] - x[floor h])), the
upper bound's rank is found with exact rational arithmetic (fractions.Fraction) from
P(x_(k) >= xi_p) = sum_{i<k} C(n, i) p^i (1 - p)^(n - i), and the statuses are counted from the
enum type of /runs/status. Tolerances: the report prints repr(float64) of its values; the same
formulas on the same float64 data differ only in the order of roundings (a few ulps), so floats
must agree to a relative 1e-12; counts and ranks exactly.
Prints one line per check; exit 0 when all pass, 1 otherwise.
"""
import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tomllib
from fractions import Fraction

import h5py
import numpy as np

PY = "/usr/bin/python3"
RTOL = 1e-12
LEVELS = [90.0, 99.865]
CONF = 0.95
from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)


def close(a, b):
    if isinstance(b, float) and math.isnan(b):
        return math.isnan(a)
    return a == b or abs(a - b) <= RTOL * max(abs(a), abs(b))


def pct7(sorted_x, q):
    n = len(sorted_x)
    h = (n - 1) * q / 100.0
    lo = int(math.floor(h))
    hi = min(lo + 1, n - 1)
    return sorted_x[lo] + (h - lo) * (sorted_x[hi] - sorted_x[lo])


def ucb_rank(n, p, conf):
    """Smallest k with sum_{i<k} C(n,i) p^i (1-p)^(n-i) >= conf, exactly (None if k > n)."""
    p = Fraction(p).limit_denominator(10 ** 9)
    conf = Fraction(conf).limit_denominator(10 ** 9)
    total = Fraction(0)
    for k in range(1, n + 1):
        total += math.comb(n, k - 1) * p ** (k - 1) * (1 - p) ** (n - k + 1)
        if total >= conf:
            return k
    return None


def report_values(path):
    text = open(path, encoding="utf-8").read()
    vals = dict(re.findall(r"data-key=['\"]([^'\"]+)['\"] data-value=['\"]([^'\"]*)['\"]", text))
    return vals, text


def expected(h5path):
    """{data-key: value} of the verdict, the design table and the margins, from the file."""
    E = {}
    with h5py.File(h5path, "r") as f:
        enum = h5py.check_enum_dtype(f["runs/status"].dtype)
        status = f["runs/status"][()]
        ok = status == enum["ok"]
        n = len(status)
        for name, code in enum.items():
            k = int(np.sum(status == code))
            if name != "ok" and k:
                E[f"verdict.status.{name}"] = k
                E[f"verdict.status.{name}.fraction"] = k / n
        nom = f["nominal"]
        loads = {}
        for key in ("peak_drive_force_N", "peak_drive_torque_Nm", "peak_pin_force_N",
                    "peak_diagonal_tension_N", "peak_latch_energy_J", "start_drive_impulse_Ns",
                    "drive_work_impulses_J", "deploy_time_s"):
            if key in f["runs"]:
                loads[key] = (f["runs"][key][()], float(nom[key][()]))
        for key in ("entry_impulse_Ns", "entry_drive_impulse_Ns", "landing_impulse_Ns",
                    "unlock_impulse_Ns"):
            b = f["runs/bays"][key][()]
            per_run = np.array([max([v for v in row if not math.isnan(v)], default=math.nan)
                                for row in b])
            nb = [v for v in nom["bays"][key][()] if not math.isnan(v)]
            loads[key] = (per_run, max(nb) if nb else math.nan)
        for key, (x, nominal) in loads.items():
            v = sorted(float(a) for a, good in zip(x, ok) if good and math.isfinite(a))
            if not v or all(a == 0 for a in v):
                continue
            E[f"design.{key}.nominal"] = nominal
            E[f"design.{key}.mean"] = math.fsum(v) / len(v)
            for q in LEVELS:
                tag = f"design.{key}.p{q:g}"
                E[tag] = pct7(v, q)
                k = ucb_rank(len(v), q / 100.0, CONF)
                if k is None:
                    E[tag + ".ucb"] = math.nan
                    need = next(m for m in range(1, 10 ** 6) if 1 - (q / 100.0) ** m >= CONF)
                    E[tag + ".ucb_n_needed"] = need
                else:
                    E[tag + ".ucb"] = v[k - 1]
                    E[tag + ".ucb_rank"] = k
            E[f"design.{key}.ratio"] = E[f"design.{key}.p{LEVELS[-1]:g}"] / nominal
        # A level that some load has no bound for is not assessed: too few runs.
        for q in LEVELS:
            short = [k for k in loads if f"design.{k}.p{q:g}.ucb_n_needed" in E]
            if short:
                E[f"verdict.too_few.p{q:g}"] = E[f"design.{short[0]}.p{q:g}.ucb_n_needed"]
                E[f"verdict.too_few.p{q:g}.n"] = min(
                    sum(1 for a, good in zip(loads[k][0], ok) if good and math.isfinite(a))
                    for k in short)
        scene = tomllib.loads(f.attrs["base_scene_toml"])
        E.update(expected_margins(f, scene, ok, nom))
    return E


def expected_margins(f, scene, ok, nom):
    """ECSS-E-ST-33-01C 4.7.5.3.1 as docs/report.md states it, written out here: spring resistance
    S and inertial resistance T_D (velocity drive; 0 in motor drive) from /runs, factors 2, 1.2
    and 1.25; T_min = 2 (1.2 S) + 1.25 T_D; MF achieved = (T_avail - 1.25 T_D) / (1.2 S);
    T_avail: the motor at the prescribed speed (velocity), the stall torque (motor)."""
    E = {}
    mode = f.attrs["drive_mode"]
    d = scene["drive"]
    S = f["runs/peak_static_drive_torque_Nm"][()]
    if mode == "velocity":
        D = np.maximum(f["runs/peak_inertial_drive_torque_Nm"][()], 0.0)
        av = f["runs/motor_torque_at_speed_Nm"][()]
    elif mode == "motor":
        D = np.zeros(len(S))
        key = "runs/inputs/drive.stall_torque_Nm"
        av = f[key][()] if key in f else np.full(len(S), float(d["stall_torque_Nm"]))
    else:
        return E
    S = np.maximum(S, 0.0)   # retraction: the diagonals help, no spring resistance
    sel = [i for i in range(len(S)) if ok[i] and 2.0 * 1.2 * S[i] + 1.25 * D[i] > 0]
    if not sel:
        return E
    tmin = [2.0 * 1.2 * S[i] + 1.25 * D[i] for i in sel]
    mf = [(av[i] - 1.25 * D[i]) / (1.2 * S[i]) if S[i] > 0 else
          (math.inf if av[i] >= 1.25 * D[i] else -math.inf) for i in sel]
    E["mech.n"] = len(sel)
    E["mech.mf_min"] = E["verdict.mf_min"] = min(mf)
    E["mech.tm_min"] = min(av[i] / t - 1.0 for i, t in zip(sel, tmin))
    E["mech.n_below"] = sum(1 for i, t in zip(sel, tmin) if av[i] < t)
    if E["mech.n_below"]:
        E["verdict.mf_n_below"] = E["mech.n_below"]
    else:
        del E["verdict.mf_min"]
    E["mech.s_design"] = max(S[i] for i in sel)
    E["mech.t_min"] = max(tmin)
    E["mech.t_avail_min"] = min(av[i] for i in sel)
    nS = float(nom["peak_static_drive_torque_Nm"][()])
    # The stall torque needed: per run the stall torque that meets the factors exactly (the
    # available torque is proportional to it: velocity drive T_min / (1 - omega / omega_0), motor
    # drive T_min), stated as the upper bound of its P99.865 at 95 % (the design loads' rule).
    if mode == "velocity":
        omega = 2 * math.pi * d["speed_m_per_s"] / d["screw_lead_m"]
        need = sorted(t / (1 - omega / d["no_load_speed_rad_per_s"]) for t in tmin)
        nD = max(float(nom["peak_inertial_drive_torque_Nm"][()]), 0.0)
        if nS > 0:
            E["mech.mf_nominal"] = (float(nom["motor_torque_at_speed_Nm"][()]) - 1.25 * nD) / (1.2 * nS)
    else:
        need = sorted(tmin)
        if nS > 0:
            E["mech.mf_nominal"] = float(d["stall_torque_Nm"]) / (1.2 * nS)
    k = ucb_rank(len(need), LEVELS[-1] / 100.0, CONF)
    E["mech.stall_needed"] = need[k - 1] if k is not None else math.nan
    if f.attrs.get("motor_declared_by", None) == "":
        # No motor declared: the required side only, nothing judged against a motor.
        E = {k2: v for k2, v in E.items() if k2 in ("mech.n", "mech.s_design", "mech.t_min", "mech.stall_needed")}
    return E


# The report's exit status per verdict (postproc/report.py) and the run statuses that are evidence
# against the mechanism (FAIL); the other statuses (caps, solver flags) and too few runs for a
# level leave the verdict NOT ASSESSED.
EXIT = {"pass": 0, "fail": 3, "not_assessed": 4}
PHYSICAL = ("rail miss", "stall", "singular configuration")


def expected_verdict(E):
    fails = E.get("mech.n_below", 0) > 0 or any(
        E.get(f"verdict.status.{s}", 0) > 0 for s in PHYSICAL)
    undecided = any(k.startswith("verdict.") and not k.endswith(".fraction") for k in E)
    return "fail" if fails else "not_assessed" if undecided else "pass"


def check_report(repo, scratch, h5path):
    name = os.path.basename(h5path)
    out = os.path.join(scratch, name + ".report")
    shutil.rmtree(out, ignore_errors=True)
    p = subprocess.run([PY, os.path.join(repo, "postproc", "report.py"), h5path, "-o", out,
                        "--levels", "99.865,90", "--confidence", str(CONF), "--csv",
                        "--revision", "B", "--no-pdf"], capture_output=True, text=True)
    E = expected(h5path)
    verdict = expected_verdict(E)
    if not check(p.returncode == EXIT[verdict] and os.path.exists(os.path.join(out, "report.html")),
                 f"{name}: report written, exit {p.returncode} (expected {EXIT[verdict]}: "
                 f"{verdict}) ({p.stderr.strip()[-300:]})"):
        return
    got, text = report_values(os.path.join(out, "report.html"))
    E = expected(h5path)
    with h5py.File(h5path, "r") as f:
        scene = tomllib.loads(f.attrs["base_scene_toml"])
        n_ok = int(np.sum(f["runs/status"][()] == h5py.check_enum_dtype(f["runs/status"].dtype)["ok"]))
    if (scene.get("stack") or {}).get("mode") == "free" and n_ok:
        # The free stack's static resistance is in the file, so its ECSS margins are computed.
        check(E.get("mech.n", 0) > 0 and "mech.n" in got,
              f"{name}: free stack: the ECSS margin table is filled ({E.get('mech.n', 0)} runs)")
    bad = [f"{k}: report {got.get(k)!r}, expected {v!r}" for k, v in E.items()
           if k not in got or not close(float(got[k]), float(v))]
    check(not bad, f"{name}: {len(E)} verdict / design / margin numbers equal the values "
          f"recomputed from the file" + (f": {bad[:4]}" if bad else ""))
    check(got.get("verdict") == verdict,
          f"{name}: verdict {got.get('verdict')} (expected {verdict})")
    first_line = p.stdout.splitlines()[0] if p.stdout else ""
    check(first_line.startswith(f"VERDICT: {verdict.replace('_', ' ').upper()} "),
          f"{name}: the terminal says the same verdict: {first_line[:80]!r}")
    first = text.find("data-key='verdict'")
    sections = re.search(r"id=[\"']campaign[\"']", text)
    check(0 < first < text.find("id='design'") < (sections.start() if sections else -1),
          f"{name}: the verdict, then the design-load table, come before everything else")
    check(got.get("revision") is None and "Revision <b data-key='revision'>B</b>" in text,
          f"{name}: sign-off block with the revision given")
    check(not re.search(r">-0(\.0*)?( |<)", text), f"{name}: no '-0' shown")
    check_direction_words(name, h5path, text)
    check_csv(name, h5path, os.path.join(out, "runs.csv"))


def check_csv(name, h5path, path):
    with h5py.File(h5path, "r") as f, open(path, newline="") as fh:
        rows = list(csv.reader(fh))
        enum = {v: k for k, v in h5py.check_enum_dtype(f["runs/status"].dtype).items()}
        status = [enum[int(s)] for s in f["runs/status"][()]]
        messages = [m.decode() if isinstance(m, bytes) else m for m in f["runs/message"][()]]
        head = rows[0]
        force = [float(r[head.index("peak_drive_force_N")]) for r in rows[1:]]
        check(head[:2] == ["run_index", "status"] and head[-1] == "message"
              and len(rows) - 1 == len(status)
              and [int(r[0]) for r in rows[1:]] == list(range(len(status)))
              and [r[1] for r in rows[1:]] == status and [r[-1] for r in rows[1:]] == messages
              and all(len(r) == len(head) for r in rows)
              and np.array_equal(force, f["runs/peak_drive_force_N"][()], equal_nan=True),
              f"{name}: run table CSV: run_index 0..n-1, status names, messages, values exact")


def check_direction_words(name, h5path, text):
    """The design table names its loads for the campaign's direction: a retraction has no
    'last lock' and no rail-entry definition, a deployment no retraction."""
    with h5py.File(h5path, "r") as f:
        direction = f.attrs["direction"]
        direction = direction.decode() if isinstance(direction, bytes) else direction
    table = text[text.find("id='design'"):text.find("id='mechanism'")]
    row = table[table.find("deploy_time_s"):]
    row = row[:row.find("</tr>")]
    if direction == "retract":
        ok = ("retraction time" in table and "end of the retraction" in row
              and "last lock" not in table and "rail entry" not in table
              and "peak unlock energy" in table and "unlock" in table)
    else:
        ok = ("deployment time" in table and "last lock" in row and "retract" not in table)
    check(ok, f"{name}: design-load labels and definitions for a {direction} campaign")


def check_reader(repo, h5path):
    sys.path.insert(0, os.path.join(repo, "postproc"))
    from truss_report import read_campaign
    name = os.path.basename(h5path)
    df = read_campaign(h5path, columns="all")     # the per-bay columns are read on demand
    check(not [c for c in read_campaign(h5path).columns if "[bay " in c or "[frame " in c],
          f"{os.path.basename(h5path)}: read_campaign: no per-bay column unless asked for")
    with h5py.File(h5path, "r") as f:
        enum = h5py.check_enum_dtype(f["runs/status"].dtype)
        by_value = {v: k for k, v in enum.items()}
        want = [by_value[int(s)] for s in f["runs/status"][()]]
        check(list(df["status"].astype(str)) == want
              and list(df["status"].cat.categories) == sorted(enum, key=enum.get),
              f"{name}: read_campaign: status names from the enum, categories in enum order")
        u = df.attrs["units"]
        wrong = [k for k in ("peak_drive_force_N", "peak_drive_torque_Nm", "deploy_time_s")
                 if u.get(k) != f["runs"][k].attrs["units"]]
        nb = f.attrs["n_bays_max"]
        check(not wrong and u.get("lock_time_s[bay 1]") == "s"
              and f"lock_time_s[bay {nb}]" in df.columns and f"lock_time_s[bay {nb + 1}]" not in df
              and np.array_equal(df[f"lock_time_s[bay {nb}]"].to_numpy(),
                                 f["runs/bays/lock_time_s"][:, nb - 1], equal_nan=True),
              f"{name}: read_campaign: units in attrs, per-bay columns 1..{nb} {wrong}")
        inputs = [c for c in df.columns if c.startswith("input:")]
        check(len(inputs) == sum(1 if ds.ndim == 1 else ds.shape[1]
                                 for ds in f["runs/inputs"].values()),
              f"{name}: read_campaign: one column per sampled input ({len(inputs)})")


def check_bad_options(repo, scratch, h5path):
    for opts in (["--confidence", "1.5"], ["--levels", "abc"], ["--levels", "100"]):
        out = os.path.join(scratch, "bad_opts")
        shutil.rmtree(out, ignore_errors=True)
        p = subprocess.run([PY, os.path.join(repo, "postproc", "report.py"), h5path, "-o", out,
                            *opts], capture_output=True, text=True)
        check(p.returncode == 2 and p.stderr.startswith("error:") and not os.path.exists(out),
              f"bad option {' '.join(opts)}: exit 2, one error line, nothing written")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign-h5", action="append", required=True)
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    check(ucb_rank(300, 0.9, 0.95) is not None and ucb_rank(2217, 0.99865, 0.95) is None
          and ucb_rank(2218, 0.99865, 0.95) == 2218,
          "exact binomial rank: n = 2218 is the smallest with a P99.865 bound at 95 %")
    for h5path in a.campaign_h5:
        check_report(a.repo, a.scratch, h5path)
        check_reader(a.repo, h5path)
    check_bad_options(a.repo, a.scratch, a.campaign_h5[0])
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
