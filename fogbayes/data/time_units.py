"""The unit of a recording's time column: from its name, or a hint from its spacing.

:func:`unit_in_name` reads ``time_ms``, ``time [ms]``, ``t_µs``, ...; :func:`spacing_hint`
suggests a ``--time-unit`` when a seconds column steps by :data:`HINT_STEP_S` or more (a hint only).
"""

from __future__ import annotations

import re

import numpy as np

#: Units a column name may state, and the ``time_unit`` each means.
_NAMED = {"s": "s", "sec": "s", "ms": "ms", "msec": "ms", "us": "us", "µs": "us",
          "μs": "us", "usec": "us", "ns": "ns", "nsec": "ns"}
#: A time column's name: ``time``/``t``/``timestamp``/``stamp``, then the unit after ``_``,
#: a space, or in brackets or parentheses.
_NAME = re.compile(r"\s*(?:time(?:stamp)?|t|stamp)\s*(?:[_ ]\s*|\[\s*|\(\s*)"
                   r"(?P<unit>[a-zµμ]+)\s*[\])]?\s*", re.IGNORECASE)
#: Median steps (s) from which the spacing suggests another unit.
HINT_STEP_S = 10.0
#: Sample rates (Hz) a hint may offer.
_OFFER_HZ = (1e-2, 1e6)


def unit_in_name(name: str) -> str | None:
    """The ``time_unit`` (``s``, ``ms``, ``us``, ``ns``) a column name states, else None."""
    m = _NAME.fullmatch(str(name))
    return _NAMED.get(m.group("unit").lower()) if m else None


def named_time_columns(columns) -> list[str]:
    """The columns whose names state a time unit (candidates when ``time`` is absent)."""
    return [c for c in columns if unit_in_name(c) is not None]


def _rate(hz: float) -> str:
    return f"{hz / 1e3:.3g} kHz" if hz >= 1e3 else f"{hz:.3g} Hz"


def spacing_hint(t_seconds: np.ndarray) -> str | None:
    """A hint to ``--time-unit`` when times read in seconds step by :data:`HINT_STEP_S`
    or more (median), naming the sample rate each other unit would give; None otherwise."""
    t = np.asarray(t_seconds, dtype=float)
    if t.size < 2:
        return None
    step = float(np.median(np.diff(t)))
    if not np.isfinite(step) or step < HINT_STEP_S:
        return None
    lo, hi = _OFFER_HZ
    offers = [f"--time-unit {u} gives {_rate(k / step)}"
              for u, k in (("ms", 1e3), ("us", 1e6)) if lo <= k / step <= hi]
    if not offers:
        return None
    return (f"the time column steps by {step:.4g} s ({_rate(1 / step)}, "
            f"{(t[-1] - t[0]) / 3600:.3g} h in all) read in seconds; if it counts ms or us, "
            + ", ".join(offers))
