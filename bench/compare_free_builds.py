#!/usr/bin/python3
"""Side-by-side check of two builds on a fixed Monte Carlo sample of a campaign's dispersions.

Turns a campaign (by default campaigns/free_rail_miss_rare.toml) into a plain design campaign
(ensemble.method = design, sampling = monte_carlo, n_runs runs, the same seed and dispersions; no
[failure] or method tables), runs it with each build's truss-campaign on the same ranks, and
compares the two results files column by column:
  - /runs/status identical for every run;
  - the failure margin (rail_margin_m) within --margin-tol (m) on every run;
  - every event time (/runs/<x>_time_s and /runs/bays/<x>_time_s: entry, lock, end, deployment,
    the rail miss's times; not the times of peaks, whose maxima are flat, nor wall times) within
    --time-tol (s) wherever either build has a finite value, NaN in the same places;
  - every other float column: the largest absolute and relative difference (reported only).
Also reports each build's CPU time a run (user + system time of the MPI processes over the runs,
all ranks, rank 0's bookkeeping included), the wall time of the whole campaign and the campaign's
own /timing/run_wall_time_s (median and mean; wall times, so only meaningful on idle cores).

Usage:
  bench/compare_free_builds.py --old OLD_BUILD_DIR --new NEW_BUILD_DIR [--runs 2000] [--ranks 2]
Exit status 0 when every check holds, 1 otherwise.
"""
import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
import tomllib

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{ " + ", ".join(f'"{k}" = {toml_value(x)}' for k, x in v.items()) + " }"
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return repr(v)


def design_campaign(src, runs):
    """The campaign of src as a Monte Carlo design of `runs` runs (same seed, scene, dispersions)."""
    with open(src, "rb") as f:
        c = tomllib.load(f)
    base = os.path.dirname(os.path.abspath(src))
    lines = ["[campaign]", f'name = {toml_value(c["campaign"]["name"] + "-mc")}', "[ensemble]",
             'method = "design"', 'sampling = "monte_carlo"', f"n_runs = {runs}",
             f'master_seed = {c["ensemble"]["master_seed"]}']
    if "max_run_wall_time_s" in c["ensemble"]:
        lines.append(f'max_run_wall_time_s = {c["ensemble"]["max_run_wall_time_s"]}')
    scene = dict(c["scene"])
    scene["file"] = os.path.join(base, scene["file"])
    lines.append("[scene]")
    lines += [f"{k} = {toml_value(v)}" for k, v in scene.items()]
    for d in c.get("dispersion", []):
        lines.append("[[dispersion]]")
        lines += [f"{k} = {toml_value(v)}" for k, v in d.items()]
    return "\n".join(lines) + "\n"


def run(build, campaign, out, ranks):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), os.path.join(build, "truss-campaign"), campaign,
           "-o", out, "--force", "--progress", "none"]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return time.monotonic() - t0, cpu


def columns(f, group):
    out = {}
    for k, d in f[group].items():
        if isinstance(d, h5py.Dataset):
            out[f"{group}/{k}"] = d[...]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="directory of the reference build's truss-campaign")
    ap.add_argument("--new", required=True, help="directory of the build under test's truss-campaign")
    ap.add_argument("--campaign", default=os.path.join(ROOT, "campaigns", "free_rail_miss_rare.toml"))
    ap.add_argument("--runs", type=int, default=2000)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--margin", default="rail_margin_m")
    ap.add_argument("--margin-tol", type=float, default=1e-7, help="m")
    ap.add_argument("--time-tol", type=float, default=1e-6, help="s")
    ap.add_argument("--keep", help="directory to keep the campaign file and the two results in")
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="compare_free_")
    os.makedirs(work, exist_ok=True)
    camp = os.path.join(work, "campaign.toml")
    with open(camp, "w") as f:
        f.write(design_campaign(a.campaign, a.runs))
    files, walls, cpus = {}, {}, {}
    for name, build in (("old", a.old), ("new", a.new)):
        files[name] = os.path.join(work, f"{name}.h5")
        walls[name], cpus[name] = run(build, camp, files[name], a.ranks)
    ok = True
    with h5py.File(files["old"], "r") as fo, h5py.File(files["new"], "r") as fn:
        for name, f in (("old", fo), ("new", fn)):
            t = f["/timing/run_wall_time_s"][...]
            print(f"{name}: campaign wall {walls[name]:.1f} s, CPU {cpus[name]:.1f} s, {1e3 * cpus[name] / len(t):.2f} ms CPU a run; "
                  f"run wall time: median {1e3 * np.median(t):.2f} ms, "
                  f"mean {1e3 * np.mean(t):.2f} ms, max {1e3 * np.max(t):.1f} ms")
        to, tn = fo["/timing/run_wall_time_s"][...], fn["/timing/run_wall_time_s"][...]
        print(f"ratio old/new: CPU a run {cpus['old'] / cpus['new']:.2f}, run wall time median {np.median(to) / np.median(tn):.2f}, mean {np.mean(to) / np.mean(tn):.2f}")
        so, sn = fo["/runs/status"][...], fn["/runs/status"][...]
        diff = np.flatnonzero(so != sn)
        print(f"status: {len(diff)} of {len(so)} runs differ" + (f" (first {diff[:10].tolist()})" if len(diff) else ""))
        ok &= len(diff) == 0
        co = {**columns(fo, "/runs"), **columns(fo, "/runs/bays")}
        cn = {**columns(fn, "/runs"), **columns(fn, "/runs/bays")}
        for key in sorted(co):
            if key not in cn:
                print(f"{key}: missing in new")
                ok = False
                continue
            x, y = co[key], cn[key]
            if x.dtype.kind != "f":
                continue
            both = np.isfinite(x) & np.isfinite(y)
            nan_same = bool(np.all(np.isfinite(x) == np.isfinite(y)))
            d = np.abs(x[both] - y[both])
            dmax = float(d.max()) if d.size else 0.0
            rel = float((d / np.maximum(np.abs(x[both]), 1e-300)).max()) if d.size else 0.0
            leaf = key.rsplit("/", 1)[1]
            tol = None
            if leaf == a.margin:
                tol = a.margin_tol
            elif leaf.endswith("_time_s") and not leaf.startswith(("peak_", "min_")) and "wall" not in leaf:
                tol = a.time_tol
            flag = ""
            if tol is not None:
                good = dmax <= tol and nan_same
                ok &= good
                flag = f"  (tol {tol:g}: {'ok' if good else 'FAIL'})"
            if tol is not None or dmax > 0.0 or not nan_same:
                print(f"{key}: max |diff| {dmax:.3g}, max rel {rel:.3g}, NaN pattern {'same' if nan_same else 'DIFFERS'}{flag}")
    print("all checks hold" if ok else "CHECKS FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
