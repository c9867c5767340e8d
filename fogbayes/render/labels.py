"""Human labels for the raw keys of fit documents, and the units of coefficients.

A report shows ``label(key)`` in the table and keeps the raw key as the cell's tooltip
(:class:`fogbayes.render.html.Cell`), so a reader who wants the JSON field still finds it.
Keys that are sentences rather than numbers (``stderr_note``) are notes, not table rows.
"""

from __future__ import annotations

from typing import Any

from .html import Cell, fmt

# key -> (label, unit or "")
LABELS: dict[str, tuple[str, str]] = {
    # fit document, "fit" block of the thermal / bias-t workflows
    "n_blocks": ("averaged blocks fitted", ""),
    "n_params": ("coefficients", ""),
    "rms_criterion": ("RMS of the fit residual (block means)", "deg/h"),
    # s = sqrt(wRSS / dof) of the block means weighted by their sample counts: the scatter
    # of one sample (a block mean of n samples scatters by s / sqrt(n))
    "residual_std": ("residual standard deviation per sample (count-weighted block fit)",
                     "deg/h"),
    "dof": ("degrees of freedom", ""),
    "method": ("method", ""),
    # sampler convergence (bayes.convergence)
    "r_hat_max": ("largest R-hat (want < 1.01)", ""),
    "rhat_max": ("largest R-hat (want < 1.01)", ""),
    "ess_bulk_min": ("smallest bulk effective sample size", ""),
    "ess_tail_min": ("smallest tail effective sample size", ""),
    "ess_min": ("smallest effective sample size", ""),
    "divergences": ("divergent transitions", ""),
    "num_divergences": ("divergent transitions", ""),
    "converged": ("converged", ""),
    "chains": ("chains", ""),
    "num_chains": ("chains", ""),
    "draws": ("draws per chain", ""),
    "num_samples": ("draws per chain", ""),
    "warmup": ("warm-up draws per chain", ""),
    "num_warmup": ("warm-up draws per chain", ""),
    # loop metrics
    "rms": ("RMS of the 10 s residual means", "deg/h"),
    "bias_stability": ("bias stability (1 s means)", "deg/h"),
    "elpd": ("ELPD (PSIS-LOO, block means)", "nats"),
}

# keys that hold prose: shown as notes
NOTE_KEYS = ("stderr_note", "note", "reason")

# segment kinds of paper 004's thermal profile
SEGMENTS = {"ramp_up": "heating ramp", "ramp_down": "cooling ramp", "soak": "soak",
            "full": "whole record"}

# Allan noise terms
NOISE_TERMS = {"Q": "quantization noise Q", "N": "angle random walk N",
               "B": "bias instability B", "K": "rate random walk K", "R": "rate ramp R"}

_UNIT_TEXT = {"degC": "°C", "degC/min": "°C/min", "deg/h": "deg/h", "deg/s": "°/s"}


def label(key: str) -> str:
    """``'rms_criterion'`` -> ``'RMS of the fit residual (block means) [deg/h]'``."""
    name, unit = LABELS.get(key, (key.replace("_", " "), ""))
    return f"{name} [{unit}]" if unit else name


def key_cell(key: str) -> Cell:
    """The label of ``key`` as a table cell whose tooltip is the raw key."""
    return Cell(label(key), title=f"JSON key: {key}")


def quantity_rows(d: dict) -> tuple[list[list[Any]], list[str]]:
    """Rows ``[label cell, value]`` of the scalar entries of ``d`` and its prose notes."""
    rows, notes = [], []
    for k, v in d.items():
        if k in NOTE_KEYS and isinstance(v, str):
            notes.append(v)
        elif isinstance(v, (bool, int, float)) or (isinstance(v, str) and len(v) < 40):
            rows.append([key_cell(k), v])
    return rows, notes


def unit_text(u: str) -> str:
    return _UNIT_TEXT.get(u, u)


def coefficient_unit(exponents, covariates, units: dict | None) -> str:
    """Unit of a polynomial coefficient: output unit / prod(covariate unit ^ exponent).

    ``coefficient_unit([2, 0], ['T', 'dT/dt'], {'output': 'deg/h', 'T': 'degC'})`` is
    ``deg/h/°C²``; the constant's unit is the output's.
    """
    if not units:
        return ""
    out = unit_text(units.get("output", "deg/h"))
    parts = []
    for e, c in zip(exponents, covariates):
        if not e:
            continue
        u = unit_text(units.get(c, ""))
        if not u:
            return ""
        u = f"({u})" if "/" in u else u
        parts.append(u + ("" if e == 1 else "".join("⁰¹²³⁴⁵⁶⁷⁸⁹"[int(ch)] for ch in str(e))))
    return out if not parts else f"{out} per {'·'.join(parts)}"


def term_label(term: str) -> str:
    """``'1'`` -> ``'constant (bias at 0 °C, 0 °C/min)'``; other terms as written."""
    return "constant" if term == "1" else term


def interval_text(low: Any, high: Any, *, sig: int = 4) -> str:
    return f"[{fmt(low, sig=sig)}, {fmt(high, sig=sig)}]"
