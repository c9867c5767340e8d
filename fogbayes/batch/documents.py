"""The fit documents of a vectorised fleet fit, as ``fit_recording`` writes them.

Same keys in the same order as :func:`fogbayes.thermal.workflow.fit_recording`'s document;
the raw coefficients (powers of the covariates, the papers' form) of all sensors come from
one batched change of basis (:func:`fogbayes.models.polynomial.rebase_matrices`),
``raw = M b``, ``Cov_raw = M Cov M^T``.
"""

from __future__ import annotations

import numpy as np

from ..data.documents import FIT_SCHEMA
from ..models.basis_document import coefficient_document
from ..inference.lsq import conditionings_from_covariances, identifiability
from ..models.polynomial import rebase_matrices

_RANK_WARNING = ("the design is rank deficient: some covariate does not vary enough (e.g. "
                 "dT/dt in a record without ramps); coefficients are not identified")


def fit_documents(recs, model: str, spec, proc, bases, fits, lo, hi, n_blocks, n_flagged,
                  metrics, version: str) -> list[dict]:
    """One document per recording. ``fits``: stacked coef, cov, rss, s2, dof, ok (S, ...);
    ``lo``/``hi`` (S, c) the covariate range each fit saw; ``n_blocks`` (S,) its blocks;
    ``n_flagged``: Pauta counts (S,) or None without outlier flags."""
    M = rebase_matrices(bases[0].terms, [b.centre for b in bases], [b.scale for b in bases])
    raw = np.einsum("spq,sq->sp", M, fits.coef)
    raw_cov = M @ fits.cov @ M.transpose(0, 2, 1)
    p = bases[0].n_terms
    n_blocks = np.asarray(n_blocks)
    with np.errstate(divide="ignore", invalid="ignore"):  # paper 000 eq. 11: inf without dof
        rms = np.where(n_blocks > p, np.sqrt(fits.rss / (n_blocks - p)), np.inf).tolist()
    s2, dof, ok = fits.s2.tolist(), fits.dof.tolist(), fits.ok.tolist()
    lo, hi, n_blocks = lo.tolist(), hi.tolist(), n_blocks.tolist()
    flagged = [0] * len(recs) if n_flagged is None else np.asarray(n_flagged).tolist()
    units = {"output": "deg/h", "T": "degC", "dT/dt": "degC/min"}
    # the condition numbers from Cov = s^2 (X^T W X)^-1: a fleet fit keeps no design
    conds = conditionings_from_covariances(fits.cov, fits.s2)
    out = []
    for s, rec in enumerate(recs):
        basis = bases[s]
        ident = identifiability(basis, lo[s], hi[s], conds[s])
        warnings = [] if ok[s] else [_RANK_WARNING]
        if not ident["identifiable"]:
            warnings.append(f"not identifiable: {ident['reason']}; the coefficients are "
                            "meaningless")
        out.append({
            "schema": FIT_SCHEMA, "model": model, "fogbayes_version": version,
            "converged": bool(ok[s]) and ident["identifiable"], "warnings": warnings,
            "input": {"source": rec.meta.source, "sensor_id": rec.meta.sensor_id,
                      "unit": rec.unit, "scale_factor": rec.scale_factor, "n": rec.n},
            "params": {"spec": spec._asdict(), **coefficient_document(
                basis, fits.coef[s], fits.cov[s], units=units,
                valid_range=dict(zip(basis.names, zip(lo[s], hi[s]))),
                raw=(raw[s], raw_cov[s]))},
            "processing": proc._asdict(),
            "outliers": {"method": proc.outliers, "n_sigma": proc.n_sigma,
                         "count": flagged[s]},
            "diagnostics": {"identifiability": ident},
            "fit": {"n_blocks": n_blocks[s], "n_params": p, "rms_criterion": rms[s],
                    "residual_std": float(np.sqrt(s2[s])), "dof": int(dof[s]),
                    "stderr_note": "least-squares standard errors assume white block means; "
                                   "see 'bayes' for intervals with AR noise"},
            "metrics": metrics[s],
            "vectorized": True,
        })
    return out
