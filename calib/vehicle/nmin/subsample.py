"""The course reports' experiment (course report LS, section 3.2.4): calibrate on every k-th
sample of the calibration run, correct the vehicle run, integrate and decide, with our region
and with the course's box criterion (:mod:`calib.vehicle.region`). Positions m, N in samples.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from calib.calibration.ls import PoorlyIdentifiedWarning
from calib.calibration.tilt_plane import calibrate
from calib.files.course import Acel, Ensayo, validate_ensayo
from calib.results import ResultMixin
from calib.vehicle.nmin.case import VehicleCase
from calib.vehicle.region import arrival_region, course_decision
from calib.vehicle.trajectory import compute_trajectory

COURSE_STEPS = (1, 2, 13, 14)
"""Subsampling steps of the course report LS (every sample, every 2nd, 13th, 14th)."""


@dataclass(frozen=True, eq=False, kw_only=True)
class SubsampleRow(ResultMixin):
    """One subsampled calibration of the course reports' experiment.

    step : every ``step``-th sample kept.  n : samples.  estimate, std : (2,) m.
    semi_axes : (2,) m.  course_box : (2,) m.  mahalanobis : name → d.  decisions: letter or
    None; ``inside`` / ``course_inside``: candidate names.
    """

    _TITLE = "Subsampled calibration"
    _UNITS = "estimate, std, semi-axes and course box m; Mahalanobis distance dimensionless"

    step: int
    n: int
    estimate: np.ndarray
    std: np.ndarray
    semi_axes: np.ndarray
    mahalanobis: dict
    decision: str | None
    inside: tuple
    calibration_only_decision: str | None
    course_box: np.ndarray
    course_decision: str | None
    course_inside: tuple

    def to_dict(self) -> dict:
        return {"step": self.step, "n": self.n, "estimate": np.asarray(self.estimate).tolist(),
                "std": np.asarray(self.std).tolist(),
                "semi_axes": np.asarray(self.semi_axes).tolist(),
                "mahalanobis": self.mahalanobis, "decision": self.decision,
                "inside": list(self.inside),
                "calibration_only_decision": self.calibration_only_decision,
                "course_box": np.asarray(self.course_box).tolist(),
                "course_decision": self.course_decision,
                "course_inside": list(self.course_inside)}

    @classmethod
    def from_dict(cls, d: dict) -> SubsampleRow:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(step=int(d["step"]), n=int(d["n"]),
                   estimate=np.array(d["estimate"], dtype=float),
                   std=np.array(d["std"], dtype=float),
                   semi_axes=np.array(d["semi_axes"], dtype=float),
                   mahalanobis=dict(d["mahalanobis"]), decision=d["decision"],
                   inside=tuple(d["inside"]),
                   calibration_only_decision=d["calibration_only_decision"],
                   course_box=np.array(d["course_box"], dtype=float),
                   course_decision=d["course_decision"], course_inside=tuple(d["course_inside"]))

    def summary(self) -> str:
        return (f"step {self.step}, N = {self.n}: estimate ({self.estimate[0]:.1f}, "
                f"{self.estimate[1]:.1f}) m, std ({self.std[0]:.1f}, {self.std[1]:.1f}) m, "
                f"decision {self.decision or 'undecided'} (inside: "
                f"{', '.join(self.inside) or 'none'}); course box ±({self.course_box[0]:.1f}, "
                f"{self.course_box[1]:.1f}) m, course decision "
                f"{self.course_decision or 'undecided'}")


def subsample_analysis(ensayo: Ensayo, acel: Acel, case: VehicleCase,
                       steps: Sequence[int] = COURSE_STEPS, noise_var=None
                       ) -> list[SubsampleRow]:
    """Calibrate on every ``step``-th sample (``tita[::step]``, as the course's
    ``Tita2(1:paso:N2)``), correct, integrate, decide — ours and the course's box criterion.

    ``ensayo`` the calibration run, ``acel`` the vehicle run, ``case`` the candidates, initial
    state, level, fit and integrator; ``noise_var`` (2,) (m/s²)² or None (estimated).
    """
    c = case
    rows = []
    for step in steps:
        if int(step) < 1:
            raise ValueError(f"subsampling step must be >= 1, got {step}")
        sub = validate_ensayo(ensayo.tita[::step], ensayo.datos[::step], None,
                              f"{ensayo.source}[::{step}]")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal = calibrate(sub, noise_var, c.method, c.g)  # type: ignore[arg-type]
        traj = compute_trajectory(acel, cal, c.p0, c.v0, c.integrator)
        reg = arrival_region(traj, cal, c.candidates, noise_var, c.level)
        reg0 = arrival_region(traj, cal, c.candidates, noise_var, c.level, include_noise=False)
        cdec, cin = course_decision(reg.estimate, c.candidates, reg.course_box_bound)
        rows.append(SubsampleRow(
            step=int(step), n=sub.n, estimate=reg.estimate, std=reg.std,
            semi_axes=reg.ellipse.semi_axes, mahalanobis=dict(reg.mahalanobis),
            decision=reg.decision, inside=reg.inside, calibration_only_decision=reg0.decision,
            course_box=reg.course_box_bound, course_decision=cdec, course_inside=cin))
    return rows


__all__ = ["COURSE_STEPS", "SubsampleRow", "subsample_analysis"]
