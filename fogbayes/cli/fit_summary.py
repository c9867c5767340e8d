"""The lines ``fogbayes fit --bayes`` prints: the posterior the document holds.

Each coefficient's posterior mean and central interval (the document's ``level``) in raw form
and units, and the sampler's verdict (largest R-hat, smallest ESS, divergences).
"""

from __future__ import annotations

from ..render.labels import coefficient_unit, term_label


def _g(x) -> str:
    return "nan" if x is None else f"{x:.4g}"


def _verdict(rhat, ess, divergences, converged) -> str:
    parts = []
    if rhat is not None:
        parts.append(f"R-hat max {rhat:.3f}")
    if ess is not None:
        parts.append(f"ESS min {ess:.0f}")
    if divergences is not None:
        parts.append(f"{int(divergences)} divergences")
    state = "converged" if converged else "NOT converged: do not use these intervals"
    return f"sampler: {', '.join(parts)}: {state}"


def posterior_lines(doc: dict) -> list[str]:
    """Lines for people from a fit document's ``bayes`` section; [] when it has none.

    bias-t/thermal: ``bayes.raw`` (terms, mean, interval) and ``bayes.convergence``;
    composite: ``raw_mean``/``raw_lo90``/``raw_hi90`` per coefficient block; allan: the
    terms under ``fit`` are the posterior's (:func:`fogbayes.cli.allan.summary_lines`);
    arma: the order each criterion selects.
    """
    bayes = doc.get("bayes")
    model = doc.get("model")
    if model == "allan" and isinstance(doc.get("fit"), dict):
        from .allan import summary_lines

        fit = doc["fit"]
        diag = fit.get("diagnostics") or {}
        lines = ["allan posterior (NUTS), terms with 90 % intervals:",
                 *summary_lines(doc)[1:]]
        if any(k in diag for k in ("r_hat_max", "divergences")):
            lines.append(_verdict(diag.get("r_hat_max"), diag.get("ess_min"),
                                  diag.get("divergences"), fit.get("converged")))
        return lines
    if not isinstance(bayes, dict):
        return []
    if model == "arma":
        return [f"arma posterior: selected {bayes.get('selected_waic')} by WAIC, "
                f"{bayes.get('selected_loo')} by PSIS-LOO"]
    if model == "composite":
        lines = ["composite posterior: raw coefficients, mean [90 % interval]:"]
        for name, mean in (bayes.get("raw_mean") or {}).items():
            lo, hi = bayes["raw_lo90"][name], bayes["raw_hi90"][name]
            flat = [(m, a, b) for m, a, b in zip(_flat(mean), _flat(lo), _flat(hi))]
            lines.append(f"  {name}: " + "; ".join(f"{_g(m)} [{_g(a)}, {_g(b)}]"
                                                    for m, a, b in flat))
        lines.append(_verdict(bayes.get("rhat_max"), bayes.get("ess_min"),
                              bayes.get("divergences"), bayes.get("converged")))
        return lines
    raw = bayes.get("raw") or {}
    if not raw.get("terms"):
        return []
    params = doc.get("params") or {}
    basis = params.get("basis") or {}
    exps = basis.get("exponents") or [None] * len(raw["terms"])
    noise = bayes.get("noise", "")
    if noise == "ar" and bayes.get("ar_order") is not None:
        noise = f"AR({bayes['ar_order']})"
    blocks = f" on {bayes['average_s']:g} s blocks" if bayes.get("average_s") else ""
    level = float(bayes.get("level", 0.9))
    lines = [f"{model} posterior (NUTS, {noise} noise{blocks}): mean "
             f"[{level:.0%} interval] per raw coefficient:"]
    for term, m, (lo, hi), e in zip(raw["terms"], raw["mean"], raw["interval"], exps):
        unit = coefficient_unit(e, basis.get("covariates", []), params.get("units")) \
            if e is not None else ""
        lines.append(f"  {term_label(term)}: {_g(m)} [{_g(lo)}, {_g(hi)}] {unit}".rstrip())
    conv = bayes.get("convergence") or {}
    lines.append(_verdict(conv.get("r_hat_max"), conv.get("ess_bulk_min"),
                          conv.get("divergences"), conv.get("converged")))
    return lines


def _flat(x) -> list:
    if isinstance(x, (list, tuple)):
        return [v for item in x for v in _flat(item)]
    return [x]
