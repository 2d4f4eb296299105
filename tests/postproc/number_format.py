"""The report's number rule (postproc/truss_report/page/numbers.py) as a reader checks it on a page's
text, written here from the rule's statement, not from the code that applies it:
  - "N m", "N s" with a space: a unit token "Nm", "Ns", "mNm", "µNs", ... is a violation (an
    identifier such as peak_drive_torque_Nm is not a unit token: it is glued to a word, or in the
    PDF's text wrapped after its underscore);
  - never "-0" (or "-0.00"): a value that rounds to zero has no sign;
  - never "nan", "inf" (Python's spellings) where a number belongs;
  - at most MOST significant digits in a number with a fraction ("179.99996" has 8): digits past
    that are the integrators' tolerance and rounding (integers, counts and seeds, are exact);
  - one SI prefix per quantity: every torque a report shows is in one of µN m, mN m or N m.
Used by test_pdf_layout.py on the HTML's visible text and the PDF's text (pdftotext)."""
import re

MOST = 5
# (?<!_\s): an identifier the PDF wrapped after its underscore ("entry_impulse_" / "Ns") is no unit.
UNIT_GLUED = re.compile(r"(?<![\w/])(?<!_\s)[µmk]?N[ms](?![\w])")
MINUS_ZERO = re.compile(r"(?<![\w.])[-−]0(?:\.0*)?(?![\d.]*[1-9])(?![\w])")
NAN_INF = re.compile(r"(?<![\w.])[-−]?(?:nan|inf)(?![\w])")
DECIMAL = re.compile(r"(?<![\w.:])[-−]?(\d+\.\d+)(?:e[-+]?\d+)?(?![\w.:]*\d)")
TORQUE = re.compile(r"\d[\s\u00a0]?(µN|mN|N)[\s\u00a0]m(?![\w/])")


def significant(digits):
    """Significant digits of a decimal text "0.001230" (trailing zeros shown count)."""
    return len(digits.replace(".", "").lstrip("0")) or 1


def violations(text):
    """[(rule, excerpt)] of every place the text breaks the number rule."""
    bad = []

    def where(m):
        return text[max(0, m.start() - 30):m.end() + 10].replace("\n", " ")

    bad += [("unit without a space", where(m)) for m in UNIT_GLUED.finditer(text)]
    bad += [("-0", where(m)) for m in MINUS_ZERO.finditer(text)]
    bad += [("nan or inf", where(m)) for m in NAN_INF.finditer(text)]
    bad += [(f"more than {MOST} significant digits", where(m)) for m in DECIMAL.finditer(text)
            if significant(m.group(1)) > MOST]
    prefixes = {}
    for m in TORQUE.finditer(text):
        prefixes.setdefault(m.group(1), where(m))
    if len(prefixes) > 1:
        bad += [("torques in more than one prefix", f"{p} m: {w}") for p, w in prefixes.items()]
    return bad
