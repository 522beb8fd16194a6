"""The planar multi-position fit: bias and scale of the two tilt-plane axes from held poses
with θ unknown, gravity on the circle (:func:`fit_multiposition`; equations and references:
:mod:`calib.calibration.multiposition`)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import linalg as sla
from scipy import optimize, stats

from calib.calibration.lackoffit import LackOfFit
from calib.calibration.ls import FitResult, NotIdentifiableError, PoorlyIdentifiedWarning
from calib.calibration.multiposition.shared import (
    COND_REFUSE,
    COND_WARN,
    SAME_POSE_STD,
    SPAN_FRACTION,
    UNIDENTIFIED_STD,
    PoseFit,
    Poses,
    Sigma2Source,
    distinct_orientations,
)
from calib.conventions import AXES, JOINT_PARAM_NAMES, G
from calib.input_rules import DataError
from calib.results import ResultMixin, readonly

POSES_NEEDED = 4
"""Fewest held poses that identify bias and scale of both axes with θ unknown."""

PLANE_FRACTION = 0.5
"""A pose whose mean reading's norm is off g by more than this fraction is not in the tilt
plane (e.g. a 3-axis IMU lying with z up): it is left out, with a warning."""


@dataclass(frozen=True, eq=False)
class MultiPositionFit(PoseFit, ResultMixin):
    """Bias and scale of both axes from held poses with θ unknown
    (:mod:`calib.calibration.multiposition`).

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

    def summary(self, level: float = 0.95) -> str:
        out = [f"Calibration: multi-position (θ unknown, gravity norm), g = {self.g} m/s², "
               f"N = {self.n}, {self.poses.count} poses",
               *self.param_table(level)]
        out.append(self.sigma2_line(
            "", "dof = 0: 4 poses fit the ellipse exactly (5 or more test the fit)"))
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
        """The project's :class:`calib.calibration.tilt_plane.Calibration` (method "multiposition"):
        the joint 4×4 covariance (with the cross-axis terms the shared angles create) in
        ``joint``, the per-axis marginal blocks in ``fits`` — what ``--save cal.json`` and
        ``trajectory --calibration`` use.

        The fits' χ² is that of the samples, as for the least squares
        (:meth:`~calib.calibration.multiposition.shared.PoseFit.plane_fits`); finite also for P = 4
        poses, where the pose means fit exactly. The joint test of the fit is
        :attr:`lack_of_fit`."""
        from calib.calibration.tilt_plane import Calibration

        fits, chi2, extra = self.plane_fits()
        joint = FitResult(JOINT_PARAM_NAMES, self.params, self.cov, self.residuals,
                          self.sigma2, self.sigma2_source, 2 * self.sigma2_dof, self.rank,
                          self.cond,
                          float(chi2.sum()), {**extra, "angles": self.angles.tolist(),
                                              "angles_std": self.angles_std.tolist()})
        return Calibration("multiposition", self.g, fits, self.n, joint=joint)


def _model(p: np.ndarray, th: np.ndarray, g: float) -> np.ndarray:
    """(P, 2) model readings of the poses: ``b + (1 + s)·A_r(θ)``."""
    return np.column_stack([p[0] + (1 + p[1]) * (-g * np.sin(th)),
                            p[2] + (1 + p[3]) * (-g * np.cos(th))])


def _residuals_and_jacobian(x: np.ndarray, means: np.ndarray, w: np.ndarray, g: float):
    """Whitened residuals (2P,) ordered [x of every pose, y of every pose] and their
    Jacobian (2P, 4 + P) in ``x = [bx, sx, by, sy, θ_1 … θ_P]``
    (:mod:`calib.calibration.multiposition`)."""
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
    """Bias and scale of both axes from held poses, θ unknown
    (:mod:`calib.calibration.multiposition`).

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
