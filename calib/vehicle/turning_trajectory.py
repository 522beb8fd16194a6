"""Dead reckoning of a vehicle that turns: heading from the gyro, corrected body readings
rotated to the world, integrated twice (issue 13 part 6, the pictures of ``fuse``).

Frames, units, signs as :mod:`calib.fusion.turning`: heading ψ (rad) from world +x to the
body +x, counter-clockwise seen from +z; the gyro reads ``ω = dψ/dt`` (rad/s); the
accelerometers read body +x, +y (m/s²); ``R(ψ)`` (:func:`calib.fusion.turning.rotation`)
maps body to world. Positions m, velocities m/s, time s.

Model::

    ψ(t_k) = ψ0 + ∫₀^t_k ω_m dτ                 (cumulative trapezoid, the EKF's rule)
    Â_b,k = (A_m,k - bias) / (1 + scale)        (:func:`calib.calibration.correct.correct`)
    a_w,k = R(ψ_k) Â_b,k                        (:func:`calib.fusion.turning.body_to_world`)
    V = V0 + ∫ a_w,   P = P0 + ∫ V              (:func:`calib.vehicle.trajectory.integrate_twice`)

Arrival region (:func:`turning_arrival_region`): the extended filter
:func:`calib.fusion.turning.fuse_turning` run with no fix IS the dead reckoning with its
covariance — one home for the propagation of ``[p, v, ψ, b]`` through the linearised turning
dynamics (Q from σ_a², σ_g², the scale variances; P0 from the calibration's bias block, ψ0,
P0, V0). Its final position block ``Σ_P`` (m²) gives the level-L ellipse
(:class:`calib.vehicle.region.Ellipse`) and the Mahalanobis distances of the candidates
(:func:`calib.vehicle.region.squared_distances`, :func:`calib.vehicle.region.decide`) around the
dead reckoning's own arrival point. Linearisation assumes a small heading error (``δψ`` rotates
``a_b`` by ``R'(ψ) a_b δψ``; second order ``|a_b| δψ²/2`` is neglected): σ_ψ grows as
``σ_g sqrt(h t)`` — about 4 mrad after the course's 60 s at 100 Hz with σ_g = 0.005 rad/s.
The filter holds each sample over its step (``p⁺ = p + v h + a h²/2``), the dead reckoning
integrates by the trapezoid: their means differ by ``e_N`` below (``TurningRegion.ekf_offset``,
0.3 m on the course against σ ≈ 18 m), so the region is centred on the dead reckoning and
only the covariance is taken from the filter.

Integration error on the bench: the bench holds the world acceleration over each step
(zero-order hold, exact ``p⁺ = p + v h + a h²/2``); the double cumulative trapezoid of the
same samples differs from it by exactly ``e_k = (h²/4) Σ_{j<k} (a_j + a_{j+1} - 2 a_0)``
on a uniform grid of step h (tests/test_fuse_turning_pictures.py), ``|e_k| ≤ h t_k
max_j |a_j - a_0| / 2`` — centimetres over the course's 60 s at 100 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from calib.calibration.correct import correct
from calib.fusion.turning import body_to_world, fuse_turning
from calib.input_rules import DataError
from calib.vehicle.region import DecidedRegion, Ellipse
from calib.vehicle.trajectory import (
    Integrator,
    SampledRun,
    check_integrator,
    cumulative_integral,
    integrate_twice,
    last_row,
)


@dataclass(frozen=True, eq=False, kw_only=True)
class TurningTrajectory(SampledRun):
    """Dead reckoning of a turning vehicle (module docstring).

    Attributes
    ----------
    t : (M,) s.  heading : (M,) ψ, rad.
    acc_body : (M, 2) corrected body readings ``Â_b``, m/s².
    acc_world : (M, 2) ``R(ψ) Â_b``, m/s² (world axes).
    pos, vel : (M, 2) m, m/s (world axes).
    p0 : (2,) m.  v0 : (2,) m/s.  psi0 : rad.  bias : (2,) m/s² and scale : (2,) used.
    integrator : "trapezoid" or "simpson" (position and velocity; the heading is always the
        trapezoid, the extended filter's rule).
    """

    _TITLE = "Turning dead reckoning"
    _UNITS = ("t s; heading and psi0 rad; positions m; velocities m/s; accelerations and bias "
              "m/s²; scale dimensionless")

    psi0: float  # the initial heading, beside SampledRun's p0 and v0
    t: np.ndarray
    heading: np.ndarray
    acc_body: np.ndarray
    acc_world: np.ndarray
    pos: np.ndarray
    vel: np.ndarray

    _ARRAYS = ("t", "heading", "acc_body", "acc_world", "pos", "vel")

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "psi0", float(self.psi0))

    final_position = last_row("pos", "(2,) dead-reckoned arrival point, m.")

    @property
    def final_heading(self) -> float:
        """ψ at the last sample, rad."""
        return float(self.heading[-1])

    def to_dict(self) -> dict:
        """The final values (``to_state`` adds the arrays)."""
        return {"final_position": self.final_position.tolist(),
                "final_velocity": self.vel[-1].tolist(), "final_heading": self.final_heading,
                "p0": self.p0.tolist(), "v0": self.v0.tolist(), "psi0": self.psi0,
                "bias": self.bias.tolist(), "scale": self.scale.tolist(),
                "integrator": self.integrator, "n_samples": int(self.t.shape[0]),
                "units": {"final_position": "m", "final_velocity": "m/s",
                          "final_heading": "rad", "p0": "m", "v0": "m/s", "psi0": "rad",
                          "bias": "m/s²", "scale": "1", "n_samples": "count"}}

    @classmethod
    def from_dict(cls, d: dict) -> TurningTrajectory:
        """Rebuild from :meth:`to_state` (exact); :meth:`to_dict` alone has no samples."""
        if not all(k in d for k in (*cls._ARRAYS, *cls._FIXED)):
            raise ValueError("this mapping has no samples; rebuild from to_state()")
        return cls(**{f.name: d[f.name] for f in fields(cls)})

    def summary(self) -> str:
        fp, fv = self.pos[-1], self.vel[-1]
        return "\n".join([
            f"Turning dead reckoning: {self.t.shape[0]} samples over "
            f"{self.t[-1] - self.t[0]:g} s, {self.integrator} double integration, "
            f"P0 = {self.p0.tolist()} m, V0 = {self.v0.tolist()} m/s, ψ0 = {self.psi0:g} rad",
            f"  correction: bias = [{self.bias[0]:.6g}, {self.bias[1]:.6g}] m/s², "
            f"scale = [{self.scale[0]:.6g}, {self.scale[1]:.6g}] (dimensionless)",
            f"  final position ({fp[0]:10.3f}, {fp[1]:10.3f}) m, velocity ({fv[0]:.3f}, "
            f"{fv[1]:.3f}) m/s, heading {self.final_heading:.4f} rad",
        ])


def turning_dead_reckoning(t, acc_m, gyro, bias, scale, p0, v0, *, psi0: float = 0.0,
                           integrator: Integrator = "trapezoid") -> TurningTrajectory:
    """Dead reckoning of a turning vehicle (module docstring for the equations).

    Parameters
    ----------
    t : (M,) s, strictly increasing, M ≥ 3.  acc_m : (M, 2) measured body readings, m/s².
    gyro : (M,) measured yaw rate, rad/s.  bias : (2,) m/s², scale : (2,) — the calibration.
    p0 : (2,) m, v0 : (2,) m/s (world axes), psi0 : initial heading, rad.
    integrator : of the position and velocity, as :func:`calib.vehicle.trajectory.integrate_twice`.
    """
    check_integrator(integrator)
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.shape[0] < 3 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise ValueError("t must be 1-D, finite, strictly increasing, with ≥ 3 samples")
    acc_m = np.asarray(acc_m, dtype=float)
    if acc_m.shape != (t.shape[0], 2):
        raise ValueError(f"accelerations must be ({t.shape[0]}, 2), got {acc_m.shape}")
    w = np.asarray(gyro, dtype=float).reshape(-1)
    if w.shape != t.shape:
        raise ValueError(f"gyro must be ({t.shape[0]},), got {np.shape(gyro)}")
    if not np.all(np.isfinite(w)):
        raise ValueError("gyro has NaN or Inf: remove or interpolate those samples")
    bias = np.broadcast_to(np.asarray(bias, dtype=float), (2,))
    scale = np.broadcast_to(np.asarray(scale, dtype=float), (2,))
    p0 = np.broadcast_to(np.asarray(p0, dtype=float), (2,))
    v0 = np.broadcast_to(np.asarray(v0, dtype=float), (2,))
    psi = float(psi0) + cumulative_integral(w, t, "trapezoid")
    a_b = correct(acc_m, bias, scale)
    a_w = body_to_world(psi, a_b)
    pos, vel = integrate_twice(t, a_w, p0, v0, integrator)
    return TurningTrajectory(t=t, heading=psi, acc_body=a_b, acc_world=a_w, pos=pos, vel=vel,
                             p0=p0, v0=v0, psi0=psi0, bias=bias, scale=scale,
                             integrator=integrator)


def refuse_turning(acel, command: str) -> None:
    """The course vehicle's analyses (``trajectory``, ``nmin``: :mod:`calib.vehicle.trajectory`,
    world-frame readings, no rotation) refuse a turning run: an ``acel``
    (:class:`calib.files.course.Acel`) with a ``gyro`` holds body-frame readings, and integrating
    them as world accelerations puts the arrival hundreds of metres off. DataError naming the file
    and what to use."""
    if getattr(acel, "gyro", None) is not None:
        raise DataError(f"{acel.source}: a turning run (it has 'gyro': body-frame readings); "
                        f"{command} models the course vehicle without rotation and does not "
                        "model turning: use 'tiltbench fuse' (the extended filter, with the "
                        "turning dead reckoning in its --plot)")


def heading_error(t, psi, t_ref, psi_ref) -> np.ndarray:
    """``ψ(t_ref) - ψ_ref`` wrapped to (-π, π], rad: ``psi`` (rad) at times ``t`` (s,
    increasing) interpolated linearly to the reference times ``t_ref`` (s, within ``t``).
    E.g. the filter's or the dead reckoning's heading against the truth's samples."""
    at = np.interp(np.asarray(t_ref, dtype=float), np.asarray(t, dtype=float),
                   np.asarray(psi, dtype=float))
    return np.angle(np.exp(1j * (at - np.asarray(psi_ref, dtype=float))))


def dead_reckoning_path(traj) -> np.ndarray:
    """(M, 2) dead-reckoned path, m, of either kind: ``pos`` of a :class:`TurningTrajectory`,
    ``pos_corrected`` of a :class:`calib.vehicle.trajectory.Trajectory`."""
    return traj.pos if isinstance(traj, TurningTrajectory) else traj.pos_corrected


@dataclass(frozen=True, eq=False, kw_only=True)
class TurningRegion(DecidedRegion):
    """Level-L arrival region of a turning dead reckoning (module docstring, "Arrival region").

    Attributes
    ----------
    estimate : (2,) dead-reckoned arrival point, m (world axes).
    cov : (2, 2) its covariance ``Σ_P``, m² (the no-fix extended filter's final position block).
    heading_std : σ_ψ at the end, rad (the linearisation's small-angle assumption).
    ekf_offset : (2,) the filter's no-fix mean minus ``estimate``, m (hold vs trapezoid).
    level : L.  ellipse : the level-L region.  candidates : name → (2,) m.
    mahalanobis : name → d.  likelihood : name → exp(-d²/2).  inside : names with
    ``d² ≤ χ²₂(L)``.  decision : the letter or None.  reason : why.
    """

    _TITLE = "Turning dead-reckoning arrival region"
    _UNITS = ("positions, std, offsets, semi-axes m; covariances m²; heading std rad; "
              "Mahalanobis distance and likelihood dimensionless")

    heading_std: float
    ekf_offset: np.ndarray

    _ARRAYS = (*DecidedRegion._ARRAYS, "ekf_offset")

    def to_dict(self) -> dict:
        return {"final_position": self.estimate.tolist(), "cov": self.cov.tolist(),
                "std": self.std.tolist(), "heading_std": self.heading_std,
                "ekf_offset": self.ekf_offset.tolist(), "level": self.level,
                "ellipse": self.ellipse.to_state(), "candidates": self.candidate_rows(),
                "inside": list(self.inside), "decision": self.decision, "reason": self.reason,
                "units": {"final_position": "m", "cov": "m²", "std": "m", "heading_std": "rad",
                          "ekf_offset": "m", "level": "1", "ellipse": "m (semi-axes, centre), "
                          "rad (angle), m² (area, cov)", "candidates.*.pos": "m",
                          "candidates.*.mahalanobis": "1", "candidates.*.likelihood": "1"}}

    @classmethod
    def from_dict(cls, d: dict) -> TurningRegion:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(estimate=d["final_position"], cov=d["cov"],
                   heading_std=float(d["heading_std"]), ekf_offset=d["ekf_offset"],
                   level=float(d["level"]), ellipse=Ellipse.from_dict(d["ellipse"]),
                   **cls.decision_fields(d))

    def summary(self) -> str:
        e, sd = self.ellipse, self.std
        lines = [f"Dead-reckoning arrival ({self.estimate[0]:.2f}, {self.estimate[1]:.2f}) m; "
                 f"std ({sd[0]:.2f}, {sd[1]:.2f}) m; heading std {self.heading_std:.2g} rad",
                 f"{100 * self.level:g}% ellipse: semi-axes {e.semi_axes[0]:.2f} m × "
                 f"{e.semi_axes[1]:.2f} m, major axis at {np.degrees(e.angle_rad):.1f}° "
                 f"from +x",
                 f"{'cand':<6}{'Mahalanobis':>13}{'inside':>8}"]
        lines += [f"{k:<6}{self.mahalanobis[k]:>13.3f}{'yes' if k in self.inside else 'no':>8}"
                  for k in self.candidates]
        lines.append(f"decision (dead reckoning): {self.decision or 'undecided'} "
                     f"({self.reason})")
        return "\n".join(lines)


def turning_arrival_region(traj: TurningTrajectory, acc_m, gyro, *, cal_cov, noise_var,
                           gyro_var: float, candidates: dict, level: float = 0.997,
                           psi0_var: float = 0.0, p0_cov=0.0, v0_cov=0.0) -> TurningRegion:
    """The level-L region of the dead reckoning ``traj`` (module docstring, "Arrival region").

    Parameters
    ----------
    traj : :func:`turning_dead_reckoning` of ``acc_m`` (M, 2) m/s² and ``gyro`` (M,) rad/s.
    cal_cov : (4, 4) calibration covariance, order [b_x, s_x, b_y, s_y].
    noise_var : σ_a², (m/s²)², scalar or (2,).  gyro_var : σ_g², (rad/s)².
    candidates : name → (2,) m.  level : L.  psi0_var rad², p0_cov m², v0_cov (m/s)²: the
        initial state's uncertainty (as :func:`calib.fusion.turning.fuse_turning`).
    """
    free = fuse_turning(traj.t, acc_m, gyro, np.empty(0), np.empty((0, 2)), bias=traj.bias,
                        scale=traj.scale, cal_cov=cal_cov, noise_var=noise_var,
                        gyro_var=gyro_var, sigma_pos=1.0, p0=traj.p0, v0=traj.v0,
                        psi0=traj.psi0, p0_cov=p0_cov, v0_cov=v0_cov, psi0_var=psi0_var,
                        keep="fixes")  # no fix: the prediction alone, start and end kept
    P = np.asarray(free.covariances, dtype=float)[-1]
    cov = 0.5 * (P[:2, :2] + P[:2, :2].T)
    est = traj.final_position
    return TurningRegion.decided(
        est, cov, candidates, level, heading_std=float(np.sqrt(max(P[4, 4], 0.0))),
        ekf_offset=np.asarray(free.final_position, dtype=float) - est)


__all__ = ["TurningRegion", "TurningTrajectory", "dead_reckoning_path", "heading_error",
           "refuse_turning", "turning_arrival_region", "turning_dead_reckoning"]
