"""truss_report.page.render: the report being rendered: its figures, drawn in forked children while
the sections go on, saved as PNG into the staging directory."""
import gc
import os
import struct
import sys
import traceback
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
from matplotlib._tight_layout import get_subplotspec_list, get_tight_layout_figure
from matplotlib.layout_engine import TightLayoutEngine

from .html import esc
from .png import encode_rgb


FIGURE_DPI = 110    # a 15-inch figure row printed 186 mm wide is at 225 dpi; on a 1400-pixel page at 0.85


class TightLayoutOnce(TightLayoutEngine):
    """matplotlib's tight layout, with the Axes' decorations measured once rather than twice.
    TightLayoutEngine.execute (matplotlib 3.6, _tight_layout.get_tight_layout_figure) measures them,
    finds the margins and spaces that fit the whole figure, then measures them again to fit that
    answer into `rect` (always given: its default is the whole figure). The second measuring finds
    what the first did (nothing has moved in between), so its answer follows from the first
    (fit_into_rect). Measuring is two thirds of a figure's drawing time."""

    def execute(self, fig):
        info = self.get()
        renderer = fig._get_renderer()
        specs = get_subplotspec_list(fig.axes)
        with getattr(renderer, "_draw_disabled", nullcontext)():
            kwargs = get_tight_layout_figure(fig, fig.axes, specs, renderer, pad=info["pad"],
                                             h_pad=info["h_pad"], w_pad=info["w_pad"], rect=None)
        grids = [ss.get_gridspec() for ss in specs if ss is not None]
        if kwargs and grids:
            kwargs = fit_into_rect(kwargs, info["rect"], max(g.nrows for g in grids), max(g.ncols for g in grids))
        if kwargs:
            fig.subplots_adjust(**kwargs)


def fit_into_rect(k, rect, rows, cols):
    """Subplot parameters k that fit a figure's whole area, fitted into rect = (left, bottom,
    right, top) in figure fractions as matplotlib's second pass would (None where it gives up):
    margins m = rect's margin + k's; a space between Axes s = w a (w: wspace or hspace, a: the Axes'
    size, from n a + (n - 1) s = 1 - margins) stays, and w' = s / a'."""
    left, bottom, right, top = rect
    m_left, m_right = left + k["left"], (1 - right) + (1 - k["right"])
    m_bottom, m_top = bottom + k["bottom"], (1 - top) + (1 - k["top"])
    if m_left + m_right >= 1 or m_bottom + m_top >= 1:
        return None
    out = dict(left=m_left, right=1 - m_right, bottom=m_bottom, top=1 - m_top)
    for n, key, before, after in ((cols, "wspace", 1 - (1 - k["right"]) - k["left"], 1 - m_left - m_right),
                                  (rows, "hspace", 1 - (1 - k["top"]) - k["bottom"], 1 - m_bottom - m_top)):
        if n > 1:
            space = k[key] * before / (n + k[key] * (n - 1))
            size = (after - space * (n - 1)) / n
            if size < 0:
                return None
            out[key] = space / size
    return out


def save_png(fig, path):
    """The figure as an opaque RGB PNG (its background is white; page.png): the PDF writer copies
    an RGB PNG's rows, and an alpha channel would be a second image to encode. A tight layout is
    found with TightLayoutOnce (the same layout)."""
    engine = fig.get_layout_engine()
    if type(engine) is TightLayoutEngine:
        fig.set_layout_engine(TightLayoutOnce(**engine.get()))
    fig.set_dpi(FIGURE_DPI)
    fig.canvas.draw()
    with open(path, "wb") as fh:
        fh.write(encode_rgb(np.asarray(fig.canvas.buffer_rgba())))


def find_background_niceness():
    """The niceness the report's children (its figures, the run table) take: 10 when fewer tasks
    are runnable as the report starts than the cores it may use (/proc/loadavg's count, this
    process included), else 0. At 10 they run on what the report's main chain leaves of the
    cores: that chain (the sections, then the PDF's layout and writing, which the report's end
    waits for) keeps a core instead of sharing it with them (docs/benchmarks.md, "Report").
    Beside other programs' work a lower priority would starve them behind it, so on a busy
    machine every process of the report keeps its priority."""
    try:
        with open("/proc/loadavg", encoding="ascii") as fh:
            running = int(fh.read().split()[3].split("/")[0])
    except (OSError, ValueError, IndexError):
        return 0
    return 10 if running < len(os.sched_getaffinity(0)) else 0


@dataclass
class Report:
    """A rendered report: the page's HTML, the lines for the terminal, and the verdict ("pass",
    "fail", "not_assessed"; None for a report without one)."""
    html: str
    summary: list[str]
    verdict: str | None


class Page:
    """The report being built: its figures, saved into the staging directory."""

    def __init__(self, outdir, plt, progress=None, niceness=0):
        self.dir, self.plt, self.niceness = outdir, plt, niceness   # the children's (find_background_niceness)
        self.files = []
        self.progress = progress or (lambda what: None)
        self.children = []        # (pid, figure name) of the figures being drawn
        # Figures drawn at once: one a core; with the children yielding to this process, a few
        # more, so that it reaches the PDF's layout sooner instead of waiting for a free one.
        self.max_children = 6 if niceness > 0 else 2
        self.sizes = {}           # figure name: (width, height) in pixels (find_size)
        self.size_pipes = {}      # figure name: the pipe its child tells the size on
        # Fonts and text layout are cached per process: draw once here, so that every forked
        # child starts with them loaded instead of loading them again.
        warm, ax = plt.subplots(figsize=(2, 1))
        ax.set_title("µ−0.5 (mN m)")
        ax.set_xlabel("x")
        warm.savefig(os.devnull, format="png", dpi=FIGURE_DPI)
        plt.close(warm)

    def figure(self, make, name, caption, cls="wide"):
        """Saves the figure `make()` returns as DIR/name and returns its HTML. A forked child
        builds the figure, tells its size in pixels (find_size), lays it out, draws it and encodes
        the PNG while this process goes on with the next sections and the PDF's layout: the
        report's figures use both cores, and this process, the report's longest chain of work,
        does none of theirs. finish() waits for them."""
        if len(self.files) % 5 == 0:
            self.progress(f"figure {len(self.files) + 1}: {name}")
        while len(self.children) >= self.max_children:
            self._reap(self.children.pop(0))
        sys.stdout.flush()
        sys.stderr.flush()
        gc.freeze()        # the child's collector leaves the parent's objects (and pages) alone
        size_r, size_w = os.pipe()
        pid = os.fork()
        if pid == 0:       # child: build, draw, encode, leave without Python's exit handlers
            os.close(size_r)
            code = 0
            try:
                os.nice(self.niceness)
                fig = make()
                fig.set_dpi(FIGURE_DPI)
                os.write(size_w, struct.pack("<II", *(int(v) for v in fig.bbox.size)))  # Agg truncates
                os.close(size_w)
                save_png(fig, os.path.join(self.dir, name))
            except BaseException:   # noqa: BLE001 - reported through the exit status
                sys.stderr.write(f"error: figure {name}:\n{traceback.format_exc()}")
                code = 1
            os._exit(code)
        os.close(size_w)
        self.children.append((pid, name))
        self.size_pipes[name] = size_r
        self.files.append(name)
        return (f'<figure class="{cls}"><img src="{esc(name)}" alt="{esc(caption)}">'
                f"<figcaption>{esc(caption)}</figcaption></figure>")

    def find_size(self, name):
        """(width, height) in pixels of this page's figure `name` (None for another file), told by
        its child once it has built the figure (RuntimeError if it failed before)."""
        if name not in self.sizes and name in self.size_pipes:
            fd = self.size_pipes.pop(name)
            data = b""
            while len(data) < 8:
                chunk = os.read(fd, 8 - len(data))
                if not chunk:
                    break
                data += chunk
            os.close(fd)
            if len(data) < 8:
                raise RuntimeError(f"drawing the figure {name} failed")
            self.sizes[name] = struct.unpack("<II", data)
        return self.sizes.get(name)

    def text_file(self, name, text):
        """Writes DIR/name (a file the report links to)."""
        with open(os.path.join(self.dir, name), "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        self.files.append(name)

    def _reap(self, child):
        pid, name = child
        _, status = os.waitpid(pid, 0)
        if os.waitstatus_to_exitcode(status) != 0:
            raise RuntimeError(f"drawing the figure {name} failed")

    def finish(self):
        """Waits for every figure (RuntimeError if one failed), then closes the pipes of the sizes
        not asked for (a child's 8 bytes fit in its pipe: it never waits on them)."""
        try:
            while self.children:
                self._reap(self.children.pop(0))
        finally:
            for fd in self.size_pipes.values():
                os.close(fd)
            self.size_pipes.clear()
