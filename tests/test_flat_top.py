"""The flat-top (clipping) score with its hinge columns formed and unformed
(``calib.stats.diagnostics.Hinges``): the same score process to rounding, on sweeps, held
poses (repeated |A_r|), a design that spans some hinge columns and a rank-deficient design."""

from __future__ import annotations

import numpy as np
import pytest

from calib.stats.diagnostics import Hinges, flat_top_score, hinge_columns, hinge_levels


def _references(rng: np.random.Generator) -> dict[str, np.ndarray]:
    theta = np.linspace(-3.0, 3.0, 4001) + 0.01 * rng.standard_normal(4001)
    held = np.repeat(np.linspace(-2.5, 2.5, 11), 150)
    return {"sweep x": -9.8 * np.sin(theta), "sweep y": -9.8 * np.cos(theta),
            "held": -9.8 * np.sin(held), "three values": np.repeat([-2.0, -1.0, 1.0], 500),
            # two values: every hinge column is affine in a, spanned by the design (the exact
            # projection of such columns, then skipped)
            "two values": np.tile(np.repeat([1.0, 2.0, 2.0, 1.0, 2.0], 3), 60)}


@pytest.mark.parametrize("design", ["none", "bias and reference", "rank deficient"])
def test_unformed_hinges_score_as_the_formed_ones(design):
    rng = np.random.default_rng(33)
    for name, a in _references(rng).items():
        levels = hinge_levels(a)
        assert levels.size, name
        n, sigma = a.size, 0.7
        r = rng.standard_normal(n)
        d = {"none": None,
             "bias and reference": np.column_stack([np.ones(n), a]) / sigma,
             "rank deficient": np.column_stack([np.ones(n), a, 2.0 * a]) / sigma}[design]
        formed = flat_top_score(r, d, hinge_columns(a, levels) / sigma)
        unformed = flat_top_score(r, d, Hinges(a, levels, sigma))
        np.testing.assert_allclose(unformed, formed, rtol=1e-9, atol=1e-12, err_msg=name)
        hinges = Hinges(a, levels, sigma)
        raw2, prods = hinges.products(np.column_stack([r, np.ones(n)]))
        h = hinge_columns(a, levels) / sigma
        np.testing.assert_allclose(raw2, np.einsum("ij,ij->j", h, h), rtol=1e-12)
        np.testing.assert_allclose(prods, np.column_stack([r, np.ones(n)]).T @ h,
                                   rtol=1e-10, atol=1e-10 * np.abs(h).sum())
        last = levels.size - 1
        np.testing.assert_array_equal(hinges.column(last), h[:, last])
