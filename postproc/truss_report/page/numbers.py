"""truss_report.page.numbers: the one rule for every number the report shows, on its pages, in its
figures' keys and in its terminal lines.

1. Results (statistics and estimates of the runs) are shown to the resolution their uncertainty
   supports: two significant digits of it, the uncertainty being the distance from an estimate to
   its confidence bound where it has one (a design load: its upper bound minus its percentile),
   else the spread of the values the number is compared with (max - min over the runs); at least
   LEAST and at most MOST significant digits of the largest |value| (past MOST the digits are the
   integrators' tolerance and rounding: 179.99996 mN s is shown 180.00 mN s). Every number of one
   quantity has that resolution wherever it is shown (fixed decimals in its unit): a row reads
   "832.0 ... 897.5 mN", never "832 ... 897.5".
2. Declared values (scene keys, options, design values, the campaign's own numbers) are shown as
   given: at most MOST significant digits, no trailing zeros ("30 mN m", "125 rad/s").
3. Probabilities (p and its bounds): 2 to 4 significant digits, from the width of the interval
   relative to p; clipped to [0, 1] (judging); an estimate of 0 with an upper bound is shown as
   that bound ("< 3.0e-04"), its coefficient of variation "—".
4. Units: SI, one prefix per quantity throughout the report, chosen from its largest typical value
   (the largest prefix not above it: 0.0149 N m is 14.9 mN m); a space between factors ("N m",
   "mN s", never "Nm"), a no-break space between a number and its unit on the page.
5. Never "-0" (a value that rounds to zero is "0"), never "nan" or "inf": "—" (explained by the
   page's footnote) and "∞". Integers (counts, indices, seeds) are exact.
"""
import html
import math
import re

import numpy as np

LEAST, MOST = 3, 5          # significant digits of a result: at least, at most
P_LEAST, P_MOST = 2, 4      # significant digits of a probability

# Shown for a value that does not apply or is not defined (the page's footnote says so).
DASH = "—"

# Units as the report spells them: a space between the factors (SI style, as "mN m").
UNIT_SPELLING = {"Nm": "N m", "Ns": "N s", "Nm/rad": "N m/rad", "N/m": "N/m"}

# Readable units: base unit -> [(label, factor)] in increasing order of size.
PREFIXES = {"N": [("mN", 1e-3), ("N", 1.0)], "Nm": [("µN m", 1e-6), ("mN m", 1e-3), ("N m", 1.0)],
            "J": [("µJ", 1e-6), ("mJ", 1e-3), ("J", 1.0)],
            "Ns": [("mN s", 1e-3), ("N s", 1.0)], "s": [("s", 1.0)],
            "m": [("mm", 1e-3), ("m", 1.0)], "kg": [("g", 1e-3), ("kg", 1.0)]}


def unit_text(u):
    """A unit as the report spells it ("Nm" in a dataset's units attribute is "N m")."""
    return UNIT_SPELLING.get(u, u)


def unit_html(u):
    """A unit after a number on the page: its spelling, never broken across lines ("mN m")."""
    return html.escape(unit_text(u)).replace(" ", "\u00a0")


def _drop_minus_zero(text):
    """"-0", "-0.00" -> "0", "0.00": a value that rounds to zero has no sign."""
    if text.startswith("-") and not any(ch in "123456789" for ch in text.split("e")[0]):
        return text[1:]
    return text


def fmt(v, digits=MOST):
    """A number with `digits` significant digits and no trailing zeros (rule 2); integers exact;
    DASH for NaN, "∞" for an infinity."""
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    v = float(v)
    if math.isnan(v):
        return DASH
    if math.isinf(v):
        return "∞" if v > 0 else "−∞"
    return _drop_minus_zero(f"{v:.{digits}g}")


# A number with a fraction in a text the simulator wrote (a run's message, a method's status).
_DECIMAL = re.compile(r"(?<![\w.:])-?\d+\.\d+(?:e[-+]?\d+)?(?![\w.:]*\d)")


# A unit glued to its prefix in such a text ("0.027 Nm").
_GLUED_UNIT = re.compile(r"(?<![\w/])([µmk]?N)([ms])(?![\w])")


# A quantity in SI in such a text ("0.0337 Nm", "0.0037 m"): a number and a unit PREFIXES knows.
_SI_QUANTITY = re.compile(r"(?<![\w.])(-?\d+(?:\.\d+)?(?:e[-+]?\d+)?) (N m|Nm|N s|Ns|N|J|m|kg)(?![\w/])")


def _readable_quantity(m):
    """One SI quantity of a message in the prefix its magnitude reads in (0.0337 N m is 33.7 mN m,
    the prefix the page gives a torque of that size)."""
    v, unit = float(m.group(1)), m.group(2).replace(" ", "")
    label, factor = readable_unit(unit, abs(v)) if v != 0.0 else (unit_text(unit), 1.0)
    return f"{fmt(v / factor, MOST)} {label}"


def message_text(text):
    """A message from the file shown by the rule: its numbers to at most MOST significant digits
    ("t = 2.92057111 s" is "t = 2.9206 s"), its quantities in the prefix their size reads in and
    their units spelled as the report does ("0.027 Nm" is "27 mN m"); the file and failed_runs.csv
    keep it whole."""
    text = _DECIMAL.sub(lambda m: fmt(float(m.group(0)), MOST), str(text))
    return _SI_QUANTITY.sub(_readable_quantity, _GLUED_UNIT.sub(r"\1 \2", text))


def decade(x):
    """floor(log10(|x|)) of a nonzero finite x."""
    return int(math.floor(math.log10(abs(x))))


def resolution(values, uncertainty=float("nan")):
    """The decimal exponent e of the last digit shown (rule 1): the results of one quantity are
    shown to 10^e. From two significant digits of `uncertainty` (when it is a positive number),
    else of the spread of `values`; kept between MOST and LEAST significant digits of their largest
    |value|. None when no value is finite."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not len(v):
        return None
    big = float(np.max(np.abs(v)))
    if big == 0.0:
        return 0
    top = decade(big)
    scale = uncertainty if np.isfinite(uncertainty) and uncertainty > 0 else float(np.ptp(v))
    e = decade(scale) - 1 if scale > 0 else top - (LEAST - 1)
    return min(max(e, top - (MOST - 1)), top - (LEAST - 1))


def uncertainty_resolution(u, scale=1.0):
    """The resolution of a number on a fixed scale (a rank correlation, a Sobol' index: in [-1, 1]),
    whose uncertainty u is absolute: two significant digits of u, at most MOST digits of the scale."""
    if not (np.isfinite(u) and u > 0):
        return None
    return max(decade(u) - 1, decade(scale) - (MOST - 1))


def fmt_at(v, e):
    """v shown to 10^e (rule 1: e from resolution()); DASH for NaN. Without a resolution (e None)
    as a declared value."""
    if e is None or isinstance(v, (int, np.integer)):
        return fmt(v)
    v = float(v)
    if not math.isfinite(v):
        return fmt(v)
    if v != 0:
        e = max(e, decade(v) - (MOST - 1))      # never more than MOST significant digits
    if e > 0:
        v = round(v / 10 ** e) * 10 ** e
    return _drop_minus_zero(f"{v:.{max(0, -e)}f}")


def p_digits(p, lo=float("nan"), hi=float("nan")):
    """Significant digits of a probability p with interval [lo, hi] (rule 3): two of the interval's
    half width, between P_LEAST and P_MOST."""
    half = (hi - lo) / 2.0
    if not (p > 0 and np.isfinite(half) and half > 0):
        return P_LEAST
    return min(max(decade(p) - decade(half) + 2, P_LEAST), P_MOST)


def fmt_p(p, lo=float("nan"), hi=float("nan"), bound=float("nan")):
    """A probability (rule 3): its digits from its interval; 0 with a finite upper `bound` is shown
    as "< bound"."""
    if p == 0 and np.isfinite(bound) and bound > 0:
        return "< " + fmt(bound, P_LEAST)
    return fmt(p, p_digits(p, lo, hi))


def readable_unit(unit, magnitude):
    """(label, factor): value / factor is shown in `label`, chosen so that |magnitude| / factor
    is at least 1 when a prefix allows (the largest prefix not above the magnitude)."""
    opts = PREFIXES.get(unit)
    if not opts:
        return unit_text(unit), 1.0
    best = opts[0]
    for lab, f in opts:
        if np.isfinite(magnitude) and abs(magnitude) >= f:
            best = (lab, f)
    return best


class DisplayUnits:
    """One display unit and one resolution per quantity for the whole report: the design table,
    section 2, the margins, the plots and the terminal summary show a load in the same unit and
    to the same decimals (chosen once: the unit from its largest typical value, the resolution
    from its uncertainty or spread). Related quantities share their load's: the per-bay fields,
    and every torque of the margins (the drive torque's)."""
    ALIASES = {"latch_energy_J": "peak_latch_energy_J",
               "peak_static_drive_torque_Nm": "peak_drive_torque_Nm",
               "peak_inertial_drive_torque_Nm": "peak_drive_torque_Nm",
               "motor_torque_at_speed_Nm": "peak_drive_torque_Nm",
               "drive.stall_torque_Nm": "peak_drive_torque_Nm", "torque": "peak_drive_torque_Nm"}

    def __init__(self):
        self.chosen = {}      # key -> (label, factor)
        self.exponent = {}    # key -> resolution in the display unit (None: shown as declared)

    def choose(self, key, unit, magnitude, values=(), uncertainty=float("nan")):
        """The unit of `key` from `magnitude`, its resolution from `values` (SI) and `uncertainty`."""
        if key in self.chosen:
            return
        lab, f = readable_unit(unit, magnitude)
        self.chosen[key] = (lab, f)
        self.exponent[key] = resolution(np.asarray(values, dtype=float) / f, uncertainty / f)

    def get(self, key, unit, values=None):
        """(label, factor) of `key`; a key not chosen yet gets both from `values` (and keeps them)."""
        key = self.ALIASES.get(key, key)
        if key not in self.chosen:
            v = np.asarray(values if values is not None else [], dtype=float)
            v = v[np.isfinite(v)]
            self.choose(key, unit, float(np.max(np.abs(v))) if len(v) else float("nan"), v)
        return self.chosen[key]

    def at(self, key):
        """The resolution of `key` in its display unit (None: not chosen, shown as declared)."""
        return self.exponent.get(self.ALIASES.get(key, key))

    def text(self, key, unit, v, values=None):
        """v (SI) in the display unit of `key`, to its resolution, with the unit: "3.282 N"."""
        lab, f = self.get(key, unit, values)
        shown = fmt_at(v / f, self.at(key))
        return shown if shown == DASH else f"{shown} {lab}"


def choose_load_units(units, loads):
    """Each design load's display unit, from the larger of its nominal and its top percentile
    (its largest value when no level is reported), and its resolution: from its top level's
    bound minus its estimate (the estimate's uncertainty), else the spread of its runs."""
    for d in loads:
        top = abs(d.levels[-1].estimate) if d.levels else abs(d.max)
        values = [d.min, d.max, d.nominal, d.mean] + [x for lv in d.levels for x in (lv.estimate, lv.bound)]
        unc = d.levels[-1].bound - d.levels[-1].estimate if d.levels else float("nan")
        units.choose(d.key, d.unit, max(abs(d.nominal) if np.isfinite(d.nominal) else 0.0, top), values, unc)
