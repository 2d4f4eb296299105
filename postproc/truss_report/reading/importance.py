"""truss_report.reading.importance: the results of a standalone cross-entropy importance-sampling
campaign (ensemble.method = "importance"): the file's /importance group (docs/hdf5-schema.md),
checked as it is read: a missing or malformed member is an InputError naming the file and the
member (the report's one `error:` line, exit 2)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .h5file import H5, Array, InputError

IMPORTANCE_ATTRS = ("status", "message", "density_refusal", "refused", "confidence", "failure_column",
                    "failure_kind", "margin_units", "n_per_level", "n_final", "rho", "max_levels")
IMPORTANCE_SCALARS = ("p", "cov", "lower", "upper", "upper_bound", "ess", "pareto_k", "final_runs",
                      "failures", "runs", "unusable")
LEVEL_COLUMNS = ("threshold", "elites", "elite_ess", "shift", "moved", "mean_noise", "runs", "unusable")


@dataclass
class Importance:
    """/importance: the weighted estimate of the final runs, the cross-entropy levels and the final
    density's mean in the standard normal space of the dispersions."""
    attrs: dict[str, Any]         # status, message, refused, failure_column, ... (as stored, str decoded)
    p: float
    cov: float
    lower: float                  # 95 % interval (NaN when refused)
    upper: float
    upper_bound: float            # one-sided 95 % upper bound (NaN when refused)
    ess: float                    # Kish's effective sample size of the failing final runs
    pareto_k: float
    final_runs: int
    failures: int
    runs: int
    unusable: int
    levels: dict[str, Array]      # LEVEL_COLUMNS, one row per cross-entropy level
    level_units: str              # the threshold's unit (the margin's)
    final_mean: Array             # d: the final density's mean (standard normal units)

    @property
    def status(self) -> str:
        return str(self.attrs["status"])

    @property
    def refused(self) -> str:
        """Empty when the estimate stands; else why not."""
        return str(self.attrs["refused"])


def _attrs(h5: H5, names: tuple[str, ...]) -> dict[str, Any]:
    g = h5.group("importance")
    missing = [k for k in names if k not in g.attrs]
    if missing:
        raise h5.error(f"/importance lacks the attribute{'s' if len(missing) > 1 else ''} {', '.join(missing)}")
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in g.attrs.items()}


def read_importance(h5: H5) -> Importance | None:
    """The /importance group of a standalone importance campaign, or None without one."""
    if not h5.has("importance"):
        return None
    try:
        attrs = _attrs(h5, IMPORTANCE_ATTRS)
        if attrs["failure_kind"] != "margin" and "failure_threshold" not in attrs:
            raise h5.error("/importance lacks the attribute failure_threshold")
        s = {k: h5.scalar(f"importance/{k}") for k in IMPORTANCE_SCALARS}
        n = h5.length("importance/levels/threshold")
        levels = {k: h5.array(f"importance/levels/{k}", (n,)) for k in LEVEL_COLUMNS}
        return Importance(attrs, s["p"], s["cov"], s["lower"], s["upper"], s["upper_bound"], s["ess"],
                          s["pareto_k"], int(s["final_runs"]), int(s["failures"]), int(s["runs"]),
                          int(s["unusable"]), levels, h5.units("importance/levels/threshold"),
                          np.asarray(h5.array("importance/final_mean", (h5.length("importance/final_mean"),))))
    except (KeyError, ValueError, TypeError) as e:   # a member of the wrong kind (a group for a dataset)
        raise InputError(f"{h5.path}: malformed /importance ({e})") from None
