"""The course question of :mod:`calib.vehicle.nmin`: with THIS vehicle run given (its noise
realisation held fixed), how big must a new calibration be for P(decision made and right) ≥ L?
Estimated from draws of the estimator's sampling law, common to every N (module docstring of
:mod:`calib.vehicle.nmin`). Positions m, covariances m², N in samples, probabilities fractions.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from calib.conventions import G
from calib.vehicle.nmin.scaling import PositionCovModel, uniform_design_cov
from calib.vehicle.region import ArrivalRegion, chi2_2dof, decide, squared_distances

FIXED_RUN_N_MAX = 10**7
"""Largest N the fixed-run search looks at (beyond it: 'not reached')."""

BAND_SIGMAS = 3.0
"""Half-width of the binomial bands, in binomial standard deviations."""


def made_and_right(points: np.ndarray, cov: np.ndarray, cands: np.ndarray, truth: int,
                    r2: float) -> int:
    """How many rows of ``points`` (R, 2) the rule of :func:`calib.vehicle.region.decide` decides
    right: the truth's ``d² = (c - P̂)ᵀ Σ⁻¹ (c - P̂) ≤ r²`` and no other candidate's.

    Vectorised form of :func:`calib.vehicle.region.squared_distances` (whitened by the Cholesky
    factor of ``cov``, no inverse); ``tests/test_nmin_fixed.py`` checks it against ``decide``.
    """
    chol = np.linalg.cholesky(np.asarray(cov, dtype=float))

    def inside(c: np.ndarray, p: np.ndarray) -> np.ndarray:
        dx, dy = c[0] - p[:, 0], c[1] - p[:, 1]
        y1 = dx / chol[0, 0]
        y2 = (dy - chol[1, 0] * y1) / chol[1, 1]
        return y1 * y1 + y2 * y2 <= r2

    sel = points[inside(cands[truth], points)]
    alone = np.ones(sel.shape[0], dtype=bool)
    for k in range(cands.shape[0]):
        if k != truth:
            alone &= ~inside(cands[k], sel)
    return int(np.count_nonzero(alone))


def calibration_draws(jacobian: np.ndarray, noise_var, draws: int, seed: int, g: float = G
                      ) -> np.ndarray:
    """(draws, 2) arrival-point errors of a calibration of N = 1: ``U = J Σ_c1^½ Z``, m.

    ``Z ~ N(0, I₄)`` from ``default_rng(SeedSequence(seed))``; ``U ~ N(0, A)`` with
    ``A = J Σ_c1 Jᵀ`` (module docstring). A calibration of N samples moves the arrival point by
    ``U/√N`` (the sampling law of the estimator, linearised through the Jacobian): the same
    ``U`` serve every N (common random numbers, so the N search compares like with like).
    """
    sd1 = np.sqrt(np.diag(uniform_design_cov(1, noise_var, g)))
    z = np.random.default_rng(np.random.SeedSequence(int(seed))).standard_normal((int(draws), 4))
    return z @ (np.asarray(jacobian, dtype=float) * sd1).T


def fixed_run_probability(n: float, center, draws_u: np.ndarray, model: PositionCovModel,
                          candidates: dict[str, np.ndarray], truth: str, level: float) -> float:
    """P(decision made and right | this vehicle run) at calibration size ``n``, by draws.

    ``P̂ = center + U/√n`` for each row of ``draws_u`` (:func:`calibration_draws`), the region
    drawn with ``Σ_P(n) = A/n + B`` (what the tool draws: it includes the vehicle-noise term),
    decided by the rule of :func:`calib.vehicle.region.decide`. ``center`` (2,) m is the arrival
    point the given run yields with the true calibration.
    """
    names = list(candidates)
    cands = np.array([candidates[k] for k in names], dtype=float)
    pts = np.asarray(center, dtype=float) + draws_u / np.sqrt(float(n))
    k = made_and_right(pts, model.cov(n), cands, names.index(truth), chi2_2dof(level))
    return k / draws_u.shape[0]


def first_n(prob: Callable[[int], float], target: float, grid: np.ndarray,
            values: np.ndarray) -> int | None:
    """Smallest integer N with ``prob(N) ≥ target``: the first grid point that reaches it, then
    bisection on integers between it and the grid point before (monotone within a bracket)."""
    hit = np.nonzero(values >= target)[0]
    if hit.size == 0:
        return None
    i = int(hit[0])
    if i == 0:
        return int(grid[0])
    lo, hi = int(grid[i - 1]), int(grid[i])  # prob(lo) < target <= prob(hi)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if prob(mid) >= target:
            hi = mid
        else:
            lo = mid
    return hi


def fixed_run_nmin(region: ArrivalRegion, truth: str, draws: int = 10**6, seed: int = 0,
                   g: float = G, n_max: int = FIXED_RUN_N_MAX, grid_points: int = 40) -> dict:
    """The course question: with THIS vehicle run given, the smallest N of a new calibration
    such that P(decision made and right) ≥ L.

    Model (plug-in, stated): the vehicle readings — hence their noise realisation — are held
    fixed; only a new calibration of N samples (θ uniform) is drawn, ``ĉ_N ~ N(c, Σ_c1/N)``
    (exact for known σ², per-axis OLS). The true calibration ``c`` is unknown on real data,
    so the arrival point the given run yields with it is taken as ``region.estimate`` (the
    full calibration's), and the true arrival point as the candidate ``truth`` (the one the
    full analysis decides). ``P̂_N = P̂ + J (ĉ_N - c) = P̂ + U/√N`` (linear in the calibration;
    the scale enters as ``1/(1 + s)``, so the remainder is second order, about ``|step|·|Δs|``
    with ``Δs ~ 0.07/√N``: centimetres at N ~ 10³ against a region tens of metres wide —
    checked against the exact map in the tests, and the answer is confirmed by full
    regeneration, :func:`confirm_fixed_run`). The region is the one the tool draws,
    ``Σ_P(N) = A/N + B``.

    The probability is estimated from ``draws`` rows of :func:`calibration_draws` (common to
    every N). It need not be monotone in N: it is evaluated on a geometric grid of
    ``grid_points`` N from 3 to ``n_max`` and refined by integer bisection inside the first
    bracket that reaches L (``monotone_on_grid`` says whether the grid values never drop).

    Returns a dict: ``n`` (None: L not reached up to ``n_max``), ``probability`` at n and
    ``probability_below`` at n - 1; ``draws``, ``seed``, ``std_error`` = √(L(1-L)/draws);
    ``n_band`` = the N at which the estimated curve reaches L ∓ 3·std_error (the draws'
    binomial error propagated to N); ``p_infinity`` (N → ∞: ``P̂ → estimate``, ``Σ_P → B``, so
    1 when ``truth`` alone is inside the B-region at the estimate, else 0); ``reachable``;
    ``monotone_on_grid``; ``truth``; ``level``; ``grid_n`` / ``grid_p`` (the curve).
    """
    level = region.level
    model = PositionCovModel.from_region(region, g)
    u = calibration_draws(region.jacobian, region.noise_var, draws, seed, g)

    memo: dict[int, float] = {}

    def prob(n: int) -> float:
        if n not in memo:
            memo[n] = fixed_run_probability(n, region.estimate, u, model, region.candidates,
                                            truth, level)
        return memo[n]

    grid = np.unique(np.round(np.geomspace(3, n_max, grid_points)).astype(np.int64))
    values = np.array([prob(int(n)) for n in grid])
    se = float(np.sqrt(level * (1.0 - level) / draws))
    n = first_n(prob, level, grid, values)
    band = [first_n(prob, min(level + s * BAND_SIGMAS * se, 1.0), grid, values)
            for s in (-1.0, 1.0)]
    if np.linalg.matrix_rank(model.B) == 2:
        d2 = squared_distances(region.estimate, model.B, region.candidates)
        p_inf = 1.0 if decide(d2, level)[0] == truth else 0.0
    else:  # no vehicle noise: the region shrinks to a point that sits on no candidate
        p_inf = 0.0
    return {
        "n": n, "probability": None if n is None else prob(n),
        "probability_below": None if n is None or n <= 3 else prob(n - 1),
        "draws": int(draws), "seed": int(seed), "std_error": se, "n_band": band,
        "p_infinity": p_inf, "reachable": n is not None, "truth": truth, "level": level,
        "best_probability": float(values.max()),
        "monotone_on_grid": bool(np.all(np.diff(values) >= 0)),
        "grid_n": grid.tolist(), "grid_p": values.tolist(),
    }


__all__ = ["BAND_SIGMAS", "FIXED_RUN_N_MAX", "calibration_draws", "first_n", "fixed_run_nmin",
           "fixed_run_probability", "made_and_right"]
