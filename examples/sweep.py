#!/usr/bin/env python3
"""A small sweep, notebook style: how the motor's stall torque sets the deployment time of the
Table-1 mast (30 bays, motor drive), down to the torque below which the motor stalls. Each `# %%`
cell runs as it is in Jupyter or VS Code; as a script it writes sweep.csv and sweep.png.

    /usr/bin/python3 examples/sweep.py [--out-dir .]
"""
# %% The base scene and the sweep: 30 stall torques, one simulate_many call on every core.
import argparse
import pathlib

import matplotlib
matplotlib.use("Agg")  # noqa: E402 (files, no window)
import matplotlib.pyplot as plt
import numpy as np

import truss_deploy as td

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--out-dir", default=".", help="folder for sweep.csv and sweep.png (default: here)")
args, _ = ap.parse_known_args()  # known only: Jupyter adds its own arguments
out = pathlib.Path(args.out_dir)
out.mkdir(parents=True, exist_ok=True)

base = td.Scene.table1().with_(**{"drive.mode": "motor"})
torques_Nm = np.linspace(0.003, 0.03, 30)
df = td.simulate_many(base, {"drive.stall_torque_Nm": torques_Nm}, bays=False)
df.to_csv(out / "sweep.csv")
print(df[["input:drive.stall_torque_Nm", "status", "deploy_time_s", "bays_completed", "peak_latch_energy_J"]]
      .to_string(float_format="{:.6g}".format))

# %% Deployment time and the largest latch energy against the stall torque; stalled runs in red.
ok = df.status == "ok"
x_mNm = 1e3 * df["input:drive.stall_torque_Nm"]
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
top.plot(x_mNm[ok], df.deploy_time_s[ok], "o-", label="deployed")
if (~ok).any():
    # The stall boundary lies between the largest stalled and the next deployed torque: the band
    # ends half-way, so that it meets the deployed points without a gap (within half a step).
    last_stall = x_mNm[~ok].max()
    above = x_mNm[ok & (x_mNm > last_stall)]
    edge = 0.5 * (last_stall + above.min()) if len(above) else last_stall
    top.axvspan(x_mNm.min(), edge, color="tab:red", alpha=0.15,
                label="motor stalls (boundary within half a step)")
top.set_ylabel("deployment time (s)")
top.legend()
bottom.plot(x_mNm[ok], 1e3 * df.peak_latch_energy_J[ok], "o-", color="tab:green")
bottom.set_ylabel("largest latch energy (mJ)")
bottom.set_xlabel("motor stall torque (mN m)")
fig.suptitle(f"Table-1 mast, {base['mast.n_bays']} bays, motor drive "
             f"(no-load speed {base['drive.no_load_speed_rad_per_s']:g} rad/s)")
fig.tight_layout()
fig.savefig(out / "sweep.png", dpi=100)
print(f"wrote {out / 'sweep.csv'} and {out / 'sweep.png'}")
