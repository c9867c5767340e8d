"""The plain reference for ``bench_interactive.py``: what a user writes without fogbayes.

Reads a recording CSV (``#`` header lines, columns ``time, output, temperature``), fits the
bias as a cubic in temperature by ordinary least squares, ``output ~ sum_k a_k T^k`` for
k = 0..3, and writes the compensated output ``output - fitted bias`` as a CSV.

Run: ``python benchmarks/plain_cubic.py REC.csv OUT.csv``.
"""

import sys

import numpy as np
import pandas as pd


def main(src: str, dst: str) -> None:
    df = pd.read_csv(src, comment="#")
    t = df["temperature"].to_numpy(float)
    y = df["output"].to_numpy(float)
    X = np.vander(t - t.mean(), 4, increasing=True)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    df["compensated"] = y - X @ coef
    df.to_csv(dst, index=False)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
