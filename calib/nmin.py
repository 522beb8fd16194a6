"""How many calibration samples N are needed to decide the arrival point.

Scaling law (θ uniform over [0, 2π))
------------------------------------
For ``θ_i = 2π i/N`` (``N ≥ 3``) the sums ``Σ sin θ_i = Σ cos θ_i = 0`` and
``Σ sin² θ_i = Σ cos² θ_i = N/2`` hold exactly, so the per-axis design ``H = [1, A_r]`` has
``HᵀH = diag(N, g² N/2)`` and the calibration covariance is (course reports, eq. 54–55, with
the exact ``N/2``)::

    Σ_c(N) = diag(σx², 2σx²/g², σy², 2σy²/g²) / N  =  Σ_c1 / N

Propagated to the arrival point (:mod:`calib.region`)::

    Σ_P(N) = A / N + B,     A = J Σ_c1 Jᵀ,     B = Σ_noise (vehicle run, independent of N)

``Σ_P(N)`` decreases with N (Loewner order), so every Mahalanobis distance
``d_i(N)² = δ_iᵀ Σ_P(N)⁻¹ δ_i`` grows monotonically with N; each candidate leaves the level-L
region at one crossing ``N_i`` (found by bisection on integers) and never comes back.

Three questions
---------------
* **The course question (this vehicle run given)** — the vehicle readings, hence their noise
  realisation, are held fixed and only a NEW calibration of N samples is drawn: the smallest
  N with P(decision made and right) ≥ L (:func:`fixed_run_nmin`). The calibration estimate
  follows its sampling law ``ĉ_N ~ N(c, Σ_c1/N)``; the arrival point moves by
  ``J (ĉ_N - c) = U/√N``; the region drawn is the tool's, ``Σ_P(N) = A/N + B``. Plug-in: on
  real data c is unknown, so the full calibration is taken as the truth and the decided
  candidate as the true arrival point. Estimated from ≥ 10⁵ draws of U (common to every N)
  and confirmed by regenerating calibrations at the answer (:func:`confirm_fixed_run`). On
  the course data: about 4,000 samples.
* **Design (before the run, vehicle noise redrawn too)** — the smallest N for which the
  level-L regions drawn around the candidates are pairwise disjoint:
  ``|c_i - c_j|_Σ(N) > 2 r`` with ``r² = χ²₂(L)``. Then, by the triangle inequality, when the
  truth's region contains the estimate (probability exactly L) no other candidate is inside:
  the decision is made *and* right with probability L — never more, so this N is only where
  the probability touches L. Its asymptote ``P_∞`` (N → ∞, ``Σ_P → B``) is below L when
  the vehicle noise alone cannot separate the candidates: the level cannot be reached
  (:func:`redrawn_design`).
* **A posteriori (this estimate fixed)** — with the estimate ``P̂`` held fixed, exactly one
  candidate is inside for ``N`` in ``[N_(K-1), N_(K))`` (second-largest and largest crossings).
  Below it several candidates are inside; above ``N_(K)`` (if finite) none is.

Why no N can guarantee a decision in general
--------------------------------------------
* The vehicle-noise term ``B`` does not shrink with the calibration N: if two candidates are
  closer than ``2r`` in the metric of ``B`` alone, no calibration, however long, separates
  them (``design`` is then None).
* Candidates can be arbitrarily close, and the estimate can fall between two of them (the
  course report WLS, Figure 8): a posteriori the decision depends on where the estimate
  landed, which no N controls.
* Everything is at a confidence level: with probability ``1 - L`` the truth is outside its
  region whatever N is.
* The linear model itself (white Gaussian noise, bias and scale only, known P0 and V0, no
  rotation) is an assumption; an unmodelled effect does not average out with N.

Monte Carlo checks: :func:`subsample_analysis` redoes the course reports' experiment (calibrate
on every k-th sample of the course run), :func:`confirm_fixed_run` regenerates calibrations
with the vehicle run given, and :func:`simulate_decisions` draws fresh synthetic calibration
and vehicle runs at a given N. Each says what its run count supports: a rate from R runs is
known to ± 3√(p(1-p)/R), and R runs without a failure bound the failure rate only below
≈ 3/R at 95 % (one-sided Clopper–Pearson, :func:`calib.proportion.lower_bound`): 100/100 supports
P ≥ 0.970, not 0.997.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from calib.calibration import Calibration, calibrate
from calib.conventions import G, reference_accel
from calib.correct import apply_errors
from calib.io import Acel, Ensayo, validate_ensayo
from calib.ls import PoorlyIdentifiedWarning
from calib.proportion import lower_bound
from calib.region import (
    AREA_COMPARISON_UNITS,
    ArrivalRegion,
    arrival_region,
    chi2_2dof,
    course_decision,
    decide,
    noise_cov_matrix,
    squared_distances,
)
from calib.results import ResultMixin
from calib.runs import Mapper, chunk_ranges, run_seeds, serial_map
from calib.trajectory import Integrator, compute_trajectory, correct_and_integrate
from calib.units import nest, with_units

N_MAX = 10**12
"""Largest N searched; a crossing beyond it is reported as 'never' (None)."""

COURSE_STEPS = (1, 2, 13, 14)
"""Subsampling steps of the course report LS (every sample, every 2nd, 13th, 14th)."""


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


def _d2(delta: np.ndarray, cov: np.ndarray) -> float:
    return float(delta @ np.linalg.solve(cov, delta))


def crossing_n(delta, model: PositionCovModel, threshold: float, n_lo: int = 3,
               n_max: int = N_MAX) -> int | None:
    """Smallest integer ``N ≥ n_lo`` with ``δᵀ Σ_P(N)⁻¹ δ > threshold``; None if none ≤ n_max.

    ``δᵀ Σ_P(N)⁻¹ δ`` is non-decreasing in N, so bisection on integers is exact.
    """
    delta = np.asarray(delta, dtype=float)

    def ok(n: int) -> bool:
        return _d2(delta, model.cov(n)) > threshold

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
                lim = np.sqrt(_d2(delta, model.B))
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


@dataclass(frozen=True, eq=False)
class SubsampleRow(ResultMixin):
    """One subsampled calibration of the course reports' experiment.

    step : every ``step``-th sample kept.  n : samples.  estimate, std : (2,) m.
    semi_axes : (2,) m.  course_box : (2,) m.  mahalanobis : name → d.  decisions: letter or
    None; ``inside`` / ``course_inside``: candidate names.
    """

    _TITLE = "Subsampled calibration"
    _UNITS = "estimate, std, semi-axes and course box m; Mahalanobis distance dimensionless"

    step: int
    n: int
    estimate: np.ndarray
    std: np.ndarray
    semi_axes: np.ndarray
    mahalanobis: dict
    decision: str | None
    inside: tuple
    calibration_only_decision: str | None
    course_box: np.ndarray
    course_decision: str | None
    course_inside: tuple

    def to_dict(self) -> dict:
        return {"step": self.step, "n": self.n, "estimate": np.asarray(self.estimate).tolist(),
                "std": np.asarray(self.std).tolist(),
                "semi_axes": np.asarray(self.semi_axes).tolist(),
                "mahalanobis": self.mahalanobis, "decision": self.decision,
                "inside": list(self.inside),
                "calibration_only_decision": self.calibration_only_decision,
                "course_box": np.asarray(self.course_box).tolist(),
                "course_decision": self.course_decision,
                "course_inside": list(self.course_inside)}

    @classmethod
    def from_dict(cls, d: dict) -> SubsampleRow:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(int(d["step"]), int(d["n"]), np.array(d["estimate"], dtype=float),
                   np.array(d["std"], dtype=float), np.array(d["semi_axes"], dtype=float),
                   dict(d["mahalanobis"]), d["decision"], tuple(d["inside"]),
                   d["calibration_only_decision"], np.array(d["course_box"], dtype=float),
                   d["course_decision"], tuple(d["course_inside"]))

    def summary(self) -> str:
        return (f"step {self.step}, N = {self.n}: estimate ({self.estimate[0]:.1f}, "
                f"{self.estimate[1]:.1f}) m, std ({self.std[0]:.1f}, {self.std[1]:.1f}) m, "
                f"decision {self.decision or 'undecided'} (inside: "
                f"{', '.join(self.inside) or 'none'}); course box ±({self.course_box[0]:.1f}, "
                f"{self.course_box[1]:.1f}) m, course decision "
                f"{self.course_decision or 'undecided'}")


def subsample_analysis(
    ensayo: Ensayo, acel: Acel, candidates: dict[str, np.ndarray],
    steps: Sequence[int] = COURSE_STEPS, p0=(0.0, 0.0), v0=(1.0, 3.0), noise_var=None,
    level: float = 0.997, method: str = "ols", integrator: Integrator = "trapezoid",
    g: float = G,
) -> list[SubsampleRow]:
    """Calibrate on every ``step``-th sample (``tita[::step]``, as the course's
    ``Tita2(1:paso:N2)``), correct, integrate, decide — ours and the course's box criterion.
    """
    rows = []
    for step in steps:
        if int(step) < 1:
            raise ValueError(f"subsampling step must be >= 1, got {step}")
        sub = validate_ensayo(ensayo.tita[::step], ensayo.datos[::step], None,
                              f"{ensayo.source}[::{step}]")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal = calibrate(sub, noise_var, method, g)  # type: ignore[arg-type]
        traj = compute_trajectory(acel, cal, p0, v0, integrator)
        reg = arrival_region(traj, cal, candidates, noise_var, level)
        reg0 = arrival_region(traj, cal, candidates, noise_var, level, include_noise=False)
        cdec, cin = course_decision(reg.estimate, candidates, reg.course_box_bound)
        rows.append(SubsampleRow(int(step), sub.n, reg.estimate, reg.std,
                                 reg.ellipse.semi_axes, dict(reg.mahalanobis), reg.decision,
                                 reg.inside, reg0.decision, reg.course_box_bound, cdec, cin))
    return rows


@dataclass(frozen=True, eq=False)
class McRow(ResultMixin):
    """Decisions over ``runs`` fresh synthetic (calibration + vehicle) runs at one N."""

    _TITLE = "Synthetic runs"
    _UNITS = "counts of runs; level and rates are fractions (dimensionless); N samples"

    n: int
    runs: int
    right: int
    wrong: int
    undecided: int
    truth_inside: int
    level: float

    def to_dict(self) -> dict:
        return {"n": self.n, "runs": self.runs, "right": self.right, "wrong": self.wrong,
                "undecided": self.undecided, "truth_inside": self.truth_inside,
                "level": self.level, "right_rate": self.right / self.runs,
                "coverage": self.truth_inside / self.runs}

    @classmethod
    def from_dict(cls, d: dict) -> McRow:
        """Rebuild from :meth:`to_dict` (exact; the rates are derived)."""
        return cls(int(d["n"]), int(d["runs"]), int(d["right"]), int(d["wrong"]),
                   int(d["undecided"]), int(d["truth_inside"]), float(d["level"]))

    def summary(self) -> str:
        return (f"N = {self.n}: {self.runs} runs at level {self.level:g}: {self.right} right, "
                f"{self.wrong} wrong, {self.undecided} undecided; truth inside its region in "
                f"{self.truth_inside}")


def synthetic_calibration(n: int, bias, scale, noise_var, rng: np.random.Generator,
                          g: float = G) -> Ensayo:
    """Calibration run with ``θ_i = 2π i/N`` and the course sensor model (numpy only).

    ``datos = (1 + scale)·[-g sin θ, -g cos θ] + bias + v``, ``v ~ N(0, diag(noise_var))``.
    """
    tita = 2.0 * np.pi * np.arange(n) / n
    a_r = reference_accel(tita, g)
    sd = np.sqrt(np.diag(noise_cov_matrix(noise_var)))
    datos = apply_errors(a_r, bias, scale) + sd * rng.standard_normal(a_r.shape)
    return Ensayo(tita, datos, None, source=f"synthetic N={n}")


def simulate_decisions(
    t: np.ndarray, a_true: np.ndarray, candidates: dict[str, np.ndarray], truth: str,
    n: int, runs: int, seed: int, bias, scale, noise_var, p0=(0.0, 0.0), v0=(1.0, 3.0),
    level: float = 0.997, method: str = "ols", integrator: Integrator = "trapezoid",
    g: float = G,
) -> McRow:
    """Decide on ``runs`` fresh synthetic runs at calibration size ``n``.

    Each run draws (from its own stream of ``SeedSequence(seed).spawn(runs)``) a calibration
    run (:func:`synthetic_calibration`) and the vehicle readings
    ``A_m = (1 + scale)·a_true + bias + v``; it calibrates (known σ²), corrects, integrates and
    decides. ``candidates[truth]`` must be the true arrival point.
    """
    nv = noise_cov_matrix(noise_var)
    sd = np.sqrt(np.diag(nv))
    a_true = np.asarray(a_true, dtype=float)
    right = wrong = undecided = inside = 0
    for ss in np.random.SeedSequence(int(seed)).spawn(int(runs)):
        rng = np.random.default_rng(ss)
        ens = synthetic_calibration(n, bias, scale, nv, rng, g)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal: Calibration = calibrate(ens, np.diag(nv), method, g)  # type: ignore[arg-type]
        a_m = apply_errors(a_true, bias, scale) + sd * rng.standard_normal(a_true.shape)
        traj = correct_and_integrate(t, a_m, cal.bias, cal.scale, p0, v0, integrator)
        reg = arrival_region(traj, cal, candidates, nv, level)
        inside += truth in reg.inside
        if reg.decision is None:
            undecided += 1
        elif reg.decision == truth:
            right += 1
        else:
            wrong += 1
    return McRow(int(n), int(runs), right, wrong, undecided, inside, float(level))


# ---------------------------------------------------------------------------------------------
# The course question: the vehicle run given, how big must a NEW calibration be?
# ---------------------------------------------------------------------------------------------

FIXED_RUN_N_MAX = 10**7
"""Largest N the fixed-run search looks at (beyond it: 'not reached')."""

CONFIRM_N_MAX = 10**6
"""Largest N at which the fixed-run answer is confirmed by regenerating calibrations."""

BAND_SIGMAS = 3.0
"""Half-width of the binomial bands, in binomial standard deviations."""


def _made_and_right(points: np.ndarray, cov: np.ndarray, cands: np.ndarray, truth: int,
                    r2: float) -> int:
    """How many rows of ``points`` (R, 2) the rule of :func:`calib.region.decide` decides
    right: the truth's ``d² = (c - P̂)ᵀ Σ⁻¹ (c - P̂) ≤ r²`` and no other candidate's.

    Vectorised form of :func:`calib.region.squared_distances` (whitened by the Cholesky factor
    of ``cov``, no inverse); ``tests/test_nmin_fixed.py`` checks it against ``decide``.
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
    decided by the rule of :func:`calib.region.decide`. ``center`` (2,) m is the arrival point
    the given run yields with the true calibration.
    """
    names = list(candidates)
    cands = np.array([candidates[k] for k in names], dtype=float)
    pts = np.asarray(center, dtype=float) + draws_u / np.sqrt(float(n))
    k = _made_and_right(pts, model.cov(n), cands, names.index(truth), chi2_2dof(level))
    return k / draws_u.shape[0]


def _first_n(prob: Callable[[int], float], target: float, grid: np.ndarray,
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
    n = _first_n(prob, level, grid, values)
    band = [_first_n(prob, min(level + s * BAND_SIGMAS * se, 1.0), grid, values)
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
    return _made_and_right(pts, cov, cands, names.index(truth), chi2_2dof(level)) / w.shape[0]


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


@dataclass(frozen=True, eq=False)
class ConfirmRow(ResultMixin):
    """Full regeneration at one N with the vehicle run given (:func:`confirm_fixed_run`).

    ``predicted`` : P(made and right) from the sampling-law draws at this N. ``band`` :
    ``predicted ± 3 √(p(1-p)/runs)``. ``lower_95`` : one-sided 95 % Clopper–Pearson bound on
    the rate of right decisions — the claim these runs support.
    """

    _TITLE = "Regenerated calibrations, vehicle run given"
    _UNITS = "counts of runs; N samples; rates, bounds and level fractions (dimensionless)"

    n: int
    runs: int
    right: int
    wrong: int
    undecided: int
    level: float
    predicted: float
    seed: int

    @property
    def rate(self) -> float:
        return self.right / self.runs

    @property
    def band(self) -> tuple[float, float]:
        h = BAND_SIGMAS * np.sqrt(self.predicted * (1.0 - self.predicted) / self.runs)
        return float(self.predicted - h), float(self.predicted + h)

    @property
    def consistent(self) -> bool:
        lo, hi = self.band
        return lo <= self.rate <= hi

    @property
    def lower_95(self) -> float:
        return lower_bound(self.right, self.runs, 0.95)

    def to_dict(self) -> dict:
        return {"n": self.n, "runs": self.runs, "right": self.right, "wrong": self.wrong,
                "undecided": self.undecided, "level": self.level,
                "predicted": self.predicted, "seed": self.seed, "rate": self.rate,
                "band": list(self.band), "consistent": self.consistent,
                "lower_95": self.lower_95}

    @classmethod
    def from_dict(cls, d: dict) -> ConfirmRow:
        """Rebuild from :meth:`to_dict` (exact; rate, band and bound are derived)."""
        return cls(int(d["n"]), int(d["runs"]), int(d["right"]), int(d["wrong"]),
                   int(d["undecided"]), float(d["level"]), float(d["predicted"]),
                   int(d["seed"]))

    def summary(self) -> str:
        lo, hi = self.band
        verdict = "consistent with" if self.consistent else "OUTSIDE"
        return (f"N = {self.n}: {self.runs} regenerated calibrations, {self.right} right, "
                f"{self.wrong} wrong, {self.undecided} undecided: rate {self.rate:.5f}, "
                f"{verdict} the predicted {self.predicted:.5f} (3σ band [{lo:.5f}, "
                f"{min(hi, 1.0):.5f}]); these runs support P(made and right) ≥ "
                f"{self.lower_95:.5f} at 95 % (one-sided), no more")


def _confirm_chunk(task: tuple) -> tuple[int, int, int]:
    """Runs ``task[0]`` (a range) of :func:`confirm_fixed_run`: (right, wrong, undecided)."""
    (runs, seed, n, t, a_m, candidates, truth, bias, scale, nv, p0, v0, level, method,
     integrator, g) = task[1:]
    seeds = run_seeds(seed, runs)
    right = wrong = undecided = 0
    for k in task[0]:
        rng = np.random.default_rng(seeds[k])
        ens = synthetic_calibration(n, bias, scale, nv, rng, g)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal = calibrate(ens, nv, method, g)  # type: ignore[arg-type]
        traj = correct_and_integrate(t, a_m, cal.bias, cal.scale, p0, v0, integrator)
        dec = arrival_region(traj, cal, candidates, nv, level).decision
        if dec is None:
            undecided += 1
        elif dec == truth:
            right += 1
        else:
            wrong += 1
    return right, wrong, undecided


def confirm_fixed_run(
    acel: Acel, candidates: dict[str, np.ndarray], truth: str, n: int, runs: int, seed: int,
    bias, scale, noise_var, predicted: float, p0=(0.0, 0.0), v0=(1.0, 3.0),
    level: float = 0.997, method: str = "ols", integrator: Integrator = "trapezoid",
    g: float = G, mapper: Mapper | None = None,
    progress: Callable[[int, int], None] | None = None, chunk: int = 250,
) -> ConfirmRow:
    """Check the fixed-run answer by full regeneration: ``runs`` new calibrations of ``n``.

    Run k draws from ``run_seeds(seed, runs)[k]`` a calibration run (:func:`synthetic_calibration`
    with the plug-in truth ``bias`` (2,) m/s², ``scale`` (2,)), calibrates it (known σ²),
    corrects and integrates the GIVEN vehicle run ``acel`` with it (exact, no linearisation),
    draws the region and decides (:func:`calib.region.arrival_region`). The counts do not
    depend on ``mapper`` (:mod:`calib.runs`) or ``chunk``. ``progress(done, total)`` counts
    chunks.
    """
    nv = np.diag(noise_cov_matrix(noise_var))
    cands = {k: np.asarray(c, dtype=float) for k, c in candidates.items()}
    common = (int(runs), int(seed), int(n), np.asarray(acel.t, float),
              np.asarray(acel.aerr, float), cands, truth, np.asarray(bias, float),
              np.asarray(scale, float), nv, tuple(p0), tuple(v0), float(level), method,
              integrator, float(g))
    tasks = [(r, *common) for r in chunk_ranges(int(runs), chunk)]
    out = (mapper or serial_map)(_confirm_chunk, tasks, progress)
    right, wrong, undecided = (int(sum(x[i] for x in out)) for i in range(3))
    return ConfirmRow(int(n), int(runs), right, wrong, undecided, float(level),
                      float(predicted), int(seed))


@dataclass(frozen=True, eq=False)
class NminResult(ResultMixin):
    """Result of the N analysis (see the module docstring for the definitions).

    level : L.  n_data : N of the data.  estimate : (2,) arrival point, m.  decision :
    letter or None.  design*, posterior* : dicts of :func:`design_nmin` /
    :func:`posterior_nrange` / :func:`course_box_nrange` (N in samples, separations
    dimensionless Mahalanobis units).  subsample : :class:`SubsampleRow` s.  monte_carlo :
    :class:`McRow` s.  notes : caveats.  area_comparison : areas m² and ratios.
    ``NminResult.from_dict(r.to_dict()) == r`` (exact).
    """

    _TITLE = "N analysis"
    _UNITS = ("N in samples; positions and box sizes m; areas m²; separations in Mahalanobis "
              "units (dimensionless); level a fraction")

    level: float
    n_data: int
    estimate: np.ndarray
    decision: str | None
    design: dict
    design_calibration_only: dict
    posterior: dict
    posterior_calibration_only: dict
    posterior_course_box: dict
    subsample: tuple = ()
    monte_carlo: tuple = ()
    notes: tuple = field(default_factory=tuple)
    area_comparison: dict = field(default_factory=dict)
    fixed_run: dict = field(default_factory=dict)
    confirmation: tuple = ()
    redrawn: dict = field(default_factory=dict)

    _JSON_UNITS = {  # the units of to_dict(), one home (docs/units.md)
        "level": "1", "n_data": "count", "estimate": "m",
        **{f"{k}.{leaf}": u for k in ("design", "design_calibration_only")
           for leaf, u in (("level", "1"), ("n", "count"), ("required_separation", "1"),
                           ("limiting_separation", "1"), ("*", "1"))},
        **{f"{k}.{leaf}": "count" for k in ("posterior", "posterior_calibration_only",
                                            "posterior_course_box")
           for leaf in ("n_min", "n_max", "crossings.*", "*")},
        "subsample.step": "count", "subsample.n": "count", "subsample.estimate": "m",
        "subsample.std": "m", "subsample.semi_axes": "m", "subsample.course_box": "m",
        "subsample.mahalanobis.*": "1",
        "monte_carlo.n": "count", "monte_carlo.level": "1", "monte_carlo.right_rate": "1",
        "monte_carlo.coverage": "1", "monte_carlo.*": "count",
        **nest("area_comparison", AREA_COMPARISON_UNITS),
        "fixed_run.n": "count", "fixed_run.n_band": "count", "fixed_run.draws": "count",
        "fixed_run.seed": "count", "fixed_run.grid_n": "count", "fixed_run.*": "1",
        "confirmation.n": "count", "confirmation.runs": "count", "confirmation.right": "count",
        "confirmation.wrong": "count", "confirmation.undecided": "count",
        "confirmation.seed": "count", "confirmation.*": "1",
        "redrawn.n": "count", "redrawn.draws": "count", "redrawn.*": "1",
    }

    def to_dict(self) -> dict:
        return with_units({
            "level": self.level, "n_data": self.n_data,
            "estimate": np.asarray(self.estimate).tolist(), "decision": self.decision,
            "design": self.design, "design_calibration_only": self.design_calibration_only,
            "posterior": self.posterior,
            "posterior_calibration_only": self.posterior_calibration_only,
            "posterior_course_box": self.posterior_course_box,
            "subsample": [r.to_dict() for r in self.subsample],
            "monte_carlo": [r.to_dict() for r in self.monte_carlo],
            "notes": list(self.notes), "area_comparison": self.area_comparison,
            "fixed_run": self.fixed_run,
            "confirmation": [r.to_dict() for r in self.confirmation],
            "redrawn": self.redrawn,
        }, self._JSON_UNITS)

    @classmethod
    def from_dict(cls, d: dict) -> NminResult:
        """Rebuild from :meth:`to_dict` (exact, also through JSON).

        Examples
        --------
        >>> from calib.nmin import NminResult
        >>> r = NminResult.from_dict({
        ...     "level": 0.95, "n_data": 10, "estimate": [0.0, 0.0], "decision": None,
        ...     "design": {}, "design_calibration_only": {}, "posterior": {},
        ...     "posterior_calibration_only": {}, "posterior_course_box": {}})
        >>> NminResult.from_dict(r.to_dict()) == r
        True
        """
        return cls(
            level=float(d["level"]), n_data=int(d["n_data"]),
            estimate=np.array(d["estimate"], dtype=float), decision=d["decision"],
            design=dict(d["design"]), design_calibration_only=dict(d["design_calibration_only"]),
            posterior=dict(d["posterior"]),
            posterior_calibration_only=dict(d["posterior_calibration_only"]),
            posterior_course_box=dict(d["posterior_course_box"]),
            subsample=tuple(SubsampleRow.from_dict(r) for r in d.get("subsample", ())),
            monte_carlo=tuple(McRow.from_dict(r) for r in d.get("monte_carlo", ())),
            notes=tuple(d.get("notes", ())), area_comparison=dict(d.get("area_comparison", {})),
            fixed_run=dict(d.get("fixed_run", {})),
            confirmation=tuple(ConfirmRow.from_dict(r) for r in d.get("confirmation", ())),
            redrawn=dict(d.get("redrawn", {})),
        )

    def summary(self) -> str:
        L = f"{100 * self.level:g}%"

        def rng_txt(d: dict) -> str:
            if d["n_min"] is None:
                return "never"
            hi = "∞" if d["n_max"] is None else f"{d['n_max']}"
            return f"{d['letter']} for {d['n_min']} ≤ N ≤ {hi}"

        def design_txt(d: dict) -> str:
            if d["n"] is None:
                lim = d["limiting_separation"]
                extra = (f"; with infinite N the closest pair {'/'.join(d['limiting_pair'])} "
                         f"is {lim:.2f} apart, {d['required_separation']:.2f} needed"
                         if lim is not None else "")
                return f"no N suffices (pair {'/'.join(d['binding_pair'])}{extra})"
            return f"N ≥ {d['n']} (binding pair {'/'.join(d['binding_pair'])})"

        out = [
            f"N analysis at {L} (θ uniform over [0, 2π); data: N = {self.n_data}, "
            f"decision {self.decision or 'undecided'})",
        ]
        if self.fixed_run:
            f = self.fixed_run
            out.append(f"  this vehicle run given (the course question): new calibration of "
                       f"N samples, P(decision made and right = {f['truth']}) ≥ {L}:")
            if f["n"] is None:
                out.append(f"    the level {L} cannot be reached with this run: the best "
                           f"reachable is P = {f['best_probability']:.5f} (N ≤ "
                           f"{FIXED_RUN_N_MAX}; N → ∞: P = {f['p_infinity']:g})")
            else:
                lo, hi = f["n_band"]
                out.append(
                    f"    N ≥ {f['n']} (P = {f['probability']:.5f} there, "
                    f"{f['probability_below']:.5f} at N - 1; {f['draws']} draws from the "
                    f"estimator's sampling law, std error {f['std_error']:.1g}: N between "
                    f"{lo} and {hi} at ±3σ; N → ∞: P = {f['p_infinity']:g})")
            for c in self.confirmation:
                out.append(f"    regeneration check: {c.summary()}")
        if self.redrawn:
            r = self.redrawn
            out.append(f"  design, vehicle noise redrawn too (truth {r['truth']}): "
                       f"{r['message']}; asymptote P_∞ = {r['p_infinity']:.5f}")
        out += [
            f"  design, full region (decided and right with prob ≥ {L}): "
            f"{design_txt(self.design)}",
            f"  design, calibration part only (course assumption, no vehicle noise): "
            f"{design_txt(self.design_calibration_only)}",
            f"  a posteriori (this estimate fixed), full region : {rng_txt(self.posterior)}",
            f"  a posteriori, calibration part only            : "
            f"{rng_txt(self.posterior_calibration_only)}",
            f"  a posteriori, course box criterion (3σ)        : "
            f"{rng_txt(self.posterior_course_box)}",
        ]
        if self.area_comparison:
            a = self.area_comparison
            out.append(f"  {L} ellipse area / course box area (same level, N = {self.n_data}): "
                       f"{a['ratio_to_course_box']:.3f}; calibration part alone: "
                       f"{a['calibration_only_ratio_to_course_box']:.3f}")
        if self.subsample:
            out.append("  subsampled course calibration (course report LS, section 3.2.4):")
            out.append(f"  {'step':>5}{'N':>7}{'x (m)':>9}{'y (m)':>9}{'ours':>7}{'inside':>10}"
                       f"{'cal-only':>9}{'box x (m)':>10}{'box y (m)':>10}{'course':>8}"
                       f"{'inside':>10}")
            for r in self.subsample:
                out.append(
                    f"  {r.step:>5}{r.n:>7}{r.estimate[0]:>9.1f}{r.estimate[1]:>9.1f}"
                    f"{r.decision or '-':>7}{','.join(r.inside) or '-':>10}"
                    f"{r.calibration_only_decision or '-':>9}{r.course_box[0]:>10.1f}"
                    f"{r.course_box[1]:>10.1f}{r.course_decision or '-':>8}"
                    f"{','.join(r.course_inside) or '-':>10}")
        if self.monte_carlo:
            out.append("  fresh synthetic runs, vehicle noise redrawn (truth at the decided "
                       "candidate):")
            out.append(f"  {'N':>8}{'runs':>6}{'right':>7}{'wrong':>7}{'undecided':>10}"
                       f"{'truth inside':>14}")
            for m in self.monte_carlo:
                out.append(f"  {m.n:>8}{m.runs:>6}{m.right:>7}{m.wrong:>7}{m.undecided:>10}"
                           f"{m.truth_inside:>14}   supports P(right) ≥ "
                           f"{lower_bound(m.right, m.runs):.4f} at 95 %")
        out.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(out)


NOTES = (
    "no N can guarantee a decision in general: the vehicle-noise part of the arrival "
    "covariance does not shrink with the calibration N, candidates may be arbitrarily close "
    "(or the estimate may fall between two), and at level L the truth is outside its region "
    "with probability 1 - L whatever N is",
    "the fixed-run N answers the course question (this vehicle run given, a new calibration "
    "drawn; plug-in: the full calibration is the truth, the decided candidate the arrival "
    "point); the design N redraws the vehicle noise as well, so there P(made and right) never "
    "exceeds L: it makes the level-L regions pairwise disjoint and only touches L; the "
    "a-posteriori range holds only for this estimate",
    "the course box bound leaves out the vehicle noise and uses worst-case |a|max: it is too "
    "wide in the calibration part and too narrow overall",
)


def analyze_nmin(
    ensayo: Ensayo, acel: Acel, candidates: dict[str, np.ndarray], p0=(0.0, 0.0),
    v0=(1.0, 3.0), noise_var=None, level: float = 0.997, method: str = "ols",
    integrator: Integrator = "trapezoid", g: float = G, steps: Sequence[int] = COURSE_STEPS,
    mc_n: Sequence[int] = (), runs: int = 0, seed: int = 0,
    progress: Callable[[str], None] | None = None, draws: int = 0, confirm_runs: int = 0,
    mapper: Mapper | None = None, count: Callable[[int, int], None] | None = None,
    calibration: Calibration | None = None,
) -> NminResult:
    """The whole N analysis on one data set (e.g. the course files).

    With ``calibration`` (a :class:`calib.Calibration`, e.g. loaded from a calibration file)
    the estimates, σ² and N come from it and ``ensayo`` may be None: every part of the
    analysis but the course's subsampling experiment needs only them (the sampling law and
    the regenerated runs assume θ uniform over a turn, as everywhere here); the subsampling
    re-fits every k-th sample of the ensayo, so it is skipped without one.

    Analytic design and a-posteriori N (module docstring), the course's subsampling
    experiment, and — when ``runs > 0`` — fresh synthetic runs at each N of ``mc_n`` (plus
    the design N when finite and ≤ 10⁶). Synthetic runs use the corrected accelerations of
    the data as the true profile, the calibration estimate as the true sensor errors, and the
    candidates translated so the decided one (or the nearest) is the true arrival point.
    ``progress`` (optional) is called with a short message before each long step.

    Parameters
    ----------
    ensayo : the calibration run (``tita`` (N,) rad, ``datos`` (N, 2) m/s²); None with
        ``calibration``.
    acel : the vehicle run (``t`` (M,) s, ``aerr`` (M, 2) m/s²).
    candidates : name → (2,) candidate arrival point, m.
    p0 : (2,) initial position, m.  v0 : (2,) initial velocity, m/s.
    noise_var : (2,) noise variances, (m/s²)², or None (estimated).
    level : confidence level L.  method : "ols" or "wls".  integrator : "trapezoid" or
        "simpson".  g : gravity, m/s².
    steps : subsampling steps of the course experiment (every k-th sample; () skips it).
    mc_n : calibration sizes N for fresh synthetic runs (vehicle noise redrawn).
    runs : runs per N (0: none).  seed : seed of the draws and of the synthetic runs.
    draws : draws from the calibration's sampling law for the fixed-run N
        (:func:`fixed_run_nmin`; 0: skipped).  confirm_runs : regenerated calibrations at the
        fixed-run answer (:func:`confirm_fixed_run`, when N ≤ ``CONFIRM_N_MAX``; 0: none).
    mapper : runs the regeneration (:mod:`calib.runs`; default in-process).
    count : ``count(done, total)`` chunks of the regeneration done.
    calibration : use this calibration instead of fitting ``ensayo`` (see above).

    Returns
    -------
    NminResult : design and a-posteriori N, subsampling rows, synthetic-run rows.

    Examples
    --------
    >>> import numpy as np
    >>> from calib import Acel, Ensayo, analyze_nmin
    >>> th = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
    >>> e = Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]))
    >>> a = Acel(np.arange(1001) * 0.01, np.zeros((1001, 2)))
    >>> r = analyze_nmin(e, a, {"A": [10.0, 30.0], "B": [60.0, 30.0]}, noise_var=[0.25, 0.64],
    ...                  steps=())
    >>> r.decision, r.design["n"] is not None
    ('A', True)
    """
    say = progress or (lambda _msg: None)
    if calibration is None:
        if ensayo is None:
            raise ValueError("analyze_nmin needs an ensayo or a calibration")
        cal = calibrate(ensayo, noise_var, method, g)  # type: ignore[arg-type]
    else:
        cal = calibration
        method, g = cal.method, cal.g
    traj = compute_trajectory(acel, cal, p0, v0, integrator)
    reg = arrival_region(traj, cal, candidates, noise_var, level)
    full = PositionCovModel.from_region(reg, g)
    calonly = PositionCovModel.from_region(reg, g, include_noise=False)
    box1 = reg.course_box_bound * np.sqrt(cal.n)  # box ∝ 1/√N for uniform θ
    rows = []
    if steps and ensayo is not None:
        say(f"subsampling the calibration (steps {list(steps)})")
        rows = subsample_analysis(ensayo, acel, candidates, steps, p0, v0, noise_var, level,
                                  method, integrator, g)
    design = design_nmin(candidates, full, level)
    truth = reg.decision or min(reg.mahalanobis, key=reg.mahalanobis.get)
    fixed: dict = {}
    confirm = []
    if draws > 0:
        say(f"fixed-run N: {draws} draws from the calibration's sampling law")
        fixed = fixed_run_nmin(reg, truth, draws, seed, g)
        if confirm_runs > 0 and fixed["n"] is not None and fixed["n"] <= CONFIRM_N_MAX:
            say(f"regenerating {confirm_runs} calibrations of N = {fixed['n']} "
                "(vehicle run given)")
            confirm.append(confirm_fixed_run(
                acel, candidates, truth, fixed["n"], confirm_runs, seed, cal.bias, cal.scale,
                reg.noise_var, fixed["probability"], p0, v0, level, method, integrator, g,
                mapper, count))
    redrawn = redrawn_design(candidates, full, truth, level, max(draws, 10**5), seed)
    mc = []
    if runs > 0:
        ns = list(mc_n)
        if design["n"] is not None and design["n"] <= 10**6 and design["n"] not in ns:
            ns.append(int(design["n"]))
        shift = reg.estimate - np.asarray(candidates[truth], float)
        moved = {k: np.asarray(c, float) + shift for k, c in candidates.items()}
        for i, n in enumerate(ns):
            say(f"synthetic runs {i + 1}/{len(ns)}: {runs} calibrations of N = {int(n)}")
            mc.append(simulate_decisions(acel.t, traj.acc_corrected, moved, truth, int(n), runs,
                                         seed + i, cal.bias, cal.scale, reg.noise_var, p0, v0,
                                         level, method, integrator, g))
    return NminResult(
        level=level, n_data=cal.n, estimate=reg.estimate, decision=reg.decision,
        design=design,
        design_calibration_only=design_nmin(candidates, calonly, level),
        posterior=posterior_nrange(reg.estimate, candidates, full, level),
        posterior_calibration_only=posterior_nrange(reg.estimate, candidates, calonly, level),
        posterior_course_box=course_box_nrange(reg.estimate, candidates, box1),
        subsample=tuple(rows), monte_carlo=tuple(mc), notes=NOTES,
        area_comparison=reg.area_comparison(), fixed_run=fixed, confirmation=tuple(confirm),
        redrawn=redrawn,
    )


__all__ = [
    "CONFIRM_N_MAX", "COURSE_STEPS", "ConfirmRow", "FIXED_RUN_N_MAX", "McRow", "NminResult",
    "PositionCovModel", "SubsampleRow", "analyze_nmin", "calibration_draws",
    "confirm_fixed_run", "course_box_nrange", "crossing_n",
    "design_nmin", "fixed_run_nmin", "fixed_run_probability", "posterior_nrange",
    "redrawn_design", "redrawn_probability",
    "simulate_decisions", "subsample_analysis", "synthetic_calibration", "uniform_design_cov",
]
