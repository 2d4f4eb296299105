"""truss_report.reading.campaign: a campaign file (truss-campaign -o RESULTS.h5) read and checked
into a Campaign: the root attributes, /runs (status, messages, the reported outputs, lock times,
inputs), /stats, /sensitivity, /histories and /stop. Everything the campaign report needs is read
and checked here, before anything is written."""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .h5file import H5, Array, BoolArray, IntArray, scene_table
from .methods import Stop, read_stop
from .run import HISTORY_FIELDS, RunHistory
from .schema import (LOCK_STATS_FIELDS, OUTPUTS, ROOT_ATTRS_INT, ROOT_ATTRS_STR, STATS_FIELDS)

# Parameters of each distribution, as attributes of /runs/inputs/<key>.
DISTRIBUTION_PARAMS = {"normal": ["mean", "std"], "truncated_normal": ["mean", "std", "lower", "upper"],
                       "uniform": ["lower", "upper"], "lognormal": ["mu", "sigma"],
                       "discrete": ["values", "weights"]}


@dataclass
class Dispersion:
    key: str
    per: str              # run, bay or frame
    apply: str            # absolute, relative or offset
    distribution: str
    params: dict[str, Any]  # distribution parameters (floats; arrays for discrete)
    nominal: float
    units: str
    factor: int
    values: Array         # n, or n x columns


@dataclass
class SobolOutput:
    """/sensitivity/<output>: the indices (first_order, total and their _lo, _hi bounds, one per
    factor) and how the campaign estimated them."""
    indices: dict[str, Array]
    n_blocks: int
    n_blocks_dropped: int
    n_resamples: int
    confidence: float
    method: str


@dataclass
class Sensitivity:
    factor: list[str]
    outputs: dict[str, SobolOutput]


@dataclass
class Campaign:
    path: str
    sha256: str
    attrs: dict[str, Any]         # ROOT_ATTRS_STR (str) and ROOT_ATTRS_INT (int)
    wall_time_s: float
    base_scene: dict[str, Any]
    status: IntArray              # int codes, n
    status_name: dict[int, str]   # code -> name (from the enum type)
    messages: list[str]
    outputs: dict[str, Array]     # name -> float64 array n
    units: dict[str, str]         # name -> units of the output
    lock: Array                   # n x n_bays_max
    dispersions: list[Dispersion]
    stats_attrs: dict[str, int]
    stats: dict[str, dict[str, float]]   # output -> {field: value}
    stats_lock: dict[str, Array]         # field -> array n_bays_max
    stats_status_names: list[str]
    stats_status_counts: IntArray
    stall_torque: Array | None = None    # motor drive: stall torque of every run (N m)
    stall_torque_dispersed: bool = False  # ... from /runs/inputs (else the base scene's)
    # velocity drive: the scene's motor torque at the prescribed speed, per run, as the simulator
    # computed it from its motor law (/runs/motor_torque_at_speed_Nm); None in older files
    motor_torque_at_speed: Array | None = None
    # free stack: closest approach of a missing hinge to the rail (NaN unless rail miss)
    rail_approach: Array | None = None
    rail_approach_unit: str = ""
    sensitivity: Sensitivity | None = None
    histories: dict[int, RunHistory] = field(default_factory=dict)
    stop: Stop | None = None      # sequential stopping (/stop)

    @property
    def n(self) -> int:
        return len(self.status)

    @property
    def ok(self) -> BoolArray:
        return np.asarray(self.status == 0)

    @property
    def name(self) -> str:
        return str(self.attrs["campaign_name"])

    @property
    def direction(self) -> str:
        return str(self.attrs["direction"])

    @property
    def drive_mode(self) -> str:
        return str(self.attrs["drive_mode"])

    @property
    def sampling(self) -> str:
        return str(self.attrs["sampling"])

    @property
    def drive(self) -> dict[str, Any]:
        """The [drive] table of the base scene ({} without one)."""
        return scene_table(self.base_scene, "drive")

    def status_mask(self, name: str) -> BoolArray:
        """The runs whose status is `name`."""
        return np.isin(self.status, [k for k, v in self.status_name.items() if v == name])


def load_campaign(h5: H5, sha256: str) -> Campaign:
    f = h5.f
    a: dict[str, Any] = {name: h5.attr_str(f, name) for name in ROOT_ATTRS_STR}
    for name in ROOT_ATTRS_INT:
        a[name] = h5.attr_int(f, name)
    wall = h5.attr_float(f, "wall_time_s")
    n, nb = int(a["n_runs"]), int(a["n_bays_max"])
    if n < 1 or nb < 1:
        raise h5.error(f"n_runs = {n} and n_bays_max = {nb} must be positive")
    try:
        base_scene = tomllib.loads(a["base_scene_toml"])
    except tomllib.TOMLDecodeError as e:
        raise h5.error(f"root attribute base_scene_toml is not valid TOML ({e})") from None

    if not np.array_equal(h5.array("runs/run_index", (n,)), np.arange(n)):
        raise h5.error("/runs/run_index is not 0 .. n_runs-1")
    names = h5.status_enum("runs/status")
    if 0 not in names or names[0] != "ok":
        raise h5.error("the /runs/status enum has no member 'ok' = 0")
    status = h5.array("runs/status", (n,)).astype(np.int64)
    unknown = sorted(set(status.tolist()) - set(names))
    if unknown:
        raise h5.error(f"/runs/status holds values outside its enum: {unknown}")
    messages = h5.strings("runs/message", (n,))
    outputs = {k: h5.array(f"runs/{k}", (n,)) for k in OUTPUTS}
    units = {k: h5.units(f"runs/{k}") for k in OUTPUTS}
    lock = h5.array("runs/bays/lock_time_s", (n, nb))
    units["lock_time_s"] = h5.units("runs/bays/lock_time_s")
    dispersions = []
    if h5.has("runs/inputs"):
        for key in f["runs/inputs"]:
            dispersions.append(read_dispersion(h5, key, n, nb))
    dispersions.sort(key=lambda d: d.factor)
    c = Campaign(path=h5.path, sha256=sha256, attrs=a, wall_time_s=wall, base_scene=base_scene,
                 status=status, status_name=names, messages=messages, outputs=outputs, units=units,
                 lock=lock, dispersions=dispersions, **read_stats(h5, nb))
    read_optional(h5, c)
    return c


def read_stats(h5: H5, nb: int) -> dict[str, Any]:
    """The Campaign fields read from /stats."""
    if not h5.has("stats"):
        raise h5.error("missing required group /stats")
    stats_attrs = {k: h5.attr_int(h5.f["stats"], k, "attribute of /stats:")
                   for k in ("n_runs", "n_ok", "n_failed")}
    stats = {k: {s: h5.scalar(f"stats/{k}/{s}") for s in STATS_FIELDS} for k in OUTPUTS}
    stats_lock = {s: h5.array(f"stats/bays/lock_time_s/{s}", (nb,)) for s in LOCK_STATS_FIELDS}
    names_ds = h5.dataset("stats/status_names")
    if names_ds.ndim != 1:
        raise h5.error(f"/stats/status_names has shape {names_ds.shape}, expected 1-D")
    n_status = names_ds.shape[0]
    return {"stats_attrs": stats_attrs, "stats": stats, "stats_lock": stats_lock,
            "stats_status_names": h5.strings("stats/status_names", (n_status,)),
            "stats_status_counts": h5.array("stats/status_counts", (n_status,)).astype(np.int64)}


def read_optional(h5: H5, c: Campaign) -> None:
    """What only some campaigns have: the motor's torques, the rail-miss approach, /sensitivity,
    /histories, /stop."""
    n = c.n
    if c.drive_mode == "motor":
        c.stall_torque, c.stall_torque_dispersed = stall_torque_per_run(h5, c)
    if h5.has("runs/motor_torque_at_speed_Nm"):
        c.motor_torque_at_speed = h5.array("runs/motor_torque_at_speed_Nm", (n,))
    if h5.has("runs/rail_miss_closest_approach_m"):
        c.rail_approach = h5.array("runs/rail_miss_closest_approach_m", (n,))
        c.rail_approach_unit = h5.units("runs/rail_miss_closest_approach_m")
    if h5.has("sensitivity"):
        c.sensitivity = read_sensitivity(h5)
    if h5.has("histories"):
        c.histories = read_histories(h5, c)
    c.stop = read_stop(h5.f)


def stall_torque_per_run(h5: H5, c: Campaign) -> tuple[Array, bool]:
    """The stall torque of every run (N m), and whether it is dispersed (motor drive)."""
    for d in c.dispersions:
        if d.key == "drive.stall_torque_Nm":
            if d.per != "run":
                raise h5.error("/runs/inputs/drive.stall_torque_Nm is not per run")
            return d.values, True
    value = c.drive.get("stall_torque_Nm")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise h5.error("drive_mode is motor, but base_scene_toml has no drive.stall_torque_Nm")
    return np.full(c.n, float(value)), False


def read_dispersion(h5: H5, key: str, n: int, nb: int) -> Dispersion:
    name = f"runs/inputs/{key}"
    ds = h5.dataset(name)
    where = f"attribute of /{name}:"
    per = h5.attr_str(ds, "per", where)
    width = {"run": None, "bay": nb, "frame": nb + 1}
    if per not in width:
        raise h5.error(f"/{name} has per = '{per}', expected run, bay or frame")
    w = width[per]
    shape = (n,) if w is None else (n, w)
    dist = h5.attr_str(ds, "distribution", where)
    if dist not in DISTRIBUTION_PARAMS:
        raise h5.error(f"/{name} has an unknown distribution '{dist}'")
    params: dict[str, Any] = {p: (h5.attr_array(ds, p, where) if dist == "discrete"
                                  else h5.attr_float(ds, p, where)) for p in DISTRIBUTION_PARAMS[dist]}
    return Dispersion(key=key, per=per, apply=h5.attr_str(ds, "apply", where),
                      distribution=dist, params=params,
                      nominal=h5.attr_float(ds, "nominal", where),
                      units=h5.attr_str(ds, "units", where),
                      factor=h5.attr_int(ds, "factor", where),
                      values=h5.array(name, shape))


def read_sensitivity(h5: H5) -> Sensitivity:
    factors = h5.strings("sensitivity/factor", h5.dataset("sensitivity/factor").shape)
    G = len(factors)
    res = Sensitivity(factors, {})
    for out in OUTPUTS:
        if not h5.has(f"sensitivity/{out}"):
            raise h5.error(f"missing required group /sensitivity/{out}")
        g = h5.f[f"sensitivity/{out}"]
        where = f"attribute of /sensitivity/{out}:"
        res.outputs[out] = SobolOutput(
            indices={k: h5.array(f"sensitivity/{out}/{k}", (G,))
                     for k in ("first_order", "first_order_lo", "first_order_hi",
                               "total", "total_lo", "total_hi")},
            n_blocks=h5.attr_int(g, "n_blocks", where),
            n_blocks_dropped=h5.attr_int(g, "n_blocks_dropped", where),
            n_resamples=h5.attr_int(g, "n_resamples", where),
            confidence=h5.attr_float(g, "confidence", where),
            method=h5.attr_str(g, "method", where))
    return res


def read_histories(h5: H5, c: Campaign) -> dict[int, RunHistory]:
    """{run index: its histories} for every /histories/run_<i>."""
    res = {}
    for name in h5.f["histories"]:
        m = re.fullmatch(r"run_(\d+)", name)
        if not m or int(m.group(1)) >= c.n:
            raise h5.error(f"/histories/{name} does not name a run (run_0 .. run_{c.n - 1})")
        i = int(m.group(1))
        hist, units = {}, {}
        for fld in HISTORY_FIELDS:
            hist[fld] = h5.array(f"histories/{name}/{fld}")
            units[fld] = h5.units(f"histories/{name}/{fld}")
        if len({v.shape for v in hist.values()}) != 1 or hist["t_s"].ndim != 1:
            raise h5.error(f"the datasets of /histories/{name} are not 1-D of one length")
        hist["bay"] = hist["bay"].astype(np.int64)
        n_bays = int(h5.array("runs/n_bays", (c.n,))[i])
        res[i] = RunHistory(path=f"run {i}", n_bays=n_bays, history=hist, units=units,
                            drive_mode=c.drive_mode, direction=c.direction,
                            stack_mode=scene_table(c.base_scene, "stack").get("mode"),
                            status=c.status_name[int(c.status[i])],
                            bays={"lock_time_s": c.lock[i, :n_bays]})
    return dict(sorted(res.items()))
