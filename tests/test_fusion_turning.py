"""Consistency of the extended Kalman fusion of a turning vehicle (calib.fusion.turning).

Truth: the MuJoCo turning vehicle (bench.vehicle, ``turning=True``), simulated ONCE at 50 Hz for
60 s: world acceleration ``a_w = R(ψ) A_body`` (MuJoCo's body-frame accelerometers rotated by
MuJoCo's heading), heading ψ and yaw rate ω. The R Monte Carlo runs are drawn here with numpy
from the equations (independent of the bench's noise code):

* true start ``p0 ~ N(P0_HAT, P0_COV I)``, ``v0 ~ N(V0_HAT, V0_COV I)``, heading offset
  ``δψ0 ~ N(0, PSI0_VAR)``; the same world accelerations, so
  ``p(t) = p_mj(t) - p_mj(0) + p0 + (v0 - v_mj(0)) t``, ``v(t) = v_mj(t) - v_mj(0) + v0``,
  ``ψ(t) = ψ_mj(t) + δψ0`` (a rigid rotation of the body about its yaw axis does not change
  ω);
* true bias and scale ``[b, s] ~ N([B̂, Ŝ], CAL_COV)``;
* readings ``A_m = (1 + s) R(ψ)ᵀ a_w + b + v``, ``v ~ N(0, σ_a²)`` white per axis;
  gyro ``ω_m = ω + v_g``, ``v_g ~ N(0, σ_g²)``; fixes ``p(t_gps) + N(0, σ_pos² I)`` at 1 Hz.

The filter's prior is the truth's distribution, so NEES of the 7-state error is χ²(7) per run
and node, and the R·M innovations are χ²(2) each.

Bands (not tuned): the mean of R independent χ²(n) values is χ²(nR)/R; the band is its exact
0.001/0.999 quantiles. NIS: R·M innovations of dimension 2 → χ²(2RM)/(RM) (innovations of an
optimal filter are white). An extended filter is only approximately optimal: the test claims
consistency at the resolution 500 runs give (the band half-width is about ±0.5 on a mean of 7
for NEES), not more.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io
from scipy.stats import chi2

from bench.cli import main
from bench.vehicle import VehicleConfig, simulate_vehicle
from calib.fusion.turning import TurningFusionResult, fuse_turning
from calib.units import missing_units
from tests.cli import unwrap

SEED = 20261123
R_RUNS = 500
RATE, DURATION = 50.0, 60.0
SIGMA_A2 = np.array([0.25, 0.16])        # (m/s²)²
SIGMA_G = 0.005                          # rad/s
SIGMA_POS = 3.0                          # m
BIAS_HAT = np.array([0.08, -0.05])       # m/s²
SCALE_HAT = np.array([-0.03, 0.02])
CAL_COV = np.diag([1e-4, 4e-6, 1e-4, 4e-6])  # [bx, sx, by, sy]
P0_HAT, V0_HAT = np.array([0.0, 0.0]), np.array([1.0, 3.0])
P0_COV, V0_COV, PSI0_VAR = 1.0, 0.01, 0.02 ** 2   # m², (m/s)², rad²


def band(n: int, count: int) -> tuple[float, float]:
    """0.001/0.999 quantiles of the mean of ``count`` χ²(n) values."""
    return chi2.ppf(0.001, n * count) / count, chi2.ppf(0.999, n * count) / count


def rot(psi):
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


@pytest.fixture(scope="module")
def truth():
    return simulate_vehicle(VehicleConfig(duration=DURATION, rate=RATE, turning=True))


def generate(tr, rng, R=R_RUNS):
    t = tr.t
    N = t.size
    a_w = np.einsum("kij,kj->ki", rot(tr.heading), tr.acc)          # (N, 2) world
    p0 = P0_HAT + rng.normal(0, np.sqrt(P0_COV), (R, 2))
    v0 = V0_HAT + rng.normal(0, np.sqrt(V0_COV), (R, 2))
    dpsi = rng.normal(0, np.sqrt(PSI0_VAR), R)
    cal = rng.multivariate_normal(np.zeros(4), CAL_COV, R)
    b = BIAS_HAT + cal[:, [0, 2]]
    s = SCALE_HAT + cal[:, [1, 3]]
    pos = tr.pos - tr.pos[0] + p0[:, None] + (v0 - tr.vel[0])[:, None] * t[:, None]
    vel = tr.vel - tr.vel[0] + v0[:, None]
    psi = tr.heading + dpsi[:, None]                                  # (R, N)
    a_body = np.einsum("rkji,kj->rki", rot(psi), a_w)                 # R(ψ)ᵀ a_w
    acc_m = a_body * (1 + s[:, None]) + b[:, None] + rng.normal(0, np.sqrt(SIGMA_A2), (R, N, 2))
    gyro = tr.yaw_rate + rng.normal(0, SIGMA_G, (R, N))
    k_fix = np.arange(int(RATE), N, int(RATE))                        # 1 Hz, on the grid
    fixes = pos[:, k_fix] + rng.normal(0, SIGMA_POS, (R, k_fix.size, 2))
    state = np.concatenate([pos, vel, psi[..., None], np.broadcast_to(b[:, None], (R, N, 2))],
                           -1)
    return dict(t=t, acc_m=acc_m, gyro=gyro, t_gps=t[k_fix], fixes=fixes, state=state)


def run(data, noise_scale=1.0, r_scale=1.0, smoother=True, keep="fixes"):
    return fuse_turning(data["t"], data["acc_m"], data["gyro"], data["t_gps"], data["fixes"],
                        bias=BIAS_HAT, scale=SCALE_HAT, cal_cov=CAL_COV,
                        noise_var=SIGMA_A2 * noise_scale, gyro_var=SIGMA_G ** 2 * noise_scale,
                        sigma_pos=SIGMA_POS * np.sqrt(r_scale), p0=P0_HAT, v0=V0_HAT,
                        psi0=0.0, p0_cov=P0_COV, v0_cov=V0_COV, psi0_var=PSI0_VAR,
                        smoother=smoother, keep=keep)


def stored(data, res):
    return data["state"][:, np.searchsorted(data["t"], res.times)]


@pytest.fixture(scope="module")
def nominal(truth):
    data = generate(truth, np.random.default_rng(SEED))
    return data, run(data)


def test_the_vehicle_turns_and_reads_in_the_body_frame(truth):
    h = 1.0 / RATE
    assert np.ptp(truth.heading) >= np.pi / 2, np.ptp(truth.heading)
    # body readings rotated by ψ are the world acceleration: the commanded one, held over the
    # step (RK4 integrates a constant force exactly: only rounding, ~1e-15 m/s²), and the one
    # the slide state shows, (v_k+1 - v_k)/h
    a_w = np.einsum("kij,kj->ki", rot(truth.heading), truth.acc)
    tol = 1e3 * np.finfo(float).eps * max(1.0, np.abs(truth.acc_cmd).max())
    np.testing.assert_allclose(a_w, truth.acc_cmd, rtol=0, atol=tol)
    np.testing.assert_allclose(np.diff(truth.vel, axis=0) / h, a_w[:-1], rtol=0,
                               atol=1e3 * np.finfo(float).eps * np.abs(truth.vel).max() / h)
    # the readings are NOT the world acceleration once the body has turned
    assert np.abs(truth.acc - truth.acc_cmd).max() > 0.1
    # gyro = dψ/dt: constant yaw acceleration over a step → trapezoid exact to rounding
    dpsi = np.diff(truth.heading)
    np.testing.assert_allclose(dpsi, 0.5 * h * (truth.yaw_rate[1:] + truth.yaw_rate[:-1]),
                               rtol=0, atol=1e3 * np.finfo(float).eps * np.pi)


def test_nees_nis_in_chi2_bands(nominal):
    data, res = nominal
    x = stored(data, res)
    lo, hi = band(7, R_RUNS)
    nees = res.nees(x)
    nees_s = res.nees(x, smoothed=True)
    mid = res.times.size // 2
    checks = {"filter end": nees[:, -1].mean(), "filter mid": nees[:, mid].mean(),
              "smoother start": nees_s[:, 0].mean(), "smoother mid": nees_s[:, mid].mean()}
    for name, v in checks.items():
        assert lo <= v <= hi, (name, v, lo, hi)
    count = R_RUNS * res.t_gps.size
    lo2, hi2 = band(2, count)
    assert lo2 <= res.nis().mean() <= hi2, (res.nis().mean(), lo2, hi2)
    # the smoother is at least as sure as the filter, equal at the end
    assert np.all(np.diagonal(res.smoothed_covariances[:, mid], axis1=-2, axis2=-1)
                  <= np.diagonal(res.covariances[:, mid], axis1=-2, axis2=-1) + 1e-12)
    np.testing.assert_allclose(res.smoothed[:, -1], res.estimates[:, -1])


@pytest.mark.parametrize("noise_scale, r_scale", [(10.0, 1.0), (0.1, 1.0), (1.0, 10.0),
                                                   (1.0, 0.1)])
def test_misset_q_or_r_leaves_the_band(nominal, noise_scale, r_scale):
    data, _ = nominal
    res = run(data, noise_scale=noise_scale, r_scale=r_scale, smoother=False)
    lo, hi = band(7, R_RUNS)
    nees = res.nees(stored(data, res))[:, -1].mean()
    assert not (lo <= nees <= hi), (noise_scale, r_scale, nees)


def test_single_run_matches_batch_and_roundtrips(nominal):
    data, res = nominal
    one = fuse_turning(data["t"], data["acc_m"][0], data["gyro"][0], data["t_gps"],
                       data["fixes"][0], bias=BIAS_HAT, scale=SCALE_HAT, cal_cov=CAL_COV,
                       noise_var=SIGMA_A2, gyro_var=SIGMA_G ** 2, sigma_pos=SIGMA_POS,
                       p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV,
                       psi0_var=PSI0_VAR, smoother=True)
    idx = np.searchsorted(one.times, res.times)
    np.testing.assert_allclose(one.estimates[idx], res.estimates[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(one.smoothed[idx], res.smoothed[0], rtol=0, atol=1e-6)
    assert TurningFusionResult.from_dict(one.to_dict()) == one
    text = one.summary()
    for word in ("P0", "Q per IMU step", "R (", "gyro noise", "final heading"):
        assert word in text, word


def test_rejects_bad_inputs():
    t = np.arange(11) * 0.1
    kw = dict(bias=BIAS_HAT, scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2,
              gyro_var=SIGMA_G ** 2, sigma_pos=SIGMA_POS, p0=P0_HAT, v0=V0_HAT)
    acc, w = np.zeros((11, 2)), np.zeros(11)
    with pytest.raises(ValueError, match="IMU sample"):
        fuse_turning(t, acc, w, [0.55], [[0.0, 0.0]], **kw)
    with pytest.raises(ValueError, match="gyro"):
        fuse_turning(t, acc, w[:5], [0.5], [[0.0, 0.0]], **kw)
    bad = w.copy()
    bad[2] = np.inf
    with pytest.raises(ValueError, match="gyro"):
        fuse_turning(t, acc, bad, [0.5], [[0.0, 0.0]], **kw)


def test_cli_generate_turning_then_fuse(capsys, tmp_path):
    out = tmp_path / "cs"
    assert main(["generate", "course", "--turning", "--gps", "--seed", "3", "--out", str(out),
                 "--rate", "50", "--count", "201", "--json"]) == 0
    capsys.readouterr()
    truth = json.loads((out / "truth.json").read_text())
    assert truth["vehicle"]["turning"] is True and missing_units(truth) == []
    assert truth["units"]["vehicle.gyro_sigma"] == "rad/s"
    mat = scipy.io.loadmat(out / "acel.mat")
    assert mat["gyro"].shape == mat["t"].shape
    # gyro noise: 3000 residuals against the true rate, variance in its χ² band
    cfg = VehicleConfig(duration=60.0, rate=50.0, turning=True)
    w_true = simulate_vehicle(cfg).yaw_rate
    res = mat["gyro"][:, 0] - w_true
    n = res.size
    s2 = float(np.sum(res ** 2)) / cfg.gyro_sigma ** 2
    assert chi2.ppf(0.001, n) <= s2 <= chi2.ppf(0.999, n), s2 / n
    files = ["--acel", out / "acel.mat", "--gps", out / "gps.mat", "--puntos",
             out / "puntos.mat", "--datos", out / "datos.txt", "--ensayo", out / "ensayo.mat"]
    assert main(["fuse", *map(str, files), "--smoother", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert missing_units(d["fusion"]) == [], missing_units(d["fusion"])
    fused = d["fusion"]
    assert fused["state_names"][4] == "psi" and d["units"] is not None
    est = np.array(fused["final_position"], dtype=float).reshape(2)
    cov = np.array(fused["final_position_cov"], dtype=float).reshape(2, 2)
    err = est - np.array(truth["true_final_position"])
    assert float(err @ np.linalg.solve(cov, err)) < chi2.ppf(0.999, 2)
    assert d["decision"]["decision"] == truth["answer"]
    assert main(["fuse", *map(str, files)]) == 0
    text = capsys.readouterr().out
    for word in ("Extended Kalman fusion", "P0 (", "Q per IMU step", "R (m²", "(rad/s)²",
                 "final heading"):
        assert word in text, word
    assert main(["fuse", *map(str, files), "--gps-vel-sigma", "0.1"]) == 2
    assert "position fixes only" in unwrap(capsys.readouterr().err)


def test_gate_and_consistency_rates_of_the_extended_filter(nominal):
    """On the same 500 right runs, the extended filter's innovation gate rejects at its α_g
    and the windowed NIS verdict fires at its α, each within the binomial band
    |p̂ − p| ≤ 4·sqrt(p(1 − p)/n) (n = R·M fixes, or R runs; calib.fusion.innovation_check: exact
    for a linear filter, to first order for this one)."""
    from calib.fusion.innovation_check import windowed_nis

    data, res = nominal

    def within(hits, n, p):
        return abs(hits / n - p) <= 4.0 * np.sqrt(p * (1.0 - p) / n)

    for alpha in (0.01, 0.2):  # the nominal run has no gate: plain χ²(2k) windows
        w = windowed_nis(res.nis(), d=2, gate_alpha=0.0, alpha=alpha)
        assert within(int(np.sum(~w["consistent"])), R_RUNS, alpha), alpha
    gated = fuse_turning(data["t"], data["acc_m"], data["gyro"], data["t_gps"], data["fixes"],
                         bias=BIAS_HAT, scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2,
                         gyro_var=SIGMA_G ** 2, sigma_pos=SIGMA_POS, p0=P0_HAT, v0=V0_HAT,
                         psi0=0.0, p0_cov=P0_COV, v0_cov=V0_COV, psi0_var=PSI0_VAR,
                         keep="fixes", gate_alpha=0.01)
    assert within(int(np.sum(~gated.fix_used)), gated.fix_used.size, 0.01)
    w = windowed_nis(gated.nis(), d=2, gate_alpha=0.01, alpha=0.2)
    assert within(int(np.sum(~w["consistent"])), R_RUNS, 0.2)
