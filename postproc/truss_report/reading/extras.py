"""truss_report.reading.extras: what the design-load part of the report reads beyond the Campaign:
every /runs/bays field, the peak locations and impulse columns of /runs, and the nominal run
(/nominal: the base scene run once by truss-campaign; a file without it has no nominal column)."""
from __future__ import annotations

from dataclasses import dataclass, field

import h5py
import numpy as np

from .campaign import Campaign
from .h5file import H5, Array, scene_table
from .run import HISTORY_FIELDS, RunHistory
from .schema import EXTRA_RUN_COLUMNS


@dataclass
class Extras:
    runs: dict[str, Array] = field(default_factory=dict)   # name -> array n (float64)
    units: dict[str, str] = field(default_factory=dict)    # name -> units (runs and bays fields)
    bays: dict[str, Array] = field(default_factory=dict)   # field -> n x n_bays_max
    nominal: dict[str, float] | None = None                 # /nominal's numbers; None: no /nominal
    nominal_bays: dict[str, Array] = field(default_factory=dict)   # /nominal/bays fields
    nominal_status: str = ""
    nominal_message: str = ""
    nominal_run: RunHistory | None = None                   # its history, when it has one

    def nominal_value(self, key: str) -> float:
        """The nominal run's value of a /runs column (NaN without /nominal or that column)."""
        return self.nominal.get(key, float("nan")) if self.nominal is not None else float("nan")


def load_extras(h5: H5, c: Campaign) -> Extras:
    """Reads the extras of campaign `c` from the open file `h5` (InputError on bad layout)."""
    e = Extras()
    n, nb = c.n, int(c.attrs["n_bays_max"])
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
    e.nominal = {k: float(ds[()]) for k, ds in g.items()
                 if isinstance(ds, h5py.Dataset) and k != "status" and ds.dtype.kind in "fiu"}
    e.nominal_bays = {k: h5.array(f"nominal/bays/{k}", (nb,)) for k in g["bays"]}
    if "history" in g and len(g["history/t_s"]) > 0:
        hist = {f: h5.array(f"nominal/history/{f}") for f in HISTORY_FIELDS}
        hist["bay"] = hist["bay"].astype(np.int64)
        units = {f: h5.units(f"nominal/history/{f}") for f in HISTORY_FIELDS}
        n_bays = int(e.nominal.get("n_bays", nb))
        e.nominal_run = RunHistory(
            path="nominal run", n_bays=n_bays, history=hist, units=units, drive_mode=c.drive_mode,
            direction=c.direction, stack_mode=scene_table(c.base_scene, "stack").get("mode"),
            status=e.nominal_status, bays={"lock_time_s": e.nominal_bays["lock_time_s"][:n_bays],
                                           "entry_time_s": e.nominal_bays["entry_time_s"][:n_bays]})
    return e
