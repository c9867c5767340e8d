"""Posterior of a linear-in-parameters model with white or ARMA(p, q) noise (NumPyro NUTS).

On standardised data: y = X beta + e, beta_k ~ N(0, prior_scale), sigma ~ HalfNormal(1); e white,
or ARMA(p, q) with phi = pacf_to_ar(r), theta = pacf_to_ar(s), r, s ~ U(-1, 1) (stationary,
invertible), exact likelihood :func:`fogbayes.models.arma.arma_loglik`. Series are padded to
``bucket_length(n)`` (:mod:`fogbayes.models.buckets`, tail masked). Pointwise log-likelihoods:
Kalman one-step-ahead densities. ``converged``: :mod:`fogbayes.inference.convergence`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import numpyro.distributions as dist
from .nuts import chain_sampler, on_host
from .convergence import converged, ess_floor

from ..errors import FogbayesError
from ..models.arma import arma_loglik, pacf_to_ar
from ..models.buckets import bucket_length
from ..models.statespace import arma_state_space, kalman_filter
from ..stats.mcmc import ess_bulk, ess_tail, over_elements, relative_efficiency, rhat_rank
from ..support.programs import program


class Convergence(NamedTuple):
    r_hat_max: float
    ess_bulk_min: float
    ess_tail_min: float
    divergences: int
    converged: bool


@dataclass(frozen=True)
class BayesFit:
    """Posterior summary of ``beta`` (in the units of ``y`` and the basis of ``X``).

    For a batch (:func:`fit_linear_bayes_batch`) every array has a leading sensor axis and
    ``convergence`` is a list, one per sensor (divergences are counted for the whole run).

    groups: the draws as arrays, ``{"posterior": {beta, sigma, phi, theta} (chain, draw,
        ...) in y units, "sample_stats": {"diverging"}, "observed_data": {"y"},
        "log_likelihood": {"y"} pointwise when asked}``.
    idata: the same as an ArviZ InferenceData, built when first asked for (ArviZ's import
        and the xarray objects cost more than a small posterior's sampling).
    mean, sd: (p,) posterior mean and standard deviation of beta.
    interval: (p, 2) central ``level`` credible interval of beta.
    noise: posterior means {"sigma", "phi", "theta"} (sigma in y units).
    convergence: :class:`Convergence`.
    """

    groups: dict
    mean: np.ndarray
    sd: np.ndarray
    interval: np.ndarray
    level: float
    noise: dict
    convergence: object

    @cached_property
    def idata(self):
        import arviz as az

        return az.from_dict(**self.groups)

    def relative_efficiency(self) -> float:
        """The chains' relative efficiency for PSIS-LOO, as ArviZ's ``loo`` takes it
        (:func:`fogbayes.stats.mcmc.relative_efficiency` of the posterior's components)."""
        return relative_efficiency(self.groups["posterior"].values())


def _log1m_tanh2(u):
    """log(1 - tanh(u)^2) = 2 (log 2 - u - softplus(-2 u)), stable for large |u|."""
    return 2.0 * (jnp.log(2.0) - u - jax.nn.softplus(-2.0 * u))


def _constrain(u: dict) -> dict:
    """Unconstrained -> model parameters: sigma = exp(.), PACFs = tanh(.) -> phi, theta."""
    return {"beta": u["beta"], "sigma": jnp.exp(u["log_sigma"]),
            "phi": pacf_to_ar(jnp.tanh(u["u_ar"])), "theta": pacf_to_ar(jnp.tanh(u["u_ma"]))}


def _log_density(u: dict, X, y, n_valid, prior_scale: float):
    """Log posterior density (up to a constant) of K independent sensors in unconstrained
    coordinates, Jacobians included (module doc; priors as written there), of the first
    ``n_valid`` samples of X (K, n, p), y (K, n)."""
    c = _constrain(u)
    lp = jnp.sum(dist.Normal(0.0, prior_scale).log_prob(u["beta"]))
    lp += jnp.sum(dist.HalfNormal(1.0).log_prob(c["sigma"]) + u["log_sigma"])
    lp += jnp.sum(_log1m_tanh2(u["u_ar"])) + jnp.sum(_log1m_tanh2(u["u_ma"]))  # Uniform(-1, 1)
    resid = y - jnp.einsum("knp,kp->kn", X, u["beta"])
    if u["u_ar"].shape[1] == 0 and u["u_ma"].shape[1] == 0:
        seen = jnp.arange(y.shape[1]) < n_valid
        return lp + jnp.sum(jnp.where(seen, dist.Normal(0.0, c["sigma"][:, None]).log_prob(resid),
                                      0.0))
    ll = jax.vmap(lambda a, b, s2, r: arma_loglik(a, b, s2, r, n_valid=n_valid))
    return lp + jnp.sum(ll(c["phi"], c["theta"], c["sigma"] ** 2, resid))


@lru_cache(maxsize=16)
def _sampler(p: int, q: int, prior_scale: float, num_warmup: int, num_samples: int,
             target_accept: float, shape: tuple[int, int, int]):
    """``run(keys (chains, 2), X, y, n_valid) -> (samples, diverging)``, compiled once per
    configuration and data shape (``n_valid`` is traced: any length held in the shape): :func:`fogbayes.inference.nuts.chain_sampler` on the log density above
    (diagonal mass; one chain's program, the chains side by side in threads: the draws of
    ``lax.map``'s chains one after another, bit for bit), started uniform(-2, 2) in the
    unconstrained space as NumPyro's ``init_to_uniform``."""
    K, _, n_coef = shape
    shapes = {"beta": (K, n_coef), "log_sigma": (K,), "u_ar": (K, p), "u_ma": (K, q)}

    def potential_gen(X, y, n_valid):
        return lambda u: -_log_density(u, X, y, n_valid, prior_scale)

    sample = chain_sampler(potential_gen, num_warmup, num_samples,
                           target_accept_prob=target_accept, dense_mass=False,
                           chain_method="threads",
                           postprocess=lambda u, X, y, n_valid: _constrain(u),
                           store_key=("inference.bayes", p, q, prior_scale))

    def start(key):
        k_init, k_run = jax.random.split(key)
        ks = dict(zip(shapes, jax.random.split(k_init, len(shapes))))
        return k_run, {k: jax.random.uniform(ks[k], shp, minval=-2.0, maxval=2.0)
                       for k, shp in shapes.items()}

    starts = on_host(program(jax.vmap(start)))

    def run(keys, X, y, n_valid):
        k_run, z0 = starts(keys)
        return sample(k_run, z0, X, y, n_valid)

    return run


def _held(X: np.ndarray, y: np.ndarray, bucket: bool):
    """X (K, n, p), y (K, n) with zero samples appended to ``bucket_length(n)`` (``bucket``)."""
    n = y.shape[1]
    nb = bucket_length(n) if bucket else n
    return np.pad(X, ((0, 0), (0, nb - n), (0, 0))), np.pad(y, ((0, 0), (0, nb - n)))


def noise_orders(noise: str, p: int, q: int) -> tuple[int, int]:
    if noise == "white":
        return 0, 0
    if noise in ("ar", "arma") and p >= 0 and q >= 0 and (p + q) > 0:
        return (p, 0) if noise == "ar" else (p, q)
    raise FogbayesError(f"unknown noise model {noise!r} (p={p}, q={q})", column="noise",
                        fix="use noise='white', noise='ar' with p >= 1, or noise='arma'")


def _pointwise(beta, sigma, phi, theta, X, y, n_valid):
    """One-step-ahead log densities (n,) for one draw (white noise: plain normal densities);
    from ``n_valid`` on they are not the series' and are cut off by the caller."""
    r = y - X @ beta
    if phi.shape[0] == 0 and theta.shape[0] == 0:
        return -0.5 * (jnp.log(2 * jnp.pi * sigma**2) + (r / sigma) ** 2)
    f = kalman_filter(arma_state_space(phi, theta, sigma**2), r, n_valid=n_valid)
    return -0.5 * (jnp.log(2 * jnp.pi * f.innov_var) + f.innov**2 / f.innov_var)


def convergence_of(post: dict, diverging, num_chains: int) -> list[Convergence]:
    """Per-sensor convergence of the draws ``post`` {name: (chain, draw, K, ...)}: the worst
    rank-normalised R-hat, bulk and tail ESS over each sensor's components
    (:mod:`fogbayes.stats.mcmc`, ArviZ's arithmetic)."""
    def per_sensor(fn, worst):
        parts = [over_elements(fn, v) for v in post.values()]  # (K, ...) each
        return worst(np.concatenate([a.reshape(a.shape[0], -1) for a in parts], axis=1),
                     axis=1)

    rhat = per_sensor(rhat_rank, np.max)
    ess_b = per_sensor(ess_bulk, np.min)
    ess_t = per_sensor(ess_tail, np.min)
    div = int(np.asarray(diverging).sum())
    return [Convergence(float(r), float(eb), float(et), div,
                        converged(r, eb, div, floor=ess_floor(num_chains)))
            for r, eb, et in zip(rhat, ess_b, ess_t)]


def fit_linear_bayes_batch(X, y, *, seed: int, noise: str = "ar", p: int = 1, q: int = 0,
                           num_warmup: int = 500, num_samples: int = 1000, num_chains: int = 2,
                           level: float = 0.9, prior_scale: float = 10.0,
                           target_accept: float = 0.85, pointwise: bool = False,
                           bucket: bool = False) -> BayesFit:
    """Posteriors of K independent sensors ``y_k = X_k beta_k + e_k`` in one NUTS run.

    The joint posterior factorises over sensors, so each sensor's marginal is exactly its
    own posterior; one compiled sampler then serves a whole batch (fleets, coverage
    studies). X: (K, n, p), y: (K, n); same options as :func:`fit_linear_bayes`.
    ``bucket``: hold the n samples in ``bucket_length(n)`` (module doc).
    """
    p, q = noise_orders(noise, p, q)
    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    my = y.mean(axis=1)
    sy = np.where(y.std(axis=1) > 0, y.std(axis=1), 1.0)
    const = np.flatnonzero((np.ptp(X[0], axis=0) == 0) & (X[0, 0] != 0))
    n = y.shape[1]
    Xb, yb = _held(X, (y - my[:, None]) / sy[:, None], bucket)
    run = _sampler(p, q, float(prior_scale), int(num_warmup), int(num_samples),
                   float(target_accept), Xb.shape)
    keys = jax.random.split(jax.random.PRNGKey(int(seed)), int(num_chains))
    s, diverging = run(keys, jnp.asarray(Xb), jnp.asarray(yb), n)
    beta = np.asarray(s["beta"]) * sy[:, None]  # (chain, draw, K, p)
    if const.size:  # the intercept carries the mean taken out by the standardisation
        beta[..., const[0]] += my / X[:, 0, const[0]]
    post = {"beta": beta, "sigma": np.asarray(s["sigma"]) * sy}
    if p:
        post["phi"] = np.asarray(s["phi"])
    if q:
        post["theta"] = np.asarray(s["theta"])
    stats = {"diverging": np.asarray(diverging)}
    groups = {"posterior": post, "sample_stats": stats, "observed_data": {"y": y}}
    if pointwise:
        groups["log_likelihood"] = {"y": _pointwise_all(post, X, y, bucket)}
    conv = convergence_of(post, stats["diverging"], num_chains)
    flat_beta = beta.reshape((-1,) + beta.shape[2:])  # (draws, K, p)
    tail = (1.0 - level) / 2
    interval = np.moveaxis(np.quantile(flat_beta, [tail, 1.0 - tail], axis=0), 0, -1)
    noise_mean = {"sigma": post["sigma"].mean(axis=(0, 1)),
                  "phi": post["phi"].mean(axis=(0, 1)) if p else np.zeros((len(y), 0)),
                  "theta": post["theta"].mean(axis=(0, 1)) if q else np.zeros((len(y), 0))}
    return BayesFit(groups, flat_beta.mean(0), flat_beta.std(0, ddof=1), interval,
                    float(level), noise_mean, conv)


#: over draws (outer) and sensors (inner); compiled once per shape
_pointwise_draws = program(jax.vmap(jax.vmap(_pointwise, in_axes=(0, 0, 0, 0, 0, 0, None)),
                                    in_axes=(0, 0, 0, 0, None, None, None)))


def _pointwise_all(post: dict, X: np.ndarray, y: np.ndarray, bucket: bool) -> np.ndarray:
    """Pointwise log-likelihood (chain, draw, K, n) of every draw of every sensor."""
    beta = post["beta"]
    c, d, K = beta.shape[:3]
    n = y.shape[1]
    empty = np.zeros((c, d, K, 0))
    args = [jnp.asarray(a).reshape((c * d,) + a.shape[2:])
            for a in (beta, post["sigma"], post.get("phi", empty), post.get("theta", empty))]
    Xb, yb = _held(X, y, bucket)
    ll = _pointwise_draws(*args, jnp.asarray(Xb), jnp.asarray(yb), n)
    return np.asarray(ll)[..., :n].reshape(c, d, K, n)


def fit_linear_bayes(X, y, *, seed: int, noise: str = "ar", p: int = 1, q: int = 0,
                     num_warmup: int = 500, num_samples: int = 1000, num_chains: int = 2,
                     level: float = 0.9, prior_scale: float = 10.0,
                     target_accept: float = 0.85, pointwise: bool = True) -> BayesFit:
    """NUTS posterior of ``y = X beta + e`` with white or ARMA(p, q) noise (module doc).

    Args:
        X: (n, p) design in a centred/scaled basis (columns of order one).
        y: (n,) observations (any unit; standardised inside).
        seed: explicit seed of the sampler.
        noise: "white", "ar" (AR(p)) or "arma" (ARMA(p, q)).
        level: credible level of ``interval`` (central, from posterior quantiles).
        pointwise: compute the pointwise log-likelihood (WAIC/LOO) into
            ``groups["log_likelihood"]``.
    """
    b = fit_linear_bayes_batch(np.asarray(X, float)[None], np.asarray(y, float)[None], seed=seed,
                               noise=noise, p=p, q=q, num_warmup=num_warmup,
                               num_samples=num_samples, num_chains=num_chains, level=level,
                               prior_scale=prior_scale, target_accept=target_accept,
                               pointwise=pointwise, bucket=True)
    groups = {"posterior": {k: v[:, :, 0] for k, v in b.groups["posterior"].items()},
              "sample_stats": dict(b.groups["sample_stats"]),
              "observed_data": {"y": np.asarray(y, float)}}
    if pointwise:
        groups["log_likelihood"] = {"y": b.groups["log_likelihood"]["y"][:, :, 0]}
    noise_mean = {"sigma": float(b.noise["sigma"][0]), "phi": b.noise["phi"][0].tolist(),
                  "theta": b.noise["theta"][0].tolist()}
    return BayesFit(groups, b.mean[0], b.sd[0], b.interval[0], b.level, noise_mean,
                    b.convergence[0])
