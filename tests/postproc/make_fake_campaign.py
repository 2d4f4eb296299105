#!/usr/bin/python3
"""Write a small synthetic campaign file in truss-campaign's layout (docs/hdf5-schema.md,
"Campaign", schema_version 2).

Test fixture for postproc/report.py. The layout, types, units and attributes follow the schema;
the numbers are made up: smooth functions of the sampled inputs plus noise, so that rank
correlations are not trivial. Bays lock from the top (bay n first), as in the simulator.
`/stats` is computed here exactly as the schema defines it (numpy.percentile, ddof = 1).

Usage:
    make_fake_campaign.py OUT.h5 [--n-runs N] [--n-bays-max N] [--seed S]
        [--sampling monte_carlo|latin_hypercube|sobol|saltelli] [--drive-mode velocity|torque|motor]
        [--n-fail K] [--variable-bays] [--no-torque] [--histories 0,3]
        [--schema-version V] [--kind K] [--omit /PATH] [--truncate]

--n-fail K     K runs fail (status rail miss, wall-time limit, stall, in turn), with messages;
               in motor mode, draws whose stall torque is below the required torque stall too.
--variable-bays  mast.n_bays is dispersed (discrete n_bays_max - 2 .. n_bays_max): per-bay
               columns beyond a run's bay count are NaN.
--no-torque    peak_drive_torque_Nm is NaN in every run (an output without a finite value).
--omit /PATH   delete this dataset or group after writing (a file missing a required dataset).
--truncate     cut the finished file to half its size (a damaged file).
"""
import argparse
import os

import h5py
import numpy as np

STATUS = {"ok": 0, "rail miss": 1, "stall": 2, "singular configuration": 3, "step limit": 4,
          "invalid input": 5, "wall-time limit": 6}
STATUS_T = h5py.enum_dtype(STATUS, basetype="i1")
STR_T = h5py.string_dtype("utf-8")
PCT = {"p1": 1.0, "p5": 5.0, "p50": 50.0, "p95": 95.0, "p99": 99.0, "p99_865": 99.865}

# Scalar numeric fields of RunResult (except wall_time_s) with their units; int64 when "i".
RUN_FIELDS = [
    ("n_bays", "1", "i"), ("bays_completed", "1", "i"), ("deploy_time_s", "s", "f"),
    ("peak_drive_force_N", "N", "f"), ("peak_drive_force_time_s", "s", "f"),
    ("peak_drive_force_bay", "1", "i"), ("min_drive_force_N", "N", "f"),
    ("min_drive_force_time_s", "s", "f"), ("min_drive_force_bay", "1", "i"),
    ("peak_drive_torque_Nm", "Nm", "f"), ("min_drive_torque_Nm", "Nm", "f"), ("motor_torque_at_speed_Nm", "Nm", "f"),
    ("peak_pin_force_N", "N", "f"), ("peak_pin_force_time_s", "s", "f"),
    ("peak_pin_force_bay", "1", "i"), ("peak_diagonal_tension_N", "N", "f"),
    ("peak_latch_energy_J", "J", "f"), ("peak_driven_speed_m_per_s", "m/s", "f"),
    ("drive_work_J", "J", "f"), ("drive_work_smooth_J", "J", "f"),
    ("drive_work_impulses_J", "J", "f"), ("start_drive_impulse_Ns", "Ns", "f"),
    ("energy_lost_J", "J", "f"), ("kinetic_energy_start_J", "J", "f"),
    ("kinetic_energy_end_J", "J", "f"), ("potential_energy_start_J", "J", "f"),
    ("potential_energy_end_J", "J", "f"), ("energy_residual_J", "J", "f"),
    ("max_rail_residual_m", "m", "f"), ("steps", "1", "i"), ("rejected_steps", "1", "i"),
    ("rhs_evals", "1", "i"),
]
BAY_FIELDS = [
    ("entry_time_s", "s"), ("lock_time_s", "s"), ("latch_energy_J", "J"),
    ("entry_impulse_Ns", "Ns"), ("landing_impulse_Ns", "Ns"), ("entry_drive_impulse_Ns", "Ns"),
    ("entry_energy_loss_J", "J"), ("peak_drive_force_N", "N"), ("peak_drive_force_time_s", "s"),
    ("peak_pin_force_N", "N"), ("peak_pin_force_time_s", "s"),
]
HISTORY_FIELDS = [
    ("t_s", "s"), ("bay", "1"), ("y_driven_m", "m"), ("y_lower_m", "m"), ("hinge_x_m", "m"),
    ("hinge_y_m", "m"), ("drive_force_N", "N"), ("drive_torque_Nm", "Nm"), ("pin_force_N", "N"),
    ("diagonal_tension_N", "N"), ("driven_speed_m_per_s", "m/s"),
]
SENSITIVITY_OUTPUTS = ["peak_drive_force_N", "peak_drive_torque_Nm", "peak_pin_force_N",
                       "peak_diagonal_tension_N", "peak_latch_energy_J", "deploy_time_s"]
LEAD_M = 0.01


def base_scene_toml(n_bays, mode):
    return f"""[mast]
n_bays = {n_bays}
strut_length_m = 0.18
strut_mass_kg = 0.1
# strut_inertia_kg_m2 = 0.00027
frame_side_m = 0.36
frame_mass_kg = 0.5
diagonal_stiffness_N_per_m = 20.0
diagonal_free_length_m = 0.45
# tip_mass_kg = 1.1

[rail]
x_m = 0.08
y_m = 0.15
beta_deg = 20.85

[drive]
mode = "{mode}"
speed_m_per_s = 0.1
screw_lead_m = {LEAD_M}
torque_Nm = 0.01
stall_torque_Nm = 0.012
no_load_speed_rad_per_s = 75.0

[stack]
mode = "held"

[panels]
count = 0
length_m = 0.5
mass_kg = 0.2

[run]
direction = "deploy"
output_step_s = 0.0
rtol = 1e-08
atol = 1e-10
integrator = "dopri54"
max_steps = 2000000
max_wall_time_s = 10.0
"""


def dispersions(a):
    """The campaign's dispersions: (key, per, apply, distribution, params, nominal, units)."""
    d = [("mast.strut_mass_kg", "bay", "relative", "normal",
          {"mean": 0.0, "std": 1.0 / 60.0}, 0.1, "kg"),
         ("mast.frame_mass_kg", "frame", "relative", "normal",
          {"mean": 0.0, "std": 1.0 / 60.0}, 0.5, "kg"),
         ("rail.x_m", "run", "offset", "uniform", {"lower": -0.0005, "upper": 0.0005}, 0.08, "m")]
    if a.drive_mode == "motor":
        d.append(("drive.stall_torque_Nm", "run", "relative", "truncated_normal",
                  {"mean": 0.0, "std": 0.05, "lower": -0.25, "upper": 0.25}, 0.012, "Nm"))
    if a.variable_bays:
        n = a.n_bays_max
        d.append(("mast.n_bays", "run", "absolute", "discrete",
                  {"values": np.array([n - 2.0, n - 1.0, n]),
                   "weights": np.array([0.25, 0.25, 0.5])}, float(n), "1"))
    return d


def draw(rng, dist, params, shape):
    if dist == "normal":
        return params["mean"] + params["std"] * rng.standard_normal(shape)
    if dist == "truncated_normal":
        x = params["mean"] + params["std"] * rng.standard_normal(shape)
        return np.clip(x, params["lower"], params["upper"])
    if dist == "uniform":
        return rng.uniform(params["lower"], params["upper"], shape)
    if dist == "discrete":
        return rng.choice(params["values"], size=shape, p=params["weights"])
    raise ValueError(dist)


def campaign_toml(a, disp, scene):
    lines = ["[campaign]", 'name = "fake-campaign"',
             'description = "synthetic campaign (tests/postproc/make_fake_campaign.py)"', "",
             "[ensemble]", f"n_runs = {a.n_runs}", f"master_seed = {a.seed}",
             f'sampling = "{a.sampling}"', "max_run_wall_time_s = 10.0", "",
             "[output]", "history_runs = [" + ", ".join(map(str, a.histories)) + "]",
             "history_step_s = 0.05", ""]
    table = None
    for line in scene.splitlines():
        if line.startswith("["):
            table = line.strip("[]")
            lines.append(f"[scene.{table}]")
        else:
            lines.append(line)
    for key, per, apply, dist, params, _, _ in disp:
        lines += ["", "[[dispersion]]", f'key = "{key}"', f'per = "{per}"', f'apply = "{apply}"',
                  f'distribution = "{dist}"']
        for k, v in params.items():
            lines.append(f"{k} = {list(v) if isinstance(v, np.ndarray) else v!r}")
    return "\n".join(lines) + "\n"


def simulate(a, rng, inputs, n_bays):
    """Made-up outputs of every run: dict of /runs columns, /runs/bays columns, status, message."""
    n, nmax = a.n_runs, a.n_bays_max
    bay_ok = np.arange(nmax)[None, :] < n_bays[:, None]          # column j = bay j + 1
    strut = np.where(bay_ok, inputs["mast.strut_mass_kg"], np.nan)
    frame = inputs["mast.frame_mass_kg"]
    dm = np.nanmean(strut / 0.1 - 1.0, axis=1)                      # mean relative deviation
    dx = inputs["rail.x_m"] - 0.08
    noise = rng.standard_normal((n, 6))

    # Lock times: bay n first; each stage takes ~3.6 s, longer for heavier struts.
    stage = 3.6 * (1.0 + 0.3 * (strut / 0.1 - 1.0)) + 0.002 * rng.standard_normal((n, nmax))
    stage = np.where(bay_ok, stage, np.nan)
    lock = np.full((n, nmax), np.nan)
    for i in range(n):
        nb = n_bays[i]
        lock[i, nb - 1::-1] = np.cumsum(stage[i, nb - 1::-1])
    bays = {"lock_time_s": lock, "entry_time_s": lock - 1.0,
            "latch_energy_J": np.where(bay_ok, 1.45e-4 * (1 + 2 * (strut / 0.1 - 1)), np.nan),
            "peak_drive_force_N": np.where(bay_ok, 3.0 * (1 + 0.5 * (strut / 0.1 - 1)), np.nan),
            "peak_pin_force_N": np.where(bay_ok, 0.8 * (1 + (frame[:, :nmax] / 0.5 - 1)), np.nan)}
    bays["peak_drive_force_time_s"] = lock - 0.5
    bays["peak_pin_force_time_s"] = lock - 0.2
    for name, _ in BAY_FIELDS:
        bays.setdefault(name, np.where(bay_ok, 0.01, np.nan))

    out = {
        "deploy_time_s": np.nanmax(lock, axis=1),
        "peak_drive_force_N": 3.0 * (1 + 0.5 * dm) + 150.0 * dx + 0.004 * noise[:, 0],
        "peak_pin_force_N": 0.83 * (1 + (frame[:, 0] / 0.5 - 1)) - 40.0 * dx + 0.002 * noise[:, 1],
        "peak_diagonal_tension_N": 1.18 + 0.01 * noise[:, 2],
        "peak_latch_energy_J": np.nanmax(bays["latch_energy_J"], axis=1) + 1e-7 * noise[:, 3],
    }
    if a.no_torque:
        out["peak_drive_torque_Nm"] = np.full(n, np.nan)
    elif a.drive_mode == "motor":
        out["peak_drive_torque_Nm"] = inputs["drive.stall_torque_Nm"].copy()
    else:
        out["peak_drive_torque_Nm"] = out["peak_drive_force_N"] * LEAD_M / (2 * np.pi)

    # The scene's motor at the prescribed speed (velocity mode; the base scene's drive, which is
    # not dispersed here): T_s (1 - omega / omega_0), omega = 2 pi v / h. NaN in other modes.
    if a.drive_mode == "velocity":
        out["motor_torque_at_speed_Nm"] = np.full(n, 0.012 * (1.0 - 2.0 * np.pi * 0.1 / LEAD_M / 75.0))
    else:
        out["motor_torque_at_speed_Nm"] = np.full(n, np.nan)
    status = np.zeros(n, dtype=np.int8)
    message = [""] * n
    if a.drive_mode == "motor":   # weak motors stall in the first stage
        required = 0.0108 * (1 + 0.02 * noise[:, 4])
        for i in np.nonzero(inputs["drive.stall_torque_Nm"] < required)[0]:
            status[i] = STATUS["stall"]
            y = 0.3 + 0.01 * noise[i, 5]
            message[i] = (f"stall: the driven frame stopped at y = {y:.9g} m, "
                          f"t = {3.0 + noise[i, 5] ** 2:.9g} s, in the stage of bay {n_bays[i]} "
                          "before its lock")
    forced = [("rail miss", "rail miss: the hinge of bay {b} passed below the rail foot"),
              ("wall-time limit", "wall-time limit: stopped after 10 s of wall time"),
              ("stall", "stall: the driven frame stopped at y = 0.31 m, t = 3.2 s, in the stage "
                        "of bay {b} before its lock")]
    ok_rows = np.nonzero(status == 0)[0]
    for k, i in enumerate(ok_rows[np.linspace(1, len(ok_rows) - 1, a.n_fail, dtype=int)]
                          if a.n_fail else []):
        name, text = forced[k % len(forced)]
        status[i] = STATUS[name]
        message[i] = text.format(b=n_bays[i] - 1)
    failed = status != 0
    # A failed run has partial peaks (finite), no deploy time, and no lock from its failing bay on.
    out["deploy_time_s"][failed] = np.nan
    for name in ("lock_time_s", "entry_time_s", "peak_drive_force_time_s", "peak_pin_force_time_s",
                 "latch_energy_J"):
        bays[name][failed, : max(nmax - 2, 0)] = np.nan
    out["peak_latch_energy_J"][failed] = np.nan
    return out, bays, status, message


def write_stats_group(g, values, units, ok):
    """/stats/<output> datasets for one column (values over all runs, shape n or n x m)."""
    vals = np.where(ok.reshape((-1,) + (1,) * (values.ndim - 1)), values, np.nan)
    cols = vals.reshape(len(vals), -1).T
    res = {k: [] for k in ["count", "mean", "std", "min", "max", *PCT]}
    for c in cols:
        x = c[np.isfinite(c)]
        res["count"].append(len(x))
        for k in ["mean", "std", "min", "max", *PCT]:
            if len(x) == 0 or (k == "std" and len(x) < 2):
                res[k].append(np.nan)
            elif k == "mean":
                res[k].append(np.mean(x))
            elif k == "std":
                res[k].append(np.std(x, ddof=1))
            elif k in ("min", "max"):
                res[k].append(getattr(np, k)(x))
            else:
                res[k].append(np.percentile(x, PCT[k]))
    for k, v in res.items():
        arr = np.array(v, dtype=np.int64 if k == "count" else np.float64)
        ds = g.create_dataset(k, data=arr[0] if values.ndim == 1 else arr)
        ds.attrs["units"] = "1" if k == "count" else units


def write(a):
    rng = np.random.default_rng(a.seed)
    n, nmax = a.n_runs, a.n_bays_max
    disp = dispersions(a)
    if a.sampling == "saltelli" and n % (len(disp) + 2):
        raise SystemExit(f"saltelli: --n-runs must be a multiple of G + 2 = {len(disp) + 2}")

    inputs, width = {}, {"run": None, "bay": nmax, "frame": nmax + 1}
    for key, per, apply, dist, params, nominal, _ in disp:
        shape = (n,) if width[per] is None else (n, width[per])
        x = draw(rng, dist, params, shape)
        inputs[key] = {"relative": nominal * (1 + x), "offset": nominal + x, "absolute": x}[apply]
    n_bays = (inputs["mast.n_bays"].astype(np.int64) if a.variable_bays
              else np.full(n, nmax, dtype=np.int64))
    for key, per, *_ in disp:                      # NaN beyond each run's bay count
        if per != "run":
            cols = np.arange(inputs[key].shape[1])[None, :]
            inputs[key] = np.where(cols < n_bays[:, None] + (per == "frame"), inputs[key], np.nan)

    out, bays, status, message = simulate(a, rng, inputs, n_bays)
    scene = base_scene_toml(nmax, a.drive_mode)

    with h5py.File(a.out, "w") as f:
        at = f.attrs
        at["schema_version"] = np.int64(a.schema_version)
        at["kind"] = a.kind
        at["campaign_name"] = "fake-campaign"
        at["campaign_description"] = "synthetic campaign (tests/postproc/make_fake_campaign.py)"
        at["campaign_toml"] = campaign_toml(a, disp, scene)
        at["base_scene_toml"] = scene
        at["n_runs"] = np.int64(n)
        at["master_seed"] = np.int64(a.seed)
        at["sampling"] = a.sampling
        at["n_bays_max"] = np.int64(nmax)
        at["direction"] = "deploy"
        at["drive_mode"] = a.drive_mode
        at["software_version"] = "0.1.0"
        at["git_revision"] = "fake000"
        at["n_ranks"] = np.int64(2)
        at["n_sessions"] = np.int64(1)
        at["start_utc"] = "2026-01-02T03:04:05Z"
        at["end_utc"] = "2026-01-02T03:05:10Z"
        at["wall_time_s"] = np.float64(65.25)

        runs = f.create_group("runs")

        def col(g, name, data, units, dtype=None):
            ds = g.create_dataset(name, data=data, dtype=dtype)
            ds.attrs["units"] = units
            return ds

        col(runs, "run_index", np.arange(n, dtype=np.int64), "1")
        col(runs, "status", status, "1", STATUS_T)
        col(runs, "message", np.array(message, dtype=object), "1", STR_T)
        ok = status == 0
        for name, units, kind in RUN_FIELDS:
            if name in out:
                data = out[name]
            elif name == "n_bays":
                data = n_bays
            elif name == "bays_completed":
                data = np.where(ok, n_bays, np.sum(np.isfinite(bays["lock_time_s"]), axis=1))
            elif kind == "i":
                data = np.full(n, 30, dtype=np.int64)
            else:
                data = 0.5 + 0.01 * rng.standard_normal(n)
            col(runs, name, np.asarray(data, dtype=np.int64 if kind == "i" else np.float64), units)
        gb = runs.create_group("bays")
        for name, units in BAY_FIELDS:
            col(gb, name, bays[name], units)
        gi = runs.create_group("inputs")
        for factor, (key, per, apply, dist, params, nominal, units) in enumerate(disp):
            ds = col(gi, key, inputs[key], units)
            ds.attrs.update({"per": per, "apply": apply, "distribution": dist,
                             "nominal": np.float64(nominal), "factor": np.int64(factor)})
            for k, v in params.items():
                ds.attrs[k] = np.asarray(v, dtype=np.float64)

        st = f.create_group("stats")
        st.attrs["n_runs"] = np.int64(n)
        st.attrs["n_ok"] = np.int64(ok.sum())
        st.attrs["n_failed"] = np.int64(n - ok.sum())
        st.attrs["percentile_method"] = ("linear interpolation between order statistics "
                                         "(Hyndman-Fan type 7, numpy.percentile default)")
        st.attrs["std_ddof"] = np.int64(1)
        names = sorted(STATUS, key=STATUS.get)
        col(st, "status_names", np.array(names, dtype=object), "1", STR_T)
        col(st, "status_counts",
            np.array([np.sum(status == STATUS[s]) for s in names], dtype=np.int64), "1")
        for name, units, kind in RUN_FIELDS:
            if kind == "f":
                write_stats_group(st.create_group(name), runs[name][()], units, ok)
        sb = st.create_group("bays")
        for name, units in BAY_FIELDS:
            write_stats_group(sb.create_group(name), bays[name], units, ok)

        if a.sampling == "saltelli":
            write_sensitivity(f, rng, [d[0] for d in disp], n // (len(disp) + 2))
        if a.histories:
            write_histories(f, a.histories, out, n_bays, status)

        tm = f.create_group("timing")
        col(tm, "run_wall_time_s", 0.01 + 0.001 * rng.random(n), "s")
        col(tm, "rank", np.arange(n, dtype=np.int64) % 2, "1")
        col(tm, "session", np.zeros(n, dtype=np.int64), "1")

        if a.omit:
            del f[a.omit]

    if a.truncate:
        size = os.path.getsize(a.out)
        with open(a.out, "r+b") as fh:
            fh.truncate(size // 2)


def write_sensitivity(f, rng, factors, n_blocks):
    g = f.create_group("sensitivity")
    ds = g.create_dataset("factor", data=np.array(factors, dtype=object), dtype=STR_T)
    ds.attrs["units"] = "1"
    G = len(factors)
    for out in SENSITIVITY_OUTPUTS:
        go = g.create_group(out)
        s1 = rng.dirichlet(np.ones(G)) * 0.9
        st = s1 + 0.1 * rng.random(G)
        for name, v in (("first_order", s1), ("total", st)):
            for suffix, d in (("", 0.0), ("_lo", -0.05), ("_hi", 0.05)):
                go.create_dataset(name + suffix, data=v + d).attrs["units"] = "1"
        go.attrs.update({"n_blocks": np.int64(n_blocks), "n_blocks_dropped": np.int64(0),
                         "n_resamples": np.int64(1000), "confidence": np.float64(0.95),
                         "method": "Saltelli 2010 first-order, Jansen total, "
                                   "percentile bootstrap over blocks"})


def write_histories(f, runs, out, n_bays, status):
    g = f.create_group("histories")
    for i in runs:
        t_end = out["deploy_time_s"][i] if status[i] == 0 else 3.0
        t = np.arange(0.0, t_end, 0.05)
        nb = int(n_bays[i])
        bay = np.clip(nb - (t // 3.6).astype(np.int64), 1, nb)
        phase = (t % 3.6) / 3.6
        h = {"t_s": t, "bay": bay, "y_driven_m": 0.1 * t, "y_lower_m": 0.0 * t,
             "hinge_x_m": 0.18 * np.cos(phase), "hinge_y_m": 0.18 * np.sin(phase),
             "drive_force_N": 3.0 * phase ** 2, "drive_torque_Nm": 3.0 * phase ** 2 * LEAD_M / 6.28,
             "pin_force_N": np.where(phase > 0.7, 0.8 * (phase - 0.7) / 0.3, 0.0),
             "diagonal_tension_N": 1.0 * phase, "driven_speed_m_per_s": 0.1 + 0.0 * t}
        gr = g.create_group(f"run_{i}")
        for name, units in HISTORY_FIELDS:
            ds = gr.create_dataset(name, data=h[name])
            ds.attrs["units"] = units


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("--n-runs", type=int, default=200)
    p.add_argument("--n-bays-max", type=int, default=6)
    p.add_argument("--seed", type=int, default=1234)
    p.add_argument("--sampling", default="monte_carlo",
                   choices=["monte_carlo", "latin_hypercube", "sobol", "saltelli"])
    p.add_argument("--drive-mode", default="velocity", choices=["velocity", "torque", "motor"])
    p.add_argument("--n-fail", type=int, default=0)
    p.add_argument("--variable-bays", action="store_true")
    p.add_argument("--no-torque", action="store_true")
    p.add_argument("--histories", type=lambda s: [int(x) for x in s.split(",") if x], default=[])
    p.add_argument("--schema-version", type=int, default=2)
    p.add_argument("--kind", default="campaign")
    p.add_argument("--omit", default=None)
    p.add_argument("--truncate", action="store_true")
    write(p.parse_args())


if __name__ == "__main__":
    main()
