"""Synthetic FOG recordings with known truth (profiles, deterministic effects, noise).

    >>> from fogbayes.simulate import simulate, SCENARIOS
    >>> rec, truth = simulate("thermal", seed=0, duration=3600.0)

See :func:`simulate` for the options, :data:`SCENARIOS` for the named scenarios,
:data:`EFFECTS` for the effect names, :mod:`.noise` for the generators.
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
