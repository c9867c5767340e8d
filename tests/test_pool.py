"""Pooling across runs and units (fogbayes.pool): the hierarchical normal model against
independent references (grid quadrature of the posterior, the DerSimonian-Laird random-effects
estimate, the conjugate normal update), outlier flags, the CLI and the measured ADIS16405 runs.

Fleet-level calibration (coverage over repetitions, shrinkage gain, flag rates) is measured
in benchmarks/bench_pool.py (benchmarks/RESULTS_pool.md): too slow for the suite.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from _pool_fleet import write_units
from fogbayes.pool.normal import MU_PRIOR_SD, SPREAD_PRIOR_SD, fit_pool, shrink


def _fleet(U, mu, s, se, seed):
    rng = np.random.default_rng(seed)
    mu, s, se = (np.atleast_1d(np.asarray(v, float)) for v in (mu, s, se))
    se_u = se * np.exp(0.5 * rng.standard_normal((U, mu.size)))  # unequal precisions
    theta = mu + s * rng.standard_normal((U, mu.size))
    y = theta + se_u * rng.standard_normal((U, mu.size))
    cov = np.stack([np.diag(v**2) for v in se_u])
    return y, cov, theta


def _dersimonian_laird(y, v):
    """Random-effects mean and between-unit variance (DerSimonian & Laird 1986), 1-D."""
    w = 1 / v
    m = np.sum(w * y) / np.sum(w)
    q = np.sum(w * (y - m) ** 2)
    tau2 = max(0.0, (q - (y.size - 1)) / (np.sum(w) - np.sum(w**2) / np.sum(w)))
    ws = 1 / (v + tau2)
    return np.sum(ws * y) / np.sum(ws), tau2, np.sqrt(1 / np.sum(ws))


def _quantile_tolerance(draws, a, density, chains=4):
    """4 Monte Carlo standard errors of the draws' a-quantile: sqrt(a (1 - a) / ESS) /
    density, the ESS that of the indicator draws <= quantile (Vehtari et al. 2021), not the
    mean's (NUTS draws of a near-normal posterior can be anticorrelated, ESS above the
    number of draws for the mean, and not for a tail quantile)."""
    from numpyro.diagnostics import effective_sample_size

    below = (draws <= np.quantile(draws, a)).astype(float).reshape(chains, -1)
    return 4 * np.sqrt(a * (1 - a) / float(effective_sample_size(below))) / density


def test_population_posterior_matches_grid_quadrature_and_dersimonian_laird():
    """Two independent parameters (diagonal covariances: the posterior factorises): the NUTS
    posterior of (mu, s) of each against the same posterior on a 2-D grid (an independent
    computation of the model), and mu against the frequentist random-effects estimate
    (within its standard error: the two estimators differ by their prior).
    Fleet size and sampler sizes are those of the other tests: one compilation serves all."""
    y, cov, _ = _fleet(8, [-2.0, 1.0], [0.4, 0.1], [0.2, 0.05], seed=3)
    res = fit_pool(y, cov, ("x", "z"), seed=1)
    assert res.diagnostics["converged"]
    for j in range(2):
        v = cov[:, j, j]
        centre = np.median(y[:, j])
        mu = np.linspace(y[:, j].min() - 2, y[:, j].max() + 2, 801)
        s = np.linspace(1e-4, 2.5, 1000)
        M, S = np.meshgrid(mu, s, indexing="ij")
        tot = S[..., None] ** 2 + v
        logp = (-0.5 * ((y[:, j] - M[..., None]) ** 2 / tot + np.log(tot)).sum(-1)
                - 0.5 * ((M - centre) / MU_PRIOR_SD) ** 2 - 0.5 * (S / SPREAD_PRIOR_SD) ** 2)
        p = np.exp(logp - logp.max())
        p /= p.sum()
        for draws, grid, w in ((res.mu[:, j], mu, p.sum(1)), (res.spread[:, j], s, p.sum(0))):
            cdf = np.cumsum(w) - 0.5 * w  # at the grid points, each holding its cell's mass
            for a in (0.05, 0.5, 0.95):
                x = np.interp(a, cdf, grid)
                density = np.interp(x, grid, w) / (grid[1] - grid[0])
                assert abs(np.quantile(draws, a) - x) < _quantile_tolerance(draws, a, density), (j, a)
        m_dl, _, se_dl = _dersimonian_laird(y[:, j], v)
        assert abs(np.median(res.mu[:, j]) - m_dl) < se_dl


def test_shrink_is_the_conjugate_normal_update():
    """Given (mu, s), theta_u | y_u is normal with precision 1/s^2 + 1/se^2 (P = 1), and in
    P = 2 with a full Sigma_u the mean is mu + S (S + Sigma)^-1 (y - mu)."""
    rng = np.random.default_rng(0)
    y = np.array([[1.0], [-0.5]])
    cov = np.array([[[0.25]], [[4.0]]])
    mu, s = np.full((40_000, 1), 0.2), np.full((40_000, 1), 0.5)
    d = shrink(y, cov, mu, s, rng)
    for u in range(2):
        prec = 1 / 0.25 + 1 / cov[u, 0, 0]
        mean = (0.2 / 0.25 + y[u, 0] / cov[u, 0, 0]) / prec
        assert abs(d[:, u, 0].mean() - mean) < 5 * np.sqrt(1 / prec / 40_000)
        assert abs(d[:, u, 0].var() / (1 / prec) - 1) < 0.05  # ~7 se of a variance ratio
    y2 = np.array([[0.3, -1.0]])
    c2 = np.array([[[0.5, 0.2], [0.2, 0.3]]])
    S = np.diag([0.4, 0.1]) ** 2
    d2 = shrink(y2, c2, np.zeros((40_000, 2)), np.tile([0.4, 0.1], (40_000, 1)), rng)
    mean = S @ np.linalg.solve(S + c2[0], y2[0])
    assert np.allclose(d2[:, 0].mean(0), mean, atol=0.01)
    assert np.allclose(np.cov(d2[:, 0].T), S - S @ np.linalg.solve(S + c2[0], S), atol=0.003)


def _censored_lik(t, y, var, c):
    """The likelihood of an unresolved term, written out here independently: normal in
    x = log((v - v_hat + S) / S), v = e^(2t), v_hat = e^(2y), S = e^(2c), variance var."""
    x = np.log((np.exp(2 * t) - np.exp(2 * y) + np.exp(2 * c)) / np.exp(2 * c))
    return np.exp(-(x**2) / (2 * var))


@pytest.mark.parametrize("y, var, c", [(0.0, 0.3**2, 0.5), (-2.0, 1.0, -1.9), (1.0, 0.05**2, 3.0),
                                       (0.2, 0.5, 0.2005)])
def test_censored_likelihood_is_level_towards_zero_and_log_quadratic_above(y, var, c):
    """An unresolved term's likelihood: 1 at the estimate, level towards v = 0 at
    exp(-log(1 - v_hat/S)^2 / (2 var)), about normal in v near the estimate, normal in
    log v far above it; a one-term block of the joint form in unit_log_lik is the same."""
    from fogbayes.pool.normal import censored_log_lik, unit_log_lik

    t = np.linspace(y - 30, y + 3, 301)
    assert np.allclose(np.exp(np.asarray(censored_log_lik(t, y, var, c))),
                       _censored_lik(t, y, var, c), rtol=1e-9, atol=1e-300)
    level = np.exp(-np.log1p(-np.exp(2 * (y - c))) ** 2 / (2 * var))
    assert np.isclose(float(np.exp(censored_log_lik(y - 40.0, y, var, c))), level)
    both = [float(unit_log_lik(np.array([1.0, y]), np.diag([0.04, var]), np.array([0.0, 1.0]),
                               np.array([1.0, 0.0]), np.array([0.2, 1.0]),
                               np.array([0.0, x]), np.array([0.0, c]))) for x in (y - 1, y + 0.5)]
    gauss = -0.5 * np.log(2 * np.pi * (0.04 + 0.2**2))
    assert np.allclose(both, [gauss + float(censored_log_lik(x, y, var, c))
                              for x in (y - 1, y + 0.5)])


def test_population_with_unresolved_units_matches_grid_quadrature():
    """Three units resolve the term (normal in log), three do not (the likelihood above,
    their parameters sampled with the population): the NUTS posterior of the population
    median and spread against the same posterior on a (mu, s) grid, each unresolved unit's
    parameter integrated out by quadrature (an independent computation), and the sampler's
    draws of an unresolved unit's parameter against its posterior mean by quadrature; the
    same for a second fit that keeps the first one's adaptation (``start``: its mass matrix
    and step size, 150 warm-up steps instead of 1000), as ``pool_allan``'s second pool does."""
    from numpyro.diagnostics import effective_sample_size

    y = np.array([[-3.9], [-3.6], [-3.75], [-3.7], [-4.6], [-6.0]])
    sd = np.array([0.15, 0.2, 0.1, 0.5, 0.3, 0.8])
    ceil = np.array([[0.0], [0.0], [0.0], [-3.5], [-3.3], [-3.4]])
    cens = np.array([[0.], [0.], [0.], [1.], [1.], [1.]])
    cov = (sd**2)[:, None, None]
    res = fit_pool(y, cov, ("b",), censored=cens, ceiling=ceil, seed=4, outliers=False)
    again = fit_pool(y, cov, ("b",), censored=cens, ceiling=ceil, seed=5, outliers=False,
                     start=res.adaptation)
    assert res.diagnostics["converged"] and again.diagnostics["converged"]
    # kept, not adapted again: the same mass matrix and step size come back
    np.testing.assert_allclose(again.adaptation[0], res.adaptation[0], rtol=1e-12, atol=0)
    assert again.adaptation[1] == pytest.approx(res.adaptation[1], rel=1e-12)
    mu = np.linspace(-14.0, 2.0, 321)
    s = np.arange(0.0025, 2.5, 0.005)  # cell midpoints: the spread's lower tail is near 0
    zg = np.linspace(-8.0, 8.0, 401)
    phi = np.exp(-0.5 * zg**2) / np.sqrt(2 * np.pi)
    M, S = np.meshgrid(mu, s, indexing="ij")
    r = cens[:, 0] == 0
    tot = S[..., None] ** 2 + sd[r] ** 2
    logp = (-0.5 * ((y[r, 0] - M[..., None]) ** 2 / tot + np.log(tot)).sum(-1)
            - 0.5 * ((M - np.median(y)) / MU_PRIOR_SD) ** 2 - 0.5 * (S / SPREAD_PRIOR_SD) ** 2)

    def moments(u, k):
        """integrals of lik(theta) N(theta; mu, s_k^2) and of theta times it, theta = mu + s z"""
        th = mu[:, None] + s[k] * zg[None, :]
        w = _censored_lik(th, y[u, 0], sd[u] ** 2, ceil[u, 0]) * phi
        return np.trapezoid(w, zg, axis=-1), np.trapezoid(w * th, zg, axis=-1)

    mom = {u: [moments(u, k) for k in range(s.size)] for u in np.flatnonzero(~r)}
    for u, m in mom.items():
        logp += np.log(np.stack([m0 for m0, _ in m], axis=1))
    p = np.exp(logp - logp.max())
    p /= p.sum()
    for fit in (res, again):
        for draws, grid, wt in ((fit.mu[:, 0], mu, p.sum(1)), (fit.spread[:, 0], s, p.sum(0))):
            cdf = np.cumsum(wt) - 0.5 * wt  # at the grid points (a coarse grid: 0.05 in mu)
            for a in (0.05, 0.5, 0.95):
                x = np.interp(a, cdf, grid)
                density = np.interp(x, grid, wt) / (grid[1] - grid[0])
                assert abs(np.quantile(draws, a) - x) < _quantile_tolerance(draws, a, density), a
        for u, m in mom.items():  # sum over (mu, s) of p(mu, s | y) E[theta | mu, s, y_u]
            mean = np.stack([m1 / np.maximum(m0, 1e-300) for m0, m1 in m], axis=1)
            d = fit.units[:, u, 0]
            n_eff = float(effective_sample_size(d.reshape(4, -1)))
            assert abs(d.mean() - np.sum(p * mean)) < 4 * d.std() / np.sqrt(n_eff), u


def test_a_refit_without_a_unit_starts_its_z_at_unit_inverse_mass():
    """The rows and columns the leave-one-out refit resets are the left-out unit's z in the
    order NumPyro ravels the sampled dict (an independent ravel: jax.flatten_util)."""
    from jax.flatten_util import ravel_pytree

    from fogbayes.pool.normal import _start_without

    U, P = 5, 3
    flat, _ = ravel_pytree({"eta": np.zeros(P), "log_s": np.zeros(P),
                            "z": np.arange(1.0, U * P + 1).reshape(U, P)})
    idx = np.flatnonzero((flat > 2 * P) & (flat <= 3 * P))  # unit 2's z: 7, 8, 9
    inv = np.full((2 * P + U * P,) * 2, 0.3) + np.eye(2 * P + U * P)
    out, step = _start_without((inv, 0.07), 2, P)
    assert step == 0.07 and idx.tolist() == [2 * P + 2 * P + j for j in range(P)]
    keep = np.setdiff1d(np.arange(inv.shape[0]), idx)
    assert np.array_equal(out[np.ix_(idx, idx)], np.eye(P))
    assert not out[np.ix_(idx, keep)].any() and not out[np.ix_(keep, idx)].any()
    assert np.array_equal(out[np.ix_(keep, keep)], inv[np.ix_(keep, keep)])


def test_a_far_unit_is_flagged_by_an_exact_refit_and_the_others_are_not():
    y, cov, _ = _fleet(8, [0.0, 1.0], [0.2, 0.3], [0.05, 0.2], seed=5)
    y[4, 1] += 3.0  # ~8 predictive sd away in the second parameter
    res = fit_pool(y, cov, ("a", "b"), seed=2)
    flagged = np.flatnonzero(res.outlier_p < 0.01)
    assert flagged.tolist() == [4]
    assert res.diagnostics["loo_method"][4] == "refit"  # a flag never rests on PSIS alone
    assert res.outlier_p[4] < 1e-4
    # parameter a is untouched by the outlier: its population interval holds the
    # random-effects estimate of the units' a
    lo, hi = np.quantile(res.mu[:, 0], [0.05, 0.95])
    assert lo < _dersimonian_laird(y[:, 0], cov[:, 0, 0])[0] < hi


def test_each_term_outlier_p_is_the_bonferroni_of_two_sided_normal_tails():
    """Fixed (mu, S), a diagonal unit covariance: the per-term p-value is 2 Phi(-|z_t|) with
    z_t = (y_t - mu_t) / sqrt(s_t^2 + Sigma_tt), the unit's the smallest times P; the joint
    one is the chi-square tail of sum z_t^2 (closed forms, scipy)."""
    from scipy import stats

    from fogbayes.pool.normal import _predictive_p

    y, mu, s, sd = np.array([0.3, 2.0, -0.1]), np.zeros(3), np.array([0.2, 0.5, 0.1]), 0.1
    cu = np.eye(3) * sd**2
    D = 7
    draws = np.broadcast_to(mu, (D, 3)), np.broadcast_to(s, (D, 3))
    z = y / np.sqrt(s**2 + sd**2)
    each = _predictive_p(y, cu, np.zeros(3), *draws, test="each")
    assert each == pytest.approx(3 * np.min(2 * stats.norm.sf(np.abs(z))), rel=1e-12)
    joint = _predictive_p(y, cu, np.zeros(3), *draws)
    assert joint == pytest.approx(stats.chi2.sf(np.sum(z**2), 3), rel=1e-12)
    # one term far off, the others at the centre: judged alone it stands out more
    assert each < joint


def test_a_datasheet_prior_moves_the_population_median_by_its_weight():
    """A tight sheet (sd 0.01 in log) pins mu near the sheet value; a loose one (sd 3) leaves
    it where the units put it. Same fleet shape as the other tests (one compilation)."""
    y, cov, _ = _fleet(8, [0.0, 1.0], [0.2, 0.3], [0.05, 0.2], seed=7)
    # only the population is checked: no leave-one-out (it does not change the mu draws)
    free = fit_pool(y, cov, ("a", "b"), seed=0, outliers=False)
    tight = fit_pool(y, cov, ("a", "b"), seed=0, outliers=False,
                     mu_prior=([0.5, 1.0], [0.01, MU_PRIOR_SD]))
    loose = fit_pool(y, cov, ("a", "b"), seed=0, outliers=False,
                     mu_prior=([0.5, 1.0], [3.0, MU_PRIOR_SD]))
    assert abs(np.median(tight.mu[:, 0]) - 0.5) < 0.03
    assert abs(np.median(loose.mu[:, 0]) - np.median(free.mu[:, 0])) < 0.03
    assert abs(np.median(free.mu[:, 0]) - 0.5) > 0.3


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """Eight simulated units, unit2 with four times the others' N, pooled by the CLI once
    per run (tests/_pool_fleet.py; tests/test_report_browser.py renders the same report)."""
    from _pool_fleet import pooled_fleet

    return pooled_fleet(tmp_path_factory)


def test_cli_pools_a_folder_writes_document_and_report(fleet, tmp_path):
    from fogbayes.cli import main

    doc = json.loads((fleet / "pool.json").read_text())
    assert doc["schema"] == "fogbayes.pool/1" and list(doc["channels"]) == ["output"]
    pool = doc["channels"]["output"]
    assert [u["name"] for u in pool["units"]] == [f"unit{u}" for u in range(8)]
    assert pool["terms"] == ["N", "B"]
    # N four times the others' (each known to ~2 %; they differ by ~10 %): with seven
    # others the population's spread is known well enough to place it outside
    assert pool["flagged"] == ["unit2"]
    med = pool["population"]["N"]["median"]
    assert med["low"] < 0.01 < med["high"] * 1.1
    html = (fleet / "pool.html").read_text()
    assert "Population" in html and "unit2" in html and "data:image/png;base64," in html
    # a datasheet prior (fogbayes prior) on the typical unit's N is recorded and applied
    # (N alone: B, which five units leave unresolved, would only slow the sampler here)
    sheet = tmp_path / "sheet.json"
    assert main(["--quiet", "prior", "--arw", "0.02", "--arw-unit", "deg/sqrt(h)",
                 "--looseness", "1.01", "--json", str(sheet)]) == 0
    assert main(["--quiet", "pool", str(fleet / "runs"), "--terms", "N", "--prior",
                 str(sheet), "--json", str(tmp_path / "p2.json")]) == 0
    p2 = json.loads((tmp_path / "p2.json").read_text())["channels"]["output"]
    assert p2["prior"]["terms"]["N"]["value"] == 0.02 and "N" in p2["prior"]["rule"]
    assert abs(p2["population"]["N"]["median"]["value"] / 0.02 - 1) < 0.02


@pytest.mark.parametrize("args, key", [
    (["--terms", "N,X"], "--terms"),
    (["--terms", "N,N"], "--terms"),
    (["--flag-level", "0"], "--flag-level"),
    (["--model", "thermal"], "--model"),
])
def test_cli_refuses_bad_arguments_in_one_line(tmp_path, capsys, args, key):
    from fogbayes.cli import main

    write_units(tmp_path / "runs", 2, n=2**10)
    assert main(["pool", str(tmp_path / "runs"), "--json", str(tmp_path / "p.json"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0] and "Traceback" not in err[0]


def test_cli_refuses_a_single_recording_and_an_empty_folder(tmp_path, capsys):
    from fogbayes.cli import main

    write_units(tmp_path / "runs", 1, n=2**10)
    assert main(["pool", str(tmp_path / "runs"), "--json", str(tmp_path / "p.json")]) == 2
    assert "at least two" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["pool", str(tmp_path / "empty"), "--json", str(tmp_path / "p.json")]) == 2
    assert "no recordings" in capsys.readouterr().err


def test_cli_refuses_a_constant_unit_in_one_line(tmp_path, capsys):
    from fogbayes import Recording, save
    from fogbayes.cli import main
    from fogbayes.data import Metadata

    write_units(tmp_path / "runs", 2, n=2**10)
    save(Recording(time=np.arange(1024) / 10.0, output=np.full(1024, 3.0), unit="deg/h",
                   meta=Metadata(sensor_id="stuck", sample_rate=10.0)), tmp_path / "runs" / "z.npz")
    assert main(["pool", str(tmp_path / "runs"), "--json", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "constant" in err[0] and "z.npz" in err[0]


ADIS = Path(os.environ.get("FOGBAYES_SHARED", Path(__file__).resolve().parents[2] / "shared")) \
    / "data" / "measured" / "adis16405_static_ucalgary"


def test_six_adis16405_runs_pool_beside_the_random_effects_estimate(tmp_path):
    """The six measured runs (gyro X, read from ../shared in the files' own matrix layout):
    the pooled population N agrees with the DerSimonian-Laird random-effects mean of the
    runs' own log N, and the runs differ by more than their noise (Cochran's Q, p < 0.01),
    which the pool reports as a between-run spread whose interval excludes no spread."""
    from scipy import stats

    from fogbayes.cli import main

    if not ADIS.exists():
        msg = f"measured ADIS16405 runs not found at {ADIS} (set FOGBAYES_SHARED)"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    files = [str(ADIS / f"adis_16405_imu{k}.npz") for k in range(1, 7)]
    out = tmp_path / "pool.json"
    assert main(["--quiet", "pool", *files, "--column", "gyro_x_dps", "--output-unit", "deg/s",
                 "--terms", "N,B", "--json", str(out)]) == 0
    pool = json.loads(out.read_text())["channels"]["gyro_x_dps"]
    logn = np.log([u["terms"]["N"]["single"]["value"] for u in pool["units"]])
    se = np.array([np.log(u["terms"]["N"]["single"]["high"] / u["terms"]["N"]["single"]["low"])
                   / (2 * 1.6449) for u in pool["units"]])
    m_dl, tau2, se_dl = _dersimonian_laird(logn, se**2)
    w = 1 / se**2
    q = np.sum(w * (logn - np.sum(w * logn) / np.sum(w)) ** 2)
    assert stats.chi2.sf(q, logn.size - 1) < 0.01
    med = pool["population"]["N"]["median"]
    assert abs(np.log(med["value"]) - m_dl) < 2 * se_dl
    assert pool["population"]["N"]["spread"]["log_sd"]["low"] > 0.3 * np.sqrt(tau2)


def test_unit_names_stay_apart_across_folders_and_a_file_named_twice_is_refused(tmp_path):
    """a/imu.npz and b/imu.npz are two units (named by their paths below the shared
    folder); the same file given twice would count one unit twice and is refused."""
    from types import SimpleNamespace

    from fogbayes.cli.pool import _names, recording_paths
    from fogbayes.errors import FileFormatError

    paths = []
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        f = tmp_path / d / "imu.npz"
        f.write_bytes(b"")
        paths.append(f)
    recs = [SimpleNamespace(meta=SimpleNamespace(sensor_id=None))] * 2
    assert _names(recs, paths) == [str(Path("a") / "imu.npz"), str(Path("b") / "imu.npz")]
    assert recording_paths([tmp_path / "a", tmp_path / "b"]) == paths
    with pytest.raises(FileFormatError, match="named twice"):
        recording_paths([paths[0], tmp_path / "a"])


def test_a_unit_is_drawn_with_its_own_covariance_and_the_population_is_unchanged():
    # fogbayes.pool.allan gives the population the units' covariances at the population
    # median and each unit its own (unit_cov) where it is taken alone: its shrunk draws.
    # Eight units, as the other tests: one compilation of the sampler serves them all
    y, cov, _ = _fleet(8, [0.0, 1.0], [0.2, 0.3], [0.05, 0.1], seed=7)
    own = cov.copy()
    own[0] *= 16.0  # unit 0 is 4x less precise than the population pass takes it
    a = fit_pool(y, cov, ("a", "b"), seed=3, outliers=False)
    b = fit_pool(y, cov, ("a", "b"), seed=3, outliers=False, unit_cov=own)
    np.testing.assert_array_equal(a.mu, b.mu)  # the population pass is the same
    np.testing.assert_array_equal(a.units[:, 1:], b.units[:, 1:])  # other units untouched
    # unit 0's draws: the conjugate normal update with its own covariance, draw by draw
    S = b.spread**2
    mean = b.mu + S / (S + np.diag(own[0])) * (y[0] - b.mu)
    sd = np.sqrt(S - S**2 / (S + np.diag(own[0])))
    z = (b.units[:, 0] - mean) / sd
    assert abs(z.mean()) < 0.1 and abs(z.std() - 1.0) < 0.05  # 4000 draws: se 0.016 / 0.011
    # and it is shrunk further toward the population than with the pool's covariance
    assert np.all(np.abs(np.median(b.units[:, 0], 0) - np.median(b.mu, 0))
                  < np.abs(np.median(a.units[:, 0], 0) - np.median(a.mu, 0)))


@pytest.mark.parametrize("case", range(4))
def test_censored_marginal_matches_a_fine_grid(case):
    """One unit's censored components integrated over theta_c ~ N(mu_c, s_c^2)
    (censored_marginal, the hat-function quadrature of censored_grids) against the same
    integral by the trapezoid rule on a fine grid of z = (theta - mu) / s (_censored_lik,
    written out independently), one component and two correlated ones (B and K of a 1 h unit,
    correlation -0.79, and a case with both plateaus high), over spreads small and large
    against the likelihood's width and centres on the plateau, at the estimate, at the
    ceiling and above it. Tolerance: the grid's piecewise-linear interpolant errs by about
    (dlogL)^2 / 8 relative on a bin over which the log likelihood changes by dlogL; nodes
    0.13 sd apart in x give 0.002 at the peak, more where the likelihood falls steeply (the
    plateau's knee, the upper edge: at 3 sd of the two-component case 3, 0.027 with s
    small, where the sum is the interpolant itself). Bounds: 0.006 in one component, 0.03
    in two, where the marginal exceeds e^-8; below it (no posterior mass to speak of)
    relative 0.2. The marginal is the leave-one-out table's importance ratio: a smooth
    log error of 0.03 at most (0.01 on the 1 h units' B and K) changes PSIS weights by
    ~1-3 %, well inside their Monte Carlo error.
    """
    from fogbayes.pool.normal import censored_grids, censored_marginal

    cases = [
        ((0.0,), (0.3,), 0.0, (0.5,)),
        ((-2.0,), (1.0,), 0.0, (-1.9 + 0.05,)),
        ((-3.963, -3.246), (0.211, 0.00172), -0.786, (-2.953, 1.081)),
        ((0.0, 0.2), (0.3, 0.5), 0.6, (0.5, 0.4)),
    ]
    y, sd, rho, c = (np.array(a) for a in cases[case][:2] + (cases[case][2],) + cases[case][3:])
    k = y.size
    cov = np.outer(sd, sd) * (np.eye(k) + rho * (1 - np.eye(k)))
    grid = censored_grids(y[None], cov[None], np.ones((1, k)), c[None])
    inv = np.linalg.inv(cov)
    z = np.linspace(-9.0, 9.0, 2401)
    wz = np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi) * np.gradient(z)

    def shift(t, j):
        return np.log((np.exp(2 * t) - np.exp(2 * y[j]) + np.exp(2 * c[j])) / np.exp(2 * c[j]))

    worst = 0.0
    for s in ([0.005, 0.1, 0.5, 2.0] if k == 1 else [0.01, 0.3, 2.0]):
        for mu0 in (y[0] - 2.0, y[0], c[0], c[0] + 0.3):
            for mu1 in ((None,) if k == 1 else (y[1] - 3.0, y[1], c[1] - 2.0, c[1])):
                mu = np.array([mu0] if k == 1 else [mu0, mu1])
                x = [shift(m + s * z, j) for j, m in enumerate(mu)]
                if k == 1:
                    brute = np.log(np.sum(wz * np.exp(-0.5 * inv[0, 0] * x[0] ** 2)))
                else:
                    q = (inv[0, 0] * x[0][:, None] ** 2 + 2 * inv[0, 1] * x[0][:, None] * x[1]
                         + inv[1, 1] * x[1][None] ** 2)
                    brute = np.log(np.sum(wz[:, None] * wz[None] * np.exp(-0.5 * q)) + 1e-300)
                if not brute > -30.0:  # no mass: the grid holds its last value beyond
                    continue
                quad = float(censored_marginal(mu, np.full(k, s), *(a[0] for a in grid)))
                tol = (0.006 if k == 1 else 0.03) if brute > -8 else 0.2 * abs(brute)
                assert abs(quad - brute) < tol, (s, mu, quad, brute)
                worst = max(worst, abs(quad - brute) if brute > -8 else 0.0)
    assert worst > 0.0  # the comparison ran where it matters


def test_three_censored_components_are_the_product_of_their_own_marginals():
    # independent components (diagonal Sigma_cc): the three-component tensor grid (40
    # nodes a component) gives the sum of the one-component log marginals (121 nodes
    # each); measured 0.0075 apart, the coarser grid's interpolation error
    from fogbayes.pool.normal import censored_grids, censored_marginal

    y, c = np.array([[0.0, -1.0, 0.5]]), np.array([[0.3, -0.6, 0.9]])
    cov = np.diag(np.array([0.3, 0.5, 0.2]) ** 2)[None]
    mu, s = np.array([0.1, -1.2, 0.4]), np.array([0.2, 0.5, 0.1])
    three = float(censored_marginal(mu, s, *(a[0] for a in censored_grids(
        y, cov, np.ones((1, 3)), c))))
    one = sum(float(censored_marginal(mu[j:j + 1], s[j:j + 1], *(a[0] for a in censored_grids(
        y[:, j:j + 1], cov[:, j:j + 1, j:j + 1], np.ones((1, 1)), c[:, j:j + 1]))))
        for j in range(3))
    assert abs(three - one) < 0.02
