"""truss_report.extras: what the design-load part of the report reads beyond h5read.Campaign:
every /runs/bays field, the peak locations and impulse columns of /runs, and the nominal run
(/nominal: the base scene run once by truss-campaign; a file without it has no nominal column)."""
from dataclasses import dataclass, field

import numpy as np

import run_figures as rf

# /runs columns read when present (units from the file).
EXTRA_RUN_COLUMNS = ["start_drive_impulse_Ns", "drive_work_impulses_J", "peak_drive_force_time_s",
                     "peak_drive_force_bay", "peak_pin_force_time_s", "peak_pin_force_bay",
                     "motor_torque_at_speed_Nm", "n_bays", "energy_residual_J",
                     "peak_static_drive_torque_Nm", "peak_inertial_drive_torque_Nm"]


@dataclass
class Extras:
    runs: dict = field(default_factory=dict)       # name -> array n (float64)
    units: dict = field(default_factory=dict)      # name -> units (runs and bays fields)
    bays: dict = field(default_factory=dict)       # field -> n x n_bays_max
    nominal: dict = None                           # name -> float; "bays" -> {field: array}
    nominal_status: str = ""
    nominal_message: str = ""
    nominal_run: dict = None                       # run_figures layout (history), or None


def load_extras(h5, c):
    """Reads the extras of campaign `c` from the open file `h5` (InputError on bad layout)."""
    import h5py
    e = Extras()
    n, nb = c.n, c.attrs["n_bays_max"]
    for k in EXTRA_RUN_COLUMNS:
        if h5.has(f"runs/{k}"):
            e.runs[k] = h5.array(f"runs/{k}", (n,))
            e.units[k] = h5.units(f"runs/{k}")
    for k in sorted(h5.f["runs/bays"]):
        e.bays[k] = h5.array(f"runs/bays/{k}", (n, nb))
        e.units[k] = h5.units(f"runs/bays/{k}")
    if not h5.has("nominal"):
        return e
    g = h5.f["nominal"]
    names = {int(v): k for k, v in h5py.check_enum_dtype(g["status"].dtype).items()}
    e.nominal_status = names.get(int(g["status"][()]), "?")
    e.nominal_message = h5.attr_or(g["status"], "message", "")
    e.nominal = {}
    for k, ds in g.items():
        if isinstance(ds, h5py.Dataset) and k != "status" and ds.dtype.kind in "fiu":
            e.nominal[k] = float(ds[()])
    e.nominal["bays"] = {k: h5.array(f"nominal/bays/{k}", (nb,)) for k in g["bays"]}
    if "history" in g and len(g["history/t_s"]) > 0:
        hist = {f: h5.array(f"nominal/history/{f}") for f in rf.HISTORY_FIELDS}
        hist["bay"] = hist["bay"].astype(np.int64)
        units = {f: h5.units(f"nominal/history/{f}") for f in rf.HISTORY_FIELDS}
        n_bays = int(e.nominal.get("n_bays", nb))
        e.nominal_run = {"path": "nominal run", "n_bays": n_bays, "history": hist, "units": units,
                         "drive_mode": c.attrs["drive_mode"], "direction": c.attrs["direction"],
                         "stack_mode": (c.base_scene.get("stack") or {}).get("mode"),
                         "status": e.nominal_status,
                         "bays": {"lock_time_s": e.nominal["bays"]["lock_time_s"][:n_bays],
                                  "entry_time_s": e.nominal["bays"]["entry_time_s"][:n_bays]}}
    return e
