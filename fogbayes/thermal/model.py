"""Thermal bias models: ``bias-t`` (polynomial in T) and ``thermal`` (paper 004, Shupe effect).

B = sum_{i<=n_T} a_i T^i + sum_{1<=j<=n_R} b_j (dT/dt)^j [+ c_ij T^i (dT/dt)^j] [+ sum d_kl E_k^l]
(eq. 14; E_k extra channels or channel differences); ``bias-t`` has n_R = 0. Scaled basis of
:mod:`fogbayes.models.polynomial`, covariates (T, dT/dt, E_1, ...) in deg C and deg C/min.
:func:`thermal_covariates` rate: ``"paper"`` (held 10 s differences), ``"difference"``
(centred), ``"savgol"``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, MissingColumnError
from ..models.polynomial import PolyBasis, make_basis

T_NAME = "T"
RATE_NAME = "dT/dt"
GRADIENT_NAME = "dT_gradient"


class ThermalSpec(NamedTuple):
    """Structure of a thermal bias model (static; hashable).

    Attributes:
        t_order: order n_T of the polynomial in T (>= 0).
        rate_order: order n_R in dT/dt (0 = ``bias-t``).
        cross: add T^i (dT/dt)^j cross terms with i + j <= max(n_T, n_R).
        extra: names of extra temperature channels used as covariates.
        gradient: ``(outer, inner)`` channel names whose difference is a covariate, or ().
        extra_order: polynomial order of each extra covariate.
        temperature: name of the main temperature channel ("" = the first channel).
    """

    t_order: int = 2
    rate_order: int = 2
    cross: bool = False
    extra: tuple[str, ...] = ()
    gradient: tuple[str, ...] = ()
    extra_order: int = 1
    temperature: str = ""

    @property
    def model(self) -> str:
        plain = self.rate_order == 0 and not self.extra and not self.gradient
        return "bias-t" if plain else "thermal"


class OrderError(FogbayesError):
    """A polynomial order is out of range or malformed."""


def bias_t_spec(order: int = 3, *, temperature: str = "") -> ThermalSpec:
    """``bias-t``: a polynomial of ``order`` in one temperature channel."""
    return check_spec(ThermalSpec(t_order=order, rate_order=0, temperature=temperature))


def check_spec(spec: ThermalSpec) -> ThermalSpec:
    for name in ("t_order", "rate_order", "extra_order"):
        v = getattr(spec, name)
        if isinstance(v, bool) or int(v) != v or not 0 <= int(v) <= 8:
            raise OrderError(f"{name} must be an integer 0 ... 8, got {v!r}", column=name,
                             fix="use e.g. --orders 2,2 (T order, dT/dt order)")
    if spec.gradient and len(spec.gradient) != 2:
        raise OrderError(f"gradient needs two channel names (outer, inner), got {spec.gradient!r}",
                         fix="pass gradient=('temperature_2', 'temperature')")
    return spec


def covariate_names(spec: ThermalSpec) -> tuple[str, ...]:
    names = [T_NAME] + ([RATE_NAME] if spec.rate_order > 0 else [])
    names += list(spec.extra) + ([GRADIENT_NAME] if spec.gradient else [])
    return tuple(names)


def thermal_terms(spec: ThermalSpec) -> tuple[tuple[int, ...], ...]:
    """Exponent tuples of the model's monomials, lowest order first (downward closed)."""
    nc = len(covariate_names(spec))

    def mono(**pos) -> tuple[int, ...]:
        e = [0] * nc
        for c, k in pos.items():
            e[int(c[1:])] = k
        return tuple(e)

    terms = [mono(c0=i) for i in range(spec.t_order + 1)]
    if spec.rate_order:
        terms += [mono(c1=j) for j in range(1, spec.rate_order + 1)]
        if spec.cross:
            top = max(spec.t_order, spec.rate_order)
            terms += [mono(c0=i, c1=j) for i in range(1, spec.t_order + 1)
                      for j in range(1, spec.rate_order + 1) if i + j <= top]
    first_extra = 1 + (spec.rate_order > 0)
    for k in range(first_extra, nc):
        terms += [mono(**{f"c{k}": l}) for l in range(1, spec.extra_order + 1)]
    return tuple(terms)


def thermal_basis(spec: ThermalSpec, z: np.ndarray) -> PolyBasis:
    """The scaled basis of ``spec``, scaled to the covariates ``z`` (n, c) of the fit data."""
    return make_basis(covariate_names(spec), thermal_terms(check_spec(spec)), z)


def thermal_covariates(time: np.ndarray, temperatures: np.ndarray,
                       temperature_names: Sequence[str], spec: ThermalSpec, *,
                       rate_method: str = "savgol", rate_window_s: float = 10.0,
                       rate_gap_factor: float | None = None,
                       source: str | None = None, rate: np.ndarray | None = None) -> np.ndarray:
    """Covariates ``z`` (n, c) in the order of :func:`covariate_names`, one row per sample.

    ``rate_gap_factor``: a time step longer than this many median steps is a gap that the
    temperature-rate estimator does not bridge (default: the preprocessing default). Pass a
    large value for burst records (e.g. 5 s every 5 min), whose rate must come from
    differences across bursts. ``rate``: dT/dt (deg C/min) per sample when already computed
    (a fleet computes all its sensors' rates in one call), else it is computed here.
    """
    temps = np.asarray(temperatures, dtype=float).reshape(len(time), -1)
    names = list(temperature_names)

    def channel(name: str) -> np.ndarray:
        if not names:
            raise MissingColumnError("the recording has no temperature channel", file=source,
                                     column="temperature",
                                     fix="add a 'temperature' column in deg C")
        if name == "":
            return temps[:, 0]
        if name not in names:
            raise MissingColumnError(f"no temperature channel '{name}' (have {names})",
                                     file=source, column=name,
                                     fix="name an existing channel or add the column")
        return temps[:, names.index(name)]

    T = channel(spec.temperature)
    cols = [T]
    if spec.rate_order > 0:
        cols.append(temperature_rate_of(time, T, method=rate_method, window_s=rate_window_s,
                                        gap_factor=rate_gap_factor) if rate is None
                    else np.asarray(rate, dtype=float))
    cols += [channel(nm) for nm in spec.extra]
    if spec.gradient:
        cols.append(channel(spec.gradient[0]) - channel(spec.gradient[1]))
    return np.column_stack(cols)


def temperature_rate_of(time, temperature, *, method: str, window_s: float,
                        gap_factor: float | None = None) -> np.ndarray:
    """dT/dt (deg C/min) per sample by :mod:`fogbayes.preprocess.temperature_rate`.

    ``method``: "savgol", "difference" (block means differenced, interpolated to each
    sample: no lag) or "paper" (the same differences held over each block: causal, as a
    DSP computes them in real time, lagging about one window).
    """
    from ..preprocess.temperature_rate import temperature_rate_per_min

    options = {"method": "difference", "align": "hold"} if method == "paper" else {"method": method}
    if gap_factor is not None:
        options["gap_factor"] = float(gap_factor)
    return temperature_rate_per_min(np.asarray(time, float), np.asarray(temperature, float),
                                    window_s=window_s, **options)
