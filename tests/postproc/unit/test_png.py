"""truss_report.page.png: the PNG file of a figure's RGBA pixels is their RGB channels exactly,
as an independent decoder (Pillow) reads them back; the file is what page.pdf copies into the PDF
(8-bit RGB, not interlaced), and a drawn figure's file is the canvas's pixels."""
import io

import matplotlib.pyplot as plt
import numpy as np
from PIL import Image

from truss_report.page import pdf
from truss_report.page.png import encode_rgb
from truss_report.page.render import save_png


def decoded(data):
    im = Image.open(io.BytesIO(data))
    assert im.format == "PNG" and im.mode == "RGB"
    return np.asarray(im)


def test_random_pixels_read_back_exactly():
    rgba = np.random.default_rng(7).integers(0, 256, (37, 53, 4), dtype=np.uint8)   # odd sizes, every value
    data = encode_rgb(rgba)
    assert np.array_equal(decoded(data), rgba[..., :3])
    assert pdf.png_rows(data, (53, 37)) is not None       # the PDF takes its rows as they are


def test_saved_figure_is_the_canvas(tmp_path):
    fig, ax = plt.subplots(figsize=(3.1, 2.3))
    ax.plot([0, 1, 2], [2, 0, 1], "o-", alpha=0.5)
    ax.set_title("µ−0.5 (mN m)")
    save_png(fig, str(tmp_path / "f.png"))
    canvas = np.asarray(fig.canvas.buffer_rgba())[..., :3]
    plt.close(fig)
    assert np.array_equal(decoded((tmp_path / "f.png").read_bytes()), canvas)
