"""The compiled compensation loop equals ``y - design(z) @ coef`` for any term set, in
float64 and float32, allocating or in place."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.thermal.compensate import _xla_programs, bias_compensator
from fogbayes.thermal.compensate_loops import compensate_into
from fogbayes.models.polynomial import design, make_basis

CASES = {
    "bias-t cubic": (("T",), ((0,), (1,), (2,), (3,))),
    "thermal with a cross term": (("T", "dT/dt"), ((0, 0), (1, 0), (2, 0), (0, 1), (1, 1))),
    "three covariates": (("T", "dT/dt", "T2"), ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1),
                                                (0, 0, 2), (2, 0, 0))),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_loop_equals_the_design_matrix_form(case):
    names, terms = CASES[case]
    rng = np.random.default_rng(len(terms))
    n = 5000
    z = np.column_stack([rng.uniform(-40, 60, n)] + [rng.normal(0, 3, n)
                                                      for _ in names[1:]])
    basis = make_basis(names, terms, z)
    coef = rng.normal(0, 5, len(terms))
    y = rng.normal(0, 10, n)
    want = y - np.asarray(design(z, basis)) @ coef
    got = compensate_into(basis, coef, z, y, method="loop")
    # the same terms summed in another order: a few roundings of terms reaching ~10 deg/h
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)
    out = np.full(n + 10, np.nan)
    back = compensate_into(basis, coef, z, y, out[5:n + 5], method="loop")  # in place, a view
    assert back.base is out and np.isnan(out[:5]).all() and np.isnan(out[-5:]).all()
    np.testing.assert_array_equal(out[5:n + 5], got)
    # the library's compensator is this loop on a CPU, or the XLA program elsewhere
    lib = np.asarray(bias_compensator(basis).single(coef, z, y))
    np.testing.assert_allclose(lib, want, rtol=0, atol=1e-13)
    # float32: the scaled basis keeps single precision close to float64 (~1e-6 relative)
    y32 = compensate_into(basis, coef.astype(np.float32), z.astype(np.float32),
                          y.astype(np.float32), method="loop")
    assert y32.dtype == np.float32
    np.testing.assert_allclose(y32, want, rtol=0, atol=2e-4 * np.abs(want).max())


def test_without_a_cpu_backend_the_xla_programs_are_used(monkeypatch):
    import jax

    from fogbayes.batch.vectorized import default_solver
    from fogbayes.composite.compensate import build_compensator
    from fogbayes.composite.model import PAPER_000, Scaling, from_raw, raw_predict

    names, terms = CASES["bias-t cubic"]
    rng = np.random.default_rng(9)
    z = rng.uniform(-40, 60, (2000, 1))
    y = rng.normal(0, 10, 2000)
    basis = make_basis(names, terms, z)
    coef = rng.normal(0, 5, len(terms))
    cpu = bias_compensator(basis).single
    T, W, t = rng.uniform(-30, 60, 500), rng.uniform(-80, 80, 500), rng.uniform(0, 60, 500)
    U = raw_predict(PAPER_000, T, W, t)
    sc = Scaling(15.0, 45.0, 80.0, 60.0, float(U.mean()), float(np.abs(U - U.mean()).max()))
    p = from_raw(PAPER_000, sc)
    comp_cpu = build_compensator(p, sc, T_range=(-30, 60), W_range=(-80, 80))
    assert default_solver() == "numba" and comp_cpu.loop is not None
    # what a machine with a GPU selects (the programs themselves run here, on the CPU)
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    bias_compensator.cache_clear()
    try:
        xla = bias_compensator(basis).single
        program = _xla_programs(basis.terms)[0]
        calls = program._cache_size()
        assert xla is not cpu
        np.testing.assert_allclose(np.asarray(xla(coef, z, y)), cpu(coef, z, y), rtol=0,
                                   atol=1e-13)
        assert program._cache_size() == max(calls, 1)  # it ran the term set's XLA program
        assert default_solver() == "gram"
        comp = build_compensator(p, sc, T_range=(-30, 60), W_range=(-80, 80))
        assert comp.loop is None
        np.testing.assert_allclose(np.asarray(comp(U, T, t).rate), comp_cpu(U, T, t).rate,
                                   rtol=1e-12)
    finally:
        bias_compensator.cache_clear()  # later tests build the CPU compensators again


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_numpy_path_is_the_loops_arithmetic(case):
    """A one-off call (no loop compiled yet, few samples) runs the loop's source in NumPy:
    the loop's bits, and no compilation (0.7 s) is paid."""
    from fogbayes.thermal import compensate_loops as cl

    names, terms = CASES[case]
    rng = np.random.default_rng(7 + len(terms))
    n = 3000
    z = np.column_stack([rng.uniform(-40, 60, n)] + [rng.normal(0, 3, n) for _ in names[1:]])
    basis = make_basis(names, terms, z)
    coef, y = rng.normal(0, 5, len(terms)), rng.normal(0, 10, n)
    want = y - np.asarray(design(z, basis)) @ coef  # the reference: the design matrix form
    np.testing.assert_allclose(compensate_into(basis, coef, z, y, method="numpy"), want,
                               rtol=0, atol=1e-13)
    fresh = basis._replace(terms=basis.terms + ((0,) * len(names),))  # never compiled
    coef2 = np.append(coef, 0.0)
    auto = compensate_into(fresh, coef2, z, y)
    assert fresh.terms not in cl._COMPILED_TERMS  # "auto" did not compile it
    np.testing.assert_allclose(auto, want, rtol=0, atol=1e-13)
    by_loop = compensate_into(basis, coef, z, y, method="loop")
    assert basis.terms in cl._COMPILED_TERMS  # once compiled, "auto" uses the loop
    # both run one generated source: the same bits, in float64 and float32
    np.testing.assert_array_equal(compensate_into(basis, coef, z, y, method="numpy"), by_loop)
    z32, y32 = z.astype(np.float32), y.astype(np.float32)
    np.testing.assert_array_equal(compensate_into(basis, coef, z32, y32, method="numpy"),
                                  compensate_into(basis, coef, z32, y32, method="loop"))
