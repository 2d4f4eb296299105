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


def test_children_take_the_pages_niceness(tmp_path):
    """Each figure is drawn at the niceness the page was given (on top of this process's), and up
    to 6 at once when it is positive, 2 otherwise."""
    import os

    def make_recording():
        with open(tmp_path / "nice.txt", "w") as fh:
            fh.write(str(os.nice(0)))
        return make_ok()

    base = os.nice(0)
    for niceness, at_once in ((0, 2), (3, 6)):
        page = Page(str(tmp_path), plt, niceness=niceness)
        page.figure(make_recording, "n.png", "x")
        page.finish()
        assert int((tmp_path / "nice.txt").read_text()) == min(base + niceness, 19)
        assert page.max_children == at_once


def test_busy_machine_keeps_priority():
    """With every core this process may use busy with other work, the children keep their
    priority (find_background_niceness is 0): a lower one would starve them behind that work."""
    import os
    import subprocess
    import sys
    import time

    from truss_report.page.render import find_background_niceness
    cores = len(os.sched_getaffinity(0))
    spin = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(cores + 1)]
    try:
        time.sleep(0.3)     # the spinners runnable: /proc/loadavg counts them as they run
        assert find_background_niceness() == 0
    finally:
        for p in spin:
            p.kill()
            p.wait()
