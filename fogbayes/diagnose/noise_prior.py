"""A cap on the random walk from a static run: what one record cannot tell by itself.

One record cannot tell a slow deterministic excursion (a warm-up, a thermal transient)
from a rate random walk: both have a 1/f^2 spectrum and similar Allan deviations, and only
the exact shape tells them apart. With the walk free, the base fit's walk takes up part of
a 0.5 deg/h warm-up (on the loop sweep's records a cap at K = 0.12 deg/h^1.5 did not bind
and 0.06 barely did, against a true 0.02), the warm-up's evidence is then calibrated under
that walk, and it is missed (0.5x warm-ups: 2 of 3, final RMS 3.05-3.77x the oracle's;
benchmarks/RESULTS_loop.md). A static run of the
same sensor says how large its walk can be; docs/DESIGN.md ("constrain the noise by what the
record itself says about it ... priors"). The loop then bounds the walk by it:

    K <= K_max,   i.e. for block means of length dt (s), relative to the white variance s2:
    log_rw <= log(K_max^2 dt / 3600 / s2)

(a rate walk of intensity K deg/h^1.5 adds K^2 dt / 3600 (deg/h)^2 per block; s2 is the
base fit's white block-mean variance, so the cap is on the absolute walk whatever share of
the short-term noise the flicker bank takes). K_max is the upper end of the static run's
interval for K -- for ``fogbayes allan --json`` documents ``fit.terms.K.high`` (90 %), an
upper bound also where K is not supported -- or a datasheet value (``{"K": 0.02}``). A
datasheet prior document (``fogbayes prior``, schema ``fogbayes.prior/1``,
:mod:`fogbayes.inference.datasheet`) gives K_max = value x looseness, the upper end of its
90 % prior range for K (rate random walk); a sheet without RRW caps nothing and is refused,
since a ``--noise-prior`` that silently bounds nothing would read as a bounded walk.

A walk cap alone is escaped: a free Gauss-Markov component with a time constant near the
record's length is a walk over the record, and ``markov_noise`` took a 0.5 deg/h warm-up
once the walk was capped (benchmarks/RESULTS_loop.md). An Allan document therefore also caps
that component by what the static run shows: a Gauss-Markov process of stationary std
sigma and time constant tau_c has its largest ADEV, 0.618 sigma, at tau = 1.89 tau_c, so

    sigma <= max ADEV_high(tau) / 0.618 over tau >= 0.95 dt,
    tau_c <= longest tau of the static run / 1.89

(log_mvar <= log(sigma_max^2 / s2) on the state's variance, which block averaging only
lowers, so the cap errs loose; the loop's Markov time constants start at dt / 2, so
their peaks lie at tau >= 0.95 dt, and the short-tau ADEV of white noise does not loosen the
cap): a larger or slower component would have shown in the static run's ADEV. A bare
``{"K": ...}`` and a datasheet prior (no ADEV curve) leave the Markov component free.

The cap is a model assumption, not evidence: if the record's own walk is larger than the
static run's (another sensor, another environment), the walk sits at the cap and the scans
say so (``noise_model_at_bound``), and effects found under it need that caveat.
"""

from __future__ import annotations

import json
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
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise FogbayesError("the noise prior does not exist", file=str(path),
                            fix=HOW) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FogbayesError(f"the noise prior is not a JSON document ({e})", file=str(path),
                            fix=HOW) from None
    except (RecursionError, ValueError) as e:  # nesting beyond the parser's stack; huge ints
        raise FogbayesError(f"the noise prior cannot be parsed ({type(e).__name__}: nested too "
                            "deep or numbers too long)", file=str(path), fix=HOW) from None
    return prior_from_doc(doc, source=str(path))


def _number(value, key: str, source: str, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x) or x < 0.0:
        raise FogbayesError(f"{key} = {value!r} is not a finite non-negative {what}",
                            file=source, column=key, fix=HOW)
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
                            column="K", fix=HOW) from None
    k = _number(k_value, "fit.terms.K.high", source, "K in deg/h^1.5")
    tau, high = doc.get("tau"), doc.get("adev_high")
    if not tau or not high or len(tau) != len(high):
        raise FogbayesError("the Allan document has no tau / adev_high band of the same "
                            "length", file=source, column="adev_high", fix=HOW)
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
            "cap on the walk", file=source, column="terms.K",
            fix="add the sheet's RRW ('fogbayes prior ... --rrw VALUE --rrw-unit UNIT'), "
                "or pass a static run's 'fogbayes allan --json' document, or leave "
                "--noise-prior out")
    who = f" {sheet.sensor}" if sheet.sensor else ""
    return NoisePrior(k.value * k.looseness,
                      source=f"{source} (datasheet{who}: K {k.value:.4g} deg/h^1.5 x "
                             f"looseness {k.looseness:g})")
