"""Honesty of the turning dead reckoning's arrival region (calib.vehicle.turning_trajectory
``turning_arrival_region``: the no-fix extended filter's covariance around the dead reckoning).

Truth: the MuJoCo turning vehicle (bench.vehicle, ``turning=True``) simulated ONCE, 60 s at
50 Hz: body accelerations ``A`` (m/s²), heading ψ (rad), yaw rate ω (rad/s). Each of the R
Monte Carlo runs is drawn here with numpy from the equations (not the bench's noise code):

* true calibration ``[b_x, s_x, b_y, s_y] ~ N([B̂_x, Ŝ_x, B̂_y, Ŝ_y], C_cal)`` — the
  estimate ``(B̂, Ŝ)`` is what the dead reckoning corrects with, ``C_cal`` its covariance;
* readings ``A_m = (1 + s) A + b + v``, ``v ~ N(0, σ_a²)`` white per axis;
  gyro ``ω_m = ω + v_g``, ``v_g ~ N(0, σ_g²)``; P0, V0, ψ0 known exactly.

The error of the final dead-reckoned position against MuJoCo's, ``δ = P̂ - p``, with the
run's own covariance ``Σ_P`` (the filter evaluated on the run's readings, as a user gets it)
gives ``NEES = δᵀ Σ_P⁻¹ δ``, χ²(2) if the region is honest; the mean of R independent values
is χ²(2R)/R, band its exact 0.001/0.999 quantiles. Coverage: the number of runs whose truth
lies in the 99.7 % ellipse is Binomial(R, 0.997); band its exact 0.001/0.999 quantiles.

What the linearisation assumes: a small heading error — the filter propagates ``δψ`` through
``R'(ψ) a_b δψ`` and drops ``|a_b| δψ²/2``; here σ_ψ is a few mrad (σ_g sqrt(h T) ≈ 5 mrad),
so the neglected term is ~1e-5 of the linear one. Also neglected: the trapezoid-vs-hold
integration difference ``e_N`` (its own test below; ≈ 0.6 m at 50 Hz against σ ≈ 18 m, a
NEES bias ≈ 0.001). What 300 runs support: the mean NEES to about ±0.35 (band half-width on
2), coverage only that the misses are few (the band admits up to a handful of 300) — not a
proof at the 0.3 % tail.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, chi2

from bench.vehicle import VehicleConfig, simulate_vehicle
from calib.fusion.turning import fuse_turning
from calib.vehicle.region import chi2_2dof
from calib.vehicle.turning_trajectory import (
    TurningRegion,
    turning_arrival_region,
    turning_dead_reckoning,
)

SEED = 20261122
R_RUNS = 300
LEVEL = 0.997
SIGMA_A2 = np.array([0.25, 0.64])              # (m/s²)², the course's datos.txt
SIGMA_G = 0.005                                # rad/s, the bench's gyro
B_HAT, S_HAT = np.array([0.08, -0.05]), np.array([-0.03, 0.02])
CAL_COV = np.diag([1e-4, 4e-6, 1e-4, 4e-6])    # [b_x, s_x, b_y, s_y]
CANDIDATES = {"A": [0.0, 0.0], "B": [100.0, 100.0]}


@pytest.fixture(scope="module")
def truth():
    return simulate_vehicle(VehicleConfig(duration=60.0, rate=50.0, turning=True))


@pytest.fixture(scope="module")
def runs(truth):
    tr, rng = truth, np.random.default_rng(SEED)
    N = tr.t.size
    c = rng.multivariate_normal([B_HAT[0], S_HAT[0], B_HAT[1], S_HAT[1]], CAL_COV, R_RUNS)
    b, s = c[:, [0, 2]], c[:, [1, 3]]
    acc_m = ((1 + s)[:, None] * tr.acc + b[:, None]
             + rng.normal(size=(R_RUNS, N, 2)) * np.sqrt(SIGMA_A2))
    gyro = tr.yaw_rate + rng.normal(0.0, SIGMA_G, (R_RUNS, N))
    init = (tr.pos[0], tr.vel[0])
    final = np.array([turning_dead_reckoning(tr.t, acc_m[r], gyro[r], B_HAT, S_HAT, *init,
                                             psi0=float(tr.heading[0])).final_position
                      for r in range(R_RUNS)])
    free = fuse_turning(tr.t, acc_m, gyro, np.empty(0), np.empty((0, 2)), bias=B_HAT,
                        scale=S_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2,
                        gyro_var=SIGMA_G ** 2, sigma_pos=1.0, p0=init[0], v0=init[1],
                        psi0=float(tr.heading[0]),
                        keep="fixes")  # the region's covariance, all runs at once
    P = np.asarray(free.covariances)[:, -1]
    return acc_m, gyro, final, P


def test_mean_nees_and_coverage_of_the_dead_reckoning_region(truth, runs):
    _, _, final, P = runs
    d = final - truth.pos[-1]
    nees = np.einsum("ri,ri->r", d, np.linalg.solve(P[:, :2, :2], d[..., None])[..., 0])
    lo, hi = chi2.ppf(0.001, 2 * R_RUNS) / R_RUNS, chi2.ppf(0.999, 2 * R_RUNS) / R_RUNS
    assert lo < nees.mean() < hi, (nees.mean(), lo, hi)
    inside = int(np.sum(nees <= chi2_2dof(LEVEL)))
    assert binom.ppf(0.001, R_RUNS, LEVEL) <= inside <= binom.ppf(0.999, R_RUNS, LEVEL)
    assert np.max(np.sqrt(P[:, 4, 4])) < 0.01   # rad: the small-angle regime claimed
    assert np.min(np.sqrt(P[:, 0, 0])) > 5.0    # m: the region is not trivially tiny


def test_region_is_the_filters_covariance_around_the_dead_reckoning(truth, runs):
    acc_m, gyro, final, P = runs
    tr = truth
    dr = turning_dead_reckoning(tr.t, acc_m[0], gyro[0], B_HAT, S_HAT, tr.pos[0], tr.vel[0],
                                psi0=float(tr.heading[0]))
    reg = turning_arrival_region(dr, acc_m[0], gyro[0], cal_cov=CAL_COV, noise_var=SIGMA_A2,
                                 gyro_var=SIGMA_G ** 2, candidates=CANDIDATES, level=LEVEL)
    assert np.array_equal(reg.estimate, final[0])
    assert np.allclose(reg.cov, P[0, :2, :2], rtol=1e-12, atol=0)
    assert reg.ellipse.contains(reg.estimate)
    d2 = [(np.subtract(c, final[0]) @ np.linalg.solve(reg.cov, np.subtract(c, final[0])))
          for c in CANDIDATES.values()]
    assert np.allclose([reg.mahalanobis[k] ** 2 for k in CANDIDATES], d2, rtol=1e-10)
    # the filter's no-fix mean is the zero-order hold of the same world accelerations: it
    # differs from the dead reckoning's trapezoid by exactly -e_N (module docstring)
    h = float(tr.t[1] - tr.t[0])
    a = dr.acc_world
    e_n = h * h / 4 * np.sum(a[:-1] + a[1:] - 2 * a[0], axis=0)
    assert np.allclose(reg.ekf_offset, -e_n, rtol=0, atol=1e-8)
    assert TurningRegion.from_dict(reg.to_dict()) == reg
