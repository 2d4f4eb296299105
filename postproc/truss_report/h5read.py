"""truss_report.h5read: see the package docstring (postproc/truss_report/__init__.py)."""
import hashlib
import re
import tomllib
from dataclasses import dataclass, field

import numpy as np

import run_figures as rf
from run_figures import InputError
from .constants import OUTPUTS, ROOT_ATTRS_INT, ROOT_ATTRS_STR, SCHEMA_VERSIONS, STATS_FIELDS


class H5:
    """An open HDF5 file and its path; reads that raise InputError naming the file."""

    def __init__(self, f, path):
        self.f, self.path = f, path

    def error(self, what):
        return InputError(f"{self.path}: {what}")

    def has(self, name):
        return name in self.f

    def attr(self, obj, name, kind, where="root attribute"):
        if name not in obj.attrs:
            raise self.error(f"missing {where} {name}")
        value = obj.attrs[name]
        try:
            if kind is str:
                return rf._text(value)
            if kind is int:
                return rf._scalar_int(value, f"{where} {name}")
            arr = np.asarray(value, dtype=np.float64)
            return float(arr.reshape(())) if arr.size == 1 and kind is float else arr
        except (InputError, ValueError, TypeError, UnicodeDecodeError) as e:
            raise self.error(f"{where} {name} is malformed ({e})") from None

    def dataset(self, name, shape=None):
        """The dataset /name (an h5py Dataset); checks it exists and has the given shape."""
        import h5py
        if name not in self.f or not isinstance(self.f[name], h5py.Dataset):
            raise self.error(f"missing required dataset /{name}")
        ds = self.f[name]
        if shape is not None and ds.shape != tuple(shape):
            raise self.error(f"/{name} has shape {ds.shape}, expected {tuple(shape)}")
        return ds

    def array(self, name, shape=None):
        ds = self.dataset(name, shape)
        if ds.dtype.kind not in "fiu":
            raise self.error(f"/{name} is not numeric (dtype {ds.dtype})")
        return np.asarray(ds[()], dtype=np.float64)

    def strings(self, name, shape):
        ds = self.dataset(name, shape)
        if ds.dtype.kind not in "OS":
            raise self.error(f"/{name} is not a string dataset (dtype {ds.dtype})")
        return [rf._text(v) for v in np.asarray(ds[()], dtype=object).ravel()]

    def attr_or(self, obj, name, default):
        """A descriptive string attribute; `default` when the file does not have it."""
        return self.attr(obj, name, str) if name in obj.attrs else default

    def units(self, name):
        ds = self.dataset(name)
        return self.attr(ds, "units", str, f"attribute of /{name}:")


def read_kind(h5):
    if "schema_version" not in h5.f.attrs:
        raise h5.error("no root attribute schema_version: not a truss-sim/truss-campaign file")
    version = h5.attr(h5.f, "schema_version", int)
    kind = h5.attr(h5.f, "kind", str)
    if kind not in SCHEMA_VERSIONS:
        raise h5.error(f"kind is '{kind}'; this report reads 'campaign' and 'single_run' files")
    if version not in SCHEMA_VERSIONS[kind]:
        readable = " and ".join(str(v) for v in SCHEMA_VERSIONS[kind])
        raise h5.error(f"schema_version is {version}; this report reads {kind} files of schema_version "
                       f"{readable}")
    return kind


def status_enum(h5, name):
    """{value: name} of the RunStatus enum dataset /name."""
    import h5py
    enum = h5py.check_enum_dtype(h5.dataset(name).dtype)
    if not enum:
        raise h5.error(f"/{name} is not an HDF5 enum dataset")
    return {int(v): k for k, v in enum.items()}


@dataclass
class Dispersion:
    key: str
    per: str              # run, bay or frame
    apply: str            # absolute, relative or offset
    distribution: str
    params: dict          # distribution parameters (floats, or arrays for discrete)
    nominal: float
    units: str
    factor: int
    values: np.ndarray    # n, or n x columns


@dataclass
class Campaign:
    path: str
    sha256: str
    attrs: dict
    wall_time_s: float
    base_scene: dict
    status: np.ndarray            # int codes, n
    status_name: dict             # code -> name (from the enum type)
    messages: list
    outputs: dict                 # name -> float64 array n
    units: dict                   # name -> units of the output
    lock: np.ndarray              # n x n_bays_max
    dispersions: list
    stats_attrs: dict
    stats: dict                   # output -> {field: value}
    stats_lock: dict              # field -> array n_bays_max
    stats_status_names: list
    stats_status_counts: np.ndarray
    stall_torque: np.ndarray = None   # motor drive: stall torque of every run (Nm)
    # velocity drive: the scene's motor torque at the prescribed speed, per run, as the simulator
    # computed it from its motor law (/runs/motor_torque_at_speed_Nm); None in older files
    motor_torque_at_speed: np.ndarray = None
    stall_torque_source: str = ""
    # free stack: closest approach of a missing hinge to the rail (NaN unless rail miss)
    rail_approach: np.ndarray = None
    rail_approach_unit: str = ""
    sensitivity: dict = None
    histories: dict = field(default_factory=dict)

    @property
    def n(self):
        return len(self.status)

    @property
    def ok(self):
        return self.status == 0


def load_campaign(h5, sha256):
    f, a = h5.f, {}
    for name in ROOT_ATTRS_STR:
        a[name] = h5.attr(f, name, str)
    for name in ROOT_ATTRS_INT:
        a[name] = h5.attr(f, name, int)
    wall = h5.attr(f, "wall_time_s", float)
    n, nb = a["n_runs"], a["n_bays_max"]
    if n < 1 or nb < 1:
        raise h5.error(f"n_runs = {n} and n_bays_max = {nb} must be positive")
    try:
        base_scene = tomllib.loads(a["base_scene_toml"])
    except tomllib.TOMLDecodeError as e:
        raise h5.error(f"root attribute base_scene_toml is not valid TOML ({e})") from None

    if not np.array_equal(h5.array("runs/run_index", (n,)), np.arange(n)):
        raise h5.error("/runs/run_index is not 0 .. n_runs-1")
    names = status_enum(h5, "runs/status")
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

    if not h5.has("stats"):
        raise h5.error("missing required group /stats")
    stats_attrs = {k: h5.attr(f["stats"], k, int, "attribute of /stats:")
                   for k in ("n_runs", "n_ok", "n_failed")}
    stats = {k: {s: float(h5.array(f"stats/{k}/{s}", ())) for s in STATS_FIELDS}
             for k in OUTPUTS}
    stats_lock = {s: h5.array(f"stats/bays/lock_time_s/{s}", (nb,))
                  for s in ("count", "p5", "p50", "p95")}
    names_ds = h5.dataset("stats/status_names")
    if names_ds.ndim != 1:
        raise h5.error(f"/stats/status_names has shape {names_ds.shape}, expected 1-D")
    n_status = names_ds.shape[0]
    c = Campaign(
        path=h5.path, sha256=sha256, attrs=a, wall_time_s=wall, base_scene=base_scene,
        status=status, status_name=names, messages=messages, outputs=outputs, units=units,
        lock=lock, dispersions=dispersions, stats_attrs=stats_attrs, stats=stats,
        stats_lock=stats_lock,
        stats_status_names=h5.strings("stats/status_names", (n_status,)),
        stats_status_counts=h5.array("stats/status_counts", (n_status,)).astype(np.int64))
    if a["drive_mode"] == "motor":
        c.stall_torque, c.stall_torque_source = stall_torque_per_run(h5, c)
    if h5.has("runs/motor_torque_at_speed_Nm"):
        c.motor_torque_at_speed = h5.array("runs/motor_torque_at_speed_Nm", (n,))
    if h5.has("runs/rail_miss_closest_approach_m"):
        c.rail_approach = h5.array("runs/rail_miss_closest_approach_m", (n,))
        c.rail_approach_unit = h5.units("runs/rail_miss_closest_approach_m")
    if h5.has("sensitivity"):
        c.sensitivity = read_sensitivity(h5)
    if h5.has("histories"):
        c.histories = read_histories(h5, c)
    return c


def stall_torque_per_run(h5, c):
    """The stall torque of every run (Nm) and where it comes from (motor drive)."""
    for d in c.dispersions:
        if d.key == "drive.stall_torque_Nm":
            if d.per != "run":
                raise h5.error("/runs/inputs/drive.stall_torque_Nm is not per run")
            return d.values, ("dispersed: per run from "
                              "<code>/runs/inputs/drive.stall_torque_Nm</code>")
    value = (c.base_scene.get("drive") or {}).get("stall_torque_Nm")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise h5.error("drive_mode is motor, but base_scene_toml has no drive.stall_torque_Nm")
    return (np.full(c.n, float(value)),
            "not dispersed: <code>drive.stall_torque_Nm</code> of the base scene")


def read_dispersion(h5, key, n, nb):
    name = f"runs/inputs/{key}"
    ds = h5.dataset(name)
    where = f"attribute of /{name}:"
    per = h5.attr(ds, "per", str, where)
    width = {"run": None, "bay": nb, "frame": nb + 1}
    if per not in width:
        raise h5.error(f"/{name} has per = '{per}', expected run, bay or frame")
    shape = (n,) if width[per] is None else (n, width[per])
    dist = h5.attr(ds, "distribution", str, where)
    param_names = {"normal": ["mean", "std"], "truncated_normal": ["mean", "std", "lower", "upper"],
                   "uniform": ["lower", "upper"], "lognormal": ["mu", "sigma"],
                   "discrete": ["values", "weights"]}
    if dist not in param_names:
        raise h5.error(f"/{name} has an unknown distribution '{dist}'")
    params = {p: h5.attr(ds, p, float if dist != "discrete" else np.ndarray, where)
              for p in param_names[dist]}
    return Dispersion(key=key, per=per, apply=h5.attr(ds, "apply", str, where),
                      distribution=dist, params=params,
                      nominal=h5.attr(ds, "nominal", float, where),
                      units=h5.attr(ds, "units", str, where),
                      factor=h5.attr(ds, "factor", int, where),
                      values=h5.array(name, shape))


def read_sensitivity(h5):
    factors = h5.strings("sensitivity/factor", h5.dataset("sensitivity/factor").shape)
    G = len(factors)
    res = {"factor": factors, "outputs": {}}
    for out in OUTPUTS:
        if not h5.has(f"sensitivity/{out}"):
            raise h5.error(f"missing required group /sensitivity/{out}")
        g = h5.f[f"sensitivity/{out}"]
        where = f"attribute of /sensitivity/{out}:"
        res["outputs"][out] = {
            **{k: h5.array(f"sensitivity/{out}/{k}", (G,))
               for k in ("first_order", "first_order_lo", "first_order_hi",
                         "total", "total_lo", "total_hi")},
            "n_blocks": h5.attr(g, "n_blocks", int, where),
            "n_blocks_dropped": h5.attr(g, "n_blocks_dropped", int, where),
            "n_resamples": h5.attr(g, "n_resamples", int, where),
            "confidence": h5.attr(g, "confidence", float, where),
            "method": h5.attr(g, "method", str, where)}
    return res


def read_histories(h5, c):
    """{run index: run dict in run_figures' layout} for every /histories/run_<i>."""
    res = {}
    for name in h5.f["histories"]:
        m = re.fullmatch(r"run_(\d+)", name)
        if not m or int(m.group(1)) >= c.n:
            raise h5.error(f"/histories/{name} does not name a run (run_0 .. run_{c.n - 1})")
        i = int(m.group(1))
        hist, units = {}, {}
        for fld in rf.HISTORY_FIELDS:
            hist[fld] = h5.array(f"histories/{name}/{fld}")
            units[fld] = h5.units(f"histories/{name}/{fld}")
        if len({v.shape for v in hist.values()}) != 1 or hist["t_s"].ndim != 1:
            raise h5.error(f"the datasets of /histories/{name} are not 1-D of one length")
        hist["bay"] = hist["bay"].astype(np.int64)
        n_bays = int(h5.array("runs/n_bays", (c.n,))[i])
        res[i] = {"path": f"run {i}", "n_bays": n_bays, "history": hist, "units": units,
                  "drive_mode": c.attrs["drive_mode"], "direction": c.attrs["direction"],
                  "stack_mode": (c.base_scene.get("stack") or {}).get("mode"),
                  "status": c.status_name[int(c.status[i])],
                  "bays": {"lock_time_s": c.lock[i, :n_bays]}}
    return dict(sorted(res.items()))


def file_sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def load_single_run(h5, sha256):
    """Everything the single-run report shows, read into memory (InputError on bad layout)."""
    import h5py
    names = status_enum(h5, "summary/status")
    code = int(h5.array("summary/status", ()))
    if code not in names:
        raise h5.error(f"/summary/status = {code} is not in its enum")
    run = {"path": h5.path, "sha256": sha256, "status": names[code],
           "message": h5.attr_or(h5.dataset("summary/status"), "message", ""),
           "scene_toml": h5.attr(h5.f, "scene_toml", str),
           **{k: h5.attr_or(h5.f, k, "(not recorded)")
              for k in ("software_version", "git_revision", "created_utc")},
           "summary": [], "bays": {}, "bay_units": {}, "figures": None}
    for name in sorted(h5.f["summary"]):
        if name == "status" or not isinstance(h5.f["summary"][name], h5py.Dataset):
            continue
        ds = h5.dataset(f"summary/{name}", ())
        u = h5.units(f"summary/{name}")
        if ds.dtype.kind in "OS":
            run["summary"].append((name, rf._text(ds[()]), u))
        else:
            v = ds[()]
            run["summary"].append((name, int(v) if ds.dtype.kind in "iu" else float(v), u))
    if h5.has("bays"):
        bay = h5.array("bays/bay").astype(np.int64)
        run["bays"]["bay"] = bay
        for k in sorted(h5.f["bays"]):
            if k != "bay":
                run["bays"][k] = h5.array(f"bays/{k}", bay.shape)
                run["bay_units"][k] = h5.units(f"bays/{k}")
    if h5.has("history"):
        run["figures"] = rf.load_run(h5.path)
    return run
