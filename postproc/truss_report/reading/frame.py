"""truss_report.reading.frame: a campaign file as a pandas DataFrame, and the run table as CSV.

    from truss_report import read_campaign
    df = read_campaign("out/table1_dispersed/table1_dispersed.h5")
    df[df.status == "stall"]
    df.attrs["units"]["peak_drive_force_N"]      # "N"

One row per run (index run_index). Columns: `status` (the status names read from the enum type
of /runs/status, as a pandas Categorical in enum order: nothing is hard-coded), `message`, every
1-D dataset of /runs, the inputs as `input:<key>` (per run) or `input:<key>[bay j]` /
`input:<key>[frame k]`, and every /runs/bays field as `<field>[bay j]` (j = 1 .. n_bays_max).
df.attrs: `units` (column -> units from the datasets' `units` attributes), `nominal` (the
/nominal values, when the file has them) and the root attributes of the file."""
from __future__ import annotations

import h5py
import numpy as np
import pandas as pd

from .h5file import text


def read_campaign(path: str) -> pd.DataFrame:
    cols, units = {}, {}
    with h5py.File(path, "r") as f:
        if text(f.attrs.get("kind", "")) != "campaign":
            raise ValueError(f"{path}: not a truss-campaign file (kind is not 'campaign')")
        runs = f["runs"]
        enum = h5py.check_enum_dtype(runs["status"].dtype)
        names = [k for k, _ in sorted(enum.items(), key=lambda kv: int(kv[1]))]
        by_value = {v: k for k, v in enum.items()}
        codes = runs["status"][()]
        cols["status"] = pd.Categorical([by_value[int(v)] for v in codes], categories=names)
        units["status"] = "1"
        cols["message"] = [text(v) for v in runs["message"][()]]
        units["message"] = "1"
        for k, ds in runs.items():
            if isinstance(ds, h5py.Dataset) and ds.ndim == 1 and k not in ("status", "message",
                                                                         "run_index"):
                cols[k] = ds[()]
                units[k] = text(ds.attrs["units"])
        for key, ds in (runs["inputs"].items() if "inputs" in runs else []):
            per = text(ds.attrs["per"])
            v = ds[()]
            if v.ndim == 1:
                name = f"input:{key}"
                cols[name], units[name] = v, text(ds.attrs["units"])
            else:
                start = 1 if per == "bay" else 0
                for j in range(v.shape[1]):
                    name = f"input:{key}[{per} {j + start}]"
                    cols[name], units[name] = v[:, j], text(ds.attrs["units"])
        for key, ds in runs["bays"].items():
            v = ds[()]
            for j in range(v.shape[1]):
                name = f"{key}[bay {j + 1}]"
                cols[name], units[name] = v[:, j], text(ds.attrs["units"])
        attrs = {k: (text(v) if isinstance(v, (bytes, str)) else
                     (v.item() if isinstance(v, np.generic) else v)) for k, v in f.attrs.items()}
        nominal = {}
        if "nominal" in f:
            for k, ds in f["nominal"].items():
                if isinstance(ds, h5py.Dataset) and ds.dtype.kind in "fiu" and k != "status":
                    nominal[k] = ds[()].item()
        index = pd.Index(runs["run_index"][()], name="run_index")
    df = pd.DataFrame(cols, index=index)
    df.attrs.update(attrs)
    df.attrs["units"] = units
    df.attrs["nominal"] = nominal
    df.attrs["path"] = path
    return df
