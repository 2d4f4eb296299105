"""truss_report.judging.subset and .sweep: the lognormal interval, the plateau rule, the design
point, and the sweep verdict: the file's, never overridden."""
import math

import numpy as np
import pandas as pd
import pytest

from conftest import make_campaign
from truss_report.judging.subset import count_plateau_levels, design_point, interval
from truss_report.judging.sweep import sweep_frame, sweep_reason, sweep_verdict
from truss_report.judging.verdict import FAIL, NOT_ASSESSED, PASS
from truss_report.reading.campaign import Dispersion
from truss_report.reading.methods import Subset, SweepTable


def test_interval_is_lognormal():
    lo, hi = interval(1e-4, 0.5)
    s = math.sqrt(math.log(1.25))
    assert lo == pytest.approx(1e-4 / math.exp(1.959963984540054 * s)) and lo * hi == pytest.approx(1e-8)
    assert all(math.isnan(v) for v in interval(0.0, 0.5))


def test_plateau_levels():
    assert count_plateau_levels([1.0, 0.995, 0.9, 0.8999, 0.0]) == 2     # moves of 0.5 % and 0.01 %
    assert count_plateau_levels([1.0, 0.5, 0.0]) == 0


@pytest.mark.parametrize("stored,want", [("PASS", PASS), ("FAIL", FAIL), ("NOT ASSESSED", NOT_ASSESSED),
                                         ("", NOT_ASSESSED)])
def test_sweep_verdict_is_the_files(stored, want):
    df = pd.DataFrame({"value": [1.0]})
    df.attrs.update({"units": {"value": "m"}, "allowable": {"verdict": stored, "reason": "why"}})
    assert sweep_verdict(sweep_frame(SweepTable(df, [None]))) == want


def test_sweep_frame_counts_the_plateaus_but_keeps_the_files_verdict():
    df = pd.DataFrame({"value": [1.0, 2.0, 3.0]})
    df.attrs.update({"units": {"value": "m"}, "allowable": {"verdict": "PASS", "reason": "the file's reason"}})
    flat = np.array([1.0, 0.999, 0.998, 0.997, 0.996, 0.0])
    s = sweep_frame(SweepTable(df, [None, np.array([1.0, 0.5, 0.0]), flat]))
    assert s["plateau_levels"].tolist() == [0, 0, 4]
    assert sweep_verdict(s) == PASS and sweep_reason(s) == "the file's reason"


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
