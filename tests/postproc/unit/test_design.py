"""truss_report.judging.design: which loads the table holds and their numbers, against values
worked out here (the bound's rank from the binomial sum is test_stats.py's)."""
import numpy as np
import pytest

from conftest import make_campaign
from truss_report.judging.design import design_loads, load_text
from truss_report.reading.extras import Extras


def test_loads_values_and_nominal():
    x = np.arange(1.0, 3001.0)                     # 3000 ok runs: P99.865 has a bound
    c = make_campaign({"peak_drive_force_N": x, "peak_pin_force_N": np.zeros(3000)})
    bays = np.column_stack([x, 2 * x, np.full(3000, np.nan)])
    e = Extras(bays={"entry_impulse_Ns": bays}, units={"entry_impulse_Ns": "Ns"},
               nominal={"peak_drive_force_N": 5.0}, nominal_bays={"entry_impulse_Ns": np.array([1.0, 4.0, np.nan])})
    loads = {d.key: d for d in design_loads(c, e, [50.0, 99.865], 0.95)}
    assert "peak_pin_force_N" not in loads          # all zero: left out
    assert "deploy_time_s" not in loads             # no finite value
    d = loads["peak_drive_force_N"]
    assert (d.n, d.nominal, d.mean, d.min, d.max) == (3000, 5.0, 1500.5, 1.0, 3000.0)
    assert d.levels[0].estimate == pytest.approx(1 + 2999 * 0.5)     # type 7: 1 + (n - 1) p
    assert d.levels[1].rank is not None and d.levels[1].bound == x[d.levels[1].rank - 1]
    assert d.ratio == pytest.approx(d.levels[1].estimate / 5.0)
    imp = loads["entry_impulse_Ns"]                 # per run: the largest over the bays
    assert imp.impulse and imp.max == 6000.0 and imp.nominal == 4.0
    assert not d.nominal_below_runs and imp.nominal_below_runs is False


def test_too_few_runs_for_a_bound():
    c = make_campaign({"peak_drive_force_N": np.linspace(1, 2, 500)})
    (d,) = design_loads(c, Extras(), [99.865], 0.95)
    assert d.levels[0].too_few and d.levels[0].n_needed == 2218 and np.isnan(d.levels[0].bound)


def test_retraction_names_and_definitions():
    assert load_text("deploy_time_s", "deployment time", "x", None, "retract")[0] == "retraction time"
    assert load_text("landing_impulse_Ns", "landing impulse", None, "y", "deploy")[1] is None
