"""truss_report.page.html and .units: numbers on the page (rounding, never "-0", NaN as "—"),
their data-key and full-precision data-value, and the unit each quantity is shown in."""
import numpy as np

from truss_report.page.html import DASH, digits_for, fmt, num, table
from truss_report.page.units import DisplayUnits, readable_unit


def test_fmt():
    assert fmt(3.14159265) == "3.1416" and fmt(7) == "7" and fmt(float("nan")) == DASH
    assert fmt(-1e-9, 3) == "-1e-09" and fmt(-0.0) == "0" and fmt(float("inf")) == "∞"


def test_digits_follow_the_spread():
    assert digits_for([13.977, 13.9771, 13.979]) >= 5          # 13.977 and 13.979 differ at the 5th
    assert digits_for([1.0, 2.0, 3.0]) == 3 and digits_for([]) == 3


def test_num_keeps_the_si_value():
    cell = num("design.x.p99", 0.0123456789, "mN", factor=1e-3)
    assert 'data-key="design.x.p99"' in cell and 'data-value="0.0123456789"' in cell
    assert ">12.346\u00a0mN<" in cell
    assert 'data-value="nan"' in num("k", float("nan")) and f">{DASH}<" in num("k", float("nan"), "N")


def test_table():
    t = table(["a", "b"], [["1", "<td class='x'>2</td>"]], "narrow")
    assert t == ('<table class="narrow"><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td>'
                 "<td class='x'>2</td></tr></tbody></table>")


def test_units():
    assert readable_unit("Nm", 0.0149) == ("mN m", 1e-3) and readable_unit("N", 3.2) == ("N", 1.0)
    assert readable_unit("Nm", 4e-5) == ("µN m", 1e-6) and readable_unit("rad/s", 5.0) == ("rad/s", 1.0)
    u = DisplayUnits()
    u.choose("peak_drive_torque_Nm", "Nm", 0.0149)
    assert u.get("motor_torque_at_speed_Nm", "Nm", np.array([5.0])) == ("mN m", 1e-3)   # the drive torque's
