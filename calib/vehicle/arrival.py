"""Where the vehicle arrived, from its accelerometers fused with position fixes: the filter
for the run's kind, then the arrival decision (what ``tiltbench fuse`` prints).

The run's kind decides the filter: readings with a yaw rate (``Acel.gyro``, a turning
vehicle) go through the extended filter :func:`calib.fusion.turning.fuse_turning`, the others
through the linear :func:`calib.fusion.linear.fuse` (docs/fusion.md). Only the fixes inside the
vehicle run's time span are used. The decision (:class:`calib.vehicle.region.Decision`) is taken at
level L around the filtered final position with its covariance (m, m²), by the same rule as
the dead-reckoning regions (:mod:`calib.vehicle.region`). The vehicle noise σ² is the stated one,
else the calibration's (:func:`calib.vehicle.region.stated_noise_var`). Nothing is tuned: Q from the
stated noise and the calibration covariance, R from the receiver's σ, P0 from the calibration and
the initial-state σ (``p0_std`` m, ``v0_std`` m/s per axis; 0 for the course, whose
datos.txt states P0 and V0 exactly).

:func:`dead_reckoning_region` gives the pictures' comparison: the dead reckoning without fixes
and its level-L region (:func:`calib.vehicle.region.arrival_region`, or for a turning run
:func:`calib.vehicle.turning_trajectory.turning_arrival_region`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.calibration.tilt_plane import Calibration
from calib.files.course import Acel, Fixes
from calib.fusion.fix_check import FreeRun, check_fixes, check_gyro, check_heading, heading_offset
from calib.fusion.innovation_check import CONSISTENCY_ALPHA, GATE_ALPHA, NIS_WINDOW, Consistency
from calib.fusion.linear import FusionResult, fuse
from calib.fusion.turning import TurningFusionResult, fuse_turning
from calib.results import ResultMixin
from calib.vehicle.region import ArrivalRegion, Decision, arrival_region, stated_noise_var
from calib.vehicle.trajectory import Trajectory, compute_trajectory
from calib.vehicle.turning_trajectory import (
    TurningRegion,
    TurningTrajectory,
    turning_arrival_region,
    turning_dead_reckoning,
)


@dataclass(frozen=True, eq=False)
class FusedArrival(ResultMixin):
    """The fused run and its arrival decision.

    Attributes
    ----------
    fusion : :class:`calib.fusion.linear.FusionResult` (or the turning one).
    decision : :class:`calib.vehicle.region.Decision` around the filtered final position.
    fixes_used : fixes inside the vehicle run.  fixes_total : fixes in the file.
    p0_std : σ of the initial position per axis, m.  v0_std : of the velocity, m/s.
    consistency : :class:`calib.fusion.innovation_check.Consistency`, the windowed NIS verdict and
        the gate's count; when not consistent, ``decision`` is withheld (:data:`NO_REGION`).
    """

    _TITLE = "Fused arrival"
    _UNITS = ("as the fusion result; decision level, Mahalanobis distances dimensionless; "
              "p0_std m, v0_std m/s")

    fusion: FusionResult
    decision: Decision
    fixes_used: int
    fixes_total: int
    p0_std: float = 0.0
    v0_std: float = 0.0
    consistency: Consistency | None = None

    @property
    def consistent(self) -> bool:
        """The filter's inputs passed the windowed NIS test (True when not checked)."""
        return self.consistency is None or self.consistency.consistent

    def to_dict(self) -> dict:
        """The ``fuse --json`` object: ``consistent``, ``consistency``, ``fusion``,
        ``decision``, ``units``."""
        d = {"consistent": self.consistent, "fusion": self.fusion.to_dict(),
             "decision": self.decision.to_dict(),
             "units": {f"decision.{k}": u for k, u in Decision.UNITS.items()}}
        if self.consistency is not None:
            d["consistency"] = self.consistency.to_dict()
        return d

    def to_state(self) -> dict:
        """:meth:`to_dict` plus what an exact rebuild needs."""
        return {**self.to_dict(), "decision": self.decision.to_state(),
                "fixes_used": self.fixes_used, "fixes_total": self.fixes_total,
                "p0_std": self.p0_std, "v0_std": self.v0_std}

    @classmethod
    def from_dict(cls, d: dict) -> FusedArrival:
        """Rebuild from :meth:`to_state` (exact)."""
        kind = TurningFusionResult if "gyro_var" in d["fusion"] else FusionResult
        cons = d.get("consistency")
        return cls(kind.from_dict(d["fusion"]), Decision.from_dict(d["decision"]),
                   int(d["fixes_used"]), int(d["fixes_total"]), float(d["p0_std"]),
                   float(d["v0_std"]), None if cons is None else Consistency.from_dict(cons))

    def summary(self) -> str:
        fused = self.fusion.summary()
        if not self.consistent:  # its stated σ is not to be trusted: say so where it is
            fused = fused.replace(", std (", ", stated std (untrustworthy) (", 1)
        lines = [
            fused,
            f"initial uncertainty: σ_p0 = {self.p0_std:g} m, σ_v0 = {self.v0_std:g} m/s per "
            "axis (--p0-std/--v0-std; datos.txt states P0 and V0 without uncertainty)",
        ]
        if self.consistency is not None:
            lines.append(self.consistency.verdict())
        letter = self.decision.letter or ("none" if not self.consistent else "undecided")
        rej = int(np.sum(~np.asarray(self.fusion.fix_used, dtype=bool)))
        lines.append(f"decision: {letter} ({self.decision.reason}); fixes used: "
                     f"{self.fixes_used - rej} of {self.fixes_total}"
                     + (f" ({rej} rejected by the gate)" if rej else ""))
        return "\n".join(lines)


def fixes_inside(acel: Acel, fixes: Fixes) -> np.ndarray:
    """(M,) bool: the fixes within the vehicle run ``[t_0, t_end]`` (s); refuses a file with
    none there (ValueError naming it)."""
    t = acel.t
    inside = (fixes.t_gps >= t[0]) & (fixes.t_gps <= t[-1])
    if not np.any(inside):
        raise ValueError(f"{fixes.source}: no fix falls within the vehicle run "
                         f"[{t[0]:g}, {t[-1]:g}] s")
    return inside


NO_REGION = "no region: the filter's inputs are inconsistent"
"""The decision's reason when the windowed NIS test fails (no region, no letter)."""


def fuse_arrival(acel: Acel, fixes: Fixes, calibration: Calibration,
                 candidates: dict[str, np.ndarray], *, p0, v0, level: float, noise_var=None,
                 sigma_pos: float = 3.0, sigma_vel: float | None = None, p0_std: float = 0.0,
                 v0_std: float = 0.0, gyro_var: float = 0.005 ** 2, psi0: float = 0.0,
                 psi0_var: float = 0.0, smoother: bool = False,
                 gate_alpha: float = GATE_ALPHA, consistency_alpha: float = CONSISTENCY_ALPHA,
                 nis_window: int = NIS_WINDOW, check_inputs: bool = True) -> FusedArrival:
    """Fuse the vehicle run with the fixes inside it and decide where it arrived, doubting
    the inputs (issue 23):

    1. a turning run's gyro must be plausible (:func:`calib.fusion.fix_check.check_gyro`) and
       ``psi0`` a heading within one turn (:func:`calib.fusion.fix_check.check_heading`);
    2. with ``check_inputs``, the fixes must agree with the dead-reckoned path
       (:func:`calib.fusion.fix_check.check_fixes`: km, swapped columns, time or constant offset,
       a gyro in °/s named in one line, :class:`calib.input_rules.DataError`);
    3. the filter runs with the innovation gate at ``gate_alpha``;
    4. its windowed NIS is tested (:class:`calib.fusion.innovation_check.Consistency`); when
       inconsistent, no region and no decision (:data:`NO_REGION`).

    Parameters
    ----------
    acel : the vehicle run (``t`` s, ``aerr`` m/s², ``gyro`` rad/s for a turning vehicle).
    fixes : the receiver's fixes (``t_gps`` s, ``pos`` m, optional ``vel`` m/s).
    calibration : the accelerometer calibration (bias, scale, covariance, σ²).
    candidates : name → (2,) candidate arrival point, m.
    p0 (2,) m, v0 (2,) m/s : initial state; p0_std m, v0_std m/s : its σ per axis.
    level : confidence level L of the decision.
    noise_var : σ_a² (2,) (m/s²)², or None: the calibration's.
    sigma_pos : σ of a position fix coordinate, m.  sigma_vel : of a velocity fix, m/s —
        velocity fixes are used only when given (linear filter only).
    gyro_var (rad/s)², psi0 rad, psi0_var rad² : a turning run's gyro noise and initial
        heading (ignored otherwise).
    smoother : also run the RTS smoother.
    gate_alpha : the innovation gate's α (0: no gate; :mod:`calib.fusion.innovation_check`).
    consistency_alpha : false-alarm rate of the consistency verdict.  nis_window : fixes
        per window of the NIS test.
    check_inputs : compare the fixes with the dead-reckoned path first (step 2).
    """
    inside = fixes_inside(acel, fixes)
    nv = stated_noise_var(noise_var, calibration)
    common = dict(calibration=calibration, noise_var=nv, sigma_pos=sigma_pos, p0=p0, v0=v0,
                  p0_cov=p0_std ** 2, v0_cov=v0_std ** 2)
    t_gps, pos = fixes.t_gps[inside], fixes.pos[inside]
    turning = acel.gyro is not None
    if turning:  # a turning vehicle: the extended filter
        if sigma_vel is not None:
            raise ValueError("the turning filter (readings with a gyro) uses position fixes "
                             "only: give no velocity-fix σ")
        check_gyro(acel.gyro, acel.source)
        psi0 = check_heading(psi0)

        def run(gyro=acel.gyro, **kw) -> FusionResult:
            return fuse_turning(acel.t, acel.aerr, gyro, t_gps, pos, gyro_var=gyro_var,
                                psi0=psi0, psi0_var=psi0_var, **common, **kw)
    else:
        vel = fixes.vel[inside] if fixes.vel is not None and sigma_vel is not None else None

        def run(**kw) -> FusionResult:
            return fuse(acel.t, acel.aerr, t_gps, pos, vel_gps=vel,
                        sigma_vel=sigma_vel if vel is not None else None, **common, **kw)
    if check_inputs:
        _check_inputs(run, pos, fixes.source, acel, psi0)
    res = run(smoother=smoother, gate_alpha=gate_alpha)
    cons = Consistency.of(res, alpha=consistency_alpha, window=nis_window)
    if cons.consistent:
        est = np.asarray(res.final_position, dtype=float).reshape(2)
        cov = np.asarray(res.final_position_cov, dtype=float).reshape(2, 2)
        decision = Decision.at(est, cov, candidates, level)
    else:
        decision = Decision.withheld(candidates, level, NO_REGION)
    return FusedArrival(res, decision, int(inside.sum()), int(inside.size), float(p0_std),
                        float(v0_std), cons)


def _check_inputs(run, pos: np.ndarray, source: str, acel: Acel, psi0: float) -> None:
    """Step 2 of :func:`fuse_arrival`: the free run (every fix rejected: the dead reckoning
    and each fix's innovation against it) and :func:`calib.fusion.fix_check.check_fixes`; for a
    turning run the gyro read in °/s (or rad read as °) and an initial heading off by a
    constant (:func:`calib.fusion.fix_check.heading_offset`) are more alternatives."""
    def free(**kw) -> FreeRun:
        return FreeRun.of(run(gate_alpha=1.0, keep="all", smoother=False, **kw), pos)

    if acel.gyro is None:
        check_fixes(free(), source, suspects=", or, for a vehicle that turns, acel.mat needs "
                                              "its 'gyro'")
        return

    base = free()

    def gyro_units() -> list[tuple[float, str]]:
        out = [heading_offset(base, psi0, "psi0")]
        for f, what in ((np.pi / 180.0, "looks like °/s: give rad/s (multiply by π/180)"),
                        (180.0 / np.pi, "looks like ° read as rad: give rad/s (multiply by "
                                        "180/π)")):
            out.append((free(gyro=acel.gyro * f).median_nis(),
                        f"{acel.source}: 'gyro' {what}; the path from it disagrees with the "
                        "fixes, converted it agrees"))
        return out

    check_fixes(base, source, alternatives=gyro_units,
                suspects=", the gyro ('gyro', rad/s) and the initial heading psi0 (rad)")


def dead_reckoning_region(acel: Acel, calibration: Calibration,
                          candidates: dict[str, np.ndarray], *, p0, v0, level: float,
                          noise_var=None, gyro_var: float = 0.005 ** 2, psi0: float = 0.0,
                          psi0_var: float = 0.0, p0_std: float = 0.0, v0_std: float = 0.0
                          ) -> tuple[Trajectory | TurningTrajectory, ArrivalRegion | TurningRegion]:
    """The dead reckoning without fixes and its level-L arrival region, the comparison the
    fused run is drawn against: :func:`calib.vehicle.region.arrival_region` of the course
    trajectory, or for a turning run (``acel.gyro``)
    :func:`calib.vehicle.turning_trajectory.turning_arrival_region` from ``psi0`` with the same σ as
    the filter (parameters as :func:`fuse_arrival`)."""
    nv = stated_noise_var(noise_var, calibration)
    if acel.gyro is not None:
        traj = turning_dead_reckoning(acel.t, acel.aerr, acel.gyro, calibration.bias,
                                      calibration.scale, p0, v0, psi0=psi0)
        return traj, turning_arrival_region(
            traj, acel.aerr, acel.gyro, cal_cov=calibration.cov, noise_var=nv,
            gyro_var=gyro_var, candidates=candidates, level=level, psi0_var=psi0_var,
            p0_cov=p0_std ** 2, v0_cov=v0_std ** 2)
    traj = compute_trajectory(acel, calibration, p0, v0)
    return traj, arrival_region(traj, calibration, candidates, nv, level)


__all__ = ["FusedArrival", "NO_REGION", "dead_reckoning_region", "fixes_inside",
           "fuse_arrival"]
