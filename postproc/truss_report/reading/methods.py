"""truss_report.reading.methods: the results a campaign's method writes beside /runs: subset
simulation (/subset), sequential stopping (/stop) and a design sweep (/sweep, its per-value table
as a pandas DataFrame)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import h5py
import numpy as np
import pandas as pd

from .h5file import H5, Array, text


@dataclass
class Stop:
    """/stop: the rule (attrs: target, output, level, width, confidence, max_runs), the state and
    reason of the last round, and one row per round."""
    attrs: dict[str, Any]
    runs: Array
    used: Array
    estimate: Array
    upper: Array
    achieved_width: Array
    unit: str
    rounds_state: list[str]


@dataclass
class Subset:
    """/subset: the failure probability, its CoVs, the levels and the failure samples."""
    attrs: dict[str, Any]         # status, message, failure_column, failure_kind, ... (as stored)
    p: float
    cov: float
    cov_lineage: float
    beta: float
    crude_mc_runs: float
    cov_interval: float           # the CoV of the interval: cov_bound (lineage in older files)
    cov_interval_name: str        # "bound" or "lineage"
    runs: int
    lineages: int
    levels: dict[str, Array]      # threshold, probability, acceptance, runs, unusable, ...
    level_units: str
    failure_runs: Array
    failure_margin: Array
    failure_z: Array              # rows x d
    failure_inputs: dict[str, tuple[Array, float, str]]   # key -> (values, nominal, units)

    @property
    def status(self) -> str:
        return str(self.attrs["status"])


def _attrs(g: h5py.Group) -> dict[str, Any]:
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in g.attrs.items()}


def read_stop(f: h5py.File) -> Stop | None:
    """The /stop group (sequential stopping), or None."""
    if "stop" not in f:
        return None
    g = f["stop"]
    return Stop(attrs=_attrs(g), **{k: g[k][()] for k in ("runs", "used", "estimate", "upper", "achieved_width")},
                unit=text(g["estimate"].attrs["units"]),
                rounds_state=[text(x) for x in g["state"][()]])


def read_subset(h5: H5) -> Subset | None:
    """The /subset group, or None."""
    if not h5.has("subset"):
        return None
    g = h5.f["subset"]
    fs = g["failure_samples"]
    # The CoV of the interval (the larger of Au & Beck's fully correlated bound and the lineage
    # CoV, docs/campaigns.md "Which CoV to read"); a file without it: the lineage CoV.
    has_bound = "cov_bound" in g
    return Subset(
        attrs=_attrs(g), **{k: h5.scalar(f"subset/{k}") for k in ("p", "cov", "cov_lineage", "beta", "crude_mc_runs")},
        cov_interval=h5.scalar("subset/cov_bound" if has_bound else "subset/cov_lineage"),
        cov_interval_name="bound" if has_bound else "lineage",
        runs=int(g["runs"][()]), lineages=int(g["lineages"][()]),
        levels={k: g["levels"][k][()] for k in g["levels"]},
        level_units=text(g["levels/threshold"].attrs["units"]),
        failure_runs=fs["run_index"][()], failure_margin=fs["margin"][()], failure_z=fs["z"][()],
        failure_inputs={k: (fs["inputs"][k][()], float(fs["inputs"][k].attrs.get("nominal", np.nan)),
                            text(fs["inputs"][k].attrs["units"])) for k in fs["inputs"]})


SWEEP_COLUMNS = ("values", "p", "cov", "upper_bound", "lower", "upper", "runs", "failures", "master_seed",
                 "index", "refinement")


@dataclass
class SweepTable:
    """/sweep: the per-value table (a DataFrame: value, p, cov, upper_bound, lower, upper, runs,
    failures, master_seed, index, refinement, status, message; df.attrs the /sweep attributes,
    design_units, units per column and the allowable), and per value the thresholds of its subset
    simulation's levels (None for the other methods)."""
    table: pd.DataFrame
    level_thresholds: list[Array | None]


def read_sweep_table(source: str | h5py.File) -> SweepTable | None:
    """/sweep of a file (path or open h5py.File), or None without one."""
    if not isinstance(source, h5py.File):
        with h5py.File(source, "r") as f:
            return read_sweep_table(f)
    if "sweep" not in source:
        return None
    g = source["sweep"]
    cols: dict[str, Any] = {("value" if k == "values" else k): g[k][()] for k in SWEEP_COLUMNS}
    cols["refinement"] = cols["refinement"].astype(bool)
    cols["status"] = [text(v) for v in g["status"][()]]
    cols["message"] = [text(v) for v in g["message"][()]]
    inner = g["inner"] if "inner" in g else {}
    thresholds = [inner[str(k)]["level_threshold"][()]
                  if str(k) in inner and "level_threshold" in inner[str(k)] else None
                  for k in cols["index"]]
    df = pd.DataFrame(cols)
    df.attrs.update({k: (text(v) if isinstance(v, (bytes, str)) else v) for k, v in g.attrs.items()})
    df.attrs["design_units"] = df.attrs.pop("units")  # the design variable's unit
    df.attrs["units"] = {("value" if k == "values" else k): text(g[k].attrs["units"]) for k in SWEEP_COLUMNS}
    a = g["allowable"]
    allow: dict[str, Any] = {k: text(v) for k, v in a.attrs.items()}
    for k in ("value", "estimate", "lower", "upper", "own_value"):
        allow[k] = float(a[k][()])
    df.attrs["allowable"] = allow
    return SweepTable(df, thresholds)
