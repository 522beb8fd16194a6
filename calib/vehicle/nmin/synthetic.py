"""Fresh synthetic calibration and vehicle runs at a given calibration size N (the vehicle
noise redrawn too): how often the decision is made and right. Course sensor model
(:mod:`calib.calibration.correct`), θ uniform over a turn; N in samples, counts of runs.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from calib.calibration.correct import apply_errors
from calib.calibration.ls import PoorlyIdentifiedWarning
from calib.calibration.tilt_plane import Calibration, calibrate
from calib.conventions import G, reference_accel
from calib.files.course import Ensayo
from calib.results import ResultMixin
from calib.vehicle.nmin.case import VehicleCase
from calib.vehicle.region import arrival_region, noise_cov_matrix
from calib.vehicle.trajectory import correct_and_integrate


@dataclass(frozen=True, eq=False)
class McRow(ResultMixin):
    """Decisions over ``runs`` fresh synthetic (calibration + vehicle) runs at one N."""

    _TITLE = "Synthetic runs"
    _UNITS = "counts of runs; level and rates are fractions (dimensionless); N samples"

    n: int
    runs: int
    right: int
    wrong: int
    undecided: int
    truth_inside: int
    level: float

    def to_dict(self) -> dict:
        return {"n": self.n, "runs": self.runs, "right": self.right, "wrong": self.wrong,
                "undecided": self.undecided, "truth_inside": self.truth_inside,
                "level": self.level, "right_rate": self.right / self.runs,
                "coverage": self.truth_inside / self.runs}

    @classmethod
    def from_dict(cls, d: dict) -> McRow:
        """Rebuild from :meth:`to_dict` (exact; the rates are derived)."""
        return cls(int(d["n"]), int(d["runs"]), int(d["right"]), int(d["wrong"]),
                   int(d["undecided"]), int(d["truth_inside"]), float(d["level"]))

    def summary(self) -> str:
        return (f"N = {self.n}: {self.runs} runs at level {self.level:g}: {self.right} right, "
                f"{self.wrong} wrong, {self.undecided} undecided; truth inside its region in "
                f"{self.truth_inside}")


def synthetic_calibration(n: int, bias, scale, noise_var, rng: np.random.Generator,
                          g: float = G) -> Ensayo:
    """Calibration run with ``θ_i = 2π i/N`` and the course sensor model (numpy only).

    ``datos = (1 + scale)·[-g sin θ, -g cos θ] + bias + v``, ``v ~ N(0, diag(noise_var))``.
    """
    tita = 2.0 * np.pi * np.arange(n) / n
    a_r = reference_accel(tita, g)
    sd = np.sqrt(np.diag(noise_cov_matrix(noise_var)))
    datos = apply_errors(a_r, bias, scale) + sd * rng.standard_normal(a_r.shape)
    return Ensayo(tita, datos, None, source=f"synthetic N={n}")


def simulate_decisions(case: VehicleCase, t: np.ndarray, a_true: np.ndarray, *, truth: str,
                       n: int, runs: int, seed: int, bias, scale, noise_var) -> McRow:
    """Decide on ``runs`` fresh synthetic runs at calibration size ``n``.

    Each run draws (from its own stream of ``SeedSequence(seed).spawn(runs)``) a calibration
    run (:func:`synthetic_calibration`) and the vehicle readings
    ``A_m = (1 + scale)·a_true + bias + v`` (``t`` (M,) s, ``a_true`` (M, 2) m/s², ``bias``
    (2,) m/s², ``scale`` (2,), ``noise_var`` (2,) (m/s²)²); it calibrates (known σ²),
    corrects, integrates and decides as ``case`` says. ``case.candidates[truth]`` must be the
    true arrival point.
    """
    c = case
    nv = noise_cov_matrix(noise_var)
    sd = np.sqrt(np.diag(nv))
    a_true = np.asarray(a_true, dtype=float)
    right = wrong = undecided = inside = 0
    for ss in np.random.SeedSequence(int(seed)).spawn(int(runs)):
        rng = np.random.default_rng(ss)
        ens = synthetic_calibration(n, bias, scale, nv, rng, c.g)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal: Calibration = calibrate(ens, np.diag(nv), c.method,  # type: ignore[arg-type]
                                         c.g)
        a_m = apply_errors(a_true, bias, scale) + sd * rng.standard_normal(a_true.shape)
        traj = correct_and_integrate(t, a_m, cal.bias, cal.scale, c.p0, c.v0, c.integrator)
        reg = arrival_region(traj, cal, c.candidates, nv, c.level)
        inside += truth in reg.inside
        if reg.decision is None:
            undecided += 1
        elif reg.decision == truth:
            right += 1
        else:
            wrong += 1
    return McRow(int(n), int(runs), right, wrong, undecided, inside, float(c.level))


__all__ = ["McRow", "simulate_decisions", "synthetic_calibration"]
