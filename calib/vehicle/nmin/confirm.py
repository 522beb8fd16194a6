"""The fixed-run answer of :mod:`calib.vehicle.nmin` checked by full regeneration: new calibrations
of N samples drawn with the vehicle run given, each one corrected, integrated and decided
exactly (no linearisation). Counts of runs; N in samples; rates fractions.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from calib.calibration.ls import PoorlyIdentifiedWarning
from calib.calibration.tilt_plane import calibrate
from calib.files.course import Acel
from calib.results import ResultMixin
from calib.stats.proportion import lower_bound
from calib.stats.runs import Mapper, chunk_ranges, run_seeds, serial_map
from calib.vehicle.nmin.case import VehicleCase
from calib.vehicle.nmin.fixed_run import BAND_SIGMAS
from calib.vehicle.nmin.synthetic import synthetic_calibration
from calib.vehicle.region import arrival_region, noise_cov_matrix
from calib.vehicle.trajectory import correct_and_integrate

CONFIRM_N_MAX = 10**6
"""Largest N at which the fixed-run answer is confirmed by regenerating calibrations."""


@dataclass(frozen=True, eq=False)
class ConfirmRow(ResultMixin):
    """Full regeneration at one N with the vehicle run given (:func:`confirm_fixed_run`).

    ``predicted`` : P(made and right) from the sampling-law draws at this N. ``band`` :
    ``predicted ± 3 √(p(1-p)/runs)``. ``lower_95`` : one-sided 95 % Clopper–Pearson bound on
    the rate of right decisions — the claim these runs support.
    """

    _TITLE = "Regenerated calibrations, vehicle run given"
    _UNITS = "counts of runs; N samples; rates, bounds and level fractions (dimensionless)"

    n: int
    runs: int
    right: int
    wrong: int
    undecided: int
    level: float
    predicted: float
    seed: int

    @property
    def rate(self) -> float:
        return self.right / self.runs

    @property
    def band(self) -> tuple[float, float]:
        h = BAND_SIGMAS * np.sqrt(self.predicted * (1.0 - self.predicted) / self.runs)
        return float(self.predicted - h), float(self.predicted + h)

    @property
    def consistent(self) -> bool:
        lo, hi = self.band
        return lo <= self.rate <= hi

    @property
    def lower_95(self) -> float:
        return lower_bound(self.right, self.runs, 0.95)

    def to_dict(self) -> dict:
        return {"n": self.n, "runs": self.runs, "right": self.right, "wrong": self.wrong,
                "undecided": self.undecided, "level": self.level,
                "predicted": self.predicted, "seed": self.seed, "rate": self.rate,
                "band": list(self.band), "consistent": self.consistent,
                "lower_95": self.lower_95}

    @classmethod
    def from_dict(cls, d: dict) -> ConfirmRow:
        """Rebuild from :meth:`to_dict` (exact; rate, band and bound are derived)."""
        return cls(int(d["n"]), int(d["runs"]), int(d["right"]), int(d["wrong"]),
                   int(d["undecided"]), float(d["level"]), float(d["predicted"]),
                   int(d["seed"]))

    def summary(self) -> str:
        lo, hi = self.band
        verdict = "consistent with" if self.consistent else "OUTSIDE"
        return (f"N = {self.n}: {self.runs} regenerated calibrations, {self.right} right, "
                f"{self.wrong} wrong, {self.undecided} undecided: rate {self.rate:.5f}, "
                f"{verdict} the predicted {self.predicted:.5f} (3σ band [{lo:.5f}, "
                f"{min(hi, 1.0):.5f}]); these runs support P(made and right) ≥ "
                f"{self.lower_95:.5f} at 95 % (one-sided), no more")


def confirm_chunk(task: tuple) -> tuple[int, int, int]:
    """Runs ``task[0]`` (a range) of :func:`confirm_fixed_run`: (right, wrong, undecided).
    A module-level function of one picklable tuple, for process pools (:mod:`calib.stats.runs`)."""
    ks, case, runs, seed, n, t, a_m, truth, bias, scale, nv = task
    c = case
    seeds = run_seeds(seed, runs)
    right = wrong = undecided = 0
    for k in ks:
        rng = np.random.default_rng(seeds[k])
        ens = synthetic_calibration(n, bias, scale, nv, rng, c.g)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PoorlyIdentifiedWarning)
            cal = calibrate(ens, nv, c.method, c.g)  # type: ignore[arg-type]
        traj = correct_and_integrate(t, a_m, cal.bias, cal.scale, c.p0, c.v0, c.integrator)
        dec = arrival_region(traj, cal, c.candidates, nv, c.level).decision
        if dec is None:
            undecided += 1
        elif dec == truth:
            right += 1
        else:
            wrong += 1
    return right, wrong, undecided


def confirm_fixed_run(acel: Acel, case: VehicleCase, *, truth: str, n: int, runs: int,
                      seed: int, bias, scale, noise_var, predicted: float,
                      mapper: Mapper | None = None,
                      progress: Callable[[int, int], None] | None = None,
                      chunk: int = 250) -> ConfirmRow:
    """Check the fixed-run answer by full regeneration: ``runs`` new calibrations of ``n``.

    Run k draws from ``run_seeds(seed, runs)[k]`` a calibration run (:func:`synthetic_calibration`
    with the plug-in truth ``bias`` (2,) m/s², ``scale`` (2,), ``noise_var`` (2,) (m/s²)²),
    calibrates it (known σ²), corrects and integrates the GIVEN vehicle run ``acel`` with it
    (exact, no linearisation), draws the region and decides as ``case`` says
    (:func:`calib.vehicle.region.arrival_region`); ``truth`` is the true candidate, ``predicted``
    the sampling-law probability at ``n``. The counts do not depend on ``mapper``
    (:mod:`calib.stats.runs`) or ``chunk``. ``progress(done, total)`` counts chunks.
    """
    nv = np.diag(noise_cov_matrix(noise_var))
    common = (case, int(runs), int(seed), int(n), np.asarray(acel.t, float),
              np.asarray(acel.aerr, float), truth, np.asarray(bias, float),
              np.asarray(scale, float), nv)
    tasks = [(r, *common) for r in chunk_ranges(int(runs), chunk)]
    out = (mapper or serial_map)(confirm_chunk, tasks, progress)
    right, wrong, undecided = (int(sum(x[i] for x in out)) for i in range(3))
    return ConfirmRow(int(n), int(runs), right, wrong, undecided, case.level,
                      float(predicted), int(seed))


__all__ = ["CONFIRM_N_MAX", "ConfirmRow", "confirm_chunk", "confirm_fixed_run"]
