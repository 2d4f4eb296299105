"""truss_report.page.pdf: the report for signature, DIR/report.pdf from DIR/report.html (WeasyPrint:
A4, page numbers in the footer), each figure embedded as the very PNG file the HTML shows.

WeasyPrint stores a PNG image as a FlateDecode stream with the PNG predictors, which is what a PNG's
IDAT chunks hold; it gets that stream by decoding the file and encoding it again (a third of the
PDF's writing for the report's figures). For an 8-bit RGB, non-interlaced PNG (what page.render
writes) the file's own IDAT bytes are that stream: they are copied instead. Anything else (another
PNG, another WeasyPrint) takes WeasyPrint's own path."""
import contextlib
import io
import logging
import struct

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
RGB, NOT_INTERLACED = 2, 0       # IHDR colour type and interlace method


def png_rows(data):
    """The zlib stream of the filtered rows of a PNG (its IDAT chunks joined) when a PDF can take
    it as it is (8 bits a sample, RGB, not interlaced, no transparency); None otherwise."""
    if not data.startswith(PNG_SIGNATURE):
        return None
    pos, idat, header_ok = len(PNG_SIGNATURE), [], False
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            _, _, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            header_ok = depth == 8 and colour == RGB and interlace == NOT_INTERLACED
        elif kind == b"tRNS":
            return None
        elif kind == b"IDAT":
            idat.append(body)
        pos += 12 + length       # length, type, data, CRC
    return b"".join(idat) if header_ok and idat else None


@contextlib.contextmanager
def png_passthrough(stream_class):
    """While open, `stream_class` (weasyprint.pdf.stream.Stream) takes the rows of an RGB PNG
    file from the file (png_rows) rather than decoding and encoding it again. The image WeasyPrint
    hands over was opened by Pillow from the file's bytes (a BytesIO: its `fp`)."""
    original = getattr(stream_class, "_get_png_data", None)
    if original is None:         # a WeasyPrint without that step: its own path throughout
        yield
        return

    def get_png_data(self, image, optimize):
        fp = getattr(image, "fp", None)
        rows = png_rows(fp.getvalue()) if isinstance(fp, io.BytesIO) and image.mode == "RGB" else None
        return rows if rows is not None else original(self, image, optimize)

    stream_class._get_png_data = get_png_data
    try:
        yield
    finally:
        stream_class._get_png_data = original


def write_pdf(html_path, pdf_path):
    """pdf_path from html_path (ImportError without WeasyPrint)."""
    logging.getLogger("weasyprint").setLevel(logging.ERROR)
    logging.getLogger("fontTools").setLevel(logging.ERROR)
    import weasyprint             # optional: --no-pdf runs without it
    from weasyprint.pdf.stream import Stream
    with png_passthrough(Stream):
        weasyprint.HTML(filename=html_path).write_pdf(pdf_path)
