"""Synthetic FOG recordings with known truth (profiles, deterministic effects, noise).

:func:`simulate` (``rec, truth = simulate("thermal", seed=0, duration=3600.0)``),
:data:`SCENARIOS`, :data:`EFFECTS`, :mod:`.noise`.
"""

from .noise import (allan_noise, allan_variance_model, arma_noise, flicker_avar,
                    markov_noise, sinusoid)
from .profiles import (PAPER000_RATES, PAPER000_TEMPERATURES, Ramp, RateTableSchedule, Soak,
                       ThermalProfile, first_order_lag, paper004_profile, rate_table_schedule,
                       thermal_profile, thermal_test_profile)
from .registry import EFFECTS
from .scenarios import SCENARIOS, simulate
from .truth import Covariates, Simulated, Truth
from ._checks import SimulationParameterError

__all__ = [
    "EFFECTS", "PAPER000_RATES", "PAPER000_TEMPERATURES", "SCENARIOS", "Covariates", "Ramp",
    "RateTableSchedule", "Simulated", "SimulationParameterError", "Soak", "ThermalProfile",
    "Truth", "allan_noise", "allan_variance_model", "arma_noise", "first_order_lag",
    "flicker_avar", "markov_noise", "paper004_profile", "rate_table_schedule", "simulate",
    "sinusoid", "thermal_profile", "thermal_test_profile",
]
