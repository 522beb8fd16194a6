"""Moments of a quantized Gaussian reading (exact, beyond Sheppard's lsb²/12)."""

from __future__ import annotations

import numpy as np
from scipy import stats


def quantized_moments(mu: np.ndarray, sigma2: float, lsb: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of ``lsb·round((μ + v)/lsb)``, v ~ N(0, σ²), per sample.

    Sums over the lattice points within ±8σ of μ (the rest has probability < 1e-15).
    """
    s = np.sqrt(sigma2)
    if s == 0:
        return lsb * np.floor(mu / lsb + 0.5), np.zeros_like(mu)
    span = int(np.ceil(8 * s / lsb)) + 1
    base = np.floor(mu / lsb + 0.5)
    m1 = np.zeros_like(mu)
    m2 = np.zeros_like(mu)
    for j in range(-span, span + 1):
        level = (base + j) * lsb
        p = (stats.norm.cdf((level + lsb / 2 - mu) / s)
             - stats.norm.cdf((level - lsb / 2 - mu) / s))
        m1 += p * level
        m2 += p * level * level
    return m1, np.maximum(m2 - m1 * m1, 1e-300)

