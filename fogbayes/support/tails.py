"""Tail probabilities and quantiles of the normal and chi-square laws, from ``scipy.special``.

The same functions ``scipy.stats.norm`` and ``scipy.stats.chi2`` call (``ndtri``, ``chdtrc``,
``chdtri``), so the numbers are theirs to the last bit; ``scipy.stats`` itself costs about a
second to import, more than the rest of a ``fogbayes fit`` call.
"""

from __future__ import annotations

import numpy as np
from scipy import special


def norm_ppf(p):
    """Quantile of the standard normal law at ``p`` (``stats.norm.ppf``)."""
    return special.ndtri(p)


def norm_isf(q):
    """Upper-tail quantile of the standard normal law, P(Z > z) = ``q`` (``stats.norm.isf``)."""
    return -special.ndtri(q)


def chi2_sf(x, df):
    """P(chi^2_df > x) (``stats.chi2.sf``)."""
    return special.chdtrc(df, x)


def chi2_isf(q, df):
    """x with P(chi^2_df > x) = ``q`` (``stats.chi2.isf``)."""
    return special.chdtri(df, q)


def chi2_ppf(q, df):
    """Quantile of chi^2_df, 2 P^-1(df/2, q) with P the regularised lower incomplete gamma
    (``stats.chi2.ppf``; the median is ``chi2_ppf(0.5, df)``)."""
    return 2.0 * special.gammaincinv(np.asarray(df, float) / 2.0, q)


def norm_cdf(x):
    """P(Z <= x) (``stats.norm.cdf``)."""
    return special.ndtr(x)


def norm_sf(x):
    """P(Z > x) (``stats.norm.sf``)."""
    return special.ndtr(-np.asarray(x, float))


def chi2_logsf(x, df):
    """log P(chi^2_df > x) (``stats.chi2.logsf``: log1p(-cdf) up to the median, log sf
    beyond it, -inf where the tail underflows)."""
    x = np.asarray(x, float)
    with np.errstate(divide="ignore"):
        return np.where(x > chi2_ppf(0.5, df), np.log(special.chdtrc(df, x)),
                        np.log1p(-special.chdtr(df, x)))


def t_ppf(p, df):
    """Quantile of Student's t with ``df`` degrees of freedom (``stats.t.ppf``)."""
    return special.stdtrit(df, p)
