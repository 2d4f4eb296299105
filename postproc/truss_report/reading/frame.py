"""truss_report.reading.frame: a campaign file as a pandas DataFrame.

    from truss_report import read_campaign
    df = read_campaign("out/table1_dispersed/table1_dispersed.h5")
    df[df.status == "stall"]
    df.attrs["units"]["peak_drive_force_N"]      # "N"
    read_campaign(path, columns=["peak_drive_force_N", "lock_time_s"])   # and the lock time of every bay

One row per run (index run_index). Columns: `status` (the status names read from the enum type
of /runs/status, as a pandas Categorical in enum order: nothing is hard-coded), `message`, every
1-D dataset of /runs and the per-run inputs as `input:<key>`. The per-bay columns are read on
demand: the /runs/bays fields as `<field>[bay j]` (j = 1 .. n_bays_max) and the per-bay / per-frame
inputs as `input:<key>[bay j]` / `input:<key>[frame k]`, by naming them in `columns` (a field or
an input key gives every bay of it, `lock_time_s[bay 3]` one; `peak_drive_force_N[bay]` the
/runs/bays field of a name that /runs also has), or all of them with
columns="all". A file of 95,200 runs then opens in tens of megabytes, not gigabytes.
df.attrs: `units` (column -> units from the datasets' `units` attributes), `nominal` (the
/nominal values, when the file has them), `bay_columns` (the per-bay fields and inputs not read)
and the root attributes of the file."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import h5py
import numpy as np
import pandas as pd

from .h5file import text


@dataclass
class Source:
    """A dataset of /runs and the columns it gives: one (a per-run dataset) or one per bay or
    frame (a 2-D dataset: `names[j]` is its column j)."""
    path: str
    names: list[str]
    units: str
    wide: bool


def sources(runs: h5py.Group) -> dict[str, Source]:
    """Every column group of /runs by its field name, in the DataFrame's column order."""
    res: dict[str, Source] = {}
    for k, ds in runs.items():
        if isinstance(ds, h5py.Dataset) and ds.ndim == 1 and k not in ("status", "message", "run_index"):
            res[k] = Source(k, [k], text(ds.attrs["units"]), False)
    for key, ds in (runs["inputs"].items() if "inputs" in runs else []):
        name = f"input:{key}"
        if ds.ndim == 1:
            res[name] = Source(f"inputs/{key}", [name], text(ds.attrs["units"]), False)
        else:
            per = text(ds.attrs["per"])
            start = 1 if per == "bay" else 0
            res[name] = Source(f"inputs/{key}", [f"{name}[{per} {j + start}]" for j in range(ds.shape[1])],
                               text(ds.attrs["units"]), True)
    for key, ds in runs["bays"].items():    # "<field>[bay]": a /runs/bays field may share a per-run name
        res[f"{key}[bay]"] = Source(f"bays/{key}", [f"{key}[bay {j + 1}]" for j in range(ds.shape[1])],
                          text(ds.attrs["units"]), True)
    return res


def selection(srcs: dict[str, Source], columns: str | Sequence[str] | None) -> dict[str, list[int]]:
    """{field: the indices of its columns to read}; ValueError naming a column the file lacks."""
    if columns is None or columns == "all":
        return {k: list(range(len(s.names))) for k, s in srcs.items() if columns == "all" or not s.wide}
    by_column = {n: (k, j) for k, s in srcs.items() for j, n in enumerate(s.names)}
    res: dict[str, list[int]] = {}
    for c in [columns] if isinstance(columns, str) else columns:
        if c in ("status", "message"):
            continue
        if c in srcs or f"{c}[bay]" in srcs:
            k = c if c in srcs else f"{c}[bay]"
            res[k] = list(range(len(srcs[k].names)))
        elif c in by_column:
            k, j = by_column[c]
            res.setdefault(k, []).append(j)
        else:
            raise ValueError(f"no column {c!r} in /runs (fields: {', '.join(srcs)})")
    return {k: sorted(set(res[k])) for k in srcs if k in res}


def read_campaign(path: str, columns: str | Sequence[str] | None = None) -> pd.DataFrame:
    """The campaign file at `path` as a DataFrame (see the module's docstring for `columns`)."""
    cols: dict[str, object] = {}
    units: dict[str, str] = {}
    with h5py.File(path, "r") as f:
        if text(f.attrs.get("kind", "")) != "campaign":
            raise ValueError(f"{path}: not a truss-campaign file (kind is not 'campaign')")
        runs = f["runs"]
        enum = h5py.check_enum_dtype(runs["status"].dtype)
        names = [k for k, _ in sorted(enum.items(), key=lambda kv: int(kv[1]))]
        values = sorted(int(v) for v in enum.values())     # names[i] is the member of values[i]
        cols["status"] = pd.Categorical.from_codes(np.searchsorted(values, runs["status"][()]), categories=names)
        units["status"] = "1"
        if columns is None or columns == "all" or "message" in columns:
            cols["message"] = [text(v) for v in runs["message"][()]]
            units["message"] = "1"
        srcs = sources(runs)
        for k, idx in selection(srcs, columns).items():
            src = srcs[k]
            ds = runs[src.path]
            if not src.wide:
                cols[k], units[k] = ds[()], src.units
                continue
            v = ds[()] if len(idx) == len(src.names) else ds[:, idx]
            for n, j in enumerate(idx):
                cols[src.names[j]], units[src.names[j]] = v[:, n], src.units
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
    df.attrs["bay_columns"] = [k for k, src in srcs.items() if src.wide and src.names[0] not in df.columns]
    df.attrs["path"] = path
    return df
