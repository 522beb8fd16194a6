"""The analytic N of :mod:`calib.vehicle.nmin`: the arrival covariance as a function of the
calibration size, ``Σ_P(N) = A/N + B`` (θ uniform over [0, 2π), module docstring of
:mod:`calib.vehicle.nmin`), the crossing N of each candidate, the design N (level-L regions pairwise
disjoint) and the a-posteriori N range with the estimate fixed (ours and the course box's).
Positions m, covariances m², N in samples, separations in Mahalanobis units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.conventions import G
from calib.results import ResultMixin
from calib.vehicle.region import ArrivalRegion, chi2_2dof, noise_cov_matrix

N_MAX = 10**12
"""Largest N searched; a crossing beyond it is reported as 'never' (None)."""


def uniform_design_cov(n: int | float, noise_var, g: float = G) -> np.ndarray:
    """Calibration covariance (4×4, order [b_x, s_x, b_y, s_y]) for N uniform θ.

    ``diag(σx², 2σx²/g², σy², 2σy²/g²)/N`` — exact for ``θ_i = 2π i/N``, N ≥ 3, per-axis OLS
    with known σ² (module docstring). Units: m²/s⁴ for biases, dimensionless for scales.
    """
    c = noise_cov_matrix(noise_var)
    sx2, sy2 = c[0, 0], c[1, 1]
    return np.diag([sx2, 2 * sx2 / g**2, sy2, 2 * sy2 / g**2]) / float(n)


@dataclass(frozen=True, eq=False)
class PositionCovModel(ResultMixin):
    """``Σ_P(N) = A/N + B`` for the arrival point, m² (module docstring)."""

    A: np.ndarray
    B: np.ndarray

    _TITLE = "Arrival covariance model Σ_P(N) = A/N + B"
    _UNITS = "A m² (per sample: Σ_P at N = 1 without B); B m²; N samples"

    def to_dict(self) -> dict:
        return {"A": np.asarray(self.A).tolist(), "B": np.asarray(self.B).tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> PositionCovModel:
        """Rebuild from :meth:`to_dict`: ``A``, ``B`` (2, 2) m²."""
        return cls(A=np.array(d["A"], dtype=float), B=np.array(d["B"], dtype=float))

    def summary(self) -> str:
        a, b = np.asarray(self.A), np.asarray(self.B)
        return (f"Σ_P(N) = A/N + B; std at N = 1: ({np.sqrt(a[0, 0] + b[0, 0]):.4g}, "
                f"{np.sqrt(a[1, 1] + b[1, 1]):.4g}) m; N → ∞: ({np.sqrt(b[0, 0]):.4g}, "
                f"{np.sqrt(b[1, 1]):.4g}) m")

    def cov(self, n: float) -> np.ndarray:
        return self.A / float(n) + self.B

    @classmethod
    def from_region(cls, region: ArrivalRegion, g: float = G,
                    include_noise: bool = True) -> PositionCovModel:
        """Build from an :class:`ArrivalRegion` (its Jacobian and noise model).

        The calibration noise is taken equal to the vehicle noise (same sensors).
        """
        A = region.jacobian @ uniform_design_cov(1, region.noise_var, g) @ region.jacobian.T
        B = region.cov_noise if include_noise else np.zeros((2, 2))
        return cls(A=A, B=np.array(B))


def mahalanobis2(delta: np.ndarray, cov: np.ndarray) -> float:
    """``δᵀ Σ⁻¹ δ`` through a solve (no inverse), dimensionless."""
    return float(delta @ np.linalg.solve(cov, delta))


def crossing_n(delta, model: PositionCovModel, threshold: float, n_lo: int = 3,
               n_max: int = N_MAX) -> int | None:
    """Smallest integer ``N ≥ n_lo`` with ``δᵀ Σ_P(N)⁻¹ δ > threshold``; None if none ≤ n_max.

    ``δᵀ Σ_P(N)⁻¹ δ`` is non-decreasing in N, so bisection on integers is exact.
    """
    delta = np.asarray(delta, dtype=float)

    def ok(n: int) -> bool:
        return mahalanobis2(delta, model.cov(n)) > threshold

    if ok(n_lo):
        return n_lo
    if not ok(n_max):
        return None
    lo, hi = n_lo, n_max  # ok(lo) False, ok(hi) True
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ok(mid):
            hi = mid
        else:
            lo = mid
    return hi


def design_nmin(candidates: dict[str, np.ndarray], model: PositionCovModel, level: float
                ) -> dict:
    """Smallest N making all level-L candidate regions pairwise disjoint (module docstring).

    Returns a dict: ``n`` (None when no N suffices), ``limiting_pair`` and
    ``limiting_separation`` (the smallest pairwise Mahalanobis distance with ``B`` alone, the
    N → ∞ limit; None when ``B`` is singular), ``required_separation`` = 2r.
    """
    r2 = chi2_2dof(level)
    names = list(candidates)
    worst, pair = 0, None
    limit_min, limit_pair = np.inf, None
    b_ok = np.linalg.matrix_rank(model.B) == 2
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            delta = np.asarray(candidates[names[i]], float) - np.asarray(candidates[names[j]],
                                                                          float)
            if b_ok:
                lim = np.sqrt(mahalanobis2(delta, model.B))
                if lim < limit_min:
                    limit_min, limit_pair = lim, (names[i], names[j])
            n = crossing_n(delta, model, 4.0 * r2)
            if n is None:
                worst, pair = None, (names[i], names[j])
                break
            if n > worst:
                worst, pair = n, (names[i], names[j])
        if worst is None:
            break
    return {"n": worst, "binding_pair": list(pair) if pair else None,
            "limiting_pair": list(limit_pair) if limit_pair else None,
            "limiting_separation": float(limit_min) if np.isfinite(limit_min) else None,
            "required_separation": float(2.0 * np.sqrt(r2)), "level": level}


def posterior_nrange(estimate, candidates: dict[str, np.ndarray], model: PositionCovModel,
                     level: float) -> dict:
    """N range over which exactly one candidate is inside the region around ``estimate``.

    Returns ``{"n_min", "n_max", "letter", "crossings"}``: decided for
    ``n_min ≤ N ≤ n_max`` (``n_max`` None: for every larger N); ``n_min`` None when never.
    ``crossings[name]`` is the N at which that candidate leaves the region (None: never).
    """
    r2 = chi2_2dof(level)
    est = np.asarray(estimate, dtype=float)
    cross = {k: crossing_n(np.asarray(c, float) - est, model, r2) for k, c in candidates.items()}
    big = float(N_MAX) * 10
    order = sorted(cross, key=lambda k: big if cross[k] is None else cross[k])
    last, second = order[-1], order[-2]
    n_min = cross[second]
    n_end = cross[last]
    if n_min is None or (n_end is not None and n_end <= n_min):
        return {"n_min": None, "n_max": None, "letter": None, "crossings": cross}
    return {"n_min": int(n_min), "n_max": None if n_end is None else int(n_end) - 1,
            "letter": last, "crossings": cross}


def course_box_nrange(estimate, candidates: dict[str, np.ndarray], box_at_n1: np.ndarray
                      ) -> dict:
    """The course criterion's N range with the estimate fixed, box ∝ 1/√N.

    ``box(N) = box(1)/√N`` (uniform θ); candidate i is inside its course ellipse while
    ``N · |(P̂ - c_i)/box(1)|² ≤ 1``, i.e. it leaves at ``N_i = ⌊1/ρ_i²⌋ + 1``.
    """
    est = np.asarray(estimate, dtype=float)
    cross = {}
    for k, c in candidates.items():
        rho2 = float(np.sum(((est - np.asarray(c, float)) / box_at_n1) ** 2))
        cross[k] = None if rho2 == 0 else int(np.floor(1.0 / rho2)) + 1
    big = float(N_MAX) * 10
    order = sorted(cross, key=lambda k: big if cross[k] is None else cross[k])
    n_min, n_end = cross[order[-2]], cross[order[-1]]
    return {"n_min": max(int(n_min), 3) if n_min is not None else None,
            "n_max": None if n_end is None else int(n_end) - 1, "letter": order[-1],
            "crossings": cross}


__all__ = ["N_MAX", "PositionCovModel", "course_box_nrange", "crossing_n", "design_nmin",
           "mahalanobis2", "posterior_nrange", "uniform_design_cov"]
