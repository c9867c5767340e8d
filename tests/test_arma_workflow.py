"""`fogbayes arma` end to end: JSON contents, figure, bad input, measured ADIS16405 data."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import fogbayes.cli.arma  # noqa: F401  (registers the command until cli/__init__ imports it)
from fogbayes.cli import main
from fogbayes.data import Recording
from fogbayes.arma.workflow import analyse_recording, parse_candidates

sm_proc = pytest.importorskip("statsmodels.tsa.arima_process")
sm_arima = pytest.importorskip("statsmodels.tsa.arima.model")

PHI = [0.5, -0.35]
# the length of the measured test below after decimation (20 000): one length bucket, so
# both run the same compiled order selection, Kalman filter and smoother
N_CLI = 20_000


def _csv(path, n=4000, gap=False):
    x = sm_proc.arma_generate_sample(np.r_[1, -np.asarray(PHI)], [1.0], n,
                                     distrvs=np.random.default_rng(0).standard_normal)
    t = np.arange(n) / 10.0
    if gap:
        t[n // 2 :] += 5.0
    y = 0.01 * x + 0.3 + 2e-5 * t  # deg/s: offset and a linear drift to be removed
    np.savetxt(path, np.c_[t, y], delimiter=",", header="time,output", comments="")
    return path


def test_cli_writes_json_and_plot(tmp_path):
    rec = _csv(tmp_path / "rec.csv", n=N_CLI)
    out, png = tmp_path / "arma.json", tmp_path / "arma.png"
    code = main(["--quiet", "arma", str(rec), "--output-unit", "deg/s", "--json", str(out),
                 "--plot", str(png)])
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["sign_convention"].startswith("x_t = sum_i phi_i x_{t-i} + a_t - sum_j theta_j")
    assert doc["selected"] == "AR(2)" and doc["converged"] is True
    assert {c["name"] for c in doc["candidates"]} == {"AR(1)", "AR(2)", "AR(3)", "ARMA(1,1)",
                                                      "ARMA(2,1)"}
    assert {"aic", "bic", "loglik", "p", "q"} <= set(doc["candidates"][0])
    par = doc["params"]
    # truth within 4 standard errors (parameters are scale-free; sigma2 in (deg/s)^2)
    assert np.all(np.abs(np.array(par["phi"]) - PHI) < 4 * np.array(par["se_phi"]))
    assert par["sigma2"] == pytest.approx(1e-4, rel=0.1)  # (0.01 deg/s)^2, n = 20 000
    w = doc["whiteness"]
    assert {"rho_a2", "rho_ax3", "ljung_box_p"} <= set(w) and w["white"] is True
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("args,needle", [
    (["--decimate", "0"], "decimate"),
    (["--candidates", "1;2"], "candidate"),
    (["--criterion", "hqic"], "criterion"),
    (["--decimate", "100"], "at least"),
])
def test_cli_bad_arguments_exit_2(tmp_path, capsys, args, needle):
    rec = _csv(tmp_path / "rec.csv")
    code = main(["arma", str(rec), "--json", str(tmp_path / "o.json"), *args])
    assert code == 2
    assert needle in capsys.readouterr().err


def test_gaps_are_refused_with_the_row(tmp_path, capsys):
    rec = _csv(tmp_path / "gap.csv", gap=True)
    assert main(["arma", str(rec), "--json", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert "uniform sampling" in err and "2000" in err  # the row after the gap


def test_parse_candidates():
    assert parse_candidates("paper")[-1] == (2, 1)
    assert len(parse_candidates("grid")) == 16
    assert parse_candidates("grid:1,2") == ((0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2))
    assert parse_candidates("1,0; 2,1") == ((1, 0), (2, 1))


@pytest.mark.measured
def test_adis16405_gyro_x_decimated_like_the_paper(measured):
    """Real data: first 2000 s of run imu1, gyro X, decimated 100 -> 10 Hz (paper's rate)."""
    data = np.load(measured("adis16405_static_ucalgary", "adis_16405_imu1.npz"))["data"]
    y = data[:200_000, 0]
    rec = Recording(time=np.arange(y.size) / 100.0, output=y, unit="deg/s")
    a = analyse_recording(rec, decimate=10, detrend_order=1)
    doc = a.document
    assert doc["n"] == 20_000 and doc["converged"]
    p, q = doc["params"]["p"], doc["params"]["q"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = sm_arima.ARIMA(a.x, order=(p, 0, q), trend="n").fit()
    best = next(c for c in doc["candidates"] if (c["p"], c["q"]) == (p, q))
    # our exact MLE is at least as good as statsmodels' on the same detrended series
    assert best["loglik"] >= r.llf - 1e-6 * abs(r.llf)
    # ~white-noise-dominated MEMS gyro: residual variance close to the series variance
    assert doc["params"]["sigma2"] == pytest.approx(np.var(a.x), rel=0.1)
    assert 0.0 <= doc["whiteness"]["ljung_box_p"] <= 1.0
