"""The design question of :mod:`calib.vehicle.nmin` with the vehicle noise redrawn as well: the N
from which P(decision made and right) = L, and its asymptote N → ∞ (below L when the vehicle noise
alone cannot separate the candidates). N in samples, probabilities fractions.
"""

from __future__ import annotations

import numpy as np

from calib.vehicle.nmin.fixed_run import made_and_right
from calib.vehicle.nmin.scaling import PositionCovModel, crossing_n
from calib.vehicle.region import chi2_2dof


def redrawn_probability(n: float, model: PositionCovModel, candidates: dict[str, np.ndarray],
                        truth: str, level: float, w: np.ndarray) -> float:
    """P(decision made and right) with the vehicle noise redrawn too, by draws.

    ``P̂ = c_truth + chol(Σ_P(n)) W`` for the rows of ``w`` (R, 2) standard normal: both the
    calibration and the vehicle noise are new. The truth is inside with probability exactly L,
    so this never exceeds L. ``n = inf`` gives the asymptote (``Σ_P = B``).
    """
    names = list(candidates)
    cands = np.array([candidates[k] for k in names], dtype=float)
    cov = model.B if np.isinf(n) else model.cov(n)
    pts = cands[names.index(truth)] + w @ np.linalg.cholesky(cov).T
    return made_and_right(pts, cov, cands, names.index(truth), chi2_2dof(level)) / w.shape[0]


def redrawn_design(candidates: dict[str, np.ndarray], model: PositionCovModel, truth: str,
                   level: float, draws: int = 10**6, seed: int = 0) -> dict:
    """The design question (vehicle noise redrawn as well), with its asymptote.

    P(made and right) ≤ L for every N (the truth is inside with probability L); it equals L
    once the truth's region is disjoint from every other candidate's, i.e. from
    ``n = max_k crossing_n(c_truth - c_k, 4 r²)`` on (exact, :func:`crossing_n`). Its
    asymptote ``p_infinity`` (N → ∞, ``Σ_P → B``) is L exactly when the B-regions are
    disjoint, otherwise estimated from ``draws`` (``p_infinity_std_error``); when it is below
    L, ``reachable`` is False and ``message`` says so plainly.
    """
    r2 = chi2_2dof(level)
    c_t = np.asarray(candidates[truth], dtype=float)
    ns = [crossing_n(c_t - np.asarray(c, float), model, 4.0 * r2)
          for k, c in candidates.items() if k != truth]
    n = None if any(x is None for x in ns) else max(ns, default=3)
    if n is not None:
        p_inf, se = float(level), 0.0
    elif np.linalg.matrix_rank(model.B) < 2:
        p_inf, se = 0.0, 0.0
    else:
        w = np.random.default_rng(np.random.SeedSequence(int(seed))).standard_normal(
            (int(draws), 2))
        p_inf = redrawn_probability(np.inf, model, candidates, truth, level, w)
        se = float(np.sqrt(max(p_inf * (1.0 - p_inf), 0.25 / draws) / draws))
    L = f"{100 * level:g}%"
    msg = (f"P(made and right) ≤ {L} for every N; it reaches {L} at N = {n} and stays there"
           if n is not None else
           f"the level {L} cannot be reached: the best reachable is P_∞ = {p_inf:.5f} "
           f"(± {se:.1g}, N → ∞)")
    return {"n": n, "p_infinity": p_inf, "p_infinity_std_error": se, "reachable": n is not None,
            "truth": truth, "level": level, "draws": int(draws) if n is None else 0,
            "message": msg}


__all__ = ["redrawn_design", "redrawn_probability"]
