"""Uncertainty of the arrival point, confidence ellipse and the arrival decision.

Error model of the final position (linear propagation, one axis a ∈ {x, y}, ``k_a = 1 + ŝ_a``)
-------------------------------------------------------------------------------------------
The corrected final position is (see :mod:`calib.vehicle.trajectory`)::

    P̂_a = P0_a + V0_a·T + Σ_k w_k (A_m,a[k] - b̂_a) / k_a

1. Calibration error. ``P̂`` depends on ``c = [b_x, s_x, b_y, s_y]`` through::

       ∂P̂_a/∂b_a = -W / k_a,        W   = Σ_k w_k            (= T²/2, s²)
       ∂P̂_a/∂s_a = -D_a / k_a,      D_a = Σ_k w_k Â_r,a[k]   (= P̂_a - P0_a - V0_a T, m)

   so ``Σ_cal = J Σ_c Jᵀ`` with the 2×4 Jacobian ``J`` (zeros across axes) and ``Σ_c`` the
   4×4 calibration covariance (:attr:`calib.calibration.tilt_plane.Calibration.cov`).
2. White noise of the vehicle readings (the course reports leave it out). With the true
   parameters ``Â_r = A_r + v/k``, so the noise moves the final position by
   ``Σ_k w_k v_a[k] / k_a``; white samples give the quadratic form::

       Σ_noise[a, b] = C_v[a, b] · Σ_k w_k² / (k_a k_b)

   (``C_v`` the 2×2 noise covariance, diagonal ``[σx², σy²]`` in the course). For the uniform
   trapezoid ``Σ w² = h⁴[(2n-1)²/16 + 1/16 + (n-1)n(2n-1)/6] ≈ h T³/3``
   (:func:`calib.vehicle.trajectory.trapezoid_sum_w2_uniform`); it does not shrink with the number
   of calibration samples.

The two are independent (different runs): ``Σ_P = J Σ_c Jᵀ + Σ_noise``. Initial position and
velocity are taken as exact (course). Second-order terms (``δs·v``, ``δb·δs``) are neglected:
relative size ``std(ŝ) ≈ 5e-4`` in the course.

Region and decision
-------------------
The level-L region around the estimate is ``{p : (p - P̂)ᵀ Σ_P⁻¹ (p - P̂) ≤ χ²₂(L)}`` with
``χ²₂(L) = -2 ln(1 - L)`` (chi-square, 2 degrees of freedom). Candidate ``i`` is *inside* when
its Mahalanobis distance ``d_i`` satisfies ``d_i² ≤ χ²₂(L)``; its relative likelihood is
``exp(-d_i²/2)`` (Gaussian density relative to its peak at the estimate).

Decision: the letter when **exactly one** candidate is inside; ``None`` ("undecided")
otherwise — when several are inside (the data cannot tell them apart at this level) and when
none is (the vehicle arrived at none of the candidates, or the model is wrong). Since the true
arrival point is inside the region with probability L, a decision is wrong with probability at
most ``1 - L``.

The course box bound (course report LS, eq. 47, and its code)::

    δP_a = T²/2 · k · (σ_b,a + a_max,a · σ_s,a),   k = 3 (≈ 99.7 %),
    a_max,a = max_k |Â_r,a[k]|,   T = t_end (t_0 = 0)

bounds the calibration part only, with worst-case acceleration and a triangle inequality; the
course draws the axis-aligned ellipse with semi-axes ``(δP_x, δP_y)`` around each candidate and
decides when the estimate lies inside exactly one (:func:`course_decision`). On the course data
this gives (25.63, 44.89) m. The report's δP_y = 45.18 m is reproduced with its code's
correction ``(A_m - b)/(1 - s)`` (the bug named in docs/conventions.md; a_max then differs); its
δP_x = 22.25 m does not follow from its own covariance and code (25.25 m) — a typo, probably.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from calib import distributions as stats
from calib.results import ResultMixin, readonly
from calib.vehicle.trajectory import Trajectory

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration

COURSE_BOX_K = 3.0
"""Number of standard deviations in the course reports' box bound ("3σ ≈ 99.7 %")."""


def chi2_2dof(level: float) -> float:
    """Quantile of χ² with 2 degrees of freedom: ``-2 ln(1 - L)`` (exact)."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    return float(-2.0 * np.log1p(-level))


def box_k_for_level(level: float) -> float:
    """Per-axis ``k`` with two-sided normal probability ``level``: ``Φ⁻¹((1 + L)/2)``."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    return float(stats.norm.ppf(0.5 + level / 2.0))


def noise_cov_matrix(noise_var) -> np.ndarray:
    """2×2 noise covariance from two variances or a 2×2 matrix, (m/s²)²."""
    c = np.asarray(noise_var, dtype=float)
    c = np.diag(c) if c.shape == (2,) else c
    if c.shape != (2, 2) or not np.allclose(c, c.T):
        raise ValueError(f"noise variance must be (2,) or a symmetric 2×2, got {c.shape}")
    if np.any(np.linalg.eigvalsh(c) < 0):
        raise ValueError(f"noise covariance must be positive semi-definite, got {c.tolist()}")
    return c


def position_jacobian(traj: Trajectory) -> np.ndarray:
    """(2, 4) ``∂P̂_end/∂[b_x, s_x, b_y, s_y]`` at the estimate (module docstring, item 1).

    Units: row a, bias column in s² (m per m/s²), scale column in m.
    """
    w = traj.weights()
    k = 1.0 + traj.scale
    W = float(w.sum())
    D = w @ traj.acc_corrected  # (2,) displacement due to the corrected acceleration
    J = np.zeros((2, 4))
    for a in range(2):
        J[a, 2 * a] = -W / k[a]
        J[a, 2 * a + 1] = -D[a] / k[a]
    return J


def noise_position_cov(traj: Trajectory, noise_var) -> np.ndarray:
    """(2, 2) covariance of the final position due to the white noise of the run, m².

    ``C_v[a, b] · Σ w_k² / (k_a k_b)`` (module docstring, item 2).
    """
    w = traj.weights()
    k = 1.0 + traj.scale
    return noise_cov_matrix(noise_var) * float(w @ w) / np.outer(k, k)


def course_box_bound(duration: float, cal_cov: np.ndarray, a_max: np.ndarray,
                     k: float = COURSE_BOX_K) -> np.ndarray:
    """Course reports' per-axis bound ``T²/2 · k · (σ_b + a_max σ_s)``, m.

    Parameters
    ----------
    duration : T = t_end - t_0, s (the course uses ``Tf = t(end) = 59.99``).
    cal_cov : (4, 4) calibration covariance, order [b_x, s_x, b_y, s_y].
    a_max : (2,) max |corrected acceleration| per axis, m/s².
    k : standard deviations (course: 3).
    """
    sd = np.sqrt(np.diag(np.asarray(cal_cov, dtype=float)))
    a_max = np.asarray(a_max, dtype=float)
    return 0.5 * duration**2 * k * (sd[[0, 2]] + a_max * sd[[1, 3]])


def course_decision(estimate, candidates: dict[str, np.ndarray], box: np.ndarray,
                    shape: str = "ellipse") -> tuple[str | None, tuple[str, ...]]:
    """The course reports' criterion: which candidate regions contain the estimate.

    Around each candidate the course draws the axis-aligned ellipse with semi-axes ``box``
    (``shape="ellipse"``, as its ``ellipse.m``; ``"box"`` uses the rectangle). Decides when the
    estimate is inside exactly one.
    """
    est = np.asarray(estimate, dtype=float)
    inside = []
    for name, c in candidates.items():
        r = (est - np.asarray(c, dtype=float)) / box
        ok = float(r @ r) <= 1.0 if shape == "ellipse" else bool(np.all(np.abs(r) <= 1.0))
        if ok:
            inside.append(name)
    return (inside[0] if len(inside) == 1 else None), tuple(inside)


def squared_distances(estimate, cov, candidates: dict[str, np.ndarray]) -> dict[str, float]:
    """Squared Mahalanobis distance ``d² = (c - x̂)ᵀ Σ⁻¹ (c - x̂)`` of each candidate (m, m²)."""
    est = np.asarray(estimate, dtype=float)
    inv = np.linalg.inv(np.asarray(cov, dtype=float))
    d2 = {}
    for name, c in candidates.items():
        diff = np.asarray(c, dtype=float) - est
        d2[name] = float(diff @ inv @ diff)
    return d2


def decide(d2: dict[str, float], level: float) -> tuple[str | None, tuple[str, ...], str]:
    """Decision from squared Mahalanobis distances at ``level`` (module docstring).

    Returns ``(letter or None, names inside, reason)``.
    """
    r2 = chi2_2dof(level)
    inside = tuple(sorted(n for n, v in d2.items() if v <= r2))
    if len(inside) == 1:
        return inside[0], inside, f"only {inside[0]} is inside the {100 * level:g}% region"
    if not inside:
        return None, inside, (f"undecided: no candidate inside the {100 * level:g}% region "
                              "(arrival at none of them, or the error model is wrong)")
    return None, inside, (f"undecided: {', '.join(inside)} are all inside the "
                          f"{100 * level:g}% region")


@dataclass(frozen=True, eq=False)
class Decision(ResultMixin):
    """The arrival decision at level L around one estimate (module docstring, "Region and
    decision"): the one value the dead-reckoning regions (:class:`ArrivalRegion`,
    :class:`calib.vehicle.turning_trajectory.TurningRegion`) and the fused arrival
    (:class:`calib.vehicle.arrival.FusedArrival`) are decided with.

    Attributes
    ----------
    level : L.  candidates : name → (2,) m.  mahalanobis : name → d (dimensionless).
    likelihood : name → ``exp(-d²/2)``.  inside : names with ``d² ≤ χ²₂(L)``, sorted.
    letter : the decided name, or None.  reason : why, in words.
    """

    _TITLE = "Arrival decision"
    _UNITS = "candidates m; level, Mahalanobis distance and relative likelihood dimensionless"

    level: float
    candidates: dict
    mahalanobis: dict
    likelihood: dict
    inside: tuple
    letter: str | None
    reason: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "candidates",
                           {k: readonly(v) for k, v in self.candidates.items()})
        object.__setattr__(self, "level", float(self.level))
        object.__setattr__(self, "inside", tuple(self.inside))

    @classmethod
    def at(cls, estimate, cov, candidates: dict, level: float) -> Decision:
        """Decide around ``estimate`` (2,) m with covariance ``cov`` (2, 2) m²
        (:func:`squared_distances`, :func:`decide`)."""
        d2 = squared_distances(estimate, cov, candidates)
        letter, inside, reason = decide(d2, level)
        return cls(float(level), {k: np.asarray(v, dtype=float) for k, v in candidates.items()},
                   {k: float(np.sqrt(v)) for k, v in d2.items()},
                   {k: float(np.exp(-0.5 * v)) for k, v in d2.items()}, inside, letter, reason)

    @classmethod
    def withheld(cls, candidates: dict, level: float, reason: str) -> Decision:
        """No region and no decision: the estimate is not to be trusted (``reason`` says why,
        e.g. "no region: the filter's inputs are inconsistent"); no distances either."""
        return cls(float(level), {k: np.asarray(v, dtype=float) for k, v in candidates.items()},
                   {}, {}, (), None, reason)

    UNITS = {"level": "1", "mahalanobis.*": "1"}
    """Units of :meth:`to_dict` (the ``decision`` object of ``fuse --json``)."""

    def to_dict(self) -> dict:
        """``decision`` (letter or None), ``inside``, ``reason``, ``level``, ``mahalanobis``
        (the ``decision`` object of ``fuse --json``; :meth:`to_state` adds the rest)."""
        return {"decision": self.letter, "inside": list(self.inside), "reason": self.reason,
                "level": self.level, "mahalanobis": dict(self.mahalanobis)}

    def to_state(self) -> dict:
        """:meth:`to_dict` plus ``candidates`` (m) and ``likelihood``: an exact rebuild."""
        return {**self.to_dict(), "likelihood": dict(self.likelihood),
                "candidates": {k: v.tolist() for k, v in self.candidates.items()}}

    @classmethod
    def from_dict(cls, d: dict) -> Decision:
        """Rebuild from :meth:`to_state` (exact)."""
        return cls(d["level"], d["candidates"], d["mahalanobis"], d["likelihood"],
                   d["inside"], d["decision"], d["reason"])

    def summary(self) -> str:
        return f"decision: {self.letter or 'undecided'} ({self.reason})"


def stated_noise_var(noise_var, calibration: Calibration) -> np.ndarray:
    """σ² of the vehicle readings, (m/s²)²: ``noise_var`` as given ((2,) or (2, 2)), else the
    calibration's σ² per axis (given to it or estimated from its residuals): the same
    sensors, so the same white noise. The one place this fallback is written."""
    if noise_var is not None:
        return np.asarray(noise_var, dtype=float)
    return np.array([calibration.fits[a].sigma2.item() for a in ("x", "y")])


AREA_COMPARISON_UNITS = {"ellipse_area": "m²", "calibration_only_area": "m²",
                         "course_box_area": "m²", "course_ellipse_area": "m²", "*": "1"}
"""Units of :meth:`ArrivalRegion.area_comparison` (areas m², the ratios dimensionless)."""


@dataclass(frozen=True, eq=False)
class Ellipse(ResultMixin):
    """Confidence ellipse ``{p : (p - center)ᵀ cov⁻¹ (p - center) ≤ χ²₂(level)}``.

    semi_axes : (2,) m, major first.  angle_rad : direction of the major axis, measured from
    +x towards +y, in (-π/2, π/2].  area : π·a·b, m².

    :meth:`to_dict` (printed inside the ``trajectory --json`` object) has no ``cov``;
    :meth:`to_state` adds it.
    """

    _TITLE = "Confidence ellipse"
    _UNITS = "center and semi-axes m; cov m²; area m²; angle rad (summary: degrees from +x)"

    center: np.ndarray
    cov: np.ndarray
    level: float
    semi_axes: np.ndarray
    angle_rad: float

    def __post_init__(self) -> None:
        for name in ("center", "cov", "semi_axes"):
            object.__setattr__(self, name, readonly(getattr(self, name)))

    @classmethod
    def from_cov(cls, center, cov, level: float) -> Ellipse:
        cov = np.asarray(cov, dtype=float)
        vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
        order = np.argsort(vals)[::-1]
        vals, vecs = np.clip(vals[order], 0.0, None), vecs[:, order]
        angle = float(np.arctan2(vecs[1, 0], vecs[0, 0]))
        if angle <= -np.pi / 2:
            angle += np.pi
        elif angle > np.pi / 2:
            angle -= np.pi
        return cls(np.asarray(center, float), cov, float(level),
                   np.sqrt(chi2_2dof(level) * vals), angle)

    @property
    def area(self) -> float:
        return float(np.pi * self.semi_axes[0] * self.semi_axes[1])

    def contains(self, points) -> np.ndarray:
        """Boolean (n,) (or scalar for one point): inside or on the boundary."""
        p = np.atleast_2d(np.asarray(points, dtype=float)) - self.center
        d2 = np.einsum("ij,ij->i", p @ np.linalg.inv(self.cov), p)
        out = d2 <= chi2_2dof(self.level)
        return out if np.ndim(points) > 1 else bool(out[0])

    def boundary(self, n: int = 256) -> np.ndarray:
        """(n, 2) points on the ellipse, m (for plots)."""
        s = np.linspace(0.0, 2.0 * np.pi, n)
        c, si = np.cos(self.angle_rad), np.sin(self.angle_rad)
        a, b = self.semi_axes
        x, y = a * np.cos(s), b * np.sin(s)
        return self.center + np.column_stack([c * x - si * y, si * x + c * y])

    def to_dict(self) -> dict:
        return {"level": self.level, "semi_axes": self.semi_axes.tolist(),
                "angle_rad": self.angle_rad, "area": self.area,
                "center": self.center.tolist()}

    def to_state(self) -> dict:
        """:meth:`to_dict` plus ``cov`` (2, 2) m² (exact rebuild by :meth:`from_dict`)."""
        return {**self.to_dict(), "cov": self.cov.tolist()}

    @classmethod
    def from_dict(cls, d: dict, cov=None) -> Ellipse:
        """Rebuild from :meth:`to_state` (exact), or from :meth:`to_dict` and ``cov`` (2, 2) m²
        (without ``cov`` it is rebuilt from the semi-axes and the angle, to rounding).

        Examples
        --------
        >>> from calib.vehicle.region import Ellipse
        >>> e = Ellipse.from_cov([0.0, 0.0], [[4.0, 1.0], [1.0, 2.0]], 0.95)
        >>> Ellipse.from_dict(e.to_state()) == e
        True
        """
        c = d.get("cov") if cov is None else cov
        if c is None:  # the printed ellipse: rebuild Σ = R diag(a², b²) Rᵀ / χ²₂(L)
            rot = np.array([[np.cos(d["angle_rad"]), -np.sin(d["angle_rad"])],
                            [np.sin(d["angle_rad"]), np.cos(d["angle_rad"])]])
            c = rot @ np.diag(np.square(d["semi_axes"])) @ rot.T / chi2_2dof(d["level"])
        return cls(d["center"], c, float(d["level"]), d["semi_axes"], float(d["angle_rad"]))

    def summary(self) -> str:
        return (f"{100 * self.level:g}% ellipse around ({self.center[0]:.2f}, "
                f"{self.center[1]:.2f}) m: semi-axes {self.semi_axes[0]:.2f} m × "
                f"{self.semi_axes[1]:.2f} m, major axis at {np.degrees(self.angle_rad):.1f}° "
                f"from +x, area {self.area:.0f} m²")


@dataclass(frozen=True, eq=False, kw_only=True)
class DecidedRegion(ResultMixin):
    """What the dead-reckoning arrival regions share (:class:`ArrivalRegion`,
    :class:`calib.vehicle.turning_trajectory.TurningRegion`): the arrival point, its
    covariance, the level-L ellipse and the :class:`Decision` around it (module docstring,
    "Region and decision"), made by :meth:`decided`.

    Attributes
    ----------
    estimate : (2,) arrival point, m (world axes).  cov : (2, 2) its covariance ``Σ_P``, m².
    level : L.  ellipse : the level-L region around the estimate.
    decision : the letter or None.  reason : why, in words.
    candidates : name → (2,) m.  mahalanobis : name → d.  likelihood : name → exp(-d²/2).
    inside : names with ``d² ≤ χ²₂(L)``.

    A region adds its own fields and lists its arrays in ``_ARRAYS`` (frozen here).
    """

    estimate: np.ndarray
    cov: np.ndarray
    level: float
    ellipse: Ellipse
    decision: str | None
    reason: str
    candidates: dict
    mahalanobis: dict
    likelihood: dict
    inside: tuple

    _ARRAYS = ("estimate", "cov")

    def __post_init__(self) -> None:
        for name in self._ARRAYS:
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "candidates",
                           {k: readonly(v) for k, v in self.candidates.items()})

    @classmethod
    def decided(cls, estimate: np.ndarray, cov: np.ndarray, candidates: dict, level: float,
                **fields):
        """The region around ``estimate`` (2,) m with covariance ``cov`` (2, 2) m² at level
        ``level``: its ellipse (:meth:`Ellipse.from_cov`) and decision
        (:meth:`Decision.at`); ``fields`` are the region's own."""
        dec = Decision.at(estimate, cov, candidates, level)
        return cls(estimate=estimate, cov=cov, level=dec.level,
                   ellipse=Ellipse.from_cov(estimate, cov, level), decision=dec.letter,
                   reason=dec.reason, candidates=dec.candidates, mahalanobis=dec.mahalanobis,
                   likelihood=dec.likelihood, inside=dec.inside, **fields)

    @property
    def std(self) -> np.ndarray:
        """(2,) standard deviation of the arrival point per axis, m."""
        return np.sqrt(np.diag(self.cov))

    def as_decision(self) -> Decision:
        """The decision part of this region (:class:`Decision`)."""
        return Decision(self.level, self.candidates, self.mahalanobis, self.likelihood,
                        self.inside, self.decision, self.reason)

    def candidate_rows(self) -> dict:
        """name → ``{"pos": (2,) m, "mahalanobis", "likelihood", "inside"}``, as printed."""
        return {k: {"pos": v.tolist(), "mahalanobis": self.mahalanobis[k],
                    "likelihood": self.likelihood[k], "inside": k in self.inside}
                for k, v in self.candidates.items()}

    @staticmethod
    def decision_fields(d: dict) -> dict:
        """The decision's fields from a printed mapping (its ``candidates`` rows,
        ``inside``, ``decision`` and ``reason``), for a region's ``from_dict`` (exact)."""
        rows = d["candidates"]
        return {"candidates": {k: v["pos"] for k, v in rows.items()},
                "mahalanobis": {k: float(v["mahalanobis"]) for k, v in rows.items()},
                "likelihood": {k: float(v["likelihood"]) for k, v in rows.items()},
                "inside": tuple(d["inside"]), "decision": d["decision"], "reason": d["reason"]}


@dataclass(frozen=True, eq=False, kw_only=True)
class ArrivalRegion(DecidedRegion):
    """Arrival point, its covariance, the confidence region and the decision.

    Attributes
    ----------
    estimate : (2,) corrected final position, m.
    cov : (2, 2) ``Σ_P = cov_calibration + cov_noise``, m².
    cov_calibration : (2, 2) ``J Σ_c Jᵀ``, m².  cov_noise : (2, 2) white-noise part, m².
    jacobian : (2, 4) ``∂P̂/∂[b_x, s_x, b_y, s_y]``.  noise_var : (2, 2) vehicle noise, (m/s²)².
    level : confidence level L.  ellipse : the level-L region around the estimate.
    candidates : name → (2,) m.  mahalanobis : name → d.  likelihood : name → exp(-d²/2).
    inside : names with ``d² ≤ χ²₂(L)``.  decision : letter or None.  reason : why.
    course_box_bound : (2,) the course's 3σ box, m.  a_max : (2,) used for it, m/s².
    duration : T, s.  include_noise : whether ``cov`` has the noise part.

    Serialisation: :meth:`to_dict` (printed by ``trajectory --json``) lacks ``duration``;
    :meth:`to_state` adds it and ``ArrivalRegion.from_dict(r.to_state()) == r``.
    ``from_dict(r.to_dict())`` gives the same printed object with ``duration = nan``.
    """

    _TITLE = "Arrival region"
    _UNITS = ("positions, std, semi-axes and box bounds m; covariances m²; area m²; "
              "noise variance (m/s²)²; Mahalanobis distance and relative likelihood "
              "dimensionless; angles in degrees from +x")

    cov_calibration: np.ndarray
    cov_noise: np.ndarray
    jacobian: np.ndarray
    noise_var: np.ndarray
    course_box_bound: np.ndarray
    a_max: np.ndarray
    duration: float
    include_noise: bool = True

    _ARRAYS = (*DecidedRegion._ARRAYS, "cov_calibration", "cov_noise", "jacobian", "noise_var",
               "course_box_bound", "a_max")

    def course_box_at_level(self) -> np.ndarray:
        """The course box with ``k = Φ⁻¹((1 + L)/2)`` instead of 3 (same per-axis level)."""
        return self.course_box_bound * box_k_for_level(self.level) / COURSE_BOX_K

    def area_comparison(self) -> dict:
        """Ellipse area against the course regions at the same level, m² and ratios.

        ``box`` is the rectangle ``2δx × 2δy``, ``course_ellipse`` the ellipse ``π δx δy`` the
        course drew; both with ``k = Φ⁻¹((1 + L)/2)``. ``calibration_only`` is our ellipse
        without the vehicle-noise term (what the course box tries to bound).
        """
        d = self.course_box_at_level()
        box, cell = 4.0 * d[0] * d[1], np.pi * d[0] * d[1]
        cal = Ellipse.from_cov(self.estimate, self.cov_calibration, self.level).area
        return {"ellipse_area": self.ellipse.area, "calibration_only_area": cal,
                "course_box_area": box, "course_ellipse_area": cell,
                "ratio_to_course_box": self.ellipse.area / box,
                "ratio_to_course_ellipse": self.ellipse.area / cell,
                "calibration_only_ratio_to_course_box": cal / box}

    def to_dict(self) -> dict:
        return {
            "final_corrected": self.estimate.tolist(),
            "cov": self.cov.tolist(),
            "cov_calibration": self.cov_calibration.tolist(),
            "cov_noise": self.cov_noise.tolist(),
            "std": self.std.tolist(),
            "jacobian": self.jacobian.tolist(),
            "noise_var": self.noise_var.tolist(),
            "include_noise": self.include_noise,
            "ellipse": self.ellipse.to_dict(),
            "candidates": self.candidate_rows(),
            "inside": list(self.inside),
            "decision": self.decision,
            "reason": self.reason,
            "course_box_bound": self.course_box_bound.tolist(),
            "course_box_k": COURSE_BOX_K,
            "course_box_a_max": self.a_max.tolist(),
            "course_decision": course_decision(self.estimate, self.candidates,
                                               self.course_box_bound)[0],
            "area_comparison": self.area_comparison(),
        }

    def to_state(self) -> dict:
        """:meth:`to_dict` plus ``level`` and ``duration`` (s) — an exact rebuild."""
        return {**self.to_dict(), "level": self.level, "duration": self.duration}

    @classmethod
    def from_dict(cls, d: dict) -> ArrivalRegion:
        """Rebuild from :meth:`to_state` (exact) or :meth:`to_dict` (``duration`` = nan).

        Parameters
        ----------
        d : the mapping of :meth:`to_state`: ``final_corrected`` (2,) m, ``cov``,
            ``cov_calibration``, ``cov_noise`` (2, 2) m², ``jacobian`` (2, 4),
            ``noise_var`` (2, 2) (m/s²)², ``ellipse``, ``candidates`` (name → ``pos`` (2,) m,
            ``mahalanobis``, ``likelihood``), ``inside``, ``decision``, ``reason``,
            ``course_box_bound`` (2,) m, ``course_box_a_max`` (2,) m/s², ``include_noise``,
            ``level``, ``duration`` s.

        Examples
        --------
        >>> import numpy as np
        >>> from calib import ArrivalRegion, Ensayo, arrival_region, calibrate
        >>> from calib.vehicle.trajectory import correct_and_integrate
        >>> th = np.linspace(0, 2 * np.pi, 100)
        >>> cal = calibrate(Ensayo(th, np.column_stack([-9.8 * np.sin(th),
        ...                                             -9.8 * np.cos(th)])), [0.25, 0.64])
        >>> tr = correct_and_integrate(np.linspace(0, 10, 101), np.zeros((101, 2)), 0, 0)
        >>> r = arrival_region(tr, cal, {"A": [10.0, 30.0], "B": [0.0, 0.0]})
        >>> ArrivalRegion.from_dict(r.to_state()) == r
        True
        """
        cov = np.asarray(d["cov"], dtype=float)
        return cls(
            estimate=d["final_corrected"], cov=cov, cov_calibration=d["cov_calibration"],
            cov_noise=d["cov_noise"], jacobian=d["jacobian"], noise_var=d["noise_var"],
            level=float(d.get("level", d["ellipse"]["level"])),
            ellipse=Ellipse.from_dict(d["ellipse"], cov=d["ellipse"].get("cov", cov)),
            **cls.decision_fields(d), course_box_bound=d["course_box_bound"],
            a_max=d["course_box_a_max"],
            duration=float(d.get("duration", float("nan"))),
            include_noise=bool(d["include_noise"]),
        )

    def summary(self) -> str:
        e = self.ellipse
        lines = [
            f"Arrival point: ({self.estimate[0]:.2f}, {self.estimate[1]:.2f}) m; "
            f"std = ({self.std[0]:.2f}, {self.std[1]:.2f}) m "
            f"[calibration ({np.sqrt(self.cov_calibration[0, 0]):.2f}, "
            f"{np.sqrt(self.cov_calibration[1, 1]):.2f}) m, vehicle noise "
            f"({np.sqrt(self.cov_noise[0, 0]):.2f}, {np.sqrt(self.cov_noise[1, 1]):.2f}) m]",
            f"{100 * self.level:g}% ellipse: semi-axes {e.semi_axes[0]:.2f} m × "
            f"{e.semi_axes[1]:.2f} m, major axis at {np.degrees(e.angle_rad):.1f}° from +x, "
            f"area {e.area:.0f} m²",
            f"{'cand':<6}{'x (m)':>10}{'y (m)':>10}{'Mahalanobis':>13}{'rel. lik.':>12}"
            f"{'inside':>8}",
        ]
        for k, c in self.candidates.items():
            lines.append(f"{k:<6}{c[0]:>10.2f}{c[1]:>10.2f}{self.mahalanobis[k]:>13.3f}"
                         f"{self.likelihood[k]:>12.3g}{'yes' if k in self.inside else 'no':>8}")
        lines.append(f"decision: {self.decision or 'undecided'} ({self.reason})")
        b = self.course_box_bound
        cd = course_decision(self.estimate, self.candidates, b)[0]
        ac = self.area_comparison()
        lines.append(f"course box bound (3σ, calibration only): ±{b[0]:.2f} m (x), "
                     f"±{b[1]:.2f} m (y); course decision: {cd or 'undecided'}")
        lines.append(f"ellipse area / course box area at {100 * self.level:g}%: "
                     f"{ac['ratio_to_course_box']:.3f} (calibration part alone: "
                     f"{ac['calibration_only_ratio_to_course_box']:.3f})")
        return "\n".join(lines)


def arrival_region(
    traj: Trajectory,
    calibration: Calibration,
    candidates: dict[str, np.ndarray],
    noise_var=None,
    level: float = 0.997,
    include_noise: bool = True,
) -> ArrivalRegion:
    """Covariance of the arrival point, level-L ellipse, distances and decision.

    Parameters
    ----------
    traj : corrected trajectory (:func:`calib.vehicle.trajectory.compute_trajectory`).
    calibration : the calibration used for it (``cov`` order [b_x, s_x, b_y, s_y]).
    candidates : name → (2,) candidate arrival points, m.
    noise_var : (2,) or (2, 2) white-noise (co)variance of the vehicle readings, (m/s²)²;
        None uses the calibration's σ² (given or estimated from its residuals — same sensors).
    level : confidence level L of the region, e.g. 0.997.
    include_noise : False drops the vehicle-noise term (the course's omission), for
        comparison only.

    Returns
    -------
    ArrivalRegion : ``estimate`` (2,) m, ``cov`` (2, 2) m², the level-L ``ellipse``, the
    Mahalanobis distance of each candidate and the ``decision`` (a name or None).

    Examples
    --------
    >>> import numpy as np
    >>> from calib import Acel, Ensayo, arrival_region, calibrate, compute_trajectory
    >>> th = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
    >>> cal = calibrate(Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])),
    ...                 noise_var=[0.25, 0.64])
    >>> t = np.arange(1001) * 0.01
    >>> tr = compute_trajectory(Acel(t, np.zeros((1001, 2))), cal)   # V0 = (1, 3) m/s
    >>> r = arrival_region(tr, cal, {"A": [10.0, 30.0], "B": [60.0, 30.0]}, level=0.997)
    >>> r.decision
    'A'
    """
    C = noise_cov_matrix(stated_noise_var(noise_var, calibration))
    J = position_jacobian(traj)
    cov_cal = J @ calibration.cov @ J.T
    cov_noise = noise_position_cov(traj, C) if include_noise else np.zeros((2, 2))
    cov = 0.5 * ((cov_cal + cov_noise) + (cov_cal + cov_noise).T)
    a_max = np.max(np.abs(traj.acc_corrected), axis=0)
    box = course_box_bound(traj.duration, calibration.cov, a_max)
    return ArrivalRegion.decided(
        traj.final_corrected, cov, candidates, level, cov_calibration=cov_cal,
        cov_noise=cov_noise, jacobian=J, noise_var=C, course_box_bound=box, a_max=a_max,
        duration=traj.duration, include_noise=include_noise)


__all__ = [
    "COURSE_BOX_K", "ArrivalRegion", "DecidedRegion", "Decision", "Ellipse", "arrival_region",
    "box_k_for_level", "chi2_2dof", "course_box_bound", "course_decision", "decide",
    "noise_cov_matrix", "noise_position_cov", "position_jacobian", "squared_distances",
    "stated_noise_var",
]
