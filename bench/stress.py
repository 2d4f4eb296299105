#!/usr/bin/python3
"""Stress grid of single runs: does any run lie at the edges?

Runs truss-sim over a seeded grid around Table 1: one-key sweeps over wide physical ranges, every
numeric key at 1e-9 and 1e9 of its value, and random combinations (log-uniform in several keys at
once), in all three drive modes and both directions. For every run it checks the promises:
  - the exit code is 0 (ok), 1 (a named non-ok status) or 2 (refused input); nothing else;
  - an `ok` run reports finite numbers (run-level loads, energies, times; per-bay event times);
  - no run exceeds its wall-time cap (run.max_wall_time_s plus the process's start and output).
  - an `ok` free-stack run with stack contacts keeps its frames apart to 2e-9 l_s
    (docs/model-notes.md, "Overlap bound");
  - the process's resident memory stays under the history cap (run.max_history_bytes, three times
    over: the columns, their JSON text, the output) plus 64 MB, and the dense Newton matrices of
    cvode / ida (three (2n)^2 float64 copies);
  - the run's wall time (its own clock) stays within its cap + 5 % (+ 0.05 s of timer slack).
The free-stack cases cover contacts on and off, slack and Table-1 diagonals, dopri54, cvode and
ida, with and without time histories (every 1 ms), and in the full grid 300 and 2,000 bays.
It prints the counts by status, the NaN-in-ok count, timeouts, cap violations and wall-time
percentiles, and exits 1 if a promise was broken.

  bench/stress.py --sim build/truss-sim                 # the full grid (about 3,000 runs)
  bench/stress.py --sim build/truss-sim --reduced       # about a minute: the ctest `stress_reduced`
  bench/stress.py --sim build/truss-sim --caps --cap-s 2   # the wall-cap cases: about a minute

--caps runs the wall-cap cases instead of the grid: the hostile cases of long stacks (CVODE's dense
Newton matrix at 2,000 bays, torque drives of 1,200 bays with short phases) and a long-stack
family (200, 600 and 2,000 bays; every integrator; held and free stack), and checks that each run
ends within its cap plus 5 % or 0.5 s, whichever is larger, and says `wall-time limit` when it
runs to the cap.
"""
import argparse
import collections
import concurrent.futures as cf
import itertools
import json
import math
import os
import random
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "campaigns", "scenes", "table1.toml")
HISTORY_BYTES = 16_000_000  # run.max_history_bytes of every run (the default)

# Table 1 values of the numeric keys (the scene file's), for the 1e-9 / 1e9 extremes.
NOMINAL = {
    "mast.strut_length_m": 0.18, "mast.strut_mass_kg": 0.1, "mast.frame_side_m": 0.36,
    "mast.frame_mass_kg": 0.5, "mast.diagonal_stiffness_N_per_m": 20.0, "mast.diagonal_free_length_m": 0.45,
    "rail.x_m": 0.08, "rail.y_m": 0.15, "rail.beta_deg": 20.85, "drive.speed_m_per_s": 0.1,
    "drive.screw_lead_m": 0.01, "drive.torque_Nm": 0.01, "drive.stall_torque_Nm": 0.02,
    "drive.no_load_speed_rad_per_s": 75.0,
}
SWEEPS = {
    "mast.diagonal_stiffness_N_per_m": [1, 10, 100, 1e3, 1e4, 1e5, 1e6],
    "drive.speed_m_per_s": [1e-3, 1e-2, 0.1, 0.5, 1, 2],
    "mast.n_bays": [1, 2, 10, 100, 1000],
    "mast.strut_mass_kg": [1e-4, 1e-3, 1e-2, 0.1, 1],
    "mast.frame_mass_kg": [1e-4, 1e-3, 1e-2, 0.1, 1],
    "rail.beta_deg": [5, 10, 20, 30, 40, 44, 45, 50, 60],
    "drive.stall_torque_Nm": [1e-3, 1e-2, 0.1, 1, 10],
    "drive.no_load_speed_rad_per_s": [0.75, 7.5, 75, 750],
    "run.rtol": [1e-2, 1e-3, 1e-6, 1e-10, 1e-13],
}
FULL_ONLY = {"mast.n_bays": [10000, 100000]}
MODES = ["velocity", "torque", "motor"]
DIRECTIONS = ["deploy", "retract"]
OK_FINITE = ["deploy_time_s", "end_time_s", "peak_drive_force_N", "min_drive_force_N", "peak_pin_force_N",
             "peak_diagonal_tension_N", "drive_work_J", "energy_lost_J", "energy_residual_J"]


def cases(reduced, seed):
    rng = random.Random(seed)
    out = []
    sweeps = dict(SWEEPS)
    if not reduced:
        for k, v in FULL_ONLY.items():
            sweeps[k] = sweeps[k] + v
    for mode, direction in itertools.product(MODES, DIRECTIONS):
        for key, values in sweeps.items():
            for v in values:
                out.append({key: v, "drive.mode": mode, "run.direction": direction})
        for key, nominal in NOMINAL.items():
            for f in (1e-9, 1e9):
                out.append({key: nominal * f, "drive.mode": mode, "run.direction": direction})
    n_random = 60 if reduced else 1200
    for _ in range(n_random):
        c = {"drive.mode": rng.choice(MODES), "run.direction": rng.choice(DIRECTIONS)}
        for key in rng.sample(sorted(NOMINAL), 3):
            c[key] = NOMINAL[key] * 10 ** rng.uniform(-2, 2)
        c["mast.n_bays"] = rng.choice([1, 3, 10, 30, 100])
        out.append(c)
    if reduced:
        rng.shuffle(out)
        out = out[:240]
    return out + free_cases(reduced, rng)


def free_cases(reduced, rng):
    """The free stack: contacts on/off, slack (l_0 = 0.49 m) and Table-1 diagonals, three
    integrators, histories on and off; the full grid adds 300- and 2,000-bay masts."""
    out = []
    bays = [1, 3, 10, 30] + ([] if reduced else [300, 2000])
    for _ in range(40 if reduced else 400):
        c = {"stack.mode": "free", "stack.contacts": rng.choice(["true", "false"]),
             "drive.mode": rng.choice(MODES), "run.direction": rng.choice(DIRECTIONS),
             "run.integrator": rng.choice(["dopri54", "cvode", "ida"]),
             "mast.diagonal_free_length_m": rng.choice([0.45, 0.49]),
             "mast.n_bays": rng.choice(bays), "run.output_step_s": rng.choice([0.0, 1e-3]),
             "run.rtol": 10 ** rng.uniform(-12, -3), "drive.torque_Nm": 0.002}
        out.append(c)
    return out


PAPER_FREE = os.path.join(HERE, "..", "campaigns", "scenes", "paper_free.toml")
INTEGRATORS = ["dopri54", "cvode", "cvode_adams", "auto", "ida"]


def cap_cases():
    """Hostile long-stack cases and the long-stack family (--caps); "scene" picks the scene file."""
    free = {"stack.mode": "free", "scene": PAPER_FREE}
    out = [
        dict(free, **{"stack.contacts": "false", "drive.mode": "velocity", "run.integrator": "cvode",
                      "mast.n_bays": 2000, "mast.diagonal_stiffness_N_per_m": 2415084.4848208167,
                      "mast.diagonal_free_length_m": 0.08339880851519334, "stack.start": start})
        for start in ("rest", "kick")]
    out.append(dict(free, **{"run.integrator": "cvode", "mast.n_bays": 2000, "drive.mode": "torque",
                             "mast.frame_mass_kg": 0.37641676509820243,
                             "mast.diagonal_stiffness_N_per_m": 0.043178328733144165,
                             "mast.frame_side_m": 2.48698767044309, "drive.torque_Nm": 0.46415925696786214,
                             "drive.screw_lead_m": 0.0003165702424885785, "run.rtol": 1.1842477732355108e-08,
                             "run.atol": 1.2178614245628708e-07}))
    out.append({"stack.mode": "free", "run.integrator": "dopri54", "mast.n_bays": 1222, "drive.mode": "torque",
                "drive.speed_m_per_s": 1.777290805037229e-05})
    out.append(dict(free, **{"run.integrator": "dopri54", "mast.n_bays": 1202, "rail.x_m": 0.09850821610554285,
                             "rail.y_m": 0.10555789738322481, "rail.beta_deg": 42.89853345116937,
                             "drive.mode": "torque", "drive.no_load_speed_rad_per_s": 64189.44773945941,
                             "run.rtol": 4.6793448256631464e-05}))
    out.append(dict(free, **{"run.integrator": "auto", "mast.n_bays": 1209, "drive.mode": "torque"}))
    out.append(dict(free, **{"run.integrator": "cvode_adams", "mast.n_bays": 619, "drive.mode": "motor",
                             "stack.contacts": "true"}))
    for n, integrator, stack in itertools.product([200, 600, 2000], INTEGRATORS, ["held", "free"]):
        if integrator == "ida" and stack == "held":
            continue  # ida solves the free stack's phases only
        c = {"mast.n_bays": n, "run.integrator": integrator, "stack.mode": stack, "drive.mode": "torque",
             "drive.torque_Nm": 0.002}
        out.append(dict(c, scene=PAPER_FREE) if stack == "free" else c)
    return out


def cap_bound_s(cap):
    """The wall-time promise: the cap plus 5 % or 0.5 s, whichever is larger."""
    return cap + max(0.05 * cap, 0.5)


def run_one(sim, case, cap_s):
    # GNU time's last stderr line: the process's peak resident memory (KiB)
    case = dict(case)
    scene = case.pop("scene", SCENE)
    args = ["/usr/bin/time", "-f", "maxrss_kib=%M", sim, scene, "--json", "--set", "run.output_step_s=0",
            "--set", f"run.max_wall_time_s={cap_s}", "--set", f"run.max_history_bytes={HISTORY_BYTES}"]
    for k, v in case.items():
        value = v if isinstance(v, str) else str(int(v)) if k == "mast.n_bays" else repr(float(v))
        args += ["--set", f"{k}={value}"]
    t0 = time.monotonic()
    try:
        p = subprocess.run(args, capture_output=True, text=True, timeout=cap_s * 3 + 20)
    except subprocess.TimeoutExpired:
        return {"case": case, "rc": "timeout", "wall": time.monotonic() - t0}
    rss = [line for line in p.stderr.splitlines() if line.startswith("maxrss_kib=")]
    stderr = "\n".join(line for line in p.stderr.splitlines() if not line.startswith("maxrss_kib="))
    r = {"case": dict(case, scene=os.path.basename(scene)), "rc": p.returncode, "wall": time.monotonic() - t0, "stderr": stderr[-300:],
         "rss_bytes": 1024 * int(rss[-1].split("=")[1]) if rss else 0}
    if p.returncode in (0, 1) and p.stdout.strip():
        try:
            r["json"] = json.loads(p.stdout)
        except ValueError:
            r["rc"] = "bad json"
    return r


def nonfinite_fields(js):
    bad = [k for k in OK_FINITE if not (isinstance(js.get(k), (int, float)) and math.isfinite(js[k]))]
    for b in js.get("bays", []):
        for k in ("lock_time_s", "entry_time_s", "latch_energy_J"):
            if not (isinstance(b.get(k), (int, float)) and math.isfinite(b[k])):
                bad.append(f"bays[{b.get('bay')}].{k}")
    return bad


def memory_bound_bytes(case):
    n = int(case.get("mast.n_bays", 30))
    dense = case.get("run.integrator") in ("cvode", "ida") and case.get("stack.mode") == "free"
    bound = 64e6 + 3 * HISTORY_BYTES + (3 * 8 * (2 * n + 3) ** 2 if dense else 0)
    if os.environ.get("TRUSS_SANITIZED") == "1":
        # AddressSanitizer keeps freed blocks in its quarantine (256 MB by default,
        # quarantine_size_mb) and a shadow byte per 8 bytes, with red zones around each block.
        bound = 2 * bound + 256e6
    return bound


def promise_problems(r, js, cap):
    """The overlap bound of contacts, the memory cap and the wall-time cap."""
    out, case = [], r["case"]
    l_s = float(case.get("mast.strut_length_m", 0.18))
    if (js["status"] == "ok" and case.get("stack.contacts") == "true"
            and js.get("min_bay_opening_m", 0.0) < -2e-9 * l_s):
        out.append(f"ok run overlapping by {-js['min_bay_opening_m']:.3g} m with contacts on: {case}")
    if r["rss_bytes"] > memory_bound_bytes(case):
        out.append(f"resident memory {r['rss_bytes'] / 1e6:.0f} MB over {memory_bound_bytes(case) / 1e6:.0f} MB: {case}")
    if js.get("wall_time_s", 0.0) > 1.05 * cap + 0.05:
        out.append(f"over its cap ({js['wall_time_s']:.2f} s > {cap} s + 5 %): {case}")
    return out


def cap_problems(r, js, cap):
    """--caps: the run ends within cap_bound_s (its own clock; the process gets 2 s more for its
    start and output) and says `wall-time limit` when it ran to the cap."""
    out, case = [], r["case"]
    if js.get("wall_time_s", 0.0) > cap_bound_s(cap) or r["wall"] > cap_bound_s(cap) + 2.0:
        out.append(f"over its cap ({js.get('wall_time_s', 0.0):.2f} s, process {r['wall']:.2f} s > "
                   f"{cap_bound_s(cap):.2f} s): {case}")
    if js.get("wall_time_s", 0.0) >= cap and js["status"] != "wall-time limit":
        out.append(f"ran {js['wall_time_s']:.2f} s to its cap of {cap} s but says {js['status']!r}: {case}")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sim", required=True, help="path to truss-sim")
    ap.add_argument("--reduced", action="store_true", help="about a minute (ctest)")
    ap.add_argument("--seed", type=int, default=20261123)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--cap-s", type=float, default=None, help="run.max_wall_time_s of every run")
    ap.add_argument("--caps", action="store_true", help="the wall-cap cases (cap_cases) instead of the grid")
    ap.add_argument("--show", default="", help="comma-separated statuses whose cases and messages to print")
    a = ap.parse_args()
    cap = a.cap_s if a.cap_s is not None else (2.0 if a.reduced else 20.0)
    todo = cap_cases() if a.caps else cases(a.reduced, a.seed)
    t0 = time.monotonic()
    with cf.ThreadPoolExecutor(a.jobs) as ex:
        results = list(ex.map(lambda c: run_one(a.sim, c, cap), todo))
    by_status, problems, walls = collections.Counter(), [], []
    for r in results:
        walls.append(r["wall"])
        if r["rc"] == 2:
            by_status["refused (exit 2)"] += 1
            continue
        if a.caps and r["rc"] == "timeout":
            problems.append(f"over its cap (killed after {r['wall']:.1f} s): {r['case']}")
        if r["rc"] not in (0, 1) or "json" not in r:
            problems.append(f"exit {r['rc']}: {r['case']} {r.get('stderr', '')!r}")
            by_status[f"exit {r['rc']}"] += 1
            continue
        js = r["json"]
        by_status[js["status"]] += 1
        if (js["status"] == "ok") != (r["rc"] == 0):
            problems.append(f"status {js['status']} with exit {r['rc']}: {r['case']}")
        if js["status"] == "ok" and (bad := nonfinite_fields(js)):
            problems.append(f"NaN in ok run ({', '.join(bad[:4])}): {r['case']}")
        problems += cap_problems(r, js, cap) if a.caps else promise_problems(r, js, cap)
    walls.sort()
    pct = lambda q: walls[min(len(walls) - 1, int(q * len(walls)))]
    print(f"stress grid: {len(results)} runs (seed {a.seed}, cap {cap} s, {a.jobs} jobs) in {time.monotonic() - t0:.1f} s")
    for k, v in sorted(by_status.items(), key=lambda kv: -kv[1]):
        print(f"  {k:24s} {v:6d}")
    nan_ok = sum(p.startswith("NaN in ok") for p in problems)
    timeouts = sum(r["rc"] == "timeout" for r in results)
    print(f"  NaN in ok runs: {nan_ok}; timeouts: {timeouts}; exit codes outside 0/1/2: "
          f"{sum(r['rc'] not in (0, 1, 2) for r in results)}")
    print(f"  process wall time (s): median {pct(0.5):.3f}, p90 {pct(0.9):.3f}, p99 {pct(0.99):.3f}, max {walls[-1]:.3f}")
    if a.caps:
        capped = [r["json"]["wall_time_s"] for r in results if r.get("json", {}).get("status") == "wall-time limit"]
        if capped:
            print(f"  runs to the cap: {len(capped)}, their own wall time {min(capped):.3f}-{max(capped):.3f} s "
                  f"(bound {cap_bound_s(cap):.3f} s)")
    show = set(filter(None, a.show.split(",")))
    for r in results:
        st = r.get("json", {}).get("status", "refused (exit 2)" if r["rc"] == 2 else None)
        if st in show:
            print(f"  {st}: {r['case']}: {(r.get('json', {}).get('message') or r.get('stderr', ''))[:240]}")
    for p in problems[:30]:
        print("  PROBLEM", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
