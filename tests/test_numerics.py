"""calib.numerics: the one R factor and equilibrated condition number of the fits, and
bench.limits.available_memory, the one memory estimate of the size checks."""

from __future__ import annotations

import numpy as np
import pytest

from bench.limits import available_memory
from calib.numerics import design_cond, equilibrated_cond, equilibrated_cond_within, r_factor


def test_r_factor_is_the_qr_factor_up_to_signs():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(200, 3)) * [1.0, 1e3, 1e-2]
    r = r_factor(a)
    r_np = np.linalg.qr(a, mode="r")
    assert np.allclose(np.abs(r), np.abs(r_np), rtol=1e-12, atol=0)
    assert np.allclose(r.T @ r, a.T @ a, rtol=1e-12)
    kept = np.asfortranarray(a.copy())
    r_factor(kept)  # default: the input is left as it was
    assert np.array_equal(kept, a)


def test_condition_of_design_and_of_its_r_factor_agree():
    rng = np.random.default_rng(2)
    h = np.column_stack([np.ones(500), rng.normal(size=500), rng.normal(size=500) * 1e4])
    c = design_cond(h)
    assert c == pytest.approx(equilibrated_cond(r_factor(h)), rel=1e-10)
    hs = h / np.linalg.norm(h, axis=0)
    s = np.linalg.svd(hs, compute_uv=False)
    assert c == pytest.approx(s[0] / s[-1], rel=1e-10)
    assert c < 10  # equilibrated: the 1e4 column scale does not count


@pytest.mark.parametrize("bad", [np.zeros((0, 2)), np.array([[1.0, 0.0], [2.0, 0.0]]),
                                 np.array([[1.0, np.nan], [0.0, 1.0]])])
def test_singular_or_bad_input_has_infinite_condition(bad):
    assert equilibrated_cond(bad) == float("inf")


def test_cond_within_a_limit_bounds_below_it_and_is_exact_above_it():
    """``equilibrated_cond_within`` decides "exceeds the limit" exactly as the SVD does: below
    the limit it may return an upper bound (never above the limit, never below the exact
    value); where the bound does not clear the limit it returns the exact value."""
    rng = np.random.default_rng(3)
    for scale in (1e-6, 1e-3, 1.0, 1e3):
        for _ in range(20):
            h = rng.normal(size=(300, 4)) * [1.0, scale, 1.0, 1e2]
            h[:, 2] += rng.uniform(0.9, 1.0) * h[:, 0]  # correlated columns
            r = r_factor(h)
            exact = equilibrated_cond(r)
            for limit in (exact * 0.5, exact * 2.0, exact * 100.0):
                got = equilibrated_cond_within(r, limit)
                assert (got > limit) == (exact > limit)
                assert got >= exact * (1 - 1e-12)
                assert got <= limit or got == pytest.approx(exact, rel=1e-12)
    near = np.column_stack([np.ones(400), np.ones(400) + 1e-13 * np.arange(400)])
    r = r_factor(near)
    assert equilibrated_cond_within(r, 1e10) == pytest.approx(equilibrated_cond(r), rel=1e-12)
    assert equilibrated_cond_within(np.zeros((2, 2)), 1e10) == float("inf")


def test_available_memory_is_a_positive_byte_count():
    m = available_memory()
    assert isinstance(m, int) and m > 2**20
