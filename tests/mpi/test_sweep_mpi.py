#!/usr/bin/python3
"""Design sweeps ([sweep], methods/sweep_method.hpp) through the engine under a real mpirun.

  test_sweep_mpi.py --case reference|motor_reference|stop|refine|ranks|resume|standalone|bad_input
                    --driver truss-campaign --repo SRC --scratch DIR

The runs are synthetic (--synthetic-run-cost-s): their [failure] column is the sum of the
dispersions' first applied values (parallel/synthetic_run.hpp). tests/mpi/sweep_analytic.toml
disperses the stall torque as x + N(0, sigma), sigma = 1 mN m, so its margin fails with
p(x) = Phi(-x / sigma) (scipy here, not the code under test), and p(x) = 1e-6 at
x* = -Phi^-1(1e-6) sigma = 4.7534 mN m. A spread sweep of the same dispersion with x = 5 mN m fixed:
p(sigma) = Phi(-x / sigma), 1e-6 at sigma* = x / 4.7534.

- reference: 20 master seeds of each sweep: the allowable's interval contains the true crossing, and
  the allowable (the crossing of the one-sided 95 % upper bound) lies on the safe side of it, as
  often as a 95 % confidence says: in at least 16 of 20 (at a true 95 % the count falls below 16 with
  probability 0.3 %, below 18 with 7.5 %); each value's two-sided 95 % interval holds the true p as
  often: of the 80 estimates at least 71 (below 71 with probability 0.7 %). The intervals use the
  campaign's default, adaptive conditional sampling with SubsetSummary::cov_interval (on seeds 1 to
  40 the allowable on the safe side in 37 of 40 spread sweeps, the interval holding the crossing in
  40; modified Metropolis with cov_bound 38 and 39); with the lineage CoV alone they held p in 70/80
  and 68/80 here (the one-input limit state leaves the failure samples few roots,
  docs/campaigns.md "Which CoV to read").
  Then Monte Carlo as the inner method at a p where it resolves: each value's failure count and
  Clopper-Pearson bounds recomputed from its rows (scipy's beta quantiles).
- motor_reference: real runs (tests/mpi/sweep_motor_reference.toml: the motor torque margin of a
  4-bay held stack at stall torques 11.8, 12.2, 12.6 mN m) against crude Monte Carlo of the
  campaign without [sweep] at each value (0.2, 0.6 and 1.2 million runs, p from the rows' margins,
  Clopper-Pearson by scipy): over 20 seeds of the subset sweep, each value's 95 % interval holds the
  crude p as often as its confidence says (at least 53 of the 60 estimates: under 53 with probability
  1 % at a true 95 %), and for a target in each bracket (1e-3, 3e-4) the
  allowable's interval holds the crossing of the crude p curve (linear in ln p) in at least 18 of 20.
- stop: [ensemble.stop] (probability target) as the inner method on real free-stack runs: each
  value's rounds recomputed from its rows, its bounds Clopper-Pearson (scipy), the allowable the
  crossing of those bounds, values 0 and 2 the standalone stop campaign's rounds and estimates.
- refine: sweep.refine = 4 (values placed evenly inside the bracket of the listed values'
  allowable): the listed values' columns are those of the sweep without refinement, byte for byte;
  the placed values are evenly inside the bracket found here from the listed values' columns; the
  allowable is recomputed from all values' columns. On a coarse sweep (3 and 6 mN m: the chord of
  the concave ln p lies below it, so the listed values' allowable can fall on the unsafe side), over
  20 seeds the refined allowable lies on the safe side of the true crossing and its interval holds
  it in at least 18 each. With a target no listed value's bound reaches, nothing is refined and
  /sweep says why.
- ranks: the same file (every dataset but the timing) on 1 and 3 ranks, with a refinement; and a
  sweep of motor runs whose chains' columns are read back at the end by the 3 ranks, each its share
  of the datasets: the 1-rank file, /stats equal to numpy's.
- resume: kill -9 of the whole job during the refinement, --resume: the same file.
- standalone: value k of the sweep against the campaign without [sweep] at that value
  (--set drive.stall_torque_Nm=x_k, ensemble.master_seed = /sweep/master_seed[k]): /sweep/inner/<k>
  holds the standalone campaign's method group (/subset: p, CoVs, levels, failure samples; Monte
  Carlo: /failure), dataset for dataset, and the value's rows (by run index) are the standalone
  campaign's rows, for two listed values and one the refinement placed.
- bad_input: each refusal exits 2 with file:line and the key, writing nothing.
"""
import argparse
import math
import os
import re
import struct
import subprocess
import sys
import time

import h5py
import numpy as np
from scipy.stats import beta as beta_dist, norm

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_campaign_mpi import ENV, check, check_stats, datasets, fresh, same_values  # noqa: E402
from test_journal_faults import all_journal_frames, kill_job  # noqa: E402

SIGMA = 0.001
Z_TARGET = -norm.ppf(1e-6)


def campaign_path(args):
    return os.path.join(args.repo, "tests", "mpi", "sweep_analytic.toml")


def run(args, out, ranks=2, sets=(), cost="0", extra=(), campaign=None, timeout=600):
    """The campaign under mpirun; synthetic runs of that cost each, or the simulator's (cost None)."""
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), args.driver, campaign or campaign_path(args), "-o", out,
           "--progress", "none"] + (["--synthetic-run-cost-s", cost] if cost is not None else [])
    for s in sets:
        cmd += ["--set", s]
    return subprocess.run(cmd + list(extra), env=ENV, capture_output=True, text=True, timeout=timeout)


def read_sweep(path):
    with h5py.File(path, "r") as f:
        g = f["sweep"]
        s = {k: g[k][()] for k in ("values", "p", "cov", "upper_bound", "lower", "upper", "runs", "master_seed",
                                   "index", "refinement")}
        s.update({k: g.attrs[k] for k in ("refine", "refine_message", "refine_low", "refine_high")})
        a = g["allowable"]
        s["allowable"] = {k: float(a[k][()]) for k in ("value", "estimate", "lower", "upper")}
        s["allowable"].update({k: a.attrs[k] for k in ("status", "safe_side", "verdict")})
        return s


SPREAD_CAMPAIGN = """
[campaign]
name = "sweep-analytic-spread"
[ensemble]
master_seed = 11
method = "subset"
[ensemble.subset]
n_per_level = 500
p0 = 0.1
max_levels = 12
[failure]
margin = "motor_torque_margin_Nm"
[scene.drive]
stall_torque_Nm = 0.005
[sweep]
spread = "drive.stall_torque_Nm"
values = [0.0009, 0.001, 0.0011, 0.0012]
target_probability = 1e-6
[[dispersion]]
key = "drive.stall_torque_Nm"
apply = "offset"
distribution = "normal"
std = 0.001
"""


def case_reference(args):
    d = fresh(args, "sweep_reference")
    spread_camp = os.path.join(d, "spread.toml")
    open(spread_camp, "w").write(SPREAD_CAMPAIGN)
    cases = [("nominal", None, SIGMA * Z_TARGET, lambda x: norm.cdf(-x / SIGMA)),
             ("spread", spread_camp, 0.005 / Z_TARGET, lambda s: norm.cdf(-0.005 / s))]
    for name, camp, truth, p_true in cases:
        inside = safe = covered = n_est = open_ends = 0
        for seed in range(1, 21):
            out = os.path.join(d, f"{name}_{seed}.h5")
            p = run(args, out, sets=[f"ensemble.master_seed={seed}"], campaign=camp)
            check(p.returncode == 0, f"{name}, seed {seed}: exit 0 ({p.stderr.strip()[-300:]})")
            s = read_sweep(out)
            a = s["allowable"]
            check(a["status"] == "found", f"{name}, seed {seed}: the allowable is found ({a})")
            # A NaN end: the interval reaches beyond the swept values on that side (hdf5-schema.md).
            inside += (math.isnan(a["lower"]) or a["lower"] <= truth) and (math.isnan(a["upper"]) or truth <= a["upper"])
            open_ends += math.isnan(a["lower"]) + math.isnan(a["upper"])
            # The allowable is on the safe side of the truth: above it when p falls with the value.
            safe += (a["value"] >= truth) if a["safe_side"] == "above" else (a["value"] <= truth)
            pt = p_true(s["values"])
            covered += int(np.sum((s["lower"] <= pt) & (pt <= s["upper"])))
            n_est += len(pt)
            os.remove(out)
        print(f"  {name}: interval holds the true crossing {truth:.6g} in {inside}/20 seeds ({open_ends} open ends); "
              f"allowable on the safe "
              f"side in {safe}/20; p's interval holds the true p in {covered}/{n_est}")
        # Binomial(n, 0.95) more than 2.2 standard deviations below its mean: under 16 of 20 (0.3 %),
        # under 71 of 80 (0.7 %).
        least = math.floor(0.95 * 20 - 2.2 * math.sqrt(20 * 0.95 * 0.05))
        check(inside >= least, f"{name}: the allowable's interval contains the true crossing in {inside} >= {least} "
              "of 20")
        check(safe >= least, f"{name}: the allowable lies on the safe side of the true crossing in {safe} >= {least} "
              "of 20")
        need = math.floor(0.95 * n_est - 2.2 * math.sqrt(n_est * 0.95 * 0.05))
        check(covered >= need, f"{name}: each value's 95 % interval holds the true p in {covered}/{n_est} (>= {need})")
    # Monte Carlo as the inner method, where 20,000 runs resolve p (1e-3 .. 1e-4): k / n and the
    # Clopper-Pearson bounds recomputed from the rows (scipy's beta quantiles).
    out = os.path.join(d, "mc.h5")
    p = run(args, out, sets=["ensemble.method=design", "ensemble.subset=false", "ensemble.n_runs=20000",
                             "sweep.target_probability=3e-4", "sweep.from=0.0031", "sweep.to=0.0037"])
    s = read_sweep(out)
    check(p.returncode == exit_for(s), f"Monte Carlo inner: exit {exit_for(s)} ({p.stderr.strip()[-300:]})")
    with h5py.File(out, "r") as f:
        v, m = f["runs/sweep_value"][:], f["runs/motor_torque_margin_Nm"][:]
    for k, x in enumerate(s["values"]):
        rows = m[v == x]
        n, kf = rows.size, int(np.sum(rows <= 0))
        lo = beta_dist.ppf(0.025, kf, n - kf + 1) if kf > 0 else 0.0
        hi = beta_dist.ppf(0.975, kf + 1, n - kf) if kf < n else 1.0
        ub = beta_dist.ppf(0.95, kf + 1, n - kf)
        check(n == 20000 and s["p"][k] == kf / n and math.isclose(s["lower"][k], lo, rel_tol=1e-9)
              and math.isclose(s["upper"][k], hi, rel_tol=1e-9) and math.isclose(s["upper_bound"][k], ub, rel_tol=1e-9),
              f"Monte Carlo value {x}: p = {kf}/{n} and its Clopper-Pearson bounds from the rows")
        print(f"  Monte Carlo value {x}: {kf} failures, {n * norm.cdf(-x / SIGMA):.1f} expected")
    check_no_failure(args, d)


def check_no_failure(args, d):
    """Monte Carlo far on the safe side (8-10 sigma: no failure at any value, every bound the same):
    the estimates cannot tell where p falls, and nothing is read from them: the nominal sweep's
    declared safe side (above: extend below the smallest value) and a spread sweep's own (below:
    extend above the largest) decide."""
    for name, camp, sets, side, extend in (
            ("nominal", None, ["sweep.from=0.008", "sweep.to=0.010"], "above", "extend it below 0.008 Nm"),
            ("spread", os.path.join(d, "spread.toml"), ["sweep.values=[0.0005,0.0006]"], "below",
             "extend it above 0.0006 Nm")):
        out = os.path.join(d, f"no_failure_{name}.h5")
        p = run(args, out, campaign=camp, sets=sets + ["ensemble.method=design", "ensemble.subset=false",
                                                       "ensemble.n_runs=2000", "sweep.target_probability=1e-2"])
        s = read_sweep(out)
        check(p.returncode == 6 and s["allowable"]["verdict"] == "NOT ASSESSED",
              f"{name}, no failure: NOT ASSESSED, exit 6 ({p.stderr.strip()[-300:]})")
        a = s["allowable"]
        with h5py.File(out, "r") as f:
            v, m = f["runs/sweep_value"][:], f["runs/motor_torque_margin_Nm"][:]
            msg = f["sweep/allowable"].attrs["message"]
        check(np.all(s["p"] == 0) and a["status"] == "beyond_unsafe_end" and a["safe_side"] == side
              and extend in msg, f"{name}, no failure at any value: safe side {a['safe_side']} (declared or a "
              f"spread's), '{msg}'")



# The crude Monte Carlo reference of tests/mpi/sweep_motor_reference.toml: runs per value (chunks
# of CRUDE_CHUNK runs, each its own seed), about 100-500 failures each.
CRUDE_RUNS = (200_000, 600_000, 1_200_000)
CRUDE_CHUNK = 200_000
MOTOR_TARGETS = (1e-3, 3e-4)


def crude_monte_carlo(args, d, camp, x, n_runs, first_seed):
    """Failures and runs of plain Monte Carlo at stall torque x: the campaign without [sweep] and
    [failure], counted from the rows (margin <= 0), chunk by chunk."""
    failures = runs = 0
    for j in range(n_runs // CRUDE_CHUNK):
        out = os.path.join(d, "crude.h5")
        p = run(args, out, campaign=camp, cost=None, sets=["ensemble.method=design", "ensemble.subset=false",
                                                f"ensemble.n_runs={CRUDE_CHUNK}", f"drive.stall_torque_Nm={x!r}",
                                                f"ensemble.master_seed={first_seed + j}"])
        check(p.returncode == 0, f"crude Monte Carlo at {x}, chunk {j}: exit 0 ({p.stderr.strip()[-300:]})")
        with h5py.File(out, "r") as f:
            m = f["runs/motor_torque_margin_Nm"][:]
        os.remove(out)
        failures += int(np.sum(m <= 0))
        runs += m.size
    return failures, runs


def ln_crossing(x, p, target):
    """Where p (falling with x) equals the target, linear in ln p between the bracketing values."""
    for j in range(len(x) - 1):
        if p[j] > target >= p[j + 1]:
            t = (math.log(target) - math.log(p[j])) / (math.log(p[j + 1]) - math.log(p[j]))
            return x[j] + (x[j + 1] - x[j]) * t
    return float("nan")


def case_motor_reference(args):
    """A real simulator margin (tests/mpi/sweep_motor_reference.toml) against crude Monte Carlo at
    the sweep's 3 values: each value's subset interval holds the crude p as often as its confidence
    says (the binomial criterion of case_reference), and the allowable's interval holds the
    crossing of the crude p curve (interpolated in ln p) in at least 18 of 20 seeds, for a target in
    each of the two brackets."""
    d = fresh(args, "sweep_motor_reference")
    camp = os.path.join(args.repo, "tests", "mpi", "sweep_motor_reference.toml")
    plain = os.path.join(d, "plain.toml")
    text = open(camp).read().replace("../../campaigns/", os.path.join(args.repo, "campaigns") + "/")
    # The tables [sweep] and [failure] removed, each up to the next line that opens a table.
    open(plain, "w").write(re.sub(r"^\[(sweep|failure)\]\n(?:(?!\[).*\n)*", "", text, flags=re.M))
    x = [float(v) for v in re.search(r"^values = \[([^\]]*)\]", text, re.M).group(1).split(",")]
    crude = []
    for k, (xk, n) in enumerate(zip(x, CRUDE_RUNS)):
        kf, n = crude_monte_carlo(args, d, plain, xk, n, 1000 * (k + 1))
        lo, hi = beta_dist.ppf(0.025, kf, n - kf + 1), beta_dist.ppf(0.975, kf + 1, n - kf)
        crude.append(kf / n)
        print(f"  crude Monte Carlo at {xk * 1e3:.4g} mN m: {kf} failures in {n} runs, p = {kf / n:.4g} "
              f"(95 % Clopper-Pearson {lo:.4g} .. {hi:.4g})")
        check(kf >= 50, f"crude Monte Carlo at {xk}: {kf} >= 50 failures (the reference resolves p)")
    check(crude[0] > crude[1] > crude[2], "the crude p falls with the stall torque")
    crossings = {t: ln_crossing(x, crude, t) for t in MOTOR_TARGETS}
    for t, c in crossings.items():
        check(x[0] < c < x[-1], f"target {t:g}: the crude p curve crosses it at {c * 1e3:.5g} mN m, inside the sweep")
    covered = n_est = 0
    inside = {t: 0 for t in MOTOR_TARGETS}
    runs, statuses = [], []
    for seed in range(1, 21):
        for t in MOTOR_TARGETS:
            out = os.path.join(d, f"sweep_{seed}.h5")
            p = run(args, out, campaign=camp, cost=None,
                    sets=[f"ensemble.master_seed={seed}", f"sweep.target_probability={t!r}"])
            check(p.returncode == 0, f"seed {seed}, target {t:g}: exit 0 ({p.stderr.strip()[-300:]})")
            s = read_sweep(out)
            if seed == 1 and t == MOTOR_TARGETS[0]:
                # The chains' columns drift with the run index: their percentiles were read back
                # from the file, the per-bay ones in groups of columns; all equal numpy's.
                with h5py.File(out, "r") as f:
                    check_stats(f, streamed=False)
            os.remove(out)
            a = s["allowable"]
            # An interval end beyond the swept values is NaN: open on that side.
            lo, hi = (-math.inf if math.isnan(a["lower"]) else a["lower"]), (math.inf if math.isnan(a["upper"])
                                                                           else a["upper"])
            inside[t] += bool(a["status"] == "found" and a["safe_side"] == "above" and lo <= crossings[t] <= hi)
            statuses.append(a["status"])
            if t == MOTOR_TARGETS[0]:
                covered += int(np.sum((s["lower"] <= crude) & (crude <= s["upper"])))
                n_est += len(crude)
                runs.append(s["runs"])
    print(f"  subset runs per value, mean of 20 seeds: {np.mean(runs, axis=0)}; crude Monte Carlo: {CRUDE_RUNS}")
    print(f"  each value's 95 % interval holds the crude p in {covered}/{n_est}; allowables found in "
          f"{statuses.count('found')}/{len(statuses)}")
    need = math.floor(0.95 * n_est - 2.2 * math.sqrt(n_est * 0.95 * 0.05))  # 53 of 60
    check(covered >= need, f"each value's 95 % interval holds the crude p in {covered}/{n_est} (>= {need})")
    for t in MOTOR_TARGETS:
        print(f"  target {t:g}: the allowable's interval holds the crude crossing {crossings[t] * 1e3:.5g} mN m in "
              f"{inside[t]}/20 seeds")
        check(inside[t] >= 18, f"target {t:g}: the allowable's interval holds the crude crossing in {inside[t]} >= 18 "
              "of 20 seeds")


# Sequential stopping as the inner method, on real runs: the free stack of 4 bays (velocity drive,
# contacts off) whose pins miss the rail (status `rail miss`, rail_margin_m <= 0) more often as the
# diagonals' free length shortens; the standalone stop campaign counts the runs that are not ok,
# which here are exactly the misses (checked on the rows).
STOP_CAMPAIGN = """
[campaign]
name = "sweep-stop"
[ensemble]
method = "design"
sampling = "monte_carlo"
n_runs = 100
master_seed = 3
max_run_wall_time_s = 30.0
[ensemble.stop]
target = "probability_relative_half_width"
width = 0.3
confidence = 0.9
max_runs = 20000
[failure]
margin = "rail_margin_m"
[sweep]
key = "mast.diagonal_free_length_m"
values = [0.474, 0.477, 0.480]
target_probability = 0.1
safe_side = "above"
[scene]
file = "{scene}"
overrides = {{ "run.output_step_s" = 0.0, "stack.contacts" = false, "mast.n_bays" = 4 }}
[[dispersion]]
key = "mast.diagonal_free_length_m"
apply = "offset"
distribution = "normal"
std = 0.005
[[dispersion]]
key = "mast.diagonal_stiffness_N_per_m"
apply = "relative"
distribution = "normal"
std = 0.05
[[dispersion]]
key = "rail.x_m"
apply = "offset"
distribution = "normal"
std = 0.0005
"""


def clopper_pearson(k, n, conf):
    """Two-sided exact interval at conf and the one-sided upper bound at conf (scipy's beta)."""
    a = 1.0 - conf
    lo = beta_dist.ppf(a / 2, k, n - k + 1) if k > 0 else 0.0
    hi = beta_dist.ppf(1 - a / 2, k + 1, n - k) if k < n else 1.0
    ub = beta_dist.ppf(conf, k + 1, n - k) if k < n else 1.0
    return lo, hi, ub


def case_stop(args):
    """[ensemble.stop] with a probability target as the inner method: each value's rounds recomputed
    from its rows (failures, the Clopper-Pearson interval at the rule's confidence, met or more),
    its estimate and bounds in /sweep Clopper-Pearson at the sweep's confidence, the allowable the
    crossing of those bounds; values 0 and 2 against the standalone stop campaign at that value (the
    file without [sweep] and [failure], its seed): the same points, rounds, estimate and interval."""
    d = fresh(args, "sweep_stop")
    camp = os.path.join(d, "stop.toml")
    text = STOP_CAMPAIGN.format(scene=os.path.join(args.repo, "campaigns", "scenes", "paper_free.toml"))
    open(camp, "w").write(text)
    open(os.path.join(d, "plain.toml"), "w").write(re.sub(r"^\[(sweep|failure)\]\n(?:(?!\[).*\n)*", "", text,
                                                          flags=re.M))
    out = os.path.join(d, "sweep.h5")
    p = run(args, out, campaign=camp, cost=None)
    check(p.returncode == 0, f"stop sweep: exit 0 ({p.stderr.strip()[-300:]})")
    s = read_sweep(out)
    width, rule_conf, conf = 0.3, 0.9, 0.95
    with h5py.File(out, "r") as f:
        order = np.argsort(f["runs/run_index"][:])
        v, m = f["runs/sweep_value"][:][order], f["runs/rail_margin_m"][:][order]
        status, inputs = f["runs/status"][:][order], f["runs/inputs/mast.diagonal_free_length_m"][:][order]
        # Each value's method writes its own results under /sweep/inner/<k>: its /stop.
        inner = {k: {n: f[f"sweep/inner/{k}/stop/{n}"][()] for n in f[f"sweep/inner/{k}/stop"]}
                 for k in f["sweep/inner"]}
        check(f["sweep"].attrs["inner_method"] == "stop", "/sweep's inner method is stop")
    for k, x in enumerate(s["values"]):
        rows, g = m[v == x], inner[str(k)]
        check(np.array_equal(rows <= 0, status[v == x] != 0),
              f"value {k}: a run fails its margin exactly when its status is not ok ({int(np.sum(rows <= 0))} misses)")
        states = [t.decode() if isinstance(t, bytes) else t for t in g["state"]]
        for r, n in enumerate(g["runs"]):
            kf = int(np.sum(rows[:n] <= 0))
            lo, hi, _ = clopper_pearson(kf, n, rule_conf)
            met = kf > 0 and (hi - lo) / 2 / (kf / n) <= width
            check(g["estimate"][r] == kf / n and math.isclose(g["lower"][r], lo, rel_tol=1e-9, abs_tol=1e-300)
                  and math.isclose(g["upper"][r], hi, rel_tol=1e-9) and states[r] == ("met" if met else "more"),
                  f"value {k}, round {r}: {kf} failures in {n} runs, {rule_conf:g} interval [{lo:.4g}, {hi:.4g}], "
                  f"{states[r]}")
        check(states[-1] == "met" and g["runs"][-1] == rows.size == s["runs"][k],
              f"value {k}: met after {rows.size} runs")
        kf, n = int(np.sum(rows <= 0)), rows.size
        lo, hi, ub = clopper_pearson(kf, n, conf)
        check(s["p"][k] == kf / n and math.isclose(s["lower"][k], lo, rel_tol=1e-9)
              and math.isclose(s["upper"][k], hi, rel_tol=1e-9) and math.isclose(s["upper_bound"][k], ub, rel_tol=1e-9),
              f"value {k}: p = {kf}/{n}, 95 % Clopper-Pearson [{lo:.4g}, {hi:.4g}], upper bound {ub:.4g}")
    a = s["allowable"]
    for name, col in (("value", "upper_bound"), ("estimate", "p"), ("upper", "upper"), ("lower", "lower")):
        ref = crossing(s["values"], s[col], 0.1)
        check(a["status"] == "found" and math.isclose(a[name], ref, rel_tol=1e-12),
              f"allowable {name} {a[name]:.9g}: the crossing of {col} recomputed ({ref:.9g})")
    for k in (0, 2):
        x, seed = s["values"][k], int(s["master_seed"][k])
        alone = os.path.join(d, f"alone_{k}.h5")
        p = run(args, alone, campaign=os.path.join(d, "plain.toml"), cost=None,
                sets=[f"mast.diagonal_free_length_m={x!r}", f"ensemble.master_seed={seed}"])
        check(p.returncode == 0, f"value {k}: the standalone stop campaign: exit 0 ({p.stderr.strip()[-300:]})")
        g = inner[str(k)]
        with h5py.File(alone, "r") as f:
            st = f["stop"]
            a_in = f["runs/inputs/mast.diagonal_free_length_m"][:][np.argsort(f["runs/run_index"][:])]
            check(a_in.tobytes() == inputs[v == x].tobytes(),
                  f"value {k}: its {a_in.size} points in run order are the standalone campaign's")
            check(all(st[n][:].tobytes() == g[n].tobytes() for n in ("runs", "used", "estimate", "lower", "upper",
                                                                     "achieved_width"))
                  and st["estimate"][-1] == s["p"][k],
                  f"value {k}: rounds {list(g['runs'])}, estimates and intervals as the standalone /stop")

def listed_crossing(s, col, target):
    """The crossing of column col over the listed values only (refinement == 0), p falling with x."""
    listed = s["refinement"] == 0
    return crossing(s["values"][listed], s[col][listed], target)


def case_refine(args):
    d = fresh(args, "sweep_refine")
    m = 4
    plain, fine = os.path.join(d, "plain.h5"), os.path.join(d, "fine.h5")
    for out, sets in ((plain, []), (fine, [f"sweep.refine={m}"])):
        p = run(args, out, sets=sets)
        check(p.returncode == 0, f"refine {sets}: exit 0 ({p.stderr.strip()[-300:]})")
    a, b = read_sweep(plain), read_sweep(fine)
    listed = b["refinement"] == 0
    check(all(a[k].tobytes() == b[k][listed].tobytes() for k in ("values", "p", "cov", "upper_bound", "lower", "upper",
                                                                 "runs", "master_seed", "index")),
          "the listed values' columns are the sweep's without refinement, byte for byte")
    # The bracket that holds the listed values' allowable (the crossing of their upper bounds).
    x_listed = b["values"][listed]
    first = listed_crossing(b, "upper_bound", 1e-6)
    i = max(j for j in range(len(x_listed) - 1) if x_listed[j] <= first)
    lo, hi = x_listed[i], x_listed[i + 1]
    want = [lo + (j + 1) * (hi - lo) / (m + 1) for j in range(m)]
    placed = b["values"][~listed]
    check(len(placed) == m and np.allclose(placed, want, rtol=0, atol=1e-15 * hi)
          and b["refine_low"] == lo and b["refine_high"] == hi and np.all(np.diff(b["values"]) > 0),
          f"the placed values {list(placed)} lie evenly inside ({lo}, {hi}), the bracket of the listed "
          f"allowable {first:.6g}; the rows ascend in value")
    n = len(x_listed)
    check(list(b["index"][~listed]) == [n + i * m + j for j in range(m)],
          f"the placed values' indices {list(b['index'][~listed])}: n + i m + j")
    al = b["allowable"]
    for name, col in (("value", "upper_bound"), ("estimate", "p"), ("upper", "upper"), ("lower", "lower")):
        ref = crossing(b["values"], b[col], 1e-6)
        check((math.isnan(ref) and math.isnan(al[name])) or math.isclose(al[name], ref, rel_tol=1e-12),
              f"allowable {name} {al[name]:.9g}: the crossing of {col} over all values ({ref:.9g})")
    # A coarse sweep, 3 and 6 mN m alone: ln p = ln Phi(-x / sigma) is concave, so its chord lies
    # below it and the listed values' allowable comes out on the unsafe side of the true crossing
    # in some seeds (their bounds hold, the interpolation between them does not). The refinement's
    # 4 values put it back on the safe side, and its interval holds the truth.
    truth = SIGMA * Z_TARGET
    inside = safe = safe_listed = 0
    for seed in range(1, 21):
        out = os.path.join(d, f"seed{seed}.h5")
        p = run(args, out, sets=[f"ensemble.master_seed={seed}", f"sweep.refine={m}", "sweep.from=0.003",
                                 "sweep.to=0.006", "sweep.count=2"])
        check(p.returncode == 0, f"seed {seed}: exit 0 ({p.stderr.strip()[-300:]})")
        s = read_sweep(out)
        a = s["allowable"]
        check(a["status"] == "found" and s["refinement"].sum() == m, f"seed {seed}: found, {m} values placed")
        inside += (math.isnan(a["lower"]) or a["lower"] <= truth) and (math.isnan(a["upper"]) or truth <= a["upper"])
        safe += a["value"] >= truth
        safe_listed += listed_crossing(s, "upper_bound", 1e-6) >= truth
        os.remove(out)
    print(f"  coarse sweep, refine = {m}: the allowable on the safe side of the true crossing in {safe}/20 (from the "
          f"listed values alone: {safe_listed}/20); its interval holds the true crossing in {inside}/20")
    check(safe >= 18, f"refined: the allowable lies on the safe side of the true crossing in {safe} >= 18 of 20")
    check(inside >= 18, f"refined: the allowable's interval contains the true crossing in {inside} >= 18 of 20")
    # A target the listed values cannot reach: nothing placed, and the file says why.
    out = os.path.join(d, "unreached.h5")
    p = run(args, out, sets=[f"sweep.refine={m}", "sweep.target_probability=1e-30"])
    s = read_sweep(out)
    check(p.returncode == 6 and s["refinement"].sum() == 0 and len(s["values"]) == 4
          and s["refine_message"].startswith("not refined: the listed values give no allowable (beyond_safe_end")
          and math.isnan(s["refine_low"]),
          f"target 1e-30: nothing refined ({s['refine_message'][:120]})")


def case_ranks(args):
    d = fresh(args, "sweep_ranks")
    outs = {}
    for ranks in (1, 3):
        outs[ranks] = os.path.join(d, f"r{ranks}.h5")
        p = run(args, outs[ranks], ranks=ranks, sets=["sweep.refine=2"])
        check(p.returncode == 0, f"{ranks} ranks: exit 0 ({p.stderr.strip()[-300:]})")
    same, why = same_values(datasets(outs[1]), datasets(outs[3]))
    check(same, f"1 and 3 ranks: the same datasets ({why})")
    with h5py.File(outs[3], "r") as f:
        check(f.attrs["n_rounds"] > 10 and "sweep" in f and f["sweep/refinement"][:].sum() == 2,
              f"{f.attrs['n_rounds']} rounds, /sweep written, 2 values placed by the refinement")
    check_allowable_and_report(args, outs[3], d)
    # Motor runs (the simulator): the chains' outputs drift, so some /stats columns are read back.
    motor = os.path.join(args.repo, "campaigns", "motor_sizing.toml")
    sets = ["ensemble.method=subset", "ensemble.importance=false", "sweep.from=0.03", "sweep.to=0.034",
            "sweep.count=2", "sweep.refine=0", "ensemble.subset.max_levels=3", "ensemble.subset.n_per_level=500"]
    for ranks in (1, 3):
        outs[ranks] = os.path.join(d, f"motor_r{ranks}.h5")
        p = run(args, outs[ranks], ranks=ranks, sets=sets, campaign=motor, cost=None)
        check(p.returncode in (0, 3, 6), f"motor runs, {ranks} ranks: the file written ({p.stderr.strip()[-200:]})")
    same, why = same_values(datasets(outs[1]), datasets(outs[3]))
    check(same, f"motor runs: 1 and 3 ranks, the same datasets ({why})")
    with h5py.File(outs[3], "r") as f:
        rb, by = int(f["timing"].attrs["stats_columns_read_back"]), int(f["timing"].attrs["stats_read_back_ranks"])
        check(rb >= 3 and by == 3, f"motor runs, 3 ranks: {rb} columns read back at the end, by {by} ranks")
        check_stats(f, streamed=False)


def crossing(x, y, target):
    """The crossing of y with the target from the largest x down (p falls with x here), linear in ln y."""
    for j in range(len(x) - 1, 0, -1):
        if y[j] <= target < y[j - 1]:
            t = (math.log(target) - math.log(y[j])) / (math.log(y[j - 1]) - math.log(y[j]))
            return x[j] + (x[j - 1] - x[j]) * t
    return float("nan")


def check_allowable_and_report(args, path, d):
    """The allowable recomputed from /sweep's columns; the report and the DataFrame show it."""
    s = read_sweep(path)
    a = s["allowable"]
    x = s["values"]
    for name, col in (("value", "upper_bound"), ("estimate", "p"), ("upper", "upper"), ("lower", "lower")):
        ref = crossing(x, s[col], 1e-6)
        check(math.isclose(a[name], ref, rel_tol=1e-12), f"allowable {name} {a[name]:.9g}: the crossing of {col} "
              f"recomputed ({ref:.9g})")
    check(a["safe_side"] == "above" and a["verdict"] == "PASS", "safe side above; the own 20 mN m passes")
    out = os.path.join(d, "report")
    p = subprocess.run(["/usr/bin/python3", os.path.join(args.repo, "postproc", "report.py"), path, "-o", out],
                       capture_output=True, text=True, timeout=300)
    check(p.returncode == 0, f"report: exit 0 ({p.stderr.strip()[-300:]})")
    html = open(os.path.join(out, "report.html"), encoding="utf-8").read()
    m = re.search(r'data-key="sweep.allowable" data-value="([^"]+)"', html)
    check(m and float(m.group(1)) == a["value"], "the report's allowable is /sweep/allowable/value")
    # The allowable as the report's number rule shows it: its digits, rounded, in mN m.
    m = re.search(r"drive\.stall_torque_Nm ≥ ([0-9.]+) mN m \(95 % upper bound", p.stdout)
    shown = m.group(1) if m else ""
    decimals = len(shown.split(".")[1]) if "." in shown else 0
    check("VERDICT: PASS" in p.stdout and m is not None
          and abs(float(shown) - a["value"] * 1e3) <= 0.5 * 10.0 ** -decimals * (1 + 1e-9),
          f"the verdict says PASS and 'drive.stall_torque_Nm ≥ {shown} mN m' ({a['value'] * 1e3:.9g} mN m rounded)")
    check(os.path.exists(os.path.join(out, "sweep.png")), "the sweep figure is drawn")
    # The values the refinement placed: marked in the table, the bracket said in a sentence.
    placed = int(s["refinement"].sum())
    check(html.count("<td>refinement</td>") == placed and html.count("<td>listed</td>") == len(x) - placed
          and (placed == 0 or f"Refinement (<code>sweep.refine = {int(s['refine'])}</code>)" in html),
          f"the report marks the {placed} placed values and says what the refinement did")
    sys.path.insert(0, os.path.join(args.repo, "postproc"))
    import truss_report
    df = truss_report.read_campaign(path)
    sw = df.attrs["sweep"]
    check(list(sw["value"]) == list(x) and list(sw["p"]) == list(s["p"]) and sw.attrs["allowable"]["value"] == a["value"]
          and list(sw["refinement"]) == list(s["refinement"] == 1) and list(sw["index"]) == list(s["index"])
          and sw.attrs["units"]["value"] == "Nm" and (df["sweep_value"].value_counts().sort_index().to_numpy()
                                                      == s["runs"]).all(),
          "read_campaign: the sweep's table in df.attrs['sweep'], the runs' sweep_value column")
    check_other_verdicts(args, d)


def exit_for(s):
    """truss-campaign's exit status for a sweep of this /sweep: 6 when its verdict is NOT ASSESSED."""
    return 6 if s["allowable"]["verdict"] == "NOT ASSESSED" else 0


def check_other_verdicts(args, d):
    """The report's other verdicts and exit codes: FAIL (3; the campaign 0) with the scene's own stall
    torque below the allowable (about 4.9 mN m), NOT ASSESSED (4; the campaign 6) when no value's
    bound reaches the target; no
    NaN shown on either page."""
    for name, sets, verdict, code, campaign_code in (
            ("fail", ["drive.stall_torque_Nm=0.003"], "FAIL", 3, 0),
            ("not_assessed", ["sweep.target_probability=1e-30"], "NOT ASSESSED", 4, 6)):
        path = os.path.join(d, f"{name}.h5")
        p = run(args, path, sets=sets)
        check(p.returncode == campaign_code,
              f"{name}: the campaign exits {campaign_code} ({p.stderr.strip()[-300:]})")
        check(read_sweep(path)["allowable"]["verdict"] == verdict, f"{name}: /sweep/allowable verdict {verdict}")
        out = os.path.join(d, f"report_{name}")
        p = subprocess.run(["/usr/bin/python3", os.path.join(args.repo, "postproc", "report.py"), path, "-o", out,
                            "--no-pdf"], capture_output=True, text=True, timeout=300)
        text = re.sub(r"<[^>]+>", " ", open(os.path.join(out, "report.html"), encoding="utf-8").read())
        check(p.returncode == code and f"VERDICT: {verdict}" in p.stdout and not re.search(r"\bnan\b", text, re.I)
              and "nan" not in p.stdout.lower(),
              f"{name}: report exit {p.returncode} (want {code}), 'VERDICT: {verdict}', no NaN on the page")


def refinement_runs(ref):
    """The run indices of the refinement's values in an uninterrupted file (the same plans, so the
    same indices, in any session): the runs whose design value /sweep flags as placed by it."""
    with h5py.File(ref, "r") as f:
        placed = f["sweep/values"][()][f["sweep/refinement"][()].astype(bool)]
        return set(int(r) for r in np.flatnonzero(np.isin(f["runs/sweep_value"][()], placed)))


def kill_mid(args, out, sets, refining_runs):
    """Kill -9 of the whole job once a run of the refinement (`refining_runs`) has its record."""
    cmd = ["mpirun", "--oversubscribe", "-np", "2", args.driver, campaign_path(args), "-o", out,
           "--synthetic-run-cost-s", "0.001", "--progress", "none", "--flush-interval", "0.02"]
    for x in sets:
        cmd += ["--set", x]
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0, plans, refining = time.time(), 0, False
    while time.time() - t0 < 300 and proc.poll() is None:
        frames = all_journal_frames(out)  # rank 0's journal (the plans) and the parts (the records)
        plans = sum(1 for _, k, _ in frames if k == b"P")
        refining = any(k == b"R" and int.from_bytes(pl[0:8], "little") in refining_runs for _, k, pl in frames)
        if refining:
            break
        time.sleep(0.005)
    kill_job(proc)
    return plans, refining


def case_resume(args):
    d = fresh(args, "sweep_resume")
    ref = os.path.join(d, "ref.h5")
    sets = ["sweep.refine=3"]
    p = run(args, ref, cost="0.001", sets=sets)
    check(p.returncode == 0, f"uninterrupted: exit 0 ({p.stderr.strip()[-300:]})")
    out = os.path.join(d, "killed.h5")
    runs = refinement_runs(ref)
    check(len(runs) > 0, f"the uninterrupted sweep refines ({len(runs)} runs of placed values)")
    plans, refining = kill_mid(args, out, sets, runs)
    check(refining and not os.path.exists(out) and os.path.exists(out + ".journal"),
          f"kill -9 after {plans} rounds planned, in the refinement: no results file, the journal kept")
    p = run(args, out, cost="0.001", sets=sets, extra=["--resume"])
    check(p.returncode == 0 and "resuming" in p.stderr, f"--resume: exit 0 ({p.stderr.strip()[-300:]})")
    same, why = same_values(datasets(ref), datasets(out))
    check(same, f"killed and resumed: the same datasets as uninterrupted ({why})")


def datasets_of(group):
    """Every dataset's bytes and every attribute under an HDF5 group, by path (the failure samples'
    run indices left out: rows of the file they are in)."""
    out = {f"@{a}": v.tobytes() if isinstance(v, np.ndarray) else v for a, v in group.attrs.items()}

    def visit(name, obj):
        if name.endswith("failure_samples/run_index"):
            return
        if isinstance(obj, h5py.Dataset):
            out[name] = obj[()].tobytes() if obj.dtype.kind != "O" else list(obj[()])
        for a, v in obj.attrs.items():
            out[f"{name}@{a}"] = v.tobytes() if isinstance(v, np.ndarray) else v
    group.visititems(visit)
    return out


def case_standalone(args):
    d = fresh(args, "sweep_standalone")
    camp = campaign_path(args)
    text = open(camp).read()
    # The campaign without [sweep]: its method estimates the same [failure] event's probability alone.
    for inner in ("subset", "monte_carlo"):
        open(os.path.join(d, f"plain_{inner}.toml"), "w").write(re.sub(r"^\[sweep\][^\[]*", "", text, flags=re.M))
    # Monte Carlo with a target 3,000 runs can bound (1.5e-3; p = 1e-3 .. 3e-6 over the values), so that
    # its allowable is found and refined.
    mc_sweep = ["sweep.from=0.0031", "sweep.to=0.0045", "sweep.target_probability=1.5e-3"]
    for inner, sets, sweep_sets in (("subset", [], []),
                                    ("monte_carlo", ["ensemble.method=design", "ensemble.subset=false",
                                                     "ensemble.n_runs=3000"], mc_sweep)):
        plain = os.path.join(d, f"plain_{inner}.toml")
        sweep = os.path.join(d, f"sweep_{inner}.h5")
        p = run(args, sweep, sets=sets + sweep_sets + ["sweep.refine=2"])
        check(p.returncode == 0, f"{inner}: the sweep: exit 0 ({p.stderr.strip()[-300:]})")
        s = read_sweep(sweep)
        placed = [int(r) for r in np.flatnonzero(s["refinement"])]
        check(len(placed) == 2, f"{inner}: 2 values placed by the refinement")
        with h5py.File(sweep, "r") as f:
            v, m, runs = f["runs/sweep_value"][:], f["runs/inputs/drive.stall_torque_Nm"][:], f["runs/run_index"][:]
            # Each value's method's own results (/sweep/inner/<k>/subset, /sweep/inner/<k>/failure): every
            # dataset but the failure samples' run indices, which are rows of the sweep's /runs.
            group = "subset" if inner == "subset" else "failure"
            inner_groups = {k: datasets_of(f[f"sweep/inner/{k}/{group}"]) for k in f["sweep/inner"]
                            if list(f[f"sweep/inner/{k}"]) == [group]}
        # The first and the last listed value and a placed one: each the campaign alone at its value and seed.
        listed = [int(r) for r in np.flatnonzero(s["refinement"] == 0)]
        for k in (listed[0], listed[-1], placed[0]):
            x, seed = float(s["values"][k]), int(s["master_seed"][k])
            alone = os.path.join(d, f"alone_{inner}_{k}.h5")
            p = run(args, alone, campaign=plain,
                    sets=sets + [f"drive.stall_torque_Nm={x!r}", f"ensemble.master_seed={seed}"])
            check(p.returncode == 0, f"{inner}, value {k}: the standalone campaign: exit 0 ({p.stderr.strip()[-300:]})")
            with h5py.File(alone, "r") as f:
                # The points: the applied stall torque (the synthetic margin) of every run.
                rows = f["runs/inputs/drive.stall_torque_Nm"][:]
                mine = m[np.argsort(runs)][v[np.argsort(runs)] == x]
                check(mine.tobytes() == rows.tobytes(),
                      f"{inner}, value {k}: its {mine.size} points in run order are the standalone campaign's {rows.size}")
                alone_groups = datasets_of(f[group])
                got = inner_groups[str(s["index"][k])]
                check(sorted(alone_groups) == sorted(got) and all(alone_groups[n] == got[n] for n in got)
                      and np.frombuffer(got["p"])[0] == s["p"][k],
                      f"{inner}, value {k}: p = {s['p'][k]:.6g}; /sweep/inner/{s['index'][k]} holds the standalone "
                      f"campaign's /{group}, {len(got)} datasets and attributes alike")
                if inner == "monte_carlo":
                    kf = int(np.sum(rows <= 0))
                    check(s["p"][k] == kf / rows.size, f"monte_carlo, value {k}: p = {kf}/{rows.size} as alone")


BAD = {
    # name: (what to change in the analytic campaign, line of the message, words)
    "not_a_key": (("key = \"drive.stall_torque_Nm\"\nfrom", "key = \"drive.stall_torqe_Nm\"\nfrom"), 23,
                  "sweep.key: \"drive.stall_torqe_Nm\" is not a real-valued scene key"),
    "not_dispersed": (("key = \"drive.stall_torque_Nm\"\nfrom", "spread = \"mast.strut_mass_kg\"\nfrom"), 23,
                      "sweep.spread: \"mast.strut_mass_kg\" is not the key of a [[dispersion]]"),
    "out_of_range": (("from = 0.004", "from = -0.004"), 22, "sweep.values: drive.stall_torque_Nm"),
    "one_value": (("from = 0.004\nto = 0.0055\ncount = 4", "values = [0.005]"), 24,
                  "sweep.values: a sweep needs at least 2 values, got 1"),
    "target_outside": (("target_probability = 1e-6", "target_probability = 1.5"), 27,
                       "sweep.target_probability: must lie in (0, 1), got 1.5"),
    "no_safe_side": (("safe_side = \"above\"\n", ""), 23,
                     "sweep.safe_side: a sweep of drive.stall_torque_Nm's nominal value must say on which side"),
    "refine_too_many": (("target_probability = 1e-6", "target_probability = 1e-6\nrefine = 30"), 28,
                        "sweep.refine: must lie in [0, 20], got 30"),
    "no_probability": (("method = \"subset\"\n\n[ensemble.subset]\nn_per_level = 500\np0 = 0.1\nmax_levels = 10\n",
                        "method = \"design\"\nn_runs = 100\nsampling = \"latin_hypercube\"\n"),
                       14, "ensemble.sampling: \"latin_hypercube\" gives no binomial interval of a probability"),
}


def case_bad_input(args):
    d = fresh(args, "sweep_bad")
    text = open(campaign_path(args)).read()
    for name, ((old, new), line, words) in BAD.items():
        check(old in text, f"{name}: the campaign has '{old}'")
        camp = os.path.join(d, f"{name}.toml")
        open(camp, "w").write(text.replace(old, new))
        out = os.path.join(d, f"{name}.h5")
        p = run(args, out, ranks=2, campaign=camp)
        msg = p.stderr.strip()
        check(p.returncode == 2 and f"{camp}:{line}:" in msg and words in msg and msg.count("error:") == 1
              and not os.path.exists(out) and not os.path.exists(out + ".journal"),
              f"{name}: exit 2, '{msg.splitlines()[0][:200] if msg else ''}', nothing written")
    p = run(args, os.path.join(d, "x.h5"), sets=["ensemble.stop.target=\"percentile_bound\"",
                                                 "ensemble.method=design", "ensemble.subset=false",
                                                 "ensemble.n_runs=100",
                                                 "ensemble.stop.output=\"peak_drive_force_N\""])
    check(p.returncode == 2 and "ensemble.stop.target" in p.stderr and "not a probability" in p.stderr,
          f"a percentile stop rule as the inner method: exit 2 ({p.stderr.strip()[:200]})")
    # A failure margin the campaign's drive never computes (motor_torque_margin_Nm under a motor
    # drive: NaN in every run, so no value would ever fail): refused by --dry-run, at its line.
    camp = os.path.join(d, "nan_margin.toml")
    open(camp, "w").write(text.replace("[sweep]", "[scene.drive]\nmode = \"motor\"\n\n[sweep]"))
    p = subprocess.run(["mpirun", "--oversubscribe", "-np", "1", args.driver, camp, "--dry-run"], env=ENV,
                       capture_output=True, text=True, timeout=600)
    check(p.returncode == 2 and f"{camp}:20: failure.margin: \"motor_torque_margin_Nm\" is defined only with "
          "drive.mode = \"velocity\"" in p.stderr and p.stdout == "",
          f"a margin the motor drive never computes: --dry-run exits 2 ({p.stderr.strip()[:200]})")
    written = [f for f in os.listdir(d) if not f.endswith(".toml")]
    check(written == [], f"nothing written by any refused run ({written})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", required=True,
                    choices=["reference", "motor_reference", "stop", "refine", "ranks", "resume", "standalone",
                             "bad_input"])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--scratch", required=True)
    args = ap.parse_args()
    globals()["case_" + args.case](args)
    print("all checks passed")


if __name__ == "__main__":
    main()
