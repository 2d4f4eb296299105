"""truss_report.page.numbers: the report's one number rule, on values whose display is worked out
here by hand from the rule's statement (docs/report.md, "Numbers and units")."""
import math

import numpy as np
import pytest

from truss_report.page.numbers import (DASH, DisplayUnits, fmt, fmt_at, fmt_p, p_digits, readable_unit, resolution,
                                       uncertainty_resolution, unit_text)


def test_declared_values_as_given():
    assert fmt(0.03 / 1e-3) == "30" and fmt(125.0) == "125" and fmt(62.83185307) == "62.832"
    assert fmt(7) == "7" and fmt(float("nan")) == DASH and fmt(float("inf")) == "∞"


def test_never_minus_zero():
    assert fmt(-0.0) == "0" and fmt(-1e-9, 3) == "-1e-09"         # a nonzero value keeps its sign
    assert fmt_at(-0.0004, -2) == "0.00" and fmt_at(-0.006, -2) == "-0.01"
    assert fmt_at(-3.0, 2) == "0"                                  # rounds to hundreds: 0


def test_resolution_from_the_uncertainty():
    # a design load: P99.865 3.2818 N, its bound 3.2970 N: uncertainty 0.0152, two digits of it
    # end at 10^-3; nominal and mean at the same decimals
    e = resolution([3.0027, 3.1012, 3.2818, 3.2970], 3.2970 - 3.2818)
    assert e == -3 and [fmt_at(v, e) for v in (3.2818, 3.2970, 3.0027)] == ["3.282", "3.297", "3.003"]
    # a row of one quantity reads with one number of decimals: 832.04 ... 897.47 mN, uncertainty 3.7
    e = resolution([832.04, 897.47], 3.7)
    assert [fmt_at(v, e) for v in (832.04, 897.47)] == ["832.0", "897.5"]


def test_resolution_from_the_spread_and_its_limits():
    # no uncertainty: two digits of the spread 0.09 end at 10^-3, within 3..5 significant digits
    assert resolution([109.8005, 109.8933]) == -2                  # 5 digits of 109.8: capped at 10^-2
    # a constant load with rounding noise: 179.99996 vs 180.00000 mN s, spread 4e-5: at most 5 digits
    e = resolution([179.99996, 180.0])
    assert e == -2 and fmt_at(179.99996, e) == "180.00"
    # a spread as large as the values (10 to 60 bays: 50 s to 218 s): at least 3 digits
    e = resolution([50.2, 217.8])
    assert e == 0 and fmt_at(217.8, e) == "218" and fmt_at(109.8, e) == "110"
    assert resolution([]) is None and resolution([float("nan")]) is None and resolution([0.0, 0.0]) == 0


def test_an_absolute_uncertainty():
    # a rank correlation over 10,000 runs: standard error 0.01, two digits of it: 10^-3
    assert uncertainty_resolution(1 / math.sqrt(9999)) == -3 and fmt_at(0.0051, -3) == "0.005"
    assert uncertainty_resolution(float("nan")) is None
    # an index near 0 whose bootstrap interval is 1e-9 wide: at most 5 digits of its scale, 1
    assert uncertainty_resolution(5e-10) == -4 and fmt_at(-8.3e-7, -4) == "0.0000"


def test_probabilities():
    # 5.3e-7 in [1e-7, 6.9e-6]: the half width 3.4e-6 is above p: the least digits, 2
    assert p_digits(5.324e-7, 1e-7, 6.9e-6) == 2 and fmt_p(5.324e-7, 1e-7, 6.9e-6) == "5.3e-07"
    # 0.01234 in [0.0120, 0.0126]: half width 3e-4, two digits of it end at 10^-5: 4 digits of p
    assert p_digits(0.01234, 0.0120, 0.0126) == 4 and fmt_p(0.012341, 0.0120, 0.0126) == "0.01234"
    # no failure: the estimate 0 is shown as its upper bound
    assert fmt_p(0.0, 0.0, 3.7e-4, 3.0e-4) == "< 0.0003" and fmt_p(0.0) == "0"


def test_units_one_prefix_spelled_with_a_space():
    assert readable_unit("Nm", 0.0149) == ("mN m", 1e-3) and readable_unit("N", 3.2) == ("N", 1.0)
    assert readable_unit("Nm", 4e-5) == ("µN m", 1e-6) and readable_unit("m", 0.45) == ("mm", 1e-3)
    assert readable_unit("Ns", 0.18) == ("mN s", 1e-3) and readable_unit("Nm/rad", 1.0) == ("N m/rad", 1.0)
    assert unit_text("Nm") == "N m" and unit_text("rad/s") == "rad/s"


def test_one_unit_and_resolution_per_quantity():
    u = DisplayUnits()
    u.choose("peak_drive_torque_Nm", "Nm", 0.0052, [0.0047, 0.0052232, 0.0052470], 0.0052470 - 0.0052232)
    # every torque of the report in the drive torque's unit and decimals
    assert u.get("motor_torque_at_speed_Nm", "Nm", np.array([5.0])) == ("mN m", 1e-3)
    assert u.text("torque", "Nm", 0.014920355) == "14.920 mN m" and u.text("torque", "Nm", float("nan")) == DASH
    assert u.text("lock_time_s", "s", 3.25, values=[3.2, 109.8]) == "3 s"   # spread 106.6 s: 3 digits of 110


@pytest.mark.parametrize("v", [1.0, 12.5, 0.001, 0.0123])
def test_fmt_at_has_the_decimals_of_the_resolution(v):
    for e in (-3, -1, 0):
        text = fmt_at(v, e)
        assert len(text.split(".")[1]) == -e if e < 0 else "." not in text


def test_fmt_at_never_shows_more_than_most_digits():
    # a value larger than the quantity's typical one (a T_min above every drive torque) keeps
    # MOST significant digits: 11.3952 mN m at 10^-4 is 11.395; 123456 at 10^-3 is 123460
    assert fmt_at(11.3952, -4) == "11.395" and fmt_at(123456.0, -3) == "123460"
    assert fmt_at(0.0, -3) == "0.000" and fmt_at(-0.00004, -3) == "0.000"
