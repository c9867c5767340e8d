"""A polynomial fit's coefficients as the fit document's ``params`` section.

``basis``: covariate names, term labels, exponents, centres and scales of the scaled basis
(:class:`~fogbayes.models.polynomial.PolyBasis`); ``coef`` (and ``covariance``, ``stderr``) on the
scaled columns; ``raw``: the same polynomial in powers of the covariates (origin 0).
"""

from __future__ import annotations

import numpy as np

from ..data.doc_models import check_basis
from ..data.doc_rules import FitDocumentError
from .polynomial import PolyBasis, to_raw


def basis_to_dict(basis: PolyBasis) -> dict:
    return {"covariates": list(basis.names), "terms": basis.labels(),
            "exponents": [list(e) for e in basis.terms],
            "centre": list(basis.centre), "scale": list(basis.scale)}


def basis_from_dict(d: dict, *, source: str | None = None) -> PolyBasis:
    """Inverse of :func:`basis_to_dict` (raises a FogbayesError on a malformed document)."""
    check_basis(d, source=source)  # shapes, finite centres, positive scales, exponents 0..8
    try:
        return PolyBasis(tuple(d["covariates"]), tuple(tuple(int(x) for x in e) for e in d["exponents"]),
                         tuple(float(x) for x in d["centre"]), tuple(float(x) for x in d["scale"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise FitDocumentError(f"the basis is malformed ({exc!r})", file=source,
                               key="params.basis",
                               fix="pass a document written by 'fogbayes fit'") from None


def coefficient_document(basis: PolyBasis, coef, cov=None, *, units: dict | None = None,
                         valid_range: dict | None = None, raw=None) -> dict:
    """JSON-able coefficients: scaled (exact) and raw (powers of the covariates, origin 0).

    ``raw``: the raw coefficients (and covariance, with ``cov``) when already computed
    (a fleet converts all its sensors at once with ``rebase_matrices``).
    """
    coef = np.asarray(coef, dtype=float)
    doc = {"basis": basis_to_dict(basis), "coef": coef.tolist()}
    if cov is not None:
        cov = np.asarray(cov, dtype=float)
        raw, raw_cov = to_raw(coef, basis, cov) if raw is None else raw
        doc.update(covariance=cov.tolist(), stderr=np.sqrt(np.diag(cov)).tolist())
        doc["raw"] = {"terms": basis.labels(), "coef": raw.tolist(),
                      "stderr": np.sqrt(np.clip(np.diag(raw_cov), 0, None)).tolist()}
    else:
        raw = to_raw(coef, basis) if raw is None else raw
        doc["raw"] = {"terms": basis.labels(), "coef": np.asarray(raw).tolist()}
    doc["raw"]["form"] = "sum_k coef_k * prod_c covariate_c ** exponent_kc (origin 0)"
    if units:
        doc["units"] = dict(units)
    if valid_range:
        doc["valid_range"] = {k: [float(v[0]), float(v[1])] for k, v in valid_range.items()}
    return doc
