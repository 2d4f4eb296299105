"""truss_report.judging.motor_answer: one motor answer from two campaigns of the same mast. A load
report states the stall torque needed as the upper confidence bound of the top percentile of the
per-run stall torque that meets the ECSS motorisation factors (judging.mechanism); a motor-sizing
sweep (a [sweep] of drive.stall_torque_Nm with the failure margin motorisation_margin) states the
smallest stall torque whose one-sided upper bound on P(margin <= 0) is at or below its target
(judging.sweep). Both are stall torques that a motor needs, each a criterion that only gets easier
as the stall torque grows, so the larger one meets both: it governs.

The two files must describe the same mast: their base scenes (the resolved scene TOML of each file)
must agree on every key but
  - the swept key (the sweep's own design variable),
  - keys that a campaign draws absolutely (apply = "absolute": the base value never enters a run),
  - [structure] (the allowables of the parts: not part of the motor's answer),
  - [run] other than run.direction (the integrator's settings and caps: how the runs were computed,
    not what was computed).
A key that a campaign disperses relative to its base value or offsets from it is compared: its
base value is the nominal of its dispersion. Dispersions themselves may differ (the sweep may
scatter the motor, the load report the geometry): the answer lists those only one of them has."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..reading.campaign import Campaign
from .mechanism import Margins
from .sweep import judge_sweep, sweep_reason
from .verdict import FAIL, PASS

SIZING_VARIABLE = "drive.stall_torque_Nm"
SIZING_FAILURE = "motorisation_margin"
IGNORED_TABLES = ("structure",)
RUN_KEYS_COMPARED = ("direction",)
LOAD, SWEEP = "load_report", "sweep"


def flat_scene(scene: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """The scene's values by dotted key ("mast.n_bays")."""
    out: dict[str, Any] = {}
    for k, v in scene.items():
        if isinstance(v, Mapping):
            out.update(flat_scene(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def compared(key: str, ignored: set[str]) -> bool:
    table = key.split(".", 1)[0]
    if key in ignored or table in IGNORED_TABLES:
        return False
    return table != "run" or key.split(".", 1)[1] in RUN_KEYS_COMPARED


def scene_differences(a: Campaign, b: Campaign, swept: str) -> tuple[list[tuple[str, Any, Any]], int]:
    """([(key, value in a, value in b)] of the compared keys that differ (None: absent), the number
    of keys compared)."""
    ignored = {swept} | {d.key for d in (*a.dispersions, *b.dispersions) if d.apply == "absolute"}
    fa, fb = flat_scene(a.base_scene), flat_scene(b.base_scene)
    keys = sorted(k for k in set(fa) | set(fb) if compared(k, ignored))
    return [(k, fa.get(k), fb.get(k)) for k in keys if fa.get(k) != fb.get(k)], len(keys)


def sizing_problem(s: pd.DataFrame) -> str:
    """Why a design sweep cannot state the motor's figure ("" when it can): it must sweep the
    stall torque with the motorisation margin as its failure."""
    at = s.attrs
    if at["variable"] != SIZING_VARIABLE:
        return f"its design variable is {at['variable']}, not {SIZING_VARIABLE}"
    if at.get("failure_column") != SIZING_FAILURE or at.get("failure_kind") != "margin":
        return f"its failure event is on {at.get('failure_column')}, not the margin {SIZING_FAILURE}"
    return ""


@dataclass
class Figure:
    """A needed stall torque (N m at the motor, declared: before derating; NaN when the campaign
    gives none, `why` then says why), with its statistical basis and its file."""
    value: float
    file: str
    sha256: str
    level: float = float("nan")         # load report: percent of the percentile
    confidence: float = float("nan")
    target: float = float("nan")        # sweep: the target probability
    n_needed: int = 0                   # load report: runs a bound needs when it has none
    why: str = ""


@dataclass
class MotorAnswer:
    load: Figure
    sweep: Figure
    n_compared: int                     # scene keys found equal
    only_load: list[str] = field(default_factory=list)    # keys dispersed in the load report only
    only_sweep: list[str] = field(default_factory=list)
    own_value: float = float("nan")     # the scene's stall torque (the sweep's own design value)
    factors_replaced: bool = False      # the report's options replaced the scene's factors

    @property
    def governs(self) -> str:
        """LOAD or SWEEP: the larger figure ("" when either is missing; LOAD when they are equal)."""
        a, b = self.load.value, self.sweep.value
        if not (np.isfinite(a) and np.isfinite(b)):
            return ""
        return LOAD if a >= b else SWEEP

    @property
    def governing_value(self) -> float:
        return {LOAD: self.load.value, SWEEP: self.sweep.value}.get(self.governs, float("nan"))


def load_figure(c: Campaign, m: Margins) -> Figure:
    why = "" if np.isfinite(m.stall_needed) else (
        f"too few runs for the bound: it needs at least {m.stall_n_needed} ok runs" if m.stall_n_needed
        else f"no stall torque needed: {m.note or 'no run has a resistance to overcome'}")
    return Figure(m.stall_needed, c.path, c.sha256, level=m.stall_level, confidence=m.stall_confidence,
                  n_needed=m.stall_n_needed, why=why)


def sweep_figure(c: Campaign, s: pd.DataFrame) -> Figure:
    """The sweep's allowable when the report shows its verdict as PASS or FAIL (the numbers of the
    file support it: judging.sweep); else NaN and the reason."""
    a, at = s.attrs["allowable"], s.attrs
    j = judge_sweep(s)
    ok = j.verdict in (PASS, FAIL) and a["status"] == "found" and np.isfinite(a["value"])
    why = "" if ok else (f"no allowable: {a['message']}" if a["status"] != "found" else
                         f"its verdict is NOT ASSESSED: {sweep_reason(s) or ', '.join(r for r, _ in j.reasons)}")
    return Figure(float(a["value"]) if ok else float("nan"), c.path, c.sha256,
                  confidence=float(at["confidence"]), target=float(at["target_probability"]), why=why)


def calc_motor_answer(load_c: Campaign, m: Margins, sweep_c: Campaign, s: pd.DataFrame,
                      factors_replaced: bool = False) -> MotorAnswer:
    """The two figures (the files are the same mast: scene_differences is empty)."""
    _, n = scene_differences(load_c, sweep_c, str(s.attrs["variable"]))
    keys_load = {d.key for d in load_c.dispersions}
    keys_sweep = {d.key for d in sweep_c.dispersions}
    return MotorAnswer(load_figure(load_c, m), sweep_figure(sweep_c, s), n,
                       sorted(keys_load - keys_sweep), sorted(keys_sweep - keys_load),
                       float(s.attrs["allowable"]["own_value"]), factors_replaced)
