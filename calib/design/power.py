"""Analytic power of the gap's likelihood-ratio test for effects linear in their parameter.

With σ² known the gap tests a linear extension h (N × k columns, coefficient c) on top of the
nominal model H = [1, A_r] per axis by ``LR = (RSS_H - RSS_[H,h]) / σ²``
(:class:`calib.effects.linear.LinearEffect`, :mod:`calib.effects.tilt`). When the readings
carry the effect, ``y = Hβ + h c + v``, ``LR ~ χ²_k(λ)``, non-central with

    λ = ‖(I - P_H) h c‖² / σ²                        (summed over the axes it acts on)

(P_H the orthogonal projection on H's columns, from a Householder QR; never a normal matrix).
The gap names the effect when ``LR > χ²_{k, 1-α}``, so the power is
``P(χ²_k(λ) > χ²_{k,1-α}) = ncx2.sf(χ²_{k,1-α}, k, λ)``. λ is quadratic in c: the smallest
coefficient with power p is ``c_p = sqrt(λ_p / λ₁)``, λ₁ = λ at unit c (fixed direction), λ_p
solving ``ncx2.sf(crit, k, λ_p) = p`` (Brent).

α: the gap's per-step threshold ``α_step = family_alpha / m`` (:mod:`calib.gap.selection`,
m = testable candidates + 2 lattice tests). The analytic power is that of the *first step*
test (the effect alone on the nominal model): the real selection also needs the effect to
win its step and survive ties (:mod:`calib.gap.confusions`), which the pair powers address.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg, optimize, stats


def residual_norm2(basis: np.ndarray, v: np.ndarray) -> float:
    """``‖(I - P_B) v‖²`` for columns ``basis`` (n × p) by a Householder QR of [B | v]."""
    a = np.column_stack([basis, v])
    r = linalg.qr(a, mode="r")[0]
    return float(r[a.shape[1] - 1, a.shape[1] - 1] ** 2) if r.shape[0] >= a.shape[1] else 0.0


def noncentrality(basis: np.ndarray, signal: np.ndarray) -> float:
    """λ = ‖(I - P_B) s‖² of a whitened signal s (rows already divided by σ)."""
    return residual_norm2(basis, signal)


def critical(alpha: float, df: int) -> float:
    """``χ²_{df, 1-α}``."""
    return float(stats.chi2.isf(alpha, df))


LAMBDA_SURE = 1e12
"""Non-centrality beyond which the power is 1 to double precision (:func:`power_from_lambda`)."""


def power_from_lambda(lam: float | np.ndarray, df: int, crit: float) -> np.ndarray:
    """``P(χ²_df(λ) > crit)`` (λ = 0: the central χ², i.e. the false-alarm rate).

    λ > :data:`LAMBDA_SURE`: exactly 1 (scipy's ``ncx2.sf`` returns NaN from λ ≈ 1e20, e.g. a
    stated σ² of 1e-50); there the mean df + λ lies ≥ 10⁵ standard deviations
    ``sqrt(2(df + 2λ))`` above any finite-α critical value (crit < 10⁴ for α ≥ 1e-300).
    """
    lam = np.asarray(lam, dtype=float)
    out = stats.ncx2.sf(crit, df, np.clip(lam, 1e-300, LAMBDA_SURE))
    return np.where(lam > LAMBDA_SURE, 1.0, np.where(lam > 0, out, stats.chi2.sf(crit, df)))


def lambda_for_power(p: float, df: int, crit: float) -> float:
    """λ with ``P(χ²_df(λ) > crit) = p`` (p above the false-alarm rate), by Brent."""
    if not stats.chi2.sf(crit, df) < p < 1.0:
        raise ValueError(f"power {p} must lie between the false-alarm rate and 1")
    hi = 1.0
    while float(power_from_lambda(hi, df, crit)) < p:
        hi *= 2.0
    return float(optimize.brentq(lambda x: float(power_from_lambda(x, df, crit)) - p, 0.0, hi,
                                 xtol=1e-12, rtol=1e-13))


def detection_power(lam_unit: float, c: float, df: int, alpha: float) -> float:
    """Power at coefficient c for ``λ = λ₁·c²`` (λ₁: λ at unit coefficient)."""
    return float(power_from_lambda(lam_unit * c * c, df, critical(alpha, df)))
