"""Error propagation over time: covariance of the corrected position along a vehicle run.

The arrival-point model of :mod:`calib.vehicle.region` (calibration covariance through the position
Jacobian, plus the vehicle noise integrated twice) applied to the trajectory truncated at each
requested sample. Used by the rerun recording (the growing ellipse, ``vehicle/position_std``)
and by the uncertainty-growth figure.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from calib.vehicle.region import noise_cov_matrix, noise_position_cov, position_jacobian
from calib.vehicle.trajectory import Trajectory

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration


def truncated(traj: Trajectory, k: int) -> Trajectory:
    """The trajectory made of samples ``0 … k`` of ``traj`` (same start, parameters, method)."""
    sl = slice(0, k + 1)
    return Trajectory(traj.t[sl], traj.acc_raw[sl], traj.acc_corrected[sl],
                      traj.pos_raw[sl], traj.vel_raw[sl], traj.pos_corrected[sl],
                      traj.vel_corrected[sl], p0=traj.p0, v0=traj.v0, bias=traj.bias,
                      scale=traj.scale, integrator=traj.integrator)


def position_cov_along(traj: Trajectory, cal: Calibration, noise_var,
                       indices) -> np.ndarray:
    """Covariance of the corrected position at the given samples.

    Parameters
    ----------
    traj : corrected trajectory (:func:`calib.vehicle.trajectory.compute_trajectory`), M samples.
    cal : the calibration used; ``cal.cov`` is the (4, 4) covariance of
        ``[bias_x, scale_x, bias_y, scale_y]`` (m/s², dimensionless).
    noise_var : vehicle accelerometer noise, two variances or a (2, 2) matrix, (m/s²)²
        (:func:`calib.vehicle.region.noise_cov_matrix`).
    indices : (K,) sample indices into ``traj`` (0 ≤ k < M).

    Returns
    -------
    (K, 2, 2) covariance of the corrected position (x, y) at each sample, m², symmetric.

    Notes
    -----
    For sample k the trajectory truncated at ``t_k`` is a trajectory of its own, so
    :func:`calib.vehicle.region.position_jacobian` (``J_k``, (2, 4)) and
    :func:`calib.vehicle.region.noise_position_cov` give (same model as the arrival point)::

        Σ_P(t_k) = J_k Σ_c J_kᵀ + Σ_noise,k

    symmetrised as ``(Σ + Σᵀ)/2``. Samples 0 and 1 have zero covariance (P0, V0 exact; the
    quadrature needs three samples).
    """
    C = noise_cov_matrix(noise_var)
    out = np.zeros((len(indices), 2, 2))
    for i, k in enumerate(indices):
        k = int(k)
        if k < 2:
            continue
        sub = truncated(traj, k)
        J = position_jacobian(sub)
        cov = J @ cal.cov @ J.T + noise_position_cov(sub, C)
        out[i] = 0.5 * (cov + cov.T)
    return out
