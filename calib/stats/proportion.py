"""What a Monte Carlo count supports: exact (Clopper–Pearson) intervals for a proportion.

With ``k`` successes in ``R`` independent runs, the two-sided interval at confidence ``L``::

    lo = Beta⁻¹((1 - L)/2; k, R - k + 1)      (0 when k = 0)
    hi = Beta⁻¹((1 + L)/2; k + 1, R - k)      (1 when k = R)

covers the true rate with probability ≥ L for every rate (exact, conservative). It is the
claim a run count allows: 100 successes in 100 runs bound the rate above 0.964 (one-sided
95 %: ``0.05^(1/100)``), not at 0.997.
"""

from __future__ import annotations

from scipy import stats


def clopper_pearson(hits: int, runs: int, level: float = 0.95) -> tuple[float, float]:
    """Two-sided exact interval ``(lo, hi)`` for a rate from ``hits`` of ``runs`` (module)."""
    if runs < 1 or not 0 <= hits <= runs:
        raise ValueError(f"need 0 ≤ hits ≤ runs and runs ≥ 1, got {hits} of {runs}")
    a = 1.0 - level
    lo = 0.0 if hits == 0 else float(stats.beta.ppf(a / 2, hits, runs - hits + 1))
    hi = 1.0 if hits == runs else float(stats.beta.ppf(1 - a / 2, hits + 1, runs - hits))
    return lo, hi


def lower_bound(hits: int, runs: int, level: float = 0.95) -> float:
    """One-sided exact lower bound on the rate at confidence ``level``."""
    if runs < 1 or not 0 <= hits <= runs:
        raise ValueError(f"need 0 ≤ hits ≤ runs and runs ≥ 1, got {hits} of {runs}")
    return 0.0 if hits == 0 else float(stats.beta.ppf(1 - level, hits, runs - hits + 1))
