"""Paper-000-style before/after tables: relative error per temperature and rate.

Per (T_i, W_j) cell: |mean - W_j| / |W_j| x 100 % (paper Tables 1-2). "Before" is a nominal
linear calibration at T_nom = 20 deg C: W_before = (U - U0(T_nom)) / S0(T_nom), S0(T) = sum_i M_i0 T^i.
"""

from __future__ import annotations

import numpy as np

from .model import RawCoefficients

#: Paper 000, Tables 1 and 2: (T, W) -> (before, before %, after, after %).
PAPER_TABLES = {
    (20.0, -80.0): (-70.576, 11.78, -79.347, 0.82), (20.0, 5.0): (4.917, 1.67, 4.957, 0.85),
    (20.0, 10.0): (9.946, 0.54, 9.959, 0.41), (20.0, 20.0): (19.894, 0.53, 19.954, 0.23),
    (20.0, 80.0): (70.306, 12.12, 79.239, 0.95),
    (-30.0, -80.0): (-71.519, 10.60, -79.311, 0.86), (-30.0, 5.0): (5.013, 0.27, 4.999, 0.02),
    (-30.0, 80.0): (71.263, 10.92, 79.303, 0.87),
    (60.0, -80.0): (-69.455, 13.18, -79.147, 1.07), (60.0, 5.0): (4.866, 2.69, 5.007, 0.13),
    (60.0, 80.0): (69.296, 13.38, 79.165, 1.04),
}


def nominal_rate(raw: RawCoefficients, U, *, T_nominal: float = 20.0) -> np.ndarray:
    """Uncompensated reading (U - U0(T_nom)) / S0(T_nom) (deg/s), see the module doc."""
    M, c = np.asarray(raw.M, float), np.asarray(raw.c, float)
    S0 = np.polynomial.polynomial.polyval(T_nominal, M[:, 0])
    U0 = np.polynomial.polynomial.polyval(T_nominal, c)
    return (np.asarray(U, float) - U0) / S0


def before_after(cell_T, cell_W, cell, rates: dict) -> list[dict]:
    """One row per cell: set-points and, per method, the mean rate and relative error (%).

    Args:
        cell_T, cell_W: (K,) set-point temperature and rate of each cell.
        cell: (m,) cell index of every sample (0..K-1).
        rates: method name -> (m,) compensated rate (deg/s) of every sample.
    """
    cell = np.asarray(cell)
    K = len(cell_T)
    cnt = np.bincount(cell, minlength=K).astype(float)
    rows = [{"temperature": float(cell_T[k]), "rate": float(cell_W[k]), "n": int(cnt[k])}
            for k in range(K)]
    for name, w in rates.items():
        mean = np.bincount(cell, np.asarray(w, float), K) / np.where(cnt > 0, cnt, 1)
        for k, row in enumerate(rows):
            W = row["rate"]
            row[name] = float(mean[k])
            row[f"{name}_error_pct"] = (float(abs(mean[k] - W) / abs(W) * 100) if W != 0
                                        else None)
    return rows


def format_table(rows: list[dict], methods=("before", "paper", "fogbayes"), *,
                 temperatures=None, rates=None, digits: int = 3) -> str:
    """A Markdown table in the paper's layout (optionally only some temperatures/rates)."""
    sel = [r for r in rows if (temperatures is None or r["temperature"] in temperatures)
           and (rates is None or r["rate"] in rates)]
    sel.sort(key=lambda r: (r["temperature"], r["rate"]))
    head = ["T (degC)", "rate (deg/s)"]
    for m in methods:
        head += [f"{m} (deg/s)", f"{m} error (%)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in sel:
        cells = [f"{r['temperature']:g}", f"{r['rate']:g}"]
        for m in methods:
            e = r.get(f"{m}_error_pct")
            cells += [f"{r[m]:.{digits}f}", "-" if e is None else f"{e:.{max(digits - 1, 2)}g}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def paper_comparison(rows: list[dict], method: str = "before") -> list[dict]:
    """Rows of the paper's Tables 1-2 next to ours: (T, W, paper %, ours %, difference)."""
    out = []
    index = {(r["temperature"], r["rate"]): r for r in rows}
    col = 1 if method == "before" else 3
    for (T, W), vals in PAPER_TABLES.items():
        r = index.get((T, W))
        if r is not None and r.get(f"{method}_error_pct") is not None:
            ours = r[f"{method}_error_pct"]
            out.append({"temperature": T, "rate": W, "paper_pct": vals[col], "ours_pct": ours,
                        "difference": ours - vals[col]})
    return out
