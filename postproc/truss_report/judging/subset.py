"""truss_report.judging.subset: what a subset-simulation estimate says. The interval: the estimate
is a product of the levels' shares, close to lognormal, so the 95 % interval is p exp(+-1.96 s),
s^2 = ln(1 + cov^2). The plateau rule: levels whose threshold hardly moved (the estimate may be
biased low). The design point: the failure sample of smallest |z|, and the inputs' importance."""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..reading.campaign import Campaign
from ..reading.methods import Subset

Z95 = 1.959963984540054

# A level "on a plateau" of the margin: its threshold moved less than this share of its distance
# to the failure (b_k - b_{k+1} < PLATEAU_SHARE b_k). From PLATEAU_LEVELS such levels on, the report
# warns that the estimate may be biased low.
PLATEAU_SHARE = 0.01
PLATEAU_LEVELS = 3


def interval(p: float, cov: float) -> tuple[float, float]:
    """Lognormal 95 % interval of the estimate p with coefficient of variation cov."""
    if not (p > 0 and math.isfinite(cov)):
        return float("nan"), float("nan")
    sd = math.sqrt(math.log1p(cov * cov))
    return p * math.exp(-Z95 * sd), p * math.exp(Z95 * sd)


def count_plateau_levels(thresholds: Sequence[float]) -> int:
    """How many levels moved their threshold by less than PLATEAU_SHARE of its distance to 0.

    On such a plateau the margin hardly depends on the inputs that lead to the failure: the levels
    select on the others (an input's scatter that moves the margin a little everywhere), the Markov
    chains condition on them, and the region where the margin falls to failure is reached, if at all,
    by a chain that must cross from one to the other. Each such level still multiplies p by about
    p0, so the estimate can lie far below the failure probability, beyond what its CoV says."""
    b = [float(x) for x in thresholds]
    return sum(1 for k in range(len(b) - 1) if b[k] > 0 and b[k] - b[k + 1] < PLATEAU_SHARE * b[k])


def biased_low(n_plateau_levels: int) -> bool:
    """An estimate that crossed PLATEAU_LEVELS or more plateau levels may be biased low."""
    return n_plateau_levels >= PLATEAU_LEVELS


@dataclass
class InputAtFailure:
    """A dispersed input at the failure: nominal, the population's median (level 0: draws of
    the dispersions), the failure samples' median, their mean standard-normal coordinate."""
    key: str
    width: int            # columns: 1, or its bays / frames
    per: str
    nominal: float
    unit: str
    population: float
    failure: float
    mean_z: float


def inputs_at_failure(s: Subset, c: Campaign) -> list[InputAtFailure]:
    """Per dispersed key, sorted by |mean z| (largest first; undefined last)."""
    n0 = int(s.levels["runs"][0])
    z, rows, col = s.failure_z, [], 0
    for d in c.dispersions:
        if d.key not in s.failure_inputs:
            continue
        x, nominal, unit = s.failure_inputs[d.key]
        w = 1 if x.ndim == 1 else x.shape[1]
        zk = z[:, col:col + w] if len(z) else np.zeros((0, w))
        col += w
        mz = float(np.mean(zk)) if zk.size else float("nan")
        pop = d.values[:n0] if d.values.ndim == 1 else np.nanmean(d.values[:n0], axis=1)
        fx = x if x.ndim == 1 else np.nanmean(x, axis=1)
        rows.append((abs(mz) if math.isfinite(mz) else -1.0,
                     InputAtFailure(d.key, w, d.per, float(nominal), unit, float(np.nanmedian(pop)),
                                    float(np.nanmedian(fx)) if len(fx) else float("nan"), mz)))
    rows.sort(key=lambda t: -t[0])
    return [r for _, r in rows]


@dataclass
class DesignPointInput:
    key: str
    width: int
    per: str
    nominal: float
    unit: str
    value: float          # at the design point (the mean over its bays / frames)
    z: float              # z* (the mean over bays likewise)
    alpha: float          # direction cosine (NaN for a per-bay or per-frame key)
    share: float          # alpha^2 summed over the key's columns


@dataclass
class DesignPoint:
    run: int
    beta: float           # |z*|
    margin: float
    rows: list[DesignPointInput]


def design_point(s: Subset, c: Campaign) -> DesignPoint | None:
    """The most probable failure point among the failure samples: the one of highest
    standard-normal density, i.e. smallest |z| (a FORM design point estimated from the samples,
    not refined); the importance of each input: the direction cosines alpha_i = -z*_i / |z*| of
    its columns; alpha^2 summed over a key's columns is its share of |z*|^2 (the shares sum to 1).
    None without failure samples."""
    z = np.asarray(s.failure_z, dtype=float)
    if z.ndim != 2 or len(z) == 0:
        return None
    norms = np.sqrt(np.sum(z * z, axis=1))
    i = int(np.argmin(norms))
    zs, beta = z[i], float(norms[i])
    alpha = -zs / beta if beta > 0 else np.zeros_like(zs)
    rows, col = [], 0
    for d in c.dispersions:
        if d.key not in s.failure_inputs:
            continue
        x, nominal, unit = s.failure_inputs[d.key]
        w = 1 if x.ndim == 1 else x.shape[1]
        xi = float(x[i]) if x.ndim == 1 else float(np.nanmean(x[i]))
        a = alpha[col:col + w]
        rows.append(DesignPointInput(d.key, w, d.per, float(nominal), unit, xi,
                                     float(np.mean(zs[col:col + w])),
                                     float(a[0]) if w == 1 else float("nan"), float(np.sum(a * a))))
        col += w
    rows.sort(key=lambda r: -r.share)
    return DesignPoint(int(s.failure_runs[i]), beta, float(s.failure_margin[i]), rows)
