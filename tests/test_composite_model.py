"""Composite model (paper 000): evaluation, parameterisations, raw <-> scaled coefficients.

The independent reference is the simulator's term-by-term evaluation of eq. 14 from the
raw coefficients (fogbayes.simulate.effects.paper000_output), written separately from the
model's Horner/scaled implementation.
"""

import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.composite.model import (PAPER_000, PAPER_ORDERS, FullParams, Orders,
                                       OrdersError, ProductParams, RawCoefficients, Scaling,
                                       design_matrix, from_raw, full_to_product, n_params, pack,
                                       param_labels, parse_orders, predict, product_to_full,
                                       raw_covariance, raw_map, raw_offset, raw_predict, to_raw,
                                       unpack)
from fogbayes.simulate import effects as fx

SC = Scaling(T_ref=15.0, T_scale=45.0, W_scale=80.0, t_scale=60.0, U_ref=4.0, U_scale=3200.0)
RNG = np.random.default_rng(0)
T = RNG.uniform(-30, 60, 200)
W = RNG.uniform(-80, 80, 200)
t = RNG.uniform(0, 60, 200)


def test_paper_constants_match_the_simulator():
    # two transcriptions of eq. 15/16/12 (ours and the simulator's) must agree exactly
    np.testing.assert_array_equal(PAPER_000.M, fx.PAPER000_M)
    np.testing.assert_array_equal(PAPER_000.c, fx.PAPER000_U0)
    np.testing.assert_array_equal(PAPER_000.d, fx.PAPER000_U1)


def test_predict_matches_term_by_term_reference():
    ref = fx.paper000_output(T, W, t)
    p = from_raw(PAPER_000, SC)
    # float64 with outputs up to ~3200 V: 1e-12 relative is ~300 ulp of headroom for the
    # basis change (binomial expansion) and Horner's rule
    np.testing.assert_allclose(predict(p, SC, T, W, t), ref, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(raw_predict(PAPER_000, T, W, t), ref, rtol=1e-13, atol=1e-10)


def test_raw_round_trip_is_exact():
    back = to_raw(from_raw(PAPER_000, SC), SC)
    for a, b in zip(back, PAPER_000):
        # coefficients span 1e1 .. 1e-12: compare each relative to itself
        np.testing.assert_allclose(a, b, rtol=1e-10)


def test_design_matrix_is_the_linear_model():
    p = from_raw(PAPER_000, SC)
    X = design_matrix(PAPER_ORDERS, SC, T, W, t)
    assert X.shape == (T.size, n_params(PAPER_ORDERS)) == (200, 18)
    np.testing.assert_allclose(SC.U_ref + SC.U_scale * X @ pack(p), predict(p, SC, T, W, t),
                               rtol=1e-12, atol=1e-9)
    # the raw map and offset take the packed scaled vector to the paper's coefficients
    raw_vec = np.concatenate([PAPER_000.M.ravel(), PAPER_000.c, PAPER_000.d])
    scaled = np.asarray(pack(p))
    np.testing.assert_allclose(raw_map(PAPER_ORDERS, SC) @ scaled + raw_offset(PAPER_ORDERS, SC),
                               raw_vec, rtol=1e-10)


def test_pack_unpack_and_labels():
    o = Orders(1, 2, 3, 0)
    th = jnp.arange(n_params(o), dtype=float)
    p = unpack(th, o)
    assert p.M.shape == (2, 3) and p.c.shape == (4,) and p.d.shape == (1,)
    np.testing.assert_array_equal(pack(p), th)
    assert param_labels(o)[:3] == ["M[0,0]", "M[0,1]", "M[0,2]"] and param_labels(o)[-1] == "d[0]"


def test_product_form_is_rank_one_and_round_trips():
    a = jnp.array([1.0, -0.02, 0.003])
    b = jnp.array([-0.001, -0.13, 0.0007])
    pp = ProductParams(a, b, jnp.array([0.1, 0.2, 0.0]), jnp.array([1e-3, 0.0, 0.0]))
    full = product_to_full(pp)
    assert np.linalg.matrix_rank(np.asarray(full.M), tol=1e-12) == 1
    np.testing.assert_allclose(full.M[:, 0], a)  # b'_0 = 1: column 0 is S1
    back = full_to_product(full)
    np.testing.assert_allclose(back.a, a, rtol=1e-12)
    np.testing.assert_allclose(back.b, b, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(predict(pp, SC, T, W, t), predict(full, SC, T, W, t), rtol=1e-13)


def test_raw_covariance_maps_draws():
    # the covariance map must agree with pushing samples through the raw map
    cov = np.diag(np.full(18, 1e-6))
    draws = RNG.multivariate_normal(np.zeros(18), cov, size=4000)
    emp = np.cov((draws @ raw_map(PAPER_ORDERS, SC).T).T)
    mod = raw_covariance(cov, PAPER_ORDERS, SC)
    sd_e, sd_m = np.sqrt(np.diag(emp)), np.sqrt(np.diag(mod))
    # 4000 draws: standard deviations within ~2 % (1 sigma 1.1 %), correlations within 0.1
    np.testing.assert_allclose(sd_e, sd_m, rtol=0.05)
    np.testing.assert_allclose(emp / np.outer(sd_e, sd_e), mod / np.outer(sd_m, sd_m), atol=0.1)


@pytest.mark.parametrize("text", ["2,3,2", "a,b,c,d", "2,3,2,9", "-1,0,0,0"])
def test_bad_orders_raise_a_fogbayes_error(text):
    with pytest.raises(OrdersError, match="orders"):
        parse_orders(text)


def test_parse_orders_and_raw_shapes():
    assert parse_orders(" 2, 3 ,2,2") == PAPER_ORDERS
    assert parse_orders(None) == PAPER_ORDERS
    raw = to_raw(FullParams(jnp.ones((2, 2)), jnp.ones(1), jnp.ones(3)), SC)
    assert isinstance(raw, RawCoefficients) and raw.M.shape == (2, 2) and raw.d.shape == (3,)


def test_one_orders_grammar_for_fit_and_loop():
    """`--orders` means the same in `fit -m composite` and `loop -m composite`: three values
    set u1 = u0 (paper 000), u1 '-' is no drift term (the loop's default; fit refuses it)."""
    from fogbayes.loop.bases import ModelNameError
    from fogbayes.loop.bases import parse_orders as loop_orders
    from fogbayes.composite.model import read_orders
    from fogbayes.composite.workflow import _orders as fit_orders

    for text, want in [("2,3,2", (2, 3, 2, 2)), ("2,3,2,1", (2, 3, 2, 1)),
                       ("0,0,2,-", (0, 0, 2, None))]:
        assert read_orders(text) == want
        assert loop_orders("composite", text) == want
        if want[3] is not None:
            assert tuple(fit_orders(text)) == want
    assert loop_orders("composite", None) == (0, 0, 2, None)
    with pytest.raises(OrdersError, match="drift"):
        fit_orders("0,0,2,-")
    for bad in ("1,2", "1,2,-", "1,2,3,4,5", "7,0,0,0", "1,2,3,x"):
        with pytest.raises(OrdersError):
            read_orders(bad)
        with pytest.raises(ModelNameError):
            loop_orders("composite", bad)
