"""The fusion wing's shared pieces: the decision value (calib.vehicle.region.Decision), the fused
arrival (calib.vehicle.arrival), the calibration taken as one value by both filters, the σ²
fallback, and the nmin vehicle case (calib.vehicle.nmin.VehicleCase)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.calibration.tilt_plane import calibrate
from calib.files.course import Acel, Ensayo, Fixes
from calib.fusion.kalman import CalibrationPrior
from calib.fusion.linear import fuse
from calib.fusion.turning import fuse_turning
from calib.vehicle.arrival import FusedArrival, dead_reckoning_region, fuse_arrival
from calib.vehicle.nmin import VehicleCase
from calib.vehicle.region import (
    Decision,
    arrival_region,
    decide,
    squared_distances,
    stated_noise_var,
)
from calib.vehicle.trajectory import compute_trajectory

CANDS = {"A": np.array([10.0, 30.0]), "B": np.array([60.0, 30.0]), "C": np.array([12.0, 33.0])}


@pytest.fixture(scope="module")
def cal():
    th = np.linspace(0.0, 2 * np.pi, 400, endpoint=False)
    rng = np.random.default_rng(5)
    datos = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) * [0.98, 1.01] + \
        [0.05, -0.02] + rng.normal(size=(400, 2)) * 0.1
    return calibrate(Ensayo(th, datos), [0.01, 0.01])


def test_decision_is_the_rule_of_decide_and_round_trips():
    est, cov = np.array([11.0, 31.0]), np.diag([4.0, 9.0])
    d = Decision.at(est, cov, CANDS, 0.95)
    d2 = squared_distances(est, cov, CANDS)
    letter, inside, reason = decide(d2, 0.95)
    assert (d.letter, d.inside, d.reason) == (letter, inside, reason)
    assert d.mahalanobis == {k: float(np.sqrt(v)) for k, v in d2.items()}
    assert d.likelihood["A"] == pytest.approx(np.exp(-0.5 * d2["A"]), rel=1e-15)
    assert Decision.from_dict(json.loads(json.dumps(d.to_state()))) == d
    assert list(d.to_dict()) == ["decision", "inside", "reason", "level", "mahalanobis"]
    far = Decision.at(est, np.diag([1e-4, 1e-4]), CANDS, 0.95)
    assert far.letter is None and far.inside == ()


def test_the_regions_carry_the_same_decision(cal):
    t = np.arange(1001) * 0.01
    traj = compute_trajectory(Acel(t, np.zeros((1001, 2))), cal)
    reg = arrival_region(traj, cal, CANDS, level=0.95)
    assert reg.as_decision() == Decision.at(reg.estimate, reg.cov, CANDS, 0.95)


def test_sigma2_falls_back_to_the_calibration(cal):
    assert stated_noise_var([0.3, 0.4], cal).tolist() == [0.3, 0.4]
    got = stated_noise_var(None, cal)
    assert got.tolist() == [cal.fits["x"].sigma2.item(), cal.fits["y"].sigma2.item()]


def test_a_calibration_or_its_parts_give_the_same_filter(cal):
    t = np.arange(501) * 0.02
    rng = np.random.default_rng(9)
    acc = rng.normal(size=(501, 2)) * 0.1
    tg, pos = t[::50], rng.normal(size=(11, 2))
    kw = dict(noise_var=[0.01, 0.01], sigma_pos=3.0, p0=[0, 0], v0=[1, 3], p0_cov=0.0,
              v0_cov=0.0, smoother=True)
    a = fuse(t, acc, tg, pos, calibration=cal, **kw)
    b = fuse(t, acc, tg, pos, bias=cal.bias, scale=cal.scale, cal_cov=cal.cov, **kw)
    assert a == b
    gyro = np.full(501, 0.01)
    ta = fuse_turning(t, acc, gyro, tg, pos, calibration=cal, gyro_var=1e-4, **kw)
    tb = fuse_turning(t, acc, gyro, tg, pos, bias=cal.bias, scale=cal.scale, cal_cov=cal.cov,
                      gyro_var=1e-4, **kw)
    assert ta == tb
    with pytest.raises(ValueError, match="not both"):
        CalibrationPrior.of(cal, bias=cal.bias)
    with pytest.raises(ValueError, match="needs a calibration"):
        CalibrationPrior.of(bias=cal.bias, scale=cal.scale)
    with pytest.raises(ValueError, match=r"\(4, 4\)"):
        CalibrationPrior.of(bias=cal.bias, scale=cal.scale, cal_cov=np.eye(2))


def test_fused_arrival_decides_on_the_filtered_end_and_round_trips(cal):
    t = np.arange(1001) * 0.01
    acel = Acel(t, np.tile(cal.bias, (1001, 1)))  # corrected: at rest
    exact = np.array([[0.0, 0.0], [2.0, 6.0], [5.0, 15.0], [10.0, 30.0]])
    # fixes with the stated σ = 1 m of noise (noise-free fixes are too good to be true:
    # their NIS sum is below its band, below)
    noisy = exact + np.random.default_rng(4).normal(0.0, 1.0, exact.shape)
    fixes = Fixes(np.array([-1.0, 2.0, 5.0, 10.0]), noisy)
    res = fuse_arrival(acel, fixes, cal, CANDS, p0=[0, 0], v0=[1, 3], level=0.95,
                       sigma_pos=1.0)
    assert (res.fixes_used, res.fixes_total) == (3, 4)  # the fix before t_0 is left out
    assert res.consistent
    end = np.asarray(res.fusion.final_position)
    assert res.decision == Decision.at(end, res.fusion.final_position_cov, CANDS, 0.95)
    perfect = fuse_arrival(acel, Fixes(fixes.t_gps, exact), cal, CANDS, p0=[0, 0], v0=[1, 3],
                           level=0.95, sigma_pos=1.0)
    assert not perfect.consistent and perfect.decision.letter is None
    assert perfect.consistency.failing_windows[0]["side"] == "low"
    assert FusedArrival.from_dict(json.loads(json.dumps(res.to_state()))) == res
    assert "fixes used: 3 of 4" in res.summary()
    traj, region = dead_reckoning_region(acel, cal, CANDS, p0=[0, 0], v0=[1, 3], level=0.95)
    assert np.allclose(region.estimate, [10.0, 30.0], atol=1e-9)
    with pytest.raises(ValueError, match="no fix falls within"):
        fuse_arrival(acel, Fixes(np.array([20.0]), np.zeros((1, 2)), source="g.mat"), cal,
                     CANDS, p0=[0, 0], v0=[1, 3], level=0.95)


def test_vehicle_case_moves_its_candidates_only():
    case = VehicleCase(CANDS, level=0.9, method="wls")
    moved = case.moved([1.0, -2.0])
    assert moved.candidates["B"].tolist() == [61.0, 28.0]
    assert (moved.p0, moved.v0, moved.level, moved.method) == ((0.0, 0.0), (1.0, 3.0), 0.9,
                                                               "wls")
    assert case.candidates["B"].tolist() == [60.0, 30.0]
