"""Declared effects given as one string: refused in one line that shows the tuple to write."""

from __future__ import annotations

import pytest


def test_one_string_for_the_declared_effects_is_refused_with_the_tuple_to_write():
    from fogbayes.errors import ArgumentError
    from fogbayes.loop.declared import check_declared

    with pytest.raises(ArgumentError) as e:
        check_declared("temperature_rate", "bias-t", where="declared")
    assert "declared=('temperature_rate',)" in e.value.fix
    assert check_declared("", "bias-t") == ()
