"""Packed parameter records: offsets from field names, and the compiled unpacking."""

from typing import NamedTuple

import numpy as np
import pytest

from pipefollow.learners import cacla_act
from pipefollow.sim import records


class Inner(NamedTuple):
    a: float = 1.0
    pair: tuple[float, float] = (2.0, 3.0)


class Outer(NamedTuple):
    x: float = 0.5
    inner: Inner = Inner()
    flag: bool = True
    n: int = 7


def test_offsets_and_sizes_follow_the_fields_by_hand():
    assert records.size(Inner()) == 3 and records.size(Outer()) == 6
    assert records.offsets(Outer()) == {"x": 0, "inner": 1, "flag": 4, "n": 5}
    packed = records.pack(Outer())
    np.testing.assert_array_equal(packed, [0.5, 1.0, 2.0, 3.0, 1.0, 7.0])
    with pytest.raises(TypeError, match="NamedTuple record"):
        records.pack((1.0, 2.0))


def test_cacla_parameters_unpack_field_by_field():
    values = dict(
        alpha_v=0.3, alpha_pi=0.1, discount=0.7, skew=0.25, gamma_max=1.5, supervised=True, delta_k=0.02,
        k_max=0.9, forgetting=0.01, skew_sample=2, skew_step=1, k_update=1, k_step=0,
    )  # fmt: skip
    p = cacla_act.CaclaParams(**values)
    assert all(getattr(p, k) == v for k, v in values.items())
    back = cacla_act.unpack(cacla_act.pack(p))
    assert back._fields == p._fields
    for name in p._fields:  # by name: a shifted slot would show
        assert float(getattr(back, name)) == float(getattr(p, name)), name
