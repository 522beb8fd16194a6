"""The planar multi-position fit: bias and scale of the two tilt-plane axes from held poses
with θ unknown, gravity on the circle (:func:`fit_multiposition`; equations and references:
:mod:`calib.calibration.multiposition`)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from calib.calibration.ls import NotIdentifiableError
from calib.calibration.multiposition.shared import (
    PoseFit,
    PoseProblem,
    Poses,
)
from calib.conventions import AXES, JOINT_PARAM_NAMES, G
from calib.results import ResultMixin

POSES_NEEDED = 4
"""Fewest held poses that identify bias and scale of both axes with θ unknown."""

PLANE_FRACTION = 0.5
"""A pose whose mean reading's norm is off g by more than this fraction is not in the tilt
plane (e.g. a 3-axis IMU lying with z up): it is left out, with a warning."""


@dataclass(frozen=True, eq=False, kw_only=True)
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

    _TITLE = "Multi-position calibration (θ unknown)"
    _UNITS = ("bias m/s²; scale dimensionless; angles rad; σ² (m/s²)²; residuals m/s²; "
              "χ² dimensionless; g m/s²")
    JSON_UNITS = {
        "params": "[m/s², 1, m/s², 1]", "std": "[m/s², 1, m/s², 1]",
        "cov": "products of the params' units", "angles": "rad", "angles_std": "rad",
        "residuals": "m/s²", "sigma2": "(m/s²)²", "sigma2_dof": "count", "dof": "count",
        "chi2": "1", "rank": "count", "cond": "1", "max_gap": "rad", "g": "m/s²",
        "poses.labels": "—", "poses.n": "count", "poses.means": "m/s²", "poses.ss": "(m/s²)²",
        "poses.tau_int": "samples",
    }
    _ARRAYS = (*PoseFit._ARRAYS, "angles", "angles_std")
    _DICT_KEYS = ("param_names", "params", "std", "cov", "angles", "angles_std", "poses",
                  "residuals", "sigma2", "sigma2_source", "sigma2_dof", "dof", "chi2", "rank",
                  "cond", "max_gap", "g", "lack_of_fit")
    _SUMMARY_TITLE = "multi-position (θ unknown, gravity norm)"
    _SIGMA2_LINE = ("", "dof = 0: 4 poses fit the ellipse exactly (5 or more test the fit)")

    angles: np.ndarray
    angles_std: np.ndarray
    max_gap: float
    param_names: tuple[str, ...] = field(default=JOINT_PARAM_NAMES)

    def pose_lines(self) -> list[str]:
        """The identifiability line and each pose's angle, its std and residuals."""
        out = [f"identifiability: {self.poses.count} poses, largest gap between pose "
               f"directions {np.degrees(self.max_gap):.1f}°, rank {self.rank}, "
               f"cond = {self.cond:.3g}",
               "pose   n      θ (deg)   std (deg)   resid x m/s²  resid y m/s²"]
        for k in range(self.poses.count):
            out.append(f"{self.poses.labels[k]:>4}{self.poses.n[k]:>7}"
                       f"{np.degrees(self.angles[k]):>12.3f}{np.degrees(self.angles_std[k]):>12.3g}"
                       f"{self.residuals[k, 0]:>14.4g}{self.residuals[k, 1]:>14.4g}")
        return out

    @classmethod
    def from_dict(cls, d: dict) -> MultiPositionFit:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(**cls.shared_fields(d, 2), angles=d["angles"], angles_std=d["angles_std"],
                   max_gap=float(d["max_gap"]))

    def to_calibration(self):
        """The project's :class:`calib.calibration.tilt_plane.Calibration` (method "multiposition"):
        the joint 4×4 covariance (with the cross-axis terms the shared angles create) in
        ``joint``, the per-axis marginal blocks in ``fits`` — what ``--save cal.json`` and
        ``trajectory --calibration`` use.

        The fits' χ² is that of the samples, as for the least squares
        (:meth:`~calib.calibration.multiposition.shared.PoseFit.plane_fits`); finite also for P = 4
        poses, where the pose means fit exactly. The joint test of the fit is
        :attr:`lack_of_fit`."""
        return self.tilt_plane_calibration(self.rank, {"angles": self.angles.tolist(),
                                                       "angles_std": self.angles_std.tolist()})


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
    return poses.subset(ok), poses.labels[~ok]


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
        poses = poses.subset(slice(None), axes=2)
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
    problem = PoseProblem(poses, g, AXES, where)
    problem.check_spans()
    sigma2, source_s2 = problem.noise_variances(noise_var)
    problem.require_distinct(sigma2, POSES_NEEDED, "to identify bias and scale of both axes")
    w = np.sqrt(poses.n[:, None] / sigma2[None, :])
    means = poses.means

    def model(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _residuals_and_jacobian(x, means, w, g)

    x = problem.solve_lm(model, _initial(means, g), 200 * (4 + P))
    # Gauss–Newton polish (quadratic near the solution): LM stops on its step-size test with
    # a gradient of ≈ 1e-6, so the last digits would depend on the order of the samples.
    for _ in range(10):
        r, J = model(x)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + step
        if np.max(np.abs(step)) <= 1e-15 * (1.0 + np.max(np.abs(x))):
            break
    r, J = model(x)
    cov_full, rank, cond = problem.covariance(
        J, JOINT_PARAM_NAMES, "the poses do not spread (e.g. all within a narrow arc, or "
        "symmetric about both axes, where a family of ellipses fits); add poses at other "
        "orientations")
    th = np.angle(np.exp(1j * x[4:]))  # wrap to (−π, π]
    params = x[:4].copy()
    chi2 = float(r @ r)
    dof = P - POSES_NEEDED
    fit = MultiPositionFit(
        params=params, cov=cov_full[:4, :4], angles=th,
        angles_std=np.sqrt(np.diag(cov_full)[4:]), poses=poses,
        residuals=means - _model(params, th, g), sigma2=sigma2, sigma2_source=source_s2,
        sigma2_dof=poses.dof_within, dof=dof, chi2=chi2, rank=rank, cond=cond,
        max_gap=_largest_gap(th), g=float(g),
        lack_of_fit=problem.lack_of_fit(sigma2, source_s2, chi2, dof))
    problem.judge(fit, geometry=f"largest gap between pose directions "
                                f"{np.degrees(fit.max_gap):.0f}°",
                  refuse="the poses do not spread (all within a narrow arc, or symmetric "
                         "about both axes); add poses at other orientations around the turn",
                  what="calibration", warn="spread the poses around the whole turn")
    return fit
