"""truss_report.run_read: reading a single-run HDF5 file (truss-sim -o RUN.h5) into plain data,
with the text helpers and error type the whole report uses (run_figures.py re-exports them)."""
import argparse
import os
import sys
import tomllib

import numpy as np

SCHEMA_VERSION = 1
EXIT_INPUT_ERROR = 2

# History fields this script plots, with the units assumed when a dataset has no `units`.
HISTORY_FIELDS = {
    "t_s": "s",
    "bay": "",
    "hinge_x_m": "m",
    "hinge_y_m": "m",
    "drive_force_N": "N",
    "pin_force_N": "N",
}


class InputError(Exception):
    """A problem with the command line or the input file: reported as `error: ...`, exit 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one `error:` line and exit 2, like every other input error
        sys.stderr.write(f"error: {message} (see {self.prog} --help)\n")
        sys.exit(EXIT_INPUT_ERROR)


def _text(value):
    """An HDF5 string attribute or dataset value (variable- or fixed-length) as str."""
    if isinstance(value, np.ndarray):
        if value.size != 1:
            raise InputError(f"expected one string, got an array of shape {value.shape}")
        value = value.reshape(()).item()
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8").rstrip("\0")
    return str(value)


def _scalar_int(value, what):
    arr = np.asarray(value)
    if arr.size != 1:
        raise InputError(f"{what} is not a single integer (shape {arr.shape})")
    v = arr.reshape(()).item()
    if isinstance(v, (bytes, str)):
        try:
            return int(_text(v).strip())
        except ValueError:
            raise InputError(f"{what} is not an integer: {v!r}") from None
    if isinstance(v, float) and not v.is_integer():
        raise InputError(f"{what} is not an integer: {v}")
    return int(v)


def _units(ds, default):
    if "units" in ds.attrs:
        try:
            return _text(ds.attrs["units"])
        except (InputError, UnicodeDecodeError):
            return default
    return default


def _scene_value(scene, table, key, kind):
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


def open_h5(path):
    """Open PATH read-only; InputError when it is missing, not HDF5, or damaged."""
    import h5py  # imported here so that --help works without h5py
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if os.path.isdir(path):
        raise InputError(f"{path}: is a directory, not an HDF5 file")
    try:
        is_h5 = h5py.is_hdf5(path)
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e})") from None
    if not is_h5:
        raise InputError(f"{path}: not an HDF5 file")
    try:
        return h5py.File(path, "r")
    except OSError as e:
        raise InputError(f"{path}: damaged or truncated HDF5 file ({e})") from None


def load_run(path):
    """Read what the figures need from RUN.h5; raise InputError on any layout problem."""
    import h5py  # imported here so that --help works without h5py

    with open_h5(path) as f:
        attrs = f.attrs
        if "schema_version" not in attrs:
            raise InputError(f"{path} has no root attribute schema_version: not a truss-sim file")
        version = _scalar_int(attrs["schema_version"], "root attribute schema_version")
        if version != SCHEMA_VERSION:
            raise InputError(
                f"{path} has schema_version {version}; this script reads schema_version "
                f"{SCHEMA_VERSION}")
        if "kind" in attrs:
            kind = _text(attrs["kind"])
            if kind != "single_run":
                raise InputError(f"{path} is a '{kind}' file, not a 'single_run' file")
        if "scene_toml" not in attrs:
            raise InputError(f"{path} has no root attribute scene_toml")
        try:
            scene = tomllib.loads(_text(attrs["scene_toml"]))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
            raise InputError(f"root attribute scene_toml is not valid TOML: {e}") from None

        run = {
            "path": path,
            "n_bays": _scene_value(scene, "mast", "n_bays", int),
            "rail_x": _scene_value(scene, "rail", "x_m", float),
            "rail_y": _scene_value(scene, "rail", "y_m", float),
            "rail_beta_deg": _scene_value(scene, "rail", "beta_deg", float),
            "drive_mode": _scene_value(scene, "drive", "mode", str),
            "direction": _scene_value(scene, "run", "direction", str),
            "stack_mode": scene.get("stack", {}).get("mode") if isinstance(
                scene.get("stack"), dict) else None,
        }
        if run["n_bays"] < 1:
            raise InputError(f"scene_toml mast.n_bays = {run['n_bays']} is not positive")
        if not 0.0 < run["rail_beta_deg"] < 90.0:
            raise InputError(f"scene_toml rail.beta_deg = {run['rail_beta_deg']} is not in (0, 90)")

        if "history" not in f or not isinstance(f["history"], h5py.Group):
            raise InputError(
                f"{path} has no /history: run truss-sim with run.output_step_s > 0")
        hist = f["history"]
        h, units = {}, {}
        for name, default in HISTORY_FIELDS.items():
            if name not in hist:
                raise InputError(f"{path} has no /history/{name}")
            ds = hist[name]
            if not isinstance(ds, h5py.Dataset) or ds.ndim != 1:
                raise InputError(f"/history/{name} is not a 1-D dataset")
            h[name] = ds[()]
            units[name] = _units(ds, default)
        lengths = {len(v) for v in h.values()}
        if len(lengths) != 1:
            raise InputError("the /history datasets have different lengths: "
                             + ", ".join(f"{k} {len(v)}" for k, v in h.items()))
        if lengths.pop() == 0:
            raise InputError(
                f"{path} has an empty /history: run truss-sim with run.output_step_s > 0")
        for name in HISTORY_FIELDS:
            if name == "bay":
                h[name] = np.asarray(h[name]).astype(np.int64)
            else:
                h[name] = np.asarray(h[name], dtype=float)
        # Free stack: every frame's height, one row per sample (optional, 2-D).
        if "frame_height_m" in hist:
            ds = hist["frame_height_m"]
            if (not isinstance(ds, h5py.Dataset) or ds.ndim != 2
                    or ds.shape != (len(h["t_s"]), run["n_bays"] + 1)):
                raise InputError(
                    f"/history/frame_height_m has shape {getattr(ds, 'shape', None)}; expected "
                    f"({len(h['t_s'])}, {run['n_bays'] + 1}): one row per sample, one column per frame")
            h["frame_height_m"] = np.asarray(ds[()], dtype=float)
            units["frame_height_m"] = _units(ds, "m")
        run["history"], run["units"] = h, units

        # Per-bay events (optional for the figures: only markers depend on them).
        bays = {}
        if "bays" in f and isinstance(f["bays"], h5py.Group):
            g = f["bays"]
            for name in ("bay", "entry_time_s", "lock_time_s"):
                if name in g and isinstance(g[name], h5py.Dataset) and g[name].ndim == 1:
                    bays[name] = np.asarray(g[name][()], dtype=float)
            if "bay" in bays and len(bays["bay"]) != run["n_bays"]:
                raise InputError(
                    f"/bays/bay has {len(bays['bay'])} entries but scene_toml mast.n_bays is "
                    f"{run['n_bays']}")
        run["bays"] = bays

        status = None
        if "summary" in f and "status" in f["summary"]:
            ds = f["summary"]["status"]
            try:
                raw = ds[()]
                enum = h5py.check_enum_dtype(ds.dtype)
                if enum:
                    names = {v: k for k, v in enum.items()}
                    status = names.get(int(np.asarray(raw).reshape(()).item()), str(raw))
                else:
                    status = _text(raw) if isinstance(raw, (bytes, str, np.bytes_)) else str(raw)
            except Exception:  # a cosmetic title item: never fail on it
                status = None
        run["status"] = status
    return run
