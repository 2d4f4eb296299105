#!/usr/bin/python3
"""Figures of one simulated run: the paper's Fig. 4 and Fig. 5.

Usage:
    /usr/bin/python3 postproc/run_figures.py RUN.h5 -o OUTDIR [--bay N] [--force]

RUN.h5 is a single-run file written by `truss-sim -o RUN.h5` (schema_version 1) with time
histories (`run.output_step_s > 0`). Writes into OUTDIR (created if needed):

    fig4_hinge_trajectory_bay<N>.png  mid-hinge trajectory of bay N in its stage (paper Fig. 4),
                                      with the guide-rail line and the rail entry point
    fig5_drive_and_pin_force.png      drive force and rail pin force over the whole run
                                      (paper Fig. 5), lock times as faint vertical lines
    fig5_bay<N>_zoom.png              the same two quantities in the stage of bay N

N defaults to the top bay (n_bays), the one the paper plots. The paths written are printed,
one per line. Any problem with the input (missing file, not HDF5, wrong schema_version, no
/history, --bay out of range, an existing PNG without --force) prints one line starting with
`error:` on stderr, exits with code 2 and writes nothing.

Needs numpy, h5py and matplotlib (Debian: python3-numpy python3-h5py python3-matplotlib) and
Python >= 3.11 (tomllib).
"""
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


def _event_time(run, field, bay):
    """Time of a per-bay event (NaN when absent or not reached)."""
    b = run["bays"]
    if field not in b:
        return float("nan")
    if "bay" in b:
        idx = np.nonzero(b["bay"] == bay)[0]
        if len(idx) == 0:
            return float("nan")
        return float(b[field][idx[0]])
    return float(b[field][bay - 1]) if len(b[field]) >= bay else float("nan")


def _lock_times(run):
    """All finite lock (retraction: unlock) times; from the bay changes if /bays has none."""
    if "lock_time_s" in run["bays"]:
        t = run["bays"]["lock_time_s"]
        return np.sort(t[np.isfinite(t)])
    h = run["history"]
    change = np.nonzero(np.diff(h["bay"]) != 0)[0]
    return h["t_s"][change + 1]


def _title(run):
    parts = [f"{run['n_bays']} bays", f"{run['drive_mode']} drive", run["direction"]]
    if run["stack_mode"]:
        parts.append(f"{run['stack_mode']} stack")
    if run["status"]:
        parts.append(f"status {run['status']}")
    return f"{os.path.basename(run['path'])}: " + ", ".join(parts)


def _words(run):
    if run["direction"] == "retract":
        return {"entry": "rail exit", "lock": "unlock"}
    return {"entry": "rail entry", "lock": "lock"}


def fig4(plt, run, bay):
    h, u = run["history"], run["units"]
    w = _words(run)
    sel = h["bay"] == bay
    x, y, t = h["hinge_x_m"][sel], h["hinge_y_m"][sel], h["t_s"][sel]
    ok = np.isfinite(x) & np.isfinite(y)
    x, y, t = x[ok], y[ok], t[ok]

    xl, yl = run["rail_x"], run["rail_y"]
    cot = 1.0 / np.tan(np.radians(run["rail_beta_deg"]))

    fig, ax = plt.subplots(figsize=(6.0, 7.5))
    ax.plot(x, y, "-", color="C0", lw=1.8, label=f"hinge of bay {bay}")
    ax.plot(x[0], y[0], "o", color="C2", ms=7, label=f"stage start (t = {t[0]:.3f} s)")
    ax.plot(x[-1], y[-1], "s", color="C3", ms=7,
            label=f"last sample of the stage (t = {t[-1]:.3f} s)")

    # Limits from the trajectory and the rail point, then the rail line across them.
    xs = np.concatenate([x, [0.0, xl]])
    ys = np.concatenate([y, [yl]])
    xmin, xmax = min(0.0, xs.min()), xs.max()
    ymin, ymax = min(0.0, ys.min()), ys.max()
    mx, my = 0.06 * (xmax - xmin or 1.0), 0.06 * (ymax - ymin or 1.0)
    xlim = (xmin - mx, xmax + mx)
    ylim = (ymin - my, ymax + my)
    xr = np.array(xlim)
    ax.plot(xr, yl - cot * (xr - xl), "--", color="0.45", lw=1.2,
            label=rf"guide rail, $\beta$ = {run['rail_beta_deg']:g}°")
    ax.plot(xl, yl, "D", color="0.45", ms=5,
            label=f"rail point (x_l, y_l) = ({xl:g}, {yl:g})")

    te = _event_time(run, "entry_time_s", bay)
    if np.isfinite(te) and t[0] <= te <= t[-1]:
        xe, ye = np.interp(te, t, x), np.interp(te, t, y)
        ax.plot(xe, ye, "*", color="C1", ms=14, mec="k", mew=0.6, zorder=5,
                label=f"{w['entry']} (t = {te:.3f} s)\n(x, y) = ({xe:.4f}, {ye:.4f}) m")
    else:
        ax.plot([], [], " ", label=f"no {w['entry']} in this stage")

    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"hinge radial offset x ({u['hinge_x_m']})")
    ax.set_ylabel(f"hinge height y ({u['hinge_y_m']})")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"Mid-hinge trajectory, bay {bay} stage (cf. paper Fig. 4)\n{_title(run)}",
                 fontsize=9)
    fig.tight_layout()
    return fig


def _force_panels(plt, run, sel, title, markers):
    h, u = run["history"], run["units"]
    t = h["t_s"][sel]
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(10.0, 6.5))
    a1.plot(t, h["drive_force_N"][sel], color="C0", lw=1.2)
    a2.plot(t, h["pin_force_N"][sel], color="C3", lw=1.2)
    a1.set_ylabel(f"drive force ({u['drive_force_N']})")
    a2.set_ylabel(f"rail pin force ({u['pin_force_N']})")
    a2.set_xlabel(f"time ({u['t_s']})")
    for ax in (a1, a2):
        for tm, style in markers:
            ax.axvline(tm, **style)
        ax.grid(True, alpha=0.3)
    a1.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig, (a1, a2)


def fig5(plt, run):
    h = run["history"]
    sel = np.ones(len(h["t_s"]), dtype=bool)
    w = _words(run)
    locks = _lock_times(run)
    style = dict(color="C4", lw=0.7, ls="--", alpha=0.35, zorder=0)
    fig, (a1, _) = _force_panels(
        plt, run, sel,
        f"Drive force and rail pin force, whole run (cf. paper Fig. 5)\n{_title(run)}",
        [(tm, style) for tm in locks])
    if len(locks):
        a1.plot([], [], color="C4", lw=0.7, ls="--", alpha=0.6, label=f"{w['lock']} times")
        a1.legend(loc="upper right", fontsize=8)
    return fig


def fig5_zoom(plt, run, bay):
    h = run["history"]
    w = _words(run)
    sel = h["bay"] == bay
    t = h["t_s"][sel]
    markers, labels = [], []
    te = _event_time(run, "entry_time_s", bay)
    tl = _event_time(run, "lock_time_s", bay)
    lo, hi = t.min(), t.max()
    span = hi - lo
    if np.isfinite(te) and lo - 0.05 * span <= te <= hi + 0.05 * span:
        markers.append((te, dict(color="C1", lw=1.0, ls="--", alpha=0.8)))
        labels.append((f"{w['entry']} (t = {te:.3f} s)", dict(color="C1", lw=1.0, ls="--")))
    if np.isfinite(tl) and lo - 0.05 * span <= tl <= hi + 0.05 * span:
        markers.append((tl, dict(color="0.4", lw=1.0, ls=":", alpha=0.8)))
        labels.append((f"{w['lock']} (t = {tl:.3f} s)", dict(color="0.4", lw=1.0, ls=":")))
    fig, (a1, _) = _force_panels(
        plt, run, sel,
        f"Drive force and rail pin force, stage of bay {bay}\n{_title(run)}", markers)
    for text, style in labels:
        a1.plot([], [], label=text, **style)
    if labels:
        a1.legend(loc="best", fontsize=8)
    return fig


def main(argv=None):
    p = _Parser(
        prog="run_figures.py",
        description="Paper Fig. 4 and Fig. 5 from a single-run truss-sim HDF5 file.")
    p.add_argument("run", metavar="RUN.h5", help="single-run file from `truss-sim -o RUN.h5`")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                   help="directory for the PNGs (created if needed)")
    p.add_argument("--bay", type=int, default=None, metavar="N",
                   help="bay for the trajectory and the zoom (default: the top bay, n_bays)")
    p.add_argument("--force", action="store_true", help="overwrite existing PNGs")
    args = p.parse_args(argv)

    try:
        run = load_run(args.run)
        n = run["n_bays"]
        bay = n if args.bay is None else args.bay
        if not 1 <= bay <= n:
            raise InputError(f"--bay {bay} is out of range: the run has bays 1..{n}")
        if not np.any(run["history"]["bay"] == bay):
            raise InputError(
                f"/history has no samples of bay {bay}'s stage (the run did not reach it"
                + (f"; status {run['status']}" if run["status"] else "") + ")")
        h = run["history"]
        sel = h["bay"] == bay
        if not np.any(np.isfinite(h["hinge_x_m"][sel]) & np.isfinite(h["hinge_y_m"][sel])):
            raise InputError(f"/history has no finite hinge position in bay {bay}'s stage")

        outdir = args.outdir
        if os.path.exists(outdir) and not os.path.isdir(outdir):
            raise InputError(f"output path {outdir} exists and is not a directory")
        names = [f"fig4_hinge_trajectory_bay{bay}.png",
                 "fig5_drive_and_pin_force.png",
                 f"fig5_bay{bay}_zoom.png"]
        targets = [os.path.join(outdir, nm) for nm in names]
        if not args.force:
            for tpath in targets:
                if os.path.exists(tpath):
                    raise InputError(f"{tpath} exists; use --force to overwrite")
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs = [fig4(plt, run, bay), fig5(plt, run), fig5_zoom(plt, run, bay)]

    # Render every figure to a temporary file first, then move all into place: a failure
    # while rendering leaves no partial set of PNGs behind.
    os.makedirs(outdir, exist_ok=True)
    temps = []
    try:
        for fig, tpath in zip(figs, targets):
            tmp = os.path.join(outdir, f".{os.path.basename(tpath)}.{os.getpid()}.tmp")
            temps.append(tmp)
            fig.savefig(tmp, format="png", dpi=130)
            plt.close(fig)
        for tmp, tpath in zip(temps, targets):
            os.replace(tmp, tpath)
    finally:
        for tmp in temps:
            if os.path.exists(tmp):
                os.remove(tmp)
    for tpath in targets:
        print(tpath)
    return 0


if __name__ == "__main__":
    sys.exit(main())
