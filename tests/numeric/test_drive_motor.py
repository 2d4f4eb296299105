#!/usr/bin/python3
"""A motor drive through a lossy drive train (docs/model-notes.md "Drive train"): the deployment
slows as the lead screw's efficiency falls, and truss-sim's time to the first rail entry agrees with
an independent integration of the model's equations (scipy's DOP853, written here from
docs/model.md §3, not from the code).

One bay of Table 1 over its held lower frame (y_0 = 0), from rest. Until the pin meets the rail the
opening D = y_1 is the only coordinate; the Lagrangian of model.md §3 (T = G(D) D'^2 +
(15/16) m_s D'^2 + (1/2) (m_f + m_tip) D'^2, U = 3 K (L - l_0)^2 while taut) gives
    M(D) D'' = -G'(D) D'^2 - dU/dD + F,    M = 2 G + 15/8 m_s + m_f + m_tip,
and the motor, of stall torque T_s derated by k_d and no-load speed w_0 at its shaft, drives the
screws through a gear of ratio N: its torque k_d T_s (1 - N 2 pi D' / (h w_0)) less the losses T_L
gives F = 2 pi N eta_g eta_s (T - T_L) / h (T > T_L; else the load drives: / (eta_g eta_s')).
The pin meets the rail when the hinge (sqrt(l^2 - D^2/4), D/2) reaches the rail line
y - y_l + cot(beta) (x - x_l) = 0.

Exit 0 when every check holds; each failure is printed."""
import argparse
import json
import math
import subprocess
import sys

from scipy.integrate import solve_ivp

# Table 1 (docs/model.md §4) and the project defaults h, J_c, m_tip.
L_S, M_S, B_F, M_F, K, L_0 = 0.18, 0.1, 0.36, 0.5, 20.0, 0.45
X_L, Y_L, BETA = 0.08, 0.15, math.radians(20.85)
H = 0.01
J_C = M_S * L_S**2 / 12.0
M_TIP = 6.0 * M_S + M_F
# The drive train of the test (N m at the motor shaft).
TRAIN = dict(gear_ratio=4.0, gear_efficiency=0.9, screw_back_efficiency=0.3, friction_torque_Nm=3e-4,
             detent_torque_Nm=1e-4, harness_torque_Nm=1e-4, hysteresis_torque_Nm=0.5e-4, motor_derating=0.85,
             stall_torque_Nm=0.01, no_load_speed_rad_per_s=600.0)
EFFICIENCIES = [1.0, 0.6, 0.35]


def motor_force(u, eta_s):
    t = TRAIN
    losses = t["friction_torque_Nm"] + t["detent_torque_Nm"] + t["harness_torque_Nm"] + t["hysteresis_torque_Nm"]
    omega_m = t["gear_ratio"] * 2.0 * math.pi * u / H
    net = t["motor_derating"] * t["stall_torque_Nm"] * (1.0 - omega_m / t["no_load_speed_rad_per_s"]) - losses
    ratio = 2.0 * math.pi * t["gear_ratio"] / H
    if net >= 0.0:
        return ratio * t["gear_efficiency"] * eta_s * net
    return ratio * net / (t["gear_efficiency"] * t["screw_back_efficiency"])


def rhs(_t, z, eta_s):
    D, u = z
    den = 4.0 * L_S**2 - D * D
    G = (3.0 / 16.0 * M_S * D * D + 3.0 * J_C) / den
    dG = D * (1.5 * M_S * L_S**2 + 6.0 * J_C) / den**2
    L = math.sqrt(B_F**2 + D * D)
    dU = 6.0 * K * (L - L_0) * D / L if L > L_0 else 0.0
    M = 2.0 * G + 15.0 / 8.0 * M_S + M_F + M_TIP
    return [u, (-dG * u * u - dU + motor_force(u, eta_s)) / M]


def rail(_t, z, _eta_s):
    D = z[0]
    return D / 2.0 - Y_L + (math.sqrt(L_S**2 - D * D / 4.0) - X_L) / math.tan(BETA)


rail.terminal, rail.direction = True, -1


def reference_entry_s(eta_s):
    sol = solve_ivp(rhs, (0.0, 100.0), [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-16, events=rail,
                    args=(eta_s,))
    assert sol.status == 1 and len(sol.t_events[0]) == 1, sol.message
    return float(sol.t_events[0][0])


def simulate(sim, scene, eta_s):
    sets = {"mast.n_bays": 1, "drive.mode": "motor", "drive.screw_efficiency": eta_s, "run.output_step_s": 0,
            "run.rtol": 1e-12, "run.atol": 1e-15, "run.integrator": "dop853"}
    sets.update({f"drive.{k}": v for k, v in TRAIN.items()})
    cmd = [sim, scene, "--json"]
    for k, v in sets.items():
        cmd += ["--set", f"{k}={v}"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", required=True)
    ap.add_argument("--scene", required=True, help="campaigns/scenes/table1.toml")
    a = ap.parse_args()
    failures = []

    def check(ok, what):
        print(("ok    " if ok else "FAIL  ") + what)
        if not ok:
            failures.append(what)

    entries, deploys = [], []
    for eta in EFFICIENCIES:
        r = simulate(a.sim, a.scene, eta)
        check(r["status"] == "ok", f"eta_s = {eta}: status {r['status']} {r['message']}")
        t_sim, t_ref = r["bays"][0]["entry_time_s"], reference_entry_s(eta)
        # Both integrate to rtol 1e-12 or below and locate the event on a dense output of order 7 or
        # more: their times agree to some 1e-12 relative; 1e-9 leaves a margin of a thousand.
        check(abs(t_sim - t_ref) <= 1e-9 * t_ref,
              f"eta_s = {eta}: rail entry at {t_sim:.15g} s, independent integration {t_ref:.15g} s "
              f"(difference {t_sim - t_ref:.3g} s)")
        entries.append(t_ref)
        deploys.append(r["deploy_time_s"])
    # A less efficient screw passes less of the motor's torque: the deployment slows, by far more
    # than the agreement above.
    for k in range(1, len(EFFICIENCIES)):
        check(entries[k] > entries[k - 1] * (1 + 1e-3) and deploys[k] > deploys[k - 1] * (1 + 1e-3),
              f"eta_s {EFFICIENCIES[k - 1]} -> {EFFICIENCIES[k]}: entry {entries[k - 1]:.6g} -> {entries[k]:.6g} s, "
              f"deployment {deploys[k - 1]:.6g} -> {deploys[k]:.6g} s")
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
