"""The record every Allan-family and total deviation returns.

:func:`fogbayes.stats.allan.allan_deviation` and :func:`fogbayes.stats.total.total_deviation`
(to which the first dispatches the total kinds) both return it; it lives in its own module so
that neither imports the other back (:mod:`fogbayes.stats.allan` offers the name as before).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class AllanDeviation(NamedTuple):
    """Deviations at each tau (arrays of length ``len(tau)``, or (batch, len(tau)))."""

    kind: str            # oadev, adev, mdev, ohdev, hdev, tdev
    fs: float            # Hz
    tau: np.ndarray      # s
    m: np.ndarray        # cluster sizes (samples)
    var: np.ndarray      # variance, input unit squared
    dev: np.ndarray      # deviation, input unit
    n_terms: np.ndarray  # terms averaged (after excluding gap-affected ones)
    excluded: np.ndarray  # terms dropped because they touch a NaN gap
    alpha: np.ndarray    # identified power-law exponent of the rate PSD
    edf: np.ndarray      # equivalent degrees of freedom (Greenhall, for alpha)
    dev_low: np.ndarray  # chi-square interval of the deviation at confidence ``ci``
    dev_high: np.ndarray
    ci: float
    n: int               # samples (NaN included)
    n_missing: int       # NaN samples
    note: str            # how gaps were handled
