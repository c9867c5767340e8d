"""After the README's two set-up commands: is the package that Python imports the real one?

Run from outside the repository. Fails when ``import fogbayes`` finds a namespace package
(a leftover ``site-packages/fogbayes`` folder without ``__init__``), when float64 is off,
or when anything but pip's own files sits in an installed copy of the package.
"""

import sys
from pathlib import Path

import fogbayes

assert getattr(fogbayes, "__file__", None), f"fogbayes is a namespace package: {fogbayes.__path__}"
import jax  # noqa: E402  (after fogbayes, as users do)
import jax.numpy as jnp  # noqa: E402

assert jax.config.jax_enable_x64 and jnp.ones(1).dtype == jnp.float64, "float64 is off"
from fogbayes.stats.allan import allan_deviation  # noqa: E402,F401  (the demo's import)

for site in map(Path, sys.path):
    stray = [p for p in (site / "fogbayes").rglob("*") if p.suffix in (".nbi", ".nbc")] \
        if (site / "fogbayes").is_dir() and site.name == "site-packages" else []
    assert not stray, f"files written into the installed package: {stray[:3]}"
print(f"fogbayes {fogbayes.__version__} from {Path(fogbayes.__file__).parent}: float64 on")
