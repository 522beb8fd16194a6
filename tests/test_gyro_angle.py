"""θ(t) from the gyro about the tilt axis, anchored to the held poses (``--theta-source gyro``,
:mod:`calib.logs.gyro_angle`): a simulated log with a known θ(t) is recovered within a bound derived
below; closure errors beyond the bound and a gyro of the wrong sign are refused in one line;
the shipped YEI 3-Space log (data/real/) closes within the bound and keeps every sample.

Bound for the recovery (no tuning): between two holds the integral's error is the integrated
white noise of the gyro, a random walk of std ``σ_ω·√(dt·T)`` after ``T`` seconds, plus the
trapezoid rule's error, which for a turn that starts and ends at rest is at most
``dt²/12 · max|θ''|`` at any sample (the composite rule's leading error term,
``dt²/12 · [θ''(b) − θ''(a)]``). The linear correction removes the bias left in the estimate
and pins each hold. A sample is allowed ``4·σ_ω·√(dt·T_max) + dt²/12·max|θ''|`` (a normal
error exceeds 4 std with probability 6e-5 per sample; the seed is fixed, so the outcome is
deterministic).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.io

from calib.input_rules import DataError
from calib.logs.gyro_angle import CLOSURE_BOUND_DEG, hold_runs, theta_from_gyro
from calib.logs.reader import LogOptions, read_log
from tests import logfixtures as fx
from tests.cli import one_line_error, run
from tests.reference import real_data as ref

G = 9.8
DT = 0.01  # s, nominal step (jittered below)
SIGMA_W = 0.004  # rad/s, gyro white noise per sample
BIAS_W = 0.013  # rad/s, gyro bias
HOLD_S, TURN_S = 2.0, 1.2  # s


def _smooth_turns(angles_deg, seed=7):
    """t (jittered), θ(t) held at each angle for HOLD_S and turned between them by a
    minimum-jerk profile (θ', θ'' zero at both ends) in TURN_S; true hold masks."""
    rng = np.random.default_rng(seed)
    angles = np.deg2rad(angles_deg)
    seg_t, seg_th, labels = [], [], []
    t0 = 0.0
    for k, a in enumerate(angles):
        n = int(HOLD_S / DT)
        seg_t.append(t0 + DT * np.arange(n))
        seg_th.append(np.full(n, a))
        labels.append(np.full(n, k))
        t0 += n * DT
        if k + 1 < len(angles):
            m = int(TURN_S / DT)
            s = np.arange(m) * DT / TURN_S
            seg_t.append(t0 + DT * np.arange(m))
            seg_th.append(a + (angles[k + 1] - a) * (10 * s**3 - 15 * s**4 + 6 * s**5))
            labels.append(np.full(m, -1))
            t0 += m * DT
    t = np.concatenate(seg_t) + rng.uniform(-0.1, 0.1, size=sum(map(len, seg_t))) * DT
    theta = np.concatenate(seg_th)
    pose = np.concatenate(labels)
    # the detector trims holds near motion: keep the middle of each hold as labelled
    for k in range(len(angles)):
        idx = np.flatnonzero(pose == k)
        pose[idx[:20]] = -1
        pose[idx[-20:]] = -1
    # exact rate of the min-jerk turns at the (jittered) sample times
    rate = np.zeros_like(theta)
    cursor = 0
    tt = 0.0
    for k in range(len(angles)):
        cursor += int(HOLD_S / DT)
        tt += int(HOLD_S / DT) * DT
        if k + 1 < len(angles):
            m = int(TURN_S / DT)
            sl = slice(cursor, cursor + m)
            s = (t[sl] - tt) / TURN_S
            d = angles[k + 1] - angles[k]
            theta[sl] = angles[k] + d * (10 * s**3 - 15 * s**4 + 6 * s**5)
            rate[sl] = d * (30 * s**2 - 60 * s**3 + 30 * s**4) / TURN_S
            cursor += m
            tt += m * DT
    max_acc = max(abs(math.radians(b - a))
                  for a, b in zip(angles_deg[:-1], angles_deg[1:], strict=True))
    max_acc *= 10 / math.sqrt(3) / TURN_S**2  # max |θ''| of a minimum-jerk turn: 5.77 Δ/T²
    return t, theta, rate, pose, max_acc


def _acc(theta, rng):
    return np.c_[-G * np.sin(theta), -G * np.cos(theta)] + 0.02 * rng.standard_normal(
        (theta.size, 2))


def test_theta_recovered_from_a_biased_noisy_gyro():
    angles = (0.0, 90.0, 200.0, -30.0, 45.0)
    t, theta, rate, pose, max_acc = _smooth_turns(angles)
    rng = np.random.default_rng(11)
    gyro = rate + BIAS_W + SIGMA_W * rng.standard_normal(t.size)
    res = theta_from_gyro(t, gyro, pose, np.deg2rad(angles), acc=_acc(theta, rng), g=G)
    runs = hold_runs(pose)
    # the walk's time: from the start of one hold (its mean anchors) to the end of the next
    span = max(t[r1[1] - 1] - t[r0[0]] for r0, r1 in zip(runs[:-1], runs[1:], strict=True))
    bound = 4 * SIGMA_W * math.sqrt(DT * span) + DT**2 / 12 * max_acc
    # -30° is reached from 200° by turning back: the target is the continuous -30°
    err = np.max(np.abs(res.theta - theta))
    assert err <= bound, (err, bound)
    assert res.bias == pytest.approx(BIAS_W, abs=4 * SIGMA_W / math.sqrt(np.sum(pose >= 0)))
    assert np.allclose(res.stated_rad, np.deg2rad(angles), atol=1e-12)
    assert np.all(np.abs(res.closure_deg) < CLOSURE_BOUND_DEG) and res.closure_deg[0] == 0
    for (a, b, k), target in zip(hold_runs(pose), res.stated_rad, strict=True):
        assert res.theta[a:b].mean() == pytest.approx(target, abs=1e-12), k
    assert res.mirror_misfit[0] < res.mirror_misfit[1]
    back = type(res).from_dict(json.loads(json.dumps(res.to_dict())))
    assert back == res


def test_without_the_correction_the_bias_error_would_show():
    """The correction does work: a bias of 0.05 rad/s present only while moving (the held
    mean cannot see it) leaves a closure error of bias × the moving time, which the
    correction removes at the holds."""
    angles = (0.0, 90.0, 180.0)
    t, theta, rate, pose, _ = _smooth_turns(angles)
    held = pose >= 0
    gyro = rate.copy()
    gyro[~held] += 0.05  # a bias present only while moving: the held mean cannot see it
    res = theta_from_gyro(t, gyro, pose, np.deg2rad(angles))
    # uncorrected, the turn picks up 0.05 rad/s over the moving stretch between holds
    a0, b0, _ = hold_runs(pose)[0]
    a1, _, _ = hold_runs(pose)[1]
    moving = np.sum(np.diff(t)[b0 - 1:a1])
    assert res.closure_deg[1] == pytest.approx(math.degrees(0.05 * moving), rel=0.05)
    for (a, b, _), target in zip(hold_runs(pose), res.stated_rad, strict=True):
        assert np.max(np.abs(res.theta[a:b] - target)) < 1e-3


@pytest.mark.parametrize("case", ["scale", "other_axis", "sign"])
def test_closure_errors_and_a_wrong_sign_are_refused(case):
    angles = (0.0, 90.0, 180.0) if case != "sign" else (0.0, 180.0, 0.0)
    t, theta, rate, pose, _ = _smooth_turns(angles)
    rng = np.random.default_rng(5)
    gyro = {"scale": 1.1 * rate, "other_axis": 0.01 * rng.standard_normal(t.size),
            "sign": -rate}[case]
    with pytest.raises(DataError) as err:
        theta_from_gyro(t, gyro, pose, np.deg2rad(angles), acc=_acc(theta, rng), g=G,
                        where="log.csv", gyro_from="gz")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("log.csv: --theta-source gyro")
    assert "--axes" in msg and "gyro column" in msg
    if case == "sign":  # 180° turns close either way: the accelerometer tells
        assert "sign is wrong" in msg
    else:
        assert "closure error" in msg and f"bound {CLOSURE_BOUND_DEG:g}°" in msg


def test_cli_import_with_theta_source_gyro(capsys, tmp_path):
    """The fixture's five-pose log (tests/logfixtures.py: linear turns, gyro noise 0.002 rad/s
    and no bias) imported with --theta-source gyro keeps every sample with θ(t): within 1° of
    the truth (a linear ramp's corners are where the gyro's rate, a central difference,
    smooths θ: at most half a step of the fastest turn, 1.1° per step ⇒ 0.6°) and exactly
    the poses' angles on average over each hold."""
    path = fx.write_csv(tmp_path / "log.csv")
    _, theta_true, *_ = fx.simulated()
    poses = ",".join(f"{a:g}" for a in fx.ANGLES_DEG)
    rc, out, err = run(capsys, "import", path, "--poses", poses, "--angle-unit", "deg",
                       "--theta-source", "gyro", "--out", tmp_path / "imp", "--json")
    assert rc == 0, err
    doc = json.loads(out)
    prov = doc["provenance"]
    assert prov["samples"]["kept"] == prov["samples"]["read"] == theta_true.size
    gy = prov["theta_from_gyro"]
    assert len(gy["closure_deg"]) == 5 and "linear in time" in gy["correction"]
    mat = scipy.io.loadmat(tmp_path / "imp" / "ensayo.mat")
    tita = mat["tita"].ravel()
    assert tita.size == theta_true.size and mat["t"].size == tita.size
    assert np.max(np.abs(tita - theta_true)) < math.radians(1.0)
    # the 45° pose is reached from 270° forwards (the fixture turns +45 − 270 = −225°)
    assert np.allclose(np.rad2deg(gy["stated_rad"]), fx.ANGLES_DEG, atol=1e-9)
    rc, out, _ = run(capsys, "import", path, "--poses", poses, "--angle-unit", "deg",
                     "--theta-source", "gyro", "--out", tmp_path / "imp2")
    assert rc == 0 and "θ from the gyro (gz (rad/s)): θ = θ₀ + ∫(ω − b̂)dt" in out
    assert "closure errors" in out and "linear in time" in out


def test_cli_refusals(capsys, tmp_path):
    path = fx.write_csv(tmp_path / "log.csv")
    nogyro = fx.write_csv(tmp_path / "nogyro.csv", gyro=False)
    poses = ",".join(f"{a:g}" for a in fx.ANGLES_DEG)
    line = one_line_error(capsys, "import", path, "--theta-source", "gyro", "--out",
                          tmp_path / "a")
    assert "--poses" in line and not (tmp_path / "a").exists()
    line = one_line_error(capsys, "import", nogyro, "--poses", poses, "--angle-unit", "deg",
                          "--theta-source", "gyro", "--out", tmp_path / "b")
    assert "needs a gyro" in line and not (tmp_path / "b").exists()
    # the tilt plane x,z turns about -y, a gyro axis the fixture never turns: refused
    line = one_line_error(capsys, "import", path, "--axes", "x,y", "--poses",
                          "0,90,180,270,0", "--angle-unit", "deg", "--theta-source", "gyro",
                          "--out", tmp_path / "c")
    assert "closure error" in line and "--axes" in line and not (tmp_path / "c").exists()


def test_the_shipped_yei_log_closes():
    """data/real/yei-3space-z-flip.csv: flat, turned over, flat again, gyro at 110 Hz. Every
    sample is kept with θ from the gyro; the closure errors stay inside the bound; the holds
    sit at 0 and 180° modulo a turn; the gyro's angle agrees with the accelerometer's own
    angle ``atan2(-a_x, -a_y)`` of each hold's mean (independent of the gyro) within 3°
    (the x axis's bias of ≈ 0.37 m/s², README, alone makes 2.2°)."""
    path = ref.REAL_DIR / "yei-3space-z-flip.csv"
    opts = LogOptions(units="g", gyro_unit="rad/s", axes=("x", "-z"), min_hold=0.5,
                      poses=(0.0, 0.0, 180.0, 0.0, 0.0), angle_unit="deg",
                      theta_source="gyro")
    log = read_log(path, opts)
    spec = ref.SPECS[path.name]
    _, rows = ref.read_rows(path)
    assert log.n == len(rows)
    t_ref = np.array(rows)[:, spec.time_column] * spec.time_to_s
    assert np.allclose(log.t, t_ref, rtol=0, atol=1e-12)
    gy = log.provenance["theta_from_gyro"]
    closure = np.array(gy["closure_deg"])
    assert np.all(np.abs(closure) < CLOSURE_BOUND_DEG)
    stated = np.rad2deg(gy["stated_rad"])
    assert np.allclose(np.mod(stated + 1e-9, 360.0) - 1e-9, [0, 0, 180, 0, 0], atol=1e-9)
    for (a, b), target in zip(gy["holds"], gy["stated_rad"], strict=True):
        assert log.theta[a:b].mean() == pytest.approx(target, abs=1e-12)
        assert np.std(log.theta[a:b]) < math.radians(0.5)
    for a, b in gy["holds"]:
        mean = log.acc[a:b].mean(axis=0)
        diff = np.angle(np.exp(1j * (np.arctan2(-mean[0], -mean[1]) - log.theta[a:b].mean())))
        assert abs(math.degrees(diff)) < 3.0, (a, b)
    mis = gy["mirror_misfit"]
    assert mis[0] < mis[1]  # the gyro turns the way the accelerometer sees
