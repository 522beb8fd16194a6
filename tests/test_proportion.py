"""Exact binomial intervals (calib.stats.proportion): known closed forms and their coverage."""

import numpy as np
import pytest
from scipy import stats

from calib.stats.proportion import clopper_pearson, lower_bound


def test_closed_forms_at_the_edges():
    # k = R: the one-sided lower bound is (1 - L)^(1/R) (100 of 100 → 0.9705 at 95 %)
    assert lower_bound(100, 100, 0.95) == pytest.approx(0.05 ** (1 / 100), rel=1e-12)
    lo, hi = clopper_pearson(0, 20)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / 20), rel=1e-12)


def test_coverage_is_at_least_the_level():
    # exact coverage summed over the binomial law: ≥ L for every rate (conservative)
    runs = 30
    k = np.arange(runs + 1)
    ci = np.array([clopper_pearson(int(i), runs) for i in k])
    for p in (0.01, 0.2, 0.5, 0.9, 0.995):
        cover = ((ci[:, 0] <= p) & (p <= ci[:, 1])) @ stats.binom.pmf(k, runs, p)
        assert cover >= 0.95 - 1e-12


def test_bad_counts_are_refused():
    with pytest.raises(ValueError, match="hits"):
        clopper_pearson(5, 3)
