"""truss_report.judging.structure: margins of safety against declared allowables, by hand."""
import numpy as np

from truss_report.judging.design import DesignLoad, LevelValue
from truss_report.judging.structure import (FAIL, NOT_ASSESSED, PASS, calc_bay_margins,
                                            calc_structural_margins, load_status, structural_verdict)
from truss_report.reading.extras import Extras


def load(key, bound):
    return DesignLoad(key, key, "d", "N", False, 3000, 0, 1.0, 1.0, 0.5, 2.0,
                      [LevelValue(99.865, 0.9 * bound, bound, 2990 if np.isfinite(bound) else None, None)])


def test_margin_by_hand():
    loads = [load("peak_pin_force_N", 10.0), load("peak_drive_force_N", 30.0)]
    s = {"yield_factor": 1.1, "ultimate_factor": 1.25, "pin_force_yield_allowable_N": 12.0,
         "screw_force_ultimate_allowable_N": 11.0, "drive_force_yield_allowable_N": 30.0}
    ms = {(m.stem, m.limit): m for m in calc_structural_margins(loads, s)}
    assert abs(ms["pin_force", "yield"].margin - (12.0 / (1.1 * 10.0) - 1.0)) < 1e-15   # +0.0909
    assert np.isnan(ms["pin_force", "ultimate"].margin)                                  # not declared
    assert abs(ms["screw_force", "ultimate"].margin - (11.0 / (1.25 * 10.0) - 1.0)) < 1e-15  # a third: -0.12
    assert abs(ms["drive_force", "yield"].margin - (30.0 / 33.0 - 1.0)) < 1e-15
    assert ("diagonal_tension", "yield") not in ms                                       # no such load
    assert load_status(list(ms.values()), "pin_force") == PASS      # yield declared, ultimate not: assessed
    assert load_status(list(ms.values()), "screw_force") == FAIL
    assert structural_verdict(list(ms.values())) == FAIL


def test_undeclared_and_unbounded_are_not_assessed():
    s = {"pin_force_yield_allowable_N": 12.0}
    ms = calc_structural_margins([load("peak_pin_force_N", float("nan")), load("peak_diagonal_tension_N", 5.0)], s)
    assert load_status(ms, "pin_force") == NOT_ASSESSED             # declared, but no bound
    assert load_status(ms, "diagonal_tension") == NOT_ASSESSED      # nothing declared
    assert structural_verdict(ms) == NOT_ASSESSED
    assert structural_verdict([]) == NOT_ASSESSED
    assert "no yield allowable declared" in [m for m in ms if m.stem == "diagonal_tension"][0].reason


def test_per_bay_bound():
    rng = np.random.default_rng(3)
    x = rng.uniform(0.0, 1.0, (3000, 2))
    x[:, 1] *= 2.0
    e = Extras(bays={"peak_pin_force_N": x, "latch_energy_J": x})
    ms = calc_bay_margins(e, np.ones(3000, bool), 99.865, 0.95, {"pin_force_yield_allowable_N": 2.0})
    assert [m.bay for m in ms] == [1, 2]
    # The upper bound of the 0.99865 quantile: an order statistic at or above the 2996th of 3000.
    for m, col in zip(ms, (x[:, 0], x[:, 1])):
        v = np.sort(col)
        assert v[2995] <= m.design_load <= v[-1]
    assert ms[0].status == PASS and ms[1].status == FAIL           # 2 / (1.1 x ~1) - 1 > 0, 2 / (1.1 x ~2) - 1 < 0
