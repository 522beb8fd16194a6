"""Uncertainty of the random-walk intensity q: REML profile interval and curvature std."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import optimize

from calib import distributions as stats
from calib.effects import Extensions, ModelState

Q_LEVEL = 0.95
"""Level of the profile-likelihood interval reported for the random-walk intensity q."""


def q_curvature_std(ext: Extensions, state: ModelState, k: int) -> float:
    """std of q from the curvature of the REML -2 log L at q̂ (others fixed): 2 / (d²/dq²).

    Used as the search scale of :func:`q_profile_interval` (and measured against it in
    ``benchmarks/gap_uncertainty_mc.py``); NaN when the curvature is not positive.
    """
    st = state.axes[k]
    q = st.q
    vals = []
    for h in (0.1, 0.03):
        f = [ext.nll(state.with_axis(k, replace(st, q=q * (1 + d))), reml=True)
             for d in (-h, 0.0, h)]
        curv = (f[0] - 2 * f[1] + f[2]) / (h * q) ** 2
        if curv > 0:
            vals.append(float(np.sqrt(2.0 / curv)))
    return vals[-1] if vals else float("nan")


def q_profile_interval(ext: Extensions, state: ModelState, k: int, level: float = Q_LEVEL
                        ) -> tuple[float, float]:
    """Profile-likelihood (REML) interval of the random-walk intensity q of axis k.

    ``{q ≥ 0 : D(q) ≤ χ²₁(level)}`` with ``D(q) = -2 log L_R(q) + 2 log L_R(q̂)`` the REML
    deviance (linear parameters integrated out; the other nonlinear parameters, and σ² when
    ``noise_level`` is named, held at their estimates: their correlation with q̂ is of order
    ``sqrt(n_eff/N)``, n_eff the few low-frequency modes where the walk beats the noise).
    The ends are found by bracketing on log q from q̂ and Brent's method (xtol 1e-5 in log q).

    Boundary q ≥ 0: when ``D(0) ≤ χ²₁(level)`` the lower end is 0. At a true q = 0 the
    deviance of q = 0 follows a mixture with at least half its mass at 0 (``½χ²₀ + ½χ²₁`` or
    more), so the interval then covers with probability ≥ 1 - (1 - level)/2: conservative.
    An effect named by :func:`analyze_gap` has ``D(0)`` far above the threshold.
    """
    st = state.axes[k]
    q_hat = st.q
    crit = float(stats.chi2.ppf(level, 1))
    f0 = ext.nll(state, reml=True)

    def dev(q: float) -> float:
        return ext.nll(state.with_axis(k, replace(st, q=float(q))), reml=True) - f0

    s = q_curvature_std(ext, state, k) / q_hat
    s = s if np.isfinite(s) and s > 0 else 0.1
    u0 = float(np.log(q_hat))

    def end(sign: float) -> float:
        d_in, d = 0.0, 1.5 * s
        for _ in range(60):
            if dev(float(np.exp(u0 + sign * d))) > crit:
                u = optimize.brentq(lambda v: dev(float(np.exp(v))) - crit, u0 + sign * d_in,
                                    u0 + sign * d, xtol=1e-5)
                return float(np.exp(u))
            d_in, d = d, 1.6 * d
            if sign < 0 and d > 40.0:  # q < 4e-18 q̂: the root is next to the boundary
                return float(optimize.brentq(lambda q: dev(q) - crit, 0.0,
                                             q_hat * float(np.exp(-d_in)), xtol=1e-12 * q_hat))
        return float("inf")

    lo = 0.0 if dev(0.0) <= crit else end(-1.0)
    return lo, end(1.0)


def q_uncertainty(ext: Extensions, state: ModelState, k: int
                   ) -> tuple[float, tuple[float, float]]:
    """(std, 95 % interval) reported for the random-walk intensity q of axis k.

    q is a variance component informed only by the few low-frequency modes where the walk
    beats the white noise, so q̂ is skewed (low more often than high). The honest statement is
    the REML profile-likelihood interval (:func:`q_profile_interval`, asymmetric); the std is
    derived from it, ``std = (high - low) / (2·1.96)`` in q units (the average of its two
    half-widths over the normal quantile), so ``q̂ ± 1.96 std`` spans the same length.

    Chosen by measurement (``benchmarks/gap_uncertainty_mc.py``: analyze_gap end to end,
    static full-turn designs (uniform and 24 held positions), N = 2000-3000, q√N = 1-4 σ,
    six cases of R = 400; a 95 % coverage has the binomial tolerance ±0.044):

    * profile interval: coverage 0.940-0.958, misses 1.3-2.5 % low and 2.3-4 % high;
    * this std: sd((q̂ - q)/std) = 0.97-1.05, mean -0.06 to -0.19, ``q̂ ± 1.96 std`` covers
      0.925-0.953 (the symmetric statement inherits the skew: it misses high more often);
    * the former curvature std (:func:`q_curvature_std`): about as good on average
      (sd 0.98-1.05; the "1.2×" once stated for it is not reproduced), but its symmetric
      interval covered 0.925-0.95 with misses 0.5-1.5 % low and 4-6 % high; the exact expected
      REML information on log q (spectral form) was no better (sd 1.00-1.07, its log-scale
      Wald interval covered 0.938-0.953; the curvature on log q, 0.943-0.959). The profile
      interval needs no quadratic approximation and handles the boundary q = 0, so it is what
      is reported.

    Falls back to the curvature std if an end of the interval is not finite.
    """
    lo, hi = q_profile_interval(ext, state, k)
    std = (hi - lo) / (2.0 * float(stats.norm.ppf(0.5 + Q_LEVEL / 2.0)))
    if not np.isfinite(std):
        std = q_curvature_std(ext, state, k)
    return float(std), (lo, hi)

