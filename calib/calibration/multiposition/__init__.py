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
scatter within the poses (pure error, :mod:`calib.calibration.lackoffit`: Student t with N − P dof).

Identifiability (reported, and refused when missing): the number of poses, the largest gap
between the pose directions, the rank and the condition number of the column-equilibrated
Jacobian; poses that leave an axis's readings nearly constant cannot identify its scale (the
message names it), and an exactly degenerate geometry (fewer than 4 distinct directions, or a
set of poses symmetric about both axes, on which a family of ellipses fits) is rank-deficient.

Not separable here, by construction: a different local g is absorbed by both scales; a tilt
offset of the table does not exist (the angles are free); a misalignment between the two
axes is not in the model and shows as lack of fit.

Three axes (:func:`fit_multiposition3d`): a 3-axis IMU held in arbitrary orientations (a
phone, a wrist sensor) — the log's third axis :attr:`calib.logs.reader.ImuLog.acc_normal` — gives
``‖(m̄_i − b) ⊘ (1 + s)‖ = g`` on the sphere, each pose's gravity direction a nuisance (two
angles), bias and scale of all three axes from at least :data:`POSES_NEEDED_3D` = 8 poses
whose directions span the sphere; quantized readings (raw counts) add ``q²/12`` to each pose
mean's variance. Its first four parameters and their 4×4 block are the planar result's, so it
gives the same :class:`calib.calibration.tilt_plane.Calibration`.

Layout (one job per module; ``from calib.calibration.multiposition import X`` works for every name):
:mod:`~calib.calibration.multiposition.shared` (poses, distinct orientations, identifiability
limits),
:mod:`~calib.calibration.multiposition.planar` (the two tilt-plane axes, :func:`fit_multiposition`),
:mod:`~calib.calibration.multiposition.spatial` (three axes, :func:`fit_multiposition3d`),
:mod:`~calib.calibration.multiposition.document` (comparison with least squares, the JSON object).
"""

from calib.calibration.multiposition.document import (
    MethodComparison,
    compare_methods,
    multiposition_document,
)
from calib.calibration.multiposition.planar import (
    PLANE_FRACTION,
    POSES_NEEDED,
    MultiPositionFit,
    OutOfPlaneWarning,
    fit_multiposition,
    in_plane,
)
from calib.calibration.multiposition.shared import (
    COND_REFUSE,
    COND_WARN,
    SAME_DIRECTION_DEG,
    SAME_POSE_STD,
    SPAN_FRACTION,
    UNIDENTIFIED_STD,
    Poses,
    Sigma2Source,
    distinct_directions,
    distinct_orientations,
    pose_statistics,
)
from calib.calibration.multiposition.spatial import (
    AXES_3D,
    PARAM_NAMES_3D,
    POSES_NEEDED_3D,
    SPHERE_EIG_MIN,
    MultiPosition3DFit,
    fit_multiposition3d,
    quantization_step,
    quantization_steps,
    three_axis_applies,
)

__all__ = ["AXES_3D", "COND_REFUSE", "COND_WARN", "PARAM_NAMES_3D", "PLANE_FRACTION",
           "POSES_NEEDED", "POSES_NEEDED_3D", "SAME_DIRECTION_DEG", "SAME_POSE_STD",
           "SPAN_FRACTION", "SPHERE_EIG_MIN", "UNIDENTIFIED_STD", "MethodComparison",
           "MultiPosition3DFit", "MultiPositionFit", "OutOfPlaneWarning", "Poses",
           "Sigma2Source", "compare_methods", "distinct_directions", "distinct_orientations",
           "fit_multiposition", "fit_multiposition3d", "in_plane", "multiposition_document",
           "pose_statistics", "quantization_step", "quantization_steps", "three_axis_applies"]
