"""Tilt-table kinematics and the accelerometer model, written from the physics.

Frames and signs (the course's, DESIGN.md "Conventions")
--------------------------------------------------------
The table turns about its hinge, the table frame's +y axis, by the angle θ (rad, right hand
about +y). A rotation R_y(θ) carries the table's +x axis to (cos θ, 0, −sin θ) in the world
(z up). At rest the specific force is f = −g_vec = (0, 0, +g) (m/s²), so

* sensor x, sensitive along the table's +x:   A_rx = f·R_y(θ)x̂   = −g sin θ,
* sensor y, sensitive along the table's −z:   A_ry = f·R_y(θ)(−ẑ) = −g cos θ,

the course's reference accelerations (x column first). A sensor whose sensitive axis is turned
by +δ about the hinge reads −g sin(θ+δ) (x) or −g cos(θ+δ) (y); a table whose true angle is
encoder + δ turns both.

Lever arm: a sensor at p = (p_x, 0, p_z) in the table frame (m, from the hinge axis) moving
with angular velocity ω ŷ and angular acceleration α ŷ has the acceleration
α ŷ×p − ω² p = α (p_z, 0, −p_x) − ω² (p_x, 0, p_z) in the table frame. Projected on the
sensitive axes: x gets α p_z − ω² p_x, y (along −ẑ) gets α p_x + ω² p_z. Specific force is
acceleration minus gravity, so these add to the static terms above.

Accelerometer model (IEEE Std 1293-2018, the model equation: K0 bias, K1 = 1 + scale, K2,
cross-coupling K_ip), per axis a with a_i the input along the sensitive axis and a_p the
other in-plane axis::

    A_m = K0 + K1·(a_i + k2·a_i² + k_ip·a_i·a_p) + v,     v ~ N(0, σ²)

This module has no effects catalogue: it gives the kinematics, the reference and the
yardstick (:func:`signature_z`) used to size every effect in :mod:`.effects`.
"""

from __future__ import annotations

import numpy as np

G = 9.8
"""Gravity of the nominal model, m/s² (the project's default, DESIGN.md)."""


def sensor_angle(theta: np.ndarray, delta: float = 0.0) -> np.ndarray:
    """Angle of a sensitive axis (rad): encoder θ plus a rotation δ about the hinge."""
    return np.asarray(theta, dtype=float) + delta


def static_force(phi: np.ndarray, g: float = G) -> np.ndarray:
    """Specific force at rest on the two sensitive directions, (N, 2) m/s²:
    ``[−g sin φ, −g cos φ]`` (course signs)."""
    return np.column_stack([-g * np.sin(phi), -g * np.cos(phi)])


def lever_force(omega: np.ndarray, alpha: np.ndarray, p_x: float, p_z: float,
                axis: int) -> np.ndarray:
    """Rigid-body acceleration of a sensor at (p_x, p_z) m projected on its sensitive axis.

    x (``axis`` 0): α p_z − ω² p_x;  y (``axis`` 1, along −ẑ): α p_x + ω² p_z  (m/s²),
    ω in rad/s, α in rad/s² (module docstring for the derivation).
    """
    omega = np.asarray(omega, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    if axis == 0:
        return alpha * p_z - omega**2 * p_x
    return alpha * p_x + omega**2 * p_z


def reference(theta: np.ndarray, g: float = G) -> np.ndarray:
    """The nominal model's regressors, (N, 2): ``A_rx = −g sin θ``, ``A_ry = −g cos θ``."""
    return static_force(np.asarray(theta, dtype=float), g)


def nuisance_basis(a_ref: np.ndarray) -> np.ndarray:
    """Orthonormal basis (N, 2) of span{1, A_r} of one axis — what bias and scale absorb."""
    h = np.column_stack([np.ones_like(a_ref), a_ref])
    q, _ = np.linalg.qr(h)
    return q


def signature_z(delta: np.ndarray, a_ref: np.ndarray, sigma2: float,
                rivals: np.ndarray | None = None) -> float:
    """Size of a change of the mean reading in noise standard deviations.

    ``z = ‖P⊥ Δ‖ / σ`` where P⊥ projects out span{1, A_r} (bias and scale refitted) and, if
    given, the ``rivals`` columns (N, k). Under white noise of variance σ² the least-squares
    test of the signature Δ has non-centrality z² (one degree of freedom): z is how many σ
    the effect stands above the noise once the nominal model has taken its share.
    """
    r = residual(delta, a_ref, rivals)
    return float(np.sqrt(r @ r / sigma2))


def residual(delta: np.ndarray, a_ref: np.ndarray, rivals: np.ndarray | None = None):
    """P⊥Δ: what is left of Δ (N,) after least squares on [1, A_r, rivals] (lstsq)."""
    h = np.column_stack([np.ones_like(a_ref), a_ref] + ([] if rivals is None else [rivals]))
    coef, *_ = np.linalg.lstsq(h, delta, rcond=None)
    return delta - h @ coef


def walk_trace(dt: np.ndarray, a_ref: np.ndarray) -> float:
    """E‖P⊥ b‖² / q² for a walk b_k = Σ_{j≤k} q·√Δt_j·w_j that starts at 0 (Δt_0 = 0).

    Cov(b) = q²·C with C_kl = Σ_{j≤min(k,l)} Δt_j; E‖P⊥ b‖² = q²·(tr C − tr QᵀCQ), Q the
    orthonormal nuisance basis (P⊥ = I − QQᵀ). C·v is a cumulative sum of Δt times a reverse
    cumulative sum of v, so nothing N×N is formed.
    """
    dt = np.asarray(dt, dtype=float)
    q = nuisance_basis(a_ref)
    trace_c = float(np.sum(np.cumsum(dt)))
    cq = np.column_stack([np.cumsum(dt * np.cumsum(col[::-1])[::-1]) for col in q.T])
    return trace_c - float(np.sum(q * cq))
