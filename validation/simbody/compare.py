#!/usr/bin/env python3
"""Cross-check of truss-sim against the Simbody model of the mast (docs/validation.md).

Runs each case with `truss-sim SCENE --json` and `simbody-mast SCENE` (the same scene file and
--set overrides, the same tolerance: Simbody's integration accuracy and constraint tolerance are
the scene's run.rtol), compares event times, peak loads and impact quantities, and times both
side by side (interleaved repeats, medians).

  compare.py --truss-sim BIN --simbody BIN --scenes DIR [--suite ci|full] [--repeats N]
             [--doc docs/validation.md] [--check]

--check fails (exit 1) when a case's difference exceeds its tolerance (see TOLERANCES); --doc
replaces the generated part of that page (between its BEGIN/END markers) with the tables, the
command, the machine and the date. Exit 2 on bad use; a program that fails ends the comparison.
"""
import argparse
import json
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import time

# name, scene file, --set overrides, simbody-mast options, suites
CASES = [
    ("held, velocity, 3 bays", "table1.toml", ["mast.n_bays=3"], [], {"ci", "full"}),
    ("held, motor, 3 bays", "table1.toml", ["mast.n_bays=3", "drive.mode=motor"], [], {"ci", "full"}),
    ("free slack, velocity, 3 bays", "paper_free_slack.toml", ["mast.n_bays=3"], [], {"ci", "full"}),
    ("held, velocity, 2 bays, 3 longerons", "table1.toml", ["mast.n_bays=2"], ["--longerons", "3"], {"ci", "full"}),
    ("free, Table-1 diagonals, velocity, 3 bays (rail miss)", "paper_free.toml",
     ["mast.n_bays=3", "stack.contacts=false"], [], {"ci", "full"}),
    ("held, velocity, 5 bays", "table1.toml", ["mast.n_bays=5"], [], {"full"}),
    ("held, motor, 5 bays", "table1.toml", ["mast.n_bays=5", "drive.mode=motor"], [], {"full"}),
    ("held, torque, 5 bays", "table1.toml", ["mast.n_bays=5", "drive.mode=torque"], [], {"full"}),
    ("free slack, velocity, 5 bays", "paper_free_slack.toml", ["mast.n_bays=5"], [], {"full"}),
    ("free slack, motor, 5 bays", "paper_free_slack.toml", ["mast.n_bays=5", "drive.mode=motor"], [], {"full"}),
    ("held, motor, 3 bays, J_c = 0.002 kg m2, m_tip = 3 kg", "table1.toml",
     ["mast.n_bays=3", "drive.mode=motor", "mast.strut_inertia_kg_m2=0.002", "mast.tip_mass_kg=3.0"], [], {"full"}),
    ("free slack, torque, 3 bays, J_c = 0.002 kg m2", "paper_free_slack.toml",
     ["mast.n_bays=3", "drive.mode=torque", "mast.strut_inertia_kg_m2=0.002"], [], {"full"}),
    ("held, motor, 3 bays, 3 longerons", "table1.toml", ["mast.n_bays=3", "drive.mode=motor"], ["--longerons", "3"],
     {"full"}),
    ("free slack, velocity, 3 bays, 3 longerons", "paper_free_slack.toml", ["mast.n_bays=3"], ["--longerons", "3"],
     {"full"}),
    ("held, velocity, 30 bays (Table 1)", "table1.toml", [], [], {"full"}),
    ("held, motor, 30 bays", "table1.toml", ["drive.mode=motor"], [], {"full"}),
    ("free slack, velocity, 30 bays", "paper_free_slack.toml", [], [], {"full"}),
]
# Convergence: each program at rtol 1e-6..1e-10 against a reference, truss-sim at rtol 1e-12, which
# Simbody at accuracy 1e-12 matches: whose error each difference is.
CONVERGENCE = [("held, velocity, 3 bays", "table1.toml", ["mast.n_bays=3"]),
               ("held, motor, 3 bays", "table1.toml", ["mast.n_bays=3", "drive.mode=motor"]),
               ("free slack, velocity, 3 bays", "paper_free_slack.toml", ["mast.n_bays=3"]),
               ("free, Table-1 diagonals, 3 bays (rail miss)", "paper_free.toml",
                ["mast.n_bays=3", "stack.contacts=false"])]
RTOLS = [1e-6, 1e-8, 1e-10, 1e-12]

# Tolerances of --check, in units of the scene's rtol (why: docs/validation.md, "Tolerances"): both
# programs' errors are proportional to rtol; over the full suite and rtol 1e-6..1e-10, event times
# differ by at most 18 rtol T (T the run's duration), loads and impact quantities by 200 rtol.
TOLERANCES = {"event_time": 100.0, "relative": 1000.0}


def run(cmd):
    """Runs cmd; returns (parsed JSON stdout, process CPU time in s)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 1):  # 1: the run ended without deploying (its JSON is complete)
        sys.exit(f"error: {' '.join(cmd)} exited {proc.returncode}: {proc.stderr.strip()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return json.loads(proc.stdout), cpu


def rel(a, b):
    return abs(b - a) / max(abs(a), 1e-300)


def compare(t, s):
    """Differences between a truss-sim summary t and a Simbody summary s. A run that does not deploy
    (a rail miss) has no per-bay events: its end time is compared instead."""
    d = {"status": (t["status"], s["status"])}
    times, impacts, bay_drive = [abs(s["end_time_s"] - t["end_time_s"])], [0.0], []
    for bt, bs in zip(t["bays"], s["bays"]):
        if bt["lock_time_s"] is None or bs["lock_time_s"] is None:
            continue
        times += [abs(bs[k] - bt[k]) for k in ("entry_time_s", "lock_time_s")]
        impacts += [rel(bt[k], bs[k]) for k in ("entry_energy_loss_J", "latch_energy_J", "entry_impulse_Ns")]
        bay_drive.append(rel(bt["peak_drive_force_N"], bs["peak_drive_force_N"]))
    if not bay_drive:
        bay_drive.append(rel(t["peak_drive_force_N"], s["peak_drive_force_N"]))
    d["event_time_s"] = max(times)
    d["deploy_time_s"] = t["end_time_s"]
    d["drive_force"] = (t["peak_drive_force_N"], s["peak_drive_force_N"], rel(t["peak_drive_force_N"],
                                                                               s["peak_drive_force_N"]))
    d["bay_drive_force"] = max(bay_drive)
    d["tension"] = (t["peak_diagonal_tension_N"], s["peak_diagonal_tension_N"],
                    rel(t["peak_diagonal_tension_N"], s["peak_diagonal_tension_N"]))
    pins = [x["peak_pin_force_N"] or 0.0 for x in (t, s)]  # never on the rail: 0 (truss-sim), null (Simbody)
    d["pin_force"] = rel(*pins) if pins[0] else abs(pins[1])
    d["impacts"] = max(impacts)
    return d


def check(name, rtol, d):
    """Failures of one case against TOLERANCES."""
    bad = []
    if d["status"][0] != d["status"][1]:
        bad.append(f"status {d['status']}")
    if d["event_time_s"] > TOLERANCES["event_time"] * rtol * d["deploy_time_s"]:
        bad.append(f"event times differ by {d['event_time_s']:.3g} s")
    for key in ("bay_drive_force", "pin_force", "impacts"):
        if d[key] > TOLERANCES["relative"] * rtol:
            bad.append(f"{key} differs by {d[key]:.3g} (relative)")
    for key in ("drive_force", "tension"):
        if d[key][2] > TOLERANCES["relative"] * rtol:
            bad.append(f"{key} differs by {d[key][2]:.3g} (relative)")
    return [f"{name}: {b}" for b in bad]


def commands(args, scene, sets, sim_opts):
    """Both command lines. Neither records time histories (truss-sim would sample the scene's
    run.output_step_s grid: 11,000 rows for Table 1; simbody-mast ignores the key)."""
    path = f"{args.scenes}/{scene}"
    set_args = [a for kv in ["run.output_step_s=0"] + sets for a in ("--set", kv)]
    return ([args.truss_sim, path, "--json"] + set_args, [args.simbody, path] + set_args + sim_opts)


def run_cases(args, cases):
    """Interleaved repeats: every case once per round, the two programs in alternating order."""
    rows = {name: {"ts": [], "sb": []} for name, *_ in cases}
    for r in range(args.repeats):
        for name, scene, sets, sim_opts, _ in cases:
            ts_cmd, sb_cmd = commands(args, scene, sets, sim_opts)
            order = [("ts", ts_cmd), ("sb", sb_cmd)] if r % 2 == 0 else [("sb", sb_cmd), ("ts", ts_cmd)]
            for who, cmd in order:
                rows[name][who].append(run(cmd))
    return rows


def fmt(x, digits=3):
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)


def table_rows(cases, rows):
    agreement, speed, failures = [], [], []
    for name, scene, sets, sim_opts, _ in cases:
        t, s = rows[name]["ts"][0][0], rows[name]["sb"][0][0]
        rtol = s["accuracy"]
        d = compare(t, s)
        failures += check(name, rtol, d)
        agreement.append(
            f"| {name} | {t['status']} / {s['status']} | {fmt(d['deploy_time_s'], 10)} | {fmt(d['event_time_s'])} | "
            f"{fmt(d['drive_force'][0], 8)} | {fmt(d['drive_force'][2])} | {fmt(d['bay_drive_force'])} | "
            f"{fmt(d['tension'][0], 8)} | {fmt(d['tension'][2])} | {fmt(d['pin_force'])} | {fmt(d['impacts'])} |")
        ts_run = statistics.median(x[0]["wall_time_s"] for x in rows[name]["ts"])
        sb_run = statistics.median(x[0]["wall_time_s"] for x in rows[name]["sb"])
        sb_run_cpu = statistics.median(x[0]["cpu_time_s"] for x in rows[name]["sb"])
        ts_cpu = statistics.median(x[1] for x in rows[name]["ts"])
        sb_cpu = statistics.median(x[1] for x in rows[name]["sb"])
        # The ratio divides Simbody's CPU time by truss-sim's wall time: truss-sim's runs last
        # milliseconds and are rarely preempted; Simbody's last seconds, and on a loaded machine
        # their wall time counts other processes' time too. On a quiet machine both are wall times.
        speed.append(f"| {name} | {t['steps']} | {s['steps']} | {fmt(ts_run)} | {fmt(sb_run)} | {fmt(sb_run_cpu)} | "
                     f"{sb_run_cpu / ts_run:.0f} | {fmt(ts_cpu)} | {fmt(sb_cpu)} | {sb_cpu / max(ts_cpu, 1e-3):.0f} |")
    return agreement, speed, failures


AGREEMENT_HEAD = [
    "| case | status (truss-sim / Simbody) | deployment time (s) | event times: max abs. difference (s) | "
    "peak drive force (N) | its rel. difference | per-bay peak drive force: max rel. difference | "
    "peak diagonal tension (N) | its rel. difference | peak pin force: rel. difference | "
    "impacts (entry and latch energy, entry impulse): max rel. difference |",
    "|---|---|---|---|---|---|---|---|---|---|---|"]
SPEED_HEAD = [
    "| case | truss-sim steps | Simbody steps | truss-sim run, wall (s) | Simbody run, wall (s) | "
    "Simbody run, CPU (s) | ratio of the runs (Simbody CPU / truss-sim wall) | truss-sim process CPU (s) | "
    "Simbody process CPU (s) | ratio (process CPU) |",
    "|---|---|---|---|---|---|---|---|---|---|"]


def convergence_rows(args):
    out = ["| case | rtol | truss-sim: event times (s) | Simbody: event times (s) | truss-sim: loads | "
           "Simbody: loads | truss-sim: impacts | Simbody: impacts |", "|---|---|---|---|---|---|---|---|"]
    for name, scene, sets in CONVERGENCE:
        def runs(rtol):
            extra = [f"run.rtol={rtol}", f"run.atol={rtol / 100}"]
            ts_cmd, sb_cmd = commands(args, scene, sets + extra, [])
            return run(ts_cmd)[0], run(sb_cmd)[0]
        reference = runs(1e-12)[0]
        for rtol in RTOLS:
            t, s = runs(rtol)
            dt, ds = compare(reference, t), compare(reference, s)
            loads = [max(d["bay_drive_force"], d["tension"][2], d["pin_force"]) for d in (dt, ds)]
            out.append(f"| {name} | {rtol:g} | {fmt(dt['event_time_s'])} | {fmt(ds['event_time_s'])} | "
                       f"{fmt(loads[0])} | {fmt(loads[1])} | {fmt(dt['impacts'])} | {fmt(ds['impacts'])} |")
    return out


BEGIN = "<!-- BEGIN generated by validation/simbody/run_validation.sh: do not edit by hand -->"
END = "<!-- END generated -->"


def output(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def machine():
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()} "
            f"(load average {load:.1f} at the start)")


def write_doc(args, tables, seconds):
    """Replaces the generated block of args.doc (between BEGIN and END) with the tables."""
    with open(args.doc) as f:
        page = f.read()
    if BEGIN not in page or END not in page:
        sys.exit(f"error: {args.doc}: no generated block (the lines {BEGIN!r} and {END!r})")
    root = os.path.dirname(os.path.abspath(args.scenes.rstrip("/"))) + "/.."
    head = [
        f"Produced by `validation/simbody/run_validation.sh` on {time.strftime('%Y-%m-%d')}, in {seconds:.0f} s: "
        f"{args.repeats} interleaved repeats per case, medians of the run times.",
        "",
        f"- Machine: {machine()}.",
        f"- {output([args.truss_sim, '--version'])}, source revision "
        f"{output(['git', '-C', root, 'rev-parse', '--short', 'HEAD'])}; Simbody "
        f"{output(['dpkg-query', '-W', '-f', '${Version}', 'libsimbody3.7'])} (Debian's libsimbody3.7).",
        "- Every case: the scene's `run.rtol` (1e-8) for both; Simbody's integrator Runge-Kutta-Merson.",
        ""]
    block = "\n".join([BEGIN, ""] + head + tables + [END])
    page = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: block, page, flags=re.S)
    with open(args.doc, "w") as f:
        f.write(page)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--truss-sim", required=True)
    ap.add_argument("--simbody", required=True)
    ap.add_argument("--scenes", required=True, help="campaigns/scenes")
    ap.add_argument("--suite", choices=["ci", "full"], default="ci")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--doc", help="rewrite the generated part of this page (docs/validation.md)")
    ap.add_argument("--check", action="store_true", help="exit 1 when a difference exceeds its tolerance")
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be at least 1")
    cases = [c for c in CASES if args.suite in c[4]]
    start = time.time()
    rows = run_cases(args, cases)
    agreement, speed, failures = table_rows(cases, rows)
    text = ["### Agreement", ""] + AGREEMENT_HEAD + agreement + ["", "### Run time", ""] + SPEED_HEAD + speed
    if args.suite == "full":
        text += ["", "### Convergence", ""] + convergence_rows(args)
    text.append("")
    if args.doc:
        write_doc(args, text, time.time() - start)
    print("\n".join(text))
    print(f"{len(cases)} cases in {time.time() - start:.1f} s")
    if args.check and failures:
        print("\n".join(["FAILED:"] + failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
