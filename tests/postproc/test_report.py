#!/usr/bin/python3
"""Test of postproc/report.py (the statistical load report).

Usage:
    test_report.py --repo REPO_ROOT --scratch DIR [--campaign-h5 PATH ...] [--run-h5 PATH ...]

Builds reports from synthetic files (tests/postproc/make_fake_campaign.py, make_fake_run.py) and
from every real file given with --campaign-h5 (a truss-campaign result) or --run-h5 (a truss-sim
result), and checks:
  - every number in the report's tables (every element with a data-key) equals the value
    computed here, independently, from the HDF5 file: counts exactly; floating-point values to a
    relative 1e-12 (the same formulas on the same float64 data, written differently here: only
    the order of the roundings differs, which costs a few ulps), and to an absolute 1e-14 for
    dimensionless values near 0 (rank correlations, relative differences);
  - every key this test expects is in the report (no silently missing table);
  - every <img> the report references exists and is a PNG with a sane IHDR header;
  - failed runs are reported with the right counts, grouped runs matching their status;
  - bad input stops with exit code 2, one `error:` line naming the file, and nothing written:
    schema_version 4, a truncated file, a text file, a wrong kind, a missing dataset, a
    non-empty output directory without --force.
Prints one line per check; exits 0 when all pass, 1 otherwise.
"""
import argparse
import hashlib
import html.parser
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tomllib
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np
from scipy import stats

OUTPUTS = ["peak_drive_force_N", "peak_drive_torque_Nm", "peak_pin_force_N",
           "peak_diagonal_tension_N", "peak_latch_energy_J", "deploy_time_s"]
LEVELS = {"p50": 0.5, "p95": 0.95, "p99": 0.99, "p99_865": 0.99865}
STAT_PCT = {"p1": 0.01, "p5": 0.05, **LEVELS}
RTOL = 1e-12
ATOL_DIMENSIONLESS = 1e-14
TORQUE_RTOL = 1e-9      # the report's documented tolerance for "peak torque > stall torque"
PY = "/usr/bin/python3"

from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)


# --------------------------------------------------------------------------------------------
# Independent statistics
# --------------------------------------------------------------------------------------------

def hf7(x_sorted, p):
    """Hyndman-Fan type 7 quantile, written out: x[h] + (h - floor h)(x[h+1] - x[h]),
    h = (n - 1) p (0-based)."""
    n = len(x_sorted)
    h = (n - 1) * p
    lo = math.floor(h)
    hi = min(lo + 1, n - 1)
    return float(x_sorted[lo] + (h - lo) * (x_sorted[hi] - x_sorted[lo]))


def col_stats(x):
    """count, mean, std (ddof 1), min, max and percentiles of finite values x."""
    x = np.sort(x)
    n = len(x)
    nan = float("nan")
    mean = math.fsum(x) / n if n else nan
    res = {"count": n, "mean": mean,
           "std": math.sqrt(math.fsum((x - mean) ** 2) / (n - 1)) if n >= 2 else nan,
           "min": float(x[0]) if n else nan, "max": float(x[-1]) if n else nan}
    for k, p in STAT_PCT.items():
        res[k] = hf7(x, p) if n else nan
    return res


def order_ci(x_sorted, p, conf=0.95):
    """Ranks (1-based) of the one-sided order-statistic bounds (each at conf) from the binomial
    CDF table, the bounds (NaN when the sample is too small), the coverage of the interval they
    make, and the n a missing bound needs."""
    n = len(x_sorted)
    a = 1 - conf
    cdf = stats.binom.cdf(np.arange(n + 1), n, p)
    r = int(np.searchsorted(cdf, a, side="left"))          # first k with F(k) >= a
    s = int(np.searchsorted(cdf, 1 - a, side="left")) + 1  # 1 + first k with F(k) >= conf
    F = lambda k: 0.0 if k < 0 else (1.0 if k >= n else float(cdf[k]))  # noqa: E731
    res = {"ci_coverage": F(min(s, n + 1) - 1) - F(r - 1)}
    if r >= 1:
        res["ci_lo"], res["ci_r"] = float(x_sorted[r - 1]), r
    else:
        res["ci_lo"] = float("nan")
        res["ci_lo.n_needed"] = first_n(lambda m: stats.binom.cdf(0, m, p) < a)
    if s <= n:
        res["ci_hi"], res["ci_s"] = float(x_sorted[s - 1]), s
    else:
        res["ci_hi"] = float("nan")
        res["ci_hi.n_needed"] = first_n(lambda m: stats.binom.cdf(m - 1, m, p) >= 1 - a)
    return res


def first_n(condition, limit=10**6):
    """The smallest sample size m >= 1 for which condition(m) holds (vectorised search)."""
    m = np.arange(1, limit + 1)
    hit = np.nonzero(condition(m))[0]
    return int(m[hit[0]])


def clopper_pearson_bisect(k, n, side, conf=0.95):
    """Exact binomial interval bound by bisection on its definition: the lower bound p solves
    P(X >= k | n, p) = a, the upper P(X <= k | n, p) = a, a = (1 - conf)/2 (0 and 1 at k = 0, n).
    (scipy's binomtest(...).proportion_ci is only good to ~1e-11 relative, not enough here.)"""
    a = (1 - conf) / 2
    if side == "lo" and k == 0:
        return 0.0
    if side == "hi" and k == n:
        return 1.0
    tail = (lambda p: stats.binom.sf(k - 1, n, p)) if side == "lo" else \
        (lambda p: -stats.binom.cdf(k, n, p))   # both increasing in p
    target = a if side == "lo" else -a
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        lo, hi = (mid, hi) if tail(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def spearman_by_ranks(x, y):
    m = np.isfinite(x) & np.isfinite(y)
    n = int(m.sum())
    if n < 3 or np.ptp(x[m]) == 0 or np.ptp(y[m]) == 0:
        return float("nan"), n
    rx, ry = stats.rankdata(x[m]), stats.rankdata(y[m])
    return float(np.corrcoef(rx, ry)[0, 1]), n


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


# --------------------------------------------------------------------------------------------
# Expected values from the HDF5 file
# --------------------------------------------------------------------------------------------

def sha256_of(path):
    """The file's SHA-256, as the document block must show it (hashlib, read here)."""
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def expected_campaign(path):
    """{data-key: value} of everything the report shows, and the keys it must show."""
    E, required = {}, set()
    with h5py.File(path, "r") as f:
        at = f.attrs
        for k in ("n_runs", "master_seed", "n_bays_max", "n_ranks", "n_sessions"):
            E[f"campaign.{k}"] = int(at[k])
        E["campaign.wall_time_s"] = float(at["wall_time_s"])
        n = int(at["n_runs"])
        enum = h5py.check_enum_dtype(f["runs/status"].dtype)
        name_of = {v: k for k, v in enum.items()}
        status = f["runs/status"][()].astype(int)
        ok = status == enum["ok"]
        stats_names = [text(s) for s in f["stats/status_names"][()]]
        stats_counts = f["stats/status_counts"][()]
        for v, name in name_of.items():
            E[f"status_count.{name}"] = int(np.sum(status == v))
            E[f"status_count.{name}.stats"] = int(stats_counts[stats_names.index(name)])
            required.add(f"status_count.{name}")
        E["runs.n_total"], E["runs.n_total.stats"] = n, int(f["stats"].attrs["n_runs"])
        E["runs.n_ok"], E["runs.n_failed"] = int(ok.sum()), int(n - ok.sum())
        required |= {"runs.n_ok", "runs.n_failed", "campaign.n_runs"}

        disps = []
        for key, ds in f["runs/inputs"].items() if "runs/inputs" in f else []:
            d = {"key": key, "per": text(ds.attrs["per"]), "nominal": float(ds.attrs["nominal"]),
                 "values": ds[()]}
            disps.append(d)
            E[f"dispersion.{key}.nominal"] = d["nominal"]
            E[f"dispersion.{key}.factor"] = int(ds.attrs["factor"])
            for p in ("mean", "std", "lower", "upper", "mu", "sigma"):
                if p in ds.attrs:
                    E[f"dispersion.{key}.{p}"] = float(ds.attrs[p])
            for p in ("values", "weights"):
                if p in ds.attrs:
                    for i, v in enumerate(np.atleast_1d(ds.attrs[p])):
                        E[f"dispersion.{key}.{p}.{i}"] = float(v)
            required.add(f"dispersion.{key}.nominal")

        scene = tomllib.loads(text(at["base_scene_toml"]))
        for tab, entries in scene.items():
            for k, v in entries.items():
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    E[f"base_scene.{tab}.{k}"] = v

        # Section 2: distributions.
        cmp_stats = Comparison()
        for out in OUTPUTS:
            y = f[f"runs/{out}"][()]
            x = np.sort(y[ok & np.isfinite(y)])
            mine = col_stats(x)
            stored = {k: f[f"stats/{out}/{k}"][()] for k in mine}
            cmp_stats.add(mine, stored, x)
            E[f"{out}.count"] = len(x)
            required.add(f"{out}.count")
            if len(x) == 0:
                continue
            for k in ("mean", "std", "min", "max"):
                E[f"{out}.{k}"], E[f"{out}.{k}.stats"] = mine[k], float(stored[k])
            for lev, p in LEVELS.items():
                E[f"{out}.{lev}"], E[f"{out}.{lev}.stats"] = mine[lev], float(stored[lev])
                for k, v in order_ci(x, p).items():
                    E[f"{out}.{lev}.{k}"] = v
                required |= {f"{out}.{lev}", f"{out}.{lev}.ci_lo", f"{out}.{lev}.ci_hi"}
        E["check.stats.count_mismatches"] = cmp_stats.counts
        E["check.stats.order_max_diff"] = cmp_stats.order
        E["check.stats.moments_max_diff"] = cmp_stats.moments

        # Section 3: lock timing.
        lock = f["runs/bays/lock_time_s"][()][ok]
        d = np.diff(lock, axis=1)
        d = d[np.isfinite(d)]
        order = ("descending" if len(d) and (d < 0).all() else
                 "ascending" if len(d) and (d > 0).all() else "mixed")
        dt = np.full(lock.shape, np.nan)
        if order == "descending":
            dt[:, :-1] = lock[:, :-1] - lock[:, 1:]
        elif order == "ascending":
            dt[:, 1:] = lock[:, 1:] - lock[:, :-1]
        else:
            dt[:, :-1] = lock[:, 1:] - lock[:, :-1]
        cmp_lock = Comparison()
        for j in range(lock.shape[1]):
            for name, arr in (("lock_time_s", lock), ("lock_interval_s", dt)):
                v = np.sort(arr[:, j][np.isfinite(arr[:, j])])
                E[f"{name}.bay{j + 1}.count"] = len(v)
                for k, p in (("p5", 0.05), ("p50", 0.5), ("p95", 0.95)):
                    E[f"{name}.bay{j + 1}.{k}"] = hf7(v, p) if len(v) else float("nan")
                if name == "lock_time_s":
                    fields = ("count", "p5", "p50", "p95")
                    cmp_lock.add({k: E[f"{name}.bay{j + 1}.{k}"] for k in fields},
                                 {k: f[f"stats/bays/lock_time_s/{k}"][j] for k in fields}, v)
            required.add(f"lock_time_s.bay{j + 1}.p50")
        E["check.lock.count_mismatches"] = cmp_lock.counts
        E["check.lock.order_max_diff"] = cmp_lock.order
        E["_lock_order"] = order

        # Section 4: motor margin.
        if text(at["drive_mode"]) == "motor":
            torque = f["runs/peak_drive_torque_Nm"][()]
            if "runs/inputs/drive.stall_torque_Nm" in f:
                stall_t = f["runs/inputs/drive.stall_torque_Nm"][()]
            else:
                stall_t = np.full(n, float(scene["drive"]["stall_torque_Nm"]))
            stalled = status == enum["stall"]
            ok_t = ok & np.isfinite(torque) & np.isfinite(stall_t)
            ok_ex = ok_t & (torque > stall_t * (1 + TORQUE_RTOL))
            n_cons, k = int(ok_t.sum() + stalled.sum()), int(ok_ex.sum() + stalled.sum())
            E.update({"motor.stall_torque_nominal": float(scene["drive"]["stall_torque_Nm"]),
                      "motor.n_considered": n_cons, "motor.n_stall": int(stalled.sum()),
                      "motor.n_ok_exceed": int(ok_ex.sum()), "motor.n_exceed": k,
                      "motor.n_other_failures": int(np.sum(~ok & ~stalled)),
                      "motor.p_exceed": k / n_cons,
                      "motor.p_exceed.ci_lo": clopper_pearson_bisect(k, n_cons, "lo"),
                      "motor.p_exceed.ci_hi": clopper_pearson_bisect(k, n_cons, "hi"),
                      "motor.utilisation_max": float(np.max(torque[ok_t] / stall_t[ok_t]))})
            required |= {"motor.p_exceed", "motor.p_exceed.ci_lo", "motor.p_exceed.ci_hi",
                         "motor.n_stall"}

        # Section 4, velocity drive: peak torque against the scene's motor at the prescribed speed,
        # T_s (1 - omega / omega_0) with omega = 2 pi v / h (per run when dispersed); only for a
        # campaign that declares its motor (root attribute motor_declared_by not empty).
        if text(at["drive_mode"]) == "velocity" and text(at.get("motor_declared_by", "-")) != "":
            def drive(key):
                name = f"runs/inputs/drive.{key}"
                return f[name][()] if name in f else np.full(n, float(scene["drive"][key]))
            torque = f["runs/peak_drive_torque_Nm"][()]
            omega = 2 * np.pi * drive("speed_m_per_s") / drive("screw_lead_m")
            avail = drive("stall_torque_Nm") * (1 - omega / drive("no_load_speed_rad_per_s"))
            cons = ok & np.isfinite(torque) & np.isfinite(avail)
            n_cons, k = int(cons.sum()), int((cons & (torque > avail)).sum())
            if n_cons:
                ratio = np.sort(avail[cons] / torque[cons])
                E.update({"velmargin.stall_torque": float(scene["drive"]["stall_torque_Nm"]),
                          "velmargin.no_load_speed": float(scene["drive"]["no_load_speed_rad_per_s"]),
                          "velmargin.required_speed": 2 * np.pi * float(scene["drive"]["speed_m_per_s"])
                          / float(scene["drive"]["screw_lead_m"]),
                          "velmargin.n_considered": n_cons, "velmargin.n_exceed": k,
                          "velmargin.p_exceed": k / n_cons,
                          "velmargin.p_exceed.ci_lo": clopper_pearson_bisect(k, n_cons, "lo"),
                          "velmargin.p_exceed.ci_hi": clopper_pearson_bisect(k, n_cons, "hi"),
                          "velmargin.ratio_min": float(ratio[0]),
                          "velmargin.ratio_p50": hf7(ratio, 0.5)})
                required |= {"velmargin.p_exceed", "velmargin.n_exceed"}

        # Section 1, free stack: rail-miss share (exact interval by bisection) and the closest
        # approaches of the missing hinges (type-7 quantiles written out).
        if "rail miss" in enum and "runs/rail_miss_closest_approach_m" in f:
            miss = status == enum["rail miss"]
            k = int(miss.sum())
            if k:
                a = f["runs/rail_miss_closest_approach_m"][()][miss]
                a = np.sort(a[np.isfinite(a)])
                E.update({"railmiss.n_runs": n, "railmiss.n_miss": k, "railmiss.p": k / n,
                          "railmiss.p.ci_lo": clopper_pearson_bisect(k, n, "lo"),
                          "railmiss.p.ci_hi": clopper_pearson_bisect(k, n, "hi")})
                for name, p in (("min", 0.0), ("p05", 0.05), ("median", 0.5), ("p95", 0.95),
                                ("max", 1.0)):
                    E[f"railmiss.approach.{name}"] = hf7(a, p)
                required |= {"railmiss.p", "railmiss.p.ci_lo", "railmiss.p.ci_hi",
                             "railmiss.approach.min", "railmiss.approach.median"}

        # Section 5: rank correlations.
        for d in disps:
            v = d["values"]
            cols = []
            if v.ndim == 1:
                cols.append((d["key"], v))
            else:
                start = 1 if d["per"] == "bay" else 0
                cols += [(f"{d['key']}[{d['per']} {j + start}]", v[:, j])
                         for j in range(v.shape[1])]
                dev = (v - d["nominal"]) / (d["nominal"] if d["nominal"] != 0 else 1.0)
                with np.errstate(invalid="ignore"):
                    agg = np.array([np.mean(r[np.isfinite(r)]) if np.isfinite(r).any()
                                    else np.nan for r in dev])
                cols.append((f"{d['key']} (mean over {d['per']}s)", agg))
            for out in OUTPUTS:
                y = np.where(ok, f[f"runs/{out}"][()], np.nan)
                for label, xcol in cols:
                    rho, m = spearman_by_ranks(xcol, y)
                    E[f"spearman.{out}.{label}"], E[f"spearman.{out}.{label}.n"] = rho, m
            required.add(f"spearman.peak_drive_force_N.{cols[-1][0]}")

        if "sensitivity" in f:
            factors = [text(s) for s in f["sensitivity/factor"][()]]
            for out in OUTPUTS:
                g = f[f"sensitivity/{out}"]
                E[f"sobol.{out}.n_blocks"] = int(g.attrs["n_blocks"])
                E[f"sobol.{out}.n_blocks_dropped"] = int(g.attrs["n_blocks_dropped"])
                for k in ("first_order", "first_order_lo", "first_order_hi",
                          "total", "total_lo", "total_hi"):
                    for i, fac in enumerate(factors):
                        E[f"sobol.{out}.{fac}.{k}"] = float(g[k][i])
                        required.add(f"sobol.{out}.{fac}.{k}")
        # Per-bay design values at the top (the default top level P99.865, upper 95 % bound).
        for fld in ("lock_time_s", "latch_energy_J", "peak_pin_force_N", "entry_impulse_Ns"):
            b = f["runs/bays"][fld][()][ok] if fld in f["runs/bays"] else np.full((0, 0), np.nan)
            for j in range(b.shape[1] if np.any(np.isfinite(b) & (b != 0)) else 0):
                x = np.sort(b[:, j][np.isfinite(b[:, j])])
                E[f"bays.{fld}.bay{j + 1}.p"] = hf7(x, 0.99865) if len(x) else float("nan")
                E[f"bays.{fld}.bay{j + 1}.ucb"] = order_ci(x, 0.99865)["ci_hi"] if len(x) else float("nan")
        E["_status"] = status
        E["_status_name"] = name_of
        E["_histories"] = sorted(int(k[4:]) for k in f["histories"]) if "histories" in f else []
    E["_sha256"] = sha256_of(path)
    return E, required


class Comparison:
    """The report's consistency check of recomputed statistics against /stats: counts that
    differ; largest |difference| / largest |value| of the column, for order statistics and
    for mean/std separately."""

    def __init__(self):
        self.counts, self.order, self.moments = 0, 0.0, 0.0

    def add(self, mine, stored, x):
        scale = float(np.max(np.abs(x))) if len(x) else 0.0
        for k, v in mine.items():
            w = float(stored[k])
            if k == "count":
                self.counts += int(v != w)
                continue
            if (math.isnan(v) and math.isnan(w)) or v == w:
                d = 0.0
            elif math.isnan(v) or math.isnan(w):
                d = float("inf")
            else:
                d = abs(v - w) / max(scale, np.finfo(float).tiny)
            if k in ("mean", "std"):
                self.moments = max(self.moments, d)
            else:
                self.order = max(self.order, d)


def expected_single_run(path):
    E, required = {}, set()
    with h5py.File(path, "r") as f:
        for name, ds in f["summary"].items():
            if name != "status" and ds.dtype.kind in "fiu":
                v = ds[()]
                E[f"summary.{name}"] = int(v) if ds.dtype.kind in "iu" else float(v)
                required.add(f"summary.{name}")
        if "bays" in f:
            bay = f["bays/bay"][()]
            for name, ds in f["bays"].items():
                if name != "bay":
                    for i, b in enumerate(bay):
                        E[f"bays.{name}.bay{b}"] = float(ds[i])
    E["_sha256"] = sha256_of(path)
    return E, required


# --------------------------------------------------------------------------------------------
# Parsing the report
# --------------------------------------------------------------------------------------------

class ReportParser(html.parser.HTMLParser):
    VOID = {"img", "br", "meta", "link", "hr", "input", "wbr"}

    def __init__(self):
        super().__init__()
        self.values = []     # (key, data-value, visible text)
        self.imgs = []
        self.rows = []       # attrs of <tr> elements with data-runs
        self.stack = []      # open elements: [tag, key, value, text parts]

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a.get("src"))
        if tag == "tr" and "data-runs" in a:
            self.rows.append(a)
        if tag not in self.VOID:
            self.stack.append([tag, a.get("data-key"), a.get("data-value"), []])

    def handle_endtag(self, tag):
        while self.stack:
            t, key, value, parts = self.stack.pop()
            if key is not None:
                self.values.append((key, value, "".join(parts)))
            if self.stack:
                self.stack[-1][3].extend(parts)
            if t == tag:
                break

    def handle_data(self, data):
        if self.stack:
            self.stack[-1][3].append(data)


def parse_report(path):
    p = ReportParser()
    with open(path, encoding="utf-8") as fh:
        p.feed(fh.read())
    p.close()
    return p


def png_size(path):
    """(width, height) from the PNG signature and IHDR chunk, or None if not a PNG."""
    with open(path, "rb") as fh:
        head = fh.read(33)
    if len(head) < 33 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    length, = struct.unpack(">I", head[8:12])
    w, h = struct.unpack(">II", head[16:24])
    return (w, h) if length == 13 else None


# --------------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------------

def run_report(repo, h5, outdir, *extra):
    """report.py without the PDF (tests/postproc/test_verdicts.py checks the PDF)."""
    return subprocess.run([PY, os.path.join(repo, "postproc", "report.py"), h5, "-o", outdir,
                           "--no-pdf", *extra], capture_output=True, text=True)


VERDICT_EXIT = {"pass": 0, "fail": 3, "not_assessed": 4}   # report.py's documented exit codes


def verdict_exit(outdir):
    """The exit status report.py must give for the verdict written in outdir/report.html."""
    with open(os.path.join(outdir, "report.html"), encoding="utf-8") as fh:
        m = re.search(r"data-key='verdict' data-value='(\w+)'", fh.read())
    return VERDICT_EXIT.get(m.group(1), -1) if m else 0


def values_match(key, got, want, scale=0.0):
    """`scale`: for a standard deviation, the magnitude of its column (largest |value|): two
    correct computations of a std differ by a few ulps of the values, not of the std, which can be
    1e-12 of them (deployment times that agree to a nanosecond)."""
    if isinstance(want, (int, np.integer)) and not isinstance(want, bool):
        try:
            return int(got) == int(want)
        except ValueError:
            return False
    g = float(got)
    if math.isnan(want) or math.isnan(g):
        return math.isnan(want) and math.isnan(g)
    tol = RTOL * max(abs(g), abs(want))
    if key.endswith(".std"):
        tol = max(tol, 64 * np.finfo(float).eps * scale)
    if key.startswith(("spearman.", "check.")) or key.endswith("ci_coverage"):
        tol = max(tol, ATOL_DIMENSIONLESS)
    return abs(g - want) <= tol


def column_scale(E, key):
    """Largest |min|, |max| of the column of a statistic key ("deploy_time_s.std"), 0 if unknown."""
    base = key.rsplit(".", 1)[0]
    vals = [E.get(f"{base}.{k}") for k in ("min", "max")]
    return max([abs(v) for v in vals if isinstance(v, float) and math.isfinite(v)], default=0.0)


def check_structure(name, parsed):
    """Each margin of safety on the page is allowable / (FoS x design load) - 1 of its row's numbers
    (ECSS-E-ST-32-10C; the rows' values are tested in tests/postproc/unit/test_structure.py)."""
    v = {}
    for key, value, _vis in parsed.values:
        if key.startswith("structure."):
            try:
                v[key] = float(value)
            except (TypeError, ValueError):
                pass      # a status cell
    bad = []
    for key, mos in v.items():
        if not key.endswith(".mos") or ".bay" in key:
            continue
        row = key[:-len(".mos")]
        a, f, d = (v.get(f"{row}.{k}", math.nan) for k in ("allowable", "factor", "design_load"))
        want = a / (f * d) - 1.0 if d > 0 else math.nan
        if not (math.isnan(want) and math.isnan(mos)) and not abs(mos - want) <= 1e-12 * max(1.0, abs(want)):
            bad.append(f"{row}: MoS {mos}, allowable / (FoS x load) - 1 = {want}")
    check(not bad, f"{name}: every margin of safety follows from its row" + (f" ({bad[:3]})" if bad else ""))


def check_numbers(name, parsed, E, required):
    seen = {}
    bad, unknown = [], []
    for key, value, vis in parsed.values:
        seen.setdefault(key, 0)
        seen[key] += 1
        if key.startswith("failure_group."):
            continue      # checked against the grouped runs by check_failure_groups
        if key.startswith(("design.", "verdict", "mech.", "nominal.", "revision", "document")):
            continue      # the top of the report: tests/postproc/test_design_loads.py
        if key.startswith("motor_answer."):
            continue      # the motor answer: tests/postproc/test_motor_answer.py
        if key.startswith("structure."):
            continue      # check_structure below
        if key == "sha256":   # the document block's SHA-256 of the results file
            if vis.strip() != E["_sha256"]:
                bad.append(f"sha256: report {vis.strip()!r}, the file's {E['_sha256']!r}")
            continue
        if key not in E:
            unknown.append(key)
        elif not values_match(key, value, E[key], column_scale(E, key)):
            bad.append(f"{key}: report {value}, expected {E[key]!r}")
        elif isinstance(E[key], float) and math.isnan(E[key]) and ".ci_" in key \
                and "n too small" not in vis:
            bad.append(f"{key}: NaN bound not shown as 'n too small' ({vis!r})")
    check_structure(name, parsed)
    check(not unknown, f"{name}: every data-key is known to the test"
          + (f" (unknown: {unknown[:5]})" if unknown else f" ({len(parsed.values)} numbers)"))
    check(not bad, f"{name}: every number equals its independent value"
          + (f": {bad[:5]}" if bad else ""))
    missing = sorted(required - set(seen))
    check(not missing, f"{name}: every expected key is present" + (f" (missing {missing[:5]})"
                                                                    if missing else ""))


def check_images(name, outdir, parsed, expected=()):
    problems = []
    for src in parsed.imgs:
        if "/" in src or src.startswith("."):
            problems.append(f"{src}: not a plain relative name")
            continue
        path = os.path.join(outdir, src)
        size = png_size(path) if os.path.isfile(path) else None
        if size is None:
            problems.append(f"{src}: missing or not a PNG")
        elif not (100 <= size[0] <= 5000 and 100 <= size[1] <= 5000):
            problems.append(f"{src}: odd size {size}")
    check(parsed.imgs and not problems, f"{name}: {len(parsed.imgs)} figures exist and are PNGs"
          + (f": {problems}" if problems else ""))
    missing = [e for e in expected if e not in parsed.imgs]
    check(not missing, f"{name}: expected figures referenced" + (f" (missing {missing})"
                                                                 if missing else ""))


def check_failure_groups(name, parsed, E):
    status, name_of = E["_status"], E["_status_name"]
    failed = set(np.nonzero(status != 0)[0].tolist())
    listed, problems = [], []
    counts = {k: int(v) for k, v, _ in parsed.values if k.startswith("failure_group.")}
    for g, row in enumerate(parsed.rows):
        runs = [int(r) for r in row["data-runs"].split()]
        listed += runs
        if counts.get(f"failure_group.{g}.count") != len(runs):
            problems.append(f"group {g}: count {counts.get(f'failure_group.{g}.count')} "
                            f"!= {len(runs)} runs")
        wrong = [r for r in runs if name_of[int(status[r])] != row["data-status"]]
        if wrong:
            problems.append(f"group {g} ({row['data-status']}): runs {wrong[:5]} have another "
                            "status")
    if sorted(listed) != sorted(failed):
        problems.append(f"grouped runs {len(listed)} != failed runs {len(failed)}")
    check(not problems, f"{name}: failed runs grouped by status, {len(failed)} in all"
          + (f": {problems}" if problems else ""))


def build_reports(repo, scratch, jobs):
    """Run report.py on every (name, h5) job, two at a time; {name: (outdir, result)}."""
    def one(job):
        name, h5 = job
        outdir = os.path.join(scratch, f"report_{name}")
        return name, (outdir, run_report(repo, h5, outdir))
    with ThreadPoolExecutor(max_workers=2) as ex:
        return dict(ex.map(one, jobs))


def check_campaign(name, h5, built, expect_imgs=()):
    outdir, r = built
    written = os.path.exists(os.path.join(outdir, "report.html"))
    if not check(written and r.returncode == verdict_exit(outdir),
                 f"{name}: report.py exit {r.returncode}, its verdict's status "
                 f"({r.stderr.strip()[:300]})"):
        return None
    parsed = parse_report(os.path.join(outdir, "report.html"))
    E, required = expected_campaign(h5)
    check_numbers(name, parsed, E, required)
    imgs = ["lock_timing.png", "tornado_peak_drive_force_N.png",
            *[f"history_run_{i}.png" for i in E["_histories"]], *expect_imgs]
    check_images(name, outdir, parsed, imgs)
    check_failure_groups(name, parsed, E)
    with open(os.path.join(outdir, "report.html"), encoding="utf-8") as fh:
        page = fh.read()
    check(f'data-order="{E["_lock_order"]}"' in page,
          f"{name}: lock order reported as {E['_lock_order']}")
    check("order-statistic" in page and "Hyndman-Fan type 7" in page,
          f"{name}: the report names its CI and percentile methods")
    return parsed


def expect_error(repo, scratch, name, h5, must_mention, outdir=None, extra=()):
    outdir = outdir or os.path.join(scratch, f"err_{name}")
    parent = os.path.dirname(outdir)
    before = sorted(os.listdir(parent))
    existed = os.path.exists(outdir)
    contents = sorted(os.listdir(outdir)) if existed else None
    r = run_report(repo, h5, outdir, *extra)
    lines = r.stderr.strip().splitlines()
    check(r.returncode == 2, f"{name}: exit code {r.returncode} (expected 2)")
    check(len(lines) == 1 and lines[0].startswith("error: ") and must_mention in lines[0],
          f"{name}: one clear error line naming {must_mention!r}: {r.stderr.strip()[:300]!r}")
    written = (sorted(os.listdir(outdir)) != contents) if existed else os.path.exists(outdir)
    check(not written and sorted(os.listdir(parent)) == before and not r.stdout,
          f"{name}: nothing written")


def fake(repo, out, *args):
    subprocess.run([PY, os.path.join(repo, "tests", "postproc", "make_fake_campaign.py"), out,
                    *args], check=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--campaign-h5", action="append", default=[],
                    help="a real truss-campaign result file to report on (repeatable)")
    ap.add_argument("--run-h5", action="append", default=[],
                    help="a real truss-sim result file to report on (repeatable)")
    a = ap.parse_args()
    repo, scratch = os.path.abspath(a.repo), os.path.abspath(a.scratch)
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    S = lambda name: os.path.join(scratch, name)  # noqa: E731

    # Synthetic campaigns: a motor campaign with stalls and failures of three more kinds, with
    # histories; Saltelli with a variable bay count and an output without finite values; five
    # runs (every CI bound "n too small"). Then the real files, and the single runs.
    subprocess.run([PY, os.path.join(repo, "tests", "postproc", "make_fake_run.py"),
                    S("run.h5"), "--n-bays", "4"], check=True)
    campaigns = {
        "motor": fake(repo, S("motor.h5"), "--n-runs", "400", "--drive-mode", "motor",
                      "--n-fail", "6", "--histories", "0,7"),
        "saltelli": fake(repo, S("saltelli.h5"), "--n-runs", "252", "--sampling", "saltelli",
                         "--variable-bays", "--no-torque"),
        "five_runs": fake(repo, S("small.h5"), "--n-runs", "5", "--n-bays-max", "3"),
        **{f"real_campaign_{i}": os.path.abspath(h) for i, h in enumerate(a.campaign_h5)}}
    runs = {"single_run": S("run.h5"),
            **{f"real_run_{i}": os.path.abspath(h) for i, h in enumerate(a.run_h5)}}
    built = build_reports(repo, scratch, list(campaigns.items()) + list(runs.items()))

    imgs = {"motor": ["motor_torque_margin.png", "dist_peak_drive_force_N.png",
                      "dist_deploy_time_s.png"], "saltelli": ["sobol_indices.png"]}
    parsed = {name: check_campaign(name, h5, built[name], imgs.get(name, ()))
              for name, h5 in campaigns.items()}
    if parsed["motor"] is not None:
        # Counts known by construction (make_fake_campaign --n-fail 6: two runs each of rail
        # miss, wall-time limit and stall, on top of the motor's own stalls).
        got = {k: v for k, v, _ in parsed["motor"].values}
        with h5py.File(campaigns["motor"], "r") as f:
            n_stall = int(np.sum(f["runs/status"][()] == 2))
        want = {"status_count.rail miss": 2, "status_count.wall-time limit": 2,
                "status_count.stall": n_stall, "runs.n_failed": n_stall + 4,
                "runs.n_ok": 400 - n_stall - 4, "motor.n_stall": n_stall}
        check(n_stall > 2 and all(int(got.get(k, -1)) == v for k, v in want.items()),
              f"motor: counts by status as constructed: {want}")
        check(int(got.get("motor.n_exceed", -1)) >= n_stall,
              f"motor: the {n_stall} stalled runs count as exceedances of the stall torque")
    if parsed["saltelli"] is not None:
        with open(S("report_saltelli/report.html"), encoding="utf-8") as fh:
            page = fh.read()
        check("No ok run has a finite value of <code>peak_drive_torque_Nm</code>" in page
              and "dist_peak_drive_torque_Nm.png" not in page,
              "saltelli: an output without a finite value is skipped with a note")

    for name, h5 in runs.items():
        outdir, r = built[name]
        if check(r.returncode == 0, f"{name}: report.py exit 0 ({r.stderr.strip()[:300]})"):
            p = parse_report(os.path.join(outdir, "report.html"))
            E, required = expected_single_run(h5)
            check_numbers(name, p, E, required)
            with h5py.File(h5, "r") as f:
                nb = int(tomllib.loads(text(f.attrs["scene_toml"]))["mast"]["n_bays"])
                has_history = "history" in f
            check_images(name, outdir, p,
                         [f"fig4_hinge_trajectory_bay{nb}.png", "fig5_drive_and_pin_force.png",
                          f"fig5_bay{nb}_zoom.png"] if has_history else [])

    # Bad input: exit 2, one error line naming the file, nothing written.
    expect_error(repo, scratch, "schema_version_4",
                 fake(repo, S("schema4.h5"), "--schema-version", "4"), "schema_version")
    expect_error(repo, scratch, "truncated", fake(repo, S("trunc.h5"), "--truncate"), "trunc.h5")
    with open(S("text.h5"), "w") as fh:
        fh.write("this is not an HDF5 file\n")
    expect_error(repo, scratch, "text_file", S("text.h5"), "not an HDF5 file")
    expect_error(repo, scratch, "wrong_kind", fake(repo, S("kind.h5"), "--kind", "benchmark"),
                 "kind")
    expect_error(repo, scratch, "missing_dataset",
                 fake(repo, S("omit.h5"), "--omit", "runs/peak_pin_force_N"),
                 "/runs/peak_pin_force_N")
    expect_error(repo, scratch, "missing_file", S("does_not_exist.h5"), "no such file")
    busy = S("busy_dir")
    os.makedirs(busy)
    with open(os.path.join(busy, "notes.txt"), "w") as fh:
        fh.write("user file\n")
    expect_error(repo, scratch, "non_empty_outdir", campaigns["five_runs"], "--force",
                 outdir=busy)
    r = run_report(repo, campaigns["five_runs"], busy, "--force")
    check(r.returncode in VERDICT_EXIT.values() and os.path.exists(os.path.join(busy, "notes.txt"))
          and os.path.exists(os.path.join(busy, "report.html")),
          "--force writes into a non-empty directory and leaves other files alone")

    if FAILS:
        print(f"{len(FAILS)} check(s) failed")
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
