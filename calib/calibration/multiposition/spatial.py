"""The 3-axis multi-position fit: bias and scale of three axes from held poses, gravity on
the sphere (:func:`fit_multiposition3d`; equations and references:
:mod:`calib.calibration.multiposition`) and the quantization step of raw-count readings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from calib.calibration.ls import NotIdentifiableError
from calib.calibration.multiposition.shared import (
    SAME_DIRECTION_DEG,
    SPAN_FRACTION,
    PoseFit,
    PoseProblem,
    Poses,
    distinct_directions,
)
from calib.conventions import JOINT_PARAM_NAMES, G
from calib.logs.static_log import quantization_step as lattice_step
from calib.results import ResultMixin

POSES_NEEDED_3D = 8
"""Fewest held poses (distinct orientations) for the 3-axis fit. Unknowns: bias and scale of
three axes (6) and each pose's gravity direction (2 angles); each pose brings 3 readings, so P
poses leave P − 6 dof. Six poses in general position fit an axis-aligned ellipsoid exactly:
nothing would check the fit. Seven would leave one dof, but then the joint region from the
linearised covariance is too small: on sets drawn as in ``tests/test_multiposition3d.py``
(σ² given, 100–400 samples per pose, directions spread over the sphere) the mean NEES of the
six parameters is 8.0 instead of 6 and 9.4 % of the sets fall beyond the χ²₆ 95 % point (R = 385
fitted sets of 400, seed 5): with one spare reading the direction angles and the ellipsoid
trade off along curved valleys the linearisation does not see. At eight poses the same study
gives a mean NEES of 5.99 and 5.2 % beyond (R = 1987, seed 11; band 5 % ± 2.0 %), so the rule
is P ≥ 8 (two dof for the lack-of-fit test); 9 or more spread over the sphere are recommended.
The coverage at exactly eight poses is the Monte Carlo
``test_joint_region_is_honest_at_the_minimum_pose_count``."""

SPHERE_EIG_MIN = 0.02
"""Smallest eigenvalue of the directions' scatter matrix ``S = (1/P) Σ u_i u_iᵀ`` (1/3 for
directions spread evenly over the sphere; 0 when every direction lies on one great circle)
under which the directions do not span three dimensions: an axis-aligned ellipsoid through a
planar conic is not unique, so the set is refused (the tilt plane alone is then the planar
fit's job). 0.02 is all directions within ≈ 8° of one great circle."""

PARAM_NAMES_3D: tuple[str, ...] = JOINT_PARAM_NAMES + ("bias_n", "scale_n")
"""``[bias_x, scale_x, bias_y, scale_y, bias_n, scale_n]``: the tilt plane's four (in the
planar fit's order, so the first four and their 4×4 block are the :class:`Calibration`'s),
then the normal axis's (``n``: the log's third axis,
:attr:`calib.logs.reader.ImuLog.acc_normal`)."""

AXES_3D = ("x", "y", "n")


def quantization_step(values: np.ndarray) -> float:
    """The step q of readings on a lattice (m/s², raw counts converted), else 0 for
    continuous readings: :func:`calib.logs.static_log.quantization_step` (one home for the
    lattice test), with "none" as 0 so it adds nothing to a pose mean's variance."""
    step = lattice_step(np.asarray(values, dtype=float))
    return 0.0 if step is None else step


@dataclass(frozen=True, eq=False, kw_only=True)
class MultiPosition3DFit(PoseFit, ResultMixin):
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
        "poses.tau_int": "samples",
    }
    _ARRAYS = (*PoseFit._ARRAYS, "directions", "directions_std", "quantization")
    _DICT_HEAD = (("axes", 3),)
    _DICT_KEYS = ("param_names", "params", "std", "cov", "directions", "directions_std",
                  "poses", "residuals", "sigma2", "sigma2_source", "sigma2_dof",
                  "quantization", "dof", "chi2", "rank", "cond", "min_eig", "largest_cap", "g",
                  "lack_of_fit")
    _SUMMARY_TITLE = "multi-position, 3 axes (gravity norm, no angle reference)"
    _SIGMA2_LINE = (" per sample", "dof = 0")

    directions: np.ndarray
    directions_std: np.ndarray
    quantization: np.ndarray
    min_eig: float
    largest_cap: float
    param_names: tuple[str, ...] = field(default=PARAM_NAMES_3D)

    def pose_lines(self) -> list[str]:
        """The quantization step (when the readings have one), the identifiability line and
        each pose's direction, its std and residuals."""
        out = []
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
        return out

    @classmethod
    def from_dict(cls, d: dict) -> MultiPosition3DFit:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(**cls.shared_fields(d, 3),
                   directions=np.asarray(d["directions"], float).reshape(-1, 3),
                   directions_std=d["directions_std"], quantization=d["quantization"],
                   min_eig=float(d["min_eig"]), largest_cap=float(d["largest_cap"]))

    def to_calibration(self):
        """The project's :class:`calib.calibration.tilt_plane.Calibration` of the tilt plane (method
        "multiposition"): the first four parameters and their 4×4 block (the normal axis and
        the directions marginalised), as :meth:`MultiPositionFit.to_calibration`; the normal
        axis's bias and scale ride along in the joint fit's ``extra["normal"]``.

        Per axis χ² of the samples with ``dof = N − P``, residuals the pose means' (m/s²):
        :meth:`~calib.calibration.multiposition.shared.PoseFit.plane_fits`."""
        normal = {"params": self.params[4:].tolist(), "std": self.std[4:].tolist(),
                  "param_names": list(self.param_names[4:])}
        return self.tilt_plane_calibration(4, {"normal": normal})


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
                "(6 unknowns; at 7 the joint region is too small)")
    distinct = distinct_directions(poses.means)
    if distinct < POSES_NEEDED_3D:
        return (f"{poses.count} held poses in only {distinct} distinct orientations (re-holds "
                f"within {SAME_DIRECTION_DEG:g}° pooled), the 3-axis fit needs at least "
                f"{POSES_NEEDED_3D}")
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
            "poses fit exactly, and at 7 the joint region is too small); hold the sensor in more "
            "orientations, 9 or more spread over all sides")
    q = np.zeros(3) if quantization is None else np.asarray(quantization, float).reshape(-1)
    if q.shape != (3,) or np.any(~np.isfinite(q)) or np.any(q < 0):
        raise ValueError(f"quantization must be three steps ≥ 0, got {quantization}")
    problem = PoseProblem(poses, g, AXES_3D, where)
    problem.check_spans({"n": "; or calibrate the tilt plane alone (planar fit)"})
    sigma2, source_s2 = problem.noise_variances(noise_var, floor=q**2 / 12)
    problem.require_distinct(sigma2, POSES_NEEDED_3D, "for the 3-axis fit", q**2 / 12)
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

    x = problem.solve_lm(lambda x: _residuals3(x, means, sd, g, u0, E),
                         np.concatenate([p0, np.zeros(2 * P)]), 200 * (6 + 2 * P))
    params = x[:6].copy()
    u = _residuals3(x, means, sd, g, u0, E)[2]
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
    spread = "the pose directions do not spread over the sphere; add poses with other sides up"
    cov_full, rank, cond = problem.covariance(J, PARAM_NAMES_3D, spread)
    dvar = np.diag(cov_full)[6:].reshape(P, 2).sum(axis=1)
    chi2 = float(r @ r)
    dof = P - 6
    fit = MultiPosition3DFit(
        params=params, cov=cov_full[:6, :6], directions=u, directions_std=np.sqrt(dvar),
        poses=poses, residuals=means - params[0::2] - (1 + params[1::2]) * g * u,
        sigma2=sigma2, sigma2_source=source_s2, sigma2_dof=poses.dof_within, quantization=q,
        dof=dof, chi2=chi2, rank=rank, cond=cond,
        min_eig=float(np.linalg.eigvalsh(u.T @ u / P)[0]), largest_cap=_largest_cap(u),
        g=float(g), lack_of_fit=problem.lack_of_fit(sigma2, source_s2, chi2, dof))
    problem.judge(fit, geometry=f"largest empty cap {np.degrees(fit.largest_cap):.0f}°",
                  refuse=spread, what="3-axis calibration",
                  warn="spread the poses over all sides")
    return fit
