"""The iterated 3-sigma (Pauta) rule over a stream, one pass per iteration.

As :func:`fogbayes.preprocess.pauta_flags`: flag keep & |x - m| > n_sigma s until nothing new.
The final set is the union of {|x - m_j| > thr_j} over the iterations, so no mask is stored;
each pass accumulates the kept samples' mean and variance (Chan et al.'s pairwise update).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import NamedTuple

import numpy as np


class PautaStream(NamedTuple):
    """Thresholds of the iterations that flagged samples, and the rule's summary."""

    history: tuple   # ((mean, threshold), ...) applied, in order
    threshold: float  # the last threshold computed (as pauta_flags)
    iterations: int
    passes: int

    def flags(self, x: np.ndarray) -> np.ndarray:
        out = np.zeros(x.shape, bool)
        for m, thr in self.history:
            out |= np.abs(x - m) > thr
        return out


class _Moments:
    """Count, mean and sum of squared deviations, merged chunk by chunk."""

    def __init__(self):
        self.n, self.mean, self.m2 = 0, 0.0, 0.0

    def add(self, v: np.ndarray) -> None:
        if v.size == 0:
            return
        nb, mb = v.size, float(v.mean())
        m2b = float(np.sum((v - mb) ** 2))
        n = self.n + nb
        delta = mb - self.mean
        self.mean += delta * nb / n
        self.m2 += m2b + delta * delta * self.n * nb / n
        self.n = n


def stream_pauta(passes: Callable[[], Iterable[np.ndarray]], *, n_sigma: float = 3.0,
                 max_iter: int = 100) -> PautaStream:
    """Run the rule over the chunks that ``passes()`` yields afresh for every pass."""
    history: list[tuple[float, float]] = []
    pending: tuple[float, float] | None = None
    threshold, it, n_pass = np.inf, 0, 0
    probe = PautaStream((), np.inf, 0, 0)
    while True:
        mom, new = _Moments(), 0
        n_pass += 1
        probe = probe._replace(history=tuple(history))
        for x in passes():
            f = probe.flags(x)
            if pending is not None:
                add = ~f & (np.abs(x - pending[0]) > pending[1])
                new += int(add.sum())
                f |= add
            mom.add(x[~f])
        if pending is not None:
            if new == 0:  # iteration `it` flagged nothing: the rule stops there
                return PautaStream(tuple(history), threshold, it, n_pass)
            history.append(pending)
            pending = None
            if it == max_iter:
                return PautaStream(tuple(history), threshold, it, n_pass)
        it += 1
        if mom.n < 3:
            return PautaStream(tuple(history), threshold, it, n_pass)
        threshold = n_sigma * float(np.sqrt(mom.m2 / (mom.n - 1)))
        pending = (mom.mean, threshold)
