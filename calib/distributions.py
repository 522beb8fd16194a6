"""The distributions and normality tests the analysis needs, from ``scipy.special`` alone.

Importing ``scipy.stats`` costs ≈ 0.55 s (its hundred distributions, ``scipy.ndimage`` and
the array-API machinery) on the 2-core machine, GIL-bound, ahead of every analysis; the
modules on the ``tiltbench gap`` path use a handful of its functions. This module gives them
with the same names and call forms (``chi2.logsf(x, k)``, ``norm.ppf(q)``,
``kurtosistest(z, alternative="greater")``), computed by the same special functions
``scipy.stats`` calls (``scipy/stats/_continuous_distns.py``: ``chdtrc``, ``chdtri``,
``gammaincinv``, ``ndtr``, ``log_ndtr``, ``ndtri``, ``stdtrit``, ``fdtrc``, ``kolmogorov``)
and the same formulas for the tests (D'Agostino 1970; Anscombe & Glynn 1983; D'Agostino &
Pearson 1973; Bartlett 1937, as in ``scipy/stats/_stats_py.py`` and ``_morestats.py``), so the
values agree with ``scipy.stats`` to rounding (``tests/test_distributions.py``).

Support rules as in ``scipy.stats`` (standard location and scale): below the support the
survival function is 1 (log 0) and the distribution function 0; NaN stays NaN. Scalars in,
floats out; arrays in, arrays out.

Why by hand: these are thin wrappers; the library's own would cost the import.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from scipy import special as sc

TestResult = namedtuple("TestResult", ("statistic", "pvalue"))
"""``(statistic, pvalue)``, as ``scipy.stats``' test results unpack and read."""


def _out(x: np.ndarray) -> float | np.ndarray:
    return float(x) if np.ndim(x) == 0 else x


def _arr(x) -> np.ndarray:
    return np.asarray(x, dtype=float)


def _log(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.log(x)


def _quantile(q, df, inside, at0: float, at1: float):
    """A quantile function with ``scipy.stats``' edges: ``inside(q, df)`` for 0 < q < 1, the
    support's ends ``at0`` at q = 0 and ``at1`` at q = 1, NaN elsewhere."""
    q, df = np.broadcast_arrays(_arr(q), _arr(df))
    within = (q > 0) & (q < 1)
    val = inside(np.where(within, q, 0.5), df)
    return _out(np.where(within, val, np.where(q == 0, at0, np.where(q == 1, at1, np.nan))))


class _Chi2:
    """χ²(k) on [0, ∞)."""

    @staticmethod
    def sf(x, df):
        x, df = np.broadcast_arrays(_arr(x), _arr(df))
        return _out(np.where(x < 0, 1.0, sc.chdtrc(df, np.maximum(x, 0.0))))

    @staticmethod
    def cdf(x, df):
        x, df = np.broadcast_arrays(_arr(x), _arr(df))
        return _out(np.where(x < 0, 0.0, sc.chdtr(df, np.maximum(x, 0.0))))

    @classmethod
    def logsf(cls, x, df):
        """``log sf``, as ``scipy.stats``: ``log(sf)`` above the median, ``log1p(−cdf)``
        below it (where sf is near 1)."""
        x, df = np.broadcast_arrays(_arr(x), _arr(df))
        upper = x > 2.0 * sc.gammaincinv(df / 2.0, 0.5)
        with np.errstate(divide="ignore"):
            return _out(np.where(upper, _log(_arr(cls.sf(x, df))),
                                 np.log1p(-_arr(cls.cdf(x, df)))))

    @classmethod
    def logcdf(cls, x, df):
        """``log cdf``, as ``scipy.stats``: ``log(cdf)`` below the median, ``log1p(−sf)``
        above it."""
        x, df = np.broadcast_arrays(_arr(x), _arr(df))
        lower = x < 2.0 * sc.gammaincinv(df / 2.0, 0.5)
        with np.errstate(divide="ignore"):
            return _out(np.where(lower, _log(_arr(cls.cdf(x, df))),
                                 np.log1p(-_arr(cls.sf(x, df)))))

    @staticmethod
    def ppf(q, df):
        return _quantile(q, df, lambda p, k: 2.0 * sc.gammaincinv(k / 2.0, p), 0.0, np.inf)

    @staticmethod
    def isf(q, df):
        return _quantile(q, df, lambda p, k: sc.chdtri(k, p), np.inf, 0.0)


class _Norm:
    """The standard normal."""

    @staticmethod
    def cdf(x):
        return _out(sc.ndtr(_arr(x)))

    @staticmethod
    def sf(x):
        return _out(sc.ndtr(-_arr(x)))

    @staticmethod
    def logcdf(x):
        return _out(sc.log_ndtr(_arr(x)))

    @staticmethod
    def logsf(x):
        return _out(sc.log_ndtr(-_arr(x)))

    @staticmethod
    def pdf(x):
        x = _arr(x)
        return _out(np.exp(-x * x / 2.0) / np.sqrt(2.0 * np.pi))

    @staticmethod
    def ppf(q):
        return _out(sc.ndtri(_arr(q)))

    @staticmethod
    def isf(q):
        return _out(-sc.ndtri(_arr(q)))


class _T:
    """Student's t with ``df`` degrees of freedom."""

    @staticmethod
    def ppf(q, df):
        return _quantile(q, df, lambda p, k: sc.stdtrit(k, p), -np.inf, np.inf)


class _F:
    """Fisher's F(dfn, dfd) on [0, ∞)."""

    @staticmethod
    def sf(x, dfn, dfd):
        x, dfn, dfd = np.broadcast_arrays(_arr(x), _arr(dfn), _arr(dfd))
        return _out(np.where(x < 0, 1.0, sc.fdtrc(dfn, dfd, np.maximum(x, 0.0))))


class _Kolmogorov:
    """The limiting distribution of √n·D_n (Kolmogorov's), on [0, ∞)."""

    @staticmethod
    def sf(x):
        x = _arr(x)
        return _out(np.where(x < 0, 1.0, sc.kolmogorov(np.maximum(x, 0.0))))


chi2 = _Chi2()
norm = _Norm()
t = _T()
f = _F()
kstwobign = _Kolmogorov()


def _central(a: np.ndarray) -> tuple[np.ndarray, float]:
    a = _arr(a).ravel()
    return a - a.mean(), float(a.mean())


def _moments(a) -> tuple[float, float, float, float]:
    """(n, m2, m3, m4): the sample size and the central moments (biased, 1/n)."""
    d, mean = _central(a)
    d2 = d * d
    m2, m3, m4 = float(np.mean(d2)), float(np.mean(d2 * d)), float(np.mean(d2 * d2))
    flat = m2 <= (np.finfo(float).eps * mean) ** 2
    return float(d.size), (np.nan if flat else m2), m3, m4


def skew(a) -> float:
    """Sample skewness ``m3 / m2^1.5`` (biased; NaN for a constant sample)."""
    _, m2, m3, _ = _moments(a)
    return float(m3 / m2**1.5)


def kurtosis(a) -> float:
    """Excess kurtosis (Fisher) ``m4 / m2² − 3`` (biased; NaN for a constant sample)."""
    _, m2, _, m4 = _moments(a)
    return float(m4 / m2**2 - 3.0)


def _skew_z(a) -> float:
    """D'Agostino's (1970) normal score of the sample skewness (n ≥ 8)."""
    n = float(np.size(a))
    if n < 8:
        raise ValueError(f"skewtest needs at least 8 samples, got {int(n)}")
    y = skew(a) * np.sqrt(((n + 1) * (n + 3)) / (6.0 * (n - 2)))
    beta2 = (3.0 * (n**2 + 27 * n - 70) * (n + 1) * (n + 3)
             / ((n - 2.0) * (n + 5) * (n + 7) * (n + 9)))
    w2 = -1 + np.sqrt(2 * (beta2 - 1))
    delta = 1 / np.sqrt(0.5 * np.log(w2))
    alpha = np.sqrt(2.0 / (w2 - 1))
    y = 1.0 if y == 0 else y
    return float(delta * np.log(y / alpha + np.sqrt((y / alpha) ** 2 + 1)))


def _kurtosis_z(a) -> float:
    """Anscombe & Glynn's (1983) normal score of the sample kurtosis (n ≥ 5)."""
    n = float(np.size(a))
    if n < 5:
        raise ValueError(f"kurtosistest needs at least 5 samples, got {int(n)}")
    b2 = kurtosis(a) + 3.0
    e = 3.0 * (n - 1) / (n + 1)
    varb2 = 24.0 * n * (n - 2) * (n - 3) / ((n + 1) * (n + 1.0) * (n + 3) * (n + 5))
    x = (b2 - e) / varb2**0.5
    sqrtbeta1 = (6.0 * (n * n - 5 * n + 2) / ((n + 7) * (n + 9))
                 * ((6.0 * (n + 3) * (n + 5)) / (n * (n - 2) * (n - 3))) ** 0.5)
    a_ = 6.0 + 8.0 / sqrtbeta1 * (2.0 / sqrtbeta1 + (1 + 4.0 / (sqrtbeta1**2)) ** 0.5)
    term1 = 1 - 2 / (9.0 * a_)
    denom = 1 + x * (2 / (a_ - 4.0)) ** 0.5
    term2 = np.nan if denom == 0 else np.sign(denom) * ((1 - 2.0 / a_) / abs(denom)) ** (1 / 3)
    return float((term1 - term2) / (2 / (9.0 * a_)) ** 0.5)


def kurtosistest(a, alternative: str = "two-sided") -> TestResult:
    """Anscombe & Glynn's kurtosis test: Z ~ N(0, 1) under normality; p for ``alternative``
    "two-sided", "greater" (heavier tails) or "less"."""
    z = _kurtosis_z(a)
    p = {"greater": norm.sf(z), "less": norm.cdf(z),
         "two-sided": 2.0 * norm.sf(abs(z))}[alternative]
    return TestResult(z, float(p))


def normaltest(a) -> TestResult:
    """D'Agostino & Pearson's omnibus test: K² = Z_skew² + Z_kurt² ~ χ²(2) under normality."""
    k2 = _skew_z(a) ** 2 + _kurtosis_z(a) ** 2
    return TestResult(float(k2), float(chi2.sf(k2, 2)))


def bartlett(*samples) -> TestResult:
    """Bartlett's test of equal variances of k ≥ 2 samples: T ~ χ²(k − 1) under equality."""
    k = len(samples)
    if k < 2:
        raise ValueError("bartlett needs at least two samples")
    ni = np.array([np.size(s) for s in samples], dtype=float)
    ssq = np.array([np.var(_arr(s), ddof=1) for s in samples])
    ntot = ni.sum()
    spsq = np.sum((ni - 1) * ssq) / (ntot - k)
    numer = (ntot - k) * np.log(spsq) - np.sum((ni - 1) * np.log(ssq))
    denom = 1 + 1 / (3 * (k - 1)) * (np.sum(1 / (ni - 1)) - 1 / (ntot - k))
    stat = float(numer / denom)
    return TestResult(max(stat, 0.0), float(chi2.sf(stat, k - 1)))
