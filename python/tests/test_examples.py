"""The examples (examples/*.py), run as a user runs them, each checked against values computed
here without the library the example leans on (OpenTURNS, scipy.optimize, pandas/matplotlib)."""
import json
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

import truss_deploy as td
from conftest import cli_json


def run_example(repo, name, *args):
    p = subprocess.run([sys.executable, str(repo / "examples" / name), *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_openturns_form(repo, scratch):
    out = scratch / "form.json"
    run_example(repo, "openturns_form.py", "--mc-runs", 10000, "--json", out)
    r = json.loads(out.read_text())
    mean = np.array([20.0, 0.45, 0.18])
    std = np.array([1.0, 0.002, 0.0005])
    x, u = np.array(r["design_point_physical"]), np.array(r["design_point_standard"])
    base = td.Scene.table1().with_(**{"mast.n_bays": 10})

    def force(v):
        return td.simulate(base.with_(**dict(zip(r["inputs"], map(float, v))))).peak_drive_force_N

    # The design point lies on the limit state (AbdoRackwitz stops at a constraint error ~1e-5 N) ...
    assert abs(force(x) - r["threshold_N"]) < 1e-4
    # ... its standard coordinates are (x - mean) / std (independent normal inputs), beta is their
    # norm and the FORM probability is Phi(-beta) ...
    np.testing.assert_allclose(u, (x - mean) / std, rtol=1e-9, atol=1e-9)
    assert math.isclose(r["beta"], float(np.linalg.norm(u)), rel_tol=1e-9)
    assert math.isclose(r["pf_form"], norm.sf(r["beta"]), rel_tol=1e-9)
    # ... and it is the most probable point of the failure domain: the force's gradient in standard
    # space, by central differences of 1e-3 standard deviations, points along u (cos > 0.999).
    grad = np.array([(force(x + h) - force(x - h)) / 2e-3 for h in np.diag(1e-3 * std)])
    assert grad @ u / (np.linalg.norm(grad) * np.linalg.norm(u)) > 0.999
    # Monte Carlo agrees with FORM within 3 of its standard errors plus FORM's own error, which the
    # curvature correction (SORM) estimates.
    assert r["mc_runs"] == 10000 and 0.005 < r["pf_mc"] < 0.05
    assert abs(r["pf_mc"] - r["pf_form"]) < 3 * r["pf_mc_std"] + abs(r["pf_sorm_breitung"] - r["pf_form"])


def test_calibrate(repo, scratch):
    out = scratch / "calibrate.json"
    run_example(repo, "calibrate.py", "--json", out)
    r = json.loads(out.read_text())
    k_true, k_fit, sigma_k = r["true_stiffness_N_per_m"], r["fitted_stiffness_N_per_m"], r["sigma_stiffness_N_per_m"]
    assert r["success"] and abs(k_fit - k_true) < 3 * sigma_k < 0.05 * k_true  # recovered, and informative
    # sigma_K = sigma_t / |d t / d K|, the sensitivities by central differences here (0.1 N/m).
    base = td.Scene.table1().with_(**{"drive.mode": "motor", "mast.n_bays": 10})
    lock = [td.simulate(base.with_(**{"mast.diagonal_stiffness_N_per_m": k_fit + d})).bays.lock_time_s.to_numpy()
            for d in (-0.05, 0.05)]
    dt_dk = (lock[1] - lock[0]) / 0.1
    assert math.isclose(sigma_k, r["sigma_t_s"] / np.linalg.norm(dt_dk), rel_tol=0.01)
    assert r["chi2"] < 3 * r["n_lock_times"]  # the noise it was given, not a misfit


def test_sweep(repo, scratch, truss_sim):
    out = scratch / "sweep"
    run_example(repo, "sweep.py", "--out-dir", out)
    png = (out / "sweep.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000
    df = pd.read_csv(out / "sweep.csv", index_col="run")
    assert len(df) == 30 and set(df.status) == {"ok", "stall"}
    # Two rows, one stalled and one deployed, against truss-sim (to the 17 digits CSV keeps).
    scene = str(repo / "campaigns" / "scenes" / "table1.toml")
    for i in (0, 29):
        torque = df["input:drive.stall_torque_Nm"].iloc[i]
        ref = cli_json(truss_sim, scene, "drive.mode=motor", f"drive.stall_torque_Nm={float(torque)!r}",
                       "run.output_step_s=0")
        assert df.status.iloc[i] == ref["status"] and df.bays_completed.iloc[i] == ref["bays_completed"]
        for k in ("deploy_time_s", "end_time_s", "peak_latch_energy_J"):
            want = math.nan if ref[k] is None else ref[k]
            assert df[k].iloc[i] == pytest.approx(want, rel=1e-15, nan_ok=True), k
