"""truss_report.judging.verdict: which items a campaign gets and the verdict they make."""
import numpy as np

from conftest import make_campaign
from truss_report.judging.design import DesignLoad, LevelValue
from truss_report.judging.mechanism import Margins
from truss_report.judging.verdict import FAIL, NOT_ASSESSED, PASS, verdict_items, verdict_of


def load(rank):
    return DesignLoad("peak_drive_force_N", "f", "d", "N", False, 900, 1.0, 1.0, 0.5, 2.0,
                      [LevelValue(99.865, 2.0, float("nan"), rank, None if rank else 2218)])


def test_pass_when_nothing_is_left():
    c = make_campaign({"peak_drive_force_N": [1.0, 2.0]})
    m = Margins("velocity", 2.0, 1.2, n=2)
    items = verdict_items(c, m, [], "ok", [load(5)])
    assert items == [] and verdict_of(items) == PASS


def test_each_reason():
    c = make_campaign({"peak_drive_force_N": np.ones(5)}, status=[0, 2, 4, 4, 0])
    m = Margins("velocity", 2.0, 1.2, n=3, n_below=1, mf_min=1.5)
    items = verdict_items(c, m, ["status counts"], "stall", [load(None)])
    got = [(it.what, it.kind, it.name, it.count) for it in items]
    assert got == [("margin", FAIL, "", 1), ("status", FAIL, "stall", 1), ("status", NOT_ASSESSED, "step limit", 2),
                   ("nominal", FAIL, "stall", 0), ("too_few", NOT_ASSESSED, "", 900), ("check", FAIL, "status counts", 0)]
    assert items[4].needed == 2218 and verdict_of(items) == FAIL
    assert verdict_of([it for it in items if it.kind == NOT_ASSESSED]) == NOT_ASSESSED


def test_missing_margins_are_not_assessed():
    c = make_campaign({"peak_drive_force_N": [1.0]})
    items = verdict_items(c, Margins("velocity", 2.0, 1.2, note="no S", missing=True), [], "ok")
    assert [(it.what, it.kind, it.name) for it in items] == [("margin_missing", NOT_ASSESSED, "no S")]
