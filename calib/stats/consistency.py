"""Is a stated covariance consistent with the errors? Bands for NEES and coverage over R runs.

Normalised estimation error squared of one run, ``d² = eᵀ P⁻¹ e`` (e the estimate minus the
truth, P the stated covariance, ``dof`` = len(e)): χ²(dof) when P is right and the errors
Gaussian. Over R independent runs ``R · mean(d²) ~ χ²(dof·R)``, and the number of runs whose
truth is inside the level-L region is Binomial(R, L). The bands below are the exact two-sided
quantiles of those laws at ``alpha`` (mass ``alpha/2`` each side; default :data:`NEES_ALPHA`,
the mass outside ±4σ of a normal, docs/conventions.md), divided by R: a consistent estimator
leaves a band with probability ≤ ``alpha``.

Along a path (the same R runs judged at M epochs, or T tests in all) the band of each test is
taken at ``alpha/T`` (Bonferroni): a consistent filter then has every test inside with
probability ≥ 1 − ``alpha``. The union bound needs no independence, so it stays valid, and
conservative, when the epochs are correlated in time (the same run's errors).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

NEES_ALPHA = 6.3e-5
"""Default two-sided level of the bands (the mass outside ±4σ of a normal)."""


def nees(e: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``eᵀ P⁻¹ e`` over the leading axes of ``e`` (..., n) and ``P`` (..., n, n) (a solve,
    never an inverse); dimensionless."""
    return np.einsum("...i,...i->...", e, np.linalg.solve(P, e[..., None])[..., 0])


def mean_nees_band(dof: int, runs: int, alpha: float = NEES_ALPHA) -> tuple[float, float]:
    """Band of the mean NEES of ``runs`` runs: ``χ²(dof·R)`` quantiles at ``alpha/2`` and
    ``1 − alpha/2``, divided by R."""
    lo, hi = stats.chi2.ppf([alpha / 2, 1 - alpha / 2], dof * runs)
    return float(lo / runs), float(hi / runs)


def coverage_band(level: float, runs: int, alpha: float = NEES_ALPHA) -> tuple[float, float]:
    """Band of the share of runs whose truth is inside its level-L region: Binomial(R, L)
    quantiles at ``alpha/2`` each side, divided by R (exact: the normal approximation is poor
    at L = 0.997)."""
    lo, hi = stats.binom.ppf([alpha / 2, 1 - alpha / 2], runs, level)
    return float(lo / runs), float(hi / runs)


def path_band(dof: int, runs: int, tests: int, alpha: float = NEES_ALPHA
              ) -> tuple[float, float]:
    """Per-test band of the mean NEES when ``tests`` tests are judged together (module
    docstring): :func:`mean_nees_band` at ``alpha/tests``."""
    return mean_nees_band(dof, runs, alpha / max(int(tests), 1))


def out_ranges(t: np.ndarray, out: np.ndarray) -> list[tuple[float, float]]:
    """The runs of consecutive epochs with ``out`` true, as ``(first t, last t)`` (units of t)."""
    t, out = np.asarray(t, float), np.asarray(out, bool)
    edges = np.diff(np.concatenate([[0], out.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


__all__ = ["NEES_ALPHA", "coverage_band", "mean_nees_band", "nees", "out_ranges", "path_band"]
