"""Extended Kalman fusion for a vehicle that turns (issue 13, parts 2–4): body-frame
accelerometers, a gyro for the yaw rate, position fixes.

Frames, units, signs
--------------------
World axes x, y (horizontal), z up. Heading ψ (rad) is the angle from world +x to the body's
+x axis, counter-clockwise seen from +z; the gyro reads ``ω = dψ/dt`` (rad/s). The two
accelerometers read the specific force along the body +x and +y axes (m/s²);
``R(ψ) = [[cos ψ, -sin ψ], [sin ψ, cos ψ]]`` maps body to world. Positions m, velocities
m/s, biases m/s² (body axes), scale factors 1, time s.

Model
-----
State ``x = [px, py, vx, vy, ψ, bx, by]``. Each accelerometer reading ``A_m,k`` (body) is
held over ``[t_k, t_k+1)`` and corrected as in :mod:`calib.fusion.linear`, then rotated::

    a_b,k = (A_m,k - b - v_k) / (1 + ŝ),     a_w,k = R(ψ_k) a_b,k

and over a step of length ``h = t_k+1 - t_k`` (trapezoid for the heading: exact while the
yaw acceleration is constant over the step, as on the bench)::

    p⁺ = p + v h + a_w h²/2,   v⁺ = v + a_w h,   ψ⁺ = ψ + h (ω_m,k + ω_m,k+1)/2,   b⁺ = b

Jacobian of the step (``g1 = h²/2``, ``g2 = h``, ``R' = dR/dψ``, ``C = diag(1/(1+ŝ))``)::

    ∂p⁺/∂v = h I,  ∂(p⁺, v⁺)/∂ψ = (g1, g2) · R'(ψ) a_b,  ∂(p⁺, v⁺)/∂b = -(g1, g2) · R(ψ) C

Process noise per step, from stated quantities only (nothing tuned)::

    W = R(ψ) diag((σ_a² + σ_s² a_b²)/(1+ŝ)²) R(ψ)ᵀ        (m/s²)², world axes
    Q_pp = g1² W,  Q_pv = g1 g2 W,  Q_vv = g2² W,  Q_ψψ = σ_g² h²

σ_a² is the accelerometer's stated white-noise variance, σ_s² the scale-factor variance of the
calibration covariance (folded as a white term, as :mod:`calib.fusion.linear` does with a fixed
scale), σ_g the gyro's stated white noise (rad/s). The trapezoid makes consecutive heading
increments share one gyro sample: their noise sums to ``σ_g² h² (N - 1/2)`` after N steps
where Q gives ``σ_g² h² N`` — conservative by half a step. No gyro bias is modelled (the
bench's gyro has none; a real one would add ``bg`` to the state).

P0 = blockdiag(P_p0, P_v0, σ_ψ0², the bias block of the calibration covariance); R = σ_pos² I
from the receiver. The update is :func:`calib.fusion.kalman.kalman_update` (Joseph form) with
``H = [I₂ 0]``, the smoother :func:`calib.fusion.kalman.rts` on the products ``Φ`` of the step
Jacobians evaluated at the filtered estimates (an extended RTS smoother).

Fixes must fall on IMU sample times (the bench's receiver puts them there): the heading's
trapezoid needs the gyro at both ends of every step.

Why numpy and not filterpy
--------------------------
filterpy 2.0.0's ``ExtendedKalmanFilter`` and ``UnscentedKalmanFilter`` run one run at a
time, a Python call per step (3000 steps × 500 Monte Carlo runs = 1.5·10⁶ predict calls, plus
an ``sigma_points`` loop for the UKF), and its ``rts_smoother`` is for the linear filter
without a control input (see :mod:`calib.fusion.linear`). This module steps R runs at once as
(R, n, n) arrays, like :func:`calib.fusion.linear.fuse`, in the loop they share
(:func:`calib.fusion.kalman.run_filter`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.fusion.kalman import (
    CalibrationLike,
    FilterInputs,
    filter_inputs,
    initial_cov,
    nominal_q,
)
from calib.fusion.linear import FusionResult

TURN_STATE_NAMES = ("px", "py", "vx", "vy", "psi", "bx", "by")
_STATE_UNITS = "[m, m, m/s, m/s, rad, m/s², m/s²]"


def rotation(psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``R(ψ)`` and ``dR/dψ``, shape ``psi.shape + (2, 2)`` (body → world)."""
    c, s = np.cos(psi), np.sin(psi)
    Rm = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    dR = np.stack([np.stack([-s, -c], -1), np.stack([c, -s], -1)], -2)
    return Rm, dR


def body_to_world(psi: np.ndarray, acc_body: np.ndarray) -> np.ndarray:
    """``R(ψ) a_b``: (…,) headings rad and (…, 2) body vectors → (…, 2) world vectors."""
    return np.einsum("...ij,...j->...i", rotation(np.asarray(psi, dtype=float))[0],
                     np.asarray(acc_body, dtype=float))


@dataclass(frozen=True, eq=False, kw_only=True)
class TurningFusionResult(FusionResult):
    """Extended Kalman filter (and smoother) of the turning vehicle: the fields of
    :class:`calib.fusion.linear.FusionResult` with the state ``TURN_STATE_NAMES`` (ψ in rad) and

    gyro_var : σ_g², the gyro's white-noise variance, (rad/s)².
    Q : (7, 7) process noise of one nominal IMU step at ψ = 0 without the data-dependent
        scale term.
    """

    _TITLE = "Extended Kalman fusion (turning vehicle)"
    _UNITS = ("t s; px, py m; vx, vy m/s; psi rad; bx, by m/s² (body axes); covariances in "
              "the products of those units; innovations m")

    gyro_var: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "gyro_var", float(self.gyro_var))

    @property
    def heading(self) -> np.ndarray:
        """(K,) or (R, K) filtered heading ψ, rad."""
        return self.estimates[..., 4].copy()

    def to_dict(self) -> dict:
        d = super().to_dict()
        d["gyro_var"] = self.gyro_var
        d["final_heading"] = self.estimates[..., -1, 4].tolist()
        d["units"] = {**d["units"], "estimates": _STATE_UNITS, "smoothed": _STATE_UNITS,
                      "gyro_var": "(rad/s)²", "final_heading": "rad", "R": "[m², m²]",
                      "innovations": "[m, m]", "innovation_covs": "[m², m²]"}
        return d

    def summary(self) -> str:
        lines = super().summary().splitlines()
        lines[0] = lines[0].replace("Kalman fusion", "Extended Kalman fusion (turning)", 1)
        lines.insert(2, f"  gyro noise σ_g² = {self.gyro_var:.4g} (rad/s)²; psi in rad, "
                        f"bx, by in body axes")
        fh = float(np.asarray(self.estimates)[..., -1, 4].reshape(-1)[0])
        fs = float(np.sqrt(np.asarray(self.covariances)[..., -1, 4, 4].reshape(-1)[0]))
        lines.insert(-1 if self.innovations.size else len(lines),
                     f"  final heading {fh:.4f} rad, std {fs:.4f} rad")
        return "\n".join(lines)


def fuse_turning(t, acc_m, gyro, t_gps, pos_gps, *, noise_var, gyro_var, sigma_pos, p0, v0,
                 calibration: CalibrationLike | None = None, bias=None, scale=None,
                 cal_cov=None, psi0=0.0, p0_cov=0.0, v0_cov=0.0, psi0_var=0.0,
                 smoother=False, keep="all", gate_alpha: float = 0.0) -> TurningFusionResult:
    """Extended Kalman filter (and RTS smoother) of a turning vehicle (module docstring).

    Parameters
    ----------
    t : (N,) IMU times, s, strictly increasing.
    acc_m : (N, 2) or (R, N, 2) measured body-frame accelerations (uncorrected), m/s².
    gyro : (N,) or (R, N) measured yaw rate ω_m, rad/s.
    t_gps : (M,) fix times, s, strictly increasing, each equal to an IMU time.
    pos_gps : (M, 2) or (R, M, 2) position fixes, world axes, m.
    calibration : the calibration (``bias`` (2,) m/s², ``scale`` (2,) 1, ``cov`` (4, 4) order
        ``CAL_ORDER``), or its three parts as ``bias``, ``scale``, ``cal_cov`` — as
        :func:`calib.fusion.linear.fuse`.
    noise_var : σ_a², (m/s²)², scalar or (2,).  gyro_var : σ_g², (rad/s)².
    sigma_pos : σ of each fix coordinate, m.
    p0 (m), v0 (m/s), psi0 (rad): initial estimate; p0_cov, v0_cov (scalar, (2,) or (2, 2)),
        m², (m/s)², and psi0_var, rad²: its covariance.
    smoother : also run the extended RTS smoother.  keep : "all" or "fixes" (start, fixes,
        end), as :func:`calib.fusion.linear.fuse`.
    gate_alpha : the innovation gate's α, as :func:`calib.fusion.linear.fuse` (0: no gate).

    Returns
    -------
    TurningFusionResult
    """
    inp = filter_inputs(t, acc_m, t_gps, pos_gps, noise_var=noise_var, sigma_pos=sigma_pos,
                        calibration=calibration, bias=bias, scale=scale, cal_cov=cal_cov)
    t, t_gps, Rn, N = inp.t, inp.t_gps, inp.runs, inp.t.shape[0]
    w = np.asarray(gyro, dtype=float)
    w = w[None] if w.ndim == 1 else w
    if w.ndim != 2 or w.shape[1] != N or w.shape[0] not in (1, Rn):
        raise ValueError(f"gyro must be (N,) or (R, N) with N = {N}, got {np.shape(gyro)}")
    if not np.all(np.isfinite(w)):
        raise ValueError("gyro has NaN or Inf: remove or interpolate those samples")
    w = np.broadcast_to(w, (Rn, N))
    tol = 1e-9 * max(1.0, float(np.max(np.abs(t))))
    k_fix = np.clip(np.searchsorted(t, t_gps - tol), 0, N - 1)
    if (np.any(np.diff(t_gps) <= 0) or np.any(np.abs(t[k_fix] - t_gps) > tol)):
        raise ValueError("t_gps must be strictly increasing and each fix on an IMU sample time "
                         "(the heading's trapezoid needs the gyro at both ends of a step)")
    sg2 = float(gyro_var)
    n = 7
    P0 = initial_cov(n, p0_cov, v0_cov, {4: float(psi0_var),
                                         5: inp.cal.cov[np.ix_([0, 2], [0, 2])]})
    x0 = np.concatenate([np.asarray(p0, float), np.asarray(v0, float), [float(psi0)],
                         inp.cal.bias])
    fixi = np.full(N, -1)
    fixi[k_fix] = np.arange(t_gps.shape[0])
    step = TurningStep(inp, w, sg2)
    fields = inp.run(step, x0, P0, fixi, nodes=t, keep=keep, smoother=smoother,
                     gate_alpha=gate_alpha)
    Qnom = nominal_q(n, inp.noise_var, step.c, inp.dt)
    Qnom[4, 4] = sg2 * inp.dt * inp.dt
    return TurningFusionResult(state_names=TURN_STATE_NAMES, **fields, Q=Qnom,
                               estimate_scale=False, gyro_var=sg2)


class TurningStep:
    """The turning vehicle's step (module docstring), for :func:`calib.fusion.kalman.run_filter`:
    ``step(k, x, F, Qk)`` moves ``x`` (R, 7) from sample k-1 to k in place and fills the
    Jacobian ``F`` and the process noise ``Qk`` (R, 7, 7)."""

    def __init__(self, inputs: FilterInputs, gyro: np.ndarray, gyro_var: float) -> None:
        self.t, self.acc, self.w = inputs.t, inputs.acc, gyro
        self.sa2, self.sg2, self.ss2 = inputs.noise_var, gyro_var, inputs.cal.scale_var
        self.c = 1.0 / (1.0 + inputs.cal.scale)

    def __call__(self, k: int, x: np.ndarray, F: np.ndarray, Qk: np.ndarray) -> None:
        c = self.c
        h = self.t[k] - self.t[k - 1]
        g1, g2 = 0.5 * h * h, h
        a_b = (self.acc[:, k - 1, :] - x[:, 5:7]) * c          # (R, 2) body
        Rot, dRot = rotation(x[:, 4])
        a_w = np.einsum("rij,rj->ri", Rot, a_b)
        da_dpsi = np.einsum("rij,rj->ri", dRot, a_b)      # (R, 2)
        da_db = -Rot * c                                    # (R, 2, 2): -R(ψ) C
        F[:, 0:2, 2:4] = np.eye(2) * h
        F[:, 0:2, 4] = g1 * da_dpsi
        F[:, 2:4, 4] = g2 * da_dpsi
        F[:, 0:2, 5:7] = g1 * da_db
        F[:, 2:4, 5:7] = g2 * da_db
        q = (self.sa2 + self.ss2 * a_b * a_b) * c * c       # (R, 2) body variances
        W = np.einsum("rij,rj,rkj->rik", Rot, q, Rot)       # R diag(q) Rᵀ
        Qk[:, 0:2, 0:2] = g1 * g1 * W
        Qk[:, 0:2, 2:4] = Qk[:, 2:4, 0:2] = g1 * g2 * W
        Qk[:, 2:4, 2:4] = g2 * g2 * W
        Qk[:, 4, 4] = self.sg2 * h * h
        x[:, 0:2] += x[:, 2:4] * h + a_w * g1
        x[:, 2:4] += a_w * h
        x[:, 4] += 0.5 * h * (self.w[:, k - 1] + self.w[:, k])


__all__ = ["TURN_STATE_NAMES", "TurningFusionResult", "TurningStep", "body_to_world",
           "fuse_turning", "rotation"]
