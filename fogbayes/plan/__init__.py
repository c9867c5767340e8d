"""Recording-length planning: how long a static run must be to know N, B or K to +-x %.

:mod:`fogbayes.plan.length` predicts the standard error of each noise term of the octave
GLS Allan fit for a record of any length (Fisher information of the octave AVAR estimates)
and finds the shortest record that meets a target, from given noise values (e.g. a
datasheet); :mod:`fogbayes.plan.pilot` takes the values and their uncertainty from a short
pilot recording and :mod:`fogbayes.plan.spread` the range of lengths their uncertainty
allows.
"""

from .length import (MAX_DAYS, LengthPlan, PlanError, expected_data, half_width, log_cov, log_se,
                     plan_length, predicted_se, predicted_width, se_for_width)
from .pilot import PilotPlan, plan_document, plan_from_pilot, plan_recording
from .spread import PlanRange, plan_range

__all__ = ["MAX_DAYS", "LengthPlan", "PilotPlan", "PlanError", "PlanRange", "expected_data",
           "half_width", "log_cov", "log_se", "plan_document", "plan_from_pilot", "plan_length",
           "plan_range", "plan_recording", "predicted_se", "predicted_width", "se_for_width"]
