"""truss_report.page.render.Page: a figure is built, drawn and saved by a forked child; the size
the child tells before drawing is the saved PNG's (read back with Pillow), and a figure whose
building fails makes find_size and finish raise, naming it."""
import matplotlib.pyplot as plt
import pytest
from PIL import Image

from truss_report.page.render import Page


def make_ok():
    fig, ax = plt.subplots(figsize=(3.3, 2.1))
    ax.plot([0, 1, 2], [1, 0, 2])
    return fig


def make_bad():
    raise ValueError("no data")


def test_size_told_is_the_pngs(tmp_path):
    page = Page(str(tmp_path), plt)
    html = page.figure(make_ok, "a.png", "caption <a>")
    assert "caption &lt;a&gt;" in html and "src=\"a.png\"" in html
    size = page.find_size("a.png")
    page.finish()
    assert Image.open(tmp_path / "a.png").size == tuple(size)
    assert page.find_size("other.png") is None


def test_failed_figure_is_named(tmp_path):
    page = Page(str(tmp_path), plt)
    page.figure(make_bad, "bad.png", "x")
    with pytest.raises(RuntimeError, match="bad.png"):
        page.find_size("bad.png")
    with pytest.raises(RuntimeError, match="bad.png"):
        page.finish()


def test_sizes_never_asked_for(tmp_path):
    """A report without its PDF never asks a figure's size: the children still finish."""
    page = Page(str(tmp_path), plt)
    for i in range(3):
        page.figure(make_ok, f"f{i}.png", "x")
    page.finish()
    assert all((tmp_path / f"f{i}.png").stat().st_size > 1000 for i in range(3))
