"""Everything the diagnosis needs about one recording, computed once (:class:`Context`).

Rate in deg/h, outlier flags, covariates, block grid and block means; ``block_design(terms)``
gives cached block means of term columns. Outliers: |d_i - median| > 6 sigma_MAD on the first
difference (blind to slow effects); left out of block means, reported, never removed.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..inference.noise_ssm import NoiseSpec, make_spec
from ..preprocess.covariates import (BlockGrid, Covariates, block_covariates, block_grid,
                                     covariates_of)
from ..effects.terms import Term, columns

MAD_TO_SIGMA = 1.4826


def spike_scale(d: np.ndarray) -> tuple[float, float]:
    """(median, robust sigma) of the first differences ``d``: sigma = 1.4826 MAD."""
    med = np.median(d)
    return float(med), float(MAD_TO_SIGMA * np.median(np.abs(d - med)))


def spikes_between(d: np.ndarray, med: float, s: float, n_sigma: float = 6.0) -> np.ndarray:
    """Flags of the samples between consecutive differences ``d`` (len(d) - 1 of them):
    both differences beyond ``n_sigma`` robust sigmas, of opposite signs."""
    big = np.abs(d - med) > n_sigma * s
    return big[:-1] & big[1:] & (np.sign(d[:-1]) != np.sign(d[1:]))


def spike_flags(x: np.ndarray, n_sigma: float = 6.0) -> np.ndarray:
    """Flag isolated spikes: both differences around sample i exceed n_sigma robust sigmas."""
    x = np.asarray(x, float)
    if x.size < 5:
        return np.zeros(x.size, bool)
    d = np.diff(x)
    med, s = spike_scale(d)
    if s <= 0:
        return np.zeros(x.size, bool)
    flag = np.zeros(x.size, bool)
    flag[1:-1] = spikes_between(d, med, s, n_sigma)
    return flag


class Context(NamedTuple):
    """One recording prepared for the loop (see module doc)."""

    rate: np.ndarray          # (n,) deg/h
    outlier: np.ndarray       # (n,) bool
    cov: Covariates           # per sample
    grid: BlockGrid
    y: np.ndarray             # (nb,) block means of the rate (0 where missing)
    bcov: Covariates          # block means of the covariates
    spec: NoiseSpec           # base noise structure (flicker bank + random walk)
    cache: dict               # term repr -> block-mean columns

    def block_columns(self, term: Term) -> np.ndarray:
        key = repr(term)
        if key not in self.cache:
            self.cache[key] = self.grid.mean(columns(term, self.cov))
        return self.cache[key]

    def block_design(self, terms: list[Term]) -> np.ndarray:
        return np.column_stack([self.block_columns(tm) for tm in terms])


def make_context(rec, *, target_blocks: int = 2500, flag_outliers: bool = True,
                 random_walk: bool = True, flicker: bool = True) -> Context:
    """Prepare ``rec`` (a :class:`~fogbayes.data.Recording`) for the loop."""
    rate = rec.rate("deg/h")
    outlier = spike_flags(rate) if flag_outliers else np.zeros(rec.n, bool)
    grid = block_grid(rec.time, rec.sample_rate, use=~outlier, target_blocks=target_blocks)
    cov = covariates_of(rec, grid)
    y = grid.mean(rate)
    spec = make_spec(grid.dt, cov.duration, random_walk=random_walk, flicker=flicker)
    return Context(rate, outlier, cov, grid, y, block_covariates(cov, grid), spec, {})
