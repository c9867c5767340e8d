"""How well can K be known at all? The Cramer-Rao bound of the coverage study's records.

Issue #3 asks that the fitted K have at most half the RMS error of the IEEE-952 slope
readout. This script asks whether *any* unbiased estimator can, on the records of
``coverage_allan.py`` (mixes A and B, two lengths each), by computing the Cramer-Rao bound of
log Q, log N, log B, log K from the Whittle (spectral) Fisher information of the
once-differenced rate, whose spectrum is smooth and bounded away from zero (the rate random
walk becomes white):

    z_k = y_k - y_{k-1},   P_z(f) = D(f) [P_Q(f) + P_N + P_B(f)] + P_dK(f),
    D(f) = 4 sin^2(pi f / fs)

with the simulator's exact components (one-sided PSD per Hz, :mod:`fogbayes.simulate.noise`):

    white     P_N = 2 (60 N)^2
    quant.    P_Q = 8 Q^2 fs sin^2(pi f / fs)          (x = (e_{k+1} - e_k) fs)
    flicker   P_B = B^2 / (pi f)
    walk, differenced: the sample means of a Brownian motion have increments with variance
              2/3 K_s^2 h and lag-1 covariance 1/6 K_s^2 h (h = 1/fs, K_s = K / 60), so
              P_dK = 2 K_s^2 h^2 (2/3 + cos(2 pi f / fs) / 3)

Each Fourier ordinate I_j of a Gaussian stationary series is ~ P(f_j) x Exp(1), so

    I(theta) = sum_{j=1}^{n/2-1} g_j g_j^T,   g_j = d log P_z(f_j) / d theta,

and sd(log K_hat) >= sqrt(I^{-1}_{KK}): the best relative RMS error of any unbiased K.
Checks: the Whittle bound against the exact Gaussian Fisher information
tr(S^-1 dS_p S^-1 dS_q) / 2 of a few thousand samples (dense Toeplitz algebra), and the
slope readout's RMS over simulated records of each cell (on the records where it exists).
A plain Whittle *estimate* on the differenced rate is not used as a check: its lowest
ordinates are dominated by the white noise's end-point leakage ((e_n - e_0)^2, correlated
across all of them), which the independent-ordinates likelihood overweights.

    python benchmarks/k_crb.py [--seeds 100] [--first-seed 0]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from scipy import linalg

import fogbayes  # noqa: F401  (float64)
from coverage_allan import LENGTHS, MIXES, PARAMS, simulate
from fogbayes.allan.readout import slope_readouts
from fogbayes.stats.allan import allan_deviation


def components(f: np.ndarray, fs: float) -> np.ndarray:
    """(4, F) PSDs of the differenced rate per unit Q^2, N^2, B^2, K^2 at frequencies f."""
    d = 4.0 * np.sin(np.pi * f / fs) ** 2
    h = 1.0 / fs
    return np.stack([
        d * 8.0 * fs * np.sin(np.pi * f / fs) ** 2,                       # Q^2
        d * 2.0 * 60.0 ** 2 * np.ones_like(f),                            # N^2
        d / (np.pi * f),                                                  # B^2
        2.0 * h * h / 60.0 ** 2 * (2.0 / 3.0 + np.cos(2 * np.pi * f / fs) / 3.0),  # K^2
    ])


def fisher(n: int, fs: float, truth: dict) -> np.ndarray:
    """Whittle Fisher information of (log Q, log N, log B, log K) for n differenced samples."""
    f = np.arange(1, n // 2) * fs / n
    comp = components(f, fs)
    sq = np.array([truth[p] ** 2 for p in PARAMS])
    parts = comp * sq[:, None]
    g = 2.0 * parts / parts.sum(axis=0)  # d log P / d log theta_p = 2 P_p / P
    return g @ g.T


def crb(n: int, fs: float, truth: dict) -> dict:
    info = fisher(n, fs, truth)
    cov = np.linalg.inv(info)
    return {p: {"all_unknown": float(np.sqrt(cov[i, i])),
                "others_known": float(1.0 / np.sqrt(info[i, i]))} for i, p in enumerate(PARAMS)}


def autocovariances(n: int, fs: float, flicker_length: int) -> np.ndarray:
    """(4, n) autocovariances of the differenced rate per unit Q^2, N^2, B^2, K^2 at lags 0..n-1.

    Exact for the simulator: white and quantization are (second) differences of white noise,
    the walk's differenced sample means have the triangle kernel's (2/3, 1/6) h, and the
    flicker is the sum of cosines of :func:`fogbayes.simulate.noise.flicker_noise` on the
    ``flicker_length``-sample comb (``coverage_allan`` simulates 4 n and keeps n).
    """
    c = np.zeros((4, n))
    c[0, :3] = np.array([6.0, -4.0, 1.0]) * fs * fs     # x = diff(e) fs, z = diff(x)
    c[1, :2] = np.array([2.0, -1.0]) * 60.0 ** 2 * fs   # white rate variance (60 N)^2 fs
    c[3, :2] = np.array([2.0 / 3.0, 1.0 / 6.0]) / 60.0 ** 2 / fs
    L = flicker_length
    k = np.arange(1, L // 2 + 1)
    v = fs / L / (np.pi * k * fs / L)                   # bin variances, unit B
    if L % 2 == 0:
        v[-1] /= 2.0
    lags = np.arange(n + 1)
    cy = np.cos(2 * np.pi * np.outer(lags, k) / L) @ v if n < 4096 else \
        np.fft.irfft(np.concatenate(([0.0], v)) * L / 2.0, L)[:n + 1] * 2.0 / 2.0
    cz = 2.0 * cy[:n] - np.concatenate(([cy[1]], cy[:n - 1])) - cy[1:n + 1]
    c[2] = cz
    return c


def exact_crb(n: int, fs: float, truth: dict) -> np.ndarray:
    """sd of (log Q, log N, log B, log K) from the exact Gaussian Fisher information of n
    differenced samples, I_pq = tr(S^-1 dS_p S^-1 dS_q) / 2 (dense: n of a few thousand)."""
    c = autocovariances(n, fs, 4 * (n + 1))
    sq = np.array([truth[p] ** 2 for p in PARAMS])
    d = [2.0 * sq[i] * linalg.toeplitz(c[i]) for i in range(4)]  # dS / d log theta_p
    cf = linalg.cho_factor(sum(d) / 2.0)
    a = [linalg.cho_solve(cf, di) for di in d]
    info = 0.5 * np.array([[np.sum(a[i] * a[j].T) for j in range(4)] for i in range(4)])
    return np.sqrt(np.diag(np.linalg.inv(info)))


def check(fs: float = 10.0) -> list[str]:
    """The Whittle bound against the exact one on records short enough for dense algebra
    (K raised so that the walk shows within a few thousand samples)."""
    lines = []
    for n, t in [(2048, dict(Q=0.19, N=0.01, B=0.165, K=19.8)),
                 (4096, dict(Q=0.19, N=0.01, B=0.165, K=9.9)),
                 (4096, dict(Q=0.19, N=0.01, B=0.66, K=9.9))]:
        w = np.sqrt(np.diag(np.linalg.inv(fisher(n + 1, fs, t))))
        e = exact_crb(n, fs, t)
        lines.append(f"| {n} | {t} | " + " | ".join(f"{a:.4f} / {b:.4f}" for a, b in zip(w, e))
                     + " |")
    return lines


def cell(mix: str, n: int, seeds: range) -> dict:
    fs, truth = MIXES[mix]
    out = {"mix": mix, "n": n, "crb": crb(n, fs, truth), "readout": []}
    for seed in seeds:
        y, _, _ = simulate(mix, n, seed)
        dev = allan_deviation(y, fs, taus="octave", ci=0.9)
        ro = slope_readouts(dev.tau, dev.dev, dev.dev_low, dev.dev_high)["K"]
        out["readout"].append(None if ro is None else ro.value / truth["K"] - 1.0)
    return out


def summary(c: dict) -> str:
    read = np.array([r for r in c["readout"] if r is not None])
    r_rms = float(np.sqrt(np.mean(read ** 2)))
    k = c["crb"]["K"]
    return (f"| {c['mix']} | 2^{int(np.log2(c['n']))} | {k['all_unknown']:.3f} | "
            f"{k['others_known']:.3f} | {len(read)}/{len(c['readout'])} | {r_rms:.3f} "
            f"(bias {np.mean(read):+.3f}) | {k['all_unknown'] / r_rms:.2f}x |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    print("| n | truth | sd log Q, N, B, K: Whittle / exact |\n|---|---|---|---|---|---|")
    print("\n".join(check()), flush=True)
    print("\n| mix | n | CRB sd(log K), all unknown | Q, N, B known | readouts | readout RMS "
          "(mean) | CRB / readout RMS |\n|---|---|---|---|---|---|---|", flush=True)
    cells = []
    t0 = time.perf_counter()
    for mix in MIXES:
        for k in LENGTHS[mix]:
            c = cell(mix, 2 ** k, seeds)
            cells.append(c)
            print(summary(c), flush=True)
    print(f"\n{len(cells) * len(seeds)} records in {time.perf_counter() - t0:.0f} s")
    for c in cells:
        print(c["mix"], c["n"], {p: round(v["all_unknown"], 4) for p, v in c["crb"].items()})
    if args.out:
        with open(args.out, "w") as f:
            json.dump(cells, f)


if __name__ == "__main__":
    main()
