"""A cap on the random walk from a static run (``--noise-prior``).

One record cannot tell a slow excursion from a rate random walk, so the walk is bounded:
K <= K_max, i.e. log_rw <= log(K_max^2 dt / 3600 / s2) (K in deg/h^1.5, s2 the white
block-mean variance). K_max: ``fit.terms.K.high`` of a ``fogbayes allan --json`` document,
``{"K": ...}``, or a ``fogbayes.prior/1`` sheet (value x looseness,
:mod:`fogbayes.inference.datasheet`; no RRW is refused). An Allan document also caps a
Gauss-Markov component: sigma <= max ADEV_high / 0.618, tau_c <= longest tau / 1.89. The cap is an
assumption; reaching it is reported as ``noise_model_at_bound``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

from ..errors import FogbayesError
from ..inference.noise_ssm import LOG_BOUNDS, NoiseSpec

#: how to write a prior, for error messages
HOW = ("write it with 'fogbayes allan STATIC.csv --json PRIOR.json' on a static run of the "
       "same sensor, or 'fogbayes prior --rrw VALUE --rrw-unit UNIT --json PRIOR.json' from "
       "the datasheet, or give a datasheet value as {\"K\": 0.02} (deg/h^1.5)")


#: a Gauss-Markov process's ADEV peaks at GM_PEAK sigma, at tau = GM_PEAK_TAU tau_c
GM_PEAK, GM_PEAK_TAU = 0.618, 1.89


class NoisePrior(NamedTuple):
    """Caps on the noise model from a static run (see module doc).

    k_max: rate random walk K (deg/h^1.5); tau, adev_high: the static run's tau (s) and the
    upper end of its ADEV interval (deg/h), which cap a free Gauss-Markov component (empty:
    not capped); source: where the values came from.
    """

    k_max: float
    tau: tuple[float, ...] = ()
    adev_high: tuple[float, ...] = ()
    source: str = "given"

    def markov_caps(self, dt: float) -> tuple[float | None, float | None]:
        """(sigma_max deg/h, tau_max s) of a Markov component on blocks of ``dt`` s."""
        seen = [h for t, h in zip(self.tau, self.adev_high) if t >= GM_PEAK_TAU * dt / 2.0]
        if not seen:
            return None, None
        return max(seen) / GM_PEAK, max(self.tau) / GM_PEAK_TAU

    def log_rw_cap(self, dt: float, sigma2: float) -> float:
        """The cap on the spec's log(random-walk / white variance) for blocks of ``dt`` s."""
        lo, hi = LOG_BOUNDS["rw"]
        if self.k_max <= 0.0:
            return lo
        return min(max(math.log(self.k_max ** 2 * dt / 3600.0 / sigma2), lo), hi)

    def capped(self, spec: NoiseSpec, sigma2: float) -> NoiseSpec:
        """``spec`` with the caps for block means of white variance ``sigma2``."""
        spec = spec._replace(log_rw_max=self.log_rw_cap(spec.dt, sigma2))
        sigma_max, tau_max = self.markov_caps(spec.dt)
        if sigma_max is None:
            return spec
        lo, hi = LOG_BOUNDS["mvar"]
        cap = math.log(sigma_max ** 2 / sigma2) if sigma_max > 0.0 else lo
        return spec._replace(log_mvar_max=min(max(cap, lo), hi),
                             tau_max=min(spec.tau_max, tau_max))

    def to_json(self, dt: float) -> dict:
        sigma_max, tau_max = self.markov_caps(dt)
        return {"K_max_deg_h15": self.k_max, "markov_sigma_max_deg_h": sigma_max,
                "markov_tau_max_s": tau_max, "source": self.source,
                "rule": "every fit of the loop has random walk K <= K_max and a Gauss-Markov "
                        "component with sigma <= markov_sigma_max and tau_c <= markov_tau_max "
                        "(null: not capped)"}


def read_noise_prior(path: str | Path) -> NoisePrior:
    """K_max from a ``fogbayes allan --json`` document, a datasheet prior document
    (``fogbayes prior``) or ``{"K": value}`` (see module doc)."""
    from ..data.json_file import read_json_file

    return prior_from_doc(read_json_file(path, "the noise prior", HOW), source=str(path))


def _number(value, key: str, source: str, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x) or x < 0.0:
        raise FogbayesError(f"{key} = {value!r} is not a finite non-negative {what}",
                            file=source, field=key, fix=HOW)
    return x


def prior_from_doc(doc, *, source: str = "given") -> NoisePrior:
    """The prior in a parsed document: an Allan document (K's interval caps the walk, its
    ADEV's upper band the Markov component), a datasheet prior (K x looseness caps the walk)
    or a bare ``{"K": value}`` (the walk only)."""
    from ..data.doc_kinds import refuse_other_kind
    from ..inference.datasheet import is_prior_document

    refuse_other_kind(doc, source, ("noise prior", {"allan", "prior"}, HOW), error=FogbayesError)
    if is_prior_document(doc):
        return _from_datasheet(doc, source)
    if isinstance(doc, dict) and "K" in doc and not isinstance(doc["K"], dict):
        return NoisePrior(_number(doc["K"], "K", source, "K in deg/h^1.5"), source=source)
    try:
        k_value = doc["fit"]["terms"]["K"]["high"]
    except (KeyError, TypeError):
        raise FogbayesError("the noise prior has no random-walk bound "
                            "(neither fit.terms.K.high nor K)", file=source,
                            field="K", fix=HOW) from None
    k = _number(k_value, "fit.terms.K.high", source, "K in deg/h^1.5")
    tau, high = doc.get("tau"), doc.get("adev_high")
    if not tau or not high or len(tau) != len(high):
        raise FogbayesError("the Allan document has no tau / adev_high band of the same "
                            "length", file=source, field="adev_high", fix=HOW)
    return NoisePrior(k, tuple(_number(t, "tau", source, "tau in s") for t in tau),
                      tuple(_number(h, "adev_high", source, "ADEV in deg/h") for h in high),
                      source)


def _from_datasheet(doc: dict, source: str) -> NoisePrior:
    """K_max = value x looseness of the sheet's K (the top of its 90 % prior range)."""
    from ..inference.datasheet import validate_prior

    sheet = validate_prior(doc, source)
    k = sheet.terms.get("K")
    if k is None:
        given = ", ".join(sheet.terms)
        raise FogbayesError(
            f"the datasheet prior gives no rate random walk (terms: {given}), so it sets no "
            "cap on the walk", file=source, field="terms.K",
            fix="add the sheet's RRW ('fogbayes prior ... --rrw VALUE --rrw-unit UNIT'), "
                "or pass a static run's 'fogbayes allan --json' document, or leave "
                "--noise-prior out")
    who = f" {sheet.sensor}" if sheet.sensor else ""
    return NoisePrior(k.value * k.looseness,
                      source=f"{source} (datasheet{who}: K {k.value:.4g} deg/h^1.5 x "
                             f"looseness {k.looseness:g})")
