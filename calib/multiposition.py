"""Calibration without an angle reference: the multi-position method.

A phone or a board turned by hand has no angle reference, but gravity has a known magnitude.
Held still in several orientations ("poses"), each pose's corrected reading lies on the circle
of radius g (Skog & Händel, "Calibration of a MEMS inertial measurement unit", XVII IMEKO
World Congress, 2006; Frosio, Pedersini & Borghese, IEEE Trans. Instrum. Meas. 58(6), 2009).
For the two tilt-plane axes of this bench, with the course model ``A_m = (1 + s)·A_r + b``
and the course signs ``A_rx = −g sin θ``, ``A_ry = −g cos θ``::

    ((m̄x_i − bx) / (1 + sx))² + ((m̄y_i − by) / (1 + sy))² = g²       for every pose i

Formulation solved here (maximum likelihood with the pose angle as a nuisance parameter):
the parameters are ``p = [bias_x, scale_x, bias_y, scale_y]`` and one angle ``θ_i`` per pose;
the observations are the pose means ``m̄_i`` (2 per pose) with variances ``σ_a² / n_i``::

    r_xi = √n_i/σx · (m̄x_i − bx − (1 + sx)(−g sin θ_i))
    r_yi = √n_i/σy · (m̄y_i − by − (1 + sy)(−g cos θ_i))       minimise Σ r²

Using all static samples instead of the pose means gives the same estimates (the within-pose
sum of squares does not depend on the parameters), so the means are used. The problem is a
proper nonlinear least squares with 2P residuals and 4 + P unknowns: **at least 4 poses**
(4 parameters of the axis-aligned ellipse; each pose adds one reading pair and one unknown
angle), 5 or more to test the fit (dof = P − 4). Solved with
:func:`scipy.optimize.least_squares` (Levenberg–Marquardt, analytic Jacobian) from an
algebraic ellipse fit. Covariance: from the whitened Jacobian ``J`` at the solution by QR,
``cov = R⁻¹R⁻ᵀ`` (never ``(JᵀJ)⁻¹``), the top-left 4×4 block being the calibration's — it
includes what the unknown angles cost.

σ² per axis: given (``--noise-var`` / ``datos.txt``: normal quantiles) or estimated from the
scatter within the poses (pure error, :mod:`calib.lackoffit`: Student t with N − P dof).

Identifiability (reported, and refused when missing): the number of poses, the largest gap
between the pose directions, the rank and the condition number of the column-equilibrated
Jacobian; poses that leave an axis's readings nearly constant cannot identify its scale (the
message names it), and an exactly degenerate geometry (fewer than 4 distinct directions, or a
set of poses symmetric about both axes, on which a family of ellipses fits) is rank-deficient.

Not separable here, by construction: a different local g is absorbed by both scales; a tilt
offset of the table does not exist (the angles are free); a misalignment between the two
axes is not in the model and shows as lack of fit.

Three axes (:func:`fit_multiposition3d`): a 3-axis IMU held in arbitrary orientations (a
phone, a wrist sensor) — the log's third axis :attr:`calib.logs.ImuLog.acc_normal` — gives
``‖(m̄_i − b) ⊘ (1 + s)‖ = g`` on the sphere, each pose's gravity direction a nuisance (two
angles), bias and scale of all three axes from at least :data:`POSES_NEEDED_3D` = 7 poses
whose directions span the sphere; quantized readings (raw counts) add ``q²/12`` to each pose
mean's variance. Its first four parameters and their 4×4 block are the planar result's, so it
gives the same :class:`calib.calibration.Calibration`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import linalg as sla
from scipy import optimize, stats

from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES, G
from calib.input_rules import DataError
from calib.lackoffit import LackOfFit
from calib.ls import FitResult, NotIdentifiableError, PoorlyIdentifiedWarning
from calib.results import ResultMixin, readonly
from calib.units import nest, with_units

POSES_NEEDED = 4
"""Fewest held poses that identify bias and scale of both axes with θ unknown."""

COND_WARN = 100.0
"""Condition number of the equilibrated Jacobian above which the fit warns (poorly spread
poses: a small error in the data moves the estimates a lot). Poses evenly spread around the
turn give ≈ 2–3; six poses within 50° give ≈ 300 with a scale std of ≈ 0.3."""

COND_REFUSE = 1e6
"""Condition number above which the poses are taken as not identifying the calibration
(refused, naming the parameters of the weakest direction): e.g. four poses symmetric about
both axes (± α, π ± α), on which a family of ellipses fits, give ≈ 5e6 with noise."""

UNIDENTIFIED_STD = {"bias": 0.1, "scale": 0.1}
"""A parameter whose std exceeds this (bias: this fraction of g, m/s²; scale: this value) is
not identified by the poses in any useful sense (an accelerometer's scale error is a few per
cent): refused, naming it. Four noisy poses near ± 20°, 180° ± 20° give std(scale) ≈ 10³."""

SAME_POSE_STD = 3.0
"""Two poses whose mean readings differ by less than this many standard deviations of their
difference on both axes count as one orientation (:func:`distinct_orientations`)."""

PLANE_FRACTION = 0.5
"""A pose whose mean reading's norm is off g by more than this fraction is not in the tilt
plane (e.g. a 3-axis IMU lying with z up): it is left out, with a warning."""

SPAN_FRACTION = 0.05
"""An axis whose pose means span less than this fraction of g (poses all within ≈ ±3° of the
same line) cannot identify its scale: refused, naming ``scale_<axis>``."""

Sigma2Source = Literal["given", "estimated"]


@dataclass(frozen=True, eq=False)
class Poses(ResultMixin):
    """Per-pose statistics of a log: the held poses' labels, sample counts and means.

    Attributes
    ----------
    labels : (P,) int pose labels (as in :attr:`calib.logs.ImuLog.pose`).
    n : (P,) int samples per pose.
    means : (P, 2) m/s², mean reading ``[m̄x, m̄y]`` of each pose; (P, 3) with the normal
        axis ``[m̄x, m̄y, m̄n]`` for the 3-axis fit (:func:`fit_multiposition3d`).
    ss : (P, 2) or (P, 3) (m/s²)², each pose's sum of squares about its mean (pure error).
    """

    labels: np.ndarray
    n: np.ndarray
    means: np.ndarray
    ss: np.ndarray

    _TITLE = "Held poses"
    _UNITS = "means m/s²; ss (m/s²)²; n count"

    def __post_init__(self) -> None:
        object.__setattr__(self, "labels", readonly(self.labels, int))
        object.__setattr__(self, "n", readonly(self.n, int))
        object.__setattr__(self, "means", readonly(self.means))
        k = self.means.shape[1] if self.means.ndim == 2 else 2
        object.__setattr__(self, "ss", readonly(np.reshape(self.ss, (-1, k))))

    @property
    def count(self) -> int:
        return int(self.labels.size)

    @property
    def axes(self) -> int:
        """Axes per pose: 2 (tilt plane) or 3 (with the normal axis)."""
        return int(self.means.shape[1])

    @property
    def ss_within(self) -> np.ndarray:
        """(2,) or (3,) (m/s²)², pure-error sum of squares of each axis (all poses)."""
        return self.ss.sum(axis=0)

    @property
    def dof_within(self) -> int:
        """Pure-error dof, N − P."""
        return int(self.n.sum() - self.n.size)

    def summary(self) -> str:
        names = "xyn"[:self.axes]
        rows = [f"{'pose':>5}{'n':>8}" + "".join(f"{'mean ' + a + ' m/s²':>14}" for a in names)]
        rows += [f"{lab:>5}{k:>8}" + "".join(f"{v:>14.5f}" for v in m)
                 for lab, k, m in zip(self.labels, self.n, self.means, strict=True)]
        return "\n".join(rows)

    def to_dict(self) -> dict:
        return {"labels": self.labels.tolist(), "n": self.n.tolist(),
                "means": self.means.tolist(), "ss": self.ss.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> Poses:
        return cls(d["labels"], d["n"], d["means"], d["ss"])


def pose_statistics(acc: np.ndarray, pose: np.ndarray, source: str = "<memory>") -> Poses:
    """The :class:`Poses` of readings ``acc`` (N, 2) m/s² — or (N, 3) with the normal axis —
    with labels ``pose`` (N,) int (−1: moving, left out). DataError when no sample is
    labelled."""
    acc = np.asarray(acc, dtype=float)
    pose = np.asarray(pose, dtype=int)
    if acc.ndim != 2 or acc.shape[1] not in (2, 3) or pose.shape != (acc.shape[0],):
        raise DataError(f"{source}: readings must be (N, 2) or (N, 3) with one pose label per "
                        f"sample, got {acc.shape} and {pose.shape}")
    held = pose >= 0
    if not np.any(held):
        raise DataError(f"{source}: no held pose (every sample is labelled moving, -1); the "
                        "multi-position calibration needs the sensor held still in several "
                        "orientations")
    labels, inverse = np.unique(pose[held], return_inverse=True)
    a = acc[held]
    n = np.bincount(inverse)
    k_ax = acc.shape[1]
    means = np.stack([np.bincount(inverse, weights=a[:, k]) / n for k in range(k_ax)], axis=1)
    dev2 = (a - means[inverse]) ** 2
    ss = np.stack([np.bincount(inverse, weights=dev2[:, k]) for k in range(k_ax)], axis=1)
    return Poses(labels, n, means, ss)


@dataclass(frozen=True, eq=False)
class MultiPositionFit(ResultMixin):
    """Bias and scale of both axes from held poses with θ unknown (module docstring).

    Attributes
    ----------
    params : (4,) ``[bias_x, scale_x, bias_y, scale_y]`` (m/s², 1, m/s², 1).
    cov : (4, 4) their covariance (the angles marginalised), products of those units.
    angles, angles_std : (P,) rad, estimated angle θ_i of each pose (course convention,
        wrapped to (−π, π]) and its std.
    poses : the :class:`Poses` the fit used (labels, counts, means).
    residuals : (P, 2) m/s², pose mean − model.
    sigma2 : (2,) (m/s²)², noise variance per axis; ``sigma2_source`` "given" or
        "estimated" (pure error, ``sigma2_dof = N − P`` dof: Student t).
    dof : P − 4 (residual dof of the pose means).  chi2 : Σ r² (whitened).
    rank, cond : rank and 2-norm condition number of the column-equilibrated Jacobian.
    max_gap : rad, the largest angle between neighbouring pose directions (2π/P at best).
    lack_of_fit : the joint test of the pose means against the ellipse (None when dof = 0).
    g : m/s².
    """

    params: np.ndarray
    cov: np.ndarray
    angles: np.ndarray
    angles_std: np.ndarray
    poses: Poses
    residuals: np.ndarray
    sigma2: np.ndarray
    sigma2_source: Sigma2Source
    sigma2_dof: int
    dof: int
    chi2: float
    rank: int
    cond: float
    max_gap: float
    g: float
    lack_of_fit: LackOfFit | None = None
    param_names: tuple[str, ...] = field(default=JOINT_PARAM_NAMES)

    _TITLE = "Multi-position calibration (θ unknown)"
    _UNITS = ("bias m/s²; scale dimensionless; angles rad; σ² (m/s²)²; residuals m/s²; "
              "χ² dimensionless; g m/s²")
    JSON_UNITS = {
        "params": "[m/s², 1, m/s², 1]", "std": "[m/s², 1, m/s², 1]",
        "cov": "products of the params' units", "angles": "rad", "angles_std": "rad",
        "residuals": "m/s²", "sigma2": "(m/s²)²", "sigma2_dof": "count", "dof": "count",
        "chi2": "1", "rank": "count", "cond": "1", "max_gap": "rad", "g": "m/s²",
        "poses.labels": "—", "poses.n": "count", "poses.means": "m/s²", "poses.ss": "(m/s²)²",
    }

    def __post_init__(self) -> None:
        for name in ("params", "cov", "angles", "angles_std", "residuals", "sigma2"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "param_names", tuple(self.param_names))

    @property
    def std(self) -> np.ndarray:
        """(4,) standard deviations of ``params``."""
        return np.sqrt(np.diag(self.cov))

    @property
    def n(self) -> int:
        """Samples used (held poses only)."""
        return int(self.poses.n.sum())

    @property
    def bias(self) -> np.ndarray:
        return self.params[[0, 2]]

    @property
    def scale(self) -> np.ndarray:
        return self.params[[1, 3]]

    def quantile(self, level: float) -> float:
        """Two-sided quantile: normal (σ² given) or Student t with ``sigma2_dof``."""
        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level}")
        q = 0.5 + level / 2
        return float(stats.norm.ppf(q) if self.sigma2_source == "given"
                     else stats.t.ppf(q, self.sigma2_dof))

    def conf_int(self, level: float = 0.95) -> np.ndarray:
        """(4, 2) two-sided intervals at ``level``."""
        half = self.quantile(level) * self.std
        return np.column_stack([self.params - half, self.params + half])

    def summary(self, level: float = 0.95) -> str:
        lo, hi = self.conf_int(level).T
        pct = f"{100 * level:g}%"
        out = [f"Calibration: multi-position (θ unknown, gravity norm), g = {self.g} m/s², "
               f"N = {self.n}, {self.poses.count} poses",
               f"{'param':<9}{'unit':<6}{'estimate':>14}{'std':>13}{'[' + pct:>14}"
               f"{pct + ']':>13}"]
        for i, name in enumerate(self.param_names):
            unit = "m/s²" if name.startswith("bias") else "1"
            out.append(f"{name:<9}{unit:<6}{self.params[i]:>14.6g}{self.std[i]:>13.4g}"
                       f"{lo[i]:>14.6g}{hi[i]:>13.6g}")
        s2 = ", ".join(f"{v:.4g}" for v in self.sigma2)
        src = ("given" if self.sigma2_source == "given"
               else f"estimated within poses, dof {self.sigma2_dof}")
        fit_line = (f"χ²/dof = {self.chi2_dof:.4f}; dof = {self.dof}" if self.dof > 0 else
                    "dof = 0: 4 poses fit the ellipse exactly (5 or more test the fit)")
        out.append(f"σ² = {s2} (m/s²)² ({src}); {fit_line}")
        out.append(f"identifiability: {self.poses.count} poses, largest gap between pose "
                   f"directions {np.degrees(self.max_gap):.1f}°, rank {self.rank}, "
                   f"cond = {self.cond:.3g}")
        out.append("pose   n      θ (deg)   std (deg)   resid x m/s²  resid y m/s²")
        for k in range(self.poses.count):
            out.append(f"{self.poses.labels[k]:>4}{self.poses.n[k]:>7}"
                       f"{np.degrees(self.angles[k]):>12.3f}{np.degrees(self.angles_std[k]):>12.3g}"
                       f"{self.residuals[k, 0]:>14.4g}{self.residuals[k, 1]:>14.4g}")
        if self.lack_of_fit is not None:
            out.append(self.lack_of_fit.summary())
        return "\n".join(out)

    @property
    def chi2_dof(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    def to_dict(self) -> dict:
        return {
            "method": "multiposition", "param_names": list(self.param_names),
            "params": self.params.tolist(), "std": self.std.tolist(), "cov": self.cov.tolist(),
            "angles": self.angles.tolist(), "angles_std": self.angles_std.tolist(),
            "poses": self.poses.to_dict(), "residuals": self.residuals.tolist(),
            "sigma2": self.sigma2.tolist(), "sigma2_source": self.sigma2_source,
            "sigma2_dof": self.sigma2_dof, "dof": self.dof, "chi2": self.chi2,
            "rank": self.rank, "cond": self.cond, "max_gap": self.max_gap, "g": self.g,
            "lack_of_fit": None if self.lack_of_fit is None else self.lack_of_fit.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict) -> MultiPositionFit:
        """Rebuild from :meth:`to_dict` (exact)."""
        lof = d.get("lack_of_fit")
        return cls(
            params=d["params"], cov=d["cov"], angles=d["angles"], angles_std=d["angles_std"],
            poses=Poses.from_dict(d["poses"]), residuals=np.asarray(d["residuals"], float)
            .reshape(-1, 2), sigma2=d["sigma2"], sigma2_source=d["sigma2_source"],
            sigma2_dof=int(d["sigma2_dof"]), dof=int(d["dof"]), chi2=float(d["chi2"]),
            rank=int(d["rank"]), cond=float(d["cond"]), max_gap=float(d["max_gap"]),
            g=float(d["g"]), lack_of_fit=None if lof is None else LackOfFit.from_dict(lof),
            param_names=tuple(d["param_names"]))

    def to_calibration(self):
        """The project's :class:`calib.calibration.Calibration` (method "multiposition"):
        the joint 4×4 covariance (with the cross-axis terms the shared angles create) in
        ``joint``, the per-axis marginal blocks in ``fits`` — what ``--save cal.json`` and
        ``trajectory --calibration`` use.

        The fits' χ² is that of the samples, as for the least squares: every held sample
        against its pose's model value, ``Σ_ij (m_ij − model_i)² / σ² = (SS_within +
        Σ n_i r_i²) / σ²`` per axis, with ``dof = N − P`` (samples less the poses' means);
        finite also for P = 4 poses, where the pose means fit exactly. Residuals: the pose
        means' (P per axis), m/s². The joint test of the fit is :attr:`lack_of_fit`."""
        from calib.calibration import Calibration

        chi2 = (self.poses.ss_within
                + np.sum(self.poses.n[:, None] * self.residuals**2, axis=0)) / self.sigma2
        dof = self.sigma2_dof
        extra = {"sigma2_dof": self.sigma2_dof} if self.sigma2_source == "estimated" else {}
        fits = {}
        for k, a in enumerate(AXES):
            sl = slice(2 * k, 2 * k + 2)
            fits[a] = FitResult(PARAM_NAMES, self.params[sl], self.cov[sl, sl],
                                self.residuals[:, k], self.sigma2[k], self.sigma2_source,
                                dof, 2, self.cond, float(chi2[k]), dict(extra))
        joint = FitResult(JOINT_PARAM_NAMES, self.params, self.cov, self.residuals,
                          self.sigma2, self.sigma2_source, 2 * dof, self.rank, self.cond,
                          float(chi2.sum()), {**extra, "angles": self.angles.tolist(),
                                              "angles_std": self.angles_std.tolist()})
        return Calibration("multiposition", self.g, fits, self.n, joint=joint)


def _model(p: np.ndarray, th: np.ndarray, g: float) -> np.ndarray:
    """(P, 2) model readings of the poses: ``b + (1 + s)·A_r(θ)``."""
    return np.column_stack([p[0] + (1 + p[1]) * (-g * np.sin(th)),
                            p[2] + (1 + p[3]) * (-g * np.cos(th))])


def _residuals_and_jacobian(x: np.ndarray, means: np.ndarray, w: np.ndarray, g: float):
    """Whitened residuals (2P,) ordered [x of every pose, y of every pose] and their
    Jacobian (2P, 4 + P) in ``x = [bx, sx, by, sy, θ_1 … θ_P]`` (module docstring)."""
    P = means.shape[0]
    p, th = x[:4], x[4:]
    s, c = np.sin(th), np.cos(th)
    r = np.concatenate([w[:, 0] * (means[:, 0] - p[0] - (1 + p[1]) * (-g * s)),
                        w[:, 1] * (means[:, 1] - p[2] - (1 + p[3]) * (-g * c))])
    J = np.zeros((2 * P, 4 + P))
    idx = np.arange(P)
    J[:P, 0] = -w[:, 0]
    J[:P, 1] = w[:, 0] * g * s
    J[idx, 4 + idx] = w[:, 0] * (1 + p[1]) * g * c
    J[P:, 2] = -w[:, 1]
    J[P:, 3] = w[:, 1] * g * c
    J[P + idx, 4 + idx] = -w[:, 1] * (1 + p[3]) * g * s
    return r, J


def _initial(means: np.ndarray, g: float) -> np.ndarray:
    """Start: an algebraic axis-aligned ellipse through the pose means,
    ``x² + c y² + d x + e y + f = 0`` by linear least squares (in units of g), then each
    pose's angle from its corrected reading. Falls back to the ideal sensor (b = 0, s = 0)
    when the algebraic fit is not an ellipse."""
    u = means / g
    A = np.column_stack([u[:, 1] ** 2, u[:, 0], u[:, 1], np.ones(len(u))])
    p = np.zeros(4)
    sol, *_ = np.linalg.lstsq(A, -u[:, 0] ** 2, rcond=None)
    c, d, e, f = sol
    if c > 0:
        bx, by = -d / 2, -e / (2 * c)
        rx2 = bx**2 + c * by**2 - f
        if rx2 > 0:
            rx, ry = np.sqrt(rx2), np.sqrt(rx2 / c)
            cand = np.array([bx * g, rx - 1, by * g, ry - 1])
            if np.all(np.abs(cand[[1, 3]]) < 0.5):  # a plausible accelerometer, not a sliver
                p = cand
    th = np.arctan2(-(means[:, 0] - p[0]) / (1 + p[1]), -(means[:, 1] - p[2]) / (1 + p[3]))
    return np.concatenate([p, th])


def _largest_gap(angles: np.ndarray) -> float:
    """Largest angle between neighbouring directions on the circle, rad."""
    a = np.sort(np.mod(angles, 2 * np.pi))
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]]))
    return float(gaps.max())


class OutOfPlaneWarning(UserWarning):
    """Poses left out of the multi-position fit because gravity is not in their tilt plane."""


def distinct_orientations(poses: Poses, sigma2: np.ndarray, mean_var=0.0) -> int:
    """Number of distinct orientations among the poses: poses whose means differ by less
    than :data:`SAME_POSE_STD` std of their difference on every axis (``σ_a² (1/n_i +
    1/n_j) + 2·mean_var_a``; ``mean_var`` (m/s²)², a variance every pose mean has whatever
    n, e.g. quantization's q²/12) are merged (single linkage). Repeating an orientation adds
    samples, not geometry."""
    P = poses.count
    parent = list(range(P))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    inv_n = 1.0 / poses.n
    for i in range(P):
        for j in range(i + 1, P):
            sd = np.sqrt(sigma2 * (inv_n[i] + inv_n[j]) + 2 * np.asarray(mean_var))
            if np.all(np.abs(poses.means[i] - poses.means[j]) < SAME_POSE_STD * sd):
                parent[root(j)] = root(i)
    return len({root(i) for i in range(P)})


def in_plane(poses: Poses, g: float = G) -> tuple[Poses, np.ndarray]:
    """``(kept, left_out_labels)``: the poses whose mean reading's norm is within
    :data:`PLANE_FRACTION` of g, and the labels of the others."""
    norm = np.hypot(poses.means[:, 0], poses.means[:, 1])
    ok = np.abs(norm - g) <= PLANE_FRACTION * g
    if np.all(ok):
        return poses, np.zeros(0, dtype=int)
    return (Poses(poses.labels[ok], poses.n[ok], poses.means[ok], poses.ss[ok]),
            poses.labels[~ok])


def _names(P: int) -> tuple[str, ...]:
    return JOINT_PARAM_NAMES + tuple(f"θ_{k}" for k in range(P))


def fit_multiposition(
    poses: Poses, noise_var=None, g: float = G, source: str = "<memory>",
) -> MultiPositionFit:
    """Bias and scale of both axes from held poses, θ unknown (module docstring).

    Parameters
    ----------
    poses : the held poses (:func:`pose_statistics`).
    noise_var : (2,) σ² per axis, (m/s²)² (normal quantiles), or None: estimated from the
        scatter within the poses (pure error; Student t with N − P dof).
    g : gravity, m/s².
    source : the file name, for messages.

    Warns
    -----
    OutOfPlaneWarning : poses left out (norm off g by more than :data:`PLANE_FRACTION`).
    PoorlyIdentifiedWarning : condition number above :data:`COND_WARN`.

    Raises
    ------
    NotIdentifiableError : fewer than :data:`POSES_NEEDED` poses (or distinct orientations,
        :func:`distinct_orientations`) in the tilt plane, an axis whose readings the poses
        hardly change (:data:`SPAN_FRACTION`, its scale is named), a degenerate set
        (Jacobian rank-deficient or its condition number above :data:`COND_REFUSE`), or a
        parameter whose std exceeds :data:`UNIDENTIFIED_STD` (named).
    DataError : σ² to estimate but no pose has two samples.

    Examples
    --------
    >>> import numpy as np
    >>> th = np.radians([0, 60, 120, 180, 240, 300])
    >>> means = np.column_stack([0.1 + 1.02 * -9.8 * np.sin(th), -0.2 + 0.99 * -9.8 * np.cos(th)])
    >>> fit = fit_multiposition(Poses(np.arange(6), [100] * 6, means, [1.0, 1.0]), [0.25, 0.64])
    >>> np.round(fit.params, 9).tolist()
    [0.1, 0.02, -0.2, -0.01]
    """
    where = "" if source == "<memory>" else f"{source}: "
    if poses.axes == 3:  # the tilt plane only: the normal axis is the 3-axis fit's
        poses = Poses(poses.labels, poses.n, poses.means[:, :2], poses.ss[:, :2])
    poses, left_out = in_plane(poses, g)
    if left_out.size:
        warnings.warn(
            f"{where}pose{'s' if left_out.size > 1 else ''} {', '.join(map(str, left_out))} "
            f"left out of the multi-position fit: the mean reading's norm is off g by more "
            f"than {PLANE_FRACTION:.0%}, so gravity is not in the tilt plane there (a 3-axis "
            "IMU lying on the third axis? --axes picks the plane)", OutOfPlaneWarning,
            stacklevel=2)
    P = poses.count
    if P < POSES_NEEDED:
        raise NotIdentifiableError(
            f"{where}{P} held pose{'s' if P != 1 else ''} in the tilt plane: the "
            f"multi-position calibration needs at least {POSES_NEEDED} (bias and scale of two "
            "axes are 4 unknowns and each pose brings one unknown angle with its two "
            "readings), 6 or more spread around the turn to check the fit; hold the sensor in "
            "more orientations, or give the angles (--poses) for the θ-based least squares")
    span = np.ptp(poses.means, axis=0)
    for k, a in enumerate(AXES):
        if span[k] < SPAN_FRACTION * g:
            raise NotIdentifiableError(
                f"{where}cannot identify scale_{a}: the {P} poses hardly turn the {a} axis (its "
                f"pose means span only {span[k]:.3g} m/s², under {SPAN_FRACTION:g}·g); hold "
                f"poses where {a} reads clearly different values (e.g. {a} up and {a} down)")
    if noise_var is None:
        if poses.dof_within <= 0:
            raise DataError(f"{where}every pose has a single sample: σ² cannot be estimated "
                            "within the poses; give --noise-var σx²,σy²")
        sigma2 = poses.ss_within / poses.dof_within
        source_s2: Sigma2Source = "estimated"
        if np.any(sigma2 <= 0):
            raise DataError(f"{where}the readings do not scatter within the poses (zero "
                            "variance on an axis): give --noise-var σx²,σy²")
    else:
        sigma2 = np.asarray(noise_var, dtype=float).reshape(-1)
        if sigma2.shape != (2,) or np.any(~np.isfinite(sigma2)) or np.any(sigma2 <= 0):
            raise ValueError(f"noise variances must be two positive numbers, got {noise_var}")
        source_s2 = "given"
    distinct = distinct_orientations(poses, sigma2)
    if distinct < POSES_NEEDED:
        raise NotIdentifiableError(
            f"{where}the {P} poses hold only {distinct} distinct orientation"
            f"{'s' if distinct != 1 else ''} (poses whose mean readings agree within "
            f"{SAME_POSE_STD:g} std count as one): at least {POSES_NEEDED} are needed to "
            "identify bias and scale of both axes; hold the sensor in other orientations")
    w = np.sqrt(poses.n[:, None] / sigma2[None, :])
    means = poses.means

    def fun(x):
        return _residuals_and_jacobian(x, means, w, g)[0]

    def jac(x):
        return _residuals_and_jacobian(x, means, w, g)[1]

    x0 = _initial(means, g)
    sol = optimize.least_squares(fun, x0, jac=jac, method="lm", max_nfev=200 * (4 + P))
    x = sol.x
    # Gauss–Newton polish (quadratic near the solution): LM stops on its step-size test with
    # a gradient of ≈ 1e-6, so the last digits would depend on the order of the samples.
    for _ in range(10):
        r, J = _residuals_and_jacobian(x, means, w, g)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + step
        if np.max(np.abs(step)) <= 1e-15 * (1.0 + np.max(np.abs(x))):
            break
    r, J = _residuals_and_jacobian(x, means, w, g)
    # Covariance by QR of the column-equilibrated Jacobian: cov = D⁻¹ R⁻¹ R⁻ᵀ D⁻¹
    norms = np.linalg.norm(J, axis=0)
    norms[norms == 0] = 1.0
    Js = J / norms
    _, R = np.linalg.qr(Js)
    sv = np.linalg.svd(R, compute_uv=False)
    m, n = Js.shape
    rank = int(np.sum(sv > sv[0] * max(m, n) * np.finfo(float).eps))
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if rank < n or cond > COND_REFUSE:
        _, _, vt = np.linalg.svd(Js)
        weak = np.abs(vt[-1][:4])  # the calibration parameters in the weakest direction
        names = _names(P)
        how = "rank-deficient" if rank < n else f"near-singular (cond {cond:.3g})"
        involved = [names[i] for i in range(4) if weak[i] > 0.1 * np.abs(vt[-1]).max()]
        raise NotIdentifiableError(
            f"{where}the {P} poses cannot identify {' / '.join(involved or names[:4])}: "
            f"the Jacobian is {how}"
            " — the poses do not spread (e.g. all within a narrow arc, or symmetric about both "
            "axes, where a family of ellipses fits); add poses at other orientations")
    Ri = sla.solve_triangular(R, np.eye(n))
    cov_full = (Ri @ Ri.T) / np.outer(norms, norms)
    cov_full = 0.5 * (cov_full + cov_full.T)
    th = np.angle(np.exp(1j * x[4:]))  # wrap to (−π, π]
    params = x[:4].copy()
    resid = means - _model(params, th, g)
    chi2 = float(r @ r)
    dof = P - POSES_NEEDED
    lof = None
    if dof > 0:
        # Joint test on the whitened pose means (Draper & Smith's split, whitened per axis):
        # pure error Σ_a SS_within,a / σ_a² with 2(N − P) dof, lack of fit χ² with P − 4 dof
        ss_pe = float(np.sum(poses.ss_within / sigma2))
        dof_pe = 2 * poses.dof_within
        if source_s2 == "given":
            lof = LackOfFit("xy", P, chi2, ss_pe, dof, dof_pe, "chi2", chi2,
                            float(stats.chi2.sf(chi2, dof)))
        else:
            # σ_a² is the pure error itself, so SS_pe/dof_pe = 1 and F = χ²/(P − 4),
            # referred to F(P − 4, 2(N − P)) (approximate: two axes, two estimated σ²)
            value = chi2 / dof
            lof = LackOfFit("xy", P, chi2, ss_pe, dof, dof_pe, "F", value,
                            float(stats.f.sf(value, dof, dof_pe)))
    fit = MultiPositionFit(
        params=params, cov=cov_full[:4, :4], angles=th,
        angles_std=np.sqrt(np.diag(cov_full)[4:]), poses=poses, residuals=resid,
        sigma2=sigma2, sigma2_source=source_s2, sigma2_dof=poses.dof_within, dof=dof,
        chi2=chi2, rank=rank, cond=cond, max_gap=_largest_gap(th), g=float(g),
        lack_of_fit=lof)
    limit = np.array([UNIDENTIFIED_STD["bias"] * g, UNIDENTIFIED_STD["scale"]] * 2)
    bad = [nm for nm, sd, lim in zip(JOINT_PARAM_NAMES, fit.std, limit, strict=True)
           if not sd <= lim]
    if bad:
        raise NotIdentifiableError(
            f"{where}the {P} poses do not identify {' / '.join(bad)} (std "
            f"{', '.join(f'{fit.std[JOINT_PARAM_NAMES.index(nm)]:.3g}' for nm in bad)}; "
            f"condition number {cond:.3g}, largest gap between pose directions "
            f"{np.degrees(fit.max_gap):.0f}°): the poses do not spread (all within a narrow "
            "arc, or symmetric about both axes); add poses at other orientations around the "
            "turn")
    if cond > COND_WARN:
        warnings.warn(
            f"{where}the poses identify the calibration only poorly (condition number "
            f"{cond:.3g}, largest gap between pose directions "
            f"{np.degrees(fit.max_gap):.0f}°): std = {np.round(fit.std, 5).tolist()}; spread "
            "the poses around the whole turn", PoorlyIdentifiedWarning, stacklevel=2)
    return fit


# --- the 3-axis fit: gravity on the sphere -------------------------------------------------

POSES_NEEDED_3D = 7
"""Fewest held poses for the 3-axis fit. Unknowns: bias and scale of three axes (6) and each
pose's gravity direction (2 angles); each pose brings 3 readings, so P poses leave P − 6 dof.
Six poses in general position fit an axis-aligned ellipsoid exactly: nothing would check the
fit, and an error outside the model (misalignment, a pose that moved) would pass unseen. The
rule is therefore P ≥ 7 (one dof for the lack-of-fit test); 9 or more spread over the sphere
are recommended."""

SPHERE_EIG_MIN = 0.02
"""Smallest eigenvalue of the directions' scatter matrix ``S = (1/P) Σ u_i u_iᵀ`` (1/3 for
directions spread evenly over the sphere; 0 when every direction lies on one great circle)
under which the directions do not span three dimensions: an axis-aligned ellipsoid through a
planar conic is not unique, so the set is refused (the tilt plane alone is then the planar
fit's job). 0.02 is all directions within ≈ 8° of one great circle."""

PARAM_NAMES_3D: tuple[str, ...] = JOINT_PARAM_NAMES + ("bias_n", "scale_n")
"""``[bias_x, scale_x, bias_y, scale_y, bias_n, scale_n]``: the tilt plane's four (in the
planar fit's order, so the first four and their 4×4 block are the :class:`Calibration`'s),
then the normal axis's (``n``: the log's third axis, :attr:`calib.logs.ImuLog.acc_normal`)."""

AXES_3D = ("x", "y", "n")


def quantization_step(values: np.ndarray) -> float:
    """The step q of readings on a lattice (m/s² if they are), else 0: the smallest gap
    between distinct values, kept only when every value is a whole number of steps from the
    smallest (within 1e-6 of a step) and the values take at least 3 levels — raw counts
    converted to m/s². Continuous readings (floats with noise) give 0."""
    u = np.unique(np.asarray(values, dtype=float))
    if u.size < 3:
        return 0.0
    q = float(np.diff(u).min())
    if q <= 0 or (u[-1] - u[0]) / q > 1e7:
        return 0.0
    k = (u - u[0]) / q
    return q if np.all(np.abs(k - np.round(k)) <= 1e-6) else 0.0


@dataclass(frozen=True, eq=False)
class MultiPosition3DFit(ResultMixin):
    """Bias and scale of three axes from held poses, no angle reference
    (:func:`fit_multiposition3d`).

    Attributes
    ----------
    params : (6,) :data:`PARAM_NAMES_3D` (m/s², 1, m/s², 1, m/s², 1).
    cov : (6, 6) their covariance (the pose directions marginalised).
    directions : (P, 3) unit vectors ``u_i``, the direction of each pose's reference reading
        ``A_r = g·u_i`` in the sensor's (x, y, n) axes (up: a sensor axis pointing up reads
        +g); directions_std : (P,) rad, the rms angular std of each (tangent plane).
    poses : the :class:`Poses` (3 axes) the fit used.
    residuals : (P, 3) m/s², pose mean − model.
    sigma2 : (3,) (m/s²)², per-sample noise variance per axis; ``sigma2_source`` "given" or
        "estimated" (pure error with N − P dof, floored at q²/12).
    quantization : (3,) m/s², step q of each axis's readings (0: continuous).
    dof : P − 6.  chi2 : Σ r² (whitened).  rank, cond : of the equilibrated Jacobian.
    min_eig : smallest eigenvalue of the directions' scatter matrix (1/3 at best).
    largest_cap : rad, angular radius of the largest spherical cap holding no direction.
    g : m/s².  lack_of_fit : joint test (axis "xyn"), None when dof = 0.
    """

    params: np.ndarray
    cov: np.ndarray
    directions: np.ndarray
    directions_std: np.ndarray
    poses: Poses
    residuals: np.ndarray
    sigma2: np.ndarray
    sigma2_source: Sigma2Source
    sigma2_dof: int
    quantization: np.ndarray
    dof: int
    chi2: float
    rank: int
    cond: float
    min_eig: float
    largest_cap: float
    g: float
    lack_of_fit: LackOfFit | None = None
    param_names: tuple[str, ...] = field(default=PARAM_NAMES_3D)

    _TITLE = "Multi-position calibration, 3 axes (no angle reference)"
    _UNITS = ("bias m/s²; scale dimensionless; directions unit vectors; directions_std rad; "
              "σ² (m/s²)²; quantization m/s²; residuals m/s²; g m/s²")
    JSON_UNITS = {
        "axes": "count", "params": "[m/s², 1, m/s², 1, m/s², 1]",
        "std": "[m/s², 1, m/s², 1, m/s², 1]",
        "cov": "products of the params' units", "directions": "1 (unit vectors, x, y, n)",
        "directions_std": "rad", "residuals": "m/s²", "sigma2": "(m/s²)²",
        "sigma2_dof": "count", "quantization": "m/s²", "dof": "count", "chi2": "1",
        "rank": "count", "cond": "1", "min_eig": "1", "largest_cap": "rad", "g": "m/s²",
        "poses.labels": "—", "poses.n": "count", "poses.means": "m/s²", "poses.ss": "(m/s²)²",
    }

    def __post_init__(self) -> None:
        for name in ("params", "cov", "directions", "directions_std", "residuals", "sigma2",
                     "quantization"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "param_names", tuple(self.param_names))

    @property
    def std(self) -> np.ndarray:
        """(6,) standard deviations of ``params``."""
        return np.sqrt(np.diag(self.cov))

    @property
    def n(self) -> int:
        return int(self.poses.n.sum())

    @property
    def bias(self) -> np.ndarray:
        """(3,) m/s², x, y, n."""
        return self.params[[0, 2, 4]]

    @property
    def scale(self) -> np.ndarray:
        """(3,) x, y, n."""
        return self.params[[1, 3, 5]]

    @property
    def chi2_dof(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    def quantile(self, level: float) -> float:
        """Two-sided quantile: normal (σ² given) or Student t with ``sigma2_dof``."""
        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level}")
        q = 0.5 + level / 2
        return float(stats.norm.ppf(q) if self.sigma2_source == "given"
                     else stats.t.ppf(q, self.sigma2_dof))

    def conf_int(self, level: float = 0.95) -> np.ndarray:
        """(6, 2) two-sided intervals at ``level``."""
        half = self.quantile(level) * self.std
        return np.column_stack([self.params - half, self.params + half])

    def summary(self, level: float = 0.95) -> str:
        lo, hi = self.conf_int(level).T
        pct = f"{100 * level:g}%"
        out = [f"Calibration: multi-position, 3 axes (gravity norm, no angle reference), "
               f"g = {self.g} m/s², N = {self.n}, {self.poses.count} poses",
               f"{'param':<9}{'unit':<6}{'estimate':>14}{'std':>13}{'[' + pct:>14}"
               f"{pct + ']':>13}"]
        for i, name in enumerate(self.param_names):
            unit = "m/s²" if name.startswith("bias") else "1"
            out.append(f"{name:<9}{unit:<6}{self.params[i]:>14.6g}{self.std[i]:>13.4g}"
                       f"{lo[i]:>14.6g}{hi[i]:>13.6g}")
        s2 = ", ".join(f"{v:.4g}" for v in self.sigma2)
        src = ("given" if self.sigma2_source == "given"
               else f"estimated within poses, dof {self.sigma2_dof}")
        fit_line = (f"χ²/dof = {self.chi2_dof:.4f}; dof = {self.dof}" if self.dof > 0
                    else "dof = 0")
        out.append(f"σ² = {s2} (m/s²)² per sample ({src}); {fit_line}")
        if np.any(self.quantization > 0):
            qs = ", ".join(f"{v:.4g}" for v in self.quantization)
            out.append(f"quantization step q = {qs} m/s²: each pose mean's variance is "
                       "σ²/n + q²/12 (a mean does not average quantization away when the "
                       "noise is below a step)")
        out.append(f"identifiability: {self.poses.count} poses, smallest eigenvalue of the "
                   f"directions' scatter {self.min_eig:.3f} (1/3 at best), largest empty cap "
                   f"{np.degrees(self.largest_cap):.1f}°, rank {self.rank}, "
                   f"cond = {self.cond:.3g}")
        out.append("pose   n     direction (x, y, n)      std (deg)  resid x m/s²  resid y m/s²"
                   "  resid n m/s²")
        for k in range(self.poses.count):
            u = self.directions[k]
            out.append(f"{self.poses.labels[k]:>4}{self.poses.n[k]:>7}  "
                       f"{u[0]:>+7.4f}{u[1]:>+8.4f}{u[2]:>+8.4f}"
                       f"{np.degrees(self.directions_std[k]):>12.3g}"
                       + "".join(f"{v:>14.4g}" for v in self.residuals[k]))
        if self.lack_of_fit is not None:
            out.append(self.lack_of_fit.summary())
        return "\n".join(out)

    def to_dict(self) -> dict:
        return {
            "method": "multiposition", "axes": 3, "param_names": list(self.param_names),
            "params": self.params.tolist(), "std": self.std.tolist(), "cov": self.cov.tolist(),
            "directions": self.directions.tolist(),
            "directions_std": self.directions_std.tolist(), "poses": self.poses.to_dict(),
            "residuals": self.residuals.tolist(), "sigma2": self.sigma2.tolist(),
            "sigma2_source": self.sigma2_source, "sigma2_dof": self.sigma2_dof,
            "quantization": self.quantization.tolist(), "dof": self.dof, "chi2": self.chi2,
            "rank": self.rank, "cond": self.cond, "min_eig": self.min_eig,
            "largest_cap": self.largest_cap, "g": self.g,
            "lack_of_fit": None if self.lack_of_fit is None else self.lack_of_fit.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict) -> MultiPosition3DFit:
        """Rebuild from :meth:`to_dict` (exact)."""
        lof = d.get("lack_of_fit")
        return cls(
            params=d["params"], cov=d["cov"],
            directions=np.asarray(d["directions"], float).reshape(-1, 3),
            directions_std=d["directions_std"], poses=Poses.from_dict(d["poses"]),
            residuals=np.asarray(d["residuals"], float).reshape(-1, 3), sigma2=d["sigma2"],
            sigma2_source=d["sigma2_source"], sigma2_dof=int(d["sigma2_dof"]),
            quantization=d["quantization"], dof=int(d["dof"]), chi2=float(d["chi2"]),
            rank=int(d["rank"]), cond=float(d["cond"]), min_eig=float(d["min_eig"]),
            largest_cap=float(d["largest_cap"]), g=float(d["g"]),
            lack_of_fit=None if lof is None else LackOfFit.from_dict(lof),
            param_names=tuple(d["param_names"]))

    def to_calibration(self):
        """The project's :class:`calib.calibration.Calibration` of the tilt plane (method
        "multiposition"): the first four parameters and their 4×4 block (the normal axis and
        the directions marginalised), as :meth:`MultiPositionFit.to_calibration`; the normal
        axis's bias and scale ride along in the joint fit's ``extra["normal"]``.

        Per axis χ² of the samples ``(SS_within + Σ n_i r_i²) / σ²`` with ``dof = N − P``,
        residuals the pose means' (m/s²)."""
        from calib.calibration import Calibration

        chi2 = (self.poses.ss_within
                + np.sum(self.poses.n[:, None] * self.residuals**2, axis=0)) / self.sigma2
        dof = self.sigma2_dof
        extra = {"sigma2_dof": self.sigma2_dof} if self.sigma2_source == "estimated" else {}
        fits = {}
        for k, a in enumerate(AXES):
            sl = slice(2 * k, 2 * k + 2)
            fits[a] = FitResult(PARAM_NAMES, self.params[sl], self.cov[sl, sl],
                                self.residuals[:, k], self.sigma2[k], self.sigma2_source,
                                dof, 2, self.cond, float(chi2[k]), dict(extra))
        normal = {"params": self.params[4:].tolist(), "std": self.std[4:].tolist(),
                  "param_names": list(self.param_names[4:])}
        joint = FitResult(JOINT_PARAM_NAMES, self.params[:4], self.cov[:4, :4],
                          self.residuals[:, :2], self.sigma2[:2], self.sigma2_source, 2 * dof,
                          4, self.cond, float(chi2[:2].sum()), {**extra, "normal": normal})
        return Calibration("multiposition", self.g, fits, self.n, joint=joint)


def quantization_steps(acc: np.ndarray) -> np.ndarray:
    """(k,) m/s²: :func:`quantization_step` of each column of readings ``acc`` (N, k)."""
    acc = np.asarray(acc, dtype=float)
    return np.array([quantization_step(acc[:, k]) for k in range(acc.shape[1])])


def three_axis_applies(poses: Poses, g: float = G) -> str | None:
    """None when the 3-axis fit applies to ``poses`` (3 axes), else why not — the planar fit
    of the tilt plane is then the one to make (``calibrate`` chooses it and says why): fewer
    than :data:`POSES_NEEDED_3D` poses (a six-position tumble log), or poses that hardly turn
    the normal axis (span under :data:`SPAN_FRACTION`·g: a tilt table turning in its plane)."""
    if poses.axes != 3:
        return "the log has no third axis"
    if poses.count < POSES_NEEDED_3D:
        return (f"{poses.count} held poses, the 3-axis fit needs at least {POSES_NEEDED_3D} "
                "(6 unknowns, and a 7th pose to check the fit)")
    span = float(np.ptp(poses.means[:, 2]))
    if span < SPAN_FRACTION * g:
        return (f"the poses hardly turn the normal axis (its pose means span {span:.3g} m/s², "
                f"under {SPAN_FRACTION:g}·g)")
    return None


def _tangent_basis(u: np.ndarray) -> np.ndarray:
    """(P, 3, 2): two orthonormal vectors perpendicular to each unit vector ``u`` (P, 3)."""
    helper = np.eye(3)[np.argmin(np.abs(u), axis=1)]
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(u, e1)
    return np.stack([e1, e2], axis=2)


def _residuals3(x: np.ndarray, means: np.ndarray, sd: np.ndarray, g: float, u0: np.ndarray,
                E: np.ndarray):
    """Whitened residuals (3P,), pose-major, their Jacobian (3P, 6 + 2P) and the directions.

    Unknowns ``x = [bx, sx, by, sy, bn, sn, δ_1 (2), …, δ_P (2)]``; each direction is
    ``u_i = v_i/|v_i|``, ``v_i = u0_i + E_i δ_i`` (a chart of the sphere around ``u0_i``,
    smooth everywhere near δ = 0, unlike two spherical angles at their poles); at δ = 0 the
    two components of δ_i are the direction's angles along ``E_i``, in rad."""
    P = means.shape[0]
    b, k = x[0:6:2], 1.0 + x[1:6:2]
    d = x[6:].reshape(P, 2)
    v = u0 + np.einsum("pij,pj->pi", E, d)
    nv = np.linalg.norm(v, axis=1)
    u = v / nv[:, None]
    r = ((means - b - k * g * u) / sd).ravel()
    J = np.zeros((3 * P, 6 + 2 * P))
    rows = np.arange(3 * P).reshape(P, 3)
    for a in range(3):
        J[rows[:, a], 2 * a] = -1.0 / sd[:, a]
        J[rows[:, a], 2 * a + 1] = -g * u[:, a] / sd[:, a]
    proj = np.eye(3)[None] - u[:, :, None] * u[:, None, :]
    dud = np.einsum("pij,pjk->pik", proj, E) / nv[:, None, None]
    blk = -(k * g)[None, :, None] * dud / sd[:, :, None]
    cols = 6 + 2 * np.arange(P)[:, None, None] + np.arange(2)[None, None, :]
    J[rows[:, :, None], cols] = blk
    return r, J, u


def _initial3(means: np.ndarray, g: float) -> np.ndarray:
    """Start: an algebraic axis-aligned ellipsoid ``x² + c₁y² + c₂z² + d·(x, y, z) + f = 0``
    through the pose means (linear least squares, units of g); the ideal sensor (b = 0,
    s = 0) when that is not a plausible ellipsoid. Returns ``[bx, sx, by, sy, bn, sn]``."""
    u = means / g
    A = np.column_stack([u[:, 1] ** 2, u[:, 2] ** 2, u, np.ones(len(u))])
    sol, *_ = np.linalg.lstsq(A, -u[:, 0] ** 2, rcond=None)
    c1, c2, d1, d2, d3, f = sol
    p = np.zeros(6)
    if c1 > 0 and c2 > 0:
        b = np.array([-d1 / 2, -d2 / (2 * c1), -d3 / (2 * c2)])
        rx2 = b[0] ** 2 + c1 * b[1] ** 2 + c2 * b[2] ** 2 - f
        if rx2 > 0:
            radii = np.sqrt(rx2 / np.array([1.0, c1, c2]))
            if np.all(np.abs(radii - 1) < 0.5):
                p = np.ravel(np.column_stack([b * g, radii - 1]))
    return p


def _largest_cap(u: np.ndarray, grid: int = 4000) -> float:
    """rad: the angular radius of the largest spherical cap with no direction inside, on a
    Fibonacci grid of ``grid`` points (resolution ≈ 2°): max over the grid of the angle to
    the nearest direction. Poses evenly over the sphere leave small caps; all poses in one
    hemisphere leave one of ≥ 90°."""
    i = np.arange(grid) + 0.5
    z = 1 - 2 * i / grid
    phi = np.pi * (1 + 5**0.5) * i
    rho = np.sqrt(1 - z * z)
    pts = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    nearest = np.max(pts @ u.T, axis=1)
    return float(np.arccos(np.clip(nearest.min(), -1.0, 1.0)))


def fit_multiposition3d(
    poses: Poses, noise_var=None, g: float = G, quantization=None, source: str = "<memory>",
) -> MultiPosition3DFit:
    """Bias and scale of three axes from held poses in arbitrary orientations, no angle
    reference: the gravity-norm constraint on the sphere (Skog & Händel 2006; Frosio et al.
    2009), for a 3-axis IMU held still in several orientations (a phone, a wrist sensor).

    Model (course sensor model per axis, ``A_m = (1 + s)·A_r + b``), pose i, axis a::

        m̄_ia = b_a + (1 + s_a)·g·u_ia + ē_ia,     |u_i| = 1,
        ē_ia ~ N(0, σ_a²/n_i + q_a²/12)

    i.e. ``‖(m̄_i − b) ⊘ (1 + s)‖ = g``: the pose means lie on an axis-aligned ellipsoid with
    centre b and semi-axes (1 + s)·g. ``u_i`` is the unit direction of the reference reading
    (the sensor's up, in its (x, y, n) axes; planar course signs: ``u = (−sin θ, −cos θ, 0)``).
    Unknowns: the six parameters (:data:`PARAM_NAMES_3D`) and each ``u_i`` (two angles, a
    chart of the sphere around the current direction, re-centred at every Gauss–Newton
    step); maximum likelihood = least squares of the whitened residuals
    ``(m̄_ia − b_a − (1 + s_a) g u_ia) / sd_ia`` (3P residuals, 6 + 2P unknowns, P − 6 dof).

    Variance of a pose mean: ``σ_a²/n_i + q_a²/12``. The first term is the noise; the second
    is quantization of step ``q_a``: when the noise is below a step the readings sit on one or
    two levels and their mean is off the true value by up to q/2 whatever n — a fixed error,
    uniform over the poses' unknown positions on the lattice, of variance q²/12 (Widrow &
    Kollár, *Quantization Noise*, 2008: exact without dither, an upper bound when the noise
    dithers the quantizer, so the intervals are then conservative). σ_a² given (normal
    quantiles) or the pure error ``Σ_i SS_ia / (N − P)`` (Student t, N − P dof), floored at
    ``q_a²/12`` (quantized readings scatter at least that much once the noise dithers them;
    below it the pure error says nothing about the noise).

    Covariance from the whitened Jacobian at the solution: QR of its column-equilibrated
    form, ``cov = D⁻¹R⁻¹R⁻ᵀD⁻¹`` (no normal matrix inverted); the 6×6 block includes what the
    unknown directions cost.

    Identifiability (refused with one line, :class:`NotIdentifiableError`): fewer than
    :data:`POSES_NEEDED_3D` poses or distinct orientations; an axis whose pose means span
    less than :data:`SPAN_FRACTION`·g (``scale_<axis>`` named); directions whose scatter
    matrix has its smallest eigenvalue below :data:`SPHERE_EIG_MIN` (all near one great
    circle); a rank-deficient or near-singular Jacobian (cond > :data:`COND_REFUSE`), or a
    std above :data:`UNIDENTIFIED_STD` (parameters named). Reported: poses, the smallest
    eigenvalue, the largest empty cap, rank, cond; a warning above :data:`COND_WARN`.

    Parameters
    ----------
    poses : held poses with 3 axes (:func:`pose_statistics` of (N, 3) readings).
    noise_var : (3,) σ² per axis, (m/s²)², or None (pure error).
    g : m/s².
    quantization : (3,) m/s², step of each axis's readings (:func:`quantization_step`), or
        None (continuous readings).
    source : the file name, for messages.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1],
    ...               [0.6, 0.48, 0.64]])
    >>> p = np.array([0.1, 0.02, -0.2, -0.01, 0.3, 0.03])
    >>> means = p[0::2] + (1 + p[1::2]) * 9.8 * u
    >>> fit = fit_multiposition3d(Poses(np.arange(7), [100] * 7, means, np.ones((7, 3))),
    ...                           [0.25, 0.25, 0.25])
    >>> np.round(fit.params, 9).tolist()
    [0.1, 0.02, -0.2, -0.01, 0.3, 0.03]
    """
    where = "" if source == "<memory>" else f"{source}: "
    if poses.axes != 3:
        raise ValueError("the 3-axis fit needs poses with three axes (x, y, normal)")
    P = poses.count
    if P < POSES_NEEDED_3D:
        raise NotIdentifiableError(
            f"{where}{P} held pose{'s' if P != 1 else ''}: the 3-axis multi-position "
            f"calibration needs at least {POSES_NEEDED_3D} (bias and scale of three axes are 6 "
            "unknowns and each pose brings 3 readings with 2 unknown direction angles, so 6 "
            "poses fit exactly and only a 7th checks the fit); hold the sensor in more "
            "orientations, 9 or more spread over all sides")
    q = np.zeros(3) if quantization is None else np.asarray(quantization, float).reshape(-1)
    if q.shape != (3,) or np.any(~np.isfinite(q)) or np.any(q < 0):
        raise ValueError(f"quantization must be three steps ≥ 0, got {quantization}")
    span = np.ptp(poses.means, axis=0)
    for k, a in enumerate(AXES_3D):
        if span[k] < SPAN_FRACTION * g:
            raise NotIdentifiableError(
                f"{where}cannot identify scale_{a}: the {P} poses hardly turn the {a} axis (its "
                f"pose means span only {span[k]:.3g} m/s², under {SPAN_FRACTION:g}·g); hold "
                f"poses where {a} reads clearly different values (e.g. {a} up and {a} down)"
                + ("; or calibrate the tilt plane alone (planar fit)" if a == "n" else ""))
    if noise_var is None:
        if poses.dof_within <= 0:
            raise DataError(f"{where}every pose has a single sample: σ² cannot be estimated "
                            "within the poses; give --noise-var σx²,σy²,σn²")
        sigma2 = np.maximum(poses.ss_within / poses.dof_within, q**2 / 12)
        source_s2: Sigma2Source = "estimated"
        if np.any(sigma2 <= 0):
            raise DataError(f"{where}the readings do not scatter within the poses (zero "
                            "variance on an axis): give --noise-var σx²,σy²,σn²")
    else:
        sigma2 = np.asarray(noise_var, dtype=float).reshape(-1)
        if sigma2.shape != (3,) or np.any(~np.isfinite(sigma2)) or np.any(sigma2 <= 0):
            raise ValueError(f"noise variances must be three positive numbers, got {noise_var}")
        source_s2 = "given"
    distinct = distinct_orientations(poses, sigma2, q**2 / 12)
    if distinct < POSES_NEEDED_3D:
        raise NotIdentifiableError(
            f"{where}the {P} poses hold only {distinct} distinct orientation"
            f"{'s' if distinct != 1 else ''} (poses whose mean readings agree within "
            f"{SAME_POSE_STD:g} std count as one): at least {POSES_NEEDED_3D} are needed for "
            "the 3-axis fit; hold the sensor in other orientations")
    means = poses.means
    sd = np.sqrt(sigma2[None, :] / poses.n[:, None] + q[None, :] ** 2 / 12)
    p0 = _initial3(means, g)
    u0 = (means - p0[0::2]) / (1 + p0[1::2])
    u0 /= np.linalg.norm(u0, axis=1, keepdims=True)
    eig = np.linalg.eigvalsh(u0.T @ u0 / P)
    if eig[0] < SPHERE_EIG_MIN:
        vec = np.linalg.eigh(u0.T @ u0)[1][:, 0]
        raise NotIdentifiableError(
            f"{where}the {P} pose directions do not span three dimensions (smallest "
            f"eigenvalue of their scatter {eig[0]:.3g} < {SPHERE_EIG_MIN:g}: all lie near the "
            f"great circle normal to ({vec[0]:+.2f}, {vec[1]:+.2f}, {vec[2]:+.2f}) in x, y, n), "
            "so an ellipsoid through them is not unique; add poses off that circle, or "
            "calibrate the tilt plane alone (planar fit)")
    E = _tangent_basis(u0)

    def fun(x):
        return _residuals3(x, means, sd, g, u0, E)[0]

    def jac(x):
        return _residuals3(x, means, sd, g, u0, E)[1]

    sol = optimize.least_squares(fun, np.concatenate([p0, np.zeros(2 * P)]), jac=jac,
                                 method="lm", max_nfev=200 * (6 + 2 * P))
    params = sol.x[:6].copy()
    u = _residuals3(sol.x, means, sd, g, u0, E)[2]
    # Gauss–Newton polish on the sphere: re-centre each chart at the current direction (δ = 0)
    # so the last digits do not depend on where LM stopped
    for _ in range(20):
        E = _tangent_basis(u)
        x = np.concatenate([params, np.zeros(2 * P)])
        r, J, _ = _residuals3(x, means, sd, g, u, E)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + step
        params = x[:6]
        u = _residuals3(x, means, sd, g, u, E)[2]
        if np.max(np.abs(step)) <= 1e-15 * (1.0 + np.max(np.abs(params))):
            break
    E = _tangent_basis(u)
    x = np.concatenate([params, np.zeros(2 * P)])
    r, J, u = _residuals3(x, means, sd, g, u, E)
    norms = np.linalg.norm(J, axis=0)
    norms[norms == 0] = 1.0
    Js = J / norms
    _, R = np.linalg.qr(Js)
    sv = np.linalg.svd(R, compute_uv=False)
    m, n = Js.shape
    rank = int(np.sum(sv > sv[0] * max(m, n) * np.finfo(float).eps))
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if rank < n or cond > COND_REFUSE:
        _, _, vt = np.linalg.svd(Js)
        weak = np.abs(vt[-1][:6])
        how = "rank-deficient" if rank < n else f"near-singular (cond {cond:.3g})"
        involved = [PARAM_NAMES_3D[i] for i in range(6)
                    if weak[i] > 0.1 * np.abs(vt[-1]).max()]
        raise NotIdentifiableError(
            f"{where}the {P} poses cannot identify {' / '.join(involved or PARAM_NAMES_3D)}: "
            f"the Jacobian is {how} — the pose directions do not spread over the sphere; add "
            "poses with other sides up")
    Ri = sla.solve_triangular(R, np.eye(n))
    cov_full = (Ri @ Ri.T) / np.outer(norms, norms)
    cov_full = 0.5 * (cov_full + cov_full.T)
    dvar = np.diag(cov_full)[6:].reshape(P, 2).sum(axis=1)
    resid = means - params[0::2] - (1 + params[1::2]) * g * u
    chi2 = float(r @ r)
    dof = P - 6
    lof = None
    if dof > 0:
        ss_pe = float(np.sum(poses.ss_within / sigma2))
        dof_pe = 3 * poses.dof_within
        if source_s2 == "given":
            lof = LackOfFit("xyn", P, chi2, ss_pe, dof, dof_pe, "chi2", chi2,
                            float(stats.chi2.sf(chi2, dof)))
        elif dof_pe > 0:
            value = chi2 / dof
            lof = LackOfFit("xyn", P, chi2, ss_pe, dof, dof_pe, "F", value,
                            float(stats.f.sf(value, dof, dof_pe)))
    fit = MultiPosition3DFit(
        params=params, cov=cov_full[:6, :6], directions=u, directions_std=np.sqrt(dvar),
        poses=poses, residuals=resid, sigma2=sigma2, sigma2_source=source_s2,
        sigma2_dof=poses.dof_within, quantization=q, dof=dof, chi2=chi2, rank=rank,
        cond=cond, min_eig=float(np.linalg.eigvalsh(u.T @ u / P)[0]),
        largest_cap=_largest_cap(u), g=float(g), lack_of_fit=lof)
    limit = np.array([UNIDENTIFIED_STD["bias"] * g, UNIDENTIFIED_STD["scale"]] * 3)
    bad = [nm for nm, sdv, lim in zip(PARAM_NAMES_3D, fit.std, limit, strict=True)
           if not sdv <= lim]
    if bad:
        raise NotIdentifiableError(
            f"{where}the {P} poses do not identify {' / '.join(bad)} (std "
            f"{', '.join(f'{fit.std[PARAM_NAMES_3D.index(nm)]:.3g}' for nm in bad)}; condition "
            f"number {cond:.3g}, largest empty cap {np.degrees(fit.largest_cap):.0f}°): the "
            "pose directions do not spread over the sphere; add poses with other sides up")
    if cond > COND_WARN:
        warnings.warn(
            f"{where}the poses identify the 3-axis calibration only poorly (condition number "
            f"{cond:.3g}, largest empty cap {np.degrees(fit.largest_cap):.0f}°): std = "
            f"{np.round(fit.std, 5).tolist()}; spread the poses over all sides",
            PoorlyIdentifiedWarning, stacklevel=2)
    return fit


@dataclass(frozen=True, eq=False)
class MethodComparison(ResultMixin):
    """The multi-position estimates against the θ-based least squares on the same run.

    ``z = (p_mp − p_ls) / sqrt(var_mp + var_ls)`` per parameter: the difference in units of
    the combined std. Both use the same readings, so their errors are positively correlated
    and this std is conservative (|z| tends to be small when both are right); when the
    θ-based fit is efficient, ``var(p_mp − p_ls) = var_mp − var_ls`` (Hausman 1978) is the
    exact spread, reported as ``z_hausman`` (NaN, null in JSON, where that difference is not
    positive).
    """

    param_names: tuple[str, ...]
    multiposition: np.ndarray
    multiposition_std: np.ndarray
    least_squares: np.ndarray
    least_squares_std: np.ndarray

    _TITLE = "Multi-position vs θ-based least squares"
    _UNITS = "bias m/s²; scale dimensionless; z dimensionless"
    JSON_UNITS = {"multiposition": "[m/s², 1, m/s², 1]",
                  "multiposition_std": "[m/s², 1, m/s², 1]",
                  "least_squares": "[m/s², 1, m/s², 1]",
                  "least_squares_std": "[m/s², 1, m/s², 1]",
                  "difference": "[m/s², 1, m/s², 1]", "combined_std": "[m/s², 1, m/s², 1]",
                  "z": "1", "z_hausman": "1"}

    def __post_init__(self) -> None:
        for name in ("multiposition", "multiposition_std", "least_squares",
                     "least_squares_std"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "param_names", tuple(self.param_names))

    @property
    def difference(self) -> np.ndarray:
        return self.multiposition - self.least_squares

    @property
    def combined_std(self) -> np.ndarray:
        return np.hypot(self.multiposition_std, self.least_squares_std)

    @property
    def z(self) -> np.ndarray:
        return self.difference / self.combined_std

    @property
    def z_hausman(self) -> np.ndarray:
        v = self.multiposition_std**2 - self.least_squares_std**2
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(v > 0, self.difference / np.sqrt(np.where(v > 0, v, 1.0)), np.nan)

    def summary(self) -> str:
        rows = [f"{'param':<9}{'multi-position':>16}{'least squares':>16}{'difference':>13}"
                f"{'z':>8}"]
        for i, name in enumerate(self.param_names):
            rows.append(f"{name:<9}{self.multiposition[i]:>16.6g}{self.least_squares[i]:>16.6g}"
                        f"{self.difference[i]:>13.4g}{self.z[i]:>8.2f}")
        rows.append("z = difference / sqrt(std_mp² + std_ls²) (combined std)")
        return "\n".join(rows)

    def to_dict(self) -> dict:
        return {"param_names": list(self.param_names),
                "multiposition": self.multiposition.tolist(),
                "multiposition_std": self.multiposition_std.tolist(),
                "least_squares": self.least_squares.tolist(),
                "least_squares_std": self.least_squares_std.tolist(),
                "difference": self.difference.tolist(),
                "combined_std": self.combined_std.tolist(), "z": self.z.tolist(),
                "z_hausman": [float(v) if np.isfinite(v) else None for v in self.z_hausman]}

    @classmethod
    def from_dict(cls, d: dict) -> MethodComparison:
        return cls(tuple(d["param_names"]), d["multiposition"], d["multiposition_std"],
                   d["least_squares"], d["least_squares_std"])


def compare_methods(mp, ls) -> MethodComparison:
    """:class:`MethodComparison` of a multi-position fit (planar or 3-axis: its tilt-plane
    parameters, the first four) and a θ-based :class:`calib.calibration.Calibration` of the
    same readings."""
    return MethodComparison(JOINT_PARAM_NAMES, mp.params[:4], mp.std[:4], ls.params, ls.std)


def multiposition_document(fit: MultiPositionFit | MultiPosition3DFit,
                           comparison: MethodComparison | None, chosen: str) -> dict:
    """The ``calibrate --method multiposition --json`` object: ``method``, how it was
    ``chosen`` ("given" or "automatic: θ unknown"), the ``fit`` (:meth:`MultiPositionFit.to_dict`),
    the ``comparison`` with the θ-based least squares (or None) and ``units``."""
    units = {**nest("fit", {k: v for k, v in type(fit).JSON_UNITS.items()
                            if not k.startswith("lack_of_fit")}),
             **nest("fit.lack_of_fit", LackOfFit.JSON_UNITS),
             **nest("comparison", MethodComparison.JSON_UNITS)}
    return with_units({"method": "multiposition", "chosen": chosen, "fit": fit.to_dict(),
                       "comparison": None if comparison is None else comparison.to_dict()},
                      units)


__all__ = ["COND_REFUSE", "COND_WARN", "PARAM_NAMES_3D", "PLANE_FRACTION", "POSES_NEEDED",
           "POSES_NEEDED_3D", "SAME_POSE_STD", "SPAN_FRACTION", "SPHERE_EIG_MIN",
           "UNIDENTIFIED_STD", "MethodComparison", "MultiPosition3DFit", "MultiPositionFit",
           "OutOfPlaneWarning", "Poses", "compare_methods", "distinct_orientations",
           "fit_multiposition", "fit_multiposition3d", "in_plane", "multiposition_document",
           "pose_statistics", "quantization_step", "quantization_steps",
           "three_axis_applies"]
