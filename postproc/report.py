#!/usr/bin/python3
"""Statistical load report of a truss-campaign results file, or the report of a single run.

Usage:
    /usr/bin/python3 postproc/report.py RESULTS.h5 -o DIR [--force]

RESULTS.h5 is a campaign file (`truss-campaign -o RESULTS.h5`, kind "campaign") or a single-run
file (`truss-sim -o RUN.h5`, kind "single_run"), schema_version 1 (docs/hdf5-schema.md). Writes
DIR/report.html, one self-contained HTML page, with its PNG figures beside it (relative links).
DIR must be new or empty unless --force is given (then files of the same names are replaced,
other files are left alone). The path of the report is printed.

Exit codes: 0 report written; 2 bad input (not an HDF5 file, damaged or truncated file, wrong
kind or schema_version, a missing or malformed required dataset, an output directory that is
not empty): one line `error: FILE: what is wrong` on stderr and nothing written.

Every number in a table carries `data-key` (a stable name) and `data-value` (the float64 value,
Python repr) attributes; the visible text is rounded. docs/report.md describes the content and
the statistical methods.

Needs numpy, scipy, h5py and matplotlib (Debian: python3-numpy python3-scipy python3-h5py
python3-matplotlib) and Python >= 3.11.
"""
import datetime
import hashlib
import html
import os
import re
import shutil
import sys
import tempfile
import tomllib
import warnings
from dataclasses import dataclass, field

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run_figures as rf  # noqa: E402  (paper Fig. 4 and 5 of a single run, HDF5 text helpers)
from run_figures import InputError  # noqa: E402

SCHEMA_VERSION = 1
EXIT_INPUT_ERROR = 2
CONFIDENCE = 0.95
REPORT_NAME = "report.html"

# The outputs whose distributions are reported, with a readable name.
OUTPUTS = {
    "peak_drive_force_N": "peak drive force",
    "peak_drive_torque_Nm": "peak drive (screw) torque",
    "peak_pin_force_N": "peak rail pin force",
    "peak_diagonal_tension_N": "peak diagonal tension",
    "peak_latch_energy_J": "peak latch impact energy",
    "deploy_time_s": "deployment time",
}
# Reported percentiles: (percent, name in /stats, label).
LEVELS = [(50.0, "p50", "P50"), (95.0, "p95", "P95"), (99.0, "p99", "P99"),
          (99.865, "p99_865", "P99.865")]
# Every statistic of /stats/<output>, as computed here, for the cross-check.
STATS_PERCENTILES = {"p1": 1.0, "p5": 5.0, **{name: q for q, name, _ in LEVELS}}
STATS_FIELDS = ["count", "mean", "std", "min", "max", *STATS_PERCENTILES]
ROOT_ATTRS_STR = ["campaign_name", "campaign_description", "campaign_toml", "base_scene_toml",
                  "sampling", "direction", "drive_mode", "software_version", "git_revision",
                  "start_utc", "end_utc"]
ROOT_ATTRS_INT = ["n_runs", "master_seed", "n_bays_max", "n_ranks", "n_sessions"]
# A statistic in /stats and its recomputation here agree when they differ by at most this much,
# relative to the largest |value| of the column: the same formula on the same float64 data, where
# only the order of the roundings may differ (sums: about n ulps of the largest value). Counts
# must agree exactly.
AGREE_RTOL = 1e-9
# Motor margin: a peak torque counts as exceeding the stall torque above stall x (1 + this).
# A motor starts from rest at its stall torque, so peak = stall up to rounding in every run.
TORQUE_RTOL = 1e-9
TORNADO_TOP = 15
MAX_HISTORY_FIGURES = 12
MAX_FAILED_LISTED = 2000


# ============================================================================================
# Reading the file
# ============================================================================================

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
    if version != SCHEMA_VERSION:
        raise h5.error(f"schema_version is {version}; this report reads schema_version "
                       f"{SCHEMA_VERSION}")
    kind = h5.attr(h5.f, "kind", str)
    if kind not in ("campaign", "single_run"):
        raise h5.error(f"kind is '{kind}'; this report reads 'campaign' and 'single_run' files")
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
    stall_torque_source: str = ""
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


# ============================================================================================
# Statistics
# ============================================================================================

def percentile(x, q):
    """Hyndman-Fan type 7 (numpy.percentile's default, linear), as /stats defines it."""
    return float(np.percentile(x, q))


@dataclass
class QuantileCI:
    """Distribution-free CI [x_(r), x_(s)] of a quantile (1-based ranks; None: no such bound)."""
    lo: float
    hi: float
    r: int
    s: int
    coverage: float       # P(x_(r) <= true quantile < x_(s)), missing bounds taken as -+inf
    n_needed_lo: int      # smallest n giving a lower bound (reported when r is None)
    n_needed_hi: int


def quantile_ci(x_sorted, p, confidence=CONFIDENCE):
    """Order-statistic confidence interval of the p-quantile (0 < p < 1) of sorted data.

    B = #{X_i <= true quantile} is Binomial(n, p). With F its CDF and a = (1 - confidence)/2:
    r = the smallest k with F(k) >= a (so F(r - 1) < a), s = 1 + the smallest k with
    F(k) >= 1 - a; then P(x_(r) <= quantile < x_(s)) = F(s - 1) - F(r - 1) >= confidence.
    r = 0 or s = n + 1 means the sample is too small for that bound.
    """
    from scipy.stats import binom
    n = len(x_sorted)
    a = (1.0 - confidence) / 2.0
    r = int(binom.ppf(a, n, p))
    s = int(binom.ppf(1.0 - a, n, p)) + 1
    cov = float(binom.cdf(min(s, n + 1) - 1, n, p) - (binom.cdf(r - 1, n, p) if r >= 1 else 0.0))
    has_lo, has_hi = r >= 1, s <= n
    return QuantileCI(lo=float(x_sorted[r - 1]) if has_lo else float("nan"),
                      hi=float(x_sorted[s - 1]) if has_hi else float("nan"),
                      r=r if has_lo else None, s=s if has_hi else None, coverage=cov,
                      n_needed_lo=None if has_lo else min_runs_for_bound(p, a, "lo"),
                      n_needed_hi=None if has_hi else min_runs_for_bound(p, a, "hi"))


def min_runs_for_bound(p, a, side):
    """Smallest n for which quantile_ci has that bound: (1-p)^n < a (lower), p^n <= a (upper)."""
    base = 1.0 - p if side == "lo" else p
    n = max(1, int(np.floor(np.log(a) / np.log(base))))
    while not (base ** n < a if side == "lo" else base ** n <= a):
        n += 1
    while n > 1 and (base ** (n - 1) < a if side == "lo" else base ** (n - 1) <= a):
        n -= 1
    return n


def clopper_pearson(k, n, confidence=CONFIDENCE):
    """Exact (Clopper-Pearson) interval of a binomial proportion k/n."""
    from scipy.stats import beta
    a = (1.0 - confidence) / 2.0
    lo = 0.0 if k == 0 else float(beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1.0 - a, k + 1, n - k))
    return lo, hi


def spearman(x, y):
    """Spearman's rho over the pairs where both are finite; (rho, n), rho NaN if undefined."""
    from scipy.stats import spearmanr
    m = np.isfinite(x) & np.isfinite(y)
    n = int(m.sum())
    if n < 3 or np.ptp(x[m]) == 0 or np.ptp(y[m]) == 0:
        return float("nan"), n
    return float(spearmanr(x[m], y[m])[0]), n


def scaled_diff(a, b, scale):
    """|a - b| / scale (scale: the largest |value| of the column); 0 when both are NaN or equal,
    inf when only one is NaN."""
    if np.isnan(a) and np.isnan(b) or a == b:
        return 0.0
    if np.isnan(a) or np.isnan(b):
        return float("inf")
    return abs(a - b) / max(scale, np.finfo(float).tiny)


@dataclass
class StatsComparison:
    """Recomputed statistics against /stats: counts that differ, and the largest scaled
    difference of the order statistics (min, max, percentiles) and of the moments (mean, std;
    None when none was compared)."""
    count_mismatches: int = 0
    order: float = 0.0
    moments: float = None

    def add(self, mine, stored, scale, fields):
        for f in fields:
            if f == "count":
                self.count_mismatches += int(mine[f] != stored[f])
            elif f in ("mean", "std"):
                self.moments = max(self.moments or 0.0, scaled_diff(mine[f], stored[f], scale))
            else:
                self.order = max(self.order, scaled_diff(mine[f], stored[f], scale))

    def report(self, page, what, key):
        page.check(f"{what}: counts", self.count_mismatches == 0,
                   num(f"check.{key}.count_mismatches", self.count_mismatches, tag="span")
                   + " counts differ")
        page.check(f"{what}: order statistics", self.order <= AGREE_RTOL,
                   "largest difference / largest |value| "
                   + num(f"check.{key}.order_max_diff", self.order, tag="span"))
        if self.moments is not None:
            page.check(f"{what}: mean and std", self.moments <= AGREE_RTOL,
                       "largest difference / largest |value| "
                       + num(f"check.{key}.moments_max_diff", self.moments, tag="span")
                       + " (sums in another order round differently)")


def column_stats(x):
    """The /stats fields of one column of finite values (NaN where undefined)."""
    nan = float("nan")
    res = {"count": len(x), "mean": float(np.mean(x)) if len(x) else nan,
           "std": float(np.std(x, ddof=1)) if len(x) >= 2 else nan,
           "min": float(np.min(x)) if len(x) else nan, "max": float(np.max(x)) if len(x) else nan}
    for name, q in STATS_PERCENTILES.items():
        res[name] = percentile(x, q) if len(x) else nan
    return res


# ============================================================================================
# HTML helpers
# ============================================================================================

def esc(s):
    return html.escape(str(s), quote=True)


def fmt(v, digits=5):
    """Rounded text of a number (integers exact)."""
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    v = float(v)
    if np.isnan(v):
        return "NaN"
    return f"{v:.{digits}g}".replace("inf", "∞")


def data_value(v):
    return str(int(v)) if isinstance(v, (int, np.integer)) else repr(float(v))


def num(key, v, unit="", digits=5, tag="td"):
    """A table cell (or span) holding one number, with its data-key and full-precision value."""
    text = fmt(v, digits) + (f" {esc(unit)}" if unit and unit != "1" else "")
    cls = ' class="num"' if tag == "td" else ""
    return f'<{tag}{cls} data-key="{esc(key)}" data-value="{data_value(v)}">{text}</{tag}>'


def table(headers, rows, cls="", attrs=None):
    """headers: header HTML (no header row when all are empty); rows: lists of cells, each a
    <td>/<th> string or text to wrap in <td>."""
    body = []
    for i, row in enumerate(rows):
        cells = "".join(c if c.startswith(("<td", "<th")) else f"<td>{c}</td>" for c in row)
        extra = f" {attrs[i]}" if attrs else ""
        body.append(f"<tr{extra}>{cells}</tr>")
    head = ("<thead><tr>" + "".join(f"<th>{h}</th>" for h in headers) + "</tr></thead>"
            if any(headers) else "")
    return f'<table class="{cls}">{head}<tbody>{"".join(body)}</tbody></table>'


def unit_label(u):
    return "" if u == "1" else f" ({u})"


class Page:
    """The report being built: HTML parts, figures saved into the staging directory, and the
    results of the consistency checks against the file's own /stats."""

    def __init__(self, outdir, plt):
        self.dir, self.plt = outdir, plt
        self.files = []
        self.checks = []          # (what, passed, detail html)

    def figure(self, fig, name, caption, cls="wide"):
        fig.savefig(os.path.join(self.dir, name), format="png", dpi=100)
        self.plt.close(fig)
        self.files.append(name)
        return (f'<figure class="{cls}"><img src="{esc(name)}" alt="{esc(caption)}">'
                f"<figcaption>{esc(caption)}</figcaption></figure>")

    def check(self, what, passed, detail):
        self.checks.append((what, passed, detail))


# ============================================================================================
# Campaign report sections
# ============================================================================================

def section_campaign(page, c):
    a = c.attrs
    out = ['<section id="campaign"><h2>1. Campaign</h2>']
    rows = [
        ("name", esc(a["campaign_name"])),
        ("description", esc(a["campaign_description"])),
        ("date (end, UTC)", esc(a["end_utc"]) + f" (started {esc(a['start_utc'])})"),
        ("software", f"truss {esc(a['software_version'])}, git revision "
                     f"<code>{esc(a['git_revision'])}</code>"),
        ("MPI ranks", num("campaign.n_ranks", a["n_ranks"], tag="span")
         + " (invocation that finished the file); sessions: "
         + num("campaign.n_sessions", a["n_sessions"], tag="span")),
        ("wall time", num("campaign.wall_time_s", c.wall_time_s, "s", tag="span")
         + " (summed over the sessions)"),
        ("sampling", esc(a["sampling"])),
        ("runs", num("campaign.n_runs", a["n_runs"], tag="span")),
        ("master seed", num("campaign.master_seed", a["master_seed"], tag="span")),
        ("largest bay count", num("campaign.n_bays_max", a["n_bays_max"], tag="span")),
        ("direction, drive mode", f"{esc(a['direction'])}, {esc(a['drive_mode'])}"),
        ("results file", f"<code>{esc(os.path.abspath(c.path))}</code>"),
        ("SHA-256 of the file", f"<code>{c.sha256}</code>"),
    ]
    out.append(table(["", ""], [[f"<th>{k}</th>", v] for k, v in rows], "kv"))
    out.append(subsection_status(page, c))
    out.append(subsection_failures(c))
    out.append(subsection_dispersions(c))
    out.append(subsection_base_scene(c))
    out.append("</section>")
    return "\n".join(out)


def subsection_status(page, c):
    codes = sorted(c.status_name)
    counted = {k: int(np.sum(c.status == k)) for k in codes}
    rows = []
    for k in codes:
        name = c.status_name[k]
        from_stats = (int(c.stats_status_counts[k]) if k < len(c.stats_status_counts)
                      else float("nan"))
        rows.append([esc(name), num(f"status_count.{name}", counted[k]),
                     num(f"status_count.{name}.stats", from_stats)])
    n_ok = counted[0]
    rows.append(["<b>all runs</b>", num("runs.n_total", c.n), num("runs.n_total.stats",
                                                                 c.stats_attrs["n_runs"])])
    names_agree = all(k < len(c.stats_status_names) and c.stats_status_names[k] == c.status_name[k]
                      for k in codes)
    counts_agree = (names_agree and len(c.stats_status_counts) == len(codes)
                    and all(int(c.stats_status_counts[k]) == counted[k] for k in codes))
    page.check("status counts: /runs/status recounted vs /stats/status_counts and status_names",
               counts_agree, "agree" if counts_agree else "DIFFER: see the status table")
    attrs_agree = (c.stats_attrs["n_ok"] == n_ok and c.stats_attrs["n_failed"] == c.n - n_ok
                   and c.stats_attrs["n_runs"] == c.n)
    page.check("/stats attributes n_runs, n_ok, n_failed vs /runs/status", attrs_agree,
               "agree" if attrs_agree else
               f"DIFFER: file says n_ok = {c.stats_attrs['n_ok']}, n_failed = "
               f"{c.stats_attrs['n_failed']}")
    return ("<h3>Outcome of the runs</h3>"
            f"<p>{num('runs.n_ok', n_ok, tag='span')} runs ok, "
            f"{num('runs.n_failed', c.n - n_ok, tag='span')} failed, of "
            f"{c.n} runs. Counts by status, from <code>/runs/status</code> and as stored in "
            "<code>/stats/status_counts</code>:</p>"
            + table(["status", "runs (counted in /runs/status)", "runs (/stats/status_counts)"],
                    rows, "narrow"))


def message_template(msg):
    """A failure message with its numbers replaced by #, to group messages that differ only
    in the numbers (times, heights, bay indices)."""
    return re.sub(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", "#", msg)


def subsection_failures(c):
    failed = np.nonzero(~c.ok)[0]
    if len(failed) == 0:
        return "<h3>Failed runs</h3><p>No run failed.</p>"
    groups = {}
    for i in failed:
        groups.setdefault((c.status_name[int(c.status[i])], message_template(c.messages[i])),
                          []).append(int(i))
    rows, attrs = [], []
    for g, ((status, tmpl), runs) in enumerate(sorted(groups.items(), key=lambda kv: -len(kv[1]))):
        shown = ", ".join(map(str, runs[:30])) + (f", … (+{len(runs) - 30} more)"
                                                  if len(runs) > 30 else "")
        rows.append([esc(status), num(f"failure_group.{g}.count", len(runs)),
                     f"<code>{esc(tmpl)}</code>", shown,
                     f"<small>run {runs[0]}: {esc(c.messages[runs[0]])}</small>"])
        attrs.append(f'data-status="{esc(status)}" data-runs="{" ".join(map(str, runs))}"')
    listed = failed[:MAX_FAILED_LISTED]
    full = table(["run", "status", "message"],
                 [[str(i), esc(c.status_name[int(c.status[i])]), esc(c.messages[i])]
                  for i in listed], "narrow")
    more = (f"<p>(first {MAX_FAILED_LISTED} of {len(failed)} failed runs listed)</p>"
            if len(failed) > MAX_FAILED_LISTED else "")
    return ("<h3>Failed runs</h3><p>Failure reasons from <code>/runs/message</code>, grouped by "
            "status and by the message with its numbers replaced by <code>#</code>; run indices "
            "are 0-based rows of <code>/runs</code>.</p>"
            + table(["status", "runs", "reason (numbers as #)", "run indices", "example"],
                    rows, "", attrs)
            + f"<details><summary>every failed run and its message ({len(failed)})</summary>"
            + full + more + "</details>")


def param_units(d):
    """Units of a dispersion's distribution parameters (the draw x, before it is applied)."""
    if d.distribution == "lognormal":
        return "1 (of ln X)"
    return "1 (relative)" if d.apply == "relative" else d.units


def subsection_dispersions(c):
    if not c.dispersions:
        return "<h3>Dispersions</h3><p>The campaign disperses no key.</p>"
    rows = []
    for d in c.dispersions:
        pu = param_units(d)
        parts = []
        for p, v in d.params.items():
            if d.distribution == "discrete":
                vals = ", ".join(num(f"dispersion.{d.key}.{p}.{i}", float(x), tag="span")
                                 for i, x in enumerate(np.atleast_1d(v)))
                parts.append(f"{p} = [{vals}]")
            else:
                parts.append(f"{p} = " + num(f"dispersion.{d.key}.{p}", v,
                                             "" if pu.startswith("1") else pu, tag="span"))
        rows.append([f"<code>{esc(d.key)}</code>", num(f"dispersion.{d.key}.factor", d.factor),
                     esc(d.distribution), "<br>".join(parts), esc(pu), esc(d.per), esc(d.apply),
                     num(f"dispersion.{d.key}.nominal", d.nominal, d.units)])
    return ("<h3>Dispersions</h3><p>From the attributes of <code>/runs/inputs/&lt;key&gt;</code>. "
            "A draw x is applied as: absolute = x, relative = nominal (1 + x), "
            "offset = nominal + x; "
            "per bay / per frame draws are independent for each bay / frame.</p>"
            + table(["key", "factor", "distribution", "parameters", "parameter units", "per",
                     "apply", "nominal"], rows))


def subsection_base_scene(c):
    tables = []
    for tab, entries in c.base_scene.items():
        if not isinstance(entries, dict):      # a top-level key outside any table
            entries, tab = {tab: entries}, ""
        rows = []
        for k, v in entries.items():
            key = f"{tab}.{k}" if tab else k
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                rows.append([f"<code>{esc(k)}</code>", esc(v)])
            else:
                rows.append([f"<code>{esc(k)}</code>", num(f"base_scene.{key}", v)])
        tables.append(table([f"<code>[{esc(tab)}]</code>" if tab else "key", "value"], rows))
    return ("<h3>Base scene</h3><p>From the root attribute <code>base_scene_toml</code> "
            "(units are in the key names; keys left unset are not listed). The complete "
            "resolved campaign, which <code>truss-campaign</code> reads back, is "
            "<code>campaign_toml</code> below.</p>"
            + "<div class='flex'>" + "".join(tables) + "</div>"
            + "<details><summary>base_scene_toml</summary><pre>"
            + esc(c.attrs["base_scene_toml"]) + "</pre></details>"
            + "<details><summary>campaign_toml</summary><pre>"
            + esc(c.attrs["campaign_toml"]) + "</pre></details>")


def ci_note(sampling):
    note = ("Confidence intervals of the percentiles are distribution-free order-statistic "
            f"intervals at {CONFIDENCE:.0%}: for the q-quantile, the number of runs below the "
            "true quantile is Binomial(n, q), and the interval is [x<sub>(r)</sub>, "
            "x<sub>(s)</sub>] with r, s from that binomial's 2.5 % and 97.5 % quantiles "
            "(r = binom.ppf(0.025, n, q), s = binom.ppf(0.975, n, q) + 1; ranks 1-based). "
            "Coverage is the exact probability that the interval holds the true quantile "
            "(≥ 95 %). When n is too small for a bound at this level, the table says "
            "“n too small” and gives the number of runs that bound needs. The intervals assume "
            "independent runs")
    if sampling == "monte_carlo":
        return note + ", which Monte Carlo sampling gives."
    if sampling == "saltelli":
        return note + (". <b>This campaign used Saltelli sampling: the runs of one block share "
                       "coordinates, so they are not independent and these intervals are not "
                       "valid; use a Monte Carlo campaign for the load percentiles.</b>")
    return note + (f". With {esc(sampling)} sampling the runs are stratified rather than "
                   "independent; the intervals are then usually conservative, but this is not "
                   "guaranteed.")


def section_loads(page, c):
    out = ['<section id="loads"><h2>2. Peak loads and deployment time</h2>',
           "<p>Statistics over the ok runs with a finite value only (the runs that "
           "<code>/stats/&lt;output&gt;/count</code> counts). Percentiles are linear "
           "interpolation between order statistics (Hyndman-Fan type 7, "
           "<code>numpy.percentile</code>'s default), the definition of <code>/stats</code>; "
           "each is shown next to the value stored in <code>/stats</code>. Standard deviations "
           "use ddof = 1.</p>", f"<p>{ci_note(c.attrs['sampling'])}</p>"]
    comparison = StatsComparison()
    for key, label in OUTPUTS.items():
        out.append(output_block(page, c, key, label, comparison))
    comparison.report(page, "the six outputs recomputed vs /stats/<output>", "stats")
    out.append("</section>")
    return "\n".join(out)


def output_block(page, c, key, label, comparison):
    """Histogram, ECDF, exceedance and tables of one output (its /stats compared into
    `comparison`)."""
    u = c.units[key]
    word = label if not (key == "deploy_time_s" and c.attrs["direction"] == "retract") \
        else "retraction time"
    x = np.sort(c.outputs[key][c.ok & np.isfinite(c.outputs[key])])
    mine = column_stats(x)
    stored = c.stats[key]
    comparison.add(mine, stored, float(np.max(np.abs(x))) if len(x) else 0.0, STATS_FIELDS)
    head = (f'<h3 id="{key}">{esc(word[0].upper() + word[1:])} <code>{key}</code>'
            f"{unit_label(u)}</h3>")
    n_ok = int(c.ok.sum())
    if len(x) == 0:
        return (head + f"<p class='note'>No ok run has a finite value of <code>{key}</code> "
                f"({num(f'{key}.count', 0, tag='span')} values from {n_ok} ok runs): nothing to "
                f"show (the {esc(c.attrs['drive_mode'])} drive mode may not define it).</p>")
    cis = {name: quantile_ci(x, q / 100.0) for q, name, _ in LEVELS}
    est = {name: percentile(x, q) for q, name, _ in LEVELS}
    fig = fig_distribution(page.plt, x, f"{word} ({key})", u, est, cis)
    parts = [head,
             f"<p>{num(f'{key}.count', len(x), tag='span')} ok runs with a finite value "
             f"(of {n_ok} ok runs and {c.n} runs).</p>",
             page.figure(fig, f"dist_{key}.png",
                         f"{word}: histogram, empirical CDF and exceedance probability "
                         "(1 − ECDF, log scale) with P50, P95, P99, P99.865 and their 95 % CIs")]
    summary = [[num(f"{key}.{s}", mine[s], u) for s in ("mean", "std", "min", "max")],
               [num(f"{key}.{s}.stats", stored[s], u) for s in ("mean", "std", "min", "max")]]
    summary[0].insert(0, "recomputed")
    summary[1].insert(0, "<code>/stats</code>")
    parts.append(table(["", "mean", "std (ddof 1)", "min", "max"], summary, "narrow"))
    rows = []
    for q, name, lab in LEVELS:
        ci = cis[name]
        rows.append([
            lab, num(f"{key}.{name}", est[name], u), num(f"{key}.{name}.stats", stored[name], u),
            ci_cell(f"{key}.{name}.ci_lo", ci.lo, ci.n_needed_lo, u),
            ci_cell(f"{key}.{name}.ci_hi", ci.hi, ci.n_needed_hi, u),
            (num(f"{key}.{name}.ci_r", ci.r) if ci.r is not None else "<td>—</td>"),
            (num(f"{key}.{name}.ci_s", ci.s) if ci.s is not None else "<td>—</td>"),
            num(f"{key}.{name}.ci_coverage", ci.coverage, digits=4)])
    parts.append(table(["percentile", "estimate", "<code>/stats</code>", "95 % CI low",
                        "95 % CI high", "rank r", "rank s", "coverage"], rows))
    return "\n".join(parts)


def ci_cell(key, v, n_needed, unit):
    if n_needed is None:
        return num(key, v, unit)
    return (f'<td class="num toosmall" data-key="{esc(key)}" data-value="nan">n too small '
            f'(needs n ≥ {num(key + ".n_needed", n_needed, tag="span")})</td>')


def fig_distribution(plt, x, title, u, est, cis):
    n = len(x)
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(15.0, 4.3))
    edges = np.histogram_bin_edges(x, bins="auto")
    if len(edges) > 81:
        edges = np.linspace(x[0], x[-1], 81)
    a1.hist(x, bins=edges, color="C0", alpha=0.8)
    a1.set_ylabel("runs")
    a2.step(x, np.arange(1, n + 1) / n, where="post", color="C0")
    a2.set_ylabel("empirical CDF")
    surv = 1.0 - np.arange(1, n + 1) / n
    a3.step(x[:-1], surv[:-1], where="post", color="C0")
    a3.set_yscale("log")
    a3.set_ylim(min(0.5 / n, 5e-4), 1.5)
    a3.set_ylabel("exceedance probability 1 − ECDF")
    colors = {"p50": "C2", "p95": "C1", "p99": "C3", "p99_865": "C4"}
    for q, name, lab in LEVELS:
        style = dict(color=colors[name], lw=1.1, ls="--")
        a1.axvline(est[name], label=f"{lab} = {est[name]:.5g} {u}", **style)
        a2.axvline(est[name], **style)
        # The CI as a segment (it need not contain the estimate for very small n); a bound
        # the sample cannot give is drawn to the sample's extreme.
        ci, level = cis[name], 1.0 - q / 100.0
        lo = ci.lo if np.isfinite(ci.lo) else x[0]
        hi = ci.hi if np.isfinite(ci.hi) else x[-1]
        a3.plot([lo, hi], [level, level], "|-", color=colors[name], lw=1.6, ms=8)
        a3.plot([est[name]], [level], "o", color=colors[name], ms=4,
                label=f"{lab} and 95 % CI" + ("" if np.isfinite(ci.lo) and np.isfinite(ci.hi)
                                             else " (a bound beyond the sample)"))
    for ax in (a1, a2, a3):
        ax.set_xlabel(f"{title} ({u})" if u != "1" else title)
        ax.grid(True, alpha=0.3)
    a1.legend(fontsize=7, loc="best")
    a3.legend(fontsize=7, loc="lower left")
    fig.suptitle(f"{title}: {n} ok runs with a finite value", fontsize=10)
    fig.tight_layout()
    return fig


def lock_order(lock_ok):
    """'descending' when every run locks bay j+1 before bay j (the top bay first),
    'ascending' for the reverse, 'mixed' otherwise (from the finite consecutive differences)."""
    d = np.diff(lock_ok, axis=1)
    d = d[np.isfinite(d)]
    if len(d) and np.all(d < 0):
        return "descending"
    if len(d) and np.all(d > 0):
        return "ascending"
    return "mixed"


def lock_intervals(lock, order):
    """Per run, per bay k (1-based): the time from the previous lock to the lock of bay k
    (descending: lock(k) - lock(k+1); ascending: lock(k) - lock(k-1); mixed: lock(k+1) - lock(k),
    signed). Returns (n x n_bays_max array, NaN where undefined, and a description)."""
    dt = np.full(lock.shape, np.nan)
    if order == "descending":
        dt[:, :-1] = lock[:, :-1] - lock[:, 1:]
        return dt, ("bay k: lock of bay k minus lock of bay k+1 (bays lock from the top, "
                    "bay n first)")
    if order == "ascending":
        dt[:, 1:] = lock[:, 1:] - lock[:, :-1]
        return dt, "bay k: lock of bay k minus lock of bay k−1 (bays lock from bay 1 upwards)"
    dt[:, :-1] = lock[:, 1:] - lock[:, :-1]
    return dt, ("bay k: lock of bay k+1 minus lock of bay k, signed (the bays do not lock in one "
                "monotonic order)")


def band_stats(cols):
    """count, P5, P50, P95 of each column's finite values (NaN where no value)."""
    res = {"count": [], "p5": [], "p50": [], "p95": []}
    for col in cols.T:
        v = col[np.isfinite(col)]
        res["count"].append(len(v))
        for name, q in (("p5", 5.0), ("p50", 50.0), ("p95", 95.0)):
            res[name].append(percentile(v, q) if len(v) else float("nan"))
    return {k: np.array(v) for k, v in res.items()}


def section_lock_timing(page, c):
    words = ("unlock", "unlocks") if c.attrs["direction"] == "retract" else ("lock", "locks")
    lock_ok = c.lock[c.ok]
    u = c.units["lock_time_s"]
    order = lock_order(lock_ok)
    dt, dt_text = lock_intervals(lock_ok, order)
    lt, it = band_stats(lock_ok), band_stats(dt)
    nb = c.lock.shape[1]
    comparison = StatsComparison()
    for j in range(nb):
        col = lock_ok[:, j][np.isfinite(lock_ok[:, j])]
        comparison.add({s: lt[s][j] for s in lt}, {s: c.stats_lock[s][j] for s in lt},
                       float(np.max(np.abs(col))) if len(col) else 0.0, list(lt))
    comparison.report(page, "per-bay lock times recomputed vs /stats/bays/lock_time_s "
                      "(count, P5, P50, P95)", "lock")
    bays = np.arange(1, nb + 1)
    fig = fig_lock_timing(page.plt, bays, lt, it, u, words, dt_text)
    rows = []
    for j in range(nb):
        b = j + 1
        rows.append([str(b), num(f"lock_time_s.bay{b}.count", int(lt["count"][j]))]
                    + [num(f"lock_time_s.bay{b}.{s}", lt[s][j], u) for s in ("p5", "p50", "p95")]
                    + [num(f"lock_interval_s.bay{b}.count", int(it["count"][j]))]
                    + [num(f"lock_interval_s.bay{b}.{s}", it[s][j], u)
                       for s in ("p5", "p50", "p95")])
    return (f'<section id="locks"><h2>3. {words[0].capitalize()} timing</h2>'
            f"<p>Per bay, over the ok runs that have that bay with a finite {words[0]} time "
            f"(<code>/runs/bays/lock_time_s</code>): median and the 5–95 % band of the "
            f"{words[0]} time, and of the time between successive {words[1]}. Bay order in the "
            f"data: <b>{order}</b>; interval at {esc(dt_text)}. Percentiles as in section 2.</p>"
            + page.figure(fig, "lock_timing.png",
                          f"{words[0]} time and time between successive {words[1]} per bay: "
                          "median and 5–95 % band")
            + "<details><summary>per-bay table</summary>"
            + table(["bay", "runs", f"{words[0]} time P5", "P50", "P95", "runs",
                     "interval P5", "P50", "P95"], rows, "narrow",
                    [f'data-order="{order}"'] * len(rows))
            + "</details></section>")


def fig_lock_timing(plt, bays, lt, it, u, words, dt_text):
    from matplotlib.ticker import MaxNLocator
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(15.0, 4.5))
    for ax, s, what in ((a1, lt, f"{words[0]} time"),
                        (a2, it, f"time between successive {words[1]}")):
        ax.fill_between(bays, s["p5"], s["p95"], color="C0", alpha=0.25, step=None,
                        label="5–95 % band")
        ax.plot(bays, s["p50"], "o-", color="C0", ms=3, lw=1.2, label="median")
        ax.set_xlabel("bay index")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel(f"{what} ({u})")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    a1.set_title(f"{words[0]} time per bay", fontsize=10)
    a2.set_title(f"time between successive {words[1]}\n({dt_text})", fontsize=9)
    fig.tight_layout()
    return fig


def section_margins(page, c):
    head = '<section id="margins"><h2>4. Margins: drive torque against the motor stall torque</h2>'
    if c.attrs["drive_mode"] == "velocity":
        return section_margins_velocity(page, c, head)
    if c.attrs["drive_mode"] != "motor":
        return (head + f"<p>The drive mode is <b>{esc(c.attrs['drive_mode'])}</b>: the drive "
                "applies a prescribed torque, there is no motor to compare with.</p></section>")
    stall_code = [k for k, v in c.status_name.items() if v == "stall"]
    stalled = np.isin(c.status, stall_code)
    torque = c.outputs["peak_drive_torque_Nm"]
    u = c.units["peak_drive_torque_Nm"]
    stall_t, source = c.stall_torque, c.stall_torque_source
    ok_t = c.ok & np.isfinite(torque) & np.isfinite(stall_t)
    ok_exceed = ok_t & (torque > stall_t * (1.0 + TORQUE_RTOL))
    n_cons = int(ok_t.sum() + stalled.sum())
    k = int(ok_exceed.sum() + stalled.sum())
    if n_cons == 0:
        return head + "<p>No ok or stalled run: nothing to compare.</p></section>"
    p = k / n_cons
    lo, hi = clopper_pearson(k, n_cons)
    util = torque[ok_t] / stall_t[ok_t]
    nominal = float((c.base_scene.get("drive") or {}).get("stall_torque_Nm", float("nan")))
    fig = fig_motor(page.plt, torque, stall_t, ok_t, stalled, nominal, u)
    rows = [
        ["stall torque of the base scene", num("motor.stall_torque_nominal", nominal, u)],
        ["runs considered (ok with a finite peak torque, + stalled)", num("motor.n_considered",
                                                                         n_cons)],
        ["stalled runs (status stall)", num("motor.n_stall", int(stalled.sum()))],
        ["ok runs with peak torque > stall torque", num("motor.n_ok_exceed", int(ok_exceed.sum()))],
        ["exceedances", num("motor.n_exceed", k)],
        ["probability of exceeding the stall torque", num("motor.p_exceed", p, digits=4)],
        ["95 % Clopper-Pearson interval, low", num("motor.p_exceed.ci_lo", lo, digits=4)],
        ["95 % Clopper-Pearson interval, high", num("motor.p_exceed.ci_hi", hi, digits=4)],
        ["largest peak torque / stall torque of an ok run",
         num("motor.utilisation_max", float(np.max(util)) if len(util) else float("nan"),
             digits=10)],
    ]
    excluded = int(np.sum(~c.ok & ~stalled))
    return (head + f"<p>Stall torque: {source}. A run exceeds the stall torque when it stalled "
            "(status <code>stall</code>: the motor could not drive the mast, so the torque the "
            "mast needed exceeded what the motor gives; <b>stalled runs count as exceedances</b>) "
            f"or when its peak torque is above its stall torque × (1 + {TORQUE_RTOL:g}). "
            "The motor gives its stall torque at zero speed, at the start, so in an ok run the "
            "peak torque equals the stall torque up to rounding. The probability is exceedances / "
            "runs considered, with an exact (Clopper-Pearson) 95 % interval; the "
            + num("motor.n_other_failures", excluded, tag="span")
            + " runs that failed for another reason are not counted.</p>"
            + page.figure(fig, "motor_torque_margin.png",
                          "stall torque of the ok and stalled runs, and peak drive torque against "
                          "stall torque")
            + table(["", "value"], rows, "narrow") + "</section>")


def drive_parameter(c, key):
    """Per-run values of a drive.* scene key: the dispersed values, else the base scene's."""
    for d in c.dispersions:
        if d.key == f"drive.{key}" and d.per == "run":
            return d.values
    return np.full(c.n, float((c.base_scene.get("drive") or {})[key]))


def calc_available_torque(c):
    """The scene's motor at the prescribed speed: T_s (1 - omega / omega_0), omega = 2 pi v / h."""
    omega = 2.0 * np.pi * drive_parameter(c, "speed_m_per_s") / drive_parameter(c, "screw_lead_m")
    return drive_parameter(c, "stall_torque_Nm") * (1.0 - omega / drive_parameter(c, "no_load_speed_rad_per_s"))


def section_margins_velocity(page, c, head):
    torque = c.outputs["peak_drive_torque_Nm"]
    u = c.units["peak_drive_torque_Nm"]
    avail = calc_available_torque(c)
    considered = c.ok & np.isfinite(torque) & np.isfinite(avail)
    n_cons = int(considered.sum())
    if n_cons == 0:
        return head + "<p>No ok run with a finite peak torque: nothing to compare.</p></section>"
    exceed = considered & (torque > avail)
    k = int(exceed.sum())
    lo, hi = clopper_pearson(k, n_cons)
    drive = c.base_scene.get("drive") or {}
    omega = 2.0 * np.pi * float(drive["speed_m_per_s"]) / float(drive["screw_lead_m"])
    ratio = avail[considered] / torque[considered]
    fig, ax = page.plt.subplots(figsize=(10.0, 4.0))
    ax.hist(torque[considered], bins=60, color="C0", label=f"peak drive torque, {n_cons} ok runs")
    for v, lab in ((float(np.min(avail[considered])), "available torque at the prescribed speed (min over runs)"),
                   (float(np.max(avail[considered])), "(max over runs)")):
        ax.axvline(v, color="C3", ls="--", lw=1, label=f"{lab}: {v:.5g} {u}")
    ax.set_xlabel(f"torque ({u})")
    ax.set_ylabel("runs")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    rows = [
        ["motor stall torque of the scene", num("velmargin.stall_torque", float(drive["stall_torque_Nm"]), u)],
        ["motor no-load speed of the scene", num("velmargin.no_load_speed", float(drive["no_load_speed_rad_per_s"]), "rad/s")],
        ["screw speed the prescribed drive speed needs", num("velmargin.required_speed", omega, "rad/s")],
        ["runs considered (ok, finite peak torque)", num("velmargin.n_considered", n_cons)],
        ["runs whose peak torque exceeds the available torque", num("velmargin.n_exceed", k)],
        ["probability of exceeding", num("velmargin.p_exceed", k / n_cons, digits=4)],
        ["95 % Clopper-Pearson interval, low", num("velmargin.p_exceed.ci_lo", lo, digits=4)],
        ["95 % Clopper-Pearson interval, high", num("velmargin.p_exceed.ci_hi", hi, digits=4)],
        ["smallest available / peak torque", num("velmargin.ratio_min", float(np.min(ratio)), digits=6)],
        ["median available / peak torque", num("velmargin.ratio_p50", float(np.percentile(ratio, 50)), digits=6)],
    ]
    return (head + "<p>Velocity drive: the driven frame follows the prescribed speed whatever torque that "
            "takes, so the campaign gives the <b>torque a motor must deliver</b>. It is compared with "
            "the scene's motor (<code>drive.stall_torque_Nm</code>, "
            "<code>drive.no_load_speed_rad_per_s</code>: project defaults unless the scene sets them) "
            "on its linear speed-torque line: at the screw speed &omega; = 2&pi; v / h the motor gives "
            "T<sub>s</sub> (1 &minus; &omega; / &omega;<sub>0</sub>), per run when any of these is "
            "dispersed. A run exceeds when its peak drive torque is above that; the probability has an "
            "exact (Clopper-Pearson) 95 % interval. A result of 1 means this motor cannot hold the "
            "prescribed speed: choose a stronger motor, or rerun the campaign in motor mode.</p>"
            + page.figure(fig, "velocity_torque_margin.png",
                          "peak drive torque of the ok runs against the torque the scene's motor gives at the "
                          "prescribed speed")
            + table(["", "value"], rows, "narrow") + "</section>")


def fig_motor(plt, torque, stall_t, ok_t, stalled, nominal, u):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(15.0, 4.5))
    both = stall_t[ok_t | stalled]
    edges = np.histogram_bin_edges(both[np.isfinite(both)], bins="auto")
    edges = edges if len(edges) <= 61 else np.linspace(edges[0], edges[-1], 61)
    a1.hist([stall_t[ok_t], stall_t[stalled]], bins=edges, stacked=True, color=["C0", "C3"],
            label=[f"ok runs ({int(ok_t.sum())})", f"stalled runs ({int(stalled.sum())})"])
    a1.axvline(nominal, color="k", ls="--", lw=1, label=f"base scene {nominal:.5g} {u}")
    a1.set_xlabel(f"stall torque of the run ({u})")
    a1.set_ylabel("runs")
    a1.legend(fontsize=8)
    a2.plot(stall_t[ok_t], torque[ok_t], ".", ms=3, color="C0", label="ok runs")
    a2.plot(stall_t[stalled], torque[stalled], "x", ms=4, color="C3",
            label="stalled runs (peak before the stall)")
    lim = np.array([np.nanmin(both), np.nanmax(both)])
    a2.plot(lim, lim, "k--", lw=1, label="peak torque = stall torque")
    a2.set_xlabel(f"stall torque of the run ({u})")
    a2.set_ylabel(f"peak drive torque ({u})")
    a2.legend(fontsize=8)
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


@dataclass
class InputColumn:
    label: str
    values: np.ndarray
    aggregate: bool       # the per-dispersion aggregate (or a per-run dispersion itself)


def input_columns(c):
    """Every sampled input column and one aggregate per dispersion (see aggregate_input)."""
    cols = []
    for d in c.dispersions:
        if d.per == "run":
            cols.append(InputColumn(d.key, d.values, True))
            continue
        start = 1 if d.per == "bay" else 0
        for j in range(d.values.shape[1]):
            cols.append(InputColumn(f"{d.key}[{d.per} {j + start}]", d.values[:, j], False))
        cols.append(InputColumn(aggregate_label(d), aggregate_input(d), True))
    return cols


def aggregate_label(d):
    return f"{d.key} (mean over {d.per}s)"


def aggregate_input(d):
    """Per run: the mean over the run's bays (frames) of (value - nominal) / nominal
    ((value - nominal) when the nominal is 0)."""
    dev = d.values - d.nominal
    if d.nominal != 0:
        dev = dev / d.nominal
    finite = np.isfinite(dev)
    count = finite.sum(axis=1)
    total = np.where(finite, dev, 0.0).sum(axis=1)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def section_sensitivity(page, c):
    out = ['<section id="sensitivity"><h2>5. What drives the loads</h2>']
    if not c.dispersions:
        return out[0] + "<p>No dispersed input.</p></section>"
    cols = input_columns(c)
    rho = {}
    for key in OUTPUTS:
        y = np.where(c.ok, c.outputs[key], np.nan)
        rho[key] = {col.label: spearman(col.values, y) for col in cols}
    out.append("<p>Spearman rank correlation ρ (<code>scipy.stats.spearmanr</code>) of each "
               "sampled input with each output, over the ok runs where both are finite. A per-bay "
               "(per-frame) dispersion contributes one input per bay (frame), "
               "<code>key[bay j]</code> (<code>key[frame k]</code>, frame 0 = base), and an "
               "aggregate: the mean over the run's bays (frames) of the relative deviation from "
               "the nominal. Each tornado shows the "
               f"{TORNADO_TOP} inputs with the largest |ρ|; aggregates are hatched. The grey band "
               "is ±1.96/√(n−1), n = the ok runs with a finite output: |ρ| inside it is what "
               "independent inputs give 95 % of the time, for one input taken alone. ρ is "
               "dimensionless.</p>")
    agg_labels = [col.label for col in cols if col.aggregate]
    rows = [[f"<code>{esc(lab)}</code>"] + [num(f"spearman.{k}.{lab}", rho[k][lab][0], digits=3)
                                            for k in OUTPUTS] for lab in agg_labels]
    out.append("<h3>Rank correlation of every dispersion (aggregates)</h3>"
               + table(["input"] + [f"<code>{k}</code>" for k in OUTPUTS], rows, "corr"))
    figs = []
    aggregate = {col.label for col in cols if col.aggregate}
    for key in OUTPUTS:
        ranked = sorted(((lab, r, n) for lab, (r, n) in rho[key].items() if np.isfinite(r)),
                        key=lambda t: -abs(t[1]))[:TORNADO_TOP]
        if not ranked:
            figs.append(f"<div class='cell'><p class='note'><code>{key}</code>: no input "
                        "correlation defined (no finite ok value, or a constant output).</p></div>")
            continue
        n_y = int(np.sum(c.ok & np.isfinite(c.outputs[key])))
        fig = fig_tornado(page.plt, ranked, aggregate, f"{key} (n = {n_y})",
                          1.96 / np.sqrt(max(n_y - 1, 1)))
        detail = table(["input", "ρ", "runs"],
                       [[f"<code>{esc(lab)}</code>", num(f"spearman.{key}.{lab}", r, digits=3),
                         num(f"spearman.{key}.{lab}.n", n)] for lab, r, n in ranked], "narrow")
        figs.append("<div class='cell'>" + page.figure(fig, f"tornado_{key}.png",
                                                         f"Spearman ρ with {key}", "half")
                    + f"<details><summary>values</summary>{detail}</details></div>")
    out.append("<h3>Tornado charts</h3><div class='grid'>" + "".join(figs) + "</div>")
    if c.sensitivity is not None:
        out.append(subsection_sobol(page, c))
    elif c.attrs["sampling"] == "saltelli":
        out.append("<p class='warn'>Saltelli sampling, but the file has no /sensitivity.</p>")
    out.append("</section>")
    return "\n".join(out)


def fig_tornado(plt, ranked, aggregate, title, band):
    labels = [lab for lab, _, _ in ranked][::-1]
    vals = np.array([r for _, r, _ in ranked][::-1])
    fig, ax = plt.subplots(figsize=(7.4, 0.32 * len(labels) + 1.4))
    colors = ["C3" if v > 0 else "C0" for v in vals]
    bars = ax.barh(range(len(vals)), vals, color=colors, alpha=0.85)
    for bar, lab in zip(bars, labels):
        if lab in aggregate:
            bar.set_hatch("///")
            bar.set_edgecolor("k")
    ax.axvspan(-band, band, color="0.8", alpha=0.6, zorder=0)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_yticks(range(len(vals)))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_xlim(-1.05, 1.05)
    ax.set_xlabel("Spearman ρ (1)")
    for i, v in enumerate(vals):
        ax.text(v, i, f" {v:+.3f} ", va="center", ha="left" if v > 0 else "right", fontsize=6)
    ax.set_title(f"{title}: top {len(vals)} inputs by |ρ|", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    fig.tight_layout()
    return fig


def subsection_sobol(page, c):
    s = c.sensitivity
    factors = s["factor"]
    outs = s["outputs"]
    meth = outs[next(iter(outs))]
    parts = ["<h3>Sobol' indices (Saltelli sampling)</h3>",
             "<p>From <code>/sensitivity</code>, as the campaign computed them: method "
             f"“{esc(meth['method'])}”, {fmt(meth['confidence'], 3)} confidence intervals from "
             f"{meth['n_resamples']} bootstrap resamples. A factor is a whole dispersion "
             "(a per-bay "
             "dispersion moves all its bays together). Indices are dimensionless.</p>",
             out_of_range_note(outs),
             page.figure(fig_sobol(page.plt, factors, outs), "sobol_indices.png",
                         "first-order and total Sobol' indices with their confidence intervals")]
    cells = []
    for key, o in outs.items():
        rows = [[f"<code>{esc(fac)}</code>"]
                + [num(f"sobol.{key}.{fac}.{k}", float(o[k][g]), digits=3)
                   for k in ("first_order", "first_order_lo", "first_order_hi",
                             "total", "total_lo", "total_hi")] for g, fac in enumerate(factors)]
        cells.append(f"<div class='cell'><h4><code>{key}</code></h4><p>blocks used "
                     f"{num(f'sobol.{key}.n_blocks', o['n_blocks'], tag='span')}, dropped "
                     f"{num(f'sobol.{key}.n_blocks_dropped', o['n_blocks_dropped'], tag='span')}"
                     "</p>" + table(["factor", "S1", "S1 low", "S1 high", "ST", "ST low",
                                     "ST high"], rows, "narrow") + "</div>")
    parts.append("<div class='grid'>" + "".join(cells) + "</div>")
    return "\n".join(parts)


def out_of_range_note(outs):
    """A warning when point estimates fall outside [0, 1]: the estimators are unbiased, not
    bounded, and such values mean too few blocks for that output."""
    bad = [key for key, o in outs.items()
           if np.any((o["first_order"] < 0) | (o["first_order"] > 1)
                     | (o["total"] < 0) | (o["total"] > 1))]
    if not bad:
        return ""
    return ("<p class='warn'>Some estimates lie outside [0, 1] ("
            + ", ".join(f"<code>{k}</code>" for k in bad)
            + "): the estimators are unbiased but not bounded, so such values mean that the "
              "blocks are too few for that output. Read the confidence intervals, or run more "
              "blocks.</p>")


def fig_sobol(plt, factors, outs):
    G = len(factors)
    ncol = 3
    nrow = -(-len(outs) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(15.0, 3.2 + 0.25 * G + 3.0 * (nrow - 1)),
                             squeeze=False)
    y = np.arange(G)
    for ax, (key, o) in zip(axes.ravel(), outs.items()):
        for k, dy, color, label in (("first_order", 0.2, "C0", "first order S1"),
                                    ("total", -0.2, "C1", "total ST")):
            ok = np.isfinite(o[k])            # NaN: undefined (e.g. an output that never varies)
            ax.barh(y[ok] + dy, o[k][ok], 0.4, color=color, label=label)
            ok &= np.isfinite(o[k + "_lo"]) & np.isfinite(o[k + "_hi"])
            ax.hlines(y[ok] + dy, o[k + "_lo"][ok], o[k + "_hi"][ok], color="k", lw=1.2)
        ax.set_yticks(y)
        ax.set_yticklabels(factors, fontsize=7)
        ax.set_ylim(G - 0.5, -0.5)
        undefined = not np.all(np.isfinite(o["first_order"]) & np.isfinite(o["total"]))
        ax.set_title(key + (" (some indices undefined: NaN)" if undefined else ""), fontsize=9)
        ax.set_xlabel("Sobol' index (1); black: CI")
        ax.grid(True, axis="x", alpha=0.3)
    axes.ravel()[0].legend(fontsize=7)
    for ax in axes.ravel()[len(outs):]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig


def section_histories(page, c):
    if not c.histories:
        return ""
    shown = list(c.histories)[:MAX_HISTORY_FIGURES]
    parts = ['<section id="histories"><h2>6. Time histories of selected runs</h2>',
             "<p>From <code>/histories/run_&lt;i&gt;</code> (the campaign's "
             "<code>[output] history_runs</code>): drive force and rail pin force against time, "
             "lock times dashed (as paper Fig. 5).</p>"]
    if len(c.histories) > len(shown):
        parts.append(f"<p>(the first {len(shown)} of {len(c.histories)} histories)</p>")
    for i in shown:
        parts.append(page.figure(rf.fig5(page.plt, c.histories[i]), f"history_run_{i}.png",
                                 f"run {i}: drive force and rail pin force against time"))
    parts.append("</section>")
    return "\n".join(parts)


def section_checks(page, number):
    rows = [[esc(what), ("<span class='okc'>pass</span>" if passed
                         else "<span class='bad'>FAIL</span>"), detail]
            for what, passed, detail in page.checks]
    return (f'<section id="checks"><h2>{number}. Consistency of the file</h2>'
            "<p>The report recomputes from <code>/runs</code> what the file also stores in "
            "<code>/stats</code>, and compares: counts exactly, other statistics to "
            f"{AGREE_RTOL:g} of the largest |value| of the column.</p>"
            + table(["check", "result", "detail"], rows) + "</section>")


def campaign_report(page, c):
    body = [section_campaign(page, c), section_loads(page, c), section_lock_timing(page, c),
            section_margins(page, c), section_sensitivity(page, c), section_histories(page, c)]
    n_checks = 7 if c.histories else 6
    body.append(section_checks(page, n_checks))
    failed = [what for what, passed, _ in page.checks if not passed]
    banner = ("<p class='warn'>The file is not consistent with itself: "
              + "; ".join(esc(w) for w in failed)
              + f". See section {n_checks}.</p>") if failed else ""
    toc = ("<nav>1. <a href='#campaign'>Campaign</a> · 2. <a href='#loads'>Peak loads</a> · "
           "3. <a href='#locks'>Lock timing</a> · 4. <a href='#margins'>Margins</a> · "
           "5. <a href='#sensitivity'>What drives the loads</a>"
           + (" · 6. <a href='#histories'>Histories</a>" if c.histories else "")
           + f" · {n_checks}. <a href='#checks'>Consistency</a></nav>")
    title = f"Statistical load report: campaign “{c.attrs['campaign_name']}”"
    return html_page(title, c.path, c.sha256, banner + toc + "\n".join(body))


# ============================================================================================
# Single-run report
# ============================================================================================

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


def single_run_report(page, run):
    """Summary table, per-bay table and paper Fig. 4 / Fig. 5 (postproc/run_figures.py)."""
    rows = []
    for name, v, u in run["summary"]:
        if isinstance(v, str):
            rows.append([f"<code>{name}</code>", esc(v), ""])
        else:
            rows.append([f"<code>{name}</code>", num(f"summary.{name}", v, digits=9), esc(u)])
    status, message = run["status"], run["message"]
    meta = [("software", f"truss {esc(run['software_version'])}, git revision "
                         f"<code>{esc(run['git_revision'])}</code>"),
            ("written (UTC)", esc(run["created_utc"])),
            ("status", f"<b>{esc(status)}</b>" + (f": {esc(message)}" if message else ""))]
    parts = [table(["", ""], [[f"<th>{k}</th>", v] for k, v in meta], "kv"),
             f"<details><summary>scene_toml</summary><pre>{esc(run['scene_toml'])}</pre>"
             "</details>",
             "<section id='summary'><h2>Summary</h2>",
             table(["field", "value", "units"], rows, "narrow"), "</section>",
             single_run_bays(run), single_run_figures(page, run["figures"])]
    title = f"Single-run report: {os.path.basename(run['path'])} (status {status})"
    return html_page(title, run["path"], run["sha256"], "\n".join(parts))


def single_run_bays(run):
    b = run["bays"]
    if not b:
        return ""
    fields = [k for k in b if k != "bay"]
    rows = [[str(bay)] + [num(f"bays.{k}.bay{bay}", float(b[k][i]), digits=7) for k in fields]
            for i, bay in enumerate(b["bay"])]
    return ("<section id='bays'><h2>Per bay</h2><details><summary>per-bay table "
            f"({len(b['bay'])} bays)</summary>"
            + table(["bay"] + [f"<code>{k}</code>{unit_label(run['bay_units'][k])}"
                               for k in fields], rows)
            + "</details></section>")


def single_run_figures(page, run):
    head = "<section id='figures'><h2>Figures (paper Fig. 4 and Fig. 5)</h2>"
    if run is None:
        return (head + "<p class='note'>The file has no <code>/history</code>: run truss-sim "
                "with <code>run.output_step_s &gt; 0</code> for the figures.</p></section>")
    bay = run["n_bays"]
    h = run["history"]
    sel = h["bay"] == bay
    parts = [head]
    if np.any(np.isfinite(h["hinge_x_m"][sel]) & np.isfinite(h["hinge_y_m"][sel])):
        parts.append(page.figure(rf.fig4(page.plt, run, bay),
                                 f"fig4_hinge_trajectory_bay{bay}.png",
                                 f"hinge trajectory of bay {bay} (paper Fig. 4)", "half"))
    else:
        parts.append(f"<p class='note'>No hinge samples of bay {bay}: no Fig. 4.</p>")
    parts.append(page.figure(rf.fig5(page.plt, run), "fig5_drive_and_pin_force.png",
                             "drive force and rail pin force against time (paper Fig. 5)"))
    if np.any(sel):
        parts.append(page.figure(rf.fig5_zoom(page.plt, run, bay), f"fig5_bay{bay}_zoom.png",
                                 f"the same in the stage of bay {bay}"))
    parts.append("</section>")
    return "\n".join(parts)


# ============================================================================================
# Page and output
# ============================================================================================

CSS = """
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 14px; margin: 24px auto;
       max-width: 1400px; color: #222; padding: 0 16px; }
h1 { font-size: 24px; margin-bottom: 4px; } h2 { border-bottom: 2px solid #345; margin-top: 36px; }
h3 { margin-top: 24px; } .meta { color: #555; font-size: 12px; }
nav { background: #eef2f6; padding: 6px 10px; margin: 12px 0; }
table { border-collapse: collapse; margin: 8px 0 14px 0; font-size: 13px; }
th, td { border: 1px solid #c8cdd3; padding: 3px 8px; text-align: left; vertical-align: top; }
thead th { background: #e6ebf0; } table.kv th { background: #f3f5f7; width: 220px; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.toosmall { color: #8a5a00; } table.corr td.num { min-width: 70px; }
figure { margin: 8px 0 16px 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figure.half img { max-width: 100%; } figcaption { font-size: 12px; color: #555; }
.flex { display: flex; flex-wrap: wrap; gap: 0 18px; align-items: flex-start; }
.grid { display: grid; grid-template-columns: 1fr 1fr; gap: 12px 24px; }
.note { color: #555; font-style: italic; }
.warn { background: #fde8e8; border: 1px solid #d33; padding: 8px; }
.okc { color: #176b17; font-weight: bold; } .bad { color: #c00; font-weight: bold; }
pre { background: #f6f8fa; padding: 8px; font-size: 12px; overflow-x: auto; }
details { margin: 6px 0 12px 0; } summary { cursor: pointer; color: #234; }
"""


def html_page(title, path, sha256, body):
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f"<title>{esc(title)}</title><style>{CSS}</style></head><body>\n"
            f"<h1>{esc(title)}</h1>\n<p class='meta'>Built {now} by "
            "<code>postproc/report.py</code> "
            f"from <code>{esc(os.path.abspath(path))}</code> (SHA-256 <code>{sha256}</code>).</p>\n"
            f"{body}\n</body></html>\n")


def check_outdir(outdir, force):
    if os.path.exists(outdir):
        if not os.path.isdir(outdir):
            raise InputError(f"{outdir}: exists and is not a directory")
        if os.listdir(outdir) and not force:
            raise InputError(f"{outdir}: directory is not empty; use --force to write into it")


def build(path, outdir, force):
    """Validate, then render into a staging directory beside OUTDIR and move the files in."""
    check_outdir(outdir, force)
    sha256 = file_sha256(path) if os.path.isfile(path) else ""
    with rf.open_h5(path) as f:
        h5 = H5(f, path)
        try:
            kind = read_kind(h5)
            data = load_campaign(h5, sha256) if kind == "campaign" else load_single_run(h5, sha256)
        except (OSError, RuntimeError) as e:
            raise InputError(f"{path}: damaged or unreadable HDF5 file ({e})") from None

        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        parent = os.path.dirname(os.path.abspath(outdir))
        os.makedirs(parent, exist_ok=True)
        staging = tempfile.mkdtemp(prefix=f".{os.path.basename(outdir)}.", dir=parent)
        try:
            page = Page(staging, plt)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                text = (campaign_report(page, data) if kind == "campaign"
                        else single_run_report(page, data))
            with open(os.path.join(staging, REPORT_NAME), "w", encoding="utf-8") as fh:
                fh.write(text)
            os.makedirs(outdir, exist_ok=True)
            for name in page.files + [REPORT_NAME]:   # report.html last
                os.replace(os.path.join(staging, name), os.path.join(outdir, name))
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    return os.path.join(outdir, REPORT_NAME)


def main(argv=None):
    p = rf._Parser(prog="report.py",
                   description="Statistical load report (HTML + PNG) of a truss-campaign file, "
                               "or the report of a truss-sim single-run file.")
    p.add_argument("results", metavar="RESULTS.h5", help="campaign or single-run HDF5 file")
    p.add_argument("-o", "--outdir", required=True, metavar="DIR",
                   help="output directory: new or empty, unless --force")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty DIR, replacing files of the same names")
    args = p.parse_args(argv)
    try:
        print(build(args.results, args.outdir, args.force))
    except InputError as e:
        sys.stderr.write(f"error: {e}\n")
        return EXIT_INPUT_ERROR
    return 0


if __name__ == "__main__":
    sys.exit(main())
