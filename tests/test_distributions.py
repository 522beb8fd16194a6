"""``calib.distributions`` against ``scipy.stats``: the same values (to rounding) on grids that
reach the tails, the support's edges and NaN, and the same tests on Gaussian, heavy-tailed and
uneven samples. The module exists only to keep ``scipy.stats`` (≈ 0.55 s to import) off the
analysis' import path, so every value it gives must be the library's."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import stats as ref

from calib import distributions as dist

X = np.array([-1.0, 0.0, 1e-12, 0.3, 1.0, 3.84, 10.0, 50.0, 300.0, 2000.0, np.inf, np.nan])
Q = np.array([0.0, 1e-300, 1e-12, 1e-4, 0.025, 0.5, 0.975, 1 - 1e-9, 1.0, np.nan])
Z = np.array([-40.0, -8.0, -1.0, 0.0, 0.5, 3.0, 9.0, 38.0, np.inf, -np.inf, np.nan])


def _same(a, b) -> bool:
    """Equal to 1e-12 relative, infinities (with their signs) and NaN in the same places."""
    return bool(np.allclose(np.asarray(a, float), np.asarray(b, float), rtol=1e-12, atol=0.0,
                            equal_nan=True))


@pytest.mark.parametrize("df", [1, 2, 3.5, 10, 400])
def test_chi2_agrees_with_scipy(df):
    for x in X:
        assert _same(dist.chi2.sf(x, df), ref.chi2.sf(x, df))
        assert _same(dist.chi2.cdf(x, df), ref.chi2.cdf(x, df))
        with np.errstate(divide="ignore"):
            assert _same(dist.chi2.logsf(x, df), ref.chi2.logsf(x, df))
            assert _same(dist.chi2.logcdf(x, df), ref.chi2.logcdf(x, df))
    for q in Q:
        assert _same(dist.chi2.ppf(q, df), ref.chi2.ppf(q, df))
        assert _same(dist.chi2.isf(q, df), ref.chi2.isf(q, df))
    assert _same(dist.chi2.ppf([0.975, 0.025], df), ref.chi2.ppf([0.975, 0.025], df))
    assert isinstance(dist.chi2.logsf(3.0, df), float)


def test_norm_t_f_kolmogorov_agree_with_scipy():
    for z in Z:
        for name in ("cdf", "sf", "logcdf", "logsf", "pdf"):
            assert _same(getattr(dist.norm, name)(z), getattr(ref.norm, name)(z))
        assert _same(dist.kstwobign.sf(z), ref.kstwobign.sf(z))
        assert _same(dist.f.sf(z, 3, 17), ref.f.sf(z, 3, 17))
    for q in Q:
        assert _same(dist.norm.ppf(q), ref.norm.ppf(q))
        assert _same(dist.norm.isf(q), ref.norm.isf(q))
        for df in (1, 4, 30):
            assert _same(dist.t.ppf(q, df), ref.t.ppf(q, df))


@pytest.mark.parametrize("kind", ["gauss", "laplace", "skewed", "short"])
def test_the_normality_tests_agree_with_scipy(kind):
    rng = np.random.default_rng([41, len(kind)])
    z = {"gauss": rng.standard_normal(4001), "laplace": rng.laplace(size=3000),
         "skewed": rng.gamma(2.0, size=500), "short": rng.standard_normal(9)}[kind]
    assert _same(dist.skew(z), ref.skew(z))
    assert _same(dist.kurtosis(z), ref.kurtosis(z))
    for alt in ("two-sided", "greater", "less"):
        mine, theirs = dist.kurtosistest(z, alternative=alt), ref.kurtosistest(z, alternative=alt)
        assert _same(mine.statistic, theirs.statistic)
        assert _same(mine.pvalue, theirs.pvalue)
    k2, p = dist.normaltest(z)
    assert _same(k2, ref.normaltest(z).statistic)
    assert _same(p, ref.normaltest(z).pvalue)
    groups = np.array_split(z, 3)
    assert _same(dist.bartlett(*groups).statistic, ref.bartlett(*groups).statistic)
    assert _same(dist.bartlett(*groups).pvalue, ref.bartlett(*groups).pvalue)


def test_the_analysis_imports_without_scipy_stats():
    """What the point is: the analysis (and the calibration) import without ``scipy.stats``."""
    code = ("import sys, calib.gap, calib.calibration.ls; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False"
