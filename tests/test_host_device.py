"""``host_device``: sequential JAX work (the loop's Kalman scans, NUTS chains) runs on the CPU
device even where an accelerator is JAX's default (benchmarks/RESULTS_gpu.md: 2.6-3.1x
faster there); on a CPU-only machine it changes nothing."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from fogbayes.support import lazy as _lazy
from fogbayes.inference.nuts import on_host


def test_on_a_cpu_machine_nothing_changes():
    before = jax.config.jax_default_device
    with _lazy.host_device():
        assert jax.config.jax_default_device is before
        x = jnp.arange(3.0) * 2
    assert x.devices() == {jax.devices("cpu")[0]}


def test_where_an_accelerator_is_the_default_the_work_goes_to_the_cpu(monkeypatch):
    # JAX here has only its CPU backend; make it report an accelerator as the default
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    before = jax.config.jax_default_device
    seen = []

    def compiled(a):
        seen.append(jax.config.jax_default_device)
        return a + 1

    assert on_host(compiled)(1) == 2
    assert seen == [jax.devices("cpu")[0]]
    assert jax.config.jax_default_device is before  # restored on the way out
