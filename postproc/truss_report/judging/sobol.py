"""truss_report.judging.sobol: Sobol' indices recomputed from a Saltelli campaign's blocks (rows A,
B, AB_1 .. AB_G), with the estimators the campaign uses, to show their convergence and how far
the file's /sensitivity is from them."""
from __future__ import annotations

import numpy as np

from ..reading.campaign import Sensitivity
from ..reading.h5file import Array

Mask = np.ndarray[tuple[int], np.dtype[np.bool_]]


def sobol_blocks(y: Array, G: int, n_blocks: int) -> tuple[Array, Array, Array]:
    """Per block (rows A, B, AB_1..AB_G of a Saltelli campaign): arrays fA, fB, fAB (b x G)."""
    Y = y[:n_blocks * (G + 2)].reshape(n_blocks, G + 2)
    return Y[:, 0], Y[:, 1], Y[:, 2:]


def usable_blocks(y: Array, ok: Mask, G: int) -> tuple[Array, Array, Array]:
    """fA, fB, fAB of the blocks whose runs are all ok with a finite output."""
    nb = len(y) // (G + 2)
    good = np.all((ok & np.isfinite(y))[:nb * (G + 2)].reshape(nb, G + 2), axis=1)
    fA, fB, fAB = sobol_blocks(y, G, nb)
    return fA[good], fB[good], fAB[good]


def sobol_estimates(fA: Array, fB: Array, fAB: Array) -> tuple[Array, Array]:
    """Saltelli 2010 first order and Jansen 1999 total indices (per factor), on outputs centred
    by the mean of f(A) and f(B), V their population variance (as the campaign computes them)."""
    mu = np.mean(np.concatenate([fA, fB]))
    fA, fB, fAB = fA - mu, fB - mu, fAB - mu
    V = np.var(np.concatenate([fA, fB]))
    s1 = np.mean(fB[:, None] * (fAB - fA[:, None]), axis=0) / V
    st = 0.5 * np.mean((fA[:, None] - fAB) ** 2, axis=0) / V
    return s1, st


def sobol_agreement(sensitivity: Sensitivity, series: list[tuple[str, Array, Mask]]) -> float:
    """Largest |difference| of the indices recomputed from all usable blocks and /sensitivity."""
    G = len(sensitivity.factor)
    worst = 0.0
    for key, y, ok in series:
        s1, st = sobol_estimates(*usable_blocks(y, ok, G))
        o = sensitivity.outputs[key].indices
        worst = max(worst, float(np.nanmax(np.abs(np.concatenate(
            [s1 - o["first_order"], st - o["total"]])))))
    return worst
