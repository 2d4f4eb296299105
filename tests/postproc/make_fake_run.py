#!/usr/bin/python3
"""Write a synthetic single-run HDF5 file in truss-sim's layout (schema_version 1).

Test fixture for postproc/run_figures.py while the simulator is not built. The numbers are
geometric, not dynamic: a held-stack deployment at constant speed v where, in each stage, the
hinge of the deploying bay moves on the quarter circle of radius l_s = 0.18 m about the lower
frame (phase A) until it meets the guide rail, then along the rail line to x = 0 (phase B).
Forces are made-up smooth curves (drive force rising to ~3 N before rail entry, dropping
after; pin force zero off the rail).

Usage:
    make_fake_run.py OUT.h5 [--n-bays N] [--schema-version V] [--no-history]
                            [--fixed-strings] [--dt S]
"""
import argparse
import math

import h5py
import numpy as np

LS = 0.18        # strut length l_s (m)
XL, YL = 0.08, 0.15
BETA_DEG = 20.85
V = 0.1          # drive speed (m/s)


def stage(d0, t0, dt):
    """One stage starting with the bay open to height d0 (lower frame held at 0) at time t0.

    Returns a dict of arrays sampled on the global grid k*dt inside the stage, plus the
    entry and lock times.
    """
    cot = 1.0 / math.tan(math.radians(BETA_DEG))
    yr = YL + XL * cot
    # Rail entry: hinge (x, D/2) on the circle x^2 + (D/2)^2 = l_s^2 and on the rail line.
    # y = yl - cot (x - xl)  ->  x^2 + (yr - cot x)^2 = l_s^2
    a, b, c = 1 + cot**2, -2 * yr * cot, yr**2 - LS**2
    # The smaller root: the hinge starts at y = 0 and the larger root lies below the floor.
    xe = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    ye = yr - cot * xe
    y_entry = 2 * ye                      # driven frame height at entry
    # Phase B: parameterize by hinge x in [xe, 0]; driven height Y(x) = yr - cot x + sqrt(l_s^2 - x^2)
    xs = np.linspace(xe, 0.0, 4001)
    Y = yr - cot * xs + np.sqrt(LS**2 - xs**2)
    y_lock = Y[-1]
    te = t0 + (y_entry - d0) / V
    tl = t0 + (y_lock - d0) / V

    k0 = int(math.ceil(t0 / dt - 1e-9))
    k1 = int(math.floor(tl / dt - 1e-9))  # the lock sample belongs to the next stage
    t = np.arange(k0, k1 + 1) * dt
    ym = d0 + V * (t - t0)
    free = ym < y_entry
    hx = np.where(free, np.sqrt(np.clip(LS**2 - (ym / 2) ** 2, 0, None)), 0.0)
    hy = np.where(free, ym / 2, 0.0)
    xb = np.interp(ym, Y, xs)             # Y is increasing as x falls to 0
    hx = np.where(free, hx, xb)
    hy = np.where(free, hy, yr - cot * xb)
    ylow = np.where(free, 0.0, 2 * hy - ym)
    D = ym - ylow
    tension = 20.0 * np.clip(np.sqrt(0.36**2 + D**2) - 0.45, 0, None)
    # Made-up forces: spring-like rise before entry, a drop and a slow decay on the rail.
    s = (t - te) / max(tl - te, 1e-9)
    drive = np.where(free, 0.05 + 3.0 * (np.clip(D - 0.27, 0, None) / (y_entry - 0.27)) ** 1.5,
                     0.8 + 1.2 * np.exp(-3 * s) + 0.6 * s)
    pin = np.where(free, 0.0, 2.0 + 4.0 * np.exp(-4 * s) + 1.5 * s**2)
    return dict(t=t, ym=ym, ylow=ylow, hx=hx, hy=hy, drive=drive, pin=pin, tension=tension,
                te=te, tl=tl, y_lock_lower=y_lock - 2 * LS, xe=xe, ye=ye)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("--n-bays", type=int, default=4)
    p.add_argument("--schema-version", type=int, default=1)
    p.add_argument("--no-history", action="store_true")
    p.add_argument("--fixed-strings", action="store_true",
                   help="store string attributes as fixed-length bytes (default: variable)")
    p.add_argument("--dt", type=float, default=0.002)
    a = p.parse_args()
    n = a.n_bays

    stages, t0, d0 = {}, 0.0, 0.0
    for m in range(n, 0, -1):              # deployment: bay n first
        st = stage(d0, t0, a.dt)
        stages[m] = st
        t0, d0 = st["tl"], st["y_lock_lower"]   # next driven frame starts where the rail left it

    scene = f"""# resolved scene (synthetic, tests/postproc/make_fake_run.py)
[mast]
n_bays = {n}
strut_length_m = {LS}
strut_mass_kg = 0.1
frame_side_m = 0.36
frame_mass_kg = 0.5
diagonal_stiffness_N_per_m = 20.0
diagonal_free_length_m = 0.45

[rail]
x_m = {XL}
y_m = {YL}
beta_deg = {BETA_DEG}

[drive]
mode = "velocity"
speed_m_per_s = {V}
screw_lead_m = 0.01

[stack]
mode = "held"

[panels]
count = 0

[run]
direction = "deploy"
output_step_s = {a.dt if not a.no_history else 0.0}
"""

    def sattr(obj, name, value):
        if a.fixed_strings:
            obj.attrs.create(name, np.bytes_(value.encode()))
        else:
            obj.attrs[name] = value

    def dset(group, name, data, units):
        ds = group.create_dataset(name, data=data)
        sattr(ds, "units", units)

    with h5py.File(a.out, "w") as f:
        f.attrs["schema_version"] = np.int32(a.schema_version)
        sattr(f, "kind", "single_run")
        sattr(f, "scene_toml", scene)

        order = list(range(n, 0, -1))
        hs = {k: np.concatenate([stages[m][k] for m in order])
              for k in ("t", "ym", "ylow", "hx", "hy", "drive", "pin", "tension")}
        hbay = np.concatenate([np.full(len(stages[m]["t"]), m, dtype=np.int32) for m in order])

        g = f.create_group("summary")
        status_t = h5py.enum_dtype({"ok": 0, "rail_miss": 1, "stall": 2,
                                    "singular_configuration": 3, "step_limit": 4,
                                    "invalid_input": 5}, basetype="i1")
        g.create_dataset("status", data=np.int8(0), dtype=status_t)
        dset(g, "deploy_time_s", stages[1]["tl"], "s")
        dset(g, "peak_drive_force_N", float(hs["drive"].max()), "N")
        dset(g, "peak_pin_force_N", float(hs["pin"].max()), "N")

        g = f.create_group("bays")
        idx = np.arange(1, n + 1)
        dset(g, "bay", idx.astype(np.int32), "")
        dset(g, "entry_time_s", np.array([stages[m]["te"] for m in idx]), "s")
        dset(g, "lock_time_s", np.array([stages[m]["tl"] for m in idx]), "s")
        dset(g, "latch_energy_J", np.full(n, 1.0e-4), "J")
        dset(g, "entry_impulse_Ns", np.full(n, 0.01), "N s")
        dset(g, "peak_drive_force_N", np.array([stages[m]["drive"].max() for m in idx]), "N")
        dset(g, "peak_pin_force_N", np.array([stages[m]["pin"].max() for m in idx]), "N")

        if not a.no_history:
            g = f.create_group("history")
            dset(g, "t_s", hs["t"], "s")
            dset(g, "bay", hbay, "")
            dset(g, "y_driven_m", hs["ym"], "m")
            dset(g, "y_lower_m", hs["ylow"], "m")
            dset(g, "hinge_x_m", hs["hx"], "m")
            dset(g, "hinge_y_m", hs["hy"], "m")
            dset(g, "drive_force_N", hs["drive"], "N")
            dset(g, "drive_torque_Nm", hs["drive"] * 0.01 / (2 * math.pi), "N m")
            dset(g, "pin_force_N", hs["pin"], "N")
            dset(g, "diagonal_tension_N", hs["tension"], "N")
            dset(g, "driven_speed_m_per_s", np.full(len(hs["t"]), V), "m/s")


if __name__ == "__main__":
    main()
