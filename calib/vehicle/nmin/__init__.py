"""How many calibration samples N are needed to decide the arrival point.

One module per job: :mod:`calib.vehicle.nmin.scaling` (the analytic ``Σ_P(N)``, design and
a-posteriori N), :mod:`calib.vehicle.nmin.fixed_run` (the course question),
:mod:`calib.vehicle.nmin.confirm` (its regeneration check), :mod:`calib.vehicle.nmin.redrawn` (the
design with the vehicle noise redrawn), :mod:`calib.vehicle.nmin.subsample` (the course's
subsampling experiment), :mod:`calib.vehicle.nmin.synthetic` (fresh synthetic runs),
:mod:`calib.vehicle.nmin.analysis` (all of it on one data set, :func:`analyze_nmin`);
:class:`VehicleCase` is the vehicle case they share. Everything is re-exported here.

Scaling law (θ uniform over [0, 2π))
------------------------------------
For ``θ_i = 2π i/N`` (``N ≥ 3``) the sums ``Σ sin θ_i = Σ cos θ_i = 0`` and
``Σ sin² θ_i = Σ cos² θ_i = N/2`` hold exactly, so the per-axis design ``H = [1, A_r]`` has
``HᵀH = diag(N, g² N/2)`` and the calibration covariance is (course reports, eq. 54–55, with
the exact ``N/2``)::

    Σ_c(N) = diag(σx², 2σx²/g², σy², 2σy²/g²) / N  =  Σ_c1 / N

Propagated to the arrival point (:mod:`calib.vehicle.region`)::

    Σ_P(N) = A / N + B,     A = J Σ_c1 Jᵀ,     B = Σ_noise (vehicle run, independent of N)

``Σ_P(N)`` decreases with N (Loewner order), so every Mahalanobis distance
``d_i(N)² = δ_iᵀ Σ_P(N)⁻¹ δ_i`` grows monotonically with N; each candidate leaves the level-L
region at one crossing ``N_i`` (found by bisection on integers) and never comes back.

Three questions
---------------
* **The course question (this vehicle run given)** — the vehicle readings, hence their noise
  realisation, are held fixed and only a NEW calibration of N samples is drawn: the smallest
  N with P(decision made and right) ≥ L (:func:`fixed_run_nmin`). The calibration estimate
  follows its sampling law ``ĉ_N ~ N(c, Σ_c1/N)``; the arrival point moves by
  ``J (ĉ_N - c) = U/√N``; the region drawn is the tool's, ``Σ_P(N) = A/N + B``. Plug-in: on
  real data c is unknown, so the full calibration is taken as the truth and the decided
  candidate as the true arrival point. Estimated from ≥ 10⁵ draws of U (common to every N)
  and confirmed by regenerating calibrations at the answer (:func:`confirm_fixed_run`). On
  the course data: about 4,000 samples.
* **Design (before the run, vehicle noise redrawn too)** — the smallest N for which the
  level-L regions drawn around the candidates are pairwise disjoint:
  ``|c_i - c_j|_Σ(N) > 2 r`` with ``r² = χ²₂(L)``. Then, by the triangle inequality, when the
  truth's region contains the estimate (probability exactly L) no other candidate is inside:
  the decision is made *and* right with probability L — never more, so this N is only where
  the probability touches L. Its asymptote ``P_∞`` (N → ∞, ``Σ_P → B``) is below L when
  the vehicle noise alone cannot separate the candidates: the level cannot be reached
  (:func:`redrawn_design`).
* **A posteriori (this estimate fixed)** — with the estimate ``P̂`` held fixed, exactly one
  candidate is inside for ``N`` in ``[N_(K-1), N_(K))`` (second-largest and largest crossings).
  Below it several candidates are inside; above ``N_(K)`` (if finite) none is.

Why no N can guarantee a decision in general
--------------------------------------------
* The vehicle-noise term ``B`` does not shrink with the calibration N: if two candidates are
  closer than ``2r`` in the metric of ``B`` alone, no calibration, however long, separates
  them (``design`` is then None).
* Candidates can be arbitrarily close, and the estimate can fall between two of them (the
  course report WLS, Figure 8): a posteriori the decision depends on where the estimate
  landed, which no N controls.
* Everything is at a confidence level: with probability ``1 - L`` the truth is outside its
  region whatever N is.
* The linear model itself (white Gaussian noise, bias and scale only, known P0 and V0, no
  rotation) is an assumption; an unmodelled effect does not average out with N.

Monte Carlo checks: :func:`subsample_analysis` redoes the course reports' experiment (calibrate
on every k-th sample of the course run), :func:`confirm_fixed_run` regenerates calibrations
with the vehicle run given, and :func:`simulate_decisions` draws fresh synthetic calibration
and vehicle runs at a given N. Each says what its run count supports: a rate from R runs is
known to ± 3√(p(1-p)/R), and R runs without a failure bound the failure rate only below
≈ 3/R at 95 % (one-sided Clopper–Pearson, :func:`calib.stats.proportion.lower_bound`): 100/100
supports P ≥ 0.970, not 0.997.
"""

from calib.vehicle.nmin.analysis import NOTES, NminResult, analyze_nmin
from calib.vehicle.nmin.case import VehicleCase
from calib.vehicle.nmin.confirm import CONFIRM_N_MAX, ConfirmRow, confirm_fixed_run
from calib.vehicle.nmin.fixed_run import (
    BAND_SIGMAS,
    FIXED_RUN_N_MAX,
    calibration_draws,
    fixed_run_nmin,
    fixed_run_probability,
)
from calib.vehicle.nmin.redrawn import redrawn_design, redrawn_probability
from calib.vehicle.nmin.scaling import (
    N_MAX,
    PositionCovModel,
    course_box_nrange,
    crossing_n,
    design_nmin,
    posterior_nrange,
    uniform_design_cov,
)
from calib.vehicle.nmin.subsample import COURSE_STEPS, SubsampleRow, subsample_analysis
from calib.vehicle.nmin.synthetic import McRow, simulate_decisions, synthetic_calibration

__all__ = [
    "BAND_SIGMAS", "CONFIRM_N_MAX", "COURSE_STEPS", "ConfirmRow", "FIXED_RUN_N_MAX", "McRow",
    "NOTES", "N_MAX", "NminResult", "PositionCovModel", "SubsampleRow", "VehicleCase",
    "analyze_nmin", "calibration_draws", "confirm_fixed_run", "course_box_nrange",
    "crossing_n", "design_nmin", "fixed_run_nmin", "fixed_run_probability", "posterior_nrange",
    "redrawn_design", "redrawn_probability", "simulate_decisions", "subsample_analysis",
    "synthetic_calibration", "uniform_design_cov",
]
