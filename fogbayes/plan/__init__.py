"""Recording-length planning: how long a static run must be to know N, B or K to +-x %.

:mod:`fogbayes.plan.length` (standard errors and shortest length from given noise values),
:mod:`fogbayes.plan.pilot` (values from a short pilot), :mod:`fogbayes.plan.spread` (the range
their uncertainty allows).
"""

from .length import (MAX_DAYS, LengthPlan, PlanError, expected_data, half_width, log_cov, log_se,
                     plan_length, predicted_se, predicted_width, se_for_width)
from .pilot import PilotPlan, plan_document, plan_from_pilot, plan_recording
from .spread import PlanRange, plan_range

__all__ = ["MAX_DAYS", "LengthPlan", "PilotPlan", "PlanError", "PlanRange", "expected_data",
           "half_width", "log_cov", "log_se", "plan_document", "plan_from_pilot", "plan_length",
           "plan_range", "plan_recording", "predicted_se", "predicted_width", "se_for_width"]
