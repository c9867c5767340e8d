"""ACF/PACF with bands, paper 002's rho_a,2 / rho_ax,3, Ljung-Box: references and rates."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.arma.fit import fit_arma_batch
from fogbayes.arma.filter import one_step_prediction
from fogbayes.stats.acf import acf, pacf
from fogbayes.stats.whiteness import ljung_box, rho_a2, rho_ax3, whiteness

sm_tsa = pytest.importorskip("statsmodels.tsa.stattools")
sm_diag = pytest.importorskip("statsmodels.stats.diagnostic")
sm_proc = pytest.importorskip("statsmodels.tsa.arima_process")


def _arma(phi, theta, n, seed):
    return sm_proc.arma_generate_sample(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)],
                                        n, distrvs=np.random.default_rng(seed).standard_normal,
                                        burnin=200)


def test_acf_pacf_and_bands_equal_statsmodels():
    x = _arma([0.6, -0.2], [0.3], 3000, 1) + 0.5
    a = acf(x, 30)
    ref, ci = sm_tsa.acf(x, nlags=30, alpha=0.05, fft=True, result_object=False)
    np.testing.assert_allclose(a.values, ref, atol=1e-12)  # same estimator
    # statsmodels returns the Bartlett interval around the estimate
    np.testing.assert_allclose(a.band[1:], (ci[:, 1] - ref)[1:], rtol=1e-10)
    pa = pacf(x, 30)
    pref, pci = sm_tsa.pacf(x, nlags=30, method="ldb", alpha=0.05)
    np.testing.assert_allclose(pa.values, pref, atol=1e-10)
    np.testing.assert_allclose(pa.band[1:], (pci[:, 1] - pref)[1:], rtol=1e-10)


def test_paper_formulas_by_hand():
    a = np.array([1.0, -2.0, 0.5, 3.0, -1.0])
    x = np.array([2.0, 1.0, -1.0, 0.5, 4.0])
    # eq. 11: sum_{t=3}^N a_t a_{t-2} / sum_{t=3}^N a_t^2 (1-based)
    assert rho_a2(a) == pytest.approx((0.5 * 1 + 3 * -2 + -1 * 0.5) / (0.25 + 9 + 1))
    # eq. 12: sum_{t=4}^N a_t x_{t-3} / sqrt(sum a_t^2 sum x_{t-3}^2)
    assert rho_ax3(a, x) == pytest.approx((3 * 2 + -1 * 1) / np.sqrt((9 + 1) * (4 + 1)))


def test_ljung_box_equals_statsmodels():
    a = np.random.default_rng(3).standard_normal(800)
    q, dof, p = ljung_box(a, 15, fitted_params=3)
    ref = sm_diag.acorr_ljungbox(a, lags=[15], model_df=3)
    assert q == pytest.approx(float(ref["lb_stat"].iloc[0]), rel=1e-10)
    assert p == pytest.approx(float(ref["lb_pvalue"].iloc[0]), rel=1e-8)
    assert dof == 12
    with pytest.raises(ValueError):
        ljung_box(a, 3, fitted_params=3)


def _verdicts(X, p, q):
    fits = fit_arma_batch(X, p=p, q=q)
    out = []
    for i in range(X.shape[0]):
        phi, theta, s2 = np.asarray(fits.phi[i]), np.asarray(fits.theta[i]), float(fits.sigma2[i])
        res = one_step_prediction(phi, theta, s2, X[i]).residual
        out.append(whiteness(res, X[i], p=p, q=q))
    return out


@pytest.mark.slow
def test_whiteness_accepts_correct_and_rejects_underfitted_models():
    """ARMA(2,1) data (n = 1000, 60 seeds). Fitted with the true order the verdict must say
    white in >= 85 % (nominal >= 1 - alpha = 95 %; measured 60/60); fitted as AR(1)
    (under-fitted) it must say not white in >= 90 % (measured 60/60), with the paper's
    rho_a2 and Ljung-Box each rejecting on their own as well."""
    X = np.stack([_arma([0.5, -0.4], [-0.5], 1000, 1000 + s) for s in range(60)])
    right = _verdicts(X, 2, 1)
    under = _verdicts(X, 1, 0)
    assert np.mean([w.white for w in right]) >= 0.85
    assert np.mean([not w.white for w in under]) >= 0.90
    assert np.mean([w.ljung_box_p < 0.05 for w in under]) >= 0.90
    assert np.mean([abs(w.rho_a2) > w.band for w in under]) >= 0.90
    # under a white null p-values are ~uniform: their mean is near 1/2 (measured 0.487)
    assert 0.35 < np.mean([w.ljung_box_p for w in right]) < 0.65
