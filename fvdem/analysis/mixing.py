"""Mixing of a two-colour bed (Mema et al., 2020, §4; docs/equations.md §5).

Particles are binned by centre into a coarse analysis grid (5 x 5 x 35 for the paper's column).
In each cell with particles, ``S = -x1 ln x1 - x2 ln x2`` with ``x1, x2`` the number fractions of
the two colours (0 ln 0 = 0); the bed's mixing entropy is the particle-weighted mean normalised by
the fully mixed value ``S0 = ln 2``:

    S_tot = (1 / ln 2) sum_cells S N_cell / N          (0: segregated, 1: perfectly mixed)

The mixing time ``t95`` is the first time ``S_tot`` reaches 0.95. A bed whose colours are shuffled at random
does not reach 1 on a finite grid: a cell of ``n`` particles holds a binomial sample, whose entropy falls short
of ln 2 by about ``1 / (2 n)``. ``random_mixture_entropy`` is that ceiling for the particles where they are.
The Lacey index ``M = (s0^2 - s^2) / (s0^2 - sR^2)`` compares the variance ``s^2`` of the colour-1 fraction over
the occupied cells (weighted by their particle counts) with the fully segregated ``s0^2 = p (1 - p)``
and the random-mixture ``sR^2 = p (1 - p) / n`` (``n`` the mean particles per occupied cell).
"""
from __future__ import annotations

import numpy as np

MIXED = 0.95  # the entropy at which a bed counts as mixed: t95, the first time S_tot reaches it (Mema et al., §4)


def mixing_cells(case) -> tuple:
    """The mixing-entropy grid: ``output.mixing_cells``, else half the gas grid (the paper's 5 x 5 x 35 on
    10 x 10 x 70), else 5 x 5 x 35."""
    if case.output.mixing_cells is not None:
        return tuple(case.output.mixing_cells)
    if case.gas.enabled:
        return tuple(max(1, n // 2) for n in case.gas.cells)
    return (5, 5, 35)


def _cell_counts(position, colour, lower, upper, cells):
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    shape = np.asarray(cells, int)
    index = np.floor((np.asarray(position) - lower) / (upper - lower) * shape).astype(int)
    index = np.clip(index, 0, shape - 1)
    flat = np.ravel_multi_index(index.T, shape)
    total = np.bincount(flat, minlength=shape.prod())
    ones = np.bincount(flat, weights=(np.asarray(colour) == 1).astype(float), minlength=shape.prod())
    return total, ones


def _binary_entropy(x):
    """``-x ln x - (1 - x) ln(1 - x)`` elementwise (0 ln 0 = 0) [nats]."""
    x1 = np.asarray(x, float)
    x0 = 1.0 - x1
    with np.errstate(divide="ignore", invalid="ignore"):
        return -np.where(x1 > 0, x1 * np.log(x1), 0.0) - np.where(x0 > 0, x0 * np.log(x0), 0.0)


def mixing_indices(position, colour, lower, upper, cells=(5, 5, 35)):
    """``(S_tot, Lacey index)`` of particles with colours 0/1 from one binning into the analysis grid."""
    total, ones = _cell_counts(position, colour, lower, upper, cells)
    occupied = total > 0
    n_cell = total[occupied]
    x1 = ones[occupied] / n_cell
    s = _binary_entropy(x1)
    entropy = float((s * n_cell).sum() / total.sum() / np.log(2.0))
    p = ones.sum() / total.sum()
    if p in (0.0, 1.0) or n_cell.mean() == 1.0:  # one colour, or one particle a cell: no random-mix variance
        return entropy, float("nan")
    variance = float(np.sum(n_cell * (x1 - p) ** 2) / n_cell.sum())
    s0 = p * (1 - p)
    s_random = s0 / n_cell.mean()
    return entropy, (s0 - variance) / (s0 - s_random)


def mixing_entropy(position, colour, lower, upper, cells=(5, 5, 35)) -> float:
    """Normalised mixing entropy S_tot (Eqs. 34-35) of particles with colours 0/1 [dimensionless]."""
    return mixing_indices(position, colour, lower, upper, cells)[0]


def lacey_index(position, colour, lower, upper, cells=(5, 5, 35)) -> float:
    """Lacey mixing index (0 segregated, 1 random mixture) on the same analysis grid."""
    return mixing_indices(position, colour, lower, upper, cells)[1]


def random_mixture_entropy(position, colour, lower, upper, cells=(5, 5, 35)) -> float:
    """The expected S_tot of the same particles, where they are, with their colours shuffled at random:
    the highest value a bed can be expected to reach on this grid (a perfect random mixture, not the
    ordered 1).

        S_random = (1 / ln 2) sum_cells (N_cell / N) E[S(K / N_cell)],   K ~ Binomial(N_cell, p)

    with ``p`` the bed's colour-1 fraction (the binomial is the sampling of a large bed; shuffling a
    finite one is hypergeometric, a relative difference of order 1 / N). Dimensionless: 0 when each
    cell holds one particle, 0.5 for cells of two at p = 1/2, about ``1 - 1 / (2 n ln 2)`` for cells of
    ``n`` >> 1 at p = 1/2 (0.95 needs about 15 particles per cell). NaN for an empty bed."""
    from scipy.stats import binom
    total, ones = _cell_counts(position, colour, lower, upper, cells)
    count = total.sum()
    if count == 0:
        return float("nan")
    p = ones.sum() / count
    sizes, cells_of_size = np.unique(total[total > 0], return_counts=True)
    expected = 0.0
    for n, m in zip(sizes, cells_of_size):
        k = np.arange(n + 1)
        expected += m * n * float(np.sum(binom.pmf(k, n, p) * _binary_entropy(k / n)))
    return float(expected / count / np.log(2.0))


def colour_by_layer(position, colour, lower, upper, layers: int):
    """Particles and the colour-1 fraction in ``layers`` horizontal slabs of equal height between ``lower[2]``
    and ``upper[2]`` (by centre; those outside counted in the end slabs): ``(count, fraction)``, the fraction
    NaN in an empty slab. Where the bed is still unmixed (Mema et al.'s t95 waits for the last slab: in
    fvdem's runs the one on the distributor, docs/validation.md)."""
    z0, z1 = float(np.asarray(lower, float)[2]), float(np.asarray(upper, float)[2])
    index = np.clip(np.floor((np.asarray(position, float)[:, 2] - z0) / (z1 - z0) * layers).astype(int), 0, layers - 1)
    count = np.bincount(index, minlength=layers)
    ones = np.bincount(index, weights=(np.asarray(colour) == 1).astype(float), minlength=layers)
    with np.errstate(divide="ignore", invalid="ignore"):
        return count, np.where(count > 0, ones / np.maximum(count, 1), np.nan)


def mixing_time(times, entropy, level: float = MIXED):
    """First time [s] at which ``entropy`` reaches ``level`` (linear interpolation between samples),
    or None if it never does."""
    times, entropy = np.asarray(times, float), np.asarray(entropy, float)
    above = np.nonzero(entropy >= level)[0]
    if not len(above):
        return None
    k = int(above[0])
    if k == 0:
        return float(times[0])
    t0, t1, s0, s1 = times[k - 1], times[k], entropy[k - 1], entropy[k]
    return float(t0 + (level - s0) / (s1 - s0) * (t1 - t0))


def orientation_angles(axis) -> np.ndarray:
    """Angle [rad] between each particle axis and the vertical, folded into [0, pi/2]."""
    return np.arccos(np.clip(np.abs(np.asarray(axis)[:, 2]), 0.0, 1.0))


def void_fraction_binarity(values, packed_percentile: float = 2.0) -> float:
    """How binary a set of cell void fractions is (Mema et al. (2020) Fig. 7: AR-1's "more binary" than AR-4's):
    the variance as a fraction of the largest a variable of the same mean can have between the packed
    voidage ``a`` (the ``packed_percentile``-th percentile of the values) and 1,

        beta = var(eps) / ((mean - a) (1 - mean))        in [0, 1],

    1 when every cell is either packed or empty (bubbles), 0 when every cell has the same voidage.
    Dimensionless; NaN for fewer than two values or no spread of the mean from ``a`` or 1."""
    values = np.asarray(values, float)
    if values.size < 2:
        return float("nan")
    a = float(np.percentile(values, packed_percentile))
    mean = float(values.mean())
    room = (mean - a) * (1.0 - mean)
    if room <= 0.0:
        return float("nan")
    return float(min(1.0, max(0.0, values.var() / room)))


def cells_in_bed(voidage, cell_centres, below: float = 0.3, empty: float = 0.99) -> np.ndarray:
    """Mask of the cells whose centres lie below ``below`` [m] and at or below the bed's top layer: the
    highest horizontal layer of cells whose mean voidage is under ``empty``. A bed lower than ``below``
    (a small demo column) then contributes its own cells, not the particle-free freeboard above it,
    whose voidage of 1 would dominate a histogram; bubbles inside the bed stay counted."""
    voidage, centres = np.asarray(voidage, float), np.asarray(cell_centres, float)
    heights, layer = np.unique(np.round(centres[:, 2], 9), return_inverse=True)
    layer_mean = np.bincount(layer, weights=voidage) / np.bincount(layer)
    filled = np.nonzero(layer_mean < empty)[0]
    top = heights[filled[-1]] if filled.size else -np.inf
    return (centres[:, 2] < below) & (np.round(centres[:, 2], 9) <= top)
