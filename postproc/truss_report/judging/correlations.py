"""truss_report.judging.correlations: what drives the loads. Every sampled input column (one per
bay or frame of a per-bay / per-frame dispersion) and one aggregate per dispersion, their
Spearman rank correlations with each output over the ok runs, the outputs proportional to an
earlier one, and two checks of a Saltelli design (A and B rows independent; indices in [0, 1])."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..reading.campaign import Campaign, Dispersion, SobolOutput
from ..reading.h5file import Array
from ..reading.schema import OUTPUTS
from .stats import spearman_table

Correlations = dict[str, dict[str, tuple[float, int]]]   # output -> input label -> (rho, pairs)


@dataclass
class InputColumn:
    label: str
    values: Array
    aggregate: bool         # the per-dispersion aggregate (or a per-run dispersion itself)
    units: str = "1"        # of the values; an aggregate (per-bay/frame mean) is a relative deviation
    relative: bool = False  # values are (value - nominal) / nominal


def aggregate_label(d: Dispersion) -> str:
    return f"{d.key} (mean over {d.per}s)"


def aggregate_input(d: Dispersion) -> Array:
    """Per run: the mean over the run's bays (frames) of (value - nominal) / nominal
    ((value - nominal) when the nominal is 0)."""
    dev = d.values - d.nominal
    if d.nominal != 0:
        dev = dev / d.nominal
    finite = np.isfinite(dev)
    count = finite.sum(axis=1)
    total = np.where(finite, dev, 0.0).sum(axis=1)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def input_columns(c: Campaign) -> list[InputColumn]:
    """Every sampled input column and one aggregate per dispersion (see aggregate_input)."""
    cols = []
    for d in c.dispersions:
        if d.per == "run":
            cols.append(InputColumn(d.key, d.values, True, d.units))
            continue
        start = 1 if d.per == "bay" else 0
        for j in range(d.values.shape[1]):
            cols.append(InputColumn(f"{d.key}[{d.per} {j + start}]", d.values[:, j], False, d.units))
        cols.append(InputColumn(aggregate_label(d), aggregate_input(d), True,
                                "1" if d.nominal != 0 else d.units, d.nominal != 0))
    return cols


def rank_correlations(c: Campaign, cols: list[InputColumn]) -> Correlations:
    """{output: {input label: (Spearman rho, pairs)}} over the ok runs (the tornado charts and the
    scatter plots of the top inputs read the same table)."""
    res: Correlations = {}
    ranks: dict[bytes, object] = {}
    for key in OUTPUTS:
        y = np.where(c.ok, c.outputs[key], np.nan)
        res[key] = dict(zip((col.label for col in cols),
                            spearman_table([col.values for col in cols], y, ranks)))
    return res


def top_inputs(cols: list[InputColumn], rho: Correlations, key: str, k: int = 3) -> list[InputColumn]:
    """The k input columns of largest |Spearman rho| with the output `key`."""
    ranked = [(abs(rho[key][col.label][0]), col) for col in cols if np.isfinite(rho[key][col.label][0])]
    ranked.sort(key=lambda t: -t[0])
    return [col for _, col in ranked[:k]]


def ranked_inputs(rho: Correlations, key: str, top: int) -> list[tuple[str, float, int]]:
    """[(label, rho, pairs)] of the `top` inputs of largest |rho| with `key` (defined ones)."""
    return sorted(((lab, r, n) for lab, (r, n) in rho[key].items() if np.isfinite(r)),
                  key=lambda t: -abs(t[1]))[:top]


def proportional_to(c: Campaign) -> dict[str, str]:
    """{output: earlier output} for outputs whose ok values are a constant multiple of an earlier
    one's (drive torque = force x lead / 2 pi): one tornado serves both."""
    res: dict[str, str] = {}
    keys = list(OUTPUTS)
    for i, k in enumerate(keys):
        for j in keys[:i]:
            a, b = c.outputs[j][c.ok], c.outputs[k][c.ok]
            m = np.isfinite(a) & np.isfinite(b) & (a != 0)
            if m.sum() >= 3 and j not in res:
                r = b[m] / a[m]
                if np.ptp(r) <= 1e-9 * abs(np.mean(r)):
                    res[k] = j
                    break
    return res


def calc_design_correlations(c: Campaign, n_factors: int) -> tuple[dict[str, float], int]:
    """Largest |rank correlation| between the A and B rows of each dispersion's columns (one per
    bay or frame for per-bay/per-frame keys). Saltelli's design (block of G + 2 runs: A, B, AB_1
    .. AB_G) assumes A and B independent; a correlated pair biases that factor's indices. Campaign
    files of schema_version 1 drew A and B from one Sobol' point, some of whose pairs of dimensions
    correlate strongly at small N (docs/campaigns.md). Returns ({key: rho}, N)."""
    block = n_factors + 2
    n_blocks = len(c.status) // block
    res: dict[str, float] = {}
    if n_blocks < 3:
        return res, n_blocks
    for d in c.dispersions:
        v = np.asarray(d.values, dtype=float)
        v = v[: n_blocks * block].reshape(n_blocks * block, -1)
        worst = 0.0
        for j in range(v.shape[1]):
            a, b = v[0::block, j], v[1::block, j]
            if np.ptp(a) == 0 or np.ptp(b) == 0:
                continue
            ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
            r = float(np.corrcoef(ra, rb)[0, 1])
            if abs(r) > abs(worst):
                worst = r
        res[d.key] = worst
    return res, n_blocks


def correlated_factors(c: Campaign, n_factors: int) -> tuple[dict[str, float], float, int]:
    """The factors whose A and B columns correlate by more than 4 / sqrt(N) (four standard
    deviations of the correlation of N independent pairs), that limit and N."""
    rho, n_blocks = calc_design_correlations(c, n_factors)
    if not rho:
        return {}, float("nan"), n_blocks
    limit = 4.0 / np.sqrt(n_blocks)
    return {k: r for k, r in rho.items() if abs(r) > limit}, float(limit), n_blocks


def outside_unit_interval(outs: Mapping[str, SobolOutput]) -> list[str]:
    """The outputs with a point estimate outside [0, 1]: the estimators are unbiased, not bounded,
    and such values mean too few blocks for that output."""
    return [key for key, o in outs.items()
            if np.any((o.indices["first_order"] < 0) | (o.indices["first_order"] > 1)
                      | (o.indices["total"] < 0) | (o.indices["total"] > 1))]
