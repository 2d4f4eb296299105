"""truss_report.page.pdf: the report for signature, DIR/report.pdf from DIR/report.html (WeasyPrint:
A4, page numbers in the footer), each figure embedded as the very PNG file the HTML shows.

WeasyPrint stores a PNG image as a FlateDecode stream with the PNG predictors, which is what a PNG's
IDAT chunks hold; it gets that stream by decoding the file and encoding it again (a third of the
PDF's writing for the report's figures). For an 8-bit RGB, non-interlaced PNG (what page.render
writes) the file's own IDAT bytes are that stream: they are copied instead. Anything else (another
PNG, another WeasyPrint) takes WeasyPrint's own path.

The layout does not wait for the figures: WeasyPrint lays a page out from an image's header (its
size), and reads its pixels only when it writes the PDF. A figure still being drawn is handed to the
layout as a placeholder, a PNG header of the figure's size naming the figure's file (placeholder_png);
the file's rows replace it when the PDF is written, after the figures are drawn."""
import contextlib
import gc
import io
import logging
import os
import struct
import urllib.parse

from .png import NOT_INTERLACED, PNG_SIGNATURE, RGB, png_chunk

FIGURE_KEY = "truss-report-figure"   # the placeholder's tEXt keyword: the figure's file name


def placeholder_png(name, size):
    """An RGB PNG that declares `size` = (width, height) pixels and holds none (an empty IDAT),
    with a tEXt chunk naming the figure's file: what the layout needs of a figure being drawn."""
    width, height = size
    return (PNG_SIGNATURE + png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, RGB, 0, 0, NOT_INTERLACED))
            + png_chunk(b"tEXt", FIGURE_KEY.encode() + b"\0" + name.encode("latin-1"))
            + png_chunk(b"IDAT", b"") + png_chunk(b"IEND", b""))


def png_rows(data, size=None):
    """The zlib stream of the filtered rows of a PNG (its IDAT chunks joined) when a PDF can take
    it as it is (8 bits a sample, RGB, not interlaced, no transparency, and `size` = (width,
    height) pixels when given); None otherwise."""
    if not data.startswith(PNG_SIGNATURE):
        return None
    pos, idat, header_ok = len(PNG_SIGNATURE), [], False
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            header_ok = (depth == 8 and colour == RGB and interlace == NOT_INTERLACED
                         and size in (None, (width, height)))
        elif kind == b"tRNS":
            return None
        elif kind == b"IDAT":
            idat.append(body)
        pos += 12 + length       # length, type, data, CRC
    return b"".join(idat) if header_ok and idat else None


def figure_rows(directory, image):
    """The rows of the figure a placeholder names (RuntimeError if its file is not the RGB PNG of
    the placeholder's size)."""
    name = image.info[FIGURE_KEY]
    with open(os.path.join(directory, name), "rb") as fh:
        rows = png_rows(fh.read(), image.size)
    if rows is None:
        raise RuntimeError(f"figure {name}: not an RGB PNG of {image.size[0]} x {image.size[1]} pixels")
    return rows


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic garbage collector off while open: WeasyPrint's layout makes a few hundred
    thousand objects that live until the document is written, and the collector's passes over them
    (none frees anything) are a sixth of the PDF's CPU time. Memory is not at stake: the garbage
    in cycles is one document's, collected once the collector is back."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


@contextlib.contextmanager
def png_passthrough(stream_class, directory):
    """While open, `stream_class` (weasyprint.pdf.stream.Stream) takes the rows of an RGB PNG
    file from the file (png_rows) rather than decoding and encoding it again, and those of a
    placeholder from the figure's file in `directory`. Yields False for a WeasyPrint without that
    step (its own path throughout: no placeholders). The image WeasyPrint hands over was opened by
    Pillow from the file's bytes (a BytesIO: its `fp`)."""
    original = getattr(stream_class, "_get_png_data", None)
    if original is None:
        yield False
        return

    def get_png_data(self, image, optimize):
        if FIGURE_KEY in image.info:
            return figure_rows(directory, image)
        fp = getattr(image, "fp", None)
        rows = png_rows(fp.getvalue()) if isinstance(fp, io.BytesIO) and image.mode == "RGB" else None
        return rows if rows is not None else original(self, image, optimize)

    stream_class._get_png_data = get_png_data
    try:
        yield True
    finally:
        stream_class._get_png_data = original


def write_pdf(html_path, pdf_path, find_size=lambda name: None, wait=lambda: None):
    """pdf_path from html_path (ImportError without WeasyPrint). find_size(name): (width, height)
    in pixels of a figure beside html_path still being drawn, None for any other file; wait()
    returns once the figures are drawn (called after the layout, before the PDF is written)."""
    logging.getLogger("weasyprint").setLevel(logging.ERROR)
    logging.getLogger("fontTools").setLevel(logging.ERROR)
    import weasyprint             # optional: --no-pdf runs without it
    from weasyprint.pdf.stream import Stream
    directory = os.path.dirname(os.path.abspath(html_path))

    def fetch(url):
        path = urllib.parse.unquote(url[len("file://"):]) if url.startswith("file://") else ""
        size = find_size(os.path.basename(path)) if os.path.dirname(path) == directory else None
        if size is not None:
            name = os.path.basename(path)
            return {"string": placeholder_png(name, size), "mime_type": "image/png", "redirected_url": url}
        return weasyprint.default_url_fetcher(url)

    with collector_paused(), png_passthrough(Stream, directory) as passthrough:
        if not passthrough:
            wait()
        document = weasyprint.HTML(filename=html_path, url_fetcher=fetch if passthrough else
                                   weasyprint.default_url_fetcher).render()
        wait()
        document.write_pdf(pdf_path)
