"""truss_report.page.render.TightLayoutOnce: matplotlib's tight layout measured once. Checked
against matplotlib's own TightLayoutEngine on the same figures: the subplot parameters it applies
(left, right, bottom, top, wspace, hspace) must agree to rounding (1e-12: the two compute the same
sums in another order), for grids of 1 x 1 to 3 x 4, a suptitle, colour bars, hidden Axes and the
rects the report's figures use; and the report's figures lay out the same in both."""
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.layout_engine import TightLayoutEngine

from truss_report.page.render import FIGURE_DPI, TightLayoutOnce, fit_into_rect

PARAMS = ("left", "right", "bottom", "top", "wspace", "hspace")


def build(rows, cols, suptitle, colorbar, hidden):
    rng = np.random.default_rng(rows * 10 + cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.0 * rows), squeeze=False)
    for i, ax in enumerate(axes.flat):
        x = rng.lognormal(size=200) * 10.0 ** i
        if colorbar and i == 0:
            fig.colorbar(ax.scatter(x, x ** 2, c=x), ax=ax, label="bay")
        else:
            ax.plot(x, np.sort(x), ".")
        ax.set_yscale("log" if i % 2 else "linear")
        ax.set_xlabel(f"input {i} (mN m)")
        ax.set_ylabel("peak drive torque (mN m)" if i % 3 == 0 else "p")
    if hidden and rows * cols > 1:
        axes.flat[-1].set_visible(False)
    if suptitle:
        fig.suptitle("exceedance probability 1 − ECDF")
    return fig


def applied(fig, engine):
    fig.set_layout_engine(engine)
    fig.set_dpi(FIGURE_DPI)
    fig.canvas.draw()
    p = fig.subplotpars
    out = np.array([getattr(p, k) for k in PARAMS])
    plt.close(fig)
    return out


CASES = [(r, c, s, cb, h, rect) for r, c in ((1, 1), (1, 2), (2, 3))
         for s, cb, h in ((False, False, False), (True, True, True))
         for rect in ((0, 0, 1, 1), (0, 0.2, 1, 1), (0.05, 0.1, 0.9, 0.95))]


@pytest.mark.parametrize("rows,cols,suptitle,colorbar,hidden,rect", CASES)
def test_same_layout_as_matplotlib(rows, cols, suptitle, colorbar, hidden, rect):
    want = applied(build(rows, cols, suptitle, colorbar, hidden), TightLayoutEngine(rect=rect))
    got = applied(build(rows, cols, suptitle, colorbar, hidden), TightLayoutOnce(rect=rect))
    assert np.allclose(got, want, rtol=0, atol=1e-12), (got, want)
    assert not np.allclose(want, [0.125, 0.9, 0.11, 0.88, 0.2, 0.2])   # a layout was applied


def test_fit_into_rect_gives_up_as_matplotlib_does():
    k = dict(left=0.1, right=0.9, bottom=0.1, top=0.9, wspace=0.3, hspace=0.3)
    assert fit_into_rect(k, (0, 0, 1, 1), 2, 2) == pytest.approx(k)
    assert fit_into_rect(k, (0.5, 0, 0.5, 1), 2, 2) is None     # no width left
    assert fit_into_rect(k, (0, 0, 1, 0.2), 2, 2) is None       # no height left
