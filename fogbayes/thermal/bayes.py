"""Posterior part of a thermal fit document: NUTS with AR(p) noise on coarser blocks.

On ``bayes_average_s`` (default 10 s) block means, AR(1) noise by default; records without a
complete block fall back to the fit blocks (the document says which).
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError
from ..inference.bayes import fit_linear_bayes
from ..inference.compare import loo, waic
from ..models.polynomial import design, rebase_matrix
from .data import coarser_blocks


def posterior_document(blocks, basis, proc, *, seed: int, noise: str = "ar", ar_order: int = 1,
                       ma_order: int = 0, num_warmup: int = 500, num_samples: int = 1000,
                       num_chains: int = 2, level: float = 0.9,
                       bayes_average_s: float = 10.0) -> dict:
    """Posterior of the coefficients of ``basis`` as a JSON-able dict (see module doc)."""
    used = blocks
    if bayes_average_s > proc.average_s:
        try:
            coarse = coarser_blocks(blocks, bayes_average_s)
            if coarse.y.size >= 5 * (basis.n_terms + ar_order + ma_order + 1):
                used = coarse
        except FogbayesError:
            pass  # bursts shorter than the window: keep the fit blocks (reported below)
    avg = bayes_average_s if used is not blocks else proc.average_s
    fit = fit_linear_bayes(design(used.z, basis), used.y, seed=seed, noise=noise, p=ar_order,
                           q=ma_order, num_warmup=num_warmup, num_samples=num_samples,
                           num_chains=num_chains, level=level)
    draws = fit.groups["posterior"]["beta"].reshape(-1, basis.n_terms)
    raw = draws @ rebase_matrix(basis).T
    tail = (1.0 - level) / 2
    doc = {"noise": noise, "ar_order": ar_order if noise != "white" else 0,
           "ma_order": ma_order if noise == "arma" else 0, "average_s": float(avg),
           "n_blocks": int(used.y.size), "level": float(level), "seed": int(seed),
           "mean": fit.mean.tolist(), "sd": fit.sd.tolist(), "interval": fit.interval.tolist(),
           "raw": {"terms": basis.labels(), "mean": raw.mean(0).tolist(),
                   "sd": raw.std(0, ddof=1).tolist(),
                   "interval": np.quantile(raw, [tail, 1 - tail], axis=0).T.tolist()},
           "noise_params": {"sigma_deg_h": fit.noise["sigma"], "phi": fit.noise["phi"],
                            "theta": fit.noise["theta"]},
           "convergence": fit.convergence._asdict()}
    try:
        ll = fit.groups["log_likelihood"]["y"]  # (chain, draw, n): draws chain by chain
        ll = ll.reshape(-1, ll.shape[-1])
        doc["waic"], doc["loo"] = waic(ll), loo(ll, fit.relative_efficiency())
    except (ValueError, TypeError) as exc:  # reported, not hidden
        doc["waic"] = doc["loo"] = {"error": str(exc)}
    return doc
