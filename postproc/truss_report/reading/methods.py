"""truss_report.reading.methods: the results a campaign's method writes beside /runs: subset
simulation (/subset), sequential stopping (/stop) and a design sweep (/sweep, its per-value table
as a pandas DataFrame). Each group is checked as it is read: a missing or malformed member is an
InputError naming the file and the member (the report's one `error:` line, exit 2)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import h5py
import numpy as np
import pandas as pd

from .h5file import H5, AnyArray, Array, InputError, open_h5, text


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
    cov_interval: float           # the CoV of the interval: /subset's interval_cov (lineage in older files)
    cov_interval_name: str        # "bound", "interval" or "lineage"
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


def _require_attrs(h5: H5, g: h5py.Group, names: tuple[str, ...]) -> dict[str, Any]:
    """The attributes of group g, checked to hold every one of `names`."""
    missing = [k for k in names if k not in g.attrs]
    if missing:
        raise h5.error(f"{g.name} lacks the attribute{'s' if len(missing) > 1 else ''} {', '.join(missing)}")
    return _attrs(g)


def _columns(h5: H5, group: str, names: tuple[str, ...], n: int) -> dict[str, AnyArray]:
    """The 1-D numeric datasets group/<name> of one length n each."""
    return {k: h5.numbers(f"{group}/{k}", (n,)) for k in names}


STOP_ATTRS = ("target", "output", "level", "width", "confidence", "max_runs", "state", "reason")


def read_stop(f: h5py.File) -> Stop | None:
    """The /stop group (sequential stopping), or None."""
    if "stop" not in f:
        return None
    h5 = H5(f, f.filename)
    g = h5.group("stop")
    attrs = _require_attrs(h5, g, STOP_ATTRS)
    n = h5.length("stop/runs")
    cols = {k: v.astype(np.float64) for k, v in
            _columns(h5, "stop", ("runs", "used", "estimate", "upper", "achieved_width"), n).items()}
    return Stop(attrs=attrs, **cols, unit=h5.units("stop/estimate"),
                rounds_state=h5.strings("stop/state", (n,)))


SUBSET_ATTRS = ("status", "message", "failure_column", "failure_kind", "margin_units", "n_per_level", "p0")


def read_subset(h5: H5) -> Subset | None:
    """The /subset group, or None."""
    if not h5.has("subset"):
        return None
    attrs = _require_attrs(h5, h5.group("subset"), SUBSET_ATTRS)
    if attrs["failure_kind"] != "margin" and "failure_threshold" not in attrs:
        raise h5.error("/subset lacks the attribute failure_threshold")
    # The CoV of the interval: the one the attribute interval_cov names (cov_bound or cov_interval,
    # docs/campaigns.md "Which CoV to read"); without it cov_bound; a file without that: the lineage CoV.
    g = h5.group("subset")
    rule = h5.attr_str(g, "interval_cov", "attribute of /subset:") if "interval_cov" in g.attrs else "cov_bound"
    has_bound = h5.has(f"subset/{rule}")
    levels = h5.group("subset/levels")
    n_levels = h5.length("subset/levels/threshold")
    scalar = {k: h5.scalar(f"subset/{k}") for k in ("p", "cov", "cov_lineage", "beta", "crude_mc_runs")}
    return Subset(
        attrs, scalar["p"], scalar["cov"], scalar["cov_lineage"], scalar["beta"], scalar["crude_mc_runs"],
        cov_interval=h5.scalar(f"subset/{rule}" if has_bound else "subset/cov_lineage"),
        cov_interval_name=(rule.removeprefix("cov_") if has_bound else "lineage"),
        runs=int(h5.scalar("subset/runs")), lineages=int(h5.scalar("subset/lineages")),
        levels={k: v.astype(np.float64) for k, v in _columns(h5, "subset/levels", tuple(levels), n_levels).items()},
        level_units=h5.units("subset/levels/threshold"), **read_failure_samples(h5))


def read_failure_samples(h5: H5) -> dict[str, Any]:
    """The Subset fields of /subset/failure_samples (failure_runs, failure_margin, failure_z,
    failure_inputs): run_index, margin, z and the inputs, one row per failing sample."""
    g = "subset/failure_samples"
    m = h5.length(f"{g}/run_index")
    z = h5.array(f"{g}/z")
    if z.ndim != 2 or z.shape[0] != m:
        raise h5.error(f"/{g}/z has shape {z.shape}, expected ({m}, inputs)")
    inputs = {}
    for k in h5.group(f"{g}/inputs"):
        ds = h5.dataset(f"{g}/inputs/{k}")
        if ds.ndim not in (1, 2) or ds.shape[0] != m:
            raise h5.error(f"/{g}/inputs/{k} has shape {ds.shape}, expected {m} rows")
        inputs[k] = (h5.array(f"{g}/inputs/{k}"), float(ds.attrs.get("nominal", np.nan)), h5.units(f"{g}/inputs/{k}"))
    return {"failure_runs": h5.array(f"{g}/run_index", (m,)), "failure_margin": h5.array(f"{g}/margin", (m,)),
            "failure_z": z, "failure_inputs": inputs}


SWEEP_COLUMNS = ("values", "p", "cov", "upper_bound", "lower", "upper", "runs", "failures", "master_seed",
                 "index", "refinement")
SWEEP_ATTRS = ("variable", "units", "confidence", "target_probability", "inner_method", "failure_column",
               "failure_kind")
ALLOWABLE_ATTRS = ("status", "verdict", "message", "method", "safe_side")
ALLOWABLE_VALUES = ("value", "estimate", "lower", "upper", "own_value")
SWEEP_VERDICTS = ("PASS", "FAIL", "NOT ASSESSED")


@dataclass
class SweepRuns:
    """Per run of /runs: its design value (/runs/sweep_value), its status (codes and the enum's
    names) and its failure margin (/runs/<failure_column>; None when the file has no such column)."""
    value: Array
    status: AnyArray
    status_name: dict[int, str]
    margin: Array | None


@dataclass
class SweepTable:
    """/sweep: the per-value table (a DataFrame: value, p, cov, upper_bound, lower, upper, runs,
    failures, master_seed, index, refinement, status, message; df.attrs the /sweep attributes,
    design_units, units per column and the allowable), per value the thresholds of its subset
    simulation's levels (None for the other methods), and the runs the file's verdict rests on
    (None when the file has no /runs/sweep_value)."""
    table: pd.DataFrame
    level_thresholds: list[Array | None]
    runs: SweepRuns | None = None


def read_sweep_table(source: str | h5py.File) -> SweepTable | None:
    """/sweep of a file (path or open h5py.File), or None without one (InputError when it is
    malformed)."""
    if not isinstance(source, h5py.File):
        with open_h5(source) as f:
            return read_sweep_table(f)
    if "sweep" not in source:
        return None
    h5 = H5(source, source.filename)
    g = h5.group("sweep")
    at = _require_attrs(h5, g, SWEEP_ATTRS)
    n = h5.length("sweep/values")
    cols: dict[str, Any] = {("value" if k == "values" else k): v
                            for k, v in _columns(h5, "sweep", SWEEP_COLUMNS, n).items()}
    cols["refinement"] = cols["refinement"].astype(bool)
    cols["status"] = h5.strings("sweep/status", (n,))
    cols["message"] = h5.strings("sweep/message", (n,))
    df = pd.DataFrame(cols)
    df.attrs.update({k: (text(v) if isinstance(v, (bytes, str)) else v) for k, v in at.items()})
    df.attrs["design_units"] = df.attrs.pop("units")  # the design variable's unit
    df.attrs["units"] = {("value" if k == "values" else k): h5.units(f"sweep/{k}") for k in SWEEP_COLUMNS}
    df.attrs["allowable"] = read_allowable(h5)
    return SweepTable(df, read_thresholds(h5, [int(k) for k in cols["index"]]),
                      read_sweep_runs(h5, str(df.attrs["failure_column"])))


def read_allowable(h5: H5) -> dict[str, Any]:
    """/sweep/allowable: its attributes (the verdict one of SWEEP_VERDICTS) and its five numbers."""
    allow: dict[str, Any] = {k: text(v) for k, v in _require_attrs(h5, h5.group("sweep/allowable"),
                                                                   ALLOWABLE_ATTRS).items()}
    if allow["verdict"] not in SWEEP_VERDICTS:
        raise h5.error(f"/sweep/allowable has verdict {allow['verdict']!r}, expected one of {', '.join(SWEEP_VERDICTS)}")
    for k in ALLOWABLE_VALUES:
        allow[k] = h5.scalar(f"sweep/allowable/{k}")
    return allow


def read_thresholds(h5: H5, index: list[int]) -> list[Array | None]:
    """Per design value: the thresholds of its subset simulation's levels. Each value's method
    writes its own results under /sweep/inner/<k> (subset simulation: its /subset there, as the
    standalone campaign's at the root)."""
    res: list[Array | None] = []
    for k in index:
        name = f"sweep/inner/{k}/subset/levels/threshold"
        res.append(h5.array(name, (h5.length(name),)) if h5.has(name) else None)
    return res


def read_sweep_runs(h5: H5, failure_column: str) -> SweepRuns | None:
    """The runs of a sweep (None when the file has no /runs/sweep_value)."""
    if not h5.has("runs/sweep_value"):
        return None
    n = h5.length("runs/status")
    margin = h5.array(f"runs/{failure_column}", (n,)) if h5.has(f"runs/{failure_column}") else None
    return SweepRuns(h5.array("runs/sweep_value", (n,)), h5.numbers("runs/status", (n,)).astype(np.int64),
                     h5.status_enum("runs/status"), margin)


def read_method_groups(h5: H5) -> tuple[Subset | None, SweepTable | None]:
    """/subset and /sweep of an open campaign file (InputError when one is malformed)."""
    try:
        return read_subset(h5), read_sweep_table(h5.f)
    except (KeyError, ValueError, TypeError) as e:   # a member of the wrong kind (a group for a dataset)
        raise InputError(f"{h5.path}: malformed method group ({e})") from None
