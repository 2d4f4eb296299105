"""truss_report.page.pdf: the PDF embeds each figure as the PNG file the HTML shows. Checked against
the files themselves: the PNG's IDAT bytes (read here with struct, from the PNG specification's
chunk layout) stand verbatim in the PDF, and the image poppler decodes from the PDF (pdfimages) is
the PNG's pixels exactly (both lossless, so equality, not a tolerance)."""
import glob
import os
import struct
import subprocess
import zlib

import numpy as np
import pytest
from PIL import Image

from truss_report.page import pdf
from truss_report.page.render import save_png

pytest.importorskip("weasyprint")


def chunks(data):
    """[(type, body)] of a PNG file, written out from the specification (length, type, body, CRC)."""
    pos, res = 8, []
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        res.append((data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]))
        pos += 12 + n
    return res


def idat(path):
    with open(path, "rb") as fh:
        return b"".join(body for kind, body in chunks(fh.read()) if kind == b"IDAT")


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    """A report directory: a figure as page.render saves it (RGB), the same one with an alpha
    channel (WeasyPrint's own path), an HTML page showing both, and its PDF."""
    import matplotlib.pyplot as plt
    d = tmp_path_factory.mktemp("pdf")
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1, 2], [1, 3, 2], "o-")
    ax.set_title("µ−0.5 (mN m)")
    save_png(fig, str(d / "rgb.png"))
    plt.close(fig)
    Image.open(d / "rgb.png").convert("RGBA").save(d / "rgba.png")
    (d / "report.html").write_text("<html><body><h1>t</h1><img src='rgb.png'><img src='rgba.png'>"
                                   "</body></html>", encoding="utf-8")
    pdf.write_pdf(str(d / "report.html"), str(d / "report.pdf"))
    return d


def test_rgb_figure_is_copied_not_encoded_again(figures):
    rows = idat(figures / "rgb.png")
    assert len(rows) > 1000
    assert rows in (figures / "report.pdf").read_bytes()
    assert pdf.png_rows((figures / "rgb.png").read_bytes()) == rows


def test_rgba_figure_goes_weasyprints_way(figures):
    assert pdf.png_rows((figures / "rgba.png").read_bytes()) is None
    assert idat(figures / "rgba.png") not in (figures / "report.pdf").read_bytes()


def test_pdf_images_are_the_pngs_pixels(figures):
    subprocess.run(["pdfimages", "-png", str(figures / "report.pdf"), str(figures / "x")], check=True)
    got = [np.asarray(Image.open(p).convert("RGB")) for p in sorted(glob.glob(str(figures / "x-*.png")))]
    for name in ("rgb.png", "rgba.png"):
        want = np.asarray(Image.open(figures / name).convert("RGB"))
        assert any(g.shape == want.shape and np.array_equal(g, want) for g in got), name


def png(width, height, depth, colour, interlace, rows=b""):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, interlace)
    return pdf.PNG_SIGNATURE + chunk(b"IHDR", ihdr) + chunk(b"IDAT", rows) + chunk(b"IEND", b"")


def test_png_rows_only_for_8_bit_rgb_not_interlaced():
    rows = zlib.compress(b"\x00" + b"\x10\x20\x30")
    assert pdf.png_rows(png(1, 1, 8, 2, 0, rows)) == rows
    assert pdf.png_rows(png(1, 1, 16, 2, 0, rows)) is None     # 16 bits a sample
    assert pdf.png_rows(png(1, 1, 8, 6, 0, rows)) is None      # RGBA
    assert pdf.png_rows(png(1, 1, 8, 3, 0, rows)) is None      # palette
    assert pdf.png_rows(png(1, 1, 8, 2, 1, rows)) is None      # Adam7
    assert pdf.png_rows(b"GIF89a") is None


def late_figure(d, size_change=0):
    """A page whose figure is drawn only after the layout (written by wait()), as report.py's
    figures are; returns (write_pdf's arguments, the figure's path)."""
    import matplotlib.pyplot as plt
    from truss_report.page.render import FIGURE_DPI
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1, 2], [2, 0, 1], "s-")
    fig.set_dpi(FIGURE_DPI)
    w, h = (int(v) for v in fig.bbox.size)
    (d / "report.html").write_text("<html><body><p>before</p><img src='late%20one.png'><p>after</p></body></html>",
                                   encoding="utf-8")

    def wait():
        save_png(fig, str(d / "late one.png"))
        plt.close(fig)
    sizes = {"late one.png": (w + size_change, h)}
    return (str(d / "report.html"), str(d / "report.pdf"), sizes.get, wait), d / "late one.png"


def test_figure_drawn_after_the_layout_is_the_pdfs_image(tmp_path):
    args, png_path = late_figure(tmp_path)
    pdf.write_pdf(*args)
    assert idat(png_path) in (tmp_path / "report.pdf").read_bytes()
    subprocess.run(["pdfimages", "-png", str(tmp_path / "report.pdf"), str(tmp_path / "x")], check=True)
    got = [np.asarray(Image.open(p).convert("RGB")) for p in glob.glob(str(tmp_path / "x-*.png"))]
    assert len(got) == 1 and np.array_equal(got[0], np.asarray(Image.open(png_path).convert("RGB")))


def test_figure_of_another_size_than_announced_is_refused(tmp_path):
    args, _ = late_figure(tmp_path, size_change=1)
    with pytest.raises(RuntimeError, match="late one.png"):
        pdf.write_pdf(*args)


def test_collector_paused_for_the_pdf_and_back_after(tmp_path, monkeypatch):
    """The cyclic collector is off while WeasyPrint lays the PDF out and writes it, on again
    afterwards (and still off if it was off)."""
    import gc
    import weasyprint
    (tmp_path / "r.html").write_text("<html><body><h1>t</h1><p>x</p></body></html>", encoding="utf-8")
    seen = []
    render, write = weasyprint.HTML.render, weasyprint.document.Document.write_pdf
    monkeypatch.setattr(weasyprint.HTML, "render", lambda *a, **k: seen.append(gc.isenabled()) or render(*a, **k))
    monkeypatch.setattr(weasyprint.document.Document, "write_pdf",
                        lambda *a, **k: seen.append(gc.isenabled()) or write(*a, **k))
    pdf.write_pdf(str(tmp_path / "r.html"), str(tmp_path / "r.pdf"))
    assert seen == [False, False] and gc.isenabled()
    gc.disable()
    try:
        pdf.write_pdf(str(tmp_path / "r.html"), str(tmp_path / "r2.pdf"))
        assert not gc.isenabled()
    finally:
        gc.enable()
    assert (tmp_path / "r.pdf").read_bytes().startswith(b"%PDF")
