"""truss_report.page.html: numbers on the page with their data-key and full-precision data-value
(the number rule itself: test_numbers.py), and tables."""
from truss_report.page.html import num, table
from truss_report.page.numbers import DASH


def test_num_keeps_the_si_value():
    cell = num("design.x.p99", 0.0123456789, "mN", factor=1e-3)
    assert 'data-key="design.x.p99"' in cell and 'data-value="0.0123456789"' in cell
    assert ">12.346\u00a0mN<" in cell and ">12.35\u00a0mN<" in num("x", 0.0123456789, "mN", factor=1e-3, at=-2)
    assert 'data-value="nan"' in num("k", float("nan")) and f">{DASH}<" in num("k", float("nan"), "N")
    assert ">&lt; 0.0003<" in num("p", 0.0, text="< 0.0003")      # the shown text escaped


def test_table():
    t = table(["a", "b"], [["1", "<td class='x'>2</td>"]], "narrow")
    assert t == ('<table class="narrow"><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td>'
                 "<td class='x'>2</td></tr></tbody></table>")
