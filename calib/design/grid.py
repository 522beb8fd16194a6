"""Monte Carlo power on a grid of sizes, and the smallest size with a given power.

For an effect without an analytic power (:data:`calib.design.signals.SIMULATED`) the power
is estimated at K sizes around the asked one. The grid is geometric in a *strength* s ≥ 0 of
the effect, defined so that the power grows with s and every s > 0 is a valid size:

================ ======================= ============================ =====================
effect           size (unit)             strength s                   size from s
================ ======================= ============================ =====================
lowpass_lag      τ (s)                   τ                            τ = s
bias_random_walk q (m/s²/√s)             q                            q = s
quantization     lsb (m/s²)              lsb                          lsb = s
saturation       limit L (m/s²)          ln(g/L): how far L is below  L = g·e^(−s)  (smaller
                                         the peak reading |A_r| = g   L: stronger)
noise_level      variance v ((m/s²)²)    |ln(v/σ²)|, σ² the stated    v = σ²·(v₀/σ²)^(s/s₀)
                                         variance of the axis         (same side as v₀)
================ ======================= ============================ =====================

Grid: ``s_k = s₀·SPAN^(2k/(K−1) − 1)``, k = 0 … K−1, s₀ the strength of the asked size, so
the grid runs from s₀/SPAN to s₀·SPAN (SPAN = 4: for K = 5 the factors are 1/4, 1/2, 1, 2,
4; odd K contain the asked size itself).

Smallest size with power p: the grid powers p̂_k (R runs each, common random numbers) are
made non-decreasing by the isotonic least-squares fit (pool adjacent violators, equal
weights: every point has R runs); the first grid point k whose fitted power reaches p, and
the size is interpolated linearly in ln s between k − 1 and k:

    ln s_p = ln s_{k−1} + (p − f_{k−1}) / (f_k − f_{k−1}) · (ln s_k − ln s_{k−1}).

When even the smallest grid point reaches p the answer is "< smallest" strength, when none
does "> largest" (a bound, not a value). R runs per point support no more than the exact
(Clopper–Pearson) interval of the power at the bracketing points.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from calib.conventions import AXES

SPAN = 4.0
"""The grid runs from the asked strength /SPAN to ×SPAN."""


def factors(k: int) -> np.ndarray:
    """Strength factors ``SPAN^(2j/(K−1) − 1)``, j = 0 … K−1 (K ≥ 2); the middle one of an
    odd K is exactly 1."""
    if int(k) != k or k < 2:
        raise ValueError(f"a Monte Carlo grid needs K >= 2 sizes, got {k}")
    e = 2.0 * np.arange(k) / (k - 1) - 1.0
    return np.array([1.0 if x == 0 else SPAN**x for x in e])


def strength(name: str, size: float, noise_var: Sequence[float], axis: str, g: float) -> float:
    """Strength s of ``size`` (module table); > 0, else ValueError (no effect to grow)."""
    if name == "saturation":
        s = float(np.log(g / size)) if size > 0 else float("nan")
    elif name == "noise_level":
        s = abs(float(np.log(size / noise_var[AXES.index(axis)])))
    else:
        s = float(size)
    if not (np.isfinite(s) and s > 0):
        why = {"saturation": f"a limit below g = {g:g} m/s²",
               "noise_level": "a variance other than the stated one"}.get(name, "a size > 0")
        raise ValueError(f"a Monte Carlo grid around {name} = {size:g} needs {why}")
    return s


def size_from(name: str, s: float, size0: float, noise_var: Sequence[float], axis: str,
              g: float) -> float:
    """The size of strength ``s`` (inverse of :func:`strength`; ``size0`` the asked size
    fixes the side of the stated variance for noise_level)."""
    if name == "saturation":
        return float(g * np.exp(-s))
    if name == "noise_level":
        v = noise_var[AXES.index(axis)]
        return float(v * np.exp(s if size0 > v else -s))
    return float(s)


def isotonic(p: Sequence[float]) -> np.ndarray:
    """Non-decreasing least-squares fit of ``p`` with equal weights (pool adjacent
    violators): each pooled block takes the mean of its points."""
    blocks: list[list[float]] = []  # [sum, count]
    for v in p:
        blocks.append([float(v), 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            s, c = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += c
    return np.concatenate([np.full(int(c), s / c) for s, c in blocks])


def smallest_strength(s: Sequence[float], fit: Sequence[float], p: float
                      ) -> tuple[float, str, int | None]:
    """(strength, relation, k) for power ``p`` on an increasing strength grid ``s`` with
    non-decreasing fitted powers ``fit``: relation "=" (interpolated in ln s between points
    k − 1 and k), "<" (the first point already reaches p: s is below s_0, k = 0) or ">"
    (no point reaches p: beyond the last, k None)."""
    s, fit = np.asarray(s, float), np.asarray(fit, float)
    hit = np.flatnonzero(fit >= p)
    if hit.size == 0:
        return float(s[-1]), ">", None
    k = int(hit[0])
    if k == 0:
        return float(s[0]), "<", 0
    t = (p - fit[k - 1]) / (fit[k] - fit[k - 1])
    return float(np.exp(np.log(s[k - 1]) + t * (np.log(s[k]) - np.log(s[k - 1])))), "=", k
