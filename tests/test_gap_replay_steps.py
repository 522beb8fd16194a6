"""The replay's sets of physics steps (``bench.gap.replay._step_union``): the sorted distinct
non-negative steps of its arrays, as ``np.unique`` of their union gives them."""

from __future__ import annotations

import numpy as np

from bench.gap.replay import _step_union


def test_step_union_is_the_sorted_distinct_non_negative_steps():
    rng = np.random.default_rng(55)
    for size in (0, 1, 7, 1000, 30000):
        steps = np.sort(rng.choice(200_000, size=size, replace=False)) if size else \
            np.zeros(0, dtype=int)
        parts = (steps - 1, steps, steps + 1)
        want = np.unique(np.concatenate(parts))
        want = want[want >= 0]
        got = _step_union(*parts)
        assert got.dtype.kind == "i"
        np.testing.assert_array_equal(got, want)
    assert _step_union(np.array([-1]), np.zeros(0, dtype=int)).size == 0
    assert _step_union(np.zeros(0, dtype=int)).size == 0
