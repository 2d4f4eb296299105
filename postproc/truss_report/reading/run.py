"""truss_report.reading.run: a single-run file (truss-sim -o RUN.h5): its histories for the
paper's figures (RunHistory), and everything the single-run report shows (SingleRunFile)."""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from typing import Any

import h5py
import numpy as np

from .h5file import H5, AnyArray, Array, InputError, open_h5, scalar_int, scene_table, text, units_or

SCHEMA_VERSION = 1

# History fields the figures plot, with the units assumed when a dataset has no `units`.
HISTORY_FIELDS = {
    "t_s": "s",
    "bay": "",
    "hinge_x_m": "m",
    "hinge_y_m": "m",
    "drive_force_N": "N",
    "pin_force_N": "N",
}


@dataclass
class RunHistory:
    """One run's time histories and per-bay events, as the figures draw them (a single-run file,
    a campaign's /histories/run_<i> or its nominal run)."""
    path: str                     # the file, or "run i" / "nominal run"
    n_bays: int
    history: dict[str, AnyArray]  # HISTORY_FIELDS (bay as integers), frame_height_m (free stack)
    units: dict[str, str]
    drive_mode: str
    direction: str
    stack_mode: str | None
    status: str | None
    bays: dict[str, Array]        # lock_time_s, entry_time_s, bay (when the file has them)
    rail_x: float = float("nan")
    rail_y: float = float("nan")
    rail_beta_deg: float = float("nan")


@dataclass
class SingleRunFile:
    """Everything the single-run report shows."""
    path: str
    sha256: str
    status: str
    message: str
    scene_toml: str
    software_version: str
    git_revision: str
    created_utc: str
    summary: list[tuple[str, str | int | float, str]] = field(default_factory=list)  # name, value, units
    bays: dict[str, AnyArray] = field(default_factory=dict)   # "bay" (integers) and the per-bay fields
    bay_units: dict[str, str] = field(default_factory=dict)
    figures: RunHistory | None = None


def scene_value(scene: dict[str, Any], table: str, key: str, kind: type) -> Any:
    tab = scene.get(table)
    if not isinstance(tab, dict) or key not in tab:
        raise InputError(f"scene_toml has no {table}.{key}")
    v = tab[key]
    if kind is float and isinstance(v, (int, float)) and not isinstance(v, bool):
        return float(v)
    if kind is int and isinstance(v, int) and not isinstance(v, bool):
        return v
    if kind is str and isinstance(v, str):
        return v
    raise InputError(f"scene_toml {table}.{key} has the wrong type: {v!r}")


def load_run(path: str) -> RunHistory:
    """Read what the figures need from RUN.h5; raise InputError on any layout problem."""
    with open_h5(path) as f:
        scene = read_scene(f, path)
        n_bays = scene_value(scene, "mast", "n_bays", int)
        rail = [scene_value(scene, "rail", k, float) for k in ("x_m", "y_m", "beta_deg")]
        run = RunHistory(path=path, n_bays=n_bays, history={}, units={},
                         drive_mode=scene_value(scene, "drive", "mode", str),
                         direction=scene_value(scene, "run", "direction", str),
                         stack_mode=scene_table(scene, "stack").get("mode"), status=None, bays={},
                         rail_x=rail[0], rail_y=rail[1], rail_beta_deg=rail[2])
        if run.n_bays < 1:
            raise InputError(f"scene_toml mast.n_bays = {run.n_bays} is not positive")
        if not 0.0 < run.rail_beta_deg < 90.0:
            raise InputError(f"scene_toml rail.beta_deg = {run.rail_beta_deg} is not in (0, 90)")
        read_history(f, path, run)
        run.bays = read_bay_events(f, run.n_bays)
        run.status = read_status_name(f)
    return run


def read_scene(f: h5py.File, path: str) -> dict[str, Any]:
    """The checked root attributes of a single-run file and its scene_toml, parsed."""
    attrs = f.attrs
    if "schema_version" not in attrs:
        raise InputError(f"{path} has no root attribute schema_version: not a truss-sim file")
    version = scalar_int(attrs["schema_version"], "root attribute schema_version")
    if version != SCHEMA_VERSION:
        raise InputError(
            f"{path} has schema_version {version}; this script reads schema_version "
            f"{SCHEMA_VERSION}")
    if "kind" in attrs:
        kind = text(attrs["kind"])
        if kind != "single_run":
            raise InputError(f"{path} is a '{kind}' file, not a 'single_run' file")
    if "scene_toml" not in attrs:
        raise InputError(f"{path} has no root attribute scene_toml")
    try:
        return tomllib.loads(text(attrs["scene_toml"]))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"root attribute scene_toml is not valid TOML: {e}") from None


def read_history(f: h5py.File, path: str, run: RunHistory) -> None:
    """/history into run.history and run.units (checked: 1-D, one length, not empty)."""
    if "history" not in f or not isinstance(f["history"], h5py.Group):
        raise InputError(
            f"{path} has no /history: run truss-sim with run.output_step_s > 0")
    hist = f["history"]
    h: dict[str, Any] = {}
    for name, default in HISTORY_FIELDS.items():
        if name not in hist:
            raise InputError(f"{path} has no /history/{name}")
        ds = hist[name]
        if not isinstance(ds, h5py.Dataset) or ds.ndim != 1:
            raise InputError(f"/history/{name} is not a 1-D dataset")
        h[name] = ds[()]
        run.units[name] = units_or(ds, default)
    lengths = {len(v) for v in h.values()}
    if len(lengths) != 1:
        raise InputError("the /history datasets have different lengths: "
                         + ", ".join(f"{k} {len(v)}" for k, v in h.items()))
    if lengths.pop() == 0:
        raise InputError(
            f"{path} has an empty /history: run truss-sim with run.output_step_s > 0")
    for name in HISTORY_FIELDS:
        h[name] = np.asarray(h[name]).astype(np.int64) if name == "bay" else np.asarray(h[name], dtype=float)
    # Free stack: every frame's height, one row per sample (optional, 2-D).
    if "frame_height_m" in hist:
        ds = hist["frame_height_m"]
        if (not isinstance(ds, h5py.Dataset) or ds.ndim != 2
                or ds.shape != (len(h["t_s"]), run.n_bays + 1)):
            raise InputError(
                f"/history/frame_height_m has shape {getattr(ds, 'shape', None)}; expected "
                f"({len(h['t_s'])}, {run.n_bays + 1}): one row per sample, one column per frame")
        h["frame_height_m"] = np.asarray(ds[()], dtype=float)
        run.units["frame_height_m"] = units_or(ds, "m")
    run.history = h


def read_bay_events(f: h5py.File, n_bays: int) -> dict[str, Array]:
    """Per-bay events (optional for the figures: only markers depend on them)."""
    bays: dict[str, Array] = {}
    if "bays" in f and isinstance(f["bays"], h5py.Group):
        g = f["bays"]
        for name in ("bay", "entry_time_s", "lock_time_s"):
            if name in g and isinstance(g[name], h5py.Dataset) and g[name].ndim == 1:
                bays[name] = np.asarray(g[name][()], dtype=float)
        if "bay" in bays and len(bays["bay"]) != n_bays:
            raise InputError(
                f"/bays/bay has {len(bays['bay'])} entries but scene_toml mast.n_bays is "
                f"{n_bays}")
    return bays


def read_status_name(f: h5py.File) -> str | None:
    """The run's status name for a figure's title (None when unreadable: never fails)."""
    if "summary" not in f or "status" not in f["summary"]:
        return None
    ds = f["summary"]["status"]
    try:
        raw = ds[()]
        enum = h5py.check_enum_dtype(ds.dtype)
        if enum:
            names = {v: k for k, v in enum.items()}
            return str(names.get(int(np.asarray(raw).reshape(()).item()), str(raw)))
        return text(raw) if isinstance(raw, (bytes, str, np.bytes_)) else str(raw)
    except Exception:  # a cosmetic title item: never fail on it
        return None


def load_single_run(h5: H5, sha256: str) -> SingleRunFile:
    """Everything the single-run report shows, read into memory (InputError on bad layout)."""
    names = h5.status_enum("summary/status")
    code = int(h5.scalar("summary/status"))
    if code not in names:
        raise h5.error(f"/summary/status = {code} is not in its enum")
    recorded = [h5.attr_or(h5.f, k, "(not recorded)") for k in ("software_version", "git_revision", "created_utc")]
    run = SingleRunFile(path=h5.path, sha256=sha256, status=names[code],
                        message=h5.attr_or(h5.dataset("summary/status"), "message", ""),
                        scene_toml=h5.attr_str(h5.f, "scene_toml"), software_version=recorded[0],
                        git_revision=recorded[1], created_utc=recorded[2])
    for name in sorted(h5.f["summary"]):
        if name == "status" or not isinstance(h5.f["summary"][name], h5py.Dataset):
            continue
        ds = h5.dataset(f"summary/{name}", ())
        u = h5.units(f"summary/{name}")
        if ds.dtype.kind in "OS":
            run.summary.append((name, text(ds[()]), u))
        else:
            v = ds[()]
            run.summary.append((name, int(v) if ds.dtype.kind in "iu" else float(v), u))
    if h5.has("bays"):
        bay = h5.array("bays/bay").astype(np.int64)
        run.bays["bay"] = bay
        for k in sorted(h5.f["bays"]):
            if k != "bay":
                run.bays[k] = h5.array(f"bays/{k}", bay.shape)
                run.bay_units[k] = h5.units(f"bays/{k}")
    if h5.has("history"):
        run.figures = load_run(h5.path)
    return run
