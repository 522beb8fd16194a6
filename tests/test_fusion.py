"""Consistency of the linear Kalman fusion (calib.fusion.linear), on data written from the
equations.

Generator (independent of bench and of calib.fusion.linear): constant-acceleration segments of 5 s
on the IMU grid (the true acceleration is constant over each IMU step), position and velocity in
closed form (``p += v h + a h²/2``), readings ``A_m = a (1 + s) + b + v`` with white
``v ~ N(0, σ_a²)``, fixes ``p(t_gps) + N(0, σ_pos²)`` at times offset from the IMU samples.
The true bias and scale are drawn around the calibration estimate with the calibration
covariance, the true start around (P0, V0) with their covariances: the filter's prior is
then the truth's distribution, so NEES is χ²(n) per run.

Bands. For R independent runs the average of R χ²(n) values is χ²(nR)/R: the band is its
exact 0.001 and 0.999 quantiles (scipy.stats.chi2). NIS: R·M innovations (white for the
optimal filter) of dimension d → χ²(dRM)/(RM). Coverage: hits/R is binomial, the band
|hits/R − p| ≤ 4·sqrt(p(1−p)/R) (docs/conventions.md).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from calib.fusion.linear import FusionResult, fuse
from calib.vehicle.trajectory import correct_and_integrate

SEED = 20261122
R_RUNS = 500
T_END, F_IMU, F_GPS = 60.0, 50.0, 1.0
SIGMA_A2 = np.array([0.25, 0.16])      # (m/s²)², accelerometer white noise
SIGMA_POS = 3.0                        # m
BIAS_HAT = np.array([0.08, -0.05])     # m/s²
SCALE_HAT = np.array([-0.03, 0.02])
CAL_COV = np.diag([1e-4, 4e-6, 1e-4, 4e-6])  # [bx, sx, by, sy]
P0_HAT, V0_HAT = np.array([0.0, 0.0]), np.array([1.0, 3.0])
P0_COV, V0_COV = 1.0, 0.01             # m², (m/s)²


def band(n: int, count: int) -> tuple[float, float]:
    """0.001/0.999 quantiles of the mean of ``count`` χ²(n) values."""
    return chi2.ppf(0.001, n * count) / count, chi2.ppf(0.999, n * count) / count


def generate(rng, R=R_RUNS, t_end=T_END, f_imu=F_IMU, f_gps=F_GPS, outage=0.0):
    """R runs: IMU times, readings, fix times and fixes, true states at the nodes."""
    h = 1.0 / f_imu
    N = int(round(t_end * f_imu)) + 1
    t = np.arange(N) * h
    t_gps = np.arange(1, int(t_end * f_gps)) / f_gps + 0.3 * h  # asynchronous
    t_gps = t_gps[t_gps <= t_end - outage]
    seg = (np.arange(N) * h // 5.0).astype(int)
    a_seg = rng.normal(0.0, 0.5, (R, seg.max() + 1, 2))
    a = a_seg[:, seg]                                  # (R, N, 2), held over each step
    cal = rng.multivariate_normal(np.zeros(4), CAL_COV, R)
    b = BIAS_HAT + cal[:, [0, 2]]
    s = SCALE_HAT + cal[:, [1, 3]]
    p0 = P0_HAT + rng.normal(0, np.sqrt(P0_COV), (R, 2))
    v0 = V0_HAT + rng.normal(0, np.sqrt(V0_COV), (R, 2))
    acc_m = a * (1 + s[:, None]) + b[:, None] + rng.normal(0, np.sqrt(SIGMA_A2), (R, N, 2))
    # exact kinematics on the merged grid of IMU and fix times
    nodes = np.sort(np.concatenate([t, t_gps]))
    hold = np.searchsorted(t, nodes, side="right") - 1
    pos = np.empty((R, nodes.size, 2))
    vel = np.empty_like(pos)
    p, v = p0.copy(), v0.copy()
    pos[:, 0], vel[:, 0] = p, v
    for k in range(1, nodes.size):
        dt = nodes[k] - nodes[k - 1]
        ak = a[:, hold[k - 1]]
        p = p + v * dt + 0.5 * ak * dt * dt
        v = v + ak * dt
        pos[:, k], vel[:, k] = p, v
    is_fix = np.isin(nodes, t_gps)
    fixes = pos[:, is_fix] + rng.normal(0, SIGMA_POS, (R, t_gps.size, 2))
    truth = np.concatenate([pos, vel, np.broadcast_to(b[:, None], pos.shape)], axis=-1)
    return dict(t=t, acc_m=acc_m, t_gps=t_gps, fixes=fixes, nodes=nodes, truth=truth,
                is_fix=is_fix, b=b, s=s, p0=p0, v0=v0)


def run(data, noise_scale=1.0, r_scale=1.0, keep="fixes", smoother=True):
    return fuse(data["t"], data["acc_m"], data["t_gps"], data["fixes"], bias=BIAS_HAT,
                scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2 * noise_scale,
                sigma_pos=SIGMA_POS * np.sqrt(r_scale), p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV,
                v0_cov=V0_COV, smoother=smoother, keep=keep)


def stored_truth(data, res):
    idx = np.searchsorted(data["nodes"], res.times)
    return data["truth"][:, idx]


@pytest.fixture(scope="module")
def nominal():
    data = generate(np.random.default_rng(SEED))
    return data, run(data)


def test_nees_nis_in_chi2_bands(nominal):
    data, res = nominal
    truth = stored_truth(data, res)
    n, R = 6, R_RUNS
    lo, hi = band(n, R)
    nees_f = res.nees(truth)[:, -1].mean()                 # filter, final state
    nees_s0 = res.nees(truth, smoothed=True)[:, 0].mean()  # smoother, initial state
    mid = res.times.size // 2
    nees_sm = res.nees(truth, smoothed=True)[:, mid].mean()  # smoother, mid-run
    assert lo <= nees_f <= hi, (nees_f, lo, hi)
    assert lo <= nees_s0 <= hi, (nees_s0, lo, hi)
    assert lo <= nees_sm <= hi, (nees_sm, lo, hi)
    M = res.t_gps.size
    nis = res.nis().mean()
    assert (band(2, R * M)[0] <= nis <= band(2, R * M)[1]), nis
    # the smoother is at least as sure as the filter, equal at the end
    assert np.all(np.diagonal(res.smoothed_covariances[:, mid], axis1=-2, axis2=-1)
                  <= np.diagonal(res.covariances[:, mid], axis1=-2, axis2=-1) + 1e-12)
    np.testing.assert_allclose(res.smoothed[:, -1], res.estimates[:, -1])


def test_bias_converges_within_reported_std(nominal):
    data, res = nominal
    std = np.sqrt(np.diagonal(res.covariances[:, -1, 4:6, 4:6], axis1=-2, axis2=-1))
    z = (res.estimates[:, -1, 4:6] - data["b"]) / std
    p, R = 0.95, R_RUNS
    for i in range(2):
        hits = np.mean(np.abs(z[:, i]) <= 1.959964)
        assert abs(hits - p) <= 4 * np.sqrt(p * (1 - p) / R), (i, hits)
    # the fixes refine the calibration: the bias std shrinks (0.007 vs 0.01 m/s² here: the
    # 0.5 m/s² white noise integrated between fixes hides most of a 0.01 m/s² bias in 60 s)
    assert np.all(std < 0.8 * np.sqrt(np.diag(CAL_COV)[[0, 2]]))


def test_final_position_metres_instead_of_tens(nominal):
    data, res = nominal
    truth_end = data["truth"][:, -1, :2]
    dr_err = np.array([
        correct_and_integrate(data["t"], data["acc_m"][r], BIAS_HAT, SCALE_HAT, P0_HAT,
                              V0_HAT).final_corrected for r in range(100)]) - truth_end[:100]
    dr_std = dr_err.std(axis=0)
    kf_std = np.sqrt(np.diagonal(res.final_position_cov, axis1=-2, axis2=-1)).mean(axis=0)
    kf_emp = (res.final_position - truth_end).std(axis=0)
    assert np.all(dr_std > 10.0), dr_std
    assert np.all(kf_std < 3.0) and np.all(kf_emp < 3.0), (kf_std, kf_emp)


def test_outage_growth_and_coverage():
    data = generate(np.random.default_rng(SEED + 1), outage=20.0)
    res = run(data, keep="fixes", smoother=False)
    truth = stored_truth(data, res)
    # every node of one run: the position variance grows through the whole outage
    one = fuse(data["t"], data["acc_m"][0], data["t_gps"], data["fixes"][0], bias=BIAS_HAT,
               scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
               p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV)
    last_fix = np.flatnonzero(one.is_fix)[-1]
    var = np.diagonal(one.covariances[last_fix:, :2, :2], axis1=-2, axis2=-1).sum(-1)
    assert np.all(np.diff(var) > 0) and var[-1] > 20 * var[0]
    np.testing.assert_allclose(one.final_position_cov, res.final_position_cov[0], rtol=1e-9)
    e = truth[:, -1, :2] - res.final_position
    # predicted vs observed spread at the end (per axis), and the 95 % ellipse coverage
    d2 = np.einsum("ri,ri->r", e, np.linalg.solve(res.final_position_cov, e[..., None])[..., 0])
    hits = np.mean(d2 <= chi2.ppf(0.95, 2))
    assert abs(hits - 0.95) <= 4 * np.sqrt(0.95 * 0.05 / R_RUNS), hits
    lo, hi = band(2, R_RUNS)
    assert lo <= d2.mean() <= hi


@pytest.mark.parametrize("noise_scale, r_scale", [(0.1, 1.0), (10.0, 1.0), (1.0, 0.1),
                                                   (1.0, 10.0)])
def test_misset_q_or_r_leaves_the_band(nominal, noise_scale, r_scale):
    data, _ = nominal
    res = run(data, noise_scale=noise_scale, r_scale=r_scale, smoother=False)
    truth = stored_truth(data, res)
    lo, hi = band(6, R_RUNS)
    nees = res.nees(truth)[:, -1].mean()
    assert not (lo <= nees <= hi), (noise_scale, r_scale, nees)


def test_single_run_all_nodes_matches_batch_and_roundtrips(nominal):
    data, res = nominal
    one = fuse(data["t"], data["acc_m"][0], data["t_gps"], data["fixes"][0], bias=BIAS_HAT,
               scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
               p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV, smoother=True)
    idx = np.searchsorted(one.times, res.times)
    np.testing.assert_allclose(one.estimates[idx], res.estimates[0], rtol=0, atol=1e-9)
    # the RTS smoother on every node equals the one on the fix nodes (exact: no data between)
    np.testing.assert_allclose(one.smoothed[idx], res.smoothed[0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(one.smoothed_covariances[idx], res.smoothed_covariances[0],
                               rtol=1e-6, atol=1e-10)
    assert one.estimates.shape == (data["nodes"].size, 6)
    assert FusionResult.from_dict(one.to_dict()) == one
    text = one.summary()
    assert "P0" in text and "Q per IMU step" in text and "R (" in text


def test_estimate_scale_option_consistent():
    data = generate(np.random.default_rng(SEED + 2), R=200)
    res = fuse(data["t"], data["acc_m"], data["t_gps"], data["fixes"], bias=BIAS_HAT,
               scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
               p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV, estimate_scale=True,
               keep="fixes")
    truth = np.concatenate([stored_truth(data, res),
                            np.broadcast_to(data["s"][:, None], (200, res.times.size, 2))], -1)
    lo, hi = band(8, 200)
    nees = res.nees(truth)[:, -1].mean()
    assert lo <= nees <= hi, nees


def test_velocity_fixes_nis_in_band():
    rng = np.random.default_rng(SEED + 3)
    data = generate(rng, R=200, t_end=30.0)
    vel_truth = data["truth"][:, data["is_fix"], 2:4]
    vel_fix = vel_truth + rng.normal(0, 0.1, vel_truth.shape)
    res = fuse(data["t"], data["acc_m"], data["t_gps"], data["fixes"], bias=BIAS_HAT,
               scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
               p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV, vel_gps=vel_fix,
               sigma_vel=0.1, keep="fixes")
    count = 200 * res.t_gps.size
    lo, hi = band(4, count)
    assert lo <= res.nis().mean() <= hi
    lo, hi = band(6, 200)
    assert lo <= res.nees(stored_truth(data, res))[:, -1].mean() <= hi


def test_rejects_bad_inputs():
    t = np.arange(11) * 0.1
    acc = np.zeros((11, 2))
    kw = dict(bias=BIAS_HAT, scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2,
              sigma_pos=SIGMA_POS, p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV)
    bad = acc.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match="acc_m"):
        fuse(t, bad, [0.5], [[0.0, 0.0]], **kw)
    with pytest.raises(ValueError, match="t_gps"):
        fuse(t, acc, [2.0], [[0.0, 0.0]], **kw)
    with pytest.raises(ValueError, match="pos_gps"):
        fuse(t, acc, [0.5, 0.7], [[0.0, 0.0]], **kw)


def test_smoother_with_a_known_start_and_every_node_kept():
    """P0 = 0 for position and velocity (the course's case) makes the prior one step later
    singular; the smoother still runs on every node, starts exactly at P0, and agrees at the
    fix nodes with the smoother on the fix nodes only (exact on any node subset with every
    fix, module docstring)."""
    rng = np.random.default_rng(11)
    t = np.arange(1001) * 0.01
    acc = 0.1 * rng.standard_normal((t.size, 2))
    t_gps = np.arange(1.0, 11.0)
    pos = 3.0 * rng.standard_normal((t_gps.size, 2))
    kw = dict(bias=[0.01, -0.02], scale=[0.0, 0.0], cal_cov=np.diag([1e-4, 1e-6, 2e-4, 1e-6]),
              noise_var=[0.25, 0.64], sigma_pos=3.0, p0=[0.0, 0.0], v0=[1.0, 3.0],
              p0_cov=0.0, v0_cov=0.0, smoother=True)
    every = fuse(t, acc, t_gps, pos, keep="all", **kw)
    fixes = fuse(t, acc, t_gps, pos, keep="fixes", **kw)
    assert np.all(np.isfinite(every.smoothed)) and np.all(np.isfinite(every.smoothed_covariances))
    np.testing.assert_allclose(every.smoothed[0, :4], [0.0, 0.0, 1.0, 3.0], atol=1e-9)
    at = np.searchsorted(every.times, fixes.times)
    np.testing.assert_allclose(every.smoothed[at], fixes.smoothed, rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(every.smoothed_covariances[at], fixes.smoothed_covariances,
                               rtol=1e-6, atol=1e-9)
