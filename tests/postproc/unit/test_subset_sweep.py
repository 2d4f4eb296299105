"""truss_report.judging.subset and .sweep: the lognormal interval, the plateau rule, the design
point, and the sweep verdict: the file's, never overridden by a rule of the report, but checked
against the numbers of its file (judge_sweep)."""
import math

import numpy as np
import pandas as pd
import pytest

from conftest import make_campaign
from truss_report.judging.subset import count_plateau_levels, design_point, interval
from truss_report.judging.sweep import judge_sweep, no_result_counts, sweep_frame, sweep_reason, sweep_verdict
from truss_report.judging.verdict import FAIL, NOT_ASSESSED, PASS
from truss_report.reading.campaign import Dispersion
from truss_report.reading.methods import Subset, SweepRuns, SweepTable


def test_interval_is_lognormal():
    lo, hi = interval(1e-4, 0.5)
    s = math.sqrt(math.log(1.25))
    assert lo == pytest.approx(1e-4 / math.exp(1.959963984540054 * s)) and lo * hi == pytest.approx(1e-8)
    assert all(math.isnan(v) for v in interval(0.0, 0.5))
    assert interval(0.6, 0.5)[1] == 1.0          # 0.6 exp(1.96 s) = 1.5: a probability stops at 1


def test_plateau_levels():
    assert count_plateau_levels([1.0, 0.995, 0.9, 0.8999, 0.0]) == 2     # moves of 0.5 % and 0.01 %
    assert count_plateau_levels([1.0, 0.5, 0.0]) == 0


def sweep(verdict="PASS", value=14.0, own=30.0, p=(1e-3, 1e-5, 1e-7), ub=(3e-3, 4e-5, 5e-7), runs=None, side="above",
          thresholds=None):
    """A sweep at 12, 14, 16 (allowable `value`, safe side `side`, the design's own value `own`)."""
    df = pd.DataFrame({"value": [12.0, 14.0, 16.0], "p": list(p), "cov": [0.3] * 3, "upper_bound": list(ub),
                       "lower": [x / 3 for x in p], "upper": [x * 3 for x in p], "runs": [100] * 3,
                       "refinement": [False] * 3})
    df.attrs.update({"units": {"value": "Nm"}, "target_probability": 1e-6,
                     "allowable": {"status": "found", "verdict": verdict, "value": value, "own_value": own,
                                   "safe_side": side, "estimate": value - 0.5, "lower": value - 1, "upper": value + 1}})
    return sweep_frame(SweepTable(df, thresholds or [None] * 3, runs))


def test_a_supported_verdict_stands():
    assert judge_sweep(sweep()).verdict == PASS and judge_sweep(sweep("FAIL", own=13.0)).verdict == FAIL
    assert judge_sweep(sweep("FAIL", value=10.0, own=20.0, side="below")).verdict == FAIL


@pytest.mark.parametrize("change,reason", [
    (dict(value=float("nan")), "allowable_nan"),                 # "≥ — mN m" and PASS
    (dict(own=float("nan")), "own_nan"),
    (dict(p=(np.nan,) * 3, ub=(np.nan,) * 3), "no_estimate"),   # every estimate NaN
    (dict(own=13.0), "wrong_side"),                              # PASS with the own value below the allowable
    (dict(ub=(3e-3, 4e-5, 2e-6)), "safe_side_above_target"),    # 16 on the safe side of 14, above 1e-6
])
def test_a_verdict_without_evidence_is_not_assessed(change, reason):
    j = judge_sweep(sweep(**change))
    assert j.verdict == NOT_ASSESSED and reason in [what for what, _ in j.reasons] and j.file_verdict == "PASS"


def test_runs_without_a_result_never_count_as_safe():
    names = {0: "ok", 2: "stall", 6: "wall-time limit"}
    value = np.repeat([12.0, 14.0, 16.0], 100)
    status = np.zeros(300, dtype=np.int64)
    status[150:152] = 6                                           # 2 of the 100 runs at 14: past 1 %
    status[50:60] = 2                                             # stalls are results (failures)
    margin = np.ones(300)
    margin[250] = np.nan                                          # an ok run at 16 without a margin: 1 %
    runs = SweepRuns(value, status, names, margin)
    assert no_result_counts([12.0, 14.0, 16.0], runs) == [0, 2, 1]
    # truss-campaign decides on them (it writes NOT ASSESSED); a stored PASS past the share is a
    # file truss-campaign never writes, so the report's check refuses it; a stored FAIL stands.
    j = judge_sweep(sweep(runs=runs))
    assert j.verdict == NOT_ASSESSED and j.reasons == [("no_result", [1])]
    assert judge_sweep(sweep("FAIL", own=13.0, runs=runs)).verdict == FAIL
    assert no_result_counts([12.0], None) == [-1]


def test_probabilities_are_clipped():
    s = sweep(p=(0.5, 1e-5, 1e-7))                                # upper = 3 p = 1.5
    assert s["upper"].tolist()[0] == 1.0 and s["lower"].tolist()[0] == pytest.approx(0.5 / 3)


def test_plateau_rows():
    flat = np.array([1.0, 0.999, 0.998, 0.997, 0.996, 0.0])
    s = sweep(thresholds=[None, np.array([1.0, 0.5, 0.0]), flat])
    assert s["plateau_levels"].tolist() == [0, 0, 4] and sweep_verdict(s) == PASS   # the file's
    assert judge_sweep(sweep("FAIL", own=13.0, thresholds=[None, None, flat])).verdict == FAIL
    assert judge_sweep(sweep("NOT ASSESSED")).verdict == NOT_ASSESSED


def test_sweep_verdict_and_reason_are_the_files():
    s = sweep("NOT ASSESSED")
    s.attrs["allowable"]["reason"] = "the file's reason"
    assert sweep_verdict(s) == NOT_ASSESSED and sweep_reason(s) == "the file's reason"
    assert sweep_verdict(sweep()) == PASS and sweep_verdict(sweep("FAIL", own=13.0)) == FAIL


def test_design_point_is_the_sample_of_smallest_z():
    z = np.array([[3.0, 4.0, 0.0], [1.0, 0.0, -2.0], [0.0, 3.0, 3.0]])   # |z| 5, sqrt(5), sqrt(18)
    x1, x2 = np.array([10.0, 11.0, 12.0]), np.array([[1.0, 2.0], [3.0, 5.0], [0.0, 0.0]])
    s = Subset({}, 1e-3, 0.1, 0.1, 3.0, 1e5, 0.1, "bound", 100, 50, {"runs": np.array([10])}, "m",
               np.array([7, 8, 9]), np.array([-0.1, -0.2, -0.3]), z,
               {"a": (x1, 10.0, "m"), "b": (x2, 2.0, "m")})
    d = [Dispersion("a", "run", "absolute", "normal", {}, 10.0, "m", 0, np.zeros(10)),
         Dispersion("b", "bay", "absolute", "normal", {}, 2.0, "m", 1, np.zeros((10, 2)))]
    dp = design_point(s, make_campaign({"peak_drive_force_N": np.ones(10)}, dispersions=d))
    assert dp.run == 8 and dp.beta == pytest.approx(math.sqrt(5)) and dp.margin == -0.2
    rows = {r.key: r for r in dp.rows}
    assert rows["a"].alpha == pytest.approx(-1 / math.sqrt(5)) and rows["a"].value == 11.0
    assert rows["b"].share == pytest.approx(4 / 5) and rows["b"].value == 4.0 and math.isnan(rows["b"].alpha)
    assert [r.key for r in dp.rows] == ["b", "a"]
