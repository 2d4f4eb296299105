"""truss_report.judging.importance: what a cross-entropy importance-sampling estimate says about
its inputs. The adapted density is N(mu, I) in the standard normal space of the dispersions
(docs/campaigns.md, "Rare failures: cross-entropy importance sampling"): a component of mu moves
only where the elite runs moved it by more than 3 standard errors, so |mu_i| says how far input i
must go, in its own standard deviations, for the failure; the inputs that drive the failure have
the largest |mu_i|. Each dispersion owns a block of dimensions in the campaign's order: 1 per run,
its columns per bay or per frame (src/campaign/dispersion.hpp DimensionLayout)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..reading.campaign import Campaign, Dispersion
from ..reading.importance import Importance


@dataclass
class InputShift:
    """A dispersed input under the adapted density: its mean shift (standard normal units, the mean
    over its bays or frames) and the input's value there in its own unit (NaN for a discrete law)."""
    key: str
    width: int            # dimensions: 1, or its bays / frames
    per: str
    nominal: float
    unit: str
    shift: float          # mu, in standard deviations of the input's law
    value: float          # the input at z = mu (the scene value, as the run applies the draw)


def calc_draw(d: Dispersion, z: float) -> float:
    """The dispersion's draw at the standard normal coordinate z: F^-1(Phi(z)) of its law."""
    p, u = d.params, float(stats.norm.cdf(z))
    if d.distribution == "normal":
        return float(p["mean"] + p["std"] * z)
    if d.distribution == "truncated_normal":
        a, b = (p["lower"] - p["mean"]) / p["std"], (p["upper"] - p["mean"]) / p["std"]
        return float(stats.truncnorm.ppf(u, a, b, loc=p["mean"], scale=p["std"]))
    if d.distribution == "uniform":
        return float(p["lower"] + (p["upper"] - p["lower"]) * u)
    if d.distribution == "lognormal":
        return float(math.exp(p["mu"] + p["sigma"] * z))
    return float("nan")   # discrete: no single value at a coordinate worth showing


def calc_applied(d: Dispersion, draw: float) -> float:
    """The scene value a draw gives: the draw itself (absolute), nominal + draw (offset) or
    nominal (1 + draw) (relative)."""
    if d.apply == "offset":
        return d.nominal + draw
    if d.apply == "relative":
        return d.nominal * (1.0 + draw)
    return draw


def calc_input_shifts(s: Importance, c: Campaign) -> list[InputShift] | None:
    """Per dispersed key, sorted by |mu| (largest first). None when the dispersions' dimensions do
    not add up to the length of /importance/final_mean (a file this reading does not match)."""
    widths = [1 if d.values.ndim == 1 else int(d.values.shape[1]) for d in c.dispersions]
    if sum(widths) != len(s.final_mean):
        return None
    rows, col = [], 0
    for d, w in zip(c.dispersions, widths):
        mu = float(np.mean(s.final_mean[col:col + w]))
        col += w
        rows.append(InputShift(d.key, w, d.per, d.nominal, d.units, mu, calc_applied(d, calc_draw(d, mu))))
    rows.sort(key=lambda r: -abs(r.shift))
    return rows
